/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The connector's types, what the layers below its calls (connector.h) read of it: the committed sample and its
 * branches (Element), an FMU state's fixed part (State), the instance (Instance), and the macros the shared headers
 * read: the memory's arrays (core.h), what the master set, kept in an FMU state (SETTINGS: state.h), the variables a
 * master sets (SETTABLE) and the outputs that must be numbers after a step (STEP_OUTPUT). It includes common.h
 * alone. */
#ifndef PRANDTL_CONNECTOR_TYPES_H
#define PRANDTL_CONNECTOR_TYPES_H
#include "common.h"

typedef struct {
    double p[N_PARAMS]; /* the coefficients in use (k0, k3, c) */
    double cs[NB_CS];   /* the series dashpots in use */
    double x, v, time, direction; /* the committed sample; the direction of the last motion */
    double u[NB_ARR];
    double account[3];  /* [1] the sliders, [2] the dashpots (connector.SLIDERS, DAMPER) */
    double mp[N_MEMP];  /* the effects with memory: their parameters in use (kernels.memory_layout) */
    int64_t nd;         /* the delay's buffer: its values (memory.delay.size at the tau in use; 0: no delay) */
    int64_t mem_len;    /* the memory's state: MEM_FIXED + nd values */
    double* mem;        /* ... on the heap (NULL in a state blob: its values follow the blob's fixed part) */
} Element;

typedef struct {
    STATE_HEAD;
    Element element;
    double x_in, v_in, start_time, par[N_PARAMS], cbranch[NB_CS];
    int initialized;
    double mpar[N_MEMP]; /* the memory's parameters the master set */
    double xd[2], vd[2]; /* x's and v's derivatives the master set (fmi2SetRealInputDerivatives) */
    uint64_t checksum;   /* of the fixed part and the memory's state, element.mem_len values after it */
} State;

typedef struct {
    INSTANCE_HEAD;
    Element el;
    /* what the master set */
    double x_in, v_in, start_time, par[N_PARAMS], cbranch[NB_CS];
    int initialized;
    int scene_load;   /* none here: what the FMI layers' Boolean and String calls refuse */
    char stepper[32];
    Element preview;  /* the outputs' state (on the heap with the instance, never a large copy on the host's stack) */
    Element saved;    /* core_do_step's checkpoint: a step whose outputs overflow is rolled back */
    double mpar[N_MEMP]; /* the memory's parameters the master set (fixed: before initialization only) */
    int memory_failed;   /* the memory's state could not be allocated at instantiation (the instance is refused) */
    double xd[2], vd[2]; /* x', x'' and v', v'' the master set for the next doStep (0: held) */
} Instance;

static double element_time(const Element* e) { return e->time; }

/* the memory's arrays (core.h): the element's, its preview's and its checkpoint's */
#define MEMORY_ARRAYS(c) {&(c)->el.mem, &(c)->preview.mem, &(c)->saved.mem}
#define MEMORY_TAU(c) ((c)->mpar[1])
#define MEMORY_SIZED(c, length) ((c)->el.mem_len = (c)->preview.mem_len = (c)->saved.mem_len = (length))
/* the outputs that must be numbers after a step (core.h: unshowable_output); no Integer to set (connector: the
 * motion comes in) */
#define STEP_OUTPUT(what) ((what) == W_FORCE || (what) == W_STIFFNESS || (what) == W_ENERGY)
#define KIND_INTEGERS 1
/* what the master set, kept in an FMU state (state.h: capture, restore_checked) */
#define SETTINGS(to, from)                                                                                     \
    COPY_FIELD(to, from, x_in), COPY_FIELD(to, from, v_in), COPY_FIELD(to, from, start_time),                  \
        COPY_FIELD(to, from, par), COPY_FIELD(to, from, cbranch), COPY_FIELD(to, from, mpar),                  \
        COPY_FIELD(to, from, xd), COPY_FIELD(to, from, vd)
#define SETTABLE(what) ((what) == W_X || (what) == W_V || (what) == W_PARAM || (what) == W_CBRANCH || \
                        (what) == W_MEMORY)

#endif
