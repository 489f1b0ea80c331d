/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The FMU state of the native FMU as a blob, for every kind (its State: kind.h): a state made from the instance
 * (state_fill), checked (state_refusal, with the kind's check of every field) and set into the instance
 * (restore_checked), never applied before it is checked. The FMI calls on states are machine.h's.
 *
 * A blob is a State, then STATE_EXTRA(s) doubles (the memory of the effects with memory: element.h, connector.h;
 * none in a network's). Its size in bytes is kept on the heap just before it, out of the master's reach: a state the
 * master wrote over (its memory's count among what it changed) is never read beyond what was allocated. */
#ifndef PRANDTL_STATE_H
#define PRANDTL_STATE_H
#include "kind.h"

#if !NETWORK
/* the doubles a state holds after its fixed part (the memory's state), (size_t)-1 when out of range */
#define MEM_MAX ((int64_t)MEM_FIXED + (int64_t)DELAY_BOUND + DELAY_HEAD + 5)
#define STATE_EXTRA(s) ((s)->element.mem_len >= 0 && (s)->element.mem_len <= MEM_MAX ? \
                        (size_t)(s)->element.mem_len : (size_t)-1)
#define INSTANCE_EXTRA(c) ((size_t)(c)->el.mem_len)
#else
/* the doubles a state holds after its fixed part: none */
#define STATE_EXTRA(s) ((size_t)0)
#define INSTANCE_EXTRA(c) ((size_t)0)
#endif
#define STATE_BYTES(extra) (sizeof(State) + (extra) * sizeof(double))

/* the checksum of a state: its fixed part up to the checksum, then the STATE_EXTRA doubles after it (which the
 * caller knows the blob holds: state_whole, or its size checked) */
static uint64_t state_checksum(const State* s)
{
    size_t extra = STATE_EXTRA(s);
    uint64_t hash = fnv1a(FNV_BASIS, (const unsigned char*)s, offsetof(State, checksum));
    return fnv1a(hash, (const unsigned char*)(s + 1), (extra == (size_t)-1 ? 0 : extra) * sizeof(double));
}

/* an FMU state of the instance: what the master set (SETTINGS), and whether it was initialized (state_fill puts
 * the element and its memory in it) */
static void capture(const Instance* c, State* s)
{
    SETTINGS(s, c);
    s->initialized = c->initialized;
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
 * checksum first, then every field as strictly as the setters check the master's values (``fields_problem``: the
 * kind's state_problem; a checksum detects accidents, not edits, and a blob with a recomputed one is checked field
 * by field) */
static const char* state_refusal(const State* s, const char* (*fields_problem)(const State*, char*, size_t),
                                 char* buffer, size_t size)
{
    if (memcmp(s->header, STATE_MAGIC, sizeof STATE_MAGIC) != 0)
        return "not a serialized state of a prandtl_fmu native FMU";
    if (s->version != STATE_VERSION || s->size != sizeof *s)
        return "a state of another version of the native runtime";
    if (strncmp(s->digest, DIGEST, 65) != 0)
        return "a state of another scene (its digest differs)";
    if (s->checksum != state_checksum(s))
        return "its checksum does not match: the state was altered";
    return fields_problem(s, buffer, size);
}

/* a state checked (state_refusal) set into the instance: its element into the instance's own arrays
 * (memory.restore_memory: the cached values recomputed, never taken from a state), what the master set, handed over
 * at the next step (which redraws the same noise's path) */
static void restore_checked(Instance* c, const State* s)
{
#if NETWORK
    c->el = s->element;
#else
    double* mem = c->el.mem;
    c->el = s->element;
    c->el.mem = mem;
    if (HAS_MEMORY) {
        memcpy(mem, (const double*)(s + 1), (size_t)s->element.mem_len * sizeof(double));
        forget_memory_cache(mem);
    }
#endif
    SETTINGS(c, s);
#ifdef FORGET_DERIVED
    FORGET_DERIVED(c);
#endif
#if !KIND_INTEGERS
    c->stepper[sizeof c->stepper - 1] = 0;
    c->handed = 0;
#endif
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

#endif
