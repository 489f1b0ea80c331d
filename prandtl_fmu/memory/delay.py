"""``[delay]``: a delayed force on the mass (Lamarque, Bastien & Holland, SIAM J. Numer. Anal. 41 (2003)).

    force on the point:   -gain * y(t - tau),   y = x (``acts_on = "x"``, default) or v (``"v"``),

with y(s) = y(0) for s < 0 (the history before t = 0 is the initial state). ``gain`` (N/m on x, N s/m on v)
may take either sign; ``tau`` (s) > 0. With a massless element the delay acts on x only.

The delayed value comes from a buffer of the path's own past values, sampled on a fixed grid of spacing
Delta (the scene's step): after each step from t to t + h the grid points j Delta in (t, t + h] receive y
interpolated linearly along the step, and y(t + h - tau) is interpolated linearly between grid points (or,
within the last grid interval, between the last grid point and the current state). Where tau < h the
delayed instant falls inside the step itself: y(t + h - tau) = (1 - theta) y(t) + theta y(t + h), theta
= 1 - tau / h, implicit in the new state (``implicit``) like every other term. The grid does not depend on
the steps taken, so a master's split of its steps into shorter ones costs no memory: the buffer holds
ceil(tau / Delta) + 4 values, checked against the memory available before the run.

The kernel form: ``((gain, tau, on_v, grid), buffer)``: ``buffer[0]`` the last grid index J recorded,
``buffer[1]`` the history value y(0), ``buffer[2 + (j mod N)]`` the value at j Delta.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._jit import inline_kernel

NAME = "delay"
HEAD = 2  # buffer entries before the ring


@dataclass(frozen=True)
class Delay:
    """A force -gain * y(t - tau) on the mass, y = x or v (``acts_on``)."""

    gain: float
    tau: float
    acts_on: str = "x"


def read(r, scene_tables) -> Delay:
    """``[delay]`` from its reader ``r`` (scene._Reader); ``scene_tables``: the other tables' names."""
    r.only({"gain", "tau", "acts_on"})
    gain = r.number("gain")
    tau = r.number("tau", positive=True)
    acts_on = r.string("acts_on", "x", choices=("x", "v"))
    if acts_on == "v" and "mass" not in scene_tables:
        r.fail("acts_on", '"v" needs [mass]: the massless element\'s velocity is a rate of its state, not a '
                          "degree of freedom (delay x)")
    return Delay(gain, tau, acts_on)


def size(delay: Delay, grid: float) -> int:
    """Entries of the buffer for a grid spacing ``grid`` (s)."""
    return HEAD + math.ceil(delay.tau / grid) + 4


def compile(delay: Delay, grid: float, y0: float):
    """The kernel form, with the buffer filled with the history y(0) = ``y0``."""
    buffer = np.zeros(size(delay, grid))
    buffer[1] = y0
    buffer[HEAD] = y0
    return (float(delay.gain), float(delay.tau), 1.0 if delay.acts_on == "v" else 0.0, float(grid)), buffer


def state(part) -> list:
    """The buffer as plain data."""
    return part[1].tolist()


def restore(part, values, time: float) -> None:
    """Put a saved buffer back (in place) for an element at ``time``; ValueError if it does not fit."""
    (gain, tau, on_v, grid), buffer = part
    if len(values) != buffer.shape[0]:
        raise ValueError(f"state has a delay buffer of {len(values)} values, the element's holds "
                         f"{buffer.shape[0]} (tau / step changed?)")
    values = np.asarray(values, dtype=float)
    expected = max(math.floor(time / grid), 0)  # the last grid point recorded, to a rounding of the clock
    if not (values[0] >= 0 and values[0] == int(values[0]) and abs(values[0] - expected) <= 1):
        raise ValueError(f"state has a delay buffer whose grid index is {values[0]!r}, at t = {time!r} s it is "
                         f"{expected}")
    buffer[:] = values


def time_problem(delay_part, start: float, end: float):
    """Why an advance from ``start`` to ``end`` (s) cannot be carried by the delay's buffer, or None: its grid
    counts from t = 0 in integers (below 2^52 steps of it, where a time still resolves the grid), and it
    cannot go back before what it recorded."""
    (gain, tau, on_v, grid), buffer = delay_part
    if start < 0:
        return f"a [delay] counts its history from t = 0: the time {start!r} s is negative"
    if end / grid >= 2.0**52:
        return (f"a [delay]'s buffer counts time in steps of {grid!r} s below 2^52: t = {end!r} s is beyond "
                "(the clock no longer resolves its grid)")
    if start < (buffer[0] - 1) * grid:
        return (f"the time goes back to {start!r} s, before what the [delay]'s buffer recorded (up to "
                f"{float(buffer[0] * grid)!r} s): its past would be wrong")
    return None


@inline_kernel
def _ring(buffer, j):
    return buffer[HEAD + j % (buffer.shape[0] - HEAD)]


@inline_kernel
def delayed(part, q, t, y_now):
    """y(q), q <= t, from the buffer and the current value ``y_now`` at t."""
    (gain, tau, on_v, grid), buffer = part
    if q <= 0.0:
        return buffer[1]
    last = int(buffer[0])
    t_last = last * grid
    if q >= t_last:
        if t > t_last:
            y_last = _ring(buffer, last)
            return y_last + min((q - t_last) / (t - t_last), 1.0) * (y_now - y_last)
        return y_now
    j = int(q / grid)
    oldest = last - (buffer.shape[0] - HEAD) + 1
    j = min(max(j, oldest), last - 1)
    y_j = _ring(buffer, j)
    return y_j + min(max((q - j * grid) / grid, 0.0), 1.0) * (_ring(buffer, j + 1) - y_j)


@inline_kernel
def terms(part, t, h, y_now):
    """(a, b): the delayed value y(t + h - tau) = a + b y(t + h) (b = 0 when tau >= h)."""
    (gain, tau, on_v, grid), buffer = part
    q = t + h - tau
    if q <= t:
        return delayed(part, q, t, y_now), 0.0
    theta = (q - t) / h
    return (1.0 - theta) * y_now, theta


@inline_kernel
def record(part, t, h, y0, y1):
    """After a step from (t, y0) to (t + h, y1): the grid points in (t, t + h] receive y along the step."""
    (gain, tau, on_v, grid), buffer = part
    if not h > 0.0:  # an instant (the connector's move at one time): no grid point is crossed
        return
    end = t + h
    j = int(buffer[0]) + 1
    capacity = buffer.shape[0] - HEAD
    newest = math.floor(end / grid)
    j = max(j, newest - capacity + 1)  # only the last `capacity` points can ever be read
    while j <= newest:
        theta = min(max((j * grid - t) / h, 0.0), 1.0)  # points before the start take its value
        buffer[HEAD + j % capacity] = y0 + theta * (y1 - y0)
        j += 1
    buffer[0] = max(buffer[0], float(newest))
