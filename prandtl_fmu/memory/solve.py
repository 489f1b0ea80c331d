"""The implicit step's scalar equation with Dahl's friction: G(w) + F_d1(w) = 0.

G is the equation of :mod:`prandtl_fmu.kernels.increment` (non-decreasing, piecewise smooth) and F_d1(w) the
Dahl force after the monotone move w (``memory/dahl.py``: non-decreasing, continuous, a kink at w = 0), so
their sum is non-decreasing: the root is bracketed by doubling from w = 0 in the direction -sign(G(0) +
F_d), then found by Illinois' regula falsi, falling back on bisection, to the rounding of w.

Bounded work: at most 2100 doublings (the doubles' range) and 400 Illinois or bisection iterations, each one
evaluation of G (O(n), or O(log n) with the memory stack). Past them, or when the sum stays short of zero up
to the largest double (a massless element beyond its strength: plastic collapse), the result is NaN and the
step is refused by the driver with the reason.
"""
import numpy as np

from .._jit import kernel
from ..kernels.increment import residual
from .dahl import after

_EPS = 2.220446049250313e-16


@kernel
def _total(w, part, fd, x, linear, offset, k0, k3, k, eta, cs, u, h, direction):
    return residual(w, x, linear, offset, k0, k3, k, eta, cs, u, h, direction)[0] + after(part, fd, w)[0]


@kernel
def solve_dahl_increment(part, x, linear, offset, k0, k3, k, eta, cs, u, h):
    """The increment w with the Dahl force of ``part`` at the step's end (see the module docstring)."""
    fd = part[1][0]
    g0 = residual(0.0, x, linear, offset, k0, k3, k, eta, cs, u, h, 1.0)[0] + fd
    if g0 == 0.0:
        return 0.0
    if g0 != g0:
        return np.nan
    d = -1.0 if g0 > 0.0 else 1.0
    sigma = part[0][0]
    scale = linear + sigma + (0.0 if k0 is None else k0)
    length = abs(g0) / scale if scale > 0.0 else 1.0
    length = max(length, 1e-300)
    lo, g_lo = 0.0, g0
    hi, g_hi = lo, g0
    for _ in range(2100):
        hi = d * length
        if not abs(hi) < np.inf:
            return np.nan
        g_hi = _total(hi, part, fd, x, linear, offset, k0, k3, k, eta, cs, u, h, d)
        if g_hi != g_hi:
            return np.nan
        if d * g_hi >= 0.0:
            break
        lo, g_lo = hi, g_hi
        length *= 2.0
    else:
        return np.nan
    if g_hi == 0.0:
        return hi
    side = 0
    for _ in range(400):
        if abs(hi - lo) <= 4.0 * _EPS * max(abs(lo), abs(hi)) or abs(hi - lo) < 1e-300:
            break
        middle = (lo * g_hi - hi * g_lo) / (g_hi - g_lo) if g_hi != g_lo else 0.5 * (lo + hi)
        if not (min(lo, hi) < middle < max(lo, hi)) or side == 2:
            middle = 0.5 * (lo + hi)
        g = _total(middle, part, fd, x, linear, offset, k0, k3, k, eta, cs, u, h, d)
        if g != g:
            return np.nan
        if g == 0.0:
            return middle
        if d * g > 0.0:
            hi, g_hi = middle, g
            if side == 1:
                g_lo *= 0.5
            side = 1 if side != 1 else 2
        else:
            lo, g_lo = middle, g
            if side == -1:
                g_hi *= 0.5
            side = -1 if side != -1 else 2
    return lo if abs(g_lo) <= abs(g_hi) else hi
