/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The instance's state machine over its kind's calls, written once for every kind: the exit of initialization mode
 * (the kind's initialize, then started), a doStep (the settings handed over: hand_over_problem, hand_over_settings;
 * then the kind's step), the check of a Real/Float64 a master sets (SETTABLE, the kind's fixed_problem), and the FMI
 * calls on FMU states (state.h's blob, checked by the kind's state_problem, set by its restore). The one header that
 * calls the kind's functions: it includes the kind's header (element.h, connector.h or network.h, as scene.h says),
 * which includes nothing of this. Above it: front.h and the FMI layers (fmi2.c, fmi3.c). */
#ifndef PRANDTL_MACHINE_H
#define PRANDTL_MACHINE_H
#include "common.h"
#if NETWORK
#include "network.h"
#elif CONNECTOR
#include "connector.h"
#else
#include "element.h"
#endif

/* a Float64/Real the master sets: one of SETTABLE, and what a fixed parameter allows (fixed_problem) */
static int core_check_float(Instance* c, const Var* var, unsigned vr, double value)
{
    if (var == NULL || !SETTABLE(var->what)) {
        say(c, ST_ERROR, FLOAT_SETTER " refused: value reference %u is not a Real input or parameter", vr);
        return ST_ERROR;
    }
    return fixed_problem(c, var, value);
}

/* fmi2/3ExitInitializationMode (the FMI layer checked the call sequence) */
static int core_exit_initialization(Instance* c)
{
    char buffer[1024];
    const char* problem;
    if (c->phase != INITIALIZING) {
        say(c, ST_ERROR, FMI "ExitInitializationMode refused: not in initialization mode");
        return ST_ERROR;
    }
    problem = initialize(c, buffer, sizeof buffer);
    if (problem != NULL) {
        say(c, ST_ERROR, "initialization refused: %s", problem);
        return ST_ERROR;
    }
    c->initialized = 1;
    c->phase = STEPPING;
    started(c);
    return ST_OK;
}

#if !KIND_INTEGERS /* the element and the network */
/* slave._apply_settings before a step: the settings set since the last one handed over (the kind's
 * hand_over_settings), or refused with the reason (its hand_over_problem; a Discard: steps are refused until it is
 * set right): 1, or 0 */
static int settings_handed(Instance* c)
{
    char buffer[1024];
    const char* problem;
    if (c->handed)
        return 1;
    problem = hand_over_problem(c, buffer, sizeof buffer);
    if (problem != NULL) {
        say(c, ST_DISCARD, "%s; steps are refused until it is set right", problem);
        return 0;
    }
    hand_over_settings(c);
    return 1;
}
#else
/* the connector: nothing to hand over (its step checks the coefficients set) */
static int settings_handed(Instance* c)
{
    (void)c;
    return 1;
}
#endif

/* fmi2/3DoStep: one communication step from t of H (the FMI layer checked the call sequence), the settings handed
 * over first */
static int core_do_step(Instance* c, double t, double H)
{
    int status;
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
    status = settings_handed(c) ? step(c, t, H) : ST_DISCARD;
    c->last_step_failed = status != ST_OK;
    return status;
}

/* ------------------------------------------------------------------ FMU state: a checked blob (state.h) */

/* fmi2/3GetFMUstate: into *state when the master hands one of this size, else a new one */
static int core_get_state(Instance* c, void** state)
{
    size_t bytes = STATE_BYTES(INSTANCE_EXTRA(c));
    State* s;
    if (!given(c, state, FMI "Get" FMU_STATE, FMU_STATE))
        return ST_ERROR;
    s = *state && state_bytes(*state) == bytes ? (State*)*state : state_new(bytes);
    if (s == NULL) {
        say(c, ST_ERROR, FMI "Get" FMU_STATE " failed: out of memory");
        return ST_ERROR;
    }
    if (*state != NULL && *state != s) /* a state of another size (the memory's): replaced */
        state_delete(*state);
    state_fill(c, s);
    *state = s;
    return ST_OK;
}

static int core_set_state(Instance* c, const void* state)
{
    if (state == NULL) {
        say(c, ST_ERROR, "FMU state refused (NULL); the instance is unchanged");
        return ST_ERROR;
    }
    if (!state_whole(state)) {
        say(c, ST_ERROR, "FMU state refused (its memory's count of values is not the one it was made with: the "
            "state was altered); the instance is unchanged");
        return ST_ERROR;
    }
    return restore(c, (const State*)state);
}

static int core_free_state(Instance* c, void** state)
{
    if (!given(c, state, FMI "Free" FMU_STATE, FMU_STATE))
        return ST_ERROR;
    state_delete(*state);
    *state = NULL;
    return ST_OK;
}

/* the bytes of a serialized state: the blob as it was allocated */
static int core_state_size(Instance* c, const void* state, size_t* size)
{
    if (!given(c, state, FMI "Serialized" FMU_STATE "Size", FMU_STATE) ||
        !given(c, size, FMI "Serialized" FMU_STATE "Size", "size"))
        return ST_ERROR;
    *size = state_bytes(state);
    return ST_OK;
}

static int core_serialize(Instance* c, const void* state, char* bytes, size_t size)
{
    size_t needed;
    if (!given(c, state, FMI "Serialize" FMU_STATE, FMU_STATE) || !given(c, bytes, FMI "Serialize" FMU_STATE, "bytes"))
        return ST_ERROR;
    needed = state_bytes(state);
    if (size < needed) {
        say(c, ST_ERROR, FMI "SerializeFMUstate refused: %zu bytes given, %zu needed", size, needed);
        return ST_ERROR;
    }
    memcpy(bytes, state, needed);
    return ST_OK;
}

/* a blob of bytes (of any alignment) into a state, checked whole before it is one: into *state when the master
 * hands one (FMI: overwritten; a state of this FMU replaced, its size may differ), else into a new one */
static int core_deserialize(Instance* c, const char* bytes, size_t size, void** state)
{
    char buffer[256];
    const char* problem;
    State* s;
    size_t extra = 0;
    if (!given(c, bytes, DESERIALIZE, "bytes") || !given(c, state, DESERIALIZE, FMU_STATE))
        return ST_ERROR;
    if (size >= sizeof(State)) { /* the fixed part says how many values follow it */
        s = state_new(sizeof(State));
        if (s == NULL) {
            say(c, ST_ERROR, "FMU state refused: out of memory");
            return ST_ERROR;
        }
        memcpy(s, bytes, sizeof(State));
        extra = STATE_EXTRA(s);
        state_delete(s);
    }
    if (size < sizeof(State) || extra == (size_t)-1 || size != STATE_BYTES(extra)) {
        say(c, ST_ERROR, "FMU state refused (%zu bytes: not a serialized state of this FMU, which has %zu)", size,
            STATE_BYTES(extra == (size_t)-1 ? 0 : extra));
        return ST_ERROR;
    }
    s = state_new(size);
    if (s == NULL) {
        say(c, ST_ERROR, "FMU state refused: out of memory");
        return ST_ERROR;
    }
    memcpy(s, bytes, size);
    problem = state_refusal(s, state_problem, buffer, sizeof buffer);
    if (problem != NULL) {
        state_delete(s);
        say(c, ST_ERROR, "FMU state refused (%s)", problem);
        return ST_ERROR;
    }
    state_delete(*state);
    *state = s;
    return ST_OK;
}

#endif
