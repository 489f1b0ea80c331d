/* The native FMU's FMI 2.0 co-simulation layer over the element (element.h). */
#include "fmi2Functions.h"
#define FMI "fmi2"
#define FMU_STATE "FMUstate" /* fmi2GetFMUstate; FMI 3.0 writes fmi3GetFMUState */
#include "scene.h"
#if CONNECTOR
#include "connector.h"
#else
#include "element.h"
#endif
#include "state.h"

static void emit(void* instance, int status, const char* category, const char* message)
{
    Instance* c = (Instance*)instance;
    fmi2CallbackLogger logger = (fmi2CallbackLogger)c->logger;
    logger((fmi2ComponentEnvironment)c->env, c->name ? c->name : "", (fmi2Status)status, category, message);
}


const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n, const fmi2String categories[])
{
    ((Instance*)comp)->logging = on ? 1 : 0;
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
    return c;
}

void fmi2FreeInstance(fmi2Component comp)
{
    Instance* c = (Instance*)comp;
    if (c == NULL)
        return;
    free(c->name);
    free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean tol_defined, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop)
{
    Instance* c = (Instance*)comp;
    if (c->phase != INSTANTIATED) {
        say(c, fmi2Error, "fmi2SetupExperiment refused: only after fmi2Instantiate");
        return fmi2Error;
    }
    c->start_time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp)
{
    Instance* c = (Instance*)comp;
    if (c->phase != INSTANTIATED) {
        say(c, fmi2Error, "fmi2EnterInitializationMode refused: only once, after fmi2Instantiate");
        return fmi2Error;
    }
    c->phase = INITIALIZING;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    return (fmi2Status)core_exit_initialization((Instance*)comp);
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real H, fmi2Boolean no_prior)
{
    return (fmi2Status)core_do_step((Instance*)comp, t, H);
}

fmi2Status fmi2Terminate(fmi2Component comp)
{
    Instance* c = (Instance*)comp;
    c->phase = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp)
{
    defaults((Instance*)comp);
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component comp) { return fmi2Error; }

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    Instance* c = (Instance*)comp;
    size_t i;
    for (i = 0; i < n; i++) {
        const Var* var = find(vr[i], T_REAL);
        if (var == NULL) {
            say(c, fmi2Error, "fmi2GetReal refused: no Real variable has value reference %u", vr[i]);
            return fmi2Error;
        }
        value[i] = real_value(c, var);
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    Instance* c = (Instance*)comp;
    size_t i;
    for (i = 0; i < n; i++) {
        if (find(vr[i], T_INTEGER) == NULL) {
            say(c, fmi2Error, "fmi2GetInteger refused: no Integer variable has value reference %u", vr[i]);
            return fmi2Error;
        }
        value[i] = N_VALUE;
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n, fmi2Boolean value[])
{
    Instance* c = (Instance*)comp;
    size_t i;
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
    Instance* c = (Instance*)comp;
    size_t i;
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
    Instance* c = (Instance*)comp;
    size_t i;
    for (i = 0; i < n; i++) /* all or nothing */
        if (core_check_float(c, find(vr[i], T_REAL), vr[i], value[i]) != ST_OK)
            return fmi2Error;
    for (i = 0; i < n; i++)
        core_set_float(c, find(vr[i], T_REAL), value[i]);
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2Integer value[])
{
    say((Instance*)comp, fmi2Error, "fmi2SetInteger refused: the FMU has no Integer input or tunable parameter");
    return n ? fmi2Error : fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n, const fmi2Boolean value[])
{
    Instance* c = (Instance*)comp;
    size_t i;
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
    Instance* c = (Instance*)comp;
    size_t i;
    for (i = 0; i < n; i++) {
        if (find(vr[i], T_STRING) == NULL || value[i] == NULL) {
            say(c, fmi2Error, "fmi2SetString refused: value reference %u is not the String parameter stepper", vr[i]);
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
    say((Instance*)comp, fmi2Error, "fmi2GetDirectionalDerivative: not provided (read the output stiffness)");
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    say((Instance*)comp, fmi2Error, "fmi2SetRealInputDerivatives: the FMU holds its input over a step");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[])
{
    say((Instance*)comp, fmi2Error, "fmi2GetRealOutputDerivatives: not provided");
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status* value) { return fmi2Discard; }
fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real* value)
{
    if (s != fmi2LastSuccessfulTime)
        return fmi2Discard;
    *value = element_time(&((Instance*)comp)->el);
    return fmi2OK;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer* value) { return fmi2Discard; }
fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean* value)
{
    if (s != fmi2Terminated)
        return fmi2Discard;
    *value = ((Instance*)comp)->last_step_failed ? fmi2True : fmi2False;
    return fmi2OK;
}
fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String* value) { return fmi2Discard; }

/* ------------------------------------------------------------------ FMU state: a checked blob */

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate* state)
{
    return (fmi2Status)core_get_state((Instance*)comp, state);
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state)
{
    return (fmi2Status)core_set_state((Instance*)comp, state);
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate* state)
{
    core_free_state(state);
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t* size)
{
    *size = sizeof(State);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte bytes[], size_t size)
{
    return (fmi2Status)core_serialize((Instance*)comp, state, bytes, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte bytes[], size_t size, fmi2FMUstate* state)
{
    return (fmi2Status)core_deserialize((Instance*)comp, bytes, size, state);
}

