/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The network's types, what the layers below its calls (network.h) read of it: the network in use and its state
 * (Element), a step's workspace the instance holds (Work), an FMU state's fixed part (State), the instance
 * (Instance), and the macros the shared headers read: what the master set, kept in an FMU state (SETTINGS: state.h),
 * the variables a master sets (SETTABLE) and the outputs that must be numbers after a step (STEP_OUTPUT). It
 * includes common.h alone. */
#ifndef PRANDTL_NETWORK_TYPES_H
#define PRANDTL_NETWORK_TYPES_H
#include "common.h"

/* the network in use and its state (driver.NetworkElement's model, x, v, u, piece, account, dissipated, ...) */
typedef struct {
    double mass[NN], coef[3 * NE_ARR]; /* the coefficients in use: (a, eta, c) per element */
    int stepper;                        /* index into STEPPER_NAMES */
    double h;
    double x[NN], v[NN], u[NE_ARR];
    int64_t piece[NE_ARR];
    double account[3];                  /* the work of the load, dissipated by sliders, by dashpots */
    double dissipated[NE_ARR], reaction, initial_energy;
    Clock clock;                        /* time = origin + steps * grid (grid 0: none yet) */
    double force;        /* the load of the last advance (plus the scene's [load] with scene_load); CONNECTOR: the
                            force of the elements on the load's node (NetworkConnector.force) */
    int scene_load;
} Element;

/* the workspace of a step (kernels.workspace's arrays): scratch, not state */
typedef struct {
    double d[NN], grad[NN], p[NN], term[NE_ARR], subtree[NN + 1], scale[NN];
    int64_t parent[NN + 1], cluster[NN + 1], queue[NN + 1], degree[NN + 1], links[NN + 1];
    double out[2 * NN + 2];
} Work;

typedef struct {
    STATE_HEAD;
    Element element;
    double F, x_in, v_in, step, start_time, time, par[N_PARAMS];
    int scene_load, stepper_valid, initialized;
    char stepper[32];
    Noise noise_set;   /* the white noise's settings (nothing drawn: the path is a function of seed and time) */
    uint64_t checksum;
} State;

typedef struct {
    INSTANCE_HEAD;
    Element el;
    /* what the master set */
    double F, x_in, v_in, step, start_time, par[N_PARAMS];
    double time;       /* CONNECTOR: the communication point, the time of the inputs set now */
    int scene_load, initialized;
    char stepper[32];
    int stepper_valid; /* the string fitted in the buffer */
    Noise noise_set;   /* noise_intensity, noise_seed, noise_unit (the element; the connector has none) */
    int handed;        /* the settings were handed over and nothing changed since */
    Noise noise;       /* the white noise handed over (sigma 0: none), on the load's node at every advance */
    int64_t noise_cache[NOISE_CACHE_SIZE]; /* the Brownian tree's cache: scratch, never in the state */
    Element saved;     /* core_do_step's checkpoint */
    Element preview;   /* CONNECTOR: the outputs' state: the committed one moved to the inputs set now */
    int preview_state; /* 0: to compute, 1: computed, -1: the move failed (no outputs) */
    char why[512];     /* why the preview's move failed */
    Work work;
} Instance;

static double element_time(const Element* e) { return clock_time(&e->clock); }

/* the outputs that must be numbers after a step (core.h: unshowable_output) */
#define STEP_OUTPUT(what) ((what) == W_X || (what) == W_V || (what) == W_REACTION || (what) == W_ENERGY || \
                           (what) == W_DISSIPATED || (what) == W_U)
#define KIND_INTEGERS 0
/* what the master set, kept in an FMU state (state.h: capture, restore_checked) */
#define SETTINGS(to, from)                                                                                     \
    COPY_FIELD(to, from, F), COPY_FIELD(to, from, x_in), COPY_FIELD(to, from, v_in), COPY_FIELD(to, from, step), \
        COPY_FIELD(to, from, start_time), COPY_FIELD(to, from, time), COPY_FIELD(to, from, par),               \
        COPY_FIELD(to, from, scene_load), COPY_FIELD(to, from, stepper_valid), COPY_FIELD(to, from, stepper),  \
        COPY_FIELD(to, from, noise_set)
#define SETTABLE(what) ((what) == W_F || (what) == W_XIN || (what) == W_VIN || (what) == W_PARAM || \
                        (what) == W_STEP || (what) == W_NOISE_INTENSITY || (what) == W_NOISE_UNIT)

#endif
