/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* What both FMI layers (fmi2.c, fmi3.c) check of a call before anything runs: the instance, the call sequence (a
 * mask of the phases a function is allowed in, as modelica/Reference-FMUs' fmi2Functions.c and fmi3Functions.c do,
 * after the state machines of the FMI 2.0 and 3.0 standards for co-simulation) and the pointers it is handed. A
 * refusal is logged with its reason, logging on or off, under a declared category. Glue only. */
#ifndef PRANDTL_CALLS_H
#define PRANDTL_CALLS_H
#include "kind.h"

static const char* phase_name(int phase)
{
    switch (phase) {
    case INSTANTIATED: return "instantiated";
    case INITIALIZING: return "initialization mode";
    case STEPPING: return STEPPING_NAME;
    case TERMINATED: return "terminated";
    case INTERMEDIATE_UPDATE: return "intermediate update mode";
    }
    return "unknown";
}

/* whether ``function`` may be called in the instance's phase; logs the refusal */
static int allowed(Instance* c, int phases, const char* function)
{
    if (c->phase & phases)
        return 1;
    say(c, ST_ERROR, "%s refused: not allowed in the state '%s' (the " STANDARD " co-simulation call sequence)",
        function, phase_name(c->phase));
    return 0;
}

/* whether the pointer ``argument`` of ``function`` is given (not NULL); logs the refusal */
static int given(Instance* c, const void* pointer, const char* function, const char* argument)
{
    if (pointer != NULL)
        return 1;
    say(c, ST_ERROR, "%s refused: the argument %s is NULL", function, argument);
    return 0;
}

/* the arrays of a getter or setter of n values: given unless n is 0 */
static int arrays_given(Instance* c, size_t n, const void* vr, const void* values, const char* function)
{
    return n == 0 || (given(c, vr, function, "vr") && given(c, values, function, "value"));
}

/* the start and stop time of the experiment: finite, stop >= start when defined */
static int experiment_valid(Instance* c, double start, int stop_defined, double stop, const char* function)
{
    if (!isfinite(start)) {
        say(c, ST_ERROR, "%s refused: the start time %.17g must be finite", function, start);
        return 0;
    }
    if (stop_defined && !(isfinite(stop) && stop >= start)) {
        say(c, ST_ERROR, "%s refused: the stop time %.17g must be finite and >= the start time %.17g", function, stop,
            start);
        return 0;
    }
    return 1;
}

/* a Real/Float64 a getter hands out: never NaN or inf with an OK status; logs the refusal */
static int shown(Instance* c, const Var* var, double value, const char* function)
{
    if (showable(var, value))
        return 1;
    say(c, ST_ERROR, "%s refused: %s is %.17g, not a finite number (a non-finite input or parameter set, or an "
        "overflow at the inputs set)", function, var->name, value);
    return 0;
}

#endif
