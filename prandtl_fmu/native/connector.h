/* The native FMU's connector (a massless scene between two bodies: x, v in, force out), shared by its FMI 2.0
 * (fmi2.c) and FMI 3.0 (fmi3.c) layers: glue only, no numerics.
 *
 * What fmu/connector_slave.py and connector.Connector do around the library's kernels (compiled for this scene,
 * declared in "scene.h"), in the same order of floating-point operations: the outputs show the element moved to
 * the inputs set last without committing (a preview: a copy of the state moved there); fmi2DoStep commits the
 * input sample at the communication point (the branches follow the exact play update along the line from the
 * last committed x, series dashpots relax over the time between samples, the dashpot dissipates
 * c (v0^2 + v0 v + v^2) dt / 3); initialization moves the element from x = 0 to the first input.
 */
#ifndef PRANDTL_CONNECTOR_H
#define PRANDTL_CONNECTOR_H
#include "common.h"

typedef struct {
    double p[N_PARAMS]; /* the coefficients in use (k0, k3, c) */
    double cs[NB_CS];   /* the series dashpots in use */
    double x, v, time, direction; /* the committed sample; the direction of the last motion */
    double u[NB_ARR];
    double account[3];  /* [1] the sliders, [2] the dashpots (connector.SLIDERS, DAMPER) */
} Element;

typedef struct {
    char header[24];
    uint32_t version, size;
    char digest[65];
    Element element;
    double x_in, v_in, start_time, par[N_PARAMS], cbranch[NB_CS];
    int initialized;
    uint64_t checksum;
} State;

typedef struct {
    char* name;
    void* env; /* the host's: its environment and logger (the FMI version's layer calls it, emit()) */
    void* logger;
    int logging, phase, last_step_failed;
    Element el;
    /* what the master set */
    double x_in, v_in, start_time, par[N_PARAMS], cbranch[NB_CS];
    int initialized;
    int scene_load;   /* none here: what the FMI layers' Boolean and String calls refuse */
    char stepper[32];
    Element preview;  /* the outputs' state (on the heap with the instance, never a large copy on the host's stack) */
    Element saved;    /* core_do_step's checkpoint: a step whose outputs overflow is rolled back */
} Instance;

static double element_time(const Element* e) { return e->time; }

static int damped(const Element* e) { return HAS_DAMPER && e->p[P_C] > 0.0; }

/* Connector.move_to: commit (x, v) at ``time`` */
static void move_to(Element* e, double x, double v, double time)
{
    double dx = x - e->x, xs = x, vs = v, duration = time - e->time, force;
    (damped(e) ? move_c : move_n)(e->p, (double*)K, (double*)ETA, e->cs, e->u, e->x, &xs, &vs, &duration, &force,
                                  e->account);
    if (damped(e))
        e->account[2] += e->p[P_C] * (e->v * e->v + e->v * v + v * v) * (time - e->time) / 3.0;
    if (dx != 0)
        e->direction = copysign(1.0, dx);
    e->x = x;
    e->v = v;
    e->time = time;
}

/* Connector.reset: x = 0, v = 0, the scene's u0 (or a fresh memory stack), time 0 */
static void reset(Element* e)
{
    memcpy(e->u, U0, sizeof e->u);
    (damped(e) ? cinitial_c : cinitial_n)(e->p, (double*)K, (double*)ETA, e->cs, e->u);
    e->x = e->v = e->time = 0.0;
    e->direction = 1.0;
    memset(e->account, 0, sizeof e->account);
}

static void hand_over(Instance* c)
{
    memcpy(c->el.p, c->par, sizeof c->el.p);
    memcpy(c->el.cs, c->cbranch, sizeof c->el.cs);
}

/* a copy of an element, its branches' state in the part in use only (the memory stack's pieces, as stack.used) */
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
}

/* the committed element moved to the inputs set last, in c->preview */
static Element* previewed(Instance* c)
{
    Element* p = &c->preview;
    copy_element(p, &c->el);
    move_to(p, c->x_in, c->v_in, p->time);
    return p;
}

/* the outputs: the element at the inputs set last, not committed (connector_slave._current) */
static double real_value(Instance* c, const Var* var)
{
    Element* preview;
    double direction;
    switch (var->what) {
    case W_X: return c->x_in;
    case W_V: return c->v_in;
    case W_PARAM: return c->par[var->index];
    case W_CBRANCH: return c->cbranch[var->index < 0 ? 0 : var->index];
    }
    if (var->what == W_ENERGY && var->index == 4)
        return c->el.account[2]; /* the dashpots: up to the last doStep */
    if (!(isfinite(c->x_in) && isfinite(c->v_in)))
        return NAN;
    preview = previewed(c);
    switch (var->what) {
    case W_FORCE:
        return (damped(preview) ? cforce_c : cforce_n)(preview->p, (double*)K, (double*)ETA, preview->cs, preview->u,
                                                       preview->x, preview->v);
    case W_STIFFNESS:
        direction = preview->v == 0 ? preview->direction : copysign(1.0, preview->v);
        return (damped(preview) ? ctangent_c : ctangent_n)(preview->p, (double*)K, (double*)ETA, preview->cs,
                                                           preview->u, preview->x, direction);
    case W_ENERGY:
        if (var->index == 1)
            return (damped(preview) ? cstored_c : cstored_n)(preview->p, (double*)K, (double*)ETA, preview->cs,
                                                             preview->u, preview->x);
        return preview->account[1]; /* dissipated_sliders */
    }
    return NAN;
}

static void defaults(Instance* c)
{
    memcpy(c->par, P_SCENE, sizeof c->par);
    memcpy(c->cbranch, CS_SCENE, sizeof c->cbranch);
    c->x_in = c->v_in = 0.0;
    c->start_time = 0.0;
    c->initialized = 0;
    c->phase = INSTANTIATED;
    c->last_step_failed = 0;
    memset(&c->el, 0, sizeof c->el);
    hand_over(c);
    reset(&c->el);
}

/* ------------------------------------------------------------------ FMU state: a checked blob */

static void capture(const Instance* c, State* s)
{
    memset(s, 0, sizeof *s);
    FILL_HEAD(s);
    s->element = c->el;
    s->x_in = c->x_in;
    s->v_in = c->v_in;
    s->start_time = c->start_time;
    memcpy(s->par, c->par, sizeof s->par);
    memcpy(s->cbranch, c->cbranch, sizeof s->cbranch);
    s->initialized = c->initialized;
    s->checksum = fnv1a((const unsigned char*)s, offsetof(State, checksum));
}

/* why a state cannot be restored here, or NULL: every field checked as strictly as the setters check the master's
 * values (a checksum detects accidents, not edits: a blob with a recomputed one is checked field by field) */
static const char* state_problem(const State* s, char* buffer, size_t size)
{
    const Element* e = &s->element;
    const char* problem;
    int i;
    const char* head = head_problem(s->header, s->version, s->size, sizeof *s, s->digest, s->checksum,
                                    fnv1a((const unsigned char*)s, offsetof(State, checksum)));
    if (head != NULL)
        return head;
    if (!(isfinite(e->x) && isfinite(e->v) && isfinite(e->time) && isfinite(s->x_in) && isfinite(s->v_in) &&
          isfinite(s->start_time) && (e->direction == 1.0 || e->direction == -1.0) &&
          (s->initialized == 0 || s->initialized == 1)))
        return "it holds a non-finite or out-of-range value";
    for (i = 0; i < 3; i++)
        if (!isfinite(e->account[i]))
            return "its energy account is not finite";
    for (i = 0; i < (STACK ? 0 : NB); i++) {
        if (!(fabs(e->u[i]) <= ETA[i])) {
            snprintf(buffer, size, "branch %d has elongation %.17g beyond its range %.17g", i + 1, e->u[i], ETA[i]);
            return buffer;
        }
    }
    problem = parameter_problem(e->p, e->cs, buffer, size); /* the coefficients in use, as the setters' */
    if (problem == NULL)
        problem = parameter_problem(s->par, s->cbranch, buffer, size);
    if (problem == NULL && STACK) { /* the memory stack: stack.restore's rules, compiled (state_check) */
        double* scratch = (double*)malloc(STATE_SCRATCH * sizeof(double));
        int64_t code;
        if (scratch == NULL)
            return "out of memory";
        prandtl_kernel_failed = 0;
        code = state_check((double*)K, (double*)e->u, scratch);
        free(scratch);
        if (prandtl_kernel_failed)
            return "its memory stack could not be checked";
        if (code != 0)
            return STATE_CHECK_REASONS[code - 1];
    }
    return problem;
}

static int restore(Instance* c, const State* s)
{
    char buffer[256];
    const char* problem = state_problem(s, buffer, sizeof buffer);
    if (problem != NULL) {
        say(c, ST_ERROR, "FMU state refused (%s); the instance is unchanged", problem);
        return ST_ERROR;
    }
    c->el = s->element;
    c->x_in = s->x_in;
    c->v_in = s->v_in;
    c->start_time = s->start_time;
    memcpy(c->par, s->par, sizeof c->par);
    memcpy(c->cbranch, s->cbranch, sizeof c->cbranch);
    return ST_OK;
}

/* ------------------------------------------------------------------ stepping */

static int core_exit_initialization(Instance* c)
{
    char buffer[512];
    const char* problem;
    if (c->phase != INITIALIZING) {
        say(c, ST_ERROR, FMI "ExitInitializationMode refused: not in initialization mode");
        return ST_ERROR;
    }
    problem = parameter_problem(c->par, c->cbranch, buffer, sizeof buffer);
    if (problem == NULL && !(isfinite(c->x_in) && isfinite(c->v_in))) {
        snprintf(buffer, sizeof buffer, "input x = %.17g, v = %.17g refused: the motion must be finite", c->x_in,
                 c->v_in);
        problem = buffer;
    }
    if (problem != NULL) {
        say(c, ST_ERROR, "initialization refused: %s", problem);
        return ST_ERROR;
    }
    hand_over(c);
    reset(&c->el);
    c->el.time = c->start_time;
    move_to(&c->el, c->x_in, c->v_in, c->el.time); /* from x = 0 to the first input, monotonically */
    c->initialized = 1;
    c->phase = STEPPING;
    return ST_OK;
}

/* the first output (force, stiffness, an energy) that is not a number to show at the inputs set last, or NULL */
static const Var* unshowable_output(Instance* c, double* value)
{
    int i;
    for (i = 0; i < N_VARS; i++) {
        const Var* var = &VARS[i];
        if (var->what != W_FORCE && var->what != W_STIFFNESS && var->what != W_ENERGY)
            continue;
        *value = real_value(c, var);
        if (!showable(var, *value))
            return var;
    }
    return NULL;
}

/* fmi2/3DoStep; the FMI layer checked the call sequence */
static int core_do_step(Instance* c, double t, double H)
{
    char buffer[512];
    const char* problem;
    const Var* overflowed;
    double value;
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
    problem = parameter_problem(c->par, c->cbranch, buffer, sizeof buffer);
    if (problem != NULL) {
        say(c, ST_DISCARD, "%s; steps are refused until it is set right", problem);
        return ST_DISCARD;
    }
    if (!(isfinite(c->x_in) && isfinite(c->v_in))) {
        say(c, ST_DISCARD, "input x = %.17g, v = %.17g refused: the motion must be finite; step not taken", c->x_in,
            c->v_in);
        return ST_DISCARD;
    }
    copy_element(&c->saved, &c->el);
    hand_over(c);
    /* the input sample belongs to the communication point: commit it (the master's clock only moves forward) */
    move_to(&c->el, c->x_in, c->v_in, t > c->el.time ? t : c->el.time);
    overflowed = unshowable_output(c, &value); /* no output is ever shown NaN or inf after an OK step */
    if (overflowed != NULL || !(isfinite(c->el.x) && isfinite(c->el.v))) {
        double time = c->el.time;
        copy_element(&c->el, &c->saved);
        say(c, ST_DISCARD, "the step to t = %.17g with x = %.17g, v = %.17g refused: %s would be %.17g, not finite "
            "(an overflow); the state is unchanged", time, c->x_in, c->v_in,
            overflowed != NULL ? overflowed->name : "the state", overflowed != NULL ? value : NAN);
        return ST_DISCARD;
    }
    c->last_step_failed = 0;
    return ST_OK;
}

static int core_check_float(Instance* c, const Var* var, unsigned vr, double value)
{
    if (var == NULL || !(var->what == W_X || var->what == W_V || var->what == W_PARAM || var->what == W_CBRANCH)) {
        say(c, ST_ERROR, FLOAT_SETTER " refused: value reference %u is not a Real input or parameter", vr);
        return ST_ERROR;
    }
    return ST_OK;
}

static void core_set_float(Instance* c, const Var* var, double value)
{
    int j;
    if (var->what == W_X)
        c->x_in = value;
    else if (var->what == W_V)
        c->v_in = value;
    else if (var->what == W_PARAM)
        c->par[var->index] = value;
    else
        for (j = 0; j < NB; j++)
            if (var->index < 0 || var->index == j)
                c->cbranch[j] = value;
}

static void core_set_stepper(Instance* c, const char* value) { (void)c; (void)value; }

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
