"""The implicit step's scalar equation with Dahl's friction: G(w) + F_d1(w) = 0.

G is the equation of :mod:`prandtl_fmu.kernels.increment` (non-decreasing, piecewise smooth) and F_d1(w) the
Dahl force after the monotone move w (``memory/dahl.py``: non-decreasing, continuous, a kink at w = 0), so
their sum H is non-decreasing. From w = 0 in the direction d = -sign(H(0)): Newton's steps with the one-sided
slope (the inertia's, the springs', the sticking branches' and Dahl's sigma y^exponent). Where H is concave in
the direction of motion (Dahl's force saturates, branches start to slide) they approach the root from below
and never overshoot; once a step does overshoot (a cubic spring), the root is bracketed and a step that would
leave the bracket halves it instead. A flat H (nothing left to balance it but a cubic spring) doubles the step.

Bounded work: at most MAX_NEWTON + MAX_BISECTIONS evaluations of H (each O(n), or O(log n) with the memory
stack). Past them, or when H stays short of zero up to the largest double (a massless element beyond its
strength: plastic collapse), the result is NaN and the step is refused by the driver.
"""
import numpy as np

from .._jit import inline_kernel, kernel
from .increment import _cubic_stiffness, _plus_spring, residual
from ..memory.dahl import _power, after

_EPS = 2.220446049250313e-16
MAX_NEWTON = 200  # Newton steps (safeguarded by the bracket once there is one)
MAX_BISECTIONS = 2100  # and room for halvings: the doubles' range


@inline_kernel
def _evaluate(w, part, fd, x, linear, offset, k0, k3, k, eta, cs, u, h, direction):
    """(H(w), its slope for a motion in ``direction``)."""
    g, sticking, room = residual(w, x, linear, offset, k0, k3, k, eta, cs, u, h, direction)
    dahl, dahl_slope = after(part, fd, w)
    if w == 0.0:  # the slope of a move in ``direction`` (at 0 itself Dahl's law has a kink)
        sigma, level, exponent = part[0]
        dahl_slope = sigma * _power(max(1.0 - direction * fd / level, 0.0), exponent)
    return g + dahl, _plus_spring(linear + sticking, k0) + _cubic_stiffness(x + w, k3) + dahl_slope


@kernel
def solve_dahl_increment(part, x, linear, offset, k0, k3, k, eta, cs, u, h):
    """The increment w with the Dahl force of ``part`` at the step's end (see the module docstring)."""
    fd = part[1][0]
    g = residual(0.0, x, linear, offset, k0, k3, k, eta, cs, u, h, 1.0)[0] + fd
    if g == 0.0:
        return 0.0
    if g != g:
        return np.nan
    d = -1.0 if g > 0.0 else 1.0
    g, slope = _evaluate(0.0, part, fd, x, linear, offset, k0, k3, k, eta, cs, u, h, d)
    w = 0.0
    lo, g_lo = 0.0, g  # d H(lo) < 0
    hi, g_hi = np.inf, np.nan  # d H(hi) > 0 once bracketed
    bracketed = False
    for _ in range(MAX_NEWTON + MAX_BISECTIONS):
        if slope > 0.0:
            trial = w - g / slope
        else:  # flat: only the cubic spring, or nothing, can still balance H
            trial = w + d * max(2.0 * abs(w), 1e-300)
        if bracketed and not (min(lo, hi) < trial < max(lo, hi)):
            trial = 0.5 * (lo + hi)
        if not abs(trial) < np.inf:
            return np.nan  # H stays short of zero up to the largest double: no root (plastic collapse)
        if abs(trial - w) <= 4.0 * _EPS * abs(trial):
            return trial  # Newton's step is at the rounding of w
        g, slope = _evaluate(trial, part, fd, x, linear, offset, k0, k3, k, eta, cs, u, h, d)
        if g != g:
            return np.nan
        w = trial
        if g == 0.0:
            return w
        if d * g < 0.0:
            lo, g_lo = w, g
        else:
            hi, g_hi, bracketed = w, g, True
        if bracketed and abs(hi - lo) <= 4.0 * _EPS * max(abs(lo), abs(hi)):
            return lo if abs(g_lo) <= abs(g_hi) else hi
    return np.nan  # past the bound: refused (the driver reports the step)
