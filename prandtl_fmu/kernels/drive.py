"""The massless element driven by its displacement: the force it transmits along a path of x.

The branches follow the exact play update: between two samples x is taken
linear (monotone), and the play operator is rate independent, so one
monotone move per sample is exact whatever the time between samples.
"""
import numpy as np

from .._jit import kernel
from .play import branch_force, piece
from .series import FLOW, move_branches
from .stack import X as stack_x
from .stack import move as stack_move
from .smooth import elastic_stiffness, smooth_force
from ..memory import force_now, prepare, record


@kernel
def drive(model, u, x_start, xs, vs, durations, forces, energy):
    """Move the branches ``u`` (in place) along the samples ``xs`` from ``x_start``; write the force
    k0 x + k3 x^3 + c v + sum_i k_i u_i at each sample into ``forces`` (``vs``: the velocities, for the
    dashpot). ``durations``: the time (s) from each sample to the one before, over which series dashpots relax
    (``kernels/series.py``, FLOW: exact along the linear path; plain branches do not need them). With an
    ``energy`` account (not None), the sliders' dissipation is added to energy[1], the series dashpots' to
    energy[2]. Returns the last x."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    x = x_start
    for j in range(xs.shape[0]):
        move_branches(k, eta, cs, u, xs[j] - x, durations[j], FLOW, energy)
        x = xs[j]
        forces[j] = smooth_force(x, vs[j], k0, k3, c) + branch_force(k, u)
    return x


@kernel
def drive_with_memory(model, u, x_start, v_start, t_start, xs, vs, durations, forces, energy):
    """:func:`drive` for a scene with effects with memory (``memory/``): along each sample's linear path from
    the last one (at ``t_start`` + the durations), the delay's buffer, the history's variables and the Dahl
    force move too, and each force adds their sum at the sample. Returns the last x."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    x, v, t = x_start, v_start, t_start
    for j in range(xs.shape[0]):
        move_branches(k, eta, cs, u, xs[j] - x, durations[j], FLOW, energy)
        prepare(memory, durations[j])
        record(memory, t, durations[j], x, v, xs[j], vs[j], xs[j] - x)
        x, v, t = xs[j], vs[j], t + durations[j]
        forces[j] = smooth_force(x, v, k0, k3, c) + branch_force(k, u) + force_now(memory, t, x, v)
    return x


@kernel
def _dashpot_work(c, v, rate, curvature, duration):
    """c times the integral of v(t)^2 over [0, duration] for v(t) = v + rate t + curvature t^2 / 2 (0 without a
    dashpot: compiled away)."""
    if c is None:
        return 0.0
    q = 0.5 * curvature
    d = duration
    return c * d * (v * v + d * (v * rate + d * ((rate * rate + 2.0 * v * q) / 3.0 + d * (0.5 * rate * q
                                                                                        + d * q * q / 5.0))))


@kernel
def drive_polynomial(model, u, x, v, xd, vd, duration, energy, out):
    """Move the branches ``u`` (in place) along the polynomial path x(t) = x + xd[0] t + xd[1] t^2 / 2 for
    0 <= t <= ``duration`` (an FMU's input x given with its derivatives), v(t) = v + vd[0] t + vd[1] t^2 / 2. The
    play operator is rate independent, so one move per monotone piece is exact: the path is cut at its turning point
    t* = -xd[0] / xd[1] where 0 < t* < duration (plain branches only: series dashpots and effects with memory
    depend on the path's timing). energy[1] gets the sliders' dissipation, energy[2] the dashpot's
    c * integral of v^2. out = [x, v, the force k0 x + k3 x^3 + c v + sum_i k_i u_i, the direction of the last
    motion (0: none)] at t = duration; all NaN, nothing moved, where the path's moves overflow."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    at, turn, direction = x, 0.0, 0.0
    if xd[1] != 0.0:
        turn = -xd[0] / xd[1]
        if 0.0 < turn < duration:
            at = x + turn * (xd[0] + 0.5 * xd[1] * turn)
    end = x + duration * (xd[0] + 0.5 * xd[1] * duration)
    if not (abs(at - x) < np.inf and abs(end - at) < np.inf):  # an overflow: nothing moved, the caller refuses
        out[:] = np.nan
        return
    if at != x:
        move_branches(k, eta, cs, u, at - x, turn, FLOW, energy)
        direction = 1.0 if at > x else -1.0
    move_branches(k, eta, cs, u, end - at, duration, FLOW, energy)
    if end != at:
        direction = 1.0 if end > at else -1.0
    out[0] = end
    out[1] = v + duration * (vd[0] + 0.5 * vd[1] * duration)
    out[2] = smooth_force(end, out[1], k0, k3, c) + branch_force(k, u)
    out[3] = direction
    energy[2] += _dashpot_work(c, v, vd[0], vd[1], duration)


@kernel
def tangent(model, x, u, direction):
    """dF/dx at (x, u) for a motion in ``direction`` (+1 or -1): k0 + 3 k3 x^2 + the stiffnesses of the
    branches that stick (a branch on its threshold in ``direction`` slides and adds nothing)."""
    m, k0, k3, c, k, eta, cs, friction, memory = model  # at an instant, a series dashpot does not move
    return elastic_stiffness(x, k0, k3) + piece(k, eta, u, 0.0, direction)[1]


@kernel
def preview(model, u, dx, v, x):
    """The force at x = (current x) + dx without moving the branches (``x`` is the new displacement)."""
    m, k0, k3, c, k, eta, cs, friction, memory = model  # at an instant, a series dashpot does not move
    direction = 1.0 if dx >= 0.0 else -1.0
    return smooth_force(x, v, k0, k3, c) + piece(k, eta, u, dx, direction)[0]


@kernel
def play_basis(xs, etas, out):
    """out[j, i]: the play operator of elastic range etas[i] (a branch of unit stiffness, virgin at x = 0)
    along the samples xs: the elongation u_i after sample j."""
    u = np.zeros(etas.shape[0])
    previous = 0.0
    for j in range(xs.shape[0]):
        dx = xs[j] - previous
        previous = xs[j]
        for i in range(etas.shape[0]):
            u[i] = min(max(u[i] + dx, -etas[i]), etas[i])
            out[j, i] = u[i]


@kernel
def spectrum_drive(params, state, xs, out):
    """out[j]: the force of the memory stack ``params`` (n branches or a continuum) in ``state`` after moving
    to each sample xs[j] in turn (state in place, from its own x)."""
    for j in range(xs.shape[0]):
        out[j] = stack_move(params, state, xs[j] - state[stack_x], None)
