/* The load of the connector example as an FMU of its own: F = amplitude cos(omega t) - force.
 *
 * OMSimulator connects an output to an input and nothing else (no sums, no signs), and the native element FMU
 * that plays the mass takes one force F, the sum of the example's harmonic force and the connector's force
 * against the motion. This FMU forms that sum (input `force`, output `F`, direct feedthrough, at the time of the
 * last communication point), so that every FMU of the loop is native and can get and set its state, which
 * OMSimulator's --inputExtrapolation needs for its second pass. No numerics: it holds no state but its time and
 * the input set last. Built by benchmarks/omsimulator_extrapolation.py (gcc -shared), FMI 2.0 co-simulation.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

enum { FORCE, F, AMPLITUDE, OMEGA, COUNT };  /* the value references */

typedef struct {
    double time;
    double value[COUNT];  /* force, (F unused), amplitude, omega */
} State;

typedef struct {
    State now;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    char name[64];
} Instance;

static double load(const State* s)
{
    return s->value[AMPLITUDE] * cos(s->value[OMEGA] * s->time) - s->value[FORCE];
}

static fmi2Status refuse(fmi2Component c, const char* function)
{
    Instance* i = (Instance*)c;
    if (i != NULL && i->logger != NULL)
        i->logger(i->environment, i->name, fmi2Error, "logStatusError",
                            "%s: not provided by this FMU", function);
    return fmi2Error;
}

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String categories[])
{
    (void)c; (void)on; (void)n; (void)categories;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions* callbacks, fmi2Boolean visible, fmi2Boolean logging)
{
    (void)guid; (void)resources; (void)visible; (void)logging;
    if (type != fmi2CoSimulation)
        return NULL;
    Instance* i = (Instance*)calloc(1, sizeof(Instance));
    if (i == NULL)
        return NULL;
    if (callbacks != NULL) {
        i->logger = callbacks->logger;
        i->environment = callbacks->componentEnvironment;
    }
    strncpy(i->name, name != NULL ? name : "load", sizeof(i->name) - 1);
    i->now.value[AMPLITUDE] = 0.45;
    i->now.value[OMEGA] = 0.5;
    return i;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop)
{
    (void)tolerance_defined; (void)tolerance; (void)stop_defined; (void)stop;
    ((Instance*)c)->now.time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c)
{
    Instance* i = (Instance*)c;
    memset(&i->now, 0, sizeof(State));
    i->now.value[AMPLITUDE] = 0.45;
    i->now.value[OMEGA] = 0.5;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    Instance* i = (Instance*)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= COUNT)
            return refuse(c, "fmi2GetReal of an unknown value reference");
        value[k] = vr[k] == F ? load(&i->now) : i->now.value[vr[k]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    Instance* i = (Instance*)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= COUNT || vr[k] == F)
            return refuse(c, "fmi2SetReal of an output or an unknown value reference");
        i->now.value[vr[k]] = value[k];
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean new_step)
{
    (void)new_step;
    ((Instance*)c)->now.time = t + h;
    return fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    if (*state == NULL)
        *state = malloc(sizeof(State));
    if (*state == NULL)
        return fmi2Error;
    memcpy(*state, &((Instance*)c)->now, sizeof(State));
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    memcpy(&((Instance*)c)->now, state, sizeof(State));
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    (void)c;
    free(*state);
    *state = NULL;
    return fmi2OK;
}

/* what this FMU does not provide: refused with the reason */
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    (void)vr; (void)value;
    return n == 0 ? fmi2OK : refuse(c, "fmi2GetInteger");
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean value[])
{
    (void)vr; (void)value;
    return n == 0 ? fmi2OK : refuse(c, "fmi2GetBoolean");
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String value[])
{
    (void)vr; (void)value;
    return n == 0 ? fmi2OK : refuse(c, "fmi2GetString");
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer value[])
{
    (void)vr; (void)value;
    return n == 0 ? fmi2OK : refuse(c, "fmi2SetInteger");
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean value[])
{
    (void)vr; (void)value;
    return n == 0 ? fmi2OK : refuse(c, "fmi2SetBoolean");
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String value[])
{
    (void)vr; (void)value;
    return n == 0 ? fmi2OK : refuse(c, "fmi2SetString");
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t* size)
{
    (void)s; (void)size;
    return refuse(c, "fmi2SerializedFMUstateSize");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte bytes[], size_t size)
{
    (void)s; (void)bytes; (void)size;
    return refuse(c, "fmi2SerializeFMUstate");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate* s)
{
    (void)bytes; (void)size; (void)s;
    return refuse(c, "fmi2DeSerializeFMUstate");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dz[], fmi2Real du[])
{
    (void)u; (void)nu; (void)z; (void)nz; (void)dz; (void)du;
    return refuse(c, "fmi2GetDirectionalDerivative");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    return refuse(c, "fmi2SetRealInputDerivatives");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)n; (void)order; (void)value;
    return refuse(c, "fmi2GetRealOutputDerivatives");
}
fmi2Status fmi2CancelStep(fmi2Component c) { return refuse(c, "fmi2CancelStep"); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status* v)
{
    (void)k; (void)v;
    return refuse(c, "fmi2GetStatus");
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real* v)
{
    (void)k; (void)v;
    return refuse(c, "fmi2GetRealStatus");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer* v)
{
    (void)k; (void)v;
    return refuse(c, "fmi2GetIntegerStatus");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean* v)
{
    (void)k; (void)v;
    return refuse(c, "fmi2GetBooleanStatus");
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String* v)
{
    (void)k; (void)v;
    return refuse(c, "fmi2GetStringStatus");
}
