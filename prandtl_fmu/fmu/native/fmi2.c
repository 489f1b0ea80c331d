/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The native FMU's FMI 2.0 co-simulation front over the instance layer of its kind (machine.h over element.h,
 * connector.h or network.h): FMI 2.0's types and names, and what FMI 2.0 alone has (its statuses); what both versions
 * do alike is front.h's (the checks of a call: BEGIN, CHECKED). */
#include "fmi2Functions.h"
#define FMI "fmi2"
#define FMU_STATE "FMUstate" /* fmi2GetFMUstate; FMI 3.0 writes fmi3GetFMUState */
#define FLOAT_SETTER "fmi2SetReal"
#define STANDARD "FMI 2.0"
#define STEPPING_NAME "stepComplete"
#define DESERIALIZE "fmi2DeSerializeFMUstate"
#include "scene.h"
typedef fmi2Component FmiInstance; /* the version's types of front.h */
typedef fmi2Status FmiStatus;
typedef fmi2FMUstate FmiState;
typedef fmi2Byte FmiByte;
#include "front.h" /* over machine.h, over the kind scene.h names: element.h, connector.h or network.h */
#ifndef FMU_TIME /* the instance's time: its element's (a network connector's: its communication point) */
#define FMU_TIME(c) element_time(&(c)->el)
#endif

static void emit(void* instance, int status, const char* category, const char* message)
{
    Instance* c = (Instance*)instance;
    fmi2CallbackLogger logger = (fmi2CallbackLogger)c->logger;
    logger((fmi2ComponentEnvironment)c->env, c->name ? c->name : "", (fmi2Status)status, category, message);
}

/* the phases of FMI 2.0 co-simulation a function is allowed in (Reference-FMUs' MASK_fmi2...; this FMU never
 * returns fmi2Pending, so a step is never in progress; a discarded step leaves it in stepComplete, as theirs) */
#define MASK_GET (INITIALIZING | STEPPING | TERMINATED)
#define MASK_SET (INSTANTIATED | INITIALIZING | STEPPING)
#define MASK_STATUS (STEPPING | TERMINATED)

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component instance, fmi2Boolean on, size_t n, const fmi2String categories[])
    CHECKED(fmi2SetDebugLogging, ANY_PHASE, core_set_debug_logging(c, on, n, categories))

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible, fmi2Boolean logging)
{
    Instance* c = functions != NULL ? instance_new(name, functions->componentEnvironment,
                                                   (void*)functions->logger, emit, logging) : NULL;
    if (c == NULL)
        return NULL;
    if (type != fmi2CoSimulation)
        say(c, fmi2Error, "fmi2Instantiate refused: this FMU is for co-simulation only");
    else if (guid == NULL || strcmp(guid, GUID) != 0)
        say(c, fmi2Error, "fmi2Instantiate refused: GUID %s is not this FMU's (%s)", guid ? guid : "(null)", GUID);
    else
        return instance_started(c);
    instance_free(c);
    return NULL;
}

void fmi2FreeInstance(fmi2Component instance) { instance_free((Instance*)instance); }

fmi2Status fmi2SetupExperiment(fmi2Component instance, fmi2Boolean tol_defined, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop)
{
    BEGIN(fmi2SetupExperiment, INSTANTIATED);
    if (!experiment_valid(c, start, stop_defined, stop, "fmi2SetupExperiment"))
        return fmi2Error;
    c->start_time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component instance)
    CHECKED(fmi2EnterInitializationMode, INSTANTIATED, phase_to(c, INITIALIZING))

fmi2Status fmi2ExitInitializationMode(fmi2Component instance)
    CHECKED(fmi2ExitInitializationMode, INITIALIZING, core_exit_initialization(c))

fmi2Status fmi2DoStep(fmi2Component instance, fmi2Real t, fmi2Real H, fmi2Boolean no_prior)
    CHECKED(fmi2DoStep, STEPPING, core_do_step(c, t, H))

fmi2Status fmi2Terminate(fmi2Component instance)
    CHECKED(fmi2Terminate, STEPPING, phase_to(c, TERMINATED))

fmi2Status fmi2Reset(fmi2Component instance)
    CHECKED(fmi2Reset, ANY_PHASE, core_reset(c))

fmi2Status fmi2CancelStep(fmi2Component instance)
{
    BEGIN(fmi2CancelStep, 0); /* only while a step is in progress (fmi2Pending): never here */
    return fmi2Error;
}

fmi2Status fmi2GetReal(fmi2Component instance, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    size_t i;
    BEGIN(fmi2GetReal, MASK_GET);
    if (!arrays_given(c, n, vr, value, "fmi2GetReal"))
        return fmi2Error;
    for (i = 0; i < n; i++) {
        const Var* var = find(vr[i], T_REAL);
        if (var == NULL) {
            say(c, fmi2Error, "fmi2GetReal refused: no Real variable has value reference %u", vr[i]);
            return fmi2Error;
        }
        value[i] = real_value(c, var);
        if (!shown(c, var, value[i], "fmi2GetReal"))
            return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, fmi2Integer values[])
    GETTER(fmi2GetInteger, T_INTEGER, "fmi2GetInteger refused: no Integer variable has value reference %u", nvr,
           integer_value(c, find(vr[i], T_INTEGER)))

/* the Boolean scene_load */
fmi2Status fmi2GetBoolean(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean values[])
    GETTER(fmi2GetBoolean, T_BOOLEAN, "fmi2GetBoolean refused: no Boolean variable has value reference %u", nvr,
           c->scene_load ? fmi2True : fmi2False)

/* the String stepper */
fmi2Status fmi2GetString(fmi2Component instance, const fmi2ValueReference vr[], size_t nvr, fmi2String values[])
    GETTER(fmi2GetString, T_STRING, "fmi2GetString refused: no String variable has value reference %u", nvr,
           c->stepper)

fmi2Status fmi2SetReal(fmi2Component instance, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
    CHECKED(fmi2SetReal, MASK_SET, core_set_floats(c, vr, n, value))

fmi2Status fmi2SetInteger(fmi2Component instance, const fmi2ValueReference vr[], size_t n, const fmi2Integer value[])
    CHECKED(fmi2SetInteger, MASK_SET, core_set_integers(c, vr, n, value, n, "fmi2SetInteger"))

fmi2Status fmi2SetBoolean(fmi2Component instance, const fmi2ValueReference vr[], size_t n, const fmi2Boolean value[])
    CHECKED(fmi2SetBoolean, MASK_SET, core_set_scene_load(c, vr, n, value, n, n > 0 && value != NULL && value[n - 1],
                                                          "fmi2SetBoolean refused: no Boolean variable has value "
                                                          "reference %u"))

fmi2Status fmi2SetString(fmi2Component instance, const fmi2ValueReference vr[], size_t n, const fmi2String value[])
    CHECKED(fmi2SetString, MASK_SET, core_set_strings(c, vr, n, n, value, "value"))

/* ------------------------------------------------------------------ the rest of FMI 2.0 co-simulation */

fmi2Status fmi2GetDirectionalDerivative(fmi2Component instance, const fmi2ValueReference u[], size_t nu, /* unknowns */
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dv[], fmi2Real dz[])
{
    BEGIN(fmi2GetDirectionalDerivative, MASK_GET);
#ifdef HAS_DIRECTIONAL_DERIVATIVES /* the connector: d force / d (x, v) (connector.h) */
    return (fmi2Status)core_directional_derivative(c, u, nu, z, nz, dv, dz, "fmi2GetDirectionalDerivative");
#else
    if (!(arrays_given(c, nu, u, dz, "fmi2GetDirectionalDerivative") &&
          arrays_given(c, nz, z, dv, "fmi2GetDirectionalDerivative")))
        return fmi2Error;
    say(c, fmi2Error, "fmi2GetDirectionalDerivative: not provided (read the output stiffness)");
    return fmi2Error;
#endif
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component instance, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    BEGIN(fmi2SetRealInputDerivatives, INITIALIZING | STEPPING);
#ifdef HAS_INPUT_DERIVATIVES /* the element: F's (element.h); the connector: x's and v's (connector.h) */
    return (fmi2Status)core_set_input_derivatives(c, vr, n, order, value, "fmi2SetRealInputDerivatives");
#else
    if (!arrays_given(c, n, vr, value, "fmi2SetRealInputDerivatives") ||
        !(n == 0 || given(c, order, "fmi2SetRealInputDerivatives", "order")))
        return fmi2Error;
    say(c, fmi2Error, "fmi2SetRealInputDerivatives: the FMU holds its input over a step");
    return fmi2Error;
#endif
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component instance, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[])
{
    BEGIN(fmi2GetRealOutputDerivatives, MASK_STATUS);
#ifdef HAS_OUTPUT_DERIVATIVES /* the element: x, v, reaction; the connector: force (front.h) */
    return (fmi2Status)core_get_output_derivatives(c, vr, n, order, value, n, "fmi2GetRealOutputDerivatives");
#else
    if (!arrays_given(c, n, vr, value, "fmi2GetRealOutputDerivatives") ||
        !(n == 0 || given(c, order, "fmi2GetRealOutputDerivatives", "order")))
        return fmi2Error;
    say(c, fmi2Error, "fmi2GetRealOutputDerivatives: not provided");
    return fmi2Error;
#endif
}

/* a status this FMU does not have (no asynchronous step): fmi2Discard, as the standard says, with the reason */
static fmi2Status no_status(Instance* c, const char* function, const void* value)
{
    if (!given(c, value, function, "value"))
        return fmi2Error;
    say(c, fmi2Discard, "%s: no such status here (this FMU never returns fmi2Pending)", function);
    return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component instance, const fmi2StatusKind s, fmi2Status* value)
    CHECKED(fmi2GetStatus, MASK_STATUS, no_status(c, "fmi2GetStatus", value))

/* fmi2GetRealStatus, fmi2GetBooleanStatus: the two statuses this FMU has, fmi2LastSuccessfulTime (its time) into
 * ``real`` and fmi2Terminated (whether the last step failed) into ``flag`` when ``known`` (``value``: the one
 * given); any other: no_status */
static fmi2Status status_of(Instance* c, const char* function, int known, const void* value, fmi2Real* real,
                            fmi2Boolean* flag)
{
    if (!known)
        return no_status(c, function, value);
    if (!given(c, value, function, "value"))
        return fmi2Error;
    if (real != NULL)
        *real = FMU_TIME(c);
    else
        *flag = c->last_step_failed ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component instance, const fmi2StatusKind s, fmi2Real* value)
    CHECKED(fmi2GetRealStatus, MASK_STATUS, status_of(c, "fmi2GetRealStatus", s == fmi2LastSuccessfulTime, value, value,
                                                      NULL))

fmi2Status fmi2GetIntegerStatus(fmi2Component instance, const fmi2StatusKind s, fmi2Integer* value)
    CHECKED(fmi2GetIntegerStatus, MASK_STATUS, no_status(c, "fmi2GetIntegerStatus", value))

fmi2Status fmi2GetBooleanStatus(fmi2Component instance, const fmi2StatusKind s, fmi2Boolean* value)
    CHECKED(fmi2GetBooleanStatus, MASK_STATUS, status_of(c, "fmi2GetBooleanStatus", s == fmi2Terminated, value, NULL,
                                                         value))

fmi2Status fmi2GetStringStatus(fmi2Component instance, const fmi2StatusKind s, fmi2String* value)
    CHECKED(fmi2GetStringStatus, MASK_STATUS, no_status(c, "fmi2GetStringStatus", value))

/* ------------------------------------------------------------------ FMU state: a checked blob (state.h) */

STATE_FUNCTIONS(fmi2GetFMUstate, fmi2SetFMUstate, fmi2FreeFMUstate, fmi2SerializedFMUstateSize, fmi2SerializeFMUstate,
                fmi2DeSerializeFMUstate)
