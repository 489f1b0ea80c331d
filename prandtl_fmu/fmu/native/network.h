/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The native FMU of a network (issue 32: nodes joined by springs, dashpots, sliders, Prandtl branches and cubic
 * springs), the element (force in at the load's node) or, with CONNECTOR, the connector (the load node's motion
 * in, force out), shared by the FMI 2.0 (fmi2.c) and FMI 3.0 (fmi3.c) layers: glue only, no numerics.
 *
 * Every number comes from the library's network kernels, compiled by numba for this scene
 * (fmu/native/network_kernels.py) and declared in the generated "scene.h" with the scene's arrays (the kinds and
 * ends of the elements, the scene's coefficients, x0, v0, u0), the parameters' rules (prandtl_fmu.network.model:
 * Network.with_parameters, check_topology and stepper_problem, as tables) and the FMU's variables (value reference
 * = index in VARS). This file does what network.driver.NetworkElement and NetworkConnector do around the kernels,
 * in the same order of floating-point operations: the clock (origin + steps * grid), a duration split into whole
 * steps and a last shorter one, the parameters handed over at a step, the refusals (fmi2Discard for a bad input,
 * a step that fails or whose outputs would not be finite, the state unchanged; fmi2Error for a bad start value,
 * a non-finite time or a bad FMU state, checked field by field; logged even with logging off, never a NULL
 * category).
 */
#ifndef PRANDTL_NETWORK_H
#define PRANDTL_NETWORK_H
#include "network_types.h"
#include "core.h"
#include "calls.h"
#include "state.h"

/* a step's workspace (Work) and the network in use (Element) as the kernels take them */
#define WORK(w) (w)->d, (w)->grad, (w)->p, (w)->parent, (w)->cluster, (w)->term, (w)->subtree, (w)->queue, \
                (w)->degree, (w)->links, (w)->scale
#define NET(e) (e)->mass, (e)->coef, (int64_t*)KIND, (int64_t*)ENDS, (int64_t)LOAD_NODE, (int64_t)HAS_CUBIC

/* the FMU's time: the network's; the connector's communication point (its outputs are the network there) */
#define FMU_TIME(c) (CONNECTOR ? (c)->time : element_time(&(c)->el))

/* ------------------------------------------------------------------ the library's rules (network/model.py) */

/* the mass of node j under the parameters par: its parameter's, or the scene's (the connector's load node) */
#define MASS_OF(par, j) (MASS_PARAM[j] >= 0 ? (par)[MASS_PARAM[j]] : MASS_SCENE[j])

/* Network.with_parameters (the magnitudes, the rule of each key, a branch's eta and its u0), check_topology (the
 * rules a mass can break: a massless node held by sliders alone, a load on a part with neither a support nor a
 * mass), stepper_problem, and for the connector a load node without mass: the message, or NULL */
static const char* network_problem(const double* par, int stepper, char* buffer, size_t size)
{
    int i, j;
    for (i = 0; i < N_PARAMS_USED; i++) {
        double value = par[i];
        const Param* p = &PARAMS[i];
        if (!isfinite(value)) {
            snprintf(buffer, size, "parameter %s: must be finite, got %.17g", p->name, value);
            return buffer;
        }
        if (magnitude_problem(p->name, value, 0, buffer, size))
            return buffer;
        if (p->rule == R_POSITIVE && !(value > 0)) {
            snprintf(buffer, size, "parameter %s: must be > 0, got %.17g", p->name, value);
            return buffer;
        }
        if (p->rule != R_POSITIVE && value < 0) {
            snprintf(buffer, size, "parameter %s: must be >= 0, got %.17g", p->name, value);
            return buffer;
        }
        if (p->rule == R_ETA && fabs(p->u0) > value) {
            snprintf(buffer, size, "parameter %s: %.17g would leave u0 = %.17g outside [-eta, eta]", p->name, value,
                     p->u0);
            return buffer;
        }
    }
    for (j = 0; j < NN; j++) {
        if (!(MASS_OF(par, j) > 0) && SLIDER_ONLY[j]) {
            snprintf(buffer, size, "parameter m_%s: node %s: massless and held by sliders alone: once a slider "
                     "slips, nothing sets where it stops (give it a mass, a spring or a dashpot)", NODE_NAMES[j],
                     NODE_NAMES[j]);
            return buffer;
        }
    }
    if (LOAD_FLOATING) {
        int carried = 0;
        for (j = 0; j < NN; j++)
            carried |= LOAD_PART[j] && MASS_OF(par, j) > 0;
        if (!carried) {
            snprintf(buffer, size, "the part of the network that carries the load (%s) is joined to the ground by no "
                     "element and has no mass: the load has no equilibrium", NODE_NAMES[LOAD_NODE]);
            return buffer;
        }
    }
    if (stepper >= 0 && strcmp(STEPPER_NAMES[stepper], "projected") == 0) {
        for (j = 0; j < NN; j++) {
            if (!(MASS_OF(par, j) > 0)) {
                snprintf(buffer, size, "'projected' is explicit and needs a mass at every node; %s is massless: use "
                         "'implicit'", NODE_NAMES[j]);
                return buffer;
            }
        }
    }
    return NULL;
}

static const char* settings_problem(Instance* c, char* buffer, size_t size)
{
    int i, stepper = c->stepper_valid ? stepper_index(c->stepper) : -1;
    const char* problem;
    if (stepper < 0) {
        snprintf(buffer, size, "parameter stepper = '%s': must be one of %s (the steppers this FMU "
                 "holds)", c->stepper_valid ? c->stepper : "?", STEPPER_LIST);
        return buffer;
    }
    if (!(isfinite(c->step) && c->step > 0)) {
        snprintf(buffer, size, "parameter step = %.17g: must be finite and > 0", c->step);
        return buffer;
    }
    problem = network_problem(c->par, stepper, buffer, size);
    if (problem != NULL)
        return problem;
    for (i = 0; i < N_PARAMS_USED; i++) { /* NetworkElement.set_parameters: an eta below the branch's |u| now */
        if (PARAMS[i].rule == R_ETA && fabs(c->el.u[PARAMS[i].element]) > c->par[i]) {
            snprintf(buffer, size, "parameter %s: %.17g is below the branch's elongation now, |u| = %.17g: it would "
                     "drop stored energy unbooked", PARAMS[i].name, c->par[i], fabs(c->el.u[PARAMS[i].element]));
            return buffer;
        }
    }
    return NULL;
}

/* stepper_problem's rule of a white noise (NOISE_MASSLESS_LOAD, the library's words): a massless load node needs a
 * dashpot on it (LOAD_DAMPED: the scene's structure); the message, or NULL */
static const char* noise_refusal(const double* par)
{
    return MASS_OF(par, LOAD_NODE) > 0 || LOAD_DAMPED ? NULL : NOISE_MASSLESS_LOAD;
}

/* slave._hand_over_settings: why the settings the master set cannot be handed over, or NULL, in its order: a noise
 * turned off goes first (its values checked), then the parameters (NetworkElement.set_parameters: under the noise in
 * use, a mass set to 0 on the load's node may be refused), the stepper and step; a noise turned on goes last (its
 * values, then NetworkElement.set_noise: the rule of the load's node) */
static const char* hand_over_problem(Instance* c, char* buffer, size_t size)
{
    int turned_on = c->noise_set.sigma != 0.0; /* (a NaN intensity too: refused by its rule) */
    const char* problem = turned_on ? NULL : noise_problem(&c->noise_set, buffer, size);
    if (problem == NULL)
        problem = settings_problem(c, buffer, size);
    if (problem != NULL || !turned_on)
        return problem;
    if (c->noise.sigma != 0.0 && noise_refusal(c->par) != NULL) { /* set_parameters: the names that changed */
        size_t at = (size_t)snprintf(buffer, size, "parameter");
        const char* separator = " ";
        int i;
        for (i = 0; i < N_PARAMS_USED && at < size; i++) {
            const Param* p = &PARAMS[i];
            double now = p->node >= 0 ? c->el.mass[p->node] : c->el.coef[3 * p->element + p->column];
            if (!(c->par[i] == now)) {
                at += (size_t)snprintf(buffer + at, size - at, "%s%s", separator, p->name);
                separator = ", ";
            }
        }
        if (at < size)
            snprintf(buffer + at, size - at, ": %s", noise_refusal(c->par));
        return buffer;
    }
    problem = noise_problem(&c->noise_set, buffer, size);
    if (problem == NULL)
        problem = noise_step_problem(&c->noise_set, c->step, buffer, size);
    if (problem == NULL && noise_refusal(c->par) != NULL) {
        snprintf(buffer, size, "parameter %s", noise_refusal(c->par));
        problem = buffer;
    }
    return problem;
}

/* the coefficients in use from the parameters: mass[j], and column ``column`` of element ``element`` */
static void coefficients_of(const double* par, double* mass, double* coef)
{
    int i;
    memcpy(mass, MASS_SCENE, sizeof(double) * NN);
    memcpy(coef, COEF_SCENE, sizeof(double) * 3 * NE_ARR);
    for (i = 0; i < N_PARAMS_USED; i++) {
        if (PARAMS[i].node >= 0)
            mass[PARAMS[i].node] = par[i];
        else
            coef[3 * PARAMS[i].element + PARAMS[i].column] = par[i];
    }
}

/* slave: the coefficients, stepper and step the master set go to the network (NetworkElement.set_parameters) */
static void hand_over(Instance* c)
{
    coefficients_of(c->par, c->el.mass, c->el.coef);
    c->el.stepper = stepper_index(c->stepper);
    c->el.h = c->step;
    c->noise = c->noise_set; /* NetworkElement.set_noise (sigma 0: none; the connector's: none) */
    c->handed = 1;
    c->preview_state = 0;
}

/* ------------------------------------------------------------------ the network */

static double energy(Element* e, int which)
{
    double kinetic_stored[2];
    if (which >= 2 && which <= 4)
        return e->account[which - 2];
    energies(NET(e), e->x, e->v, e->u, kinetic_stored);
    if (which < 2)
        return kinetic_stored[which];
    /* NetworkElement.energy: work - sliders - damper - (kinetic + stored - initial) */
    return e->account[0] - e->account[1] - e->account[2] - (kinetic_stored[0] + kinetic_stored[1] -
                                                             e->initial_energy);
}

/* driver.failure_message: why a step (or the equilibrium at t = 0) could not be taken */
static const char* failure(int64_t status, char* buffer, size_t size)
{
    if (status == -2)
        snprintf(buffer, size, "no equilibrium: a part of the network with no mass is pushed beyond what holds it "
                 "(e.g. a massless chain pulled beyond the total friction of its nodes, or a massless node beyond its "
                 "branches' strength)");
    else if (status == -1)
        snprintf(buffer, size, "the active-set search did not end within its budget of %lld iterations (%d per node "
                 "and element + %d); a smaller step needs fewer", (long long)SEARCH_BUDGET, SEARCH_PER_TERM,
                 SEARCH_CONSTANT);
    else
        snprintf(buffer, size, "a number overflowed (not finite)");
    return buffer;
}

/* NetworkElement.reset(force) (the connector's: force 0): the scene's x0, v0, u0 and every massless node in
 * equilibrium with the force; NULL, or why not */
static const char* reset(Instance* c, double force, char* buffer, size_t size)
{
    Element* e = &c->el;
    double reaction[1] = {0.0}, kinetic_stored[2];
    int64_t status;
    memset(&e->clock, 0, sizeof e->clock);
    e->force = force;
    e->scene_load = 0;
    memcpy(e->x, X0, sizeof e->x);
    memcpy(e->v, V0, sizeof e->v);
    memcpy(e->u, U0, sizeof e->u);
    memset(e->piece, 0, sizeof e->piece);
    memset(e->account, 0, sizeof e->account);
    memset(e->dissipated, 0, sizeof e->dissipated);
    prandtl_kernel_failed = 0;
    status = initial(NET(e), e->x, e->v, e->u, e->piece, force, reaction);
    if (prandtl_kernel_failed)
        return "a kernel failed (out of memory)";
    if (status < 0)
        return failure(status, buffer, size);
    e->reaction = reaction[0];
    energies(NET(e), e->x, e->v, e->u, kinetic_stored);
    e->initial_energy = kinetic_stored[0] + kinetic_stored[1];
    e->force = 0.0; /* the connector's: the force of a fresh workspace's elements (NetworkConnector.reset) */
    if (!CONNECTOR)
        e->force = force;
    c->preview_state = 0;
    return NULL;
}

/* NetworkElement._steps_from: ``count`` steps of h from step number ``first`` (t_p = t_base + p h); NULL, or why
 * not (the element is then partly advanced: the caller rolls back) */
static const char* steps_from(Instance* c, const Load* l, double t_base, int64_t first, int64_t count, double h,
                              char* buffer, size_t size)
{
    Element* e = &c->el;
    int64_t status = 0, taken;
    if (count == 0)
        return NULL;
    prandtl_kernel_failed = 0;
    if (l->noise.sigma != 0.0) /* the load tuple with its noise (loads.with_white_noise): the noisy kernel */
        taken = NOISY[e->stepper](NET(e), e->x, e->v, e->u, e->piece, e->account, e->dissipated, c->work.out,
                                  WORK(&c->work), l->kind, (double*)l->lk, (double*)l->t, (double*)l->f, l->n, t_base,
                                  first, h, count, &status, l->noise.sigma, l->noise.seed, l->noise.unit, l->cache);
    else
        taken = ADVANCE[e->stepper](NET(e), e->x, e->v, e->u, e->piece, e->account, e->dissipated, c->work.out,
                                    WORK(&c->work), l->kind, (double*)l->lk, (double*)l->t, (double*)l->f, l->n,
                                    t_base, first, h, count, &status);
    if (prandtl_kernel_failed)
        return "a kernel failed (out of memory)";
    if (taken < count) {
        char reason[256];
        snprintf(buffer, size, "the %s step from t = %.17g s %s", STEPPER_NAMES[e->stepper],
                 t_base + (double)(first + taken) * h, failure(status, reason, sizeof reason));
        return buffer;
    }
    e->reaction = c->work.out[2 * NN + 1];
    return NULL;
}

/* NetworkElement.advance: NULL, or why the step was not taken (the caller rolls back) */
static const char* advance(Instance* c, double duration, double force, int scene_load, char* buffer, size_t size)
{
    Element* e = &c->el;
    double h = e->h, whole, rest;
    const char* problem;
    Load l;
    if (duration == 0.0)
        return NULL;
    problem = plan_advance(duration, h, element_time(e) + duration, &whole, &rest, buffer, size);
    if (problem != NULL || (whole == 0 && rest == 0)) /* (0, 0): below rounding of h, no step, the clock stays */
        return problem;
    l = load_of(force, scene_load, &c->noise, c->noise_cache);
    e->force = force;
    e->scene_load = scene_load;
    clock_regrid(&e->clock, h);
    problem = steps_from(c, &l, e->clock.origin, e->clock.steps, (int64_t)whole, h, buffer, size);
    if (problem == NULL && rest > 0)
        problem = steps_from(c, &l, e->clock.origin + (double)(e->clock.steps + (int64_t)whole) * h, 0, 1, rest,
                             buffer, size);
    if (problem != NULL)
        return problem;
    clock_advanced(&e->clock, whole, rest, h);
    return NULL;
}

#if CONNECTOR
/* NetworkConnector.move_to(x, v, time) on ``e``: the load's node along the line from its x to ``x`` in implicit
 * steps of h (kernels.move_node), or in an instant when no time passes (kernels.jump_node); NULL, or why not (``e``
 * is then partly moved: the caller keeps a copy) */
static const char* move(Instance* c, Element* e, double x, double v, double time, char* buffer, size_t size)
{
    double start = element_time(e), duration = time - start, whole = 0.0, rest = 0.0, h = e->h, force[1] = {0.0};
    int64_t status;
    int j;
    if (!(isfinite(x) && isfinite(v) && isfinite(time)) || duration < 0) {
        snprintf(buffer, size, "the motion must be finite and go forward, got x = %.17g, v = %.17g at t = %.17g",
                 x, v, time);
        return buffer;
    }
    prandtl_kernel_failed = 0;
    if (duration > 0) {
        split_duration(duration, h, time, &whole, &rest);
        if (whole == 0 && rest == 0) /* below rounding of h: a sample at the instant it is at (move_to) */
            duration = 0;
    }
    if (duration == 0) { /* an instant: the masses and dashpots hold, the massless part follows */
        status = jump_c(NET(e), e->x, e->v, e->u, e->piece, e->account, e->dissipated, x, force);
    } else {
        if (whole + (rest > 0) > ADVANCE_BUDGET) {
            snprintf(buffer, size, "a move over %.17g s takes more than %.0e steps", duration, ADVANCE_BUDGET);
            return buffer;
        }
        status = move_c(NET(e), e->x, e->v, e->u, e->piece, e->account, e->dissipated, WORK(&c->work), x,
                        (int64_t)whole, h, rest, force);
    }
    if (prandtl_kernel_failed)
        return "a kernel failed (out of memory)";
    if (status < 0) {
        char reason[256];
        snprintf(buffer, size, "the %s from t = %.17g s %s", duration == 0 ? "instant" : "implicit step", start,
                 failure(status, reason, sizeof reason));
        return buffer;
    }
    if (duration != 0) {
        e->clock.origin = time;
        e->clock.steps = 0;
        e->clock.grid = h;
    }
    e->v[LOAD_NODE] = v;
    e->force = force[0];
    for (j = 0; j < NN && isfinite(e->force); j++)
        if (!isfinite(e->x[j]))
            break;
    if (!isfinite(e->force) || j < NN) {
        snprintf(buffer, size, "the motion x = %.17g at t = %.17g s refused: an output would not be finite (an "
                 "overflow)", x, time);
        return buffer;
    }
    return NULL;
}

/* CONNECTOR: the outputs' state, the committed network moved to the inputs set now at the FMU's time, not
 * committed (the PythonFMU NetworkConnectorKind's preview); NULL when that motion is refused (the reason in ``why``) */
static Element* previewed(Instance* c)
{
    if (c->preview_state == 0) {
        double now = element_time(&c->el);
        c->preview = c->el;
        c->preview_state = move(c, &c->preview, c->x_in, c->v_in, c->time > now ? c->time : now, c->why,
                                sizeof c->why) == NULL ? 1 : -1;
    }
    return c->preview_state == 1 ? &c->preview : NULL;
}
#else
static Element* previewed(Instance* c) { return &c->el; } /* the element shows its state */
#endif

/* ------------------------------------------------------------------ outputs */

static double real_value(Instance* c, const Var* var)
{
    Element* e = &c->el;
    switch (var->what) {
    case W_F: return c->F;
    case W_XIN: return c->x_in;
    case W_VIN: return c->v_in;
    case W_PARAM: return c->par[var->index];
    case W_STEP: return c->step;
    case W_NOISE_INTENSITY: return c->noise_set.sigma;
    case W_NOISE_UNIT: return c->noise_set.unit;
    }
    if ((e = previewed(c)) == NULL)
        return NAN; /* the connector's motion refused: so is the getter (calls.h: shown) */
    switch (var->what) {
    case W_X: return e->x[var->index];
    case W_V: return e->v[var->index];
    case W_REACTION: return e->reaction;
    case W_FORCE: return e->force;
    case W_ENERGY: return energy(e, var->index);
    case W_DISSIPATED: return e->dissipated[var->index];
    case W_U: return SENSE[var->index] * e->u[var->index];  /* as written: x_j - x_i (network/model.py) */
    }
    return NAN;
}

#if ARRAYS
/* FMI 3.0's arrays x and v (ARRAYS): every node's value in ``out``; 0, or -1 when one is not a number */
static int node_values(Instance* c, int velocities, double* out)
{
    Element* e = previewed(c);
    int j;
    if (e == NULL)
        return -1;
    for (j = 0; j < NN; j++) {
        out[j] = velocities ? e->v[j] : e->x[j];
        if (!isfinite(out[j]))
            return -1;
    }
    return 0;
}
#endif

static void defaults(Instance* c)
{
    char buffer[512];
    memcpy(c->par, P_SCENE, sizeof c->par);
    instantiated(c);
    c->x_in = X0[LOAD_NODE]; /* the inputs' start values */
    c->v_in = V0[LOAD_NODE];
    c->time = 0.0;
    memset(&c->el, 0, sizeof c->el);
    hand_over(c);
    if (reset(c, 0.0, buffer, sizeof buffer) != NULL)
        c->preview_state = -1; /* no equilibrium under F = 0 (a scene's u0): initialization will say why */
    c->handed = 0;
}

/* ------------------------------------------------------------------ FMU state: a checked blob */

/* the coefficients in use: the parameters' values (checked by their rules), the rest the scene's (on the heap: a
 * network may be large, the host's stack small) */
static const char* coefficients_problem(const Element* e, char* buffer, size_t size)
{
    double* par = (double*)calloc(N_PARAMS + NN + 3 * NE_ARR, sizeof(double));
    double *mass, *coef;
    const char* problem = NULL;
    int i;
    if (par == NULL)
        return "out of memory";
    mass = par + N_PARAMS;
    coef = mass + NN;
    for (i = 0; i < N_PARAMS_USED; i++)
        par[i] = PARAMS[i].node >= 0 ? e->mass[PARAMS[i].node] : e->coef[3 * PARAMS[i].element + PARAMS[i].column];
    coefficients_of(par, mass, coef);
    if (memcmp(mass, e->mass, sizeof(double) * NN) != 0 || memcmp(coef, e->coef, sizeof(double) * 3 * NE_ARR) != 0)
        problem = "its coefficients are not this network's";
    else
        problem = network_problem(par, e->stepper, buffer, size);
    free(par);
    return problem;
}

/* why a state cannot be restored here, or NULL: every field checked (a checksum detects accidents, not edits: a
 * blob with a recomputed one is checked field by field): the coefficients in use by the parameters' rules, the
 * network's state as NetworkElement.set_state checks it (x, v, u, the accounts finite; |u| <= eta of a branch,
 * u = 0 elsewhere), and more: a piece each element's kind can be on, no negative dissipation, the clock */
static const char* state_problem(const State* s, char* buffer, size_t size)
{
    const Element* e = &s->element;
    const char* problem;
    int i, j;
    if (!(e->stepper >= 0 && e->stepper < N_STEPPERS && isfinite(e->h) && e->h > 0 && isfinite(e->force) &&
          isfinite(e->reaction) && isfinite(e->initial_energy) && isfinite(s->time) &&
          (e->scene_load == 0 || e->scene_load == 1) &&
          (s->scene_load == 0 || s->scene_load == 1) && (s->stepper_valid == 0 || s->stepper_valid == 1) &&
          (s->initialized == 0 || s->initialized == 1) && memchr(s->stepper, 0, sizeof s->stepper) != NULL))
        return "it holds a non-finite or out-of-range value";
    if (!clock_valid(&e->clock))
        return "its clock is not a finite time (origin, steps and grid)";
    problem = coefficients_problem(e, buffer, size);
    if (problem == NULL) /* the noise's settings (NoiseParameters._check_noise_state) */
        problem = noise_problem(&s->noise_set, buffer, size);
    if (problem != NULL)
        return problem;
    for (j = 0; j < NN; j++)
        if (!(isfinite(e->x[j]) && isfinite(e->v[j])))
            return "its x and v must be finite numbers";
    if (!(isfinite(e->account[0]) && e->account[1] >= 0 && isfinite(e->account[1]) && e->account[2] >= 0 &&
          isfinite(e->account[2])))
        return "its energy account is not finite (or a dissipation is negative)";
    for (i = 0; i < NE; i++) {
        int64_t p = e->piece[i];
        int plastic = KIND[i] == K_SLIDER || KIND[i] == K_BRANCH;
        if (!(p >= -2 && p <= 2) || (KIND[i] == K_SLIDER && (p == 2 || p == -2)) || (!plastic && p != 0)) {
            snprintf(buffer, size, "element %s is on piece %lld, which its kind has not", ELEMENT_NAMES[i],
                     (long long)p);
            return buffer;
        }
        if (KIND[i] == K_BRANCH ? !(fabs(e->u[i]) <= e->coef[3 * i + 1]) : e->u[i] != 0) {
            snprintf(buffer, size, "the u of %s (%.17g) is outside its elastic range", ELEMENT_NAMES[i], e->u[i]);
            return buffer;
        }
        if (!(isfinite(e->dissipated[i]) && e->dissipated[i] >= 0) ||
            (!plastic && KIND[i] != K_DASHPOT && e->dissipated[i] != 0)) {
            snprintf(buffer, size, "the dissipation of %s (%.17g) is not one", ELEMENT_NAMES[i], e->dissipated[i]);
            return buffer;
        }
    }
#if !CONNECTOR
    { /* the reaction, checked against what x, v and u fix of it (NetworkElement.set_state: kernels.reaction_fits) */
        Element* w = (Element*)e; /* (read only: the kernel writes nothing of it) */
        double range[2] = {0.0, 0.0};
        if (!reaction_check(NET(w), w->x, w->v, w->u, w->piece, (int64_t)(e->clock.grid != 0.0), e->reaction,
                            range)) {
            snprintf(buffer, size, "its reaction (%.17g N) is not the one its x, v and u give (%.17g N, %.17g N either "
                     "way by its stuck sliders)", e->reaction, range[0], range[1]);
            return buffer;
        }
    }
#endif
    return NULL;
}

static int restore(Instance* c, const State* s)
{
    char buffer[512];
    const char* problem = state_refusal(s, state_problem, buffer, sizeof buffer);
    if (problem != NULL) {
        say(c, ST_ERROR, "FMU state refused (%s); the instance is unchanged", problem);
        return ST_ERROR;
    }
    restore_checked(c, s);
    c->initialized = s->initialized;
    c->preview_state = 0;
    return ST_OK;
}

/* ------------------------------------------------------------------ stepping */

/* the exit of initialization mode (machine.h): the settings checked and handed over, the network reset (the
 * connector: moved to the first input) */
static const char* initialize(Instance* c, char* buffer, size_t size)
{
    char reason[512];
    const char* problem = hand_over_problem(c, buffer, size);
    double force = CONNECTOR ? 0.0 : c->F;
    if (problem == NULL && !(isfinite(c->F) && isfinite(c->x_in) && isfinite(c->v_in))) {
        snprintf(buffer, size, "the inputs must be finite (%s = %.17g, %.17g)", CONNECTOR ? "x, v" : "F",
                 CONNECTOR ? c->x_in : c->F, CONNECTOR ? c->v_in : c->F);
        return buffer;
    }
    if (problem != NULL)
        return problem;
    hand_over(c);
    if (!CONNECTOR && c->scene_load) { /* F plus the scene's load at the start time */
        Load l = load_of(0.0, 1, NULL, NULL);
        force = c->F + load_force(l.kind, (double*)l.lk, (double*)l.t, (double*)l.f, l.n, c->start_time);
    }
    if (reset(c, force, reason, sizeof reason) != NULL) {
        snprintf(buffer, size, "no equilibrium at t = 0 under F = %.17g N: %s", force, reason);
        return buffer;
    }
    clock_set(&c->el.clock, c->start_time);
    c->time = c->start_time;
    c->preview_state = 0;
    if (CONNECTOR && previewed(c) == NULL) { /* the first sample, checked now (committed by the first doStep) */
        snprintf(buffer, size, "%s", c->why);
        return buffer;
    }
    c->handed = 0;
    c->preview_state = 0;
    return NULL;
}

/* once started: a master that connects F is told the scene's load is added (logging on or off) */
static void started(Instance* c)
{
    if (!CONNECTOR && c->scene_load)
        say(c, ST_WARNING, "%s", SCENE_LOAD_NOTICE);
}

static void hand_over_settings(Instance* c) { hand_over(c); }

/* a doStep (machine.h, the settings handed over): the connector's input sample committed at the communication
 * point (the clock only goes on), the element checkpointed, put at t and advanced by H under F; a step that fails or
 * would show an output that is not a number is rolled back */
static int step(Instance* c, double t, double H)
{
    char buffer[768];
    const char* problem;
    const Var* overflowed;
    double value;
    if (!(isfinite(c->F) && isfinite(c->x_in) && isfinite(c->v_in))) {
        say(c, ST_DISCARD, "the inputs must be finite (%s = %.17g, %.17g); step not taken", CONNECTOR ? "x, v" : "F",
            CONNECTOR ? c->x_in : c->F, CONNECTOR ? c->v_in : c->F);
        return ST_DISCARD;
    }
    if (CONNECTOR) {
        double now = c->time;
        c->time = t;
        c->preview_state = 0;
        if (previewed(c) == NULL) {
            c->time = now;
            c->preview_state = 0;
            say(c, ST_DISCARD, "step from t = %.17g with x = %.17g refused: %s; the state is unchanged", t, c->x_in,
                c->why);
            return ST_DISCARD;
        }
        c->el = c->preview;
        c->time = t + H;
        c->preview_state = 0;
        return ST_OK;
    }
    c->saved = c->el; /* NetworkElement.checkpoint, then the time */
    clock_set(&c->el.clock, t);
    problem = advance(c, H, c->F, c->scene_load, buffer, sizeof buffer);
    if (problem != NULL) {
        c->el = c->saved;
        say(c, ST_DISCARD, "step from t = %.17g refused: %s; the state is unchanged", t, problem);
        return ST_DISCARD;
    }
    overflowed = unshowable_output(c, real_value, &value); /* no output is ever shown NaN or inf after an OK step */
    if (overflowed != NULL) {
        double time = element_time(&c->el);
        c->el = c->saved;
        c->preview_state = 0;
        say(c, ST_DISCARD, "the step to t = %.17g refused: %s would be %.17g, not finite (an overflow); the state is "
            "unchanged", time, overflowed->name, value);
        return ST_DISCARD;
    }
    return ST_OK;
}

static int fixed_problem(Instance* c, const Var* var, double value) /* (no fixed parameter) */
{
    (void)c;
    (void)var;
    (void)value;
    return ST_OK;
}

static void core_set_float(Instance* c, const Var* var, double value)
{
    if (var->what == W_F)
        c->F = value;
    else if (var->what == W_XIN)
        c->x_in = value;
    else if (var->what == W_VIN)
        c->v_in = value;
    else if (var->what == W_PARAM) {
        c->par[var->index] = value;
        c->handed = 0;
    } else if (var->what == W_NOISE_INTENSITY || var->what == W_NOISE_UNIT) {
        *(var->what == W_NOISE_INTENSITY ? &c->noise_set.sigma : &c->noise_set.unit) = value;
        c->handed = 0; /* checked when handed over (a bad value: a Discard at the next step) */
    } else {
        c->step = value;
        c->handed = 0;
    }
    c->preview_state = 0;
}

/* an Integer: noise_seed (the network has no other) */
static int32_t integer_value(Instance* c, const Var* var)
{
    (void)var;
    return (int32_t)c->noise_set.seed;
}

#endif
