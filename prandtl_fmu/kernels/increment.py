"""The scalar equation of an implicit step, solved to rounding.

Every implicit update of the element reduces to one equation in the
increment w = x1 - x of the displacement,

    G(w) = linear w + offset + k0 (x+w) + k3 (x+w)^3 + sum_i k_i clip(u_i + w, -eta_i, eta_i) = 0,

with ``linear`` >= 0 (m/h^2 + c/h for backward Euler; 0 for the quasi-static
massless element). G is non-decreasing and smooth between the kinks
w = ±eta_i - u_i (piecewise linear without the cubic spring).
:func:`solve_increment`: the sign of G(0) gives the direction; from the left
end of the current smooth piece, the piece's own root is taken exactly
(linear) or by safeguarded Newton (cubic); if it lies beyond the next kink,
the solver jumps over all kinks below the piece's Newton point at once when G
is still short of zero there, or else moves to the next kink. No tolerance is
involved except rounding.
"""
import numpy as np

from .._jit import kernel
from .play import branch_count, piece
from .smooth import elastic_force


@kernel
def _plus_spring(value, k0):
    """value + k0; just value without a linear spring."""
    if k0 is None:
        return value
    return value + k0


@kernel
def _cubic_stiffness(x, k3):
    """3 k3 x^2, or 0 without a cubic spring."""
    if k3 is None:
        return 0.0
    return 3.0 * k3 * x * x


@kernel
def _cubic_change(x, a, b, k3):
    """k3 ((x+b)^3 - (x+a)^3), without cancellation; 0 without a cubic spring."""
    if k3 is None:
        return 0.0
    xa, xb = x + a, x + b
    return k3 * (b - a) * (xb * xb + xb * xa + xa * xa)


@kernel
def residual(w, x, linear, offset, k0, k3, k, eta, u, direction):
    """G(w); the stiffness of the branches sticking beyond w in ``direction``; the room to the next kink."""
    branches, sticking, room = piece(k, eta, u, w, direction)
    g = linear * w + offset + elastic_force(x + w, k0, k3) + branches
    return g, sticking, room


@kernel
def solve_increment(x, linear, offset, k0, k3, k, eta, u):
    """The root w of G(w) = linear w + offset + k0 (x+w) + k3 (x+w)^3 + sum k_i clip(u_i + w).

    ``linear`` >= 0. The returned w is exact to rounding. G is non-decreasing;
    when it stays short of zero for ever (``linear`` = 0, no hardening spring
    and |offset| above the strength of the branches) there is no root and
    the result is NaN.
    """
    direction = 1.0
    g, sticking, room = residual(0.0, x, linear, offset, k0, k3, k, eta, u, direction)
    if g == 0.0:
        return 0.0
    if g > 0.0:
        direction = -1.0
        g, sticking, room = residual(0.0, x, linear, offset, k0, k3, k, eta, u, direction)
    if g != g:
        return np.nan
    lo = 0.0  # direction * G(lo) < 0: the root lies beyond lo
    hi = direction * np.inf  # direction * G(hi) > 0
    crawl = 0
    for _ in range(4 * max(branch_count(k), 0) + 64):
        if g != g:  # not representable (overflow)
            return np.nan
        if direction * g >= 0.0:  # zero, or past zero by rounding only
            return lo
        end = lo + direction * room  # next kink: the smooth piece is [lo, end]
        if end == lo:
            crawl += 1
            if crawl > 8:  # rounding stalls the walk: bisect instead
                break
            end = np.nextafter(lo, hi)
        last_piece = direction * (end - hi) >= 0.0  # the root is in this piece
        if last_piece:
            end = hi
        # Root of the piece without the growth of the cubic term: the cubic
        # only adds a term of the sign of (w - lo), so the piece's root lies
        # between lo and this one.
        slope_linear = _plus_spring(linear + sticking, k0)
        if slope_linear == 0.0:
            # No inertia, dashpot, linear spring or sticking branch: beyond lo
            # only the cubic spring (if any) can still balance G.
            return _cubic_only_root(x, lo, g, k3)
        tangent_root = lo - g / slope_linear
        if k3 is None:
            if direction * (tangent_root - end) <= 0.0:
                return tangent_root
            if last_piece:  # only rounding can put the tangent root beyond hi
                return end
        elif k3 == 0.0:  # a cubic spring with k3 = 0: the same straight pieces (no Newton iterations)
            if direction * (tangent_root - end) <= 0.0:
                return tangent_root
            if last_piece:
                return end
        else:
            if direction * (tangent_root - end) <= 0.0 or last_piece:
                stop = tangent_root if direction * (tangent_root - end) <= 0.0 else end
                return _piece_root(x, lo, stop, g, slope_linear, k3)
            q_end = g + slope_linear * (end - lo) + _cubic_change(x, lo, end, k3)
            if direction * q_end >= 0.0:
                return _piece_root(x, lo, end, g, slope_linear, k3)
        # The root lies beyond the kink at `end`. Jump over every kink up to
        # the Newton point if G is still short of zero there (always the case
        # without the cubic spring: G is concave in the direction of motion).
        jump = lo - g / (slope_linear + _cubic_stiffness(x + lo, k3))
        if direction * (jump - end) > 0.0 and direction * (jump - hi) < 0.0:
            g_jump, sticking_jump, room_jump = residual(jump, x, linear, offset, k0, k3, k, eta, u, direction)
            if g_jump == 0.0:
                return jump
            if direction * g_jump < 0.0:
                lo, g, sticking, room = jump, g_jump, sticking_jump, room_jump
                continue
            hi = jump
        lo = end
        g, sticking, room = residual(lo, x, linear, offset, k0, k3, k, eta, u, direction)
    return _bisect(x, linear, offset, k0, k3, k, eta, u, direction, lo, hi)


@kernel
def _bisect(x, linear, offset, k0, k3, k, eta, u, direction, lo, hi):
    """The root beyond ``lo`` by bisection on the doubles: direction G(lo) < 0, direction G(hi) > 0 (hi may
    be infinite: a bracket is found by doubling first). NaN when G has no root (collapse) or is not
    representable. Always terminates: at most ~2100 doublings and ~2100 halvings."""
    if not abs(hi) < np.inf:
        width = max(abs(lo), 1e-300)
        while True:
            trial = lo + direction * width
            if not abs(trial) < np.inf:
                return np.nan  # G stays short of zero up to the largest double: no representable root
            g = residual(trial, x, linear, offset, k0, k3, k, eta, u, direction)[0]
            if g != g:
                return np.nan
            if direction * g >= 0.0:
                hi = trial
                break
            lo = trial
            width *= 2.0
    while True:
        middle = lo + 0.5 * (hi - lo)
        if middle == lo or middle == hi:
            return lo
        g = residual(middle, x, linear, offset, k0, k3, k, eta, u, direction)[0]
        if g != g:
            return np.nan
        if g == 0.0:
            return middle
        if direction * g < 0.0:
            lo = middle
        else:
            hi = middle


@kernel
def _piece_root(x, lo, hi, g_lo, slope_linear, k3):
    """Root of q(w) = g_lo + slope_linear (w - lo) + k3((x+w)^3 - (x+lo)^3) on [lo, hi].

    q is strictly increasing; q(lo) and q(hi) bracket zero. Newton, falling
    back on bisection whenever Newton would leave the bracket, until the
    bracket cannot shrink any more in floating point.
    """
    a, b = lo, hi  # q(a) has the sign of q(lo), q(b) the other
    w = lo
    q = g_lo
    for _ in range(200):
        dq = slope_linear + 3.0 * k3 * (x + w) * (x + w)
        trial = w - q / dq
        if not ((trial - a) * (trial - b) < 0.0):
            trial = 0.5 * (a + b)
        if abs(trial - w) <= 4.4e-16 * abs(trial) or trial == a or trial == b:
            return trial  # Newton's step, or the bracket, is at the rounding level of w or x + w: converged
        w = trial
        q = g_lo + slope_linear * (w - lo) + _cubic_change(x, lo, w, k3)
        if q == 0.0:
            return w
        if (q > 0.0) == (g_lo > 0.0):
            a = w
        else:
            b = w
    return w


@kernel
def _cubic_only_root(x, lo, g, k3):
    """Root of g + k3 ((x+w)^3 - (x+lo)^3), or NaN when there is no cubic spring (or k3 = 0)."""
    if k3 is None:
        return np.nan
    if k3 == 0.0:
        return np.nan
    return np.cbrt((x + lo) ** 3 - g / k3) - x
