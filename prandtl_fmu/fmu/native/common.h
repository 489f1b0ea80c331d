/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* What the native FMU's element (element.h) and connector (connector.h) share: logging, the parameters'
 * rules (the library's magnitudes included, from scene.h), the variables' table, which values may be shown, the
 * checksum of a state. Glue only, no numerics. */
#ifndef PRANDTL_COMMON_H
#define PRANDTL_COMMON_H
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene.h"
#ifndef NETWORK /* the element's scene.h (a network's says 1) */
#define NETWORK 0
#endif
#define ELEMENT_CONNECTOR (CONNECTOR && !NETWORK) /* the element as a connector (connector.h) */

/* set by the stubs of numba's error path (stubs.c): a kernel raised */
extern __thread int prandtl_kernel_failed;

/* MAX_STEPS, SHORTEST_STEP, ADVANCE_BUDGET and the magnitudes of a coefficient: scene.h, from prandtl_fmu.scene */
#define STATE_MAGIC "PRANDTL-FMU-STATE"
#define STATE_VERSION 3 /* 2: the white noise's settings (issue 34); 3: the effects with memory (issue 35) */
/* the scratch of state_check (a memory-stack state and n elongations) */
#define STATE_SCRATCH (NB_ARR + NB)

#if !NETWORK /* the element's parameters (a network's are its scene's: network.h) */
enum { P_M, P_X0, P_V0, P_K0, P_K3, P_C, P_ALPHA, P_ALPHA_KINETIC, P_STRIBECK, P_BELT, N_PARAMS };
#endif
/* the phases of an instance, one bit each: a function is allowed in a mask of them (as in the Reference-FMUs) */
enum { INSTANTIATED = 1, INITIALIZING = 2, STEPPING = 4, TERMINATED = 8, INTERMEDIATE_UPDATE = 16 };
#define ANY_PHASE (INSTANTIATED | INITIALIZING | STEPPING | TERMINATED)
/* the FMI version's layer (fmi2.c, fmi3.c): hands a message to the host's logger (``instance`` is its Instance) */
typedef void (*Emit)(void* instance, int status, const char* category, const char* message);
/* the first fields of every kind's Instance: the host's (its environment and logger, which the FMI version's
 * layer calls: emit, handed over when the instance is made), the logging, the phase and whether the last step
 * failed */
#define INSTANCE_HEAD                                                                                          \
    char* name;                                                                                                \
    void* env;                                                                                                 \
    void* logger;                                                                                              \
    Emit emit;                                                                                                 \
    int logging, phase, last_step_failed
/* the first fields of every kind's State (state.h): the magic, the version and size, the scene's digest */
#define STATE_HEAD                                                                                             \
    char header[24];                                                                                           \
    uint32_t version, size;                                                                                    \
    char digest[65]
/* statuses: the same numbers in FMI 2.0 and 3.0 */
enum { ST_OK, ST_WARNING, ST_DISCARD, ST_ERROR, ST_FATAL };
/* ``field`` of ``from`` into ``to`` (a kind's SETTINGS, the element's checkpoint: any type, an array too) */
#define COPY_FIELD(to, from, field) memcpy(&(to)->field, &(from)->field, sizeof (to)->field)


/* ------------------------------------------------------------------ logging */

/* log a message: every status but OK reaches the logger (by the instance's emit), logging on or off, under a
 * declared category */
#define say(c, ...) say_to((c), (c)->emit, (c)->logger, (c)->logging, __VA_ARGS__)

static void say_to(void* instance, Emit emitter, void* logger, int logging, int status, const char* format, ...)
{
    static const char* categories[] = {"logAll", "logStatusWarning", "logStatusDiscard", "logStatusError",
                                       "logStatusFatal", "logAll"};
    char text[1024], message[2048];
    size_t i, j;
    va_list args;
    if (logger == NULL || (status == ST_OK && !logging))
        return;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    /* the message is the logger's format: every % doubled (a host that formats it prints the text, one that
       does not still gets the words) */
    for (i = 0, j = 0; text[i] && j + 2 < sizeof message; i++) {
        if (text[i] == '%')
            message[j++] = '%';
        message[j++] = text[i];
    }
    message[j] = 0;
    emitter(instance, status, categories[status], message);
}

#if !NETWORK
static const char* PARAM_NAMES[N_PARAMS] = {"m", "x0", "v0", "k0", "k3", "c", "alpha", "alpha_kinetic",
                                            "stribeck_velocity", "belt_velocity"};

#endif

/* Python's repr of a double (the shortest digits that read back, a ".0" on an integral value, an exponent below
 * 1e-4 and from 1e16 on): what the PythonFMU FMU's messages show */
static const char* python_repr(double value, char* buffer, size_t size)
{
    char digits[40];
    int precision = 1, exponent;
    if (!isfinite(value) || value == 0.0) {
        snprintf(buffer, size, "%s", isnan(value) ? "nan" : isinf(value) ? (value > 0 ? "inf" : "-inf")
                                     : signbit(value) ? "-0.0" : "0.0");
        return buffer;
    }
    do
        snprintf(digits, sizeof digits, "%.*e", precision - 1, value);
    while (strtod(digits, NULL) != value && ++precision <= 17);
    exponent = atoi(strchr(digits, 'e') + 1);
    if (exponent < -4 || exponent >= 16)
        snprintf(buffer, size, "%s", digits); /* d.ddde+XX, as Python's (two exponent digits at least) */
    else if (exponent >= precision - 1)
        snprintf(buffer, size, "%.1f", value); /* an integral value: exact in fixed notation */
    else
        snprintf(buffer, size, "%.*f", precision - 1 - exponent, value);
    return buffer;
}

/* scene.magnitude_problem: a finite nonzero coefficient's |value| lies in [SMALLEST_MAGNITUDE, LARGEST_MAGNITUDE];
   a value's (is_value: scene.VALUES) is at most LARGEST_MAGNITUDE */
static const char* magnitude_problem(const char* name, double value, int is_value, char* buffer, size_t size)
{
    int coefficient_out = !is_value && value != 0
                          && !(fabs(value) >= SMALLEST_MAGNITUDE && fabs(value) <= LARGEST_MAGNITUDE);
    if (coefficient_out || (is_value && !(fabs(value) <= LARGEST_MAGNITUDE))) {
        char shortest[32];
        int digits = 1;
        do /* the shortest that reads back as the value: Python's repr, as the library's message writes it */
            snprintf(shortest, sizeof shortest, "%.*g", digits, value);
        while (strtod(shortest, NULL) != value && ++digits <= 17);
        if (is_value)
            snprintf(buffer, size, "parameter %s: |%s| is above %g: no physical magnitude, its products in a step "
                     "would overflow", name, shortest, LARGEST_MAGNITUDE);
        else
            snprintf(buffer, size, "parameter %s: |%s| is outside [%g, %g] (or 0): no physical magnitude, its "
                     "products in a step would underflow or overflow", name, shortest, SMALLEST_MAGNITUDE,
                     LARGEST_MAGNITUDE);
        return buffer;
    }
    return NULL;
}

#if !NETWORK
/* scene.coefficient_problem and the rule alpha_kinetic <= alpha (scene.with_coefficients): the message in the
 * library's words (its values as Python's repr), or NULL */
static const char* parameter_problem(const double* par, const double* cbranch, char* buffer, size_t size)
{
    char a[40], b[40];
    int i;
    for (i = 0; i < N_PARAMS; i++) {
        double value = par[i];
        if (!P_PRESENT[i]) {
            if (!isfinite(value)) { /* never read by a kernel, but a state must hold no such number */
                snprintf(buffer, size, "parameter %s: must be finite, got %s", PARAM_NAMES[i],
                         python_repr(value, a, sizeof a));
                return buffer;
            }
            continue;
        }
        if (!isfinite(value)) {
            snprintf(buffer, size, "parameter %s: must be finite, got %s", PARAM_NAMES[i],
                         python_repr(value, a, sizeof a));
            return buffer;
        }
        if (magnitude_problem(PARAM_NAMES[i], value, P_VALUE[i], buffer, size))
            return buffer;
        if (P_RULE[i] == 1 && !(value > 0)) {
            snprintf(buffer, size, "parameter %s: must be > 0, got %s", PARAM_NAMES[i],
                     python_repr(value, a, sizeof a));
            return buffer;
        }
        if (P_RULE[i] == 2 && value < 0) {
            snprintf(buffer, size, "parameter %s: must be >= 0, got %s", PARAM_NAMES[i],
                     python_repr(value, a, sizeof a));
            return buffer;
        }
    }
    for (i = 0; i < (HAS_SERIES ? NB : 0); i++) {
        char name[32];
        snprintf(name, sizeof name, "c_branch[%d]", i + 1);
        if (!isfinite(cbranch[i])) {
            snprintf(buffer, size, "parameter %s: must be finite, got %s", name, python_repr(cbranch[i], a, sizeof a));
            return buffer;
        }
        if (magnitude_problem(name, cbranch[i], 0, buffer, size))
            return buffer;
        if (!(cbranch[i] > 0)) {
            snprintf(buffer, size, "parameter %s: must be > 0, got %s", name, python_repr(cbranch[i], a, sizeof a));
            return buffer;
        }
    }
    if (HAS_STRIBECK && par[P_ALPHA_KINETIC] > par[P_ALPHA]) {
        snprintf(buffer, size, "parameter alpha_kinetic: alpha_kinetic must be <= alpha, got alpha_kinetic = %s and "
                 "alpha = %s", python_repr(par[P_ALPHA_KINETIC], a, sizeof a), python_repr(par[P_ALPHA], b, sizeof b));
        return buffer;
    }
    if (!CONNECTOR && !HAS_MASS && HAS_DAMPER && !(par[P_C] > 0)) {
        snprintf(buffer, size, "parameter c = %.17g: the native runtime keeps the dashpot of a massless element "
                 "(c > 0)", par[P_C]);
        return buffer;
    }
    return NULL;
}


/* the length of the branches' state in use (stack.used): the memory stack's header and pieces, or n elongations */
static size_t branch_state_used(const double* u)
{
    size_t used;
    if (!STACK)
        return NB;
    used = STACK_HEADER + STACK_ROW * (size_t)(u[0] > 0 ? u[0] : 0); /* u[0]: the count of pieces */
    return used < NB_ARR ? used : NB_ARR;
}

#endif

/* the variable of value reference ``vr`` and ``type``, or NULL: VARS holds the value references of the FMI version
 * built, in order from VR_FIRST on, without a gap but the network's holes (vr UINT32_MAX) */
static const Var* find(unsigned vr, int type)
{
    unsigned index = vr - (unsigned)VR_FIRST; /* (below VR_FIRST: wraps beyond N_VARS) */
    if (index < (unsigned)N_VARS && VARS[index].vr == vr && VARS[index].type == type)
        return &VARS[index];
    return NULL;
}

/* ------------------------------------------------------------------ the clock (the element's, a network's) */

/* time = origin + steps * grid (grid 0: none yet; driver.Element's _origin, _steps, _grid) */
typedef struct { double origin, grid; int64_t steps; } Clock;

static double clock_time(const Clock* k) { return k->steps ? k->origin + (double)k->steps * k->grid : k->origin; }

/* Element.time = value: within 1e-9 of the grid's step and of the time itself, the same instant (the grid goes
 * on) */
static void clock_set(Clock* k, double value)
{
    if (k->grid != 0.0 && fabs(value - clock_time(k)) <= 1e-9 * fmin(k->grid, fabs(value)))
        return;
    k->origin = value;
    k->steps = 0;
}

/* stepping.split_duration: whole steps of h, then a last shorter one; within 1e-9 h of whole steps, whole steps
 * only, and a remainder below 1e-9 h and 1e-9 |end| after them (a duration below it too: no step at all) is a
 * master's clock's rounding, dropped (``end``: the clock's time after the duration; a step far longer than the
 * duration is cut to it) */
static void split_duration(double duration, double h, double end, double* whole, double* rest)
{
    double ratio = duration / h, nearest = nearbyint(ratio);
    if (nearest >= 1 && fabs(ratio - nearest) <= 1e-9) {
        *whole = nearest;
        *rest = 0.0;
        return;
    }
    *whole = floor(ratio);
    *rest = duration - *whole * h;
    if (!(*rest >= 1e-9 * fmin(h, fabs(end))))
        *rest = 0.0;
}

/* Element.advance's (NetworkElement.advance's) checks of a duration in steps of h, in the library's words: NULL
 * and its split (whole, rest; (0, 0): no step at all), or why not */
static const char* plan_advance(double duration, double h, double end, double* whole, double* rest, char* buffer,
                                size_t size)
{
    if (duration < SHORTEST_STEP) {
        snprintf(buffer, size, NETWORK ? "the duration is shorter than %g s" : "the duration is shorter than %g s (a "
                 "step's square underflows)", SHORTEST_STEP);
        return buffer;
    }
    if (!(duration / h < MAX_STEPS)) {
        if (NETWORK)
            snprintf(buffer, size, "the duration is more than 2^53 steps of h = %.17g s", h);
        else
            snprintf(buffer, size, "the duration is more than %.17g internal steps (2^53): advance by shorter "
                     "durations or with a larger step", MAX_STEPS);
        return buffer;
    }
    split_duration(duration, h, end, whole, rest);
    if (*whole + (*rest > 0) > ADVANCE_BUDGET) { /* never run for days */
        snprintf(buffer, size, "an advance of %.17g s takes %.4g steps of h = %.17g s, more than the budget of %.0e "
                 "steps of one advance: advance by shorter durations%s or with a larger step", duration,
                 *whole + (*rest > 0), h, ADVANCE_BUDGET, NETWORK ? "" : " (communication steps)");
        return buffer;
    }
    return NULL;
}

/* the clock after ``whole`` steps of h and a last one of ``rest`` from where it stands on the grid of h (a new
 * step: the grid starts again at the time; a short last step: again where it ends) */
static void clock_regrid(Clock* k, double h)
{
    if (k->grid != h) {
        k->origin = clock_time(k);
        k->steps = 0;
        k->grid = h;
    }
}

static void clock_advanced(Clock* k, double whole, double rest, double h)
{
    if (rest > 0) {
        k->origin = k->origin + (double)(k->steps + (int64_t)whole) * h + rest;
        k->steps = 0;
    } else {
        k->steps += (int64_t)whole;
    }
}

/* whether a clock holds a finite time (origin, steps and grid) */
static int clock_valid(const Clock* k)
{
    return isfinite(k->origin) && isfinite(k->grid) && k->grid >= 0 && k->steps >= 0 &&
           (double)k->steps <= MAX_STEPS && (k->grid > 0 || k->steps == 0) && isfinite(clock_time(k));
}

/* whether an output's value may be shown: finite (every stepper books its energy account, as driver.Element) */
static int showable(const Var* var, double value) { (void)var; return isfinite(value); }

/* FNV-1a over ``size`` bytes, from ``hash`` (FNV_BASIS: from the start) */
#define FNV_BASIS 1469598103934665603ULL
static uint64_t fnv1a(uint64_t hash, const unsigned char* bytes, size_t size)
{
    size_t i;
    for (i = 0; i < size; i++) {
        hash ^= bytes[i];
        hash *= 1099511628211ULL;
    }
    return hash;
}

#if !NETWORK
/* ------------------------------------------------------------------ the effects with memory (memory/)
 *
 * The rules of their parameters and of a saved memory, on plain arrays: ``mp`` the parameters (the names of
 * kernels.memory_layout, MEM_NAMES), ``mem`` the state (MEM_FIXED values, then the delay's buffer of nd). The
 * element's and the connector's (the element's own rules are under !CONNECTOR). */

/* the delay's buffer for the tau in mp (memory.delay.size: HEAD + ceil(tau / grid) + 4; 0 without a delay), or -1
 * beyond DELAY_BOUND values */
static int64_t delay_size(const double* mp)
{
    double ratio;
    if (!HAS_DELAY)
        return 0;
    ratio = ceil(mp[1] / DELAY_GRID);
    if (!(ratio <= DELAY_BOUND))
        return -1;
    return DELAY_HEAD + (int64_t)ratio + 4;
}

/* why the memory's parameters mp cannot be used, or NULL: each one's rule (scene.coefficient_problem), then
 * scene._check_memory_rules (the element's: a monotone step; both: Dahl's exponent; the native runtime's: a buffer
 * within DELAY_BOUND values) */
static const char* memory_problem(const double* mp, char* buffer, size_t size)
{
    char a[40], b[40];
    int i;
    for (i = 0; i < N_MEMORY_PARAMS; i++) {
        double value = mp[i];
        if (!isfinite(value)) { /* (the values in the library's words: Python's repr) */
            snprintf(buffer, size, "parameter %s: must be finite, got %s", MEM_NAMES[i],
                     python_repr(value, a, sizeof a));
            return buffer;
        }
        if (magnitude_problem(MEM_NAMES[i], value, 0, buffer, size))
            return buffer;
        if ((MEM_RULE[i] == 1 && !(value > 0)) || (MEM_RULE[i] == 2 && value < 0)) {
            snprintf(buffer, size, "parameter %s: must be %s 0, got %s", MEM_NAMES[i], MEM_RULE[i] == 1 ? ">" : ">=",
                     python_repr(value, a, sizeof a));
            return buffer;
        }
    }
    if (HAS_DELAY && !CONNECTOR && mp[0] < 0 && (QUASI_STATIC || mp[1] < DELAY_GRID)) { /* (the connector solves
                                                                                         nothing: its motion is given) */
        char why[128];
        const char* fix = QUASI_STATIC ? "add [mass] or a [damper]"
                                       : "a [solver] step no longer than tau, or a longer tau";
        if (QUASI_STATIC)
            snprintf(why, sizeof why, "on a massless element without a dashpot");
        else
            snprintf(why, sizeof why, "with tau = %s s below the step %s s", python_repr(mp[1], a, sizeof a),
                     python_repr(DELAY_GRID, b, sizeof b));
        snprintf(buffer, size, "parameter delay_gain: a negative gain %s makes the implicit equation of a step "
                 "non-monotone (no unique solution): %s", why, fix);
        return buffer;
    }
    if (HAS_DAHL && mp[MEM_DAHL_AT + 2] > DAHL_MAX_EXPONENT) {
        snprintf(buffer, size, "parameter dahl_exponent: must be <= 100 (sigma 2^exponent, the slope at a reversal, "
                 "would overflow), got %s", python_repr(mp[MEM_DAHL_AT + 2], a, sizeof a));
        return buffer;
    }
    for (i = 0; i < (QUASI_STATIC ? NH : 0); i++)
        if (mp[MEM_HISTORY_AT + i] < 0) {
            snprintf(buffer, size, "parameter history_weight[%d]: a negative weight on a massless element without a "
                     "dashpot makes the implicit equation of a step non-monotone: add [mass] or a [damper]", i + 1);
            return buffer;
        }
    if (delay_size(mp) < 0) {
        snprintf(buffer, size, "parameter delay_tau = %s: tau / step = %.4g values in the delay's buffer, more than "
                 "the native runtime's bound of %.0f (%.0f MiB): a shorter tau, or a longer [solver] step in the scene",
                 python_repr(mp[1], a, sizeof a), mp[1] / DELAY_GRID, DELAY_BOUND, DELAY_BOUND * 8 / 1048576);
        return buffer;
    }
    return NULL;
}

/* memory.delay.time_problem: why a move from ``start`` to ``end`` (s) cannot be carried by the delay's buffer in
 * ``mem`` (its grid counts from t = 0 below 2^52 steps, and cannot go back before what it recorded), or NULL */
static const char* delay_time_problem(const double* mem, double start, double end, char* buffer, size_t size)
{
    char a[40], b[40];
    double recorded;
    if (!HAS_DELAY)
        return NULL;
    recorded = mem[MEM_FIXED];
    if (start < 0) {
        snprintf(buffer, size, "a [delay] counts its history from t = 0: the time %s s is negative",
                 python_repr(start, a, sizeof a));
        return buffer;
    }
    if (end / DELAY_GRID >= 4503599627370496.0) {
        snprintf(buffer, size, "a [delay]'s buffer counts time in steps of %s s below 2^52: t = %s s is beyond (the "
                 "clock no longer resolves its grid)", python_repr(DELAY_GRID, a, sizeof a),
                 python_repr(end, b, sizeof b));
        return buffer;
    }
    if (start < (recorded - 1) * DELAY_GRID) {
        snprintf(buffer, size, "the time goes back to %s s, before what the [delay]'s buffer recorded (up to %s s): "
                 "its past would be wrong", python_repr(start, a, sizeof a),
                 python_repr(recorded * DELAY_GRID, b, sizeof b));
        return buffer;
    }
    return NULL;
}

/* why a saved memory (``mem_len`` values ``mem``, a delay's buffer of ``nd``) cannot be restored under the
 * parameters mp at ``time``, or NULL: memory.check_memory_state's rules (the buffer's size for its tau, its grid
 * index, the Dahl force within F_c) and numbers only (a NaN only where a fresh memory holds one, MEM_MARKERS) */
static const char* memory_values_problem(const double* mp, const double* mem, int64_t nd, int64_t mem_len,
                                         double time, char* buffer, size_t size)
{
    int64_t i, expected_nd;
    if (!HAS_MEMORY)
        return mem_len == 0 && nd == 0 ? NULL : "it holds the memory of effects this element has not";
    expected_nd = delay_size(mp);
    if (nd != expected_nd || mem_len != MEM_FIXED + expected_nd) {
        snprintf(buffer, size, "its memory holds %.0f values, the element's at tau = %.17g s holds %.0f (a delay "
                 "buffer of %.0f)", (double)mem_len, HAS_DELAY ? mp[1] : 0.0, (double)(MEM_FIXED + expected_nd),
                 (double)expected_nd);
        return buffer;
    }
    for (i = 0; i < mem_len; i++) {
        int marker = 0, j;
        for (j = 0; j < N_MEM_MARKERS; j++)
            marker |= MEM_MARKERS[j] == i && isnan(mem[i]);
        if (!isfinite(mem[i]) && !marker)
            return "its memory holds a non-finite value";
    }
    if (HAS_DELAY) { /* memory.delay.restore: the last grid point recorded, to a rounding of the clock */
        double last = mem[MEM_FIXED], expected = fmax(floor(time / DELAY_GRID), 0.0);
        if (!(last >= 0 && last == floor(last) && last <= MAX_STEPS && fabs(last - expected) <= 1)) {
            char a[40], b[40];
            snprintf(buffer, size, "it has a delay buffer whose grid index is %s, at t = %s s it is %.0f",
                     python_repr(last, a, sizeof a), python_repr(time, b, sizeof b), expected);
            return buffer;
        }
    }
    if (HAS_DAHL && !(fabs(mem[MEM_DAHL_STATE]) <= mp[MEM_DAHL_AT + 1])) {
        char a[40], b[40];
        snprintf(buffer, size, "it has a Dahl force %s beyond its level F_c = %s", python_repr(mem[MEM_DAHL_STATE],
                 a, sizeof a), python_repr(mp[MEM_DAHL_AT + 1], b, sizeof b));
        return buffer;
    }
    return NULL;
}

/* memory.restore_memory: the cached values a restored memory recomputes (the history's coefficients of a step,
 * marked NaN as fresh: a function of the step alone, they never change a result) */
static void forget_memory_cache(double* mem)
{
    int j;
    for (j = 0; j < N_MEM_MARKERS; j++)
        mem[MEM_MARKERS[j]] = NAN;
}
#endif

#if NETWORK || !CONNECTOR /* the element and the network take a load; the element connector a motion */
/* ------------------------------------------------------------------ the white noise (loads.WhiteNoise) */

/* a white noise sigma xi(t) on the force: its intensity sigma (N sqrt(s); 0: none), the seed of its Brownian path
 * (an FMI Integer, 32 bits: 0 <= seed < 2^31) and the Brownian tree's time unit (s). What the master set, and what
 * was handed over to the kernels; the path is a function of (seed, time) alone, drawn by the kernels (noise.py) */
typedef struct { double sigma; int64_t seed; double unit; } Noise;
static const Noise SCENE_NOISE = NOISE_SCENE; /* the start values: the scene's [load] noise, or none */

/* why the noise's settings break a rule, or NULL: NoiseParameters._hand_over_noise's checks, in its order (the
 * seed an FMU takes, NOISE_SEED_LIMIT, then loads.white_noise: the intensity, the seed, the unit), and its words
 * (scene.h: *_WORDS, taken from the PythonFMU's messages at build time) */
static const char* noise_problem(const Noise* n, char* buffer, size_t size)
{
    char shown[40];
    if (!(n->seed >= 0 && (double)n->seed < NOISE_SEED_LIMIT)) {
        snprintf(buffer, size, "parameter noise_seed = %lld: %s", (long long)n->seed, NOISE_SEED_WORDS);
        return buffer;
    }
    if (!(isfinite(n->sigma) && n->sigma >= 0)) {
        snprintf(buffer, size, "parameter noise_intensity = %s: %s", python_repr(n->sigma, shown, sizeof shown),
                 NOISE_INTENSITY_WORDS);
        return buffer;
    }
    if (!(isfinite(n->unit) && n->unit > 0)) {
        snprintf(buffer, size, "parameter noise_unit = %s: %s", python_repr(n->unit, shown, sizeof shown),
                 NOISE_UNIT_WORDS);
        return buffer;
    }
    return NULL;
}

/* why the noise's unit is too coarse for the internal step, or NULL: loads.noise_problem's first rule and words
 * (the Brownian tree resolves 2^-40 of its unit; below, the path would be rounded away), as Element.set_noise and
 * set_step refuse it. (Its second rule, the tree's end at 2^52 units, fails the step in the kernel.) */
static const char* noise_step_problem(const Noise* n, double step, char* buffer, size_t size)
{
    char unit[40], shown[40];
    if (n->sigma == 0.0 || step / n->unit >= 0x1p-40)
        return NULL;
    snprintf(buffer, size, "parameter noise_unit = %s s is too coarse for the step %s s: the Brownian tree resolves "
             "2^-40 of its unit; take noise_unit <= %.3g s (the coarsest step of a study is the advice)",
             python_repr(n->unit, unit, sizeof unit), python_repr(step, shown, sizeof shown), step / 0x1p-40);
    return buffer;
}

/* the load of an advance: the force held, or the scene's [load] plus it (loads.held, loads.plus), and the white
 * noise (loads.with_white_noise: sigma 0, none; ``cache``: the Brownian tree's, any content valid) */
typedef struct {
    int64_t kind;
    double lk[3];
    const double *t, *f;
    int64_t n;
    Noise noise;
    int64_t* cache;
    double origin[1]; /* a polynomial's (loads.polynomial): its table of one time, t pointing here */
} Load;
static const double NO_TABLE[1] = {0.0};

static Load load_of(double force, int scene_load, const Noise* noise, int64_t* cache)
{
    Load l;
    if (scene_load) {
        l.kind = LOAD_KIND;
        l.lk[0] = LOAD_LK[0] + force;
        l.lk[1] = LOAD_LK[1];
        l.lk[2] = LOAD_LK[2];
        l.t = LOAD_T;
        l.f = LOAD_F;
        l.n = LOAD_N;
    } else {
        l.kind = 0;
        l.lk[0] = force;
        l.lk[1] = 0.0;
        l.lk[2] = 0.0;
        l.t = NO_TABLE;
        l.f = NO_TABLE;
        l.n = 1;
    }
    l.noise.sigma = noise != NULL ? noise->sigma : 0.0;
    l.noise.seed = noise != NULL ? noise->seed : 0;
    l.noise.unit = noise != NULL ? noise->unit : 1.0;
    l.cache = cache;
    l.origin[0] = 0.0;
    return l;
}
#endif

#endif
