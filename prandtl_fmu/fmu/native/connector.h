/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The native FMU's connector (a massless scene between two bodies: x, v in, force out), shared by its FMI 2.0
 * (fmi2.c) and FMI 3.0 (fmi3.c) layers: glue only, no numerics.
 *
 * What fmu/python/kinds.py's ConnectorKind and connector.Connector do around the library's kernels (compiled for this scene,
 * declared in "scene.h"), in the same order of floating-point operations: the outputs show the element moved to
 * the inputs set last without committing (a preview: a copy of the state moved there); fmi2DoStep commits the
 * input sample at the communication point (the branches follow the exact play update along the line from the
 * last committed x, series dashpots relax over the time between samples, the dashpot dissipates
 * c (v0^2 + v0 v + v^2) dt / 3: the kernel move); initialization moves the element from x = 0 to the first input.
 *
 * The effects with memory (memory/: [delay], [history], [dahl]) as the element carries them (element.h): their
 * parameters are the FMU's fixed ones (mp), their state an array on the heap (mem: the history's variables, the Dahl
 * force, the delay's buffer of nd values, sized at instantiation, at the exit of initialization mode and at a reset
 * from the delay's tau in use), handed to every kernel, which rebuilds the library's tuple from them; a move
 * carries them along the path (kernels/drive.py drive_with_memory), the force and the tangent add theirs. The
 * preview and the checkpoint have arrays of their own; an FMU state carries the memory after its fixed part
 * (state.h: STATE_EXTRA), under its checksum.
 */
#ifndef PRANDTL_CONNECTOR_H
#define PRANDTL_CONNECTOR_H
#include "connector_types.h"
#include "core.h"
#include "calls.h"
#include "state.h"

static int damped(const Element* e) { return HAS_DAMPER && e->p[P_C] > 0.0; }

static double* memory_of(const Element* e) { return e->mem != NULL ? e->mem : (double*)e->mp; } /* (none: unread) */
/* the arrays every kernel takes: the coefficients, the branches', the memory's (kernels._CONNECTOR_SIGNATURES);
 * KERNEL_ARGS(e, mem) with the memory's state ``mem`` (a state blob's: read only, by the force and the energy) */
#define KERNEL_ARGS(e, mem) (double*)(e)->p, (double*)K, (double*)ETA, (double*)(e)->cs, (double*)(e)->u, \
                       (double*)(e)->mp, (double*)(mem), (e)->nd
#define KERNEL_ARGS_OF(e) KERNEL_ARGS(e, memory_of(e))
#define KERNEL(e, name) (damped(e) ? name##_c : name##_n)

/* Connector.move_to: commit (x, v) at ``time`` */
static void move_to(Element* e, double x, double v, double time)
{
    double dx = x - e->x, xs = x, vs = v, duration = time - e->time, force;
    KERNEL(e, move)(KERNEL_ARGS_OF(e), e->x, e->v, e->time, &xs, &vs, &duration, &force, e->account);
    if (dx != 0)
        e->direction = copysign(1.0, dx);
    e->x = x;
    e->v = v;
    e->time = time;
}

/* Connector.reset: x = 0, v = 0, the scene's u0 (or a fresh memory stack), a fresh memory, time 0 */
static void reset(Element* e)
{
    memcpy(e->u, U0, sizeof e->u);
    KERNEL(e, cinitial)(KERNEL_ARGS_OF(e));
    e->x = e->v = e->time = 0.0;
    e->direction = 1.0;
    memset(e->account, 0, sizeof e->account);
}

/* the coefficients the master set go to the element (at initialization and at every step) */
static void hand_over(Instance* c)
{
    memcpy(c->el.p, c->par, sizeof c->el.p);
    memcpy(c->el.cs, c->cbranch, sizeof c->el.cs);
}

/* a copy of an element (Connector.copy), its branches' state in the part in use only (the memory stack's pieces, as
 * stack.used), its memory's state into ``to``'s own array (allocated with the element's: allocate_memory) */
static void copy_element(Element* to, const Element* from)
{
    memcpy(to->p, from->p, sizeof to->p);
    memcpy(to->cs, from->cs, sizeof to->cs);
    to->x = from->x;
    to->v = from->v;
    to->time = from->time;
    to->direction = from->direction;
    memcpy(to->account, from->account, sizeof to->account);
    memcpy(to->u, from->u, branch_state_used(from->u) * sizeof(double));
    memcpy(to->mp, from->mp, sizeof to->mp);
    to->nd = from->nd;
    to->mem_len = from->mem_len;
    if (from->mem_len > 0) /* memory.copy_memory */
        memcpy(to->mem, from->mem, (size_t)from->mem_len * sizeof(double));
}

/* the committed element moved to the inputs set last, in c->preview */
static Element* previewed(Instance* c)
{
    Element* p = &c->preview;
    copy_element(p, &c->el);
    move_to(p, c->x_in, c->v_in, p->time);
    return p;
}

/* the outputs: the element at the inputs set last, not committed (the PythonFMU ConnectorKind's preview) */
static double real_value(Instance* c, const Var* var)
{
    Element* preview;
    double direction;
    switch (var->what) {
    case W_X: return c->x_in;
    case W_V: return c->v_in;
    case W_PARAM: return c->par[var->index];
    case W_CBRANCH: return c->cbranch[var->index < 0 ? 0 : var->index];
    case W_MEMORY: return c->mpar[var->index];
    }
    if (var->what == W_ENERGY && var->index == 4)
        return c->el.account[2]; /* the dashpots: up to the last doStep */
    if (!(isfinite(c->x_in) && isfinite(c->v_in)))
        return NAN;
    preview = previewed(c);
    switch (var->what) {
    case W_FORCE:
        return KERNEL(preview, cforce)(KERNEL_ARGS_OF(preview), preview->x, preview->v, preview->time);
    case W_STIFFNESS:
        direction = preview->v == 0 ? preview->direction : copysign(1.0, preview->v);
        return KERNEL(preview, ctangent)(KERNEL_ARGS_OF(preview), preview->x, direction);
    case W_ENERGY:
        if (var->index == 1)
            return KERNEL(preview, cstored)(KERNEL_ARGS_OF(preview), preview->x);
        return preview->account[1]; /* dissipated_sliders */
    }
    return NAN;
}

/* fmi2GetDirectionalDerivative, fmi3GetDirectionalDerivative (``function``): d force = (d force/d x) dx + (d force/d v)
 * dv at the element moved to the inputs set last (the outputs' preview), the tangent for the direction of the move
 * from the committed x to the x set (at the committed x itself: of v, else of the last motion, as the output
 * stiffness); ``unknown`` must be force,
 * ``known`` x and v (each at most once), their seeds ``seed`` (kernel cdirectional: no arithmetic here) */
#define HAS_DIRECTIONAL_DERIVATIVES 1
static int core_directional_derivative(Instance* c, const unsigned unknown[], size_t n_unknown, const unsigned known[],
                                       size_t n_known, const double seed[], double sensitivity[], const char* function)
{
    Element* preview;
    double dx = 0.0, dv = 0.0, direction, value;
    int seen_x = 0, seen_v = 0;
    size_t i;
    if (!(given(c, unknown, function, "unknowns") && given(c, known, function, "knowns") &&
          given(c, seed, function, "seed") && given(c, sensitivity, function, "sensitivity")))
        return ST_ERROR;
    if (n_unknown != 1) {
        say(c, ST_ERROR, "%s refused: %zu unknowns: this FMU has one output with a directional derivative, force",
            function, n_unknown);
        return ST_ERROR;
    }
    if (find(unknown[0], T_REAL) == NULL || find(unknown[0], T_REAL)->what != W_FORCE) {
        say(c, ST_ERROR, "%s refused: unknown %u is not the output force (the one output with a directional "
            "derivative)", function, unknown[0]);
        return ST_ERROR;
    }
    for (i = 0; i < n_known; i++) {
        const Var* var = find(known[i], T_REAL);
        int* seen = var == NULL ? NULL : var->what == W_X ? &seen_x : var->what == W_V ? &seen_v : NULL;
        if (seen == NULL || *seen) {
            say(c, ST_ERROR, "%s refused: known %u is not the input x or v, or is listed twice", function, known[i]);
            return ST_ERROR;
        }
        if (!isfinite(seed[i])) {
            say(c, ST_ERROR, "%s refused: the seed %.17g of known %u is not finite", function, seed[i], known[i]);
            return ST_ERROR;
        }
        *seen = 1;
        *(var->what == W_X ? &dx : &dv) = seed[i];
    }
    if (!(isfinite(c->x_in) && isfinite(c->v_in))) {
        say(c, ST_ERROR, "%s refused: the inputs x = %.17g, v = %.17g are not finite", function, c->x_in, c->v_in);
        return ST_ERROR;
    }
    preview = previewed(c);
    /* the force is the function of x that moves the branches from the committed x to it: its slope is the tangent
     * for that move's direction (on both sides of x, between switches); at the committed x, for the motion ahead */
    direction = c->x_in != c->el.x || preview->v == 0 ? preview->direction : copysign(1.0, preview->v);
    prandtl_kernel_failed = 0;
    value = KERNEL(preview, cdirectional)(KERNEL_ARGS_OF(preview), preview->x, direction, dx, dv);
    if (prandtl_kernel_failed || !isfinite(value)) {
        say(c, ST_ERROR, "%s refused: the derivative is not a finite number here", function);
        return ST_ERROR;
    }
    sensitivity[0] = value;
    return ST_OK;
}

/* fmi2GetRealOutputDerivatives, fmi3GetOutputDerivatives (front.h's core_get_output_derivatives): the ``order``-th
 * time derivative of force at the element moved to the inputs set last (the outputs' preview), along the path the
 * inputs' derivatives set for the next doStep describe, x' = v where x's are not set (Connector.output_derivatives:
 * the kernel crates, kernels/rates.connector_rates), into ``value``; NULL, or why it is not given */
#define HAS_OUTPUT_DERIVATIVES 1
static const char* output_derivative(Instance* c, const Var* var, int order, double* value, char* buffer, size_t size)
{
    Element* preview;
    double out[2] = {0.0, 0.0};
    if (var == NULL || var->what != W_FORCE)
        return "not an output whose derivatives this FMU gives (force)";
    if (OUTPUT_DERIVATIVE_ORDER == 0)
        return "not given with series dashpots or effects with memory (their forces' rates are not the tangent's)";
    if (order < 1 || order > OUTPUT_DERIVATIVE_ORDER) {
        snprintf(buffer, size, "order %d: this FMU gives orders 1 and 2 (maxOutputDerivativeOrder)", order);
        return buffer;
    }
    if (!(isfinite(c->x_in) && isfinite(c->v_in)))
        return "the inputs x and v are not finite";
    preview = previewed(c);
    prandtl_kernel_failed = 0;
    KERNEL(preview, crates)(KERNEL_ARGS_OF(preview), preview->x, preview->v, c->xd, c->vd, preview->direction, out);
    *value = out[order - 1];
    if (prandtl_kernel_failed || !isfinite(*value))
        return "it is not a finite number here";
    return NULL;
}

static void defaults(Instance* c)
{
    memcpy(c->par, P_SCENE, sizeof c->par);
    memcpy(c->cbranch, CS_SCENE, sizeof c->cbranch);
    memcpy(c->mpar, MEM_SCENE, sizeof c->mpar);
    c->x_in = c->v_in = 0.0;
    c->xd[0] = c->xd[1] = c->vd[0] = c->vd[1] = 0.0;
    instantiated(c);
    clear_element(&c->el);
    hand_over(c);
    memcpy(c->el.mp, c->mpar, sizeof c->el.mp);
    prandtl_kernel_failed = 0;
    if (memory_at_instantiation(c))
        reset(&c->el);
}

/* ------------------------------------------------------------------ FMU state: a checked blob */

/* why a state cannot be restored here, or NULL: every field checked as strictly as the setters check the master's
 * values (a checksum detects accidents, not edits: a blob with a recomputed one is checked field by field) */
static const char* state_problem(const State* s, char* buffer, size_t size)
{
    const Element* e = &s->element;
    const char* problem;
    int i;
    if (!(isfinite(e->x) && isfinite(e->v) && isfinite(e->time) && isfinite(s->x_in) && isfinite(s->v_in) &&
          isfinite(s->start_time) && isfinite(s->xd[0]) && isfinite(s->xd[1]) && isfinite(s->vd[0]) &&
          isfinite(s->vd[1]) && (e->direction == 1.0 || e->direction == -1.0) &&
          (s->initialized == 0 || s->initialized == 1)))
        return "it holds a non-finite or out-of-range value";
    for (i = 0; i < 3; i++)
        if (!isfinite(e->account[i]) || (i > 0 && e->account[i] < 0)) /* (a dissipation never gives back) */
            return "its energy account is not finite (or a dissipation is negative)";
    for (i = 0; i < (STACK ? 0 : NB); i++) {
        if (!(fabs(e->u[i]) <= ETA[i])) {
            snprintf(buffer, size, "branch %d has elongation %.17g beyond its range %.17g", i + 1, e->u[i], ETA[i]);
            return buffer;
        }
    }
    problem = parameter_problem(e->p, e->cs, buffer, size); /* the coefficients in use, as the setters' */
    if (problem == NULL)
        problem = parameter_problem(s->par, s->cbranch, buffer, size);
    if (problem == NULL) /* the memory's parameters and state */
        problem = memory_state_problem(s, buffer, size);
    if (problem == NULL && STACK) /* the memory stack */
        problem = stack_problem(K, e->u);
    if (problem == NULL) { /* Connector.set_state: its force (the memory's with it) and energy are numbers */
        const double* mem = HAS_MEMORY ? (const double*)(s + 1) : e->mp;
        double force, energy;
        prandtl_kernel_failed = 0;
        force = KERNEL(e, cforce)(KERNEL_ARGS(e, mem), e->x, e->v, e->time);
        energy = KERNEL(e, cstored)(KERNEL_ARGS(e, mem), e->x);
        if (prandtl_kernel_failed || !(isfinite(force) && isfinite(energy))) {
            snprintf(buffer, size, "it has x = %.17g, v = %.17g: its force or energy is not finite", e->x, e->v);
            return buffer;
        }
    }
    return problem;
}

static int restore(Instance* c, const State* s)
{
    char buffer[256];
    const char* problem = state_refusal(s, state_problem, buffer, sizeof buffer);
    if (problem == NULL && HAS_MEMORY) /* the memory's arrays sized for the state's */
        problem = allocate_memory(c, s->element.mem_len, buffer, sizeof buffer);
    if (problem != NULL) {
        say(c, ST_ERROR, "FMU state refused (%s); the instance is unchanged", problem);
        return ST_ERROR;
    }
    restore_checked(c, s);
    return ST_OK;
}

/* ------------------------------------------------------------------ stepping */

/* the exit of initialization mode (machine.h): the coefficients checked and handed over, the memory sized for its
 * parameters, the element moved from x = 0 to the first input (the PythonFMU ConnectorKind.start) */
static const char* initialize(Instance* c, char* buffer, size_t size)
{
    char why[400], shown[40];
    const char* problem = parameter_problem(c->par, c->cbranch, buffer, size);
    if (problem == NULL)
        problem = memory_problem(c->mpar, buffer, size);
    if (problem == NULL && !(isfinite(c->x_in) && isfinite(c->v_in))) {
        snprintf(buffer, size, "input x = %.17g, v = %.17g refused: the motion must be finite", c->x_in, c->v_in);
        return buffer;
    }
    if (problem == NULL) {
        hand_over(c);
        memcpy(c->el.mp, c->mpar, sizeof c->el.mp); /* fixed: handed over here only */
        problem = size_memory(c, buffer, size); /* the delay's buffer for the tau set */
    }
    if (problem != NULL)
        return problem;
    reset(&c->el);
    c->el.time = c->start_time;
    if (delay_time_problem(memory_of(&c->el), c->el.time, c->el.time, why, sizeof why) != NULL) {
        snprintf(buffer, size, "the sample at t = %s s refused: %s", python_repr(c->el.time, shown, sizeof shown), why);
        reset(&c->el);
        return buffer;
    }
    move_to(&c->el, c->x_in, c->v_in, c->el.time); /* from x = 0 to the first input, monotonically */
    return NULL;
}

static void started(Instance* c) { (void)c; } /* (a connector has no load to tell of, no stepper to check) */

/* Connector.advance's motion along the inputs' Taylor polynomial over ``H`` from the committed sample (kernel cpath:
 * the play update per monotone piece, the path cut at its turning point); the inputs become the path's end */
static void follow_derivatives(Instance* c, double H)
{
    Element* e = &c->el;
    double out[4];
    KERNEL(e, cpath)(KERNEL_ARGS_OF(e), e->x, e->v, c->xd, c->vd, H, e->account, out);
    if (out[3] != 0)
        e->direction = out[3];
    e->x = c->x_in = out[0];
    e->v = c->v_in = out[1];
    e->time = e->time + H;
}

/* a doStep (machine.h): the input sample committed at the communication point (the master's clock only moves
 * forward), then, with the inputs' derivatives set, the motion along their polynomial to t + H (Connector.advance);
 * a sample whose outputs would not be numbers is rolled back (the inputs and their derivatives kept) */
static int step(Instance* c, double t, double H)
{
    char buffer[512], why[400], shown[40];
    const char* problem = parameter_problem(c->par, c->cbranch, buffer, sizeof buffer);
    const Var* overflowed;
    double value, time, x_in = c->x_in, v_in = c->v_in;
    int polynomial = c->xd[0] != 0.0 || c->xd[1] != 0.0 || c->vd[0] != 0.0 || c->vd[1] != 0.0;
    if (problem != NULL) {
        say(c, ST_DISCARD, "%s; steps are refused until it is set right", problem);
        return ST_DISCARD;
    }
    if (!(isfinite(c->x_in) && isfinite(c->v_in))) {
        say(c, ST_DISCARD, "input x = %.17g, v = %.17g refused: the motion must be finite; step not taken", c->x_in,
            c->v_in);
        return ST_DISCARD;
    }
    time = t > c->el.time ? t : c->el.time;
    if (delay_time_problem(memory_of(&c->el), c->el.time, time, why, sizeof why) != NULL) { /* Connector.move_to */
        say(c, ST_DISCARD, "step from t = %.17g refused: the sample at t = %s s refused: %s; the state is unchanged",
            t, python_repr(time, shown, sizeof shown), why);
        return ST_DISCARD;
    }
    copy_element(&c->saved, &c->el);
    hand_over(c);
    move_to(&c->el, c->x_in, c->v_in, time);
    if (polynomial)
        follow_derivatives(c, H);
    overflowed = unshowable_output(c, real_value, &value); /* no output is ever shown NaN or inf after an OK step */
    if (overflowed != NULL || !(isfinite(c->el.x) && isfinite(c->el.v))) {
        copy_element(&c->el, &c->saved);
        c->x_in = x_in;
        c->v_in = v_in;
        say(c, ST_DISCARD, "the step to t = %.17g with x = %.17g, v = %.17g refused: %s would be %.17g, not finite "
            "(an overflow); the state is unchanged", time, x_in, v_in,
            overflowed != NULL ? overflowed->name : "the state", overflowed != NULL ? value : NAN);
        return ST_DISCARD;
    }
    c->xd[0] = c->xd[1] = c->vd[0] = c->vd[1] = 0.0; /* they described this step: the next is held unless set */
    return ST_OK;
}

static int fixed_problem(Instance* c, const Var* var, double value) { return memory_fixed(c, var, value); }

static void core_set_float(Instance* c, const Var* var, double value)
{
    int j;
    if (var->what == W_X) {
        c->x_in = value;
        c->xd[0] = c->xd[1] = 0.0; /* a new value of x: the derivatives set for the old one no longer hold */
    } else if (var->what == W_V) {
        c->v_in = value;
        c->vd[0] = c->vd[1] = 0.0;
    } else if (var->what == W_PARAM)
        c->par[var->index] = value;
    else if (var->what == W_MEMORY)
        c->mpar[var->index] = value; /* checked when handed over (the next exit of initialization mode) */
    else
        for (j = 0; j < NB; j++)
            if (var->index < 0 || var->index == j)
                c->cbranch[j] = value;
}

static void core_set_stepper(Instance* c, const char* value) { (void)c; (void)value; }

/* ------------------------------------------------------------------ x's and v's derivatives (FMI 2.0) */

#define HAS_INPUT_DERIVATIVES 1

/* fmi2SetRealInputDerivatives: x', x'' and v', v'' (orders 1 and 2) at the next doStep's start; over that step the
 * flanges follow x(t) = x + x' (t - t0) + x'' (t - t0)^2 / 2 (v the same with its own), Connector.advance (kernel
 * cpath). Every entry checked (a value reference of x or v, an order 1 or 2, a finite value; a scene whose
 * branches have series dashpots or effects with memory takes none), then all set; fmi2SetReal of x (v) sets x's
 * (v's) to 0, a completed doStep all of them. */
static int core_set_input_derivatives(Instance* c, const unsigned vr[], size_t n, const int order[],
                                      const double value[], const char* function)
{
    size_t i;
    if (!arrays_given(c, n, vr, value, function) || !(n == 0 || given(c, order, function, "order")))
        return ST_ERROR;
    for (i = 0; i < n; i++) {
        const Var* var = find(vr[i], T_REAL);
        if (var == NULL || (var->what != W_X && var->what != W_V)) {
            say(c, ST_ERROR, "%s refused: value reference %u is not the input x or v (the inputs whose derivatives "
                "this FMU takes); nothing set", function, vr[i]);
            return ST_ERROR;
        }
        if (order[i] != 1 && order[i] != 2) {
            say(c, ST_ERROR, "%s refused: order %d of %s: this FMU takes orders 1 and 2 (maxInputDerivativeOrder); "
                "nothing set", function, (int)order[i], var->name);
            return ST_ERROR;
        }
        if (!isfinite(value[i])) {
            say(c, ST_ERROR, "%s refused: %s's derivative of order %d = %.17g must be finite; nothing set", function,
                var->name, (int)order[i], value[i]);
            return ST_ERROR;
        }
    }
    if (n > 0 && (HAS_SERIES || HAS_MEMORY)) {
        say(c, ST_ERROR, "%s refused: input derivatives with series dashpots or effects with memory: their forces "
            "depend on the path's timing, which the connector does not follow; hold the inputs; nothing set",
            function);
        return ST_ERROR;
    }
    for (i = 0; i < n; i++)
        (find(vr[i], T_REAL)->what == W_X ? c->xd : c->vd)[order[i] - 1] = value[i];
    return ST_OK;
}

/* the connector's one Integer is n, a constant: the motion comes in, no white noise */
static int32_t integer_value(Instance* c, const Var* var) { (void)c; (void)var; return (int32_t)N_VALUE; }

static int core_check_integer(Instance* c, const Var* var, unsigned vr, const char* function)
{
    (void)var;
    say(c, ST_ERROR, "%s refused: the FMU has no Integer input or tunable parameter (value reference %u)", function,
        vr);
    return ST_ERROR;
}

static void core_set_integer(Instance* c, const Var* var, int32_t value) { (void)c; (void)var; (void)value; }

#endif
