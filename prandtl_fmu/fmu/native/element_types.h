/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The element's types, what the layers below its calls (element.h) read of it: what a step changes (Element), an
 * FMU state's fixed part (State), the instance (Instance), the checkpoint the instance holds (Checkpoint), and the
 * macros the shared headers read: the memory's arrays (core.h), what the master set, kept in an FMU state (SETTINGS:
 * state.h), the variables a master sets (SETTABLE) and the outputs that must be numbers after a step (STEP_OUTPUT).
 * It includes common.h alone. */
#ifndef PRANDTL_ELEMENT_TYPES_H
#define PRANDTL_ELEMENT_TYPES_H
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
    Clock clock;          /* time = origin + steps * grid (grid 0: none yet) */
    double force;         /* the load of the last advance: force, plus the scene's [load] with scene_load */
    int scene_load;
    int row_stale;        /* erow is not the state's: an advance moved it (the row is computed when read: fresh_row) */
    double mp[N_MEMP];    /* the effects with memory: their parameters in use (kernels.memory_layout) */
    int64_t nd;           /* the delay's buffer: its values (memory.delay.size at the tau in use; 0: no delay) */
    int64_t mem_len;      /* the memory's state: MEM_FIXED + nd values */
    double* mem;          /* ... on the heap (NULL in a state blob: its values follow the blob's fixed part) */
} Element;

typedef struct {
    STATE_HEAD;
    Element element;
    double F, step, start_time, par[N_PARAMS], cbranch[NB_CS];
    int scene_load, stepper_valid, initialized;
    char stepper[32];
    double mpar[N_MEMP]; /* the memory's parameters the master set */
    double dF[2];        /* F's derivatives the master set (fmi2SetRealInputDerivatives) */
    Noise noise_set;   /* the white noise's settings (nothing drawn: the path is a function of seed and time) */
    uint64_t checksum;   /* of the fixed part and the memory's state, element.mem_len values after it */
} State;
/* the memory's arrays (core.h): the element's and the checkpoint's */
#define MEMORY_ARRAYS(c) {&(c)->el.mem, &(c)->saved_mem}
#define MEMORY_TAU(c) ((c)->el.mp[1])
#define MEMORY_SIZED(c, length) ((c)->el.mem_len = (length))
/* a state set: its energy row is computed again when read, never taken from the blob (state.h: restore_checked) */
#define FORGET_DERIVED(c) ((c)->el.row_stale = 1)
/* the outputs that must be numbers after a step (core.h: unshowable_output) */
#define STEP_OUTPUT(what) ((what) == W_X || (what) == W_V || (what) == W_REACTION || (what) == W_STIFFNESS || \
                           (what) == W_ENERGY)
#define KIND_INTEGERS 0
/* what the master set, kept in an FMU state (state.h: capture, restore_checked) */
#define SETTINGS(to, from)                                                                                     \
    COPY_FIELD(to, from, F), COPY_FIELD(to, from, step), COPY_FIELD(to, from, start_time), COPY_FIELD(to, from, par), \
        COPY_FIELD(to, from, cbranch), COPY_FIELD(to, from, scene_load), COPY_FIELD(to, from, stepper_valid),   \
        COPY_FIELD(to, from, stepper), COPY_FIELD(to, from, noise_set), COPY_FIELD(to, from, mpar),           \
        COPY_FIELD(to, from, dF)
#define SETTABLE(what) ((what) == W_F || (what) == W_PARAM || (what) == W_CBRANCH || (what) == W_STEP || \
                        (what) == W_NOISE_INTENSITY || (what) == W_NOISE_UNIT || (what) == W_MEMORY)

/* what an advance changes (driver.Element.checkpoint): a step that fails is rolled back from it; the branches'
 * state is copied in its part in use only (the memory stack's pieces), into the instance's buffer */
typedef struct {
    double x, v, account[4], out[3], erow[6], force;
    Clock clock;
    int scene_load, row_stale;
    size_t used;
} Checkpoint;
#define SAVED_U (NB_ARR > NB_PLAY ? NB_ARR : NB_PLAY)

typedef struct {
    INSTANCE_HEAD;
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
    double dF[2];        /* F' and F'' the master set for the next doStep (fmi2SetRealInputDerivatives; 0: held) */
    /* FMI 3.0 intermediate update: the master's callback (NULL: none), asked at every internal step for F (fmi3.c) */
    void (*ask_inputs)(void* instance, double time, int first);
    void (*intermediate_update)(void); /* (the callback itself, of FMI 3.0's type: fmi3.c) */
    double* saved_mem;   /* the checkpoint's memory state (el.mem_len values) */
    int memory_failed;   /* the memory's state could not be allocated at instantiation (the instance is refused) */
    double limits[3];    /* |x|, |v|, |an account's entry| below which every output is surely a number ... */
    int limit_play;      /* ... on the branches' kernel they were given for (el.play): note_limits */
} Instance;

/* ------------------------------------------------------------------ the element */

static double element_time(const Element* e) { return clock_time(&e->clock); }

#endif
