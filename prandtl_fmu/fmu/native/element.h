/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
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
#include "element_types.h"
#include "core.h"
#include "calls.h"
#include "state.h"

/* what an advance changes (driver.Element.checkpoint): a step that fails is rolled back from it; the branches'
 * state is copied in its part in use only (the memory stack's pieces), into the instance's buffer */
#define CHECKPOINTED(to, from)                                                                                 \
    COPY_FIELD(to, from, x), COPY_FIELD(to, from, v), COPY_FIELD(to, from, account), COPY_FIELD(to, from, out), \
        COPY_FIELD(to, from, erow), COPY_FIELD(to, from, clock), COPY_FIELD(to, from, force),                  \
        COPY_FIELD(to, from, scene_load), COPY_FIELD(to, from, row_stale)

/* ------------------------------------------------------------------ the element */

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
    e->row_stale = 0;
}

/* the energy row of the state, computed when an output reads it (an advance leaves it stale: the library's
 * Element.advance records it, the FMU only when asked) */
static void fresh_row(Element* e)
{
    double xv[2] = {e->x, e->v};
    if (!e->row_stale)
        return;
    KERNEL(e, row)(BRANCHES(e), xv, e->account, e->erow);
    e->row_stale = 0;
}

/* the magnitudes of x, v and the account's entries below which every output is surely a number, for the
 * coefficients handed over and the branches' kernel in use (showable.limits); 0 (every output is then computed
 * after every step) if the kernel fails. After every hand-over: surely_showable reads them. */
static void note_limits(Instance* c)
{
    int failed = prandtl_kernel_failed;
    prandtl_kernel_failed = 0;
    KERNEL(&c->el, limits)(BRANCHES(&c->el), c->limits);
    if (prandtl_kernel_failed)
        memset(c->limits, 0, sizeof c->limits);
    c->limit_play = c->el.play;
    prandtl_kernel_failed = failed;
}

/* ------------------------------------------------------------------ the effects with memory */

/* Element.set_step's rule with memory: a negative delay gain with tau below the step in use, or NULL */
static const char* memory_step_problem(const double* mp, double step, char* buffer, size_t size)
{
    char a[40], b[40], c[40];
    if (!(HAS_DELAY && !QUASI_STATIC && mp[0] < 0 && mp[1] < step))
        return NULL;
    snprintf(buffer, size, "parameter step = %s: a negative gain with tau = %s s below the step %s s makes the implicit "
             "equation of a step non-monotone (no unique solution): a [solver] step no longer than tau, "
             "or a longer tau",
             python_repr(step, a, sizeof a), python_repr(mp[1], b, sizeof b), python_repr(step, c, sizeof c));
    return buffer;
}

/* Element.reset(force): the initial state under the force held; 0 when a massless element has no equilibrium */
static int reset(Element* e, double force)
{
    Load l = load_of(force, 0, NULL, NULL);
    double xv[2];
    int ok;
    memset(&e->clock, 0, sizeof e->clock);
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

static int64_t integrate(Element* e, const Load* l, double t_base, int64_t first, double h, int64_t steps)
{
    double xv[2] = {e->x, e->v};
    int64_t taken;
    if (l->noise.sigma != 0.0) { /* the load tuple with its noise (loads.with_white_noise): the noisy kernel */
        noisy_fn noisy = (e->play ? (damped(e) ? NOISY_CP : NOISY_NP) : (damped(e) ? NOISY_C : NOISY_N))[e->stepper];
        if (noisy == NULL) /* a stepper that takes no noise: refused when the settings are handed over */
            return -1;
        taken = noisy(BRANCHES(e), xv, e->account, e->out, l->kind, (double*)l->lk, (double*)l->t,
                      (double*)l->f, l->n, t_base, first, h, steps, l->noise.sigma, l->noise.seed, l->noise.unit,
                      l->cache);
    } else {
        taken = (e->play ? (damped(e) ? ADVANCE_CP : ADVANCE_NP) : (damped(e) ? ADVANCE_C : ADVANCE_N))[e->stepper](
            BRANCHES(e), xv, e->account, e->out, l->kind, (double*)l->lk, (double*)l->t, (double*)l->f,
            l->n, t_base, first, h, steps);
    }
    e->row_stale = 1; /* the branches and the account moved (a failed advance is rolled back whole) */
    if (prandtl_kernel_failed)
        return -1;
    e->x = xv[0];
    e->v = xv[1];
    return taken;
}

/* Element.advance under ``force`` (plus the scene's [load] with ``scene_load``) and the white ``noise`` (its
 * Brownian tree's ``cache``): NULL, or why the step was not taken (the element then is as it was: the caller rolls
 * back); ``failed_at`` NaN: refused before any step (a duration of too many steps) */
static const char* advance(Element* e, double duration, double force, const double* derivatives, int scene_load,
                           const Noise* noise, int64_t* cache, double* failed_at, char* buffer, size_t size)
{
    double h = e->h, whole, rest, t_base;
    int64_t first, taken;
    const char* problem;
    Load l;
    *failed_at = NAN;
    if (duration == 0.0)
        return NULL;
    if (STEP_IS_OUTPUT[e->stepper]) { /* one step per advance (exact) ... */
        h = duration;
        if (e->clock.grid != 0.0 && fabs(duration - e->clock.grid) <= 1e-9 * e->clock.grid)
            h = e->clock.grid; /* ... of the grid's step when it is that to rounding */
    }
    problem = plan_advance(duration, h, element_time(e) + duration, &whole, &rest, buffer, size);
    if (problem != NULL || (whole == 0 && rest == 0)) /* (0, 0): below rounding of h, no step, the clock stays */
        return problem;
    problem = delay_time_problem(e->mem, element_time(e), element_time(e) + duration, buffer, size);
    if (problem != NULL)
        return problem;
    l = load_of(force, scene_load, noise, cache);
    if (derivatives[0] != 0.0 || derivatives[1] != 0.0) { /* Element._load_of: the polynomial from the time now */
        l.kind = LOAD_POLYNOMIAL;
        l.lk[1] = derivatives[0];
        l.lk[2] = derivatives[1];
        l.origin[0] = element_time(e);
        l.t = l.origin;
    }
    e->force = force;
    e->scene_load = scene_load;
    clock_regrid(&e->clock, h);
    t_base = e->clock.origin;
    first = e->clock.steps;
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
    }
    clock_advanced(&e->clock, whole, rest, h);
    return NULL;
}

/* ------------------------------------------------------------------ parameters */

static const char* stepper_problem(const Instance* c, char* buffer, size_t size)
{
    if (!c->stepper_valid || stepper_index(c->stepper) < 0) {
        snprintf(buffer, size, "parameter stepper = '%s': must be one of %s (the steppers this FMU "
                 "holds)", c->stepper_valid ? c->stepper : "?", STEPPER_LIST);
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
    note_limits(c);
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

static double energy(Element* e, int which)
{
    const double* r = e->erow;
    fresh_row(e);
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

/* 1 when every output a step must leave a number (STEP_OUTPUT) surely is one, computing none but the reaction
 * (O(1)): x, v, the account's entries and the initial energy within the magnitudes of showable.limits (note_limits),
 * below which the stiffness and the energies are numbers. 0: unshowable_output must compute them all (it then names
 * the culprit, or finds none). Never 1 where unshowable_output would name one
 * (tests/fmu/native/test_showable_bounds.py), in a fraction of its time (benchmarks/dostep_cost.py). */
static int surely_showable(Instance* c)
{
    const Element* e = &c->el;
    const double* limit = c->limits;
    int i;
    if (!(c->limit_play == e->play && isfinite(e->x) && fabs(e->x) <= limit[0] && isfinite(e->v) &&
          fabs(e->v) <= limit[1] && fabs(e->initial_energy) <= limit[2]))
        return 0;
    for (i = 0; i < 4; i++) /* the account's entries, whichever are outputs */
        if (!(fabs(e->account[i]) <= limit[2]))
            return 0;
    return isfinite(reaction_now(c));
}

/* fmi2GetRealOutputDerivatives, fmi3GetOutputDerivatives: the ``order``-th time derivative of the output ``var`` at
 * the state under the F set now, held (Element.output_derivatives: the kernel rates, kernels/rates.py), into
 * ``value``; NULL, or why it is not given (in ``buffer``) */
static const char* output_derivative(Instance* c, const Var* var, int order, double* value, char* buffer, size_t size)
{
    Element* e = &c->el;
    double xv[2] = {e->x, e->v}, out[3] = {0.0, 0.0, 0.0};
    Load l;
    int which; /* 0: a, 1: a', 2: R', -1: v */
    if (var == NULL || !(var->what == W_X || var->what == W_V || var->what == W_REACTION))
        return "not an output whose derivatives this FMU gives (x, v, reaction)";
    if (order < 1 || order > 2) {
        snprintf(buffer, size, "order %d: this FMU gives orders 1 and 2 (maxOutputDerivativeOrder)", order);
        return buffer;
    }
    which = var->what == W_X ? order - 2 : var->what == W_V ? order - 1 : 2 + (order - 1) * 8;
    if (which > 2)
        return "the reaction's derivative of order 2 is not given (its tangent's rate is not an output of the model)";
    if (which >= 0 && !HAS_MASS)
        return "a massless element's v follows F: only x's derivative of order 1 (v) is given";
    if (which >= 1 && !EXACT_RATES)
        return "not exact for this scene (a friction on the mass, series dashpots or an effect with memory): only x's "
               "derivatives and v's of order 1 are given";
    if (which == 1 && c->scene_load)
        return "v's derivative of order 2 is not given with scene_load (it would need the scene's load's rate)";
    if (which < 0) {
        *value = e->v;
        return NULL;
    }
    l = load_of(c->F, c->scene_load, NULL, NULL);
    prandtl_kernel_failed = 0;
    KERNEL(e, rates)(BRANCHES(e), xv, l.kind, l.lk, (double*)l.t, (double*)l.f, l.n, element_time(e), out);
    *value = out[which];
    if (prandtl_kernel_failed || !isfinite(*value))
        return "it is not a finite number here";
    return NULL;
}

#define HAS_OUTPUT_DERIVATIVES 1 /* output_derivative: front.h's core_get_output_derivatives */

/* an Integer: n (the scene's), or noise_seed */
static int32_t integer_value(Instance* c, const Var* var)
{
    return var->what == W_NOISE_SEED ? (int32_t)c->noise_set.seed : (int32_t)N_VALUE;
}

static void defaults(Instance* c)
{
    memcpy(c->par, P_SCENE, sizeof c->par);
    memcpy(c->cbranch, CS_SCENE, sizeof c->cbranch);
    instantiated(c);
    memcpy(c->mpar, MEM_SCENE, sizeof c->mpar);
    c->dF[0] = c->dF[1] = 0.0; /* (ask_inputs is the instantiation's: a reset keeps it) */
    clear_element(&c->el);
    hand_over(c);
    prandtl_kernel_failed = 0;
    if (memory_at_instantiation(c))
        reset(&c->el, 0.0);
}

/* ------------------------------------------------------------------ FMU state: a checked blob */

/* why a state cannot be restored here, or NULL: every field checked as strictly as the setters check the master's
 * values (a checksum detects accidents, not edits: a blob with a recomputed one is checked field by field) */
static const char* state_problem(const State* s, char* buffer, size_t size)
{
    const Element* e = &s->element;
    const char* problem;
    int i;
    if (!(e->stepper >= 0 && e->stepper < N_STEPPERS && isfinite(e->h) && e->h > 0 && isfinite(e->x) &&
          isfinite(e->v) && isfinite(e->force) && isfinite(s->F) && isfinite(s->start_time) && isfinite(s->dF[0]) &&
          isfinite(s->dF[1]) &&
          (e->play == 0 || (FOLDS && e->play == 1)) && (e->scene_load == 0 || e->scene_load == 1) &&
          (e->row_stale == 0 || e->row_stale == 1) &&
          (s->scene_load == 0 || s->scene_load == 1) && (s->stepper_valid == 0 || s->stepper_valid == 1) &&
          (s->initialized == 0 || s->initialized == 1) && memchr(s->stepper, 0, sizeof s->stepper) != NULL))
        return "it holds a non-finite or out-of-range value";
    /* the clock: time = origin + steps * grid, grid 0 before the first advance */
    if (!clock_valid(&e->clock))
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
        if (!isfinite(e->account[i]) || (i > 0 && e->account[i] < 0)) /* (a dissipation never gives back) */
            return "its energy account is not finite (or a dissipation is negative)";
    if (!(isfinite(e->out[0]) && isfinite(e->out[1]) && isfinite(e->out[2]) && isfinite(e->initial_energy)))
        return "its outputs are not finite"; /* (its energy row is not read: computed again, FORGET_DERIVED) */
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
    return STACK && !e->play ? stack_problem(FOLDS ? e->kst : K, e->u) : NULL; /* the memory stack */
}

static int restore(Instance* c, const State* s)
{
    char buffer[256];
    Instance* trial; /* the settings of the state, checked as the master's are (on the heap: an instance is large) */
    const char* problem = state_refusal(s, state_problem, buffer, sizeof buffer);
    if (problem == NULL && (trial = (Instance*)malloc(sizeof *trial)) == NULL)
        problem = "out of memory";
    else if (problem == NULL) {
        memcpy((void*)trial, c, sizeof *trial);
        SETTINGS(trial, s);
        trial->stepper[sizeof trial->stepper - 1] = 0;
        problem = settings_problem(trial, buffer, sizeof buffer);
        free(trial);
    }
    if (problem == NULL && HAS_MEMORY) /* the memory's arrays sized for the state's */
        problem = allocate_memory(c, s->element.mem_len, buffer, sizeof buffer);
    if (problem != NULL) {
        say(c, ST_ERROR, "FMU state refused (%s); the instance is unchanged", problem);
        return ST_ERROR;
    }
    restore_checked(c, s);
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

/* the exit of initialization mode (machine.h): the settings checked and handed over, the element reset under F (plus
 * the scene's load at the start time with scene_load) and put at the start time */
static const char* initialize(Instance* c, char* buffer, size_t size)
{
    const char* problem = hand_over_problem(c, buffer, size);
    double force;
    if (problem == NULL && !isfinite(c->F)) {
        snprintf(buffer, size, "F = %.17g refused: the force must be finite", c->F);
        return buffer;
    }
    if (problem == NULL) {
        hand_over(c);
        problem = size_memory(c, buffer, size); /* the delay's buffer for the tau set */
    }
    if (problem != NULL)
        return problem;
    force = c->F;
    if (c->scene_load) { /* F plus the scene's load at the start time */
        Load l = load_of(0.0, 1, NULL, NULL);
        double xv[2] = {0.0, 0.0};
        force = c->F + scene_force_at(l.kind, l.lk, (double*)l.t, (double*)l.f, l.n, c->start_time, xv);
    }
    prandtl_kernel_failed = 0;
    if (!reset(&c->el, force)) {
        snprintf(buffer, size, "no equilibrium exists at t = 0 under F = %.17g N (a massless element with no hardening "
                 "spring beyond its strength)", force);
        return buffer;
    }
    clock_set(&c->el.clock, c->start_time);
    c->handed = 0;
    return NULL;
}

/* once started: a master that connects F is told the scene's load is added (logging on or off); the stepper's
 * stability */
static void started(Instance* c)
{
    if (c->scene_load)
        say(c, ST_WARNING, "%s", SCENE_LOAD_NOTICE);
    warn_if_unstable(c);
}

/* ``count`` doubles by the C library's memcpy, called: a compiler that inlines a memcpy of a run it cannot size
 * (tens of doubles, every doStep) may emit a rep movs that costs more than the copy (benchmarks/dostep_cost.py) */
static void* (*volatile const library_memcpy)(void*, const void*, size_t) = memcpy;
static void copy_doubles(double* to, const double* from, size_t count)
{
    library_memcpy(to, from, count * sizeof(double));
}

static void checkpoint(Instance* c)
{
    const Element* e = &c->el;
    Checkpoint* k = &c->saved;
    CHECKPOINTED(k, e);
    k->used = e->play ? NB : branch_state_used(e->u);
    copy_doubles(c->saved_u, e->play ? e->up : e->u, k->used);
    if (HAS_MEMORY) /* the memory's state (memory.copy_memory) */
        memcpy(c->saved_mem, e->mem, (size_t)e->mem_len * sizeof(double));
}

static void rollback(Instance* c)
{
    Element* e = &c->el;
    const Checkpoint* k = &c->saved;
    CHECKPOINTED(e, k);
    memcpy(e->play ? e->up : e->u, c->saved_u, k->used * sizeof(double));
    if (HAS_MEMORY) /* memory.put_back */
        memcpy(e->mem, c->saved_mem, (size_t)e->mem_len * sizeof(double));
}

/* hand_over after a change of the settings: the stability checked anew when the element's changed
 * (slave._apply_settings: on a change only) */
static void hand_over_settings(Instance* c)
{
    double p[N_PARAMS], cs[NB_CS], h = c->el.h;
    int stepper = c->el.stepper;
    memcpy(p, c->el.p, sizeof p);
    memcpy(cs, c->el.cs, sizeof cs);
    hand_over(c);
    if (memcmp(p, c->el.p, sizeof p) != 0 || memcmp(cs, c->el.cs, sizeof cs) != 0 || stepper != c->el.stepper ||
        h != c->el.h)
        warn_if_unstable(c);
}

/* ------------------------------------------------------------------ F's derivatives (FMI 2.0) */

#define HAS_INPUT_DERIVATIVES 1

/* why F's derivatives cannot drive the next step, or NULL: with scene_load (F plus the scene's [load], which F's
 * derivatives do not describe) or a stepper whose closed forms know the scene's load kinds only (Element's
 * _derivatives_of, its words) */
static const char* derivatives_problem(Instance* c, char* buffer, size_t size)
{
    int stepper = stepper_index(c->stepper);
    if (c->dF[0] == 0.0 && c->dF[1] == 0.0)
        return NULL;
    if (c->scene_load)
        return "force derivatives with scene_load: the force is F plus the scene's [load], which the derivatives of F "
               "alone do not describe";
    if (stepper >= 0 && !POLYNOMIAL_INPUT[stepper]) {
        snprintf(buffer, size, "force derivatives with stepper '%s': its closed forms take the scene's load kinds, not "
                 "a polynomial force; use another stepper or hold the force", STEPPER_NAMES[stepper]);
        return buffer;
    }
    return NULL;
}

/* fmi2SetRealInputDerivatives: F' (order 1) and F'' (order 2) of the input F at the next doStep's start; over that
 * step F(t) = F + F' (t - t0) + F'' (t - t0)^2 / 2 (loads.polynomial, evaluated by the kernels). Every entry checked
 * (a value reference of F, an order 1 or 2, a finite value), then all set; fmi2SetReal of F sets them to 0. */
static int core_set_input_derivatives(Instance* c, const unsigned vr[], size_t n, const int order[],
                                      const double value[], const char* function)
{
    size_t i;
    if (!arrays_given(c, n, vr, value, function) || !(n == 0 || given(c, order, function, "order")))
        return ST_ERROR;
    for (i = 0; i < n; i++) {
        const Var* var = find(vr[i], T_REAL);
        if (var == NULL || var->what != W_F) {
            say(c, ST_ERROR, "%s refused: value reference %u is not the continuous input F (the only input whose "
                "derivatives this FMU takes); nothing set", function, vr[i]);
            return ST_ERROR;
        }
        if (order[i] != 1 && order[i] != 2) {
            say(c, ST_ERROR, "%s refused: order %d of F: this FMU takes orders 1 and 2 (maxInputDerivativeOrder); "
                "nothing set", function, (int)order[i]);
            return ST_ERROR;
        }
        if (!isfinite(value[i])) {
            say(c, ST_ERROR, "%s refused: F's derivative of order %d = %.17g must be finite; nothing set", function,
                (int)order[i], value[i]);
            return ST_ERROR;
        }
    }
    for (i = 0; i < n; i++)
        c->dF[order[i] - 1] = value[i];
    return ST_OK;
}

/* FMI 3.0 intermediate update (c->ask_inputs): the doStep taken one internal step at a time, the master asked for F
 * at the start of each (it may set F there: intermediateUpdate="true"), each step the library's Element.advance(h,
 * F) of that F; a stepper that takes one step per doStep (exact) is asked once. The split into whole steps and a
 * shorter last one is the doStep's (plan_advance); NULL, or why a step was not taken (*failed_at as advance's). */
#define HAS_INTERMEDIATE_UPDATE 1
static const char* advance_with_updates(Instance* c, double H, double* failed_at, char* buffer, size_t size)
{
    Element* e = &c->el;
    double whole = 0.0, rest = 0.0;
    const char* problem = NULL;
    int64_t p, steps;
    *failed_at = NAN;
    if (!STEP_IS_OUTPUT[e->stepper]) {
        problem = plan_advance(H, e->h, element_time(e) + H, &whole, &rest, buffer, size);
        if (problem != NULL || (whole == 0 && rest == 0))
            return problem;
    }
    steps = STEP_IS_OUTPUT[e->stepper] ? 1 : (int64_t)whole + (rest > 0);
    for (p = 0; p < steps; p++) {
        double start = element_time(e);
        c->ask_inputs(c, start, p == 0);
        if (!isfinite(c->F)) {
            *failed_at = start;
            snprintf(buffer, size, "F = %.17g set at the intermediate update at t = %.17g is not finite", c->F, start);
            return buffer;
        }
        problem = advance(e, STEP_IS_OUTPUT[e->stepper] ? H : p < (int64_t)whole ? e->h : rest, c->F, c->dF,
                          c->scene_load, &c->noise, c->noise_cache, failed_at, buffer, size);
        if (problem != NULL) {
            if (isnan(*failed_at))
                *failed_at = start;
            return problem;
        }
    }
    return NULL;
}

#ifdef PRANDTL_BENCH_KERNEL_ONLY
/* benchmarks/dostep_cost.py only, never in a build of the package: a doStep that is the kernel's advance of one
 * step of H from t and nothing else (no check, no checkpoint, no clock), what the library's Element.advance pays
 * for its compiled part; the rest of a doStep's time is what this layer adds */
static int step(Instance* c, double t, double H)
{
    Load l = load_of(c->F, c->scene_load, &c->noise, c->noise_cache);
    return integrate(&c->el, &l, t, 0, H, 1) == 1 ? ST_OK : ST_DISCARD;
}
#else
/* a doStep (machine.h, the settings handed over; slave.do_step): the element checkpointed, put at t and advanced by
 * H under F; a step that fails or would show an output that is not a number is rolled back */
static int step(Instance* c, double t, double H)
{
    char buffer[512];
    const char* problem;
    const Var* overflowed;
    double failed_at, value;
    if (!isfinite(c->F)) {
        say(c, ST_DISCARD, "F = %.17g refused: the force must be finite; step not taken", c->F);
        return ST_DISCARD;
    }
    problem = derivatives_problem(c, buffer, sizeof buffer);
    if (problem != NULL) {
        say(c, ST_DISCARD, "step from t = %.17g refused: %s; the state is unchanged", t, problem);
        return ST_DISCARD;
    }
    checkpoint(c); /* slave.do_step: element.checkpoint(), then the time */
    clock_set(&c->el.clock, t);
    prandtl_kernel_failed = 0;
    problem = c->ask_inputs != NULL ? advance_with_updates(c, H, &failed_at, buffer, sizeof buffer)
              : advance(&c->el, H, c->F, c->dF, c->scene_load, &c->noise, c->noise_cache, &failed_at, buffer,
                        sizeof buffer);
    if (problem != NULL && isnan(failed_at)) { /* refused before any step */
        rollback(c);
        say(c, ST_DISCARD, "step from t = %.17g refused: %s; the state is unchanged", t, problem);
        return ST_DISCARD;
    }
    if (problem == NULL && !(isfinite(c->el.x) && isfinite(c->el.v) && isfinite(c->el.out[2])))
        problem = "it would leave a non-finite state";
    if (problem != NULL) {
        int implicit = strcmp(STEPPER_NAMES[c->el.stepper], "implicit") == 0; /* advise nothing already done */
        rollback(c);
        say(c, ST_DISCARD, "step from t = %.17g with F = %.17g refused: %s (stepper '%s' with step = %.17g%s)", t,
            c->F, problem, STEPPER_NAMES[c->el.stepper], c->el.h, implicit ? "" : "; try 'implicit'");
        return ST_DISCARD;
    }
    /* no output is ever shown NaN or inf after an OK step */
    overflowed = surely_showable(c) ? NULL : unshowable_output(c, real_value, &value);
    if (overflowed != NULL) {
        double time = element_time(&c->el);
        rollback(c);
        say(c, ST_DISCARD, "the step to t = %.17g with F = %.17g refused: %s would be %.17g, not finite (an "
            "overflow); the state is unchanged", time, c->F, overflowed->name, value);
        return ST_DISCARD;
    }
    c->dF[0] = c->dF[1] = 0.0; /* they described F over this step (set at its start): the next is held unless set */
    return ST_OK;
}
#endif

/* the fixed parameters (machine.h): x0 and v0 (the initial state), an effect with memory's */
static int fixed_problem(Instance* c, const Var* var, double value)
{
    if (c->phase == INTERMEDIATE_UPDATE && var->what != W_F) { /* only F is intermediateUpdate="true" */
        say(c, ST_ERROR, "%s refused in intermediate update mode: only F may be set there", var->name);
        return ST_ERROR;
    }
    if (var->what == W_PARAM && c->initialized && (var->index == P_X0 || var->index == P_V0) &&
        value != c->par[var->index]) {
        say(c, ST_ERROR, "parameter %s = %.17g refused: %s is fixed (the initial state) and cannot change after "
            "initialization; the element is unchanged", PARAM_NAMES[var->index], value, PARAM_NAMES[var->index]);
        return ST_ERROR;
    }
    return memory_fixed(c, var, value);
}

static void core_set_float(Instance* c, const Var* var, double value)
{
    if (var->what == W_F) {
        c->F = value;
        c->dF[0] = c->dF[1] = 0.0; /* a new value of F: the derivatives set for the old one no longer hold */
    } else if (var->what == W_PARAM) {
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

#endif
