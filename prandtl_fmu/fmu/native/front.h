/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* What the FMI 2.0 (fmi2.c) and FMI 3.0 (fmi3.c) layers do alike, written once: an instance made, started with its
 * defaults, reset and freed; the debug logging; the setters of the Real/Float64, Integer/Int32, Boolean and String
 * variables (all or nothing) and the checks of a getter's value references; each function's words name the
 * version's function (FMI: "fmi2", "fmi3"). Glue only. */
#ifndef PRANDTL_FRONT_H
#define PRANDTL_FRONT_H
#include "machine.h"

/* Every function first checks its instance (NULL: Error, nothing logged: there is no logger) and the call sequence
 * (calls.h: allowed in the phases of ``mask``, the version's state machine for co-simulation); its pointers are
 * checked where they are used (NULL: Error with the reason logged). A refusal leaves the instance as it was.
 * BEGIN: the instance ``c`` of a call (its FmiInstance argument ``instance``), or return Error. */
#define BEGIN(function, mask)                                                                                  \
    Instance* c = (Instance*)instance;                                                                         \
    if (c == NULL)                                                                                             \
        return (FmiStatus)ST_ERROR;                                                                            \
    if (!allowed(c, (mask), #function))                                                                        \
        return (FmiStatus)ST_ERROR

/* the body of a function that is its checks, then ``call`` (a status) */
#define CHECKED(function, mask, call)                                                                          \
    {                                                                                                          \
        BEGIN(function, mask);                                                                                 \
        return (FmiStatus)(call);                                                                              \
    }

/* the six functions of the FMU state (machine.h), alike in both versions but for their names */
#define STATE_FUNCTIONS(get, set, release, size_of, serialize, deserialize)                                    \
    FmiStatus get(FmiInstance instance, FmiState* state) CHECKED(get, ANY_PHASE, core_get_state(c, state))    \
    FmiStatus set(FmiInstance instance, FmiState state) CHECKED(set, ANY_PHASE, core_set_state(c, state))     \
    FmiStatus release(FmiInstance instance, FmiState* state)                                                   \
        CHECKED(release, ANY_PHASE, core_free_state(c, state))                                                 \
    FmiStatus size_of(FmiInstance instance, FmiState state, size_t* size)                                      \
        CHECKED(size_of, ANY_PHASE, core_state_size(c, state, size))                                           \
    FmiStatus serialize(FmiInstance instance, FmiState state, FmiByte bytes[], size_t size)                    \
        CHECKED(serialize, ANY_PHASE, core_serialize(c, state, (char*)bytes, size))                            \
    FmiStatus deserialize(FmiInstance instance, const FmiByte bytes[], size_t size, FmiState* state)           \
        CHECKED(deserialize, ANY_PHASE, core_deserialize(c, (const char*)bytes, size, state))

/* fmi2/3EnterInitializationMode, Terminate: the instance goes to ``phase`` */
static int phase_to(Instance* c, int phase)
{
    c->phase = phase;
    return ST_OK;
}

/* a new instance for the host's environment and logger, which ``emit`` calls (the FMI version's: not yet started,
 * instance_started), or NULL (out of memory) */
static Instance* instance_new(const char* name, void* env, void* logger, Emit emit, int logging)
{
    Instance* c = (Instance*)calloc(1, sizeof(Instance));
    if (c == NULL)
        return NULL;
    c->env = env;
    c->logger = logger;
    c->emit = emit;
    c->name = strdup(name ? name : "");
    c->logging = logging ? 1 : 0;
    if (c->name == NULL) {
        free(c);
        return NULL;
    }
    return c;
}

static void instance_free(Instance* c)
{
    if (c == NULL)
        return;
#ifdef RELEASE_INSTANCE
    RELEASE_INSTANCE(c);
#endif
    free(c->name);
    free(c);
}

/* the instance with its defaults, or NULL: refused (logged) and freed */
static Instance* instance_started(Instance* c)
{
    defaults(c);
#ifdef INSTANCE_FAILED
    if (INSTANCE_FAILED(c)) {
        instance_free(c);
        return NULL;
    }
#endif
    return c;
}

/* fmi2/3Reset: the defaults again (ST_ERROR, logged: the memory's state could not be allocated) */
static int core_reset(Instance* c)
{
    defaults(c);
#ifdef INSTANCE_FAILED
    if (INSTANCE_FAILED(c))
        return ST_ERROR;
#endif
    return ST_OK;
}

/* fmi2/3SetDebugLogging: the categories are every one or none (each named must be given) */
static int core_set_debug_logging(Instance* c, int on, size_t n, const char* const categories[])
{
    size_t i;
    if (n > 0 && !given(c, categories, FMI "SetDebugLogging", "categories"))
        return ST_ERROR;
    for (i = 0; i < n; i++) {
        if (categories[i] == NULL) {
            say(c, ST_ERROR, FMI "SetDebugLogging refused: categories[%zu] is NULL", i);
            return ST_ERROR;
        }
    }
    c->logging = on ? 1 : 0;
    return ST_OK;
}

/* the ``n`` value references of a getter or setter (``function``) and its values: given (unless n is 0), each a
 * variable of ``type``, at most ``nvalues`` of them (FMI 3.0's count of values; FMI 2.0: n): 1, or 0 with the
 * first refused logged in ``words`` (of its value reference) */
static int all_of_type(Instance* c, const unsigned vr[], size_t n, const void* values, size_t nvalues, int type,
                       const char* function, const char* words)
{
    size_t i;
    if (!arrays_given(c, n, vr, values, function))
        return 0;
    for (i = 0; i < n; i++) {
        if (find(vr[i], type) == NULL || i >= nvalues) {
            say(c, ST_ERROR, words, vr[i]);
            return 0;
        }
    }
    return 1;
}

/* the body of the getter ``function`` of the variables of ``type`` (refused in ``words``): ``count`` values at
 * most (FMI 2.0: nvr; FMI 3.0: nvalues), each ``value`` */
#define GETTER(function, type, words, count, value)                                                            \
    {                                                                                                          \
        size_t i;                                                                                              \
        BEGIN(function, MASK_GET);                                                                             \
        if (!all_of_type(c, vr, nvr, values, (count), (type), #function, words))                               \
            return (FmiStatus)ST_ERROR;                                                                        \
        for (i = 0; i < nvr; i++)                                                                              \
            values[i] = (value);                                                                               \
        return (FmiStatus)ST_OK;                                                                               \
    }

/* fmi2/3SetBoolean: the one Boolean, scene_load, is ``last`` (the last value: each sets it in turn) */
static int core_set_scene_load(Instance* c, const unsigned vr[], size_t n, const void* values, size_t nvalues,
                               int last, const char* words)
{
    if (!all_of_type(c, vr, n, values, nvalues, T_BOOLEAN, FMI "SetBoolean", words))
        return ST_ERROR;
    if (n > 0)
        c->scene_load = last ? 1 : 0;
    return ST_OK;
}

/* fmi2SetReal, fmi3SetFloat64: every value checked (core_check_float), then all set */
static int core_set_floats(Instance* c, const unsigned vr[], size_t n, const double values[])
{
    size_t i;
    if (!arrays_given(c, n, vr, values, FLOAT_SETTER))
        return ST_ERROR;
    for (i = 0; i < n; i++)
        if (core_check_float(c, find(vr[i], T_REAL), vr[i], values[i]) != ST_OK)
            return ST_ERROR;
    for (i = 0; i < n; i++)
        core_set_float(c, find(vr[i], T_REAL), values[i]);
    return ST_OK;
}

/* fmi2SetInteger, fmi3SetInt32 (``function``; ``nvalues`` FMI 3.0's count of values, FMI 2.0: n): every value
 * reference checked, then all set */
static int core_set_integers(Instance* c, const unsigned vr[], size_t n, const int values[], size_t nvalues,
                             const char* function)
{
    size_t i;
    if (!arrays_given(c, n, vr, values, function))
        return ST_ERROR;
    if (nvalues < n) {
        say(c, ST_ERROR, "%s refused: %zu values for %zu value references", function, nvalues, n);
        return ST_ERROR;
    }
    for (i = 0; i < n; i++)
        if (core_check_integer(c, find(vr[i], T_INTEGER), vr[i], function) != ST_OK)
            return ST_ERROR;
    for (i = 0; i < n; i++)
        core_set_integer(c, find(vr[i], T_INTEGER), values[i]);
    return ST_OK;
}

/* fmi2/3SetString: the stepper's name, each value given (``values_name``: the version's name of the argument) */
static int core_set_strings(Instance* c, const unsigned vr[], size_t n, size_t nvalues, const char* const values[],
                            const char* values_name)
{
    size_t i;
    if (!arrays_given(c, n, vr, values, FMI "SetString"))
        return ST_ERROR;
    for (i = 0; i < n; i++) {
        if (find(vr[i], T_STRING) == NULL || i >= nvalues) {
            say(c, ST_ERROR, FMI "SetString refused: value reference %u is not the String parameter stepper", vr[i]);
            return ST_ERROR;
        }
        if (values[i] == NULL) {
            say(c, ST_ERROR, FMI "SetString refused: %s[%zu] is NULL (a stepper's name is needed)", values_name, i);
            return ST_ERROR;
        }
    }
    for (i = 0; i < n; i++)
        core_set_stepper(c, values[i]);
    return ST_OK;
}

/* the body of fmi2GetRealOutputDerivatives and fmi3GetOutputDerivatives (``function``): every entry checked and
 * computed by the kind's output_derivative (element.h, connector.h), then written (nothing written on a refusal) */
#ifdef HAS_OUTPUT_DERIVATIVES
static int core_get_output_derivatives(Instance* c, const unsigned vr[], size_t n, const int order[], double value[],
                                       size_t nvalues, const char* function)
{
    char buffer[256];
    size_t i;
    double found[8];
    if (!arrays_given(c, n, vr, value, function) || !(n == 0 || given(c, order, function, "order")))
        return ST_ERROR;
    if (nvalues < n || n > sizeof found / sizeof found[0]) {
        say(c, ST_ERROR, "%s refused: %zu value references for %zu values (at most %zu at once)", function, n, nvalues,
            sizeof found / sizeof found[0]);
        return ST_ERROR;
    }
    for (i = 0; i < n; i++) {
        const char* problem = output_derivative(c, find(vr[i], T_REAL), order[i], &found[i], buffer, sizeof buffer);
        if (problem != NULL) {
            say(c, ST_ERROR, "%s refused: value reference %u, order %d: %s; nothing written", function, vr[i],
                (int)order[i], problem);
            return ST_ERROR;
        }
    }
    memcpy(value, found, n * sizeof(double));
    return ST_OK;
}
#endif

#endif
