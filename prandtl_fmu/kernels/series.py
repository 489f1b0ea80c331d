"""Branches with a dashpot in series (the series model, eq. 15 of 004): the O(n) kernel.

Branch i has stiffness k[i] (N/m), elastic range eta[i] (m), a dashpot c[i]
(N s/m) in series with its spring and slider, and elongation u[i] (m) of
its spring, |u[i]| <= eta[i]:

    u_i' + d psi_[-eta_i, eta_i](u_i) ∋ v - lambda_i u_i,   lambda_i = k_i / c_i,

force k_i u_i; the dashpot dissipates (k_i u_i)^2 / c_i. Over a step of h in
which x moves by dx, the elongation moves by one of three rules, each the
clip of a linear update u_free = decay u + gain dx:

* ``EXPLICIT`` (``projected``, the paper's scheme: the relaxation at the
  old state): decay = 1 - h lambda, gain = 1; stable for h lambda <= 2;
* ``BACKWARD`` (``implicit``: every term at the new state):
  u1 = clip((u + dx) / (1 + h lambda)), decay = gain = 1 / (1 + h lambda);
* ``FLOW`` (``symplectic``, ``verlet``: the exact solution along the
  straight path, v = dx / h constant, as the play update is for a plain
  branch): decay = exp(-h lambda), gain = (1 - exp(-h lambda)) / (h lambda).
  The free flow is monotone in time, so clipping its end is exact.

With c -> infinity (lambda -> 0) every rule is the play update clip(u + dx).
The energy account books each rule's own dissipation, >= 0 at every step:
the sliders alpha_i |slip_i| and the dashpots (k_i u_i)^2 h / c_i at the
state the rule takes (old for EXPLICIT, new for BACKWARD), or their exact
integrals along the path (FLOW). The memory stack does not apply (a relaxing
branch forgets its history: no stack of reversal points describes it), so
these branches always run on this kernel.
"""

import numpy as np
from numba.extending import overload

from .. import libm
from .._jit import kernel
from .play import move, piece

EXPLICIT, BACKWARD, FLOW = 0, 1, 2


@kernel
def rates(z):
    """(phi1, psi) of z = h lambda >= 0: phi1 = (1 - e^-z) / z, psi = (z - 1 + e^-z) / z^2 (1 and 1/2 at 0),
    without cancellation."""
    if z < 1e-4:
        return 1.0 - z * (0.5 - z / 6.0), 0.5 - z * (1.0 / 6.0 - z / 24.0)
    return -libm.expm1(-z) / z, (z + libm.expm1(-z)) / (z * z)


@kernel
def coefficients(rule, rate, h):
    """(decay, gain) of ``rule`` for a branch relaxing at ``rate`` = k / c (1/s) over h."""
    z = h * rate
    if rule == EXPLICIT:
        return 1.0 - z, 1.0
    if rule == BACKWARD:
        return 1.0 / (1.0 + z), 1.0 / (1.0 + z)
    return libm.exp(-z), rates(z)[0]


@kernel
def series_move(k, eta, c, u, dx, h, rule, energy):
    """Move every series branch over a step of h in which x moves by dx (in place); return sum_i k_i u_i.
    With an ``energy`` account, the sliders' dissipation goes to energy[1] and the dashpots' to energy[2]."""
    force = 0.0
    sliders = 0.0
    dashpots = 0.0
    for i in range(k.shape[0]):
        rate = k[i] / c[i]
        decay, gain = coefficients(rule, rate, h)
        u0 = u[i]
        moved = decay * u0 + gain * dx
        ui = min(max(moved, -eta[i]), eta[i])
        u[i] = ui
        force += k[i] * ui
        if energy is not None:
            if rule == FLOW and h > 0.0:
                slider, dashpot = _flow_dissipation(k[i], eta[i], rate, u0, ui, moved, dx, h)
            else:
                # the free update is u0 + dx - (relaxation) - slip: the slip is what the clip removes, scaled back
                # to the units of x (BACKWARD divides the whole update by 1 + h lambda); h = 0 (an instant):
                # no relaxation, the play update
                slip = (moved - ui) / gain
                held = u0 if rule == EXPLICIT else ui  # where the rule takes the dashpot's force
                slider = k[i] * eta[i] * abs(slip)
                dashpot = k[i] * held * held * rate * h
            sliders += slider
            dashpots += dashpot
    if energy is not None:
        energy[1] += sliders
        energy[2] += dashpots
    return force


@kernel
def _flow_dissipation(k, eta, rate, u0, u1, moved, dx, h):
    """(slider, dashpot) dissipation (J) of one branch along the exact path at v = dx / h: a free phase from u0,
    then, if the branch reaches its threshold b = u1 = ±eta, a slip phase at u = b until h.

    Free phase of T: integral u dt = u0 T phi1(lambda T) + v T^2 psi(lambda T), and the dashpot takes
    k (v integral u dt - (u_T^2 - u0^2) / 2) (the work into the branch less its stored energy; rounding
    can only make it a hair negative: clamped at 0). Slip phase of S: the slider slips (v - lambda b) S,
    the dashpot takes k lambda b^2 S."""
    v = dx / h
    if moved == u1:  # no slip
        free, slip_time, end = h, 0.0, u1
    else:
        b = u1
        free = 0.0  # already on the threshold (or a flow that only rounding takes beyond it)
        if u0 != b and rate * u0 != v:
            if rate == 0.0:
                free = (b - u0) / v
            else:
                free = -libm.log1p(rate * (b - u0) / (rate * u0 - v)) / rate
        if not free >= 0.0:
            free = 0.0
        free = min(free, h)
        slip_time, end = h - free, b
    phi1, psi = rates(rate * free)
    integral = u0 * free * phi1 + v * free * free * psi
    dashpot = max(k * (v * integral - 0.5 * (end - u0) * (end + u0)), 0.0)
    slider = 0.0
    if slip_time > 0.0:
        slider = k * eta * abs(v - rate * end) * slip_time
        dashpot += k * rate * end * end * slip_time
    return slider, dashpot


@kernel
def series_piece(k, eta, c, u, w, h, direction):
    """:func:`play.piece` for the BACKWARD rule: the branch force sum_i k_i clip((u_i + w) / (1 + h lambda_i))
    as a function of the increment w around ``w`` in ``direction``: ``(force, stiffness, room)``."""
    force = 0.0
    stiffness = 0.0
    room = np.inf
    for i in range(k.shape[0]):
        scale = 1.0 + h * k[i] / c[i]
        moved = (u[i] + w) / scale
        force += k[i] * min(max(moved, -eta[i]), eta[i])
        gap = eta[i] - direction * moved
        sticking = gap > 0.0
        stiffness += k[i] / scale * sticking
        room = min(room, gap * scale if sticking else np.inf)
    return force, stiffness, room


def move_branches(k, eta, c, u, dx, h, rule, energy):
    """Move the branches over a step of h in which x moves by dx: the play update (``c`` None: plain branches,
    or the memory stack) or :func:`series_move`; returns the branch force (compiled only)."""
    raise NotImplementedError


@overload(move_branches, inline="always")
def _move_branches_overload(k, eta, c, u, dx, h, rule, energy):
    from numba.core import types

    if isinstance(c, types.NoneType):
        return lambda k, eta, c, u, dx, h, rule, energy: move(k, eta, u, dx, energy)
    return lambda k, eta, c, u, dx, h, rule, energy: series_move(k, eta, c, u, dx, h, rule, energy)


def branch_piece(k, eta, c, u, w, h, direction):
    """:func:`play.piece`, or :func:`series_piece` for series branches (compiled only)."""
    raise NotImplementedError


@overload(branch_piece, inline="always")
def _branch_piece_overload(k, eta, c, u, w, h, direction):
    from numba.core import types

    if isinstance(c, types.NoneType):
        return lambda k, eta, c, u, w, h, direction: piece(k, eta, u, w, direction)
    return lambda k, eta, c, u, w, h, direction: series_piece(k, eta, c, u, w, h, direction)
