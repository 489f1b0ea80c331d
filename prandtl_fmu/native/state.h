/* The FMU state of the native FMU, for both FMI layers (fmi2.c, fmi3.c) over the element or the connector
 * (their State, capture, state_problem, restore): a checked blob, never applied before it is checked. */
#ifndef PRANDTL_STATE_H
#define PRANDTL_STATE_H

/* the doubles a state holds after its fixed part (the element's memory: element.h), (size_t)-1 when out of range */
#ifndef STATE_EXTRA
#define STATE_EXTRA(s) ((size_t)0)
#define INSTANCE_EXTRA(c) ((size_t)0)
#endif
#define STATE_BYTES(extra) (sizeof(State) + (extra) * sizeof(double))

static int core_get_state(Instance* c, void** state)
{
    size_t bytes = STATE_BYTES(INSTANCE_EXTRA(c));
    State* s = *state && STATE_BYTES(STATE_EXTRA((State*)*state)) == bytes ? (State*)*state : (State*)malloc(bytes);
    if (s == NULL) {
        say(c, ST_ERROR, FMI "Get" FMU_STATE " failed: out of memory");
        return ST_ERROR;
    }
    if (*state != NULL && *state != s) /* a state of another size (the memory's): replaced */
        free(*state);
    capture(c, s);
    *state = s;
    return ST_OK;
}

static int core_set_state(Instance* c, const void* state)
{
    if (state == NULL) {
        say(c, ST_ERROR, "FMU state refused (NULL); the instance is unchanged");
        return ST_ERROR;
    }
    return restore(c, (const State*)state);
}

static void core_free_state(void** state)
{
    if (state != NULL) {
        free(*state);
        *state = NULL;
    }
}

static int core_serialize(Instance* c, const void* state, char* bytes, size_t size)
{
    size_t needed = STATE_BYTES(STATE_EXTRA((const State*)state));
    if (size < needed) {
        say(c, ST_ERROR, FMI "SerializeFMUstate refused: %zu bytes given, %zu needed", size, needed);
        return ST_ERROR;
    }
    memcpy(bytes, state, needed);
    return ST_OK;
}

/* a blob of bytes (of any alignment) into a state, checked whole before it is one: into *state when the master
 * hands one (FMI: overwritten), else into a new one */
static int core_deserialize(Instance* c, const char* bytes, size_t size, void** state)
{
    char buffer[256];
    const char* problem;
    State* s;
    size_t extra = 0;
    if (size >= sizeof(State)) { /* the fixed part says how many values follow it */
        s = (State*)malloc(sizeof(State));
        if (s == NULL) {
            say(c, ST_ERROR, "FMU state refused: out of memory");
            return ST_ERROR;
        }
        memcpy(s, bytes, sizeof(State));
        extra = STATE_EXTRA(s);
        free(s);
    }
    if (size < sizeof(State) || extra == (size_t)-1 || size != STATE_BYTES(extra)) {
        say(c, ST_ERROR, "FMU state refused (%zu bytes: not a serialized state of this FMU, which has %zu)", size,
            STATE_BYTES(extra == (size_t)-1 ? 0 : extra));
        return ST_ERROR;
    }
    s = (State*)malloc(size);
    if (s == NULL) {
        say(c, ST_ERROR, "FMU state refused: out of memory");
        return ST_ERROR;
    }
    memcpy(s, bytes, size);
    problem = state_problem(s, buffer, sizeof buffer);
    if (problem != NULL) {
        free(s);
        say(c, ST_ERROR, "FMU state refused (%s)", problem);
        return ST_ERROR;
    }
    free(*state); /* the master's state, if any, is overwritten: replaced (its size may differ) */
    *state = s;
    return ST_OK;
}

#endif
