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
enum { INSTANTIATED = 1, INITIALIZING = 2, STEPPING = 4, TERMINATED = 8 };
#define ANY_PHASE (INSTANTIATED | INITIALIZING | STEPPING | TERMINATED)
/* statuses: the same numbers in FMI 2.0 and 3.0 */
enum { ST_OK, ST_WARNING, ST_DISCARD, ST_ERROR, ST_FATAL };


/* ------------------------------------------------------------------ logging */

/* the FMI version's layer: hands a message to the host's logger (``instance`` is its Instance) */
static void emit(void* instance, int status, const char* category, const char* message);

/* log a message: every status but OK reaches the logger, logging on or off, under a declared category */
#define say(c, ...) say_to((c), (c)->logger, (c)->logging, __VA_ARGS__)

static void say_to(void* instance, void* logger, int logging, int status, const char* format, ...)
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
    emit(instance, status, categories[status], message);
}

#if !NETWORK
static const char* PARAM_NAMES[N_PARAMS] = {"m", "x0", "v0", "k0", "k3", "c", "alpha", "alpha_kinetic",
                                            "stribeck_velocity", "belt_velocity"};

#endif

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
/* scene.coefficient_problem and the rule alpha_kinetic <= alpha: the message, or NULL */
static const char* parameter_problem(const double* par, const double* cbranch, char* buffer, size_t size)
{
    int i;
    for (i = 0; i < N_PARAMS; i++) {
        double value = par[i];
        if (!P_PRESENT[i]) {
            if (!isfinite(value)) { /* never read by a kernel, but a state must hold no such number */
                snprintf(buffer, size, "parameter %s: must be finite, got %.17g", PARAM_NAMES[i], value);
                return buffer;
            }
            continue;
        }
        if (!isfinite(value)) {
            snprintf(buffer, size, "parameter %s: must be finite, got %.17g", PARAM_NAMES[i], value);
            return buffer;
        }
        if (magnitude_problem(PARAM_NAMES[i], value, P_VALUE[i], buffer, size))
            return buffer;
        if (P_RULE[i] == 1 && !(value > 0)) {
            snprintf(buffer, size, "parameter %s: must be > 0, got %.17g", PARAM_NAMES[i], value);
            return buffer;
        }
        if (P_RULE[i] == 2 && value < 0) {
            snprintf(buffer, size, "parameter %s: must be >= 0, got %.17g", PARAM_NAMES[i], value);
            return buffer;
        }
    }
    for (i = 0; i < (HAS_SERIES ? NB : 0); i++) {
        char name[32];
        snprintf(name, sizeof name, "c_branch[%d]", i + 1);
        if (!isfinite(cbranch[i])) {
            snprintf(buffer, size, "parameter %s: must be finite, got %.17g", name, cbranch[i]);
            return buffer;
        }
        if (magnitude_problem(name, cbranch[i], 0, buffer, size))
            return buffer;
        if (!(cbranch[i] > 0)) {
            snprintf(buffer, size, "parameter %s: must be > 0, got %.17g", name, cbranch[i]);
            return buffer;
        }
    }
    if (HAS_STRIBECK && par[P_ALPHA_KINETIC] > par[P_ALPHA]) {
        snprintf(buffer, size, "parameter alpha_kinetic = %.17g: must be <= alpha = %.17g",
                 par[P_ALPHA_KINETIC], par[P_ALPHA]);
        return buffer;
    }
    if (!CONNECTOR && !HAS_MASS && HAS_DAMPER && !(par[P_C] > 0)) {
        snprintf(buffer, size, "parameter c = %.17g: the native runtime keeps the dashpot of a massless element "
                 "(c > 0)", par[P_C]);
        return buffer;
    }
    return NULL;
}


static const Var* find(unsigned vr, int type)
{
    int i;
    for (i = 0; i < N_VARS; i++)
        if (VARS[i].vr == vr && VARS[i].type == type)
            return &VARS[i];
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

/* whether an output's value may be shown: finite (every stepper books its energy account, as driver.Element) */
static int showable(const Var* var, double value) { (void)var; return isfinite(value); }

static uint64_t fnv1a(const unsigned char* bytes, size_t size)
{
    uint64_t hash = 1469598103934665603ULL;
    size_t i;
    for (i = 0; i < size; i++) {
        hash ^= bytes[i];
        hash *= 1099511628211ULL;
    }
    return hash;
}

/* the head of a state blob (the first fields of the element's and the connector's State) */
#define FILL_HEAD(s)                                                        \
    do {                                                                    \
        snprintf((s)->header, sizeof (s)->header, "%s", STATE_MAGIC);       \
        (s)->version = STATE_VERSION;                                       \
        (s)->size = (uint32_t)sizeof *(s);                                  \
        snprintf((s)->digest, sizeof (s)->digest, "%s", DIGEST);            \
    } while (0)

/* what every state is checked for first: the magic, the version and size, the scene's digest, the checksum */
static const char* head_problem(const char* header, uint32_t version, uint32_t size, size_t expected,
                                const char* digest, uint64_t checksum, uint64_t computed)
{
    if (memcmp(header, STATE_MAGIC, sizeof STATE_MAGIC) != 0)
        return "not a serialized state of a prandtl_fmu native FMU";
    if (version != STATE_VERSION || size != expected)
        return "a state of another version of the native runtime";
    if (strncmp(digest, DIGEST, 65) != 0)
        return "a state of another scene (its digest differs)";
    if (checksum != computed)
        return "its checksum does not match: the state was altered";
    return NULL;
}

#if NETWORK || !CONNECTOR /* the element and the network take a load; the element connector a motion */
/* ------------------------------------------------------------------ the white noise (loads.WhiteNoise) */

/* a white noise sigma xi(t) on the force: its intensity sigma (N sqrt(s); 0: none), the seed of its Brownian path
 * (an FMI Integer, 32 bits: 0 <= seed < 2^31) and the Brownian tree's time unit (s). What the master set, and what
 * was handed over to the kernels; the path is a function of (seed, time) alone, drawn by the kernels (noise.py) */
typedef struct { double sigma; int64_t seed; double unit; } Noise;
static const Noise SCENE_NOISE = NOISE_SCENE; /* the start values: the scene's [load] noise, or none */

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
    return l;
}
#endif

#endif
