/* The FMU state of the native FMU, for both FMI layers (fmi2.c, fmi3.c) over the element or the connector
 * (their State, capture, state_problem, restore): a checked blob, never applied before it is checked. */
#ifndef PRANDTL_STATE_H
#define PRANDTL_STATE_H

static int core_get_state(Instance* c, void** state)
{
    State* s = *state ? (State*)*state : (State*)malloc(sizeof(State));
    if (s == NULL) {
        say(c, ST_ERROR, FMI "Get" FMU_STATE " failed: out of memory");
        return ST_ERROR;
    }
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
    if (size < sizeof(State)) {
        say(c, ST_ERROR, FMI "SerializeFMUstate refused: %zu bytes given, %zu needed", size, sizeof(State));
        return ST_ERROR;
    }
    memcpy(bytes, state, sizeof(State));
    return ST_OK;
}

/* a blob of bytes (of any alignment) into a state, checked whole before it is one: into *state when the master
 * hands one (FMI: overwritten), else into a new one */
static int core_deserialize(Instance* c, const char* bytes, size_t size, void** state)
{
    char buffer[256];
    const char* problem;
    State* s;
    if (size != sizeof(State)) {
        say(c, ST_ERROR, "FMU state refused (%zu bytes: not a serialized state of this FMU, which has %zu)", size,
            sizeof(State));
        return ST_ERROR;
    }
    s = (State*)malloc(sizeof(State));
    if (s == NULL) {
        say(c, ST_ERROR, "FMU state refused: out of memory");
        return ST_ERROR;
    }
    memcpy(s, bytes, sizeof(State));
    problem = state_problem(s, buffer, sizeof buffer);
    if (problem != NULL) {
        free(s);
        say(c, ST_ERROR, "FMU state refused (%s)", problem);
        return ST_ERROR;
    }
    if (*state != NULL) {
        memcpy(*state, s, sizeof(State));
        free(s);
    } else {
        *state = s;
    }
    return ST_OK;
}

#endif
