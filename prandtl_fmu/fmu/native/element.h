/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/test_native_refusals.py checks the refusals against the library's. */
/* The native FMU's element, shared by its FMI 2.0 (fmi2.c) and FMI 3.0 (fmi3.c) layers: glue only, no numerics.
 *
 * Every number comes from the library's kernels, compiled by numba for this scene (fmu/native/kernels.py)
 * and declared in the generated "scene.h" with the scene's constants, the variables of the FMU (the same
 * names and value references as the PythonFMU FMU of the scene) and the kernels' symbols. This file does
 * what fmu/python/slave.py and driver.Element do around them, in the same order of floating-point operations:
 * the element's clock (origin + steps * grid), a duration split into whole steps and a last shorter one,
 * the parameters handed over at a step (a white noise turned off first, one turned on last), the refusals
 * (fmi2Discard for a bad input, a step of more internal steps than ADVANCE_BUDGET, a step that fails or whose
 * outputs would not be finite, the state unchanged;
 * fmi2Error for a bad start value, a non-finite time or a bad FMU state, checked field by field; logged even
 * with logging off, never a NULL category).
 *
 * The effects with memory (memory/: [delay], [history], [dahl]): their parameters are the FMU's fixed ones (mp),
 * their state an array on the heap (mem: the history's variables, the Dahl force, the delay's buffer of nd values,
 * sized at the exit of initialization mode and at a reset from the delay's tau in use, kernels.memory_layout),
 * handed to every kernel, which rebuilds the library's tuple from them. A checkpoint copies it, an FMU state
 * carries it after its fixed part (state.h: STATE_EXTRA).
 */
#ifndef PRANDTL_ELEMENT_H
#define PRANDTL_ELEMENT_H
#include "common.h"

typedef struct {
    double p[N_PARAMS];   /* the coefficients in use */
    double cs[NB_CS];    /* the series dashpots in use */
    int stepper;          /* index into STEPPER_NAMES */
    double h;
    double x, v, u[NB_ARR];
    int play;             /* FOLDS: the stack unfolded to the n elongations up (a stepper that does not take it) */
    double up[NB_PLAY];
    double kst[K_LEN];    /* FOLDS: the stack's parameters, referring to the elongations of the last fold */
    double account[4], out[3], erow[6], initial_energy;
    double origin, grid;  /* the clock: time = origin + steps * grid (grid 0: none yet) */
    int64_t steps;
    double force;         /* the load of the last advance: force, plus the scene's [load] with scene_load */
    int scene_load;
    double mp[N_MEMP];    /* the effects with memory: their parameters in use (kernels.memory_layout) */
    int64_t nd;           /* the delay's buffer: its values (memory.delay.size at the tau in use; 0: no delay) */
    int64_t mem_len;      /* the memory's state: MEM_FIXED + nd values */
    double* mem;          /* ... on the heap (NULL in a state blob: its values follow the blob's fixed part) */
} Element;

typedef struct {
    char header[24];
    uint32_t version, size;
    char digest[65];
    Element element;
    double F, step, start_time, par[N_PARAMS], cbranch[NB_CS];
    int scene_load, stepper_valid, initialized;
    char stepper[32];
    double mpar[N_MEMP]; /* the memory's parameters the master set */
    Noise noise_set;   /* the white noise's settings (nothing drawn: the path is a function of seed and time) */
    uint64_t checksum;   /* of the fixed part and the memory's state, element.mem_len values after it */
} State;
/* the doubles an FMU state holds after its fixed part (state.h), or (size_t)-1 when its count is out of range */
#define MEM_MAX ((int64_t)MEM_FIXED + (int64_t)DELAY_BOUND + DELAY_HEAD + 5)
#define STATE_EXTRA(s) ((s)->element.mem_len >= 0 && (s)->element.mem_len <= MEM_MAX ? \
                        (size_t)(s)->element.mem_len : (size_t)-1)
#define INSTANCE_EXTRA(c) ((size_t)(c)->el.mem_len)
#define RELEASE_INSTANCE(c) release_memory(c)
#define INSTANCE_FAILED(c) ((c)->memory_failed)

/* what an advance changes (driver.Element.checkpoint): a step that fails is rolled back from it; the branches'
 * state is copied in its part in use only (the memory stack's pieces), into the instance's buffer */
typedef struct {
    double x, v, account[4], out[3], erow[6], origin, grid, force;
    int64_t steps;
    int scene_load;
    size_t used;
} Checkpoint;
#define SAVED_U (NB_ARR > NB_PLAY ? NB_ARR : NB_PLAY)

typedef struct {
    char* name;
    void* env;         /* the host's: its environment and logger (the FMI version's layer calls it, emit()) */
    void* logger;
    int logging, phase, last_step_failed;
    Element el;
    /* what the master set */
    double F, step, start_time, par[N_PARAMS], cbranch[NB_CS];
    int scene_load, initialized;
    char stepper[32];
    int stepper_valid; /* the string fitted in the buffer */
    Noise noise_set;   /* noise_intensity, noise_seed, noise_unit */
    int handed;        /* the settings were handed over and nothing changed since */
    Noise noise;       /* the white noise handed over (sigma 0: none), on the force of every advance */
    int64_t noise_cache[NOISE_CACHE_SIZE]; /* the Brownian tree's cache: scratch, never in the state */
    Checkpoint saved;  /* core_do_step's, on the heap with the instance (never a large copy on the host's stack) */
    double saved_u[SAVED_U];
    double mpar[N_MEMP]; /* the memory's parameters the master set (fixed: before initialization only) */
    double* saved_mem;   /* the checkpoint's memory state (el.mem_len values) */
    int memory_failed;   /* the memory's state could not be allocated at instantiation (the instance is refused) */
} Instance;

/* ------------------------------------------------------------------ the element */

static double element_time(const Element* e) { return e->steps ? e->origin + (double)e->steps * e->grid : e->origin; }

static void set_time(Element* e, double value)
{
    if (e->grid != 0.0 && fabs(value - element_time(e)) <= 1e-9 * e->grid)
        return;
    e->origin = value;
    e->steps = 0;
}

static int damped(const Element* e) { return HAS_DAMPER && e->p[P_C] > 0.0; }

/* The branches' arrays of the kernel in use (driver.Element's model[4:6] and u): the scene's (n elongations, or
 * the memory stack), or with FOLDS the stack's parameters as last folded, or the O(n) kernel's when unfolded. */
static double* kernel_k(Element* e) { return e->play ? (double*)K_PLAY : FOLDS ? e->kst : (double*)K; }
static double* kernel_eta(Element* e) { return e->play ? (double*)ETA_PLAY : (double*)ETA; }
static double* kernel_u(Element* e) { return e->play ? e->up : e->u; }
static double* memory_of(Element* e) { return e->mem != NULL ? e->mem : e->mp; } /* (no memory: never read) */
#define BRANCHES(e) (e)->p, kernel_k(e), kernel_eta(e), (e)->cs, kernel_u(e), (e)->mp, memory_of(e), (e)->nd
#define KERNEL(e, name) ((e)->play ? (damped(e) ? name##_cp : name##_np) : (damped(e) ? name##_c : name##_n))

static void record(Element* e, double t)
{
    Load l = load_of(e->force, e->scene_load, NULL, NULL); /* the outputs read F(t) alone (loads.force_at) */
    double xv[2] = {e->x, e->v};
    KERNEL(e, record)(BRANCHES(e), xv, e->account, e->out, e->erow, l.kind, l.lk, (double*)l.t, (double*)l.f, l.n,
                      t);
}

/* ------------------------------------------------------------------ the effects with memory */

/* Element.set_step's rule with memory: a negative delay gain with tau below the step in use, or NULL */
static const char* memory_step_problem(const double* mp, double step, char* buffer, size_t size)
{
    char a[40], b[40], c[40];
    if (!(HAS_DELAY && !QUASI_STATIC && mp[0] < 0 && mp[1] < step))
        return NULL;
    snprintf(buffer, size, "parameter step = %s: a negative gain with tau = %s s below the step %s s makes the implicit "
             "equation of a step non-monotone (no unique solution): add [mass] or a [damper], or a longer tau",
             python_repr(step, a, sizeof a), python_repr(mp[1], b, sizeof b), python_repr(step, c, sizeof c));
    return buffer;
}

/* the memory's state (and the checkpoint's) of ``length`` values: NULL, or why not (out of memory; the instance
 * keeps its arrays) */
static const char* allocate_memory(Instance* c, int64_t length, char* buffer, size_t size)
{
    double *mem, *saved;
    if (c->el.mem != NULL && length == c->el.mem_len)
        return NULL;
    mem = (double*)calloc((size_t)(length > 0 ? length : 1), sizeof(double));
    saved = (double*)calloc((size_t)(length > 0 ? length : 1), sizeof(double));
    if (mem == NULL || saved == NULL) {
        free(mem);
        free(saved);
        snprintf(buffer, size, "out of memory for the state of the effects with memory (%.0f values: the delay's "
                 "buffer at tau = %.17g s)", (double)length, HAS_DELAY ? c->el.mp[1] : 0.0);
        return buffer;
    }
    free(c->el.mem);
    free(c->saved_mem);
    c->el.mem = mem;
    c->saved_mem = saved;
    c->el.mem_len = length;
    return NULL;
}

/* the memory's state sized for the parameters in use (el.mp: the delay's tau), at the exit of initialization mode
 * and at a reset: NULL, or why not */
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
    free(c->el.mem);
    free(c->saved_mem);
    c->el.mem = c->saved_mem = NULL;
    c->el.mem_len = c->el.nd = 0;
}

/* Element.reset(force): the initial state under the force held; 0 when a massless element has no equilibrium */
static int reset(Element* e, double force)
{
    Load l = load_of(force, 0, NULL, NULL);
    double xv[2];
    int ok;
    e->origin = 0.0;
    e->steps = 0;
    e->grid = 0.0;
    e->force = force;
    e->scene_load = 0;
    e->play = FOLDS && e->stepper >= 0 && !TAKES_STACK[e->stepper]; /* driver.choose_branch_kernel */
    if (FOLDS)
        memcpy(e->kst, K, sizeof e->kst);
    memcpy(e->u, U0, sizeof e->u);
    memcpy(e->up, U0_PLAY, sizeof e->up);
    ok = (int)KERNEL(e, initial)(BRANCHES(e), xv, l.kind, l.lk, (double*)l.t, (double*)l.f, l.n);
    if (!ok || prandtl_kernel_failed)
        return 0;
    e->x = xv[0];
    e->v = xv[1];
    memset(e->account, 0, sizeof e->account);
    record(e, 0.0);
    e->initial_energy = e->erow[0] + e->erow[1];
    return 1;
}

/* stepping.split_duration: whole steps of h, then a last shorter one; within 1e-9 h of whole steps, whole steps
 * only, and a remainder below 1e-9 h after them (a duration below it too: no step at all) is a master's clock's
 * rounding, dropped */
static void split_duration(double duration, double h, double* whole, double* rest)
{
    double ratio = duration / h, nearest = nearbyint(ratio);
    if (nearest >= 1 && fabs(ratio - nearest) <= 1e-9) {
        *whole = nearest;
        *rest = 0.0;
        return;
    }
    *whole = floor(ratio);
    *rest = duration - *whole * h;
    if (!(*rest >= 1e-9 * h))
        *rest = 0.0;
}

static int64_t integrate(Element* e, const Load* l, double t_base, int64_t first, double h, int64_t steps)
{
    double xv[2] = {e->x, e->v};
    int64_t taken;
    if (l->noise.sigma != 0.0) { /* the load tuple with its noise (loads.with_white_noise): the noisy kernel */
        noisy_fn noisy = (e->play ? (damped(e) ? NOISY_CP : NOISY_NP) : (damped(e) ? NOISY_C : NOISY_N))[e->stepper];
        if (noisy == NULL) /* a stepper that takes no noise: refused when the settings are handed over */
            return -1;
        taken = noisy(BRANCHES(e), xv, e->account, e->out, e->erow, l->kind, (double*)l->lk, (double*)l->t,
                      (double*)l->f, l->n, t_base, first, h, steps, l->noise.sigma, l->noise.seed, l->noise.unit,
                      l->cache);
    } else {
        taken = (e->play ? (damped(e) ? ADVANCE_CP : ADVANCE_NP) : (damped(e) ? ADVANCE_C : ADVANCE_N))[e->stepper](
            BRANCHES(e), xv, e->account, e->out, e->erow, l->kind, (double*)l->lk, (double*)l->t, (double*)l->f,
            l->n, t_base, first, h, steps);
    }
    if (prandtl_kernel_failed)
        return -1;
    e->x = xv[0];
    e->v = xv[1];
    return taken;
}

/* Element.advance under ``force`` (plus the scene's [load] with ``scene_load``) and the white ``noise`` (its
 * Brownian tree's ``cache``): NULL, or why the step was not taken (the element then is as it was: the caller rolls
 * back); ``failed_at`` NaN: refused before any step (a duration of too many steps) */
static const char* advance(Element* e, double duration, double force, int scene_load, const Noise* noise,
                           int64_t* cache, double* failed_at, char* buffer, size_t size)
{
    double h = e->h, whole, rest, t_base;
    int64_t first, taken;
    Load l;
    *failed_at = NAN;
    if (duration == 0.0)
        return NULL;
    if (STEP_IS_OUTPUT[e->stepper]) { /* one step per advance (exact) ... */
        h = duration;
        if (e->grid != 0.0 && fabs(duration - e->grid) <= 1e-9 * e->grid)
            h = e->grid; /* ... of the grid's step when it is that to rounding */
    }
    if (duration < SHORTEST_STEP) {
        snprintf(buffer, size, "the duration is shorter than %g s (a step's square underflows)", SHORTEST_STEP);
        return buffer;
    }
    if (!(duration / h < MAX_STEPS)) {
        snprintf(buffer, size, "the duration is more than %.17g internal steps (2^53): advance by shorter durations "
                 "or with a larger step", MAX_STEPS);
        return buffer;
    }
    split_duration(duration, h, &whole, &rest);
    if (whole == 0 && rest == 0) /* below rounding of h: no step, the clock stays on its grid (Element.advance) */
        return NULL;
    if (whole + (rest > 0) > ADVANCE_BUDGET) { /* Element.advance: ElementError, never run for days */
        snprintf(buffer, size, "an advance of %.17g s takes %.4g steps of h = %.17g s, more than the budget of %.0e "
                 "steps of one advance: advance by shorter durations (communication steps) or with a larger step",
                 duration, whole + (rest > 0), h, ADVANCE_BUDGET);
        return buffer;
    }
    {
        const char* problem = delay_time_problem(e->mem, element_time(e), element_time(e) + duration, buffer, size);
        if (problem != NULL)
            return problem;
    }
    l = load_of(force, scene_load, noise, cache);
    e->force = force;
    e->scene_load = scene_load;
    if (e->grid != h) {
        e->origin = element_time(e);
        e->steps = 0;
        e->grid = h;
    }
    t_base = e->origin;
    first = e->steps;
    if (whole > 0) {
        taken = integrate(e, &l, t_base, first, h, (int64_t)whole);
        if (taken < (int64_t)whole) {
            *failed_at = taken < 0 ? t_base : t_base + (double)(first + (taken < 0 ? 0 : taken)) * h;
            return "a step could not be taken (it would leave a non-finite state)";
        }
    }
    if (rest > 0) {
        double start = t_base + (double)(first + (int64_t)whole) * h;
        taken = integrate(e, &l, start, 0, rest, 1);
        if (taken < 1) {
            *failed_at = start;
            return "a step could not be taken (it would leave a non-finite state)";
        }
        e->origin = e->origin + (double)(e->steps + (int64_t)whole) * h + rest;
        e->steps = 0;
    } else {
        e->steps += (int64_t)whole;
    }
    return NULL;
}

/* ------------------------------------------------------------------ parameters */

static int stepper_index(const char* name)
{
    int i;
    for (i = 0; i < N_STEPPERS; i++)
        if (strcmp(name, STEPPER_NAMES[i]) == 0)
            return i;
    return -1;
}

static const char* stepper_problem(const Instance* c, char* buffer, size_t size)
{
    if (!c->stepper_valid || stepper_index(c->stepper) < 0) {
        snprintf(buffer, size, "parameter stepper = '%s': must be one of %s (the steppers that apply to this "
                 "scene)", c->stepper_valid ? c->stepper : "?", STEPPER_LIST);
        return buffer;
    }
    if (!(isfinite(c->step) && c->step > 0)) {
        snprintf(buffer, size, "parameter step = %.17g: must be finite and > 0", c->step);
        return buffer;
    }
    return NULL;
}

/* Element._use_branch_kernel("play"): the stack's n elongations, for a stepper that does not take it */
static void unfold(Element* e)
{
    (damped(e) ? elongations_c : elongations_n)(e->p, e->kst, (double*)ETA, e->cs, e->u, e->mp, memory_of(e), e->nd,
                                                e->up);
    e->play = 1;
    record(e, element_time(e));
}

/* Element._use_branch_kernel("stack") when the elongations are admissible (Element._can_fold); else the O(n)
 * kernel stays */
static void fold_back(Element* e)
{
    if (!stack_fold(e->kst, e->up, e->x, e->u))
        return;
    e->play = 0;
    record(e, element_time(e));
}

/* slave._hand_over_settings: the coefficients, stepper and step the master set go to the element */
static void hand_over(Instance* c)
{
    Element* e = &c->el;
    int stepper = stepper_index(c->stepper);
    int changed = memcmp(e->p, c->par, sizeof e->p) != 0 || memcmp(e->cs, c->cbranch, sizeof e->cs) != 0;
    memcpy(e->p, c->par, sizeof e->p);
    if (!HAS_STRIBECK)
        e->p[P_ALPHA_KINETIC] = e->p[P_ALPHA];
    memcpy(e->cs, c->cbranch, sizeof e->cs);
    memcpy(e->mp, c->mpar, sizeof e->mp); /* fixed: they change before initialization only (reset sizes them) */
    if (changed)
        record(e, element_time(e));
    if (FOLDS && c->initialized && stepper != e->stepper) { /* Element.set_stepper (reset chooses afresh) */
        if (!TAKES_STACK[stepper] && !e->play)
            unfold(e);
        else if (TAKES_STACK[stepper] && e->play)
            fold_back(e);
    }
    e->stepper = stepper;
    e->h = c->step;
    c->noise = c->noise_set; /* Element.set_noise (sigma 0: none) */
    c->handed = 1;
}

/* the coefficients, the stepper's name and the step: what a saved state's settings are checked for too */
static const char* settings_problem(Instance* c, char* buffer, size_t size)
{
    const char* problem = parameter_problem(c->par, c->cbranch, buffer, size);
    if (problem == NULL)
        problem = memory_problem(c->mpar, buffer, size);
    if (problem == NULL)
        problem = stepper_problem(c, buffer, size);
    return problem ? problem : memory_step_problem(c->mpar, c->step, buffer, size);
}

/* slave._hand_over_settings: why the settings the master set cannot be handed over, or NULL, in its order: a noise
 * turned off goes first (its values checked), then the coefficients, the stepper (Element.set_stepper under the
 * noise in use: the stepper's own refusal, NOISE_REFUSAL) and the step; a noise turned on goes last (its values,
 * then Element.set_noise: the stepper's refusal) */
static const char* hand_over_problem(Instance* c, char* buffer, size_t size)
{
    int turned_on = c->noise_set.sigma != 0.0, stepper; /* (a NaN intensity too: refused by its rule) */
    const char* problem = turned_on ? NULL : noise_problem(&c->noise_set, buffer, size);
    if (problem == NULL)
        problem = settings_problem(c, buffer, size);
    if (problem != NULL || !turned_on)
        return problem;
    stepper = stepper_index(c->stepper);
    if (c->noise.sigma != 0.0 && stepper != c->el.stepper && NOISE_REFUSAL[stepper] != NULL) {
        snprintf(buffer, size, "parameter stepper = '%s' refused: %s", c->stepper, NOISE_REFUSAL[stepper]);
        return buffer;
    }
    problem = noise_problem(&c->noise_set, buffer, size);
    if (problem == NULL)
        problem = noise_step_problem(&c->noise_set, c->step, buffer, size);
    if (problem == NULL && NOISE_REFUSAL[stepper] != NULL) {
        snprintf(buffer, size, "parameter %s", NOISE_REFUSAL[stepper]);
        problem = buffer;
    }
    return problem;
}

/* ------------------------------------------------------------------ outputs */

static double reaction_now(Instance* c)
{
    Element* e = &c->el;
    double xv[2], out[3], erow[6];
    Load l;
    if (!HAS_FRICTION)
        return e->out[2];
    l = load_of(c->F, c->scene_load, NULL, NULL); /* the reaction under the F set now: a stuck mass is held against
                                                     it (F(t) alone: loads.force_at) */
    xv[0] = e->x;
    xv[1] = e->v;
    KERNEL(e, record)(BRANCHES(e), xv, e->account, out, erow, l.kind, l.lk, (double*)l.t, (double*)l.f, l.n,
                      element_time(e));
    return out[2];
}

static double energy(const Element* e, int which)
{
    const double* r = e->erow;
    if (which < 6)
        return r[which];
    return r[2] - r[3] - r[4] - r[5] - (r[0] + r[1] - e->initial_energy);
}

static double real_value(Instance* c, const Var* var)
{
    Element* e = &c->el;
    double xv[2] = {e->x, e->v};
    switch (var->what) {
    case W_F: return c->F;
    case W_X: return e->x;
    case W_V: return e->v;
    case W_REACTION: return reaction_now(c);
    case W_STIFFNESS:
        return KERNEL(e, stiffness)(BRANCHES(e), xv);
    case W_ENERGY: return energy(e, var->index);
    case W_PARAM: return c->par[var->index];
    case W_CBRANCH: return c->cbranch[var->index < 0 ? 0 : var->index];
    case W_MEMORY: return c->mpar[var->index];
    case W_STEP: return c->step;
    case W_NOISE_INTENSITY: return c->noise_set.sigma;
    case W_NOISE_UNIT: return c->noise_set.unit;
    }
    return NAN;
}

/* an Integer: n (the scene's), or noise_seed */
static int32_t integer_value(Instance* c, const Var* var)
{
    return var->what == W_NOISE_SEED ? (int32_t)c->noise_set.seed : (int32_t)N_VALUE;
}

static void defaults(Instance* c)
{
    memcpy(c->par, P_SCENE, sizeof c->par);
    memcpy(c->cbranch, CS_SCENE, sizeof c->cbranch);
    snprintf(c->stepper, sizeof c->stepper, "%s", DEFAULT_STEPPER);
    c->stepper_valid = 1;
    c->step = DEFAULT_STEP;
    c->F = 0.0;
    c->scene_load = SCENE_LOAD_START; /* true when the scene names a load: a fresh FMU runs the scene */
    c->start_time = 0.0;
    c->initialized = 0;
    c->handed = 0;
    c->phase = INSTANTIATED;
    c->last_step_failed = 0;
    c->noise_set = SCENE_NOISE;
    memset(c->noise_cache, 0, sizeof c->noise_cache); /* a new cache (noise.new_cache) */
    memcpy(c->mpar, MEM_SCENE, sizeof c->mpar);
    {
        double* mem = c->el.mem; /* the memory's arrays are kept (size_memory resizes them) */
        int64_t length = c->el.mem_len;
        memset(&c->el, 0, sizeof c->el);
        c->el.mem = mem;
        c->el.mem_len = length;
    }
    hand_over(c);
    prandtl_kernel_failed = 0;
    {
        char buffer[256];
        const char* problem = size_memory(c, buffer, sizeof buffer);
        c->memory_failed = problem != NULL;
        if (problem != NULL) {
            say(c, ST_ERROR, "instantiation refused: %s", problem);
            return;
        }
    }
    reset(&c->el, 0.0);
}

/* ------------------------------------------------------------------ FMU state: a checked blob */

/* the checksum of a state: its fixed part up to the checksum, then its memory's state (element.mem_len values,
 * which the caller knows the blob holds) */
static uint64_t state_checksum(const State* s)
{
    uint64_t hash = fnv1a((const unsigned char*)s, offsetof(State, checksum));
    const unsigned char* tail = (const unsigned char*)(s + 1);
    size_t i, n = (size_t)s->element.mem_len * sizeof(double);
    for (i = 0; i < n; i++) {
        hash ^= tail[i];
        hash *= 1099511628211ULL;
    }
    return hash;
}

/* why the memory's state of a state blob (its parameters in use, its values after the fixed part) cannot be
 * restored, or NULL: memory.check_memory_state's rules (the buffer's size for its tau, its grid index, the Dahl
 * force within F_c) and numbers only */
static const char* memory_state_problem(const State* s, char* buffer, size_t size)
{
    const Element* e = &s->element;
    const char* problem;
    if (!HAS_MEMORY)
        return memory_values_problem(e->mp, NULL, e->nd, e->mem_len, element_time(e), buffer, size);
    problem = memory_problem(e->mp, buffer, size);
    if (problem != NULL)
        return problem;
    if (s->initialized && memcmp(s->mpar, e->mp, sizeof e->mp) != 0) /* fixed: set before initialization */
        return "its memory's parameters in use are not those set";
    return memory_values_problem(e->mp, (const double*)(s + 1), e->nd, e->mem_len, element_time(e), buffer, size);
}

static void capture(const Instance* c, State* s)
{
    memset(s, 0, sizeof *s);
    FILL_HEAD(s);
    s->element = c->el;
    s->F = c->F;
    s->step = c->step;
    s->start_time = c->start_time;
    memcpy(s->par, c->par, sizeof s->par);
    memcpy(s->cbranch, c->cbranch, sizeof s->cbranch);
    s->scene_load = c->scene_load;
    s->stepper_valid = c->stepper_valid;
    s->initialized = c->initialized;
    memcpy(s->stepper, c->stepper, sizeof s->stepper);
    s->noise_set = c->noise_set;
    memcpy(s->mpar, c->mpar, sizeof s->mpar);
    s->element.mem = NULL;
    if (c->el.mem_len > 0)
        memcpy((double*)(s + 1), c->el.mem, (size_t)c->el.mem_len * sizeof(double));
    s->checksum = state_checksum(s);
}

/* why a state cannot be restored here, or NULL: every field checked as strictly as the setters check the master's
 * values (a checksum detects accidents, not edits: a blob with a recomputed one is checked field by field) */
static const char* state_problem(const State* s, char* buffer, size_t size)
{
    const Element* e = &s->element;
    const char* problem;
    int i;
    const char* head = head_problem(s->header, s->version, s->size, sizeof *s, s->digest, s->checksum,
                                    state_checksum(s));
    if (head != NULL)
        return head;
    if (!(e->stepper >= 0 && e->stepper < N_STEPPERS && isfinite(e->h) && e->h > 0 && isfinite(e->x) &&
          isfinite(e->v) && isfinite(e->force) && isfinite(s->F) && isfinite(s->start_time) &&
          (e->play == 0 || (FOLDS && e->play == 1)) && (e->scene_load == 0 || e->scene_load == 1) &&
          (s->scene_load == 0 || s->scene_load == 1) && (s->stepper_valid == 0 || s->stepper_valid == 1) &&
          (s->initialized == 0 || s->initialized == 1) && memchr(s->stepper, 0, sizeof s->stepper) != NULL))
        return "it holds a non-finite or out-of-range value";
    /* the clock: time = origin + steps * grid, grid 0 before the first advance */
    if (!(isfinite(e->origin) && isfinite(e->grid) && e->grid >= 0 && e->steps >= 0 &&
          (double)e->steps <= MAX_STEPS && (e->grid > 0 || e->steps == 0) && isfinite(element_time(e))))
        return "its clock is not a finite time (origin, steps and grid)";
    problem = parameter_problem(e->p, e->cs, buffer, size); /* the coefficients in use, as the setters' */
    if (problem == NULL) /* the noise's settings (NoiseParameters._check_noise_state) */
        problem = noise_problem(&s->noise_set, buffer, size);
    if (problem != NULL)
        return problem;
    if (!HAS_STRIBECK && e->p[P_ALPHA_KINETIC] != e->p[P_ALPHA])
        return "it holds a non-finite or out-of-range value";
    problem = memory_state_problem(s, buffer, size); /* the memory's parameters in use and its state */
    if (problem != NULL)
        return problem;
    for (i = 0; i < 4; i++) /* numbers only, as the library's saved state */
        if (!(isfinite(e->account[i]) && isfinite(e->erow[2 + i])))
            return "its energy account is not finite";
    if (!(isfinite(e->out[0]) && isfinite(e->out[1]) && isfinite(e->out[2]) && isfinite(e->erow[0]) &&
          isfinite(e->erow[1]) && isfinite(e->initial_energy)))
        return "its outputs are not finite";
    if (FOLDS && !e->play && !TAKES_STACK[e->stepper])
        return "its stepper runs on the branches' elongations, which it does not hold";
    for (i = 0; i < (STACK && !e->play ? 0 : NB); i++) { /* n elongations: |u_i| <= eta_i */
        double u = e->play ? e->up[i] : e->u[i], eta = e->play ? ETA_PLAY[i] : ETA[i];
        if (!(fabs(u) <= eta)) {
            snprintf(buffer, size, "branch %d has elongation %.17g beyond its range %.17g", i + 1, u, eta);
            return buffer;
        }
    }
    if (FOLDS) { /* the stack's parameters: only the rows of the elongations folded last may differ from K */
        static const int fixed[] = {0, 1, 3, 4, 6, 7}; /* k, eta, their prefix sums, the order, sum k eta^2 */
        for (i = 0; i < 6; i++)
            if (memcmp(e->kst + fixed[i] * (NB + 1), K + fixed[i] * (NB + 1), (NB + 1) * sizeof(double)) != 0)
                return "its memory-stack parameters are not this scene's";
    }
    if (STACK && !e->play) { /* the memory stack: stack.restore's rules, compiled (state_check) */
        double* scratch = (double*)malloc(STATE_SCRATCH * sizeof(double));
        int64_t code;
        if (scratch == NULL)
            return "out of memory";
        prandtl_kernel_failed = 0;
        code = state_check(FOLDS ? (double*)e->kst : (double*)K, (double*)e->u, scratch);
        free(scratch);
        if (prandtl_kernel_failed)
            return "its memory stack could not be checked";
        if (code != 0)
            return STATE_CHECK_REASONS[code - 1];
    }
    return NULL;
}

static int restore(Instance* c, const State* s)
{
    char buffer[256];
    Instance* trial; /* the settings of the state, checked as the master's are (on the heap: an instance is large) */
    const char* problem = state_problem(s, buffer, sizeof buffer);
    if (problem == NULL && (trial = (Instance*)malloc(sizeof *trial)) == NULL)
        problem = "out of memory";
    else if (problem == NULL) {
        memcpy((void*)trial, c, sizeof *trial);
        memcpy(trial->par, s->par, sizeof trial->par);
        memcpy(trial->cbranch, s->cbranch, sizeof trial->cbranch);
        trial->stepper_valid = s->stepper_valid;
        memcpy(trial->stepper, s->stepper, sizeof trial->stepper);
        trial->stepper[sizeof trial->stepper - 1] = 0;
        trial->step = s->step;
        memcpy(trial->mpar, s->mpar, sizeof trial->mpar);
        problem = settings_problem(trial, buffer, sizeof buffer);
        free(trial);
    }
    if (problem == NULL && HAS_MEMORY) /* the memory's arrays sized for the state's */
        problem = allocate_memory(c, s->element.mem_len, buffer, sizeof buffer);
    if (problem != NULL) {
        say(c, ST_ERROR, "FMU state refused (%s); the instance is unchanged", problem);
        return ST_ERROR;
    }
    {
        double* mem = c->el.mem; /* the instance's arrays, with the state's values */
        c->el = s->element;
        c->el.mem = mem;
        if (HAS_MEMORY) { /* memory.restore_memory: the cached values are recomputed, never taken from a state */
            memcpy(mem, (const double*)(s + 1), (size_t)s->element.mem_len * sizeof(double));
            forget_memory_cache(mem);
        }
    }
    memcpy(c->mpar, s->mpar, sizeof c->mpar);
    c->F = s->F;
    c->step = s->step;
    c->start_time = s->start_time;
    memcpy(c->par, s->par, sizeof c->par);
    memcpy(c->cbranch, s->cbranch, sizeof c->cbranch);
    c->scene_load = s->scene_load;
    c->stepper_valid = s->stepper_valid;
    memcpy(c->stepper, s->stepper, sizeof c->stepper);
    c->stepper[sizeof c->stepper - 1] = 0;
    c->noise_set = s->noise_set; /* handed over at the next step, which redraws the same path */
    c->handed = 0;
    return ST_OK;
}


/* ------------------------------------------------------------------ stability warnings (stability.py) */

/* stability.stability_problem for the element's stepper and step at its state: what the library's check (the kernel
 * stability_check, stability.check) finds, in stability.explain's words: the message, or NULL */
static const char* stability_problem(const Element* e, char* buffer, size_t size)
{
    const char* stepper = STEPPER_NAMES[e->stepper];
    double out[4] = {0.0, 0.0, 0.0, 0.0};
    char advice[128], growth[64];
    int64_t found = stability_check((double*)e->p, (double*)e->cs, e->x, e->h, STEPPER_STABILITY[e->stepper], out);
    switch (found) {
    case LEAPFROG_UNSTABLE:
        snprintf(buffer, size, "stepper '%s' is beyond its stability limit: omega h = %.3g >= 2 (omega = sqrt(K/m) = "
                 "%.6g rad/s with every branch sticking); use 'implicit' or h < %.3g s", stepper, out[0], out[1],
                 out[2]);
        return buffer;
    case RELAXATION_UNSTABLE:
    case GROWTH_UNSTABLE: {
        int relaxation = found == RELAXATION_UNSTABLE;
        double limit = relaxation ? out[2] : out[3];
        if (limit > 0)
            snprintf(advice, sizeof advice, "use 'implicit' or h <= %.3g s", limit);
        else
            snprintf(advice, sizeof advice, "use 'implicit' (no step is small enough)");
        if (relaxation) {
            snprintf(buffer, size, "stepper 'projected' is unstable here: h K / c = %.3g > 2 (K = %.6g N/m with "
                     "every branch sticking); %s", out[0], out[1], advice);
            return buffer;
        }
        if (isfinite(out[2]))
            snprintf(growth, sizeof growth, "x%.3g", out[2]);
        else
            snprintf(growth, sizeof growth, "beyond any float");
        snprintf(buffer, size, "stepper 'projected' is beyond its stability limit: omega h = %.3g (omega = sqrt(K/m) "
                 "= %.6g rad/s with every branch sticking) makes the amplitude grow %s per period; %s", out[0], out[1],
                 growth, advice);
        return buffer;
    }
    case STRIBECK_UNRESOLVED:
        snprintf(buffer, size, "[friction]: the Stribeck drop (alpha - alpha_kinetic) / stribeck_velocity = %.6g N.s/m "
                 "exceeds m/h + c = %.6g N.s/m: the step cannot resolve it (the implicit step may have several roots; "
                 "'implicit' takes the least slip); use h < %.3g s", out[0], out[1], out[2]);
        return buffer;
    case SERIES_UNSTABLE:
        snprintf(buffer, size, "stepper 'projected' relaxes the series dashpots explicitly and is unstable here: "
                 "h k_i / c_i = %.3g > 2 (branch %.0f); use 'implicit', 'verlet' or h <= %.3g s", out[0], out[1],
                 out[2]);
        return buffer;
    default:
        return NULL;
    }
}

static void warn_if_unstable(Instance* c)
{
    char buffer[512];
    const char* problem = stability_problem(&c->el, buffer, sizeof buffer);
    if (problem != NULL)
        say(c, ST_WARNING, "%s", problem);
}

/* fmi2/3ExitInitializationMode: the settings checked and handed over, the element reset */
static int core_exit_initialization(Instance* c)
{
    char buffer[512];
    const char* problem;
    double force;
    if (c->phase != INITIALIZING) {
        say(c, ST_ERROR, FMI "ExitInitializationMode refused: not in initialization mode");
        return ST_ERROR;
    }
    problem = hand_over_problem(c, buffer, sizeof buffer);
    if (problem == NULL && !isfinite(c->F)) {
        snprintf(buffer, sizeof buffer, "F = %.17g refused: the force must be finite", c->F);
        problem = buffer;
    }
    if (problem == NULL) {
        hand_over(c);
        problem = size_memory(c, buffer, sizeof buffer); /* the delay's buffer for the tau set */
    }
    if (problem == NULL) {
        Load l = load_of(0.0, 1, NULL, NULL);
        force = c->F;
        if (c->scene_load) { /* F plus the scene's load at the start time */
            double xv[2] = {0.0, 0.0};
            force = c->F + scene_force_at(l.kind, l.lk, (double*)l.t, (double*)l.f, l.n, c->start_time, xv);
        }
        prandtl_kernel_failed = 0;
        if (!reset(&c->el, force)) {
            snprintf(buffer, sizeof buffer, "no equilibrium exists at t = 0 under F = %.17g N (a massless element "
                     "with no hardening spring beyond its strength)", force);
            problem = buffer;
        }
    }
    if (problem != NULL) {
        say(c, ST_ERROR, "initialization refused: %s", problem);
        return ST_ERROR;
    }
    set_time(&c->el, c->start_time);
    c->handed = 0;
    c->initialized = 1;
    c->phase = STEPPING;
    if (c->scene_load) /* a master that connects F is told the scene's load is added, logging on or off */
        say(c, ST_WARNING, "%s", SCENE_LOAD_NOTICE);
    warn_if_unstable(c);
    return ST_OK;
}

static void checkpoint(Instance* c)
{
    const Element* e = &c->el;
    Checkpoint* k = &c->saved;
    k->x = e->x;
    k->v = e->v;
    memcpy(k->account, e->account, sizeof k->account);
    memcpy(k->out, e->out, sizeof k->out);
    memcpy(k->erow, e->erow, sizeof k->erow);
    k->origin = e->origin;
    k->grid = e->grid;
    k->force = e->force;
    k->steps = e->steps;
    k->scene_load = e->scene_load;
    k->used = e->play ? NB : branch_state_used(e->u);
    memcpy(c->saved_u, e->play ? e->up : e->u, k->used * sizeof(double));
    if (HAS_MEMORY) /* the memory's state (memory.copy_memory) */
        memcpy(c->saved_mem, e->mem, (size_t)e->mem_len * sizeof(double));
}

static void rollback(Instance* c)
{
    Element* e = &c->el;
    const Checkpoint* k = &c->saved;
    e->x = k->x;
    e->v = k->v;
    memcpy(e->account, k->account, sizeof k->account);
    memcpy(e->out, k->out, sizeof k->out);
    memcpy(e->erow, k->erow, sizeof k->erow);
    e->origin = k->origin;
    e->grid = k->grid;
    e->force = k->force;
    e->steps = k->steps;
    e->scene_load = k->scene_load;
    memcpy(e->play ? e->up : e->u, c->saved_u, k->used * sizeof(double));
    if (HAS_MEMORY) /* memory.put_back */
        memcpy(e->mem, c->saved_mem, (size_t)e->mem_len * sizeof(double));
}

/* the first output (x, v, reaction, stiffness, an energy) that is not a number to show after a step, or NULL */
static const Var* unshowable_output(Instance* c, double* value)
{
    int i;
    for (i = 0; i < N_VARS; i++) {
        const Var* var = &VARS[i];
        if (var->what != W_X && var->what != W_V && var->what != W_REACTION && var->what != W_STIFFNESS &&
            var->what != W_ENERGY)
            continue;
        *value = real_value(c, var);
        if (!showable(var, *value))
            return var;
    }
    return NULL;
}

/* fmi2/3DoStep: one communication step (slave.do_step); the FMI layer checked the call sequence */
static int core_do_step(Instance* c, double t, double H)
{
    char buffer[512];
    const char* problem;
    const Var* overflowed;
    double failed_at, value;
    if (c->phase != STEPPING) {
        say(c, ST_ERROR, FMI "DoStep refused: not allowed before " FMI "ExitInitializationMode nor after " FMI
            "Terminate");
        return ST_ERROR;
    }
    if (!(isfinite(t) && isfinite(H) && H >= 0 && isfinite(t + H))) {
        say(c, ST_ERROR, FMI "DoStep refused: the communication point %.17g and step %.17g must be finite, the step "
            ">= 0 (and their sum finite)", t, H);
        return ST_ERROR;
    }
    c->last_step_failed = 1;
    if (!c->handed) {
        problem = hand_over_problem(c, buffer, sizeof buffer);
        if (problem != NULL) {
            say(c, ST_DISCARD, "%s; steps are refused until it is set right", problem);
            return ST_DISCARD;
        }
        {
            double p[N_PARAMS], cs[NB_CS], h = c->el.h;
            int stepper = c->el.stepper;
            memcpy(p, c->el.p, sizeof p);
            memcpy(cs, c->el.cs, sizeof cs);
            hand_over(c);
            if (memcmp(p, c->el.p, sizeof p) != 0 || memcmp(cs, c->el.cs, sizeof cs) != 0 ||
                stepper != c->el.stepper || h != c->el.h)
                warn_if_unstable(c); /* slave._apply_settings: on a change only */
        }
    }
    if (!isfinite(c->F)) {
        say(c, ST_DISCARD, "F = %.17g refused: the force must be finite; step not taken", c->F);
        return ST_DISCARD;
    }
    checkpoint(c); /* slave.do_step: element.checkpoint(), then the time */
    set_time(&c->el, t);
    prandtl_kernel_failed = 0;
    problem = advance(&c->el, H, c->F, c->scene_load, &c->noise, c->noise_cache, &failed_at, buffer, sizeof buffer);
    if (problem != NULL && isnan(failed_at)) { /* refused before any step */
        rollback(c);
        say(c, ST_DISCARD, "step from t = %.17g refused: %s; the state is unchanged", t, problem);
        return ST_DISCARD;
    }
    if (problem == NULL && !(isfinite(c->el.x) && isfinite(c->el.v) && isfinite(c->el.out[2])))
        problem = "it would leave a non-finite state";
    if (problem != NULL) {
        rollback(c);
        int implicit = strcmp(STEPPER_NAMES[c->el.stepper], "implicit") == 0; /* advise nothing already done */
        say(c, ST_DISCARD, "step from t = %.17g with F = %.17g refused: %s (stepper '%s' with step = %.17g%s)", t,
            c->F, problem, STEPPER_NAMES[c->el.stepper], c->el.h, implicit ? "" : "; try 'implicit'");
        return ST_DISCARD;
    }
    overflowed = unshowable_output(c, &value); /* no output is ever shown NaN or inf after an OK step */
    if (overflowed != NULL) {
        double time = element_time(&c->el);
        rollback(c);
        say(c, ST_DISCARD, "the step to t = %.17g with F = %.17g refused: %s would be %.17g, not finite (an "
            "overflow); the state is unchanged", time, c->F, overflowed->name, value);
        return ST_DISCARD;
    }
    c->last_step_failed = 0;
    return ST_OK;
}

/* a Float64/Real the master sets: which variables take one, and the rule of the fixed parameters */
static int core_check_float(Instance* c, const Var* var, unsigned vr, double value)
{
    if (var == NULL || !(var->what == W_F || var->what == W_PARAM || var->what == W_CBRANCH || var->what == W_STEP ||
                         var->what == W_NOISE_INTENSITY || var->what == W_NOISE_UNIT || var->what == W_MEMORY)) {
        say(c, ST_ERROR, FLOAT_SETTER " refused: value reference %u is not a Real input or parameter", vr);
        return ST_ERROR;
    }
    if (var->what == W_PARAM && c->initialized && (var->index == P_X0 || var->index == P_V0) &&
        value != c->par[var->index]) {
        say(c, ST_ERROR, "parameter %s = %.17g refused: %s is fixed (the initial state) and cannot change after "
            "initialization; the element is unchanged", PARAM_NAMES[var->index], value, PARAM_NAMES[var->index]);
        return ST_ERROR;
    }
    if (var->what == W_MEMORY && c->initialized && value != c->mpar[var->index]) { /* slave._set_parameter */
        char shown[40];
        say(c, ST_ERROR, "parameter %s = %s refused: %s is fixed (the initial state, or an effect with memory) and "
            "cannot change after initialization; the element is unchanged", MEM_NAMES[var->index],
            python_repr(value, shown, sizeof shown), MEM_NAMES[var->index]);
        return ST_ERROR;
    }
    return ST_OK;
}

static void core_set_float(Instance* c, const Var* var, double value)
{
    if (var->what == W_F)
        c->F = value;
    else if (var->what == W_PARAM) {
        c->par[var->index] = value;
        c->handed = 0;
    } else if (var->what == W_MEMORY) {
        c->mpar[var->index] = value; /* checked when handed over (the next exit of initialization mode) */
        c->handed = 0;
    } else if (var->what == W_CBRANCH) {
        int j;
        for (j = 0; j < NB; j++)
            if (var->index < 0 || var->index == j)
                c->cbranch[j] = value;
        c->handed = 0;
    } else if (var->what == W_NOISE_INTENSITY || var->what == W_NOISE_UNIT) {
        *(var->what == W_NOISE_INTENSITY ? &c->noise_set.sigma : &c->noise_set.unit) = value;
        c->handed = 0; /* checked when handed over (a bad value: a Discard at the next step) */
    } else {
        c->step = value;
        c->handed = 0;
    }
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

static void core_set_stepper(Instance* c, const char* value)
{
    c->stepper_valid = strlen(value) < sizeof c->stepper;
    snprintf(c->stepper, sizeof c->stepper, "%s", c->stepper_valid ? value : "");
    c->handed = 0;
}

#endif
