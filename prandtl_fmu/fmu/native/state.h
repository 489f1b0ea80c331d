/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The FMU state of the native FMU, for both FMI layers (fmi2.c, fmi3.c) over the element or the connector
 * (their State, capture, state_problem, restore): a checked blob, never applied before it is checked.
 *
 * A blob is a State, then STATE_EXTRA(s) doubles (the element's memory: element.h; none elsewhere). Its size in
 * bytes is kept on the heap just before it, out of the master's reach: a state the master wrote over (its
 * memory's count among what it changed) is never read beyond what was allocated. */
#ifndef PRANDTL_STATE_H
#define PRANDTL_STATE_H

/* the doubles a state holds after its fixed part, (size_t)-1 when out of range */
#ifndef STATE_EXTRA
#define STATE_EXTRA(s) ((size_t)0)
#define INSTANCE_EXTRA(c) ((size_t)0)
#endif
#define STATE_BYTES(extra) (sizeof(State) + (extra) * sizeof(double))

/* what each kind supplies: each field of a state checked (NULL, or why not), a state restored (core.h: capture) */
static const char* state_problem(const State* s, char* buffer, size_t size);
static int restore(Instance* c, const State* s);

/* the checksum of a state: its fixed part up to the checksum, then the STATE_EXTRA doubles after it (which the
 * caller knows the blob holds: state_whole, or its size checked) */
static uint64_t state_checksum(const State* s)
{
    size_t extra = STATE_EXTRA(s);
    uint64_t hash = fnv1a(FNV_BASIS, (const unsigned char*)s, offsetof(State, checksum));
    return fnv1a(hash, (const unsigned char*)(s + 1), (extra == (size_t)-1 ? 0 : extra) * sizeof(double));
}

/* the instance's state into ``s``: its head, the element (the memory's state after the fixed part), the kind's
 * fields (capture), the checksum */
static void state_fill(const Instance* c, State* s)
{
    memset(s, 0, sizeof *s);
    snprintf(s->header, sizeof s->header, "%s", STATE_MAGIC);
    s->version = STATE_VERSION;
    s->size = (uint32_t)sizeof *s;
    snprintf(s->digest, sizeof s->digest, "%s", DIGEST);
    s->element = c->el;
#if !NETWORK
    s->element.mem = NULL;
    if (c->el.mem_len > 0)
        memcpy((double*)(s + 1), c->el.mem, (size_t)c->el.mem_len * sizeof(double));
#endif
    capture(c, s);
    s->checksum = state_checksum(s);
}

/* why a state cannot be restored here, or NULL: the magic, the version and size, the scene's digest and the
 * checksum first, then every field as strictly as the setters check the master's values (state_problem: a
 * checksum detects accidents, not edits, and a blob with a recomputed one is checked field by field) */
static const char* state_refusal(const State* s, char* buffer, size_t size)
{
    if (memcmp(s->header, STATE_MAGIC, sizeof STATE_MAGIC) != 0)
        return "not a serialized state of a prandtl_fmu native FMU";
    if (s->version != STATE_VERSION || s->size != sizeof *s)
        return "a state of another version of the native runtime";
    if (strncmp(s->digest, DIGEST, 65) != 0)
        return "a state of another scene (its digest differs)";
    if (s->checksum != state_checksum(s))
        return "its checksum does not match: the state was altered";
    return state_problem(s, buffer, size);
}

typedef union { size_t bytes; double align; } StateHead; /* before each blob: its size */

static State* state_new(size_t bytes)
{
    StateHead* head = (StateHead*)malloc(sizeof(StateHead) + bytes);
    if (head == NULL)
        return NULL;
    head->bytes = bytes;
    return (State*)(head + 1);
}

static size_t state_bytes(const void* state) { return ((const StateHead*)state - 1)->bytes; }

static void state_delete(void* state)
{
    if (state != NULL)
        free((StateHead*)state - 1);
}

/* whether the blob's own count of values after its fixed part is what it was allocated with */
static int state_whole(const void* state)
{
    size_t extra = STATE_EXTRA((const State*)state);
    return extra != (size_t)-1 && STATE_BYTES(extra) == state_bytes(state);
}

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
    problem = state_refusal(s, buffer, sizeof buffer);
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
