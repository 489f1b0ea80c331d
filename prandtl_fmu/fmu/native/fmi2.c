/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/test_native_refusals.py checks the refusals against the library's. */
/* The native FMU's FMI 2.0 co-simulation layer over the element (element.h) or the connector (connector.h).
 *
 * Every function first checks its instance (NULL: fmi2Error, nothing logged: there is no logger), the call
 * sequence (calls.h: the phases it is allowed in, FMI 2.0's state machine for co-simulation) and its pointers
 * (NULL: fmi2Error with the reason logged). A refusal leaves the instance as it was. */
#include "fmi2Functions.h"
#define FMI "fmi2"
#define FMU_STATE "FMUstate" /* fmi2GetFMUstate; FMI 3.0 writes fmi3GetFMUState */
#define FLOAT_SETTER "fmi2SetReal"
#define STANDARD "FMI 2.0"
#define STEPPING_NAME "stepComplete"
#include "scene.h"
#if NETWORK
#include "network.h"
#elif CONNECTOR
#include "connector.h"
#else
#include "element.h"
#endif
#include "state.h"
#include "calls.h"
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

/* the instance of a call, or return fmi2Error: NULL, or a call not allowed in its phase */
#define BEGIN(function, mask)                                                                                  \
    Instance* c = (Instance*)comp;                                                                             \
    if (c == NULL)                                                                                             \
        return fmi2Error;                                                                                      \
    if (!allowed(c, (mask), #function))                                                                        \
        return fmi2Error

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n, const fmi2String categories[])
{
    size_t i;
    BEGIN(fmi2SetDebugLogging, ANY_PHASE);
    if (n > 0 && !given(c, categories, "fmi2SetDebugLogging", "categories"))
        return fmi2Error;
    for (i = 0; i < n; i++) {
        if (categories[i] == NULL) {
            say(c, fmi2Error, "fmi2SetDebugLogging refused: categories[%zu] is NULL", i);
            return fmi2Error;
        }
    }
    c->logging = on ? 1 : 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible, fmi2Boolean logging)
{
    Instance* c;
    if (functions == NULL)
        return NULL;
    c = (Instance*)calloc(1, sizeof(Instance));
    if (c == NULL)
        return NULL;
    c->env = functions->componentEnvironment;
    c->logger = (void*)functions->logger;
    c->name = strdup(name ? name : "");
    c->logging = logging ? 1 : 0;
    if (c->name == NULL) {
        free(c);
        return NULL;
    }
    if (type != fmi2CoSimulation) {
        say(c, fmi2Error, "fmi2Instantiate refused: this FMU is for co-simulation only");
        free(c->name);
        free(c);
        return NULL;
    }
    if (guid == NULL || strcmp(guid, GUID) != 0) {
        say(c, fmi2Error, "fmi2Instantiate refused: GUID %s is not this FMU's (%s)", guid ? guid : "(null)", GUID);
        free(c->name);
        free(c);
        return NULL;
    }
    defaults(c);
#ifdef INSTANCE_FAILED
    if (INSTANCE_FAILED(c)) { /* logged */
        RELEASE_INSTANCE(c);
        free(c->name);
        free(c);
        return NULL;
    }
#endif
    return c;
}

void fmi2FreeInstance(fmi2Component comp)
{
    Instance* c = (Instance*)comp;
    if (c == NULL)
        return;
#ifdef RELEASE_INSTANCE
    RELEASE_INSTANCE(c);
#endif
    free(c->name);
    free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tol_defined, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop)
{
    BEGIN(fmi2SetupExperiment, INSTANTIATED);
    if (!experiment_valid(c, start, stop_defined, stop, "fmi2SetupExperiment"))
        return fmi2Error;
    c->start_time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp)
{
    BEGIN(fmi2EnterInitializationMode, INSTANTIATED);
    c->phase = INITIALIZING;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    BEGIN(fmi2ExitInitializationMode, INITIALIZING);
    return (fmi2Status)core_exit_initialization(c);
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real H, fmi2Boolean no_prior)
{
    BEGIN(fmi2DoStep, STEPPING);
    return (fmi2Status)core_do_step(c, t, H);
}

fmi2Status fmi2Terminate(fmi2Component comp)
{
    BEGIN(fmi2Terminate, STEPPING);
    c->phase = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp)
{
    BEGIN(fmi2Reset, ANY_PHASE);
    defaults(c);
#ifdef INSTANCE_FAILED
    if (INSTANCE_FAILED(c))
        return fmi2Error; /* logged */
#endif
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component comp)
{
    BEGIN(fmi2CancelStep, 0); /* only while a step is in progress (fmi2Pending): never here */
    return fmi2Error;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
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

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    size_t i;
    BEGIN(fmi2GetInteger, MASK_GET);
    if (!arrays_given(c, n, vr, value, "fmi2GetInteger"))
        return fmi2Error;
    for (i = 0; i < n; i++) {
        const Var* var = find(vr[i], T_INTEGER);
        if (var == NULL) {
            say(c, fmi2Error, "fmi2GetInteger refused: no Integer variable has value reference %u", vr[i]);
            return fmi2Error;
        }
        value[i] = integer_value(c, var);
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Boolean value[])
{
    size_t i;
    BEGIN(fmi2GetBoolean, MASK_GET);
    if (!arrays_given(c, n, vr, value, "fmi2GetBoolean"))
        return fmi2Error;
    for (i = 0; i < n; i++) {
        if (find(vr[i], T_BOOLEAN) == NULL) {
            say(c, fmi2Error, "fmi2GetBoolean refused: no Boolean variable has value reference %u", vr[i]);
            return fmi2Error;
        }
        value[i] = c->scene_load ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2String value[])
{
    size_t i;
    BEGIN(fmi2GetString, MASK_GET);
    if (!arrays_given(c, n, vr, value, "fmi2GetString"))
        return fmi2Error;
    for (i = 0; i < n; i++) {
        if (find(vr[i], T_STRING) == NULL) {
            say(c, fmi2Error, "fmi2GetString refused: no String variable has value reference %u", vr[i]);
            return fmi2Error;
        }
        value[i] = c->stepper;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    size_t i;
    BEGIN(fmi2SetReal, MASK_SET);
    if (!arrays_given(c, n, vr, value, "fmi2SetReal"))
        return fmi2Error;
    for (i = 0; i < n; i++) /* all or nothing */
        if (core_check_float(c, find(vr[i], T_REAL), vr[i], value[i]) != ST_OK)
            return fmi2Error;
    for (i = 0; i < n; i++)
        core_set_float(c, find(vr[i], T_REAL), value[i]);
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2Integer value[])
{
    size_t i;
    BEGIN(fmi2SetInteger, MASK_SET);
    if (!arrays_given(c, n, vr, value, "fmi2SetInteger"))
        return fmi2Error;
    for (i = 0; i < n; i++) /* all or nothing */
        if (core_check_integer(c, find(vr[i], T_INTEGER), vr[i], "fmi2SetInteger") != ST_OK)
            return fmi2Error;
    for (i = 0; i < n; i++)
        core_set_integer(c, find(vr[i], T_INTEGER), value[i]);
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2Boolean value[])
{
    size_t i;
    BEGIN(fmi2SetBoolean, MASK_SET);
    if (!arrays_given(c, n, vr, value, "fmi2SetBoolean"))
        return fmi2Error;
    for (i = 0; i < n; i++) {
        if (find(vr[i], T_BOOLEAN) == NULL) {
            say(c, fmi2Error, "fmi2SetBoolean refused: no Boolean variable has value reference %u", vr[i]);
            return fmi2Error;
        }
    }
    for (i = 0; i < n; i++)
        c->scene_load = value[i] ? 1 : 0;
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2String value[])
{
    size_t i;
    BEGIN(fmi2SetString, MASK_SET);
    if (!arrays_given(c, n, vr, value, "fmi2SetString"))
        return fmi2Error;
    for (i = 0; i < n; i++) {
        if (find(vr[i], T_STRING) == NULL) {
            say(c, fmi2Error, "fmi2SetString refused: value reference %u is not the String parameter stepper", vr[i]);
            return fmi2Error;
        }
        if (value[i] == NULL) {
            say(c, fmi2Error, "fmi2SetString refused: value[%zu] is NULL (a stepper's name is needed)", i);
            return fmi2Error;
        }
    }
    for (i = 0; i < n; i++)
        core_set_stepper(c, value[i]);
    return fmi2OK;
}

/* ------------------------------------------------------------------ the rest of FMI 2.0 co-simulation */

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dv[], fmi2Real dz[])
{
    BEGIN(fmi2GetDirectionalDerivative, MASK_GET);
    say(c, fmi2Error, "fmi2GetDirectionalDerivative: not provided (read the output stiffness)");
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    BEGIN(fmi2SetRealInputDerivatives, INSTANTIATED | INITIALIZING | STEPPING);
    say(c, fmi2Error, "fmi2SetRealInputDerivatives: the FMU holds its input over a step");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[])
{
    BEGIN(fmi2GetRealOutputDerivatives, MASK_STATUS);
    say(c, fmi2Error, "fmi2GetRealOutputDerivatives: not provided");
    return fmi2Error;
}

/* a status this FMU does not have (no asynchronous step): fmi2Discard, as the standard says, with the reason */
static fmi2Status no_status(Instance* c, const char* function, const void* value)
{
    if (!given(c, value, function, "value"))
        return fmi2Error;
    say(c, fmi2Discard, "%s: no such status here (this FMU never returns fmi2Pending)", function);
    return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status* value)
{
    BEGIN(fmi2GetStatus, MASK_STATUS);
    return no_status(c, "fmi2GetStatus", value);
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real* value)
{
    BEGIN(fmi2GetRealStatus, MASK_STATUS);
    if (s != fmi2LastSuccessfulTime)
        return no_status(c, "fmi2GetRealStatus", value);
    if (!given(c, value, "fmi2GetRealStatus", "value"))
        return fmi2Error;
    *value = FMU_TIME(c);
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer* value)
{
    BEGIN(fmi2GetIntegerStatus, MASK_STATUS);
    return no_status(c, "fmi2GetIntegerStatus", value);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean* value)
{
    BEGIN(fmi2GetBooleanStatus, MASK_STATUS);
    if (s != fmi2Terminated)
        return no_status(c, "fmi2GetBooleanStatus", value);
    if (!given(c, value, "fmi2GetBooleanStatus", "value"))
        return fmi2Error;
    *value = c->last_step_failed ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String* value)
{
    BEGIN(fmi2GetStringStatus, MASK_STATUS);
    return no_status(c, "fmi2GetStringStatus", value);
}

/* ------------------------------------------------------------------ FMU state: a checked blob */

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate* state)
{
    BEGIN(fmi2GetFMUstate, ANY_PHASE);
    if (!given(c, state, "fmi2GetFMUstate", "FMUstate"))
        return fmi2Error;
    return (fmi2Status)core_get_state(c, state);
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state)
{
    BEGIN(fmi2SetFMUstate, ANY_PHASE);
    return (fmi2Status)core_set_state(c, state);
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate* state)
{
    BEGIN(fmi2FreeFMUstate, ANY_PHASE);
    if (!given(c, state, "fmi2FreeFMUstate", "FMUstate"))
        return fmi2Error;
    core_free_state(state);
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t* size)
{
    BEGIN(fmi2SerializedFMUstateSize, ANY_PHASE);
    if (!given(c, state, "fmi2SerializedFMUstateSize", "FMUstate") ||
        !given(c, size, "fmi2SerializedFMUstateSize", "size"))
        return fmi2Error;
    *size = core_state_size(state);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte bytes[], size_t size)
{
    BEGIN(fmi2SerializeFMUstate, ANY_PHASE);
    if (!given(c, state, "fmi2SerializeFMUstate", "FMUstate") || !given(c, bytes, "fmi2SerializeFMUstate", "bytes"))
        return fmi2Error;
    return (fmi2Status)core_serialize(c, state, bytes, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte bytes[], size_t size, fmi2FMUstate* state)
{
    BEGIN(fmi2DeSerializeFMUstate, ANY_PHASE);
    if (!given(c, bytes, "fmi2DeSerializeFMUstate", "bytes") || !given(c, state, "fmi2DeSerializeFMUstate",
                                                                        "FMUstate"))
        return fmi2Error;
    return (fmi2Status)core_deserialize(c, bytes, size, state);
}
