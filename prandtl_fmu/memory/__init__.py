"""Effects with memory: forces on the mass that depend on the path, not only on the state (x, v, u).

One module per effect (its equation, its scene reader, its kernel form and its state as plain data):

* ``delay``   -gain y(t - tau)                          (a buffer of past values)
* ``history`` -int_0^t sum_j w_j exp(-r_j (t - s)) y(s) ds   (exact internal variables)
* ``dahl``    -F_d, Dahl's friction                     (one internal force)

:data:`EFFECTS` is the registry: a scene table of that name is read by the module's ``read`` and held in
the scene's attribute of that name. In the kernels the memory is one entry of the model tuple,
``(delay, history, dahl)`` with ``None`` for an absent effect (numba compiles an absent part away: an element
without memory, ``(None, None, None)``, runs none of this). Each part is its parameters and its state arrays, updated in place by the
steppers (``implicit`` and ``projected``; the others refuse): the Element saves and restores them with the
rest of its state.

Every memory force enters a step as a force beside the load (``implicit``: at the step's end, implicit in
the new state; ``projected``: at its start). The energy account books its work with the load's (``work`` is
the work of F and of the memory forces), so the balance residual keeps its meaning.
"""
from __future__ import annotations

from .._jit import kernel
from . import dahl, delay, history

EFFECTS = {"delay": delay, "history": history, "dahl": dahl}  # scene table -> module (in kernel order)
NONE = (None, None, None)  # the kernel form of no memory


def has_memory(memory) -> bool:
    """Whether a kernel form holds any effect."""
    return any(part is not None for part in memory)


def present(scene) -> list:
    """The memory effects of ``scene`` (their table names)."""
    return [name for name in EFFECTS if getattr(scene, name, None) is not None]


def time_problem(memory, start: float, end: float):
    """Why an advance from ``start`` to ``end`` cannot be carried by the memory, or None (the delay's buffer:
    ``delay.time_problem``)."""
    if memory[0] is None:
        return None
    return delay.time_problem(memory[0], start, end)


def refuse_memory(scene, stepper: str) -> None:
    """ValueError if ``scene`` has effects with memory: only ``implicit`` and ``projected`` carry them."""
    names = present(scene)
    if names:
        tables = ", ".join(f"[{name}]" for name in names)
        raise ValueError(f"{stepper!r} does not carry the effects with memory ({tables}): use 'implicit' (implicit "
                         "in every term, order 1) or 'projected' (the paper's scheme)")


def compile_memory(scene, x0: float, v0: float):
    """The kernel form of the scene's memory effects (``NONE`` without any); ``x0``, ``v0``: the state at t = 0
    (the delay's history)."""
    parts = []
    for name in EFFECTS:
        effect = getattr(scene, name)
        if effect is None:
            parts.append(None)
        elif name == "delay":
            parts.append(delay.compile(effect, scene.solver.step, v0 if effect.acts_on == "v" else x0))
        else:
            parts.append(EFFECTS[name].compile(effect))
    return tuple(parts)


def memory_state(memory) -> dict:
    """The state of the memory effects as plain data ({} without any)."""
    return {name: EFFECTS[name].state(part) for name, part in zip(EFFECTS, memory) if part is not None}


def restore_memory(memory, saved, time: float) -> None:
    """Put saved :func:`memory_state` data back into ``memory`` (in place) for an element at ``time``;
    ValueError if it does not fit. Check with :func:`check_memory_state` first where nothing may change on a
    refusal."""
    for name, part in zip(EFFECTS, memory):
        if part is not None:
            if name == "delay":
                delay.restore(part, saved[name], time)
            else:
                EFFECTS[name].restore(part, saved[name])


def check_memory_state(memory, saved, time: float) -> None:
    """ValueError naming what in ``saved`` does not fit ``memory`` (nothing changes)."""
    from ..saved_state import number_list

    if not isinstance(saved, dict):
        raise ValueError(f"state has memory = {saved!r:.60}, not a table")
    names = [name for name, part in zip(EFFECTS, memory) if part is not None]
    if sorted(saved) != sorted(names):
        raise ValueError(f"state has the memory of {sorted(saved) or 'no effect'}, the element has "
                         f"{names or 'none'}")
    restore_memory(copy_memory(memory), {name: number_list(values, name).tolist() for name, values in saved.items()},
                   time)


def copy_memory(memory):
    """A deep copy (the state arrays copied, the parameters shared)."""
    return tuple(None if part is None else (part[0],) + tuple(array.copy() for array in part[1:])
                 for part in memory)


def put_back(memory, copy) -> None:
    """Overwrite ``memory``'s state arrays with those of a :func:`copy_memory` (a rollback)."""
    for part, saved in zip(memory, copy):
        if part is not None:
            for array, values in zip(part[1:], saved[1:]):
                array[:] = values


# ------------------------------------------------------------------ kernels


@kernel
def prepare(memory, h):
    """Before steps of size ``h``: the history's coefficients of that h (``history.prepare``). Every time loop
    calls it before its steps (a step without it is refused: its force is NaN)."""
    _prepare_history(memory[1], h)


@kernel
def _prepare_history(part, h):
    if part is None:
        return
    history.prepare(part, h)


@kernel
def linear_force(memory, t, h, x, v):
    """(A, B): the delay's and the history's force at the end of a step from (t, x, v) as A + B w, w the
    increment of x (v1 = w / h): implicit in the new state."""
    d, s, f = memory
    a1, b1 = _delay_linear(d, t, h, x, v)
    a2, b2 = _history_linear(s, h, x, v)
    return a1 + a2, b1 + b2


@kernel
def _delay_linear(part, t, h, x, v):
    if part is None:
        return 0.0, 0.0
    gain = part[0][0]
    if part[0][2] == 0.0:  # on x: y1 = x + w
        a, b = delay.terms(part, t, h, x)
        return gain * (a + b * x), gain * b
    a, b = delay.terms(part, t, h, v)  # on v: y1 = w / h
    return gain * a, gain * b / h


@kernel
def _history_linear(part, h, x, v):
    if part is None:
        return 0.0, 0.0
    if part[0][1] == 0.0:
        a, b = history.terms(part, h, x)
        return a + b * x, b
    a, b = history.terms(part, h, v)
    return a, b / h


@kernel
def force_now(memory, t, x, v):
    """The memory forces' sum at time t in the state (x, v) (what the reaction adds, what ``projected``
    takes): gain y(t - tau) + sum_j w_j z_j + F_d."""
    d, s, f = memory
    return _delay_now(d, t, x, v) + _history_now(s) + _dahl_now(f)


@kernel
def _delay_now(part, t, x, v):
    if part is None:
        return 0.0
    gain, tau, on_v, grid = part[0]
    return gain * delay.delayed(part, t - tau, t, v if on_v != 0.0 else x)


@kernel
def _history_now(part):
    if part is None:
        return 0.0
    return history.force(part)


@kernel
def _dahl_now(part):
    if part is None:
        return 0.0
    return dahl.force(part)


@kernel
def tangent_now(memory, direction):
    """d(memory force)/dx at an instant for a motion in ``direction``: Dahl's sigma (1 - F_d / F_c s)^exponent
    (the delay and the history add nothing at an instant)."""
    return _dahl_tangent(memory[2], direction)


@kernel
def _dahl_tangent(part, direction):
    if part is None:
        return 0.0
    sigma, level, exponent = part[0]
    return sigma * dahl._power(max(1.0 - direction * part[1][0] / level, 0.0), exponent)


@kernel
def record(memory, t, h, x, v, x1, v1, dx):
    """After a step from (t, x, v) to (t + h, x1, v1): the delay's buffer, the history's variables and the
    Dahl force move along it; ``dx`` the increment the step solved for (x1 - x may differ from it by a
    rounding, which Dahl's stiffness would turn into a force)."""
    d, s, f = memory
    _record_delay(d, t, h, x, v, x1, v1)
    _record_history(s, h, x, v, x1, v1)
    _record_dahl(f, dx)


@kernel
def _record_delay(part, t, h, x, v, x1, v1):
    if part is None:
        return
    if part[0][2] == 0.0:
        delay.record(part, t, h, x, x1)
    else:
        delay.record(part, t, h, v, v1)


@kernel
def _record_history(part, h, x, v, x1, v1):
    if part is None:
        return
    if part[0][1] == 0.0:
        history.record(part, h, x, x1)
    else:
        history.record(part, h, v, v1)


@kernel
def _record_dahl(part, dx):
    if part is None:
        return
    part[1][0] = dahl.after(part, part[1][0], dx)[0]
