/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The native FMU's FMI 3.0 co-simulation front over the instance layer of its kind (machine.h over element.h,
 * connector.h or network.h; what both versions do alike: front.h): the scalars of the FMI 2.0 FMU (Float64 for Real,
 * each under its 1-based position in ModelVariables as its value reference) and the branch elongations as the
 * scalars u_1 .. u_n (VR_U_FIRST + i - 1), which every master reads; built with arrays (ARRAYS), also the array u of
 * n Float64 (VR_U), sized by the structural parameter n (UInt64, fixed). The functions of model exchange, scheduled
 * execution, clocks and event mode are refused with a logged reason. */
#include "fmi3Functions.h"
#define FMI "fmi3"
#define FMU_STATE "FMUState"
#define FLOAT_SETTER "fmi3SetFloat64"
#define STANDARD "FMI 3.0"
#define STEPPING_NAME "step mode"
#define DESERIALIZE "fmi3DeserializeFMUState"
#include "scene.h"
typedef fmi3Instance FmiInstance; /* the version's types of front.h */
typedef fmi3Status FmiStatus;
typedef fmi3FMUState FmiState;
typedef fmi3Byte FmiByte;
#include "front.h" /* over machine.h, over the kind scene.h names: element.h, connector.h or network.h */
#ifndef FMU_TIME /* the instance's time: its element's (a network connector's: its communication point) */
#define FMU_TIME(c) element_time(&(c)->el)
#endif
#ifndef STRUCTURAL_N /* the structural parameter (VR_N): the element's n branches; a network's nodes (ARRAYS) */
#define STRUCTURAL_N NB
#define HAS_STRUCTURAL 1
#define STRUCTURAL_TEXT "n is the scene's number of branches"
#endif
#ifndef ARRAYS /* scene.h says whether the FMU offers arrays */
#define ARRAYS 1
#endif

static void emit(void* instance, int status, const char* category, const char* message)
{
    Instance* c = (Instance*)instance;
    fmi3LogMessageCallback logger = (fmi3LogMessageCallback)c->logger;
    logger((fmi3InstanceEnvironment)c->env, (fmi3Status)status, category, message);
}

/* the phases of FMI 3.0 co-simulation a function is allowed in (Reference-FMUs' MASK_fmi3..., this FMU having no
 * event mode, no configuration mode and no clocks; a setter is refused after fmi3Terminate) */
#define MASK_GET (INSTANTIATED | INITIALIZING | STEPPING | TERMINATED | INTERMEDIATE_UPDATE)
/* fmi3SetFloat64: also in intermediate update mode (the element's F alone there: element.h fixed_problem) */
#define MASK_SET_FLOAT (MASK_SET | INTERMEDIATE_UPDATE)
#define MASK_SET (INSTANTIATED | INITIALIZING | STEPPING)
#define MASK_OUTPUT_DERIVATIVES (STEPPING | TERMINATED) /* fmi3GetOutputDerivatives: Step Mode, Terminated */

/* a function this co-simulation FMU does not provide: fmi3Error, with the reason */
static fmi3Status not_provided(fmi3Instance instance, const char* message)
{
    if (instance != NULL)
        say((Instance*)instance, ST_ERROR, "%s", message);
    return fmi3Error;
}

const char* fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean on, size_t n, const fmi3String categories[])
    CHECKED(fmi3SetDebugLogging, ANY_PHASE, core_set_debug_logging(c, on, n, categories))

#ifdef HAS_INTERMEDIATE_UPDATE
/* the master's intermediate update callback at an internal step's start ``time`` (element.h advance_with_updates): in
 * intermediate update mode it may set F; no early return (canReturnEarlyAfterIntermediateUpdate="false") */
static void ask_inputs(void* instance, double time, int first)
{
    Instance* c = (Instance*)instance;
    fmi3Boolean early = fmi3False;
    fmi3Float64 early_time = time;
    int phase = c->phase;
    c->phase = INTERMEDIATE_UPDATE;
    ((fmi3IntermediateUpdateCallback)c->intermediate_update)((fmi3InstanceEnvironment)c->env, time, fmi3True,
                                                              fmi3False, first ? fmi3False : fmi3True, fmi3False,
                                                              &early, &early_time);
    c->phase = phase;
}
#endif

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                         fmi3Boolean logging, fmi3Boolean event_mode, fmi3Boolean early_return,
                                         const fmi3ValueReference intermediate[], size_t n_intermediate,
                                         fmi3InstanceEnvironment env, fmi3LogMessageCallback logger,
                                         fmi3IntermediateUpdateCallback update)
{
    Instance* c = instance_new(name, env, (void*)logger, emit, logging);
    if (c == NULL)
        return NULL;
    if (token == NULL || strcmp(token, GUID) != 0)
        say(c, ST_ERROR, "fmi3InstantiateCoSimulation refused: instantiation token %s is not this FMU's (%s)",
            token ? token : "(null)", GUID);
    else if (event_mode)
        say(c, ST_ERROR, "fmi3InstantiateCoSimulation refused: this FMU has no event mode");
    else {
#ifdef HAS_INTERMEDIATE_UPDATE /* the element: F asked for at every internal step (element.h) */
        if (update != NULL) {
            c->intermediate_update = (void (*)(void))update;
            c->ask_inputs = ask_inputs;
        }
#endif
        return instance_started(c);
    }
    instance_free(c);
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { instance_free((Instance*)instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tol_defined, fmi3Float64 tol,
                                       fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop)
{
    BEGIN(fmi3EnterInitializationMode, INSTANTIATED);
    if (!experiment_valid(c, start, stop_defined, stop, "fmi3EnterInitializationMode"))
        return fmi3Error;
    c->start_time = start;
    return (fmi3Status)phase_to(c, INITIALIZING);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
    CHECKED(fmi3ExitInitializationMode, INITIALIZING, core_exit_initialization(c))

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    BEGIN(fmi3EnterStepMode, 0); /* from event mode only, which this FMU has not: step mode follows initialization */
    return fmi3Error;
}

fmi3Status fmi3Terminate(fmi3Instance instance)
    CHECKED(fmi3Terminate, STEPPING, phase_to(c, TERMINATED))

fmi3Status fmi3Reset(fmi3Instance instance)
    CHECKED(fmi3Reset, ANY_PHASE, core_reset(c))

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 H, fmi3Boolean no_prior,
                      fmi3Boolean* event_handling_needed, fmi3Boolean* terminate, fmi3Boolean* early_return,
                      fmi3Float64* last_successful_time)
{
    int status;
    BEGIN(fmi3DoStep, STEPPING);
    if (!given(c, event_handling_needed, "fmi3DoStep", "eventHandlingNeeded") ||
        !given(c, terminate, "fmi3DoStep", "terminateSimulation") ||
        !given(c, early_return, "fmi3DoStep", "earlyReturn") ||
        !given(c, last_successful_time, "fmi3DoStep", "lastSuccessfulTime"))
        return fmi3Error;
    status = core_do_step(c, t, H);
    *event_handling_needed = fmi3False;
    *terminate = fmi3False;
    *early_return = fmi3False;
    *last_successful_time = status == ST_OK ? t + H : t;
    return (fmi3Status)status;
}

/* the elongations u (m), in the scene's order: the array u (VR_U) or the scalars u_1 .. u_n */
static void elongations(Instance* c, double* out)
{
#if NETWORK
    (void)c; /* a network has no array u (NB is 0) */
    (void)out;
#elif CONNECTOR
    Element* e = &c->el;
    (damped(e) ? elongations_c : elongations_n)(e->p, (double*)K, (double*)ETA, e->cs, e->u, out);
#else
    Element* e = &c->el;
    KERNEL(e, elongations)(BRANCHES(e), out);
#endif
}

#if !NETWORK && NB > 0
/* the elongation of the scalar u_i at ``vr`` (VR_U_FIRST + i - 1), into ``value``: 1; 0 when vr is no u_i. ``u``
 * holds the n elongations of one call, computed at its first u_i (NULL until then). Refused (-1, the reason
 * logged): no memory, or u_i not a finite number. */
static int elongation_scalar(Instance* c, fmi3ValueReference vr, double** u, double* value)
{
    size_t i;
    if (vr < VR_U_FIRST || vr - VR_U_FIRST >= (fmi3ValueReference)NB)
        return 0;
    i = vr - VR_U_FIRST;
    if (*u == NULL) {
        *u = (double*)malloc(NB * sizeof(double));
        if (*u == NULL) {
            say(c, ST_ERROR, "fmi3GetFloat64 refused: no memory for the %d elongations", NB);
            return -1;
        }
        elongations(c, *u);
    }
    if (!isfinite((*u)[i])) {
        say(c, ST_ERROR, "fmi3GetFloat64 refused: u_%zu is %.17g, not a finite number", i + 1, (*u)[i]);
        return -1;
    }
    *value = (*u)[i];
    return 1;
}
#endif

static fmi3Status get_float64(Instance* c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                              size_t nvalues);

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nvalues)
    CHECKED(fmi3GetFloat64, MASK_GET, get_float64(c, vr, nvr, values, nvalues))

/* fmi3GetFloat64 of an instance allowed to answer: the scalars (u_i among them: the n elongations computed once
 * per call) and, with arrays, the arrays, each filling as many values as it has */
static fmi3Status get_float64(Instance* c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                              size_t nvalues)
{
    size_t i, j, at = 0;
#if !NETWORK && NB > 0
    double* u = NULL; /* the elongations of this call, at its first u_i */
#define GET_FLOAT64_END(status) do { free(u); return (status); } while (0)
#else
#define GET_FLOAT64_END(status) return (status)
#endif
    if (!(nvr == 0 || given(c, vr, "fmi3GetFloat64", "valueReferences")) ||
        !(nvalues == 0 || given(c, values, "fmi3GetFloat64", "values")))
        GET_FLOAT64_END(fmi3Error);
    for (i = 0; i < nvr; i++) {
        const Var* var;
#if NETWORK && ARRAYS
        if (vr[i] == VR_XA || vr[i] == VR_VA) { /* x or v of every node, in the nodes' order */
            if (at + NN > nvalues) {
                say(c, ST_ERROR, "fmi3GetFloat64 refused: %zu values asked, %s alone has %d", nvalues,
                    vr[i] == VR_XA ? "x" : "v", NN);
                GET_FLOAT64_END(fmi3Error);
            }
            if (node_values(c, vr[i] == VR_VA, values + at) != 0) {
                say(c, ST_ERROR, "fmi3GetFloat64 refused: %s of a node is not a finite number (a non-finite input "
                    "or a motion refused)", vr[i] == VR_XA ? "x" : "v");
                GET_FLOAT64_END(fmi3Error);
            }
            at += NN;
            continue;
        }
#endif
#if !NETWORK && NB > 0
        if (at < nvalues) { /* a scalar u_i */
            int found = elongation_scalar(c, vr[i], &u, values + at);
            if (found < 0)
                GET_FLOAT64_END(fmi3Error);
            if (found) {
                at++;
                continue;
            }
        }
#endif
        if (ARRAYS && vr[i] == VR_U && NB > 0) {
            if (at + NB > nvalues) {
                say(c, ST_ERROR, "fmi3GetFloat64 refused: %zu values asked, u alone has %d", nvalues, NB);
                GET_FLOAT64_END(fmi3Error);
            }
            elongations(c, values + at);
            for (j = 0; j < (size_t)NB; j++) {
                if (!isfinite(values[at + j])) {
                    say(c, ST_ERROR, "fmi3GetFloat64 refused: u[%zu] is %.17g, not a finite number", j + 1,
                        values[at + j]);
                    GET_FLOAT64_END(fmi3Error);
                }
            }
            at += NB;
            continue;
        }
        if (vr[i] == VR_TIME && at < nvalues) { /* the independent variable */
            values[at++] = FMU_TIME(c);
            continue;
        }
        var = find(vr[i], T_REAL);
        if (var == NULL || at >= nvalues) {
            say(c, ST_ERROR, "fmi3GetFloat64 refused: no Float64 variable has value reference %u (or too few "
                "values)", vr[i]);
            GET_FLOAT64_END(fmi3Error);
        }
        values[at] = real_value(c, var);
        if (!shown(c, var, values[at], "fmi3GetFloat64"))
            GET_FLOAT64_END(fmi3Error);
        at++;
    }
    GET_FLOAT64_END(fmi3OK);
#undef GET_FLOAT64_END
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nvalues)
{
    BEGIN(fmi3SetFloat64, MASK_SET_FLOAT);
    if (nvalues != nvr) {
        say(c, ST_ERROR, "fmi3SetFloat64 refused: %zu values for %zu scalar variables", nvalues, nvr);
        return fmi3Error;
    }
    return (fmi3Status)core_set_floats(c, vr, nvr, values);
}

fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 values[],
                         size_t nvalues)
{
    size_t i;
    BEGIN(fmi3GetUInt64, MASK_GET);
    if (!arrays_given(c, nvr, vr, values, "fmi3GetUInt64"))
        return fmi3Error;
    for (i = 0; i < nvr; i++) {
        if (!HAS_STRUCTURAL || vr[i] != VR_N || i >= nvalues) {
            say(c, ST_ERROR, "fmi3GetUInt64 refused: value reference %u is not the structural parameter", vr[i]);
            return fmi3Error;
        }
        values[i] = (fmi3UInt64)STRUCTURAL_N;
    }
    return fmi3OK;
}

fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3UInt64 values[], size_t nvalues)
{
    size_t i;
    BEGIN(fmi3SetUInt64, MASK_SET);
    if (!arrays_given(c, nvr, vr, values, "fmi3SetUInt64"))
        return fmi3Error;
    for (i = 0; i < nvr; i++) {
        if (!HAS_STRUCTURAL || vr[i] != VR_N || i >= nvalues || values[i] != (fmi3UInt64)STRUCTURAL_N) {
            say(c, ST_ERROR, "fmi3SetUInt64 refused: " STRUCTURAL_TEXT ", %d", (int)STRUCTURAL_N);
            return fmi3Error;
        }
    }
    return fmi3OK;
}

/* the Boolean scene_load */
fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Boolean values[],
                          size_t nvalues)
    GETTER(fmi3GetBoolean, T_BOOLEAN, "fmi3GetBoolean refused: no Boolean variable has value reference %u", nvalues,
           c->scene_load ? fmi3True : fmi3False)

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nvalues)
    CHECKED(fmi3SetBoolean, MASK_SET, core_set_scene_load(c, vr, nvr, values, nvalues,
                                                          nvr > 0 && values != NULL && values[nvr - 1],
                                                          "fmi3SetBoolean refused: no Boolean variable has value "
                                                          "reference %u"))

/* the String stepper */
fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3String values[],
                         size_t nvalues)
    GETTER(fmi3GetString, T_STRING, "fmi3GetString refused: no String variable has value reference %u", nvalues,
           c->stepper)

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3String values[], size_t nvalues)
    CHECKED(fmi3SetString, MASK_SET, core_set_strings(c, vr, nvr, nvalues, values, "values"))

/* ------------------------------------------------------------------ FMU state: a checked blob (state.h) */

STATE_FUNCTIONS(fmi3GetFMUState, fmi3SetFMUState, fmi3FreeFMUState, fmi3SerializedFMUStateSize, fmi3SerializeFMUState,
                fmi3DeserializeFMUState)

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
    return not_provided(instance, "fmi3EnterEventMode: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float32 values[], size_t nValues)
{
    return not_provided(instance, "fmi3GetFloat32: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int8 values[], size_t nValues)
{
    return not_provided(instance, "fmi3GetInt8: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt8 values[], size_t nValues)
{
    return not_provided(instance, "fmi3GetUInt8: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int16 values[], size_t nValues)
{
    return not_provided(instance, "fmi3GetInt16: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt16 values[], size_t nValues)
{
    return not_provided(instance, "fmi3GetUInt16: not provided by this co-simulation FMU");
}

/* noise_seed, and n where it is a local constant (no array u: -1 for the continuum) */
fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[],
                        size_t nvalues)
    GETTER(fmi3GetInt32, T_INTEGER, "fmi3GetInt32 refused: value reference %u is not an Int32 variable (noise_seed, "
           "or n where it is no structural parameter)", nvalues, integer_value(c, find(vr[i], T_INTEGER)))

fmi3Status fmi3GetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt32 values[], size_t nValues)
{
    return not_provided(instance, "fmi3GetUInt32: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int64 values[], size_t nValues)
{
    return not_provided(instance, "fmi3GetInt64: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    return not_provided(instance, "fmi3GetBinary: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Clock values[])
{
    return not_provided(instance, "fmi3GetClock: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float32 values[], size_t nValues)
{
    return not_provided(instance, "fmi3SetFloat32: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int8 values[], size_t nValues)
{
    return not_provided(instance, "fmi3SetInt8: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt8 values[], size_t nValues)
{
    return not_provided(instance, "fmi3SetUInt8: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int16 values[], size_t nValues)
{
    return not_provided(instance, "fmi3SetInt16: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt16 values[], size_t nValues)
{
    return not_provided(instance, "fmi3SetUInt16: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 values[], size_t nValues)
{
    BEGIN(fmi3SetInt32, MASK_SET); /* noise_seed: an FMI 2.0 Integer, 32 bits as there (0 <= seed < 2^31) */
    return (fmi3Status)core_set_integers(c, valueReferences, nValueReferences, values, nValues, "fmi3SetInt32");
}

fmi3Status fmi3SetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt32 values[], size_t nValues)
{
    return not_provided(instance, "fmi3SetUInt32: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int64 values[], size_t nValues)
{
    return not_provided(instance, "fmi3SetInt64: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    return not_provided(instance, "fmi3SetBinary: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Clock values[])
{
    return not_provided(instance, "fmi3SetClock: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference, size_t* nDependencies)
{
    return not_provided(instance, "fmi3GetNumberOfVariableDependencies: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent, size_t elementIndicesOfDependent[], fmi3ValueReference independents[], size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    return not_provided(instance, "fmi3GetVariableDependencies: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)
#ifdef HAS_DIRECTIONAL_DERIVATIVES /* the connector: d force / d (x, v), scalars (connector.h) */
{
    BEGIN(fmi3GetDirectionalDerivative, MASK_GET);
    if (nSeed != nKnowns || nSensitivity != nUnknowns) {
        say(c, ST_ERROR, "fmi3GetDirectionalDerivative refused: %zu seeds for %zu knowns, %zu sensitivities for %zu "
            "unknowns (scalars: one each)", nSeed, nKnowns, nSensitivity, nUnknowns);
        return fmi3Error;
    }
    return (fmi3Status)core_directional_derivative(c, unknowns, nUnknowns, knowns, nKnowns, seed, sensitivity,
                                                   "fmi3GetDirectionalDerivative");
}
#else
{
    return not_provided(instance, "fmi3GetDirectionalDerivative: not provided by this co-simulation FMU");
}
#endif

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)
{
    return not_provided(instance, "fmi3GetAdjointDerivative: not provided by this co-simulation FMU");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EnterConfigurationMode: not provided by this co-simulation FMU");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3ExitConfigurationMode: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
{
    return not_provided(instance, "fmi3GetIntervalDecimal: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[])
{
    return not_provided(instance, "fmi3GetIntervalFraction: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 shifts[])
{
    return not_provided(instance, "fmi3GetShiftDecimal: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    return not_provided(instance, "fmi3GetShiftFraction: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 intervals[])
{
    return not_provided(instance, "fmi3SetIntervalDecimal: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    return not_provided(instance, "fmi3SetIntervalFraction: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 shifts[])
{
    return not_provided(instance, "fmi3SetShiftDecimal: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    return not_provided(instance, "fmi3SetShiftFraction: not provided by this co-simulation FMU");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EvaluateDiscreteStates: not provided by this co-simulation FMU");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate, fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged, fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined, fmi3Float64* nextEventTime)
{
    return not_provided(instance, "fmi3UpdateDiscreteStates: not provided by this co-simulation FMU");
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EnterContinuousTimeMode: not provided by this co-simulation FMU");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation)
{
    return not_provided(instance, "fmi3CompletedIntegratorStep: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    return not_provided(instance, "fmi3SetTime: not provided by this co-simulation FMU");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[], size_t nContinuousStates)
{
    return not_provided(instance, "fmi3SetContinuousStates: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t nContinuousStates)
{
    return not_provided(instance, "fmi3GetContinuousStateDerivatives: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators)
{
    return not_provided(instance, "fmi3GetEventIndicators: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates)
{
    return not_provided(instance, "fmi3GetContinuousStates: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nContinuousStates)
{
    return not_provided(instance, "fmi3GetNominalsOfContinuousStates: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* nEventIndicators)
{
    return not_provided(instance, "fmi3GetNumberOfEventIndicators: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* nContinuousStates)
{
    return not_provided(instance, "fmi3GetNumberOfContinuousStates: not provided by this co-simulation FMU");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues)
#ifdef HAS_OUTPUT_DERIVATIVES /* the element: x, v, reaction; the connector: force (front.h) */
    CHECKED(fmi3GetOutputDerivatives, MASK_OUTPUT_DERIVATIVES,
            core_get_output_derivatives(c, valueReferences, nValueReferences, orders, values, nValues,
                                        "fmi3GetOutputDerivatives"))
#else
{
    return not_provided(instance, "fmi3GetOutputDerivatives: not provided by this co-simulation FMU");
}
#endif

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime)
{
    return not_provided(instance, "fmi3ActivateModelPartition: not provided by this co-simulation FMU");
}
