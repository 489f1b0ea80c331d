/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The services of the instance layer, written once for every kind (the element, element.h; its connector,
 * connector.h; a network and its connector, network.h) and called by them: an instance's start values, the setters of
 * the stepper and the noise's seed, the memory's arrays of the effects with memory and their place in an FMU state,
 * the first output a step leaves that is not a number. It reads the kind's types (kind.h: Element, State, Instance,
 * the macros MEMORY_ARRAYS, STEP_OUTPUT, KIND_INTEGERS) and calls none of the kind's functions: what calls them is
 * machine.h, above the kinds. */
#ifndef PRANDTL_CORE_H
#define PRANDTL_CORE_H
#include "kind.h"

/* defaults(): what every instance starts from (the settings a master sets: each kind's own) */
static void instantiated(Instance* c)
{
    c->start_time = 0.0;
    c->initialized = 0;
    c->phase = INSTANTIATED;
    c->last_step_failed = 0;
#if !KIND_INTEGERS
    snprintf(c->stepper, sizeof c->stepper, "%s", DEFAULT_STEPPER);
    c->stepper_valid = 1;
    c->step = DEFAULT_STEP;
    c->F = 0.0;
    c->scene_load = SCENE_LOAD_START; /* true when the scene names a load: a fresh FMU runs the scene */
    c->handed = 0;
    c->noise_set = SCENE_NOISE;
    memset(c->noise_cache, 0, sizeof c->noise_cache); /* a new cache (noise.new_cache) */
#endif
}

/* the first output (STEP_OUTPUT) that is not a number to show after a step, its value (``value_of``: the kind's
 * real_value) in ``value``, or NULL */
static const Var* unshowable_output(Instance* c, double (*value_of)(Instance*, const Var*), double* value)
{
    int i;
    for (i = 0; i < N_VARS; i++) {
        const Var* var = &VARS[i];
        if (!STEP_OUTPUT(var->what))
            continue;
        *value = value_of(c, var);
        if (!showable(var, *value))
            return var;
    }
    return NULL;
}

#if !KIND_INTEGERS /* the element and the network: a stepper to choose and a noise's seed */
/* the index of the stepper ``name`` in STEPPER_NAMES (the steppers this FMU holds), or -1 */
static int stepper_index(const char* name)
{
    int i;
    for (i = 0; i < N_STEPPERS; i++)
        if (strcmp(name, STEPPER_NAMES[i]) == 0)
            return i;
    return -1;
}

static void core_set_stepper(Instance* c, const char* value)
{
    c->stepper_valid = strlen(value) < sizeof c->stepper;
    snprintf(c->stepper, sizeof c->stepper, "%s", c->stepper_valid ? value : "");
    c->handed = 0;
}

/* an Integer the master sets: noise_seed alone (its rule is checked when it is handed over) */
static int core_check_integer(Instance* c, const Var* var, unsigned vr, const char* function)
{
    if (var == NULL || var->what != W_NOISE_SEED) {
        say(c, ST_ERROR, "%s refused: value reference %u is not the Integer parameter noise_seed", function, vr);
        return ST_ERROR;
    }
    return ST_OK;
}

static void core_set_integer(Instance* c, const Var* var, int32_t value)
{
    (void)var;
    c->noise_set.seed = value;
    c->handed = 0;
}
#endif

#if !NETWORK /* the effects with memory (the element and its connector) */
/* the memory's state of ``length`` values in each of MEMORY_ARRAYS(c) (the element's, and its copies: the
 * checkpoint's, the connector's preview): NULL, or why not (out of memory; the instance keeps its arrays) */
static const char* allocate_memory(Instance* c, int64_t length, char* buffer, size_t size)
{
    double** arrays[] = MEMORY_ARRAYS(c);
    double* fresh[sizeof arrays / sizeof *arrays];
    size_t i, count = sizeof arrays / sizeof *arrays;
    int failed = 0;
    if (c->el.mem != NULL && length == c->el.mem_len)
        return NULL;
    for (i = 0; i < count; i++) {
        fresh[i] = (double*)calloc((size_t)(length > 0 ? length : 1), sizeof(double));
        failed |= fresh[i] == NULL;
    }
    if (failed) {
        for (i = 0; i < count; i++)
            free(fresh[i]);
        snprintf(buffer, size, "out of memory for the state of the effects with memory (%.0f values: the delay's "
                 "buffer at tau = %.17g s)", (double)length, HAS_DELAY ? MEMORY_TAU(c) : 0.0);
        return buffer;
    }
    for (i = 0; i < count; i++) {
        free(*arrays[i]);
        *arrays[i] = fresh[i];
    }
    MEMORY_SIZED(c, length);
    return NULL;
}

/* the memory's state sized for the parameters in use (el.mp: the delay's tau), at instantiation, at the exit of
 * initialization mode and at a reset: NULL, or why not */
static const char* size_memory(Instance* c, char* buffer, size_t size)
{
    int64_t nd = delay_size(c->el.mp);
    const char* problem;
    if (!HAS_MEMORY)
        return NULL;
    if (nd < 0)
        return memory_problem(c->el.mp, buffer, size);
    problem = allocate_memory(c, MEM_FIXED + nd, buffer, size);
    if (problem == NULL)
        c->el.nd = nd;
    return problem;
}

static void release_memory(Instance* c)
{
    double** arrays[] = MEMORY_ARRAYS(c);
    size_t i;
    for (i = 0; i < sizeof arrays / sizeof *arrays; i++) {
        free(*arrays[i]);
        *arrays[i] = NULL;
    }
    c->el.mem_len = c->el.nd = 0;
}
#define RELEASE_INSTANCE(c) release_memory(c)
#define INSTANCE_FAILED(c) ((c)->memory_failed)

/* a parameter of an effect with memory set after initialization (fixed: slave._set_parameter,
 * the PythonFMU slave's _set_parameter): ST_ERROR with the refusal, or ST_OK */
static int memory_fixed(Instance* c, const Var* var, double value)
{
    char shown[40];
    if (!(var->what == W_MEMORY && c->initialized && value != c->mpar[var->index]))
        return ST_OK;
    say(c, ST_ERROR, "parameter %s = %s refused: %s is fixed (%s) and cannot change after initialization; the %s is "
        "unchanged", MEM_NAMES[var->index], python_repr(value, shown, sizeof shown), MEM_NAMES[var->index],
        ELEMENT_CONNECTOR ? "an effect with memory" : "the initial state, or an effect with memory",
        ELEMENT_CONNECTOR ? "connector" : "element");
    return ST_ERROR;
}

/* defaults(): the element cleared but its memory's arrays (size_memory resizes them) */
static void clear_element(Element* e)
{
    double* mem = e->mem;
    int64_t length = e->mem_len;
    memset(e, 0, sizeof *e);
    e->mem = mem;
    e->mem_len = length;
}

/* defaults(): the memory sized for the parameters set (el.mp), or the instance refused: 1, or 0 (logged) */
static int memory_at_instantiation(Instance* c)
{
    char buffer[256];
    const char* problem = size_memory(c, buffer, sizeof buffer);
    c->memory_failed = problem != NULL;
    if (problem != NULL)
        say(c, ST_ERROR, "instantiation refused: %s", problem);
    return problem == NULL;
}

/* why the memory of a state blob (its parameters in use and set, its values after the fixed part) cannot be
 * restored, or NULL (Element.set_state, Connector.set_state: memory.check_memory_state's rules, numbers only) */
static const char* memory_state_problem(const State* s, char* buffer, size_t size)
{
    const Element* e = &s->element;
    const char* problem;
    if (!HAS_MEMORY)
        return memory_values_problem(e->mp, NULL, e->nd, e->mem_len, element_time(e), buffer, size);
    problem = memory_problem(e->mp, buffer, size);
    if (problem == NULL && ELEMENT_CONNECTOR) /* (the element checks the parameters set with its settings) */
        problem = memory_problem(s->mpar, buffer, size);
    if (problem != NULL)
        return problem;
    if (s->initialized && memcmp(s->mpar, e->mp, sizeof e->mp) != 0) /* fixed: set before initialization */
        return "its memory's parameters in use are not those set";
    return memory_values_problem(e->mp, (const double*)(s + 1), e->nd, e->mem_len, element_time(e), buffer, size);
}

/* the memory stack of a state (``k`` its parameters, ``u`` its state): stack.restore's rules, compiled
 * (state_check); the reason, or NULL */
static const char* stack_problem(const double* k, const double* u)
{
    double* scratch = (double*)malloc(STATE_SCRATCH * sizeof(double));
    int64_t code;
    if (scratch == NULL)
        return "out of memory";
    prandtl_kernel_failed = 0;
    code = state_check((double*)k, (double*)u, scratch);
    free(scratch);
    if (prandtl_kernel_failed)
        return "its memory stack could not be checked";
    return code != 0 ? STATE_CHECK_REASONS[code - 1] : NULL;
}
#endif

#endif
