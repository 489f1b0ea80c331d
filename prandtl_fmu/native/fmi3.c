/* The native FMU's FMI 3.0 co-simulation layer over the element (element.h): the scalars of the FMI 2.0
 * FMU (Float64 for Real, the same value references), the structural parameter n (UInt64, fixed) and the
 * branch elongations u, an array of n Float64 (VR_U). The functions of model exchange, scheduled execution,
 * clocks and event mode are refused with a logged reason. */
#include "fmi3Functions.h"
#define FMI "fmi3"
#define FMU_STATE "FMUState"
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
    fmi3LogMessageCallback logger = (fmi3LogMessageCallback)c->logger;
    logger((fmi3InstanceEnvironment)c->env, (fmi3Status)status, category, message);
}

const char* fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean on, size_t n, const fmi3String categories[])
{
    ((Instance*)instance)->logging = on ? 1 : 0;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                         fmi3Boolean logging, fmi3Boolean event_mode, fmi3Boolean early_return,
                                         const fmi3ValueReference intermediate[], size_t n_intermediate,
                                         fmi3InstanceEnvironment env, fmi3LogMessageCallback logger,
                                         fmi3IntermediateUpdateCallback update)
{
    Instance* c = (Instance*)calloc(1, sizeof(Instance));
    if (c == NULL)
        return NULL;
    c->env = env;
    c->logger = (void*)logger;
    c->name = strdup(name ? name : "");
    c->logging = logging ? 1 : 0;
    if (token == NULL || strcmp(token, GUID) != 0) {
        say(c, ST_ERROR, "fmi3InstantiateCoSimulation refused: instantiation token %s is not this FMU's (%s)",
            token ? token : "(null)", GUID);
        free(c->name);
        free(c);
        return NULL;
    }
    if (event_mode) {
        say(c, ST_ERROR, "fmi3InstantiateCoSimulation refused: this FMU has no event mode");
        free(c->name);
        free(c);
        return NULL;
    }
    defaults(c);
    return c;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    Instance* c = (Instance*)instance;
    if (c == NULL)
        return;
    free(c->name);
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tol_defined, fmi3Float64 tol,
                                       fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop)
{
    Instance* c = (Instance*)instance;
    if (c->phase != INSTANTIATED) {
        say(c, ST_ERROR, "fmi3EnterInitializationMode refused: only once, after fmi3InstantiateCoSimulation");
        return fmi3Error;
    }
    c->start_time = start;
    c->phase = INITIALIZING;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    return (fmi3Status)core_exit_initialization((Instance*)instance);
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) { return fmi3OK; }

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    ((Instance*)instance)->phase = TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    defaults((Instance*)instance);
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 H, fmi3Boolean no_prior,
                      fmi3Boolean* event_handling_needed, fmi3Boolean* terminate, fmi3Boolean* early_return,
                      fmi3Float64* last_successful_time)
{
    Instance* c = (Instance*)instance;
    int status = core_do_step(c, t, H);
    if (event_handling_needed)
        *event_handling_needed = fmi3False;
    if (terminate)
        *terminate = fmi3False;
    if (early_return)
        *early_return = fmi3False;
    if (last_successful_time)
        *last_successful_time = status == ST_OK ? t + H : t;
    return (fmi3Status)status;
}

/* the elongations u (m), in the scene's order: VR_U, an array of n */
static void elongations(Instance* c, double* out)
{
    Element* e = &c->el;
#if CONNECTOR
    (damped(e) ? elongations_c : elongations_n)(e->p, (double*)K, (double*)ETA, e->cs, e->u, out);
#else
    KERNEL(e, elongations)(BRANCHES(e), out);
#endif
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nvalues)
{
    Instance* c = (Instance*)instance;
    size_t i, at = 0;
    for (i = 0; i < nvr; i++) {
        const Var* var;
        if (vr[i] == VR_U && NB > 0) {
            if (at + NB > nvalues) {
                say(c, ST_ERROR, "fmi3GetFloat64 refused: %zu values asked, u alone has %d", nvalues, NB);
                return fmi3Error;
            }
            elongations(c, values + at);
            at += NB;
            continue;
        }
        if (vr[i] == VR_TIME && at < nvalues) { /* the independent variable */
            values[at++] = element_time(&c->el);
            continue;
        }
        var = find(vr[i], T_REAL);
        if (var == NULL || at >= nvalues) {
            say(c, ST_ERROR, "fmi3GetFloat64 refused: no Float64 variable has value reference %u (or too few "
                "values)", vr[i]);
            return fmi3Error;
        }
        values[at++] = real_value(c, var);
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nvalues)
{
    Instance* c = (Instance*)instance;
    size_t i;
    if (nvalues != nvr) {
        say(c, ST_ERROR, "fmi3SetFloat64 refused: %zu values for %zu scalar variables", nvalues, nvr);
        return fmi3Error;
    }
    for (i = 0; i < nvr; i++) /* all or nothing */
        if (core_check_float(c, find(vr[i], T_REAL), vr[i], values[i]) != ST_OK)
            return fmi3Error;
    for (i = 0; i < nvr; i++)
        core_set_float(c, find(vr[i], T_REAL), values[i]);
    return fmi3OK;
}

fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 values[],
                         size_t nvalues)
{
    Instance* c = (Instance*)instance;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (vr[i] != VR_N || i >= nvalues) {
            say(c, ST_ERROR, "fmi3GetUInt64 refused: value reference %u is not n", vr[i]);
            return fmi3Error;
        }
        values[i] = (fmi3UInt64)NB;
    }
    return fmi3OK;
}

fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3UInt64 values[], size_t nvalues)
{
    Instance* c = (Instance*)instance;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (vr[i] != VR_N || i >= nvalues || values[i] != (fmi3UInt64)NB) {
            say(c, ST_ERROR, "fmi3SetUInt64 refused: n is the scene's number of branches, %d", NB);
            return fmi3Error;
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Boolean values[],
                          size_t nvalues)
{
    Instance* c = (Instance*)instance;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (find(vr[i], T_BOOLEAN) == NULL || i >= nvalues) {
            say(c, ST_ERROR, "fmi3GetBoolean refused: no Boolean variable has value reference %u", vr[i]);
            return fmi3Error;
        }
        values[i] = c->scene_load ? fmi3True : fmi3False;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nvalues)
{
    Instance* c = (Instance*)instance;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (find(vr[i], T_BOOLEAN) == NULL || i >= nvalues) {
            say(c, ST_ERROR, "fmi3SetBoolean refused: no Boolean variable has value reference %u", vr[i]);
            return fmi3Error;
        }
    }
    for (i = 0; i < nvr; i++)
        c->scene_load = values[i] ? 1 : 0;
    return fmi3OK;
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3String values[],
                         size_t nvalues)
{
    Instance* c = (Instance*)instance;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (find(vr[i], T_STRING) == NULL || i >= nvalues) {
            say(c, ST_ERROR, "fmi3GetString refused: no String variable has value reference %u", vr[i]);
            return fmi3Error;
        }
        values[i] = c->stepper;
    }
    return fmi3OK;
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3String values[], size_t nvalues)
{
    Instance* c = (Instance*)instance;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (find(vr[i], T_STRING) == NULL || i >= nvalues || values[i] == NULL) {
            say(c, ST_ERROR, "fmi3SetString refused: value reference %u is not the String parameter stepper", vr[i]);
            return fmi3Error;
        }
    }
    for (i = 0; i < nvr; i++)
        core_set_stepper(c, values[i]);
    return fmi3OK;
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState* state)
{
    return (fmi3Status)core_get_state((Instance*)instance, state);
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state)
{
    return (fmi3Status)core_set_state((Instance*)instance, state);
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState* state)
{
    core_free_state(state);
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t* size)
{
    *size = sizeof(State);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte bytes[], size_t size)
{
    return (fmi3Status)core_serialize((Instance*)instance, state, (char*)bytes, size);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte bytes[], size_t size, fmi3FMUState* state)
{
    return (fmi3Status)core_deserialize((Instance*)instance, (const char*)bytes, size, state);
}

/* ------------------------------------------------------------------ what a co-simulation FMU does not provide */

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage)
{
    return NULL; /* this FMU is for co-simulation only */
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    return NULL; /* this FMU is for co-simulation only */
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    say((Instance*)instance, ST_ERROR, "fmi3EnterEventMode: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float32 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetFloat32: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int8 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetInt8: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt8 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetUInt8: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int16 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetInt16: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt16 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetUInt16: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int32 values[], size_t nValues)
{
    size_t i; /* n of the continuum: -1, a local constant (there is no array u then) */
    for (i = 0; i < nValueReferences; i++) {
        if (find(valueReferences[i], T_INTEGER) == NULL || i >= nValues) {
            say((Instance*)instance, ST_ERROR, "fmi3GetInt32 refused: value reference %u is not n", valueReferences[i]);
            return fmi3Error;
        }
        values[i] = N_VALUE;
    }
    return fmi3OK;
}

fmi3Status fmi3GetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt32 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetUInt32: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int64 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetInt64: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetBinary: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Clock values[])
{
    say((Instance*)instance, ST_ERROR, "fmi3GetClock: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float32 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetFloat32: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int8 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetInt8: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt8 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetUInt8: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int16 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetInt16: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt16 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetUInt16: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetInt32: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt32 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetUInt32: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int64 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetInt64: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetBinary: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Clock values[])
{
    say((Instance*)instance, ST_ERROR, "fmi3SetClock: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference, size_t* nDependencies)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetNumberOfVariableDependencies: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent, size_t elementIndicesOfDependent[], fmi3ValueReference independents[], size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetVariableDependencies: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetDirectionalDerivative: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetAdjointDerivative: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    say((Instance*)instance, ST_ERROR, "fmi3EnterConfigurationMode: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    say((Instance*)instance, ST_ERROR, "fmi3ExitConfigurationMode: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
{
    say((Instance*)instance, ST_ERROR, "fmi3GetIntervalDecimal: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[])
{
    say((Instance*)instance, ST_ERROR, "fmi3GetIntervalFraction: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 shifts[])
{
    say((Instance*)instance, ST_ERROR, "fmi3GetShiftDecimal: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    say((Instance*)instance, ST_ERROR, "fmi3GetShiftFraction: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 intervals[])
{
    say((Instance*)instance, ST_ERROR, "fmi3SetIntervalDecimal: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    say((Instance*)instance, ST_ERROR, "fmi3SetIntervalFraction: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 shifts[])
{
    say((Instance*)instance, ST_ERROR, "fmi3SetShiftDecimal: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    say((Instance*)instance, ST_ERROR, "fmi3SetShiftFraction: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    say((Instance*)instance, ST_ERROR, "fmi3EvaluateDiscreteStates: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate, fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged, fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined, fmi3Float64* nextEventTime)
{
    say((Instance*)instance, ST_ERROR, "fmi3UpdateDiscreteStates: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    say((Instance*)instance, ST_ERROR, "fmi3EnterContinuousTimeMode: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation)
{
    say((Instance*)instance, ST_ERROR, "fmi3CompletedIntegratorStep: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetTime: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[], size_t nContinuousStates)
{
    say((Instance*)instance, ST_ERROR, "fmi3SetContinuousStates: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t nContinuousStates)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetContinuousStateDerivatives: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetEventIndicators: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetContinuousStates: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nContinuousStates)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetNominalsOfContinuousStates: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* nEventIndicators)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetNumberOfEventIndicators: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* nContinuousStates)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetNumberOfContinuousStates: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues)
{
    say((Instance*)instance, ST_ERROR, "fmi3GetOutputDerivatives: not provided by this co-simulation FMU");
    return fmi3Error;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime)
{
    say((Instance*)instance, ST_ERROR, "fmi3ActivateModelPartition: not provided by this co-simulation FMU");
    return fmi3Error;
}
