"""``implicit``: backward Euler on the whole inclusion (every term at t_{p+1}).

Not to be confused with what the papers call "the implicit Euler scheme",
which is our ``projected`` (implicit only in the multivalued term). Here

    x1 = x + h v1
    m (v1 - v) / h = F(t_{p+1}) - k0 x1 - k3 x1^3 - c v1 - sum_i k_i u1_i
    u1_i = clip(u_i + h v1, -eta_i, eta_i)

With the increment w = x1 - x = h v1 this is one scalar equation G(w) = 0,

    G(w) = (m/h^2 + c/h) w - m v/h + k0 (x+w) + k3 (x+w)^3
           + sum_i k_i clip(u_i + w, -eta_i, eta_i) - F(t_{p+1}),

strictly increasing in w and smooth between the kinks w = ±eta_i - u_i
(piecewise linear without the cubic spring). It is solved to rounding by
:func:`solve_increment`: the sign of G(0) gives the direction; from the left
end of the current smooth piece, the piece's own root is taken exactly
(linear) or by safeguarded Newton (cubic); if it lies beyond the next kink,
the solver jumps over all kinks below the piece's tangent root at once when G
is still negative there, or else moves to the next kink. No tolerance is
involved except rounding.

Order 1. Unconditionally stable: with no load the discrete energy
m v^2/2 + k0 x^2/2 + k3 x^4/4 + sum_i k_i u_i^2/2 never increases, for any h
(backward Euler on a monotone inclusion with convex potentials).
"""
import numpy as np

from .._jit import kernel
from ..kernels.play import piece, shift
from ..kernels.smooth import elastic_force
from ..loads import force_at

ORDER = 1


@kernel
def step(model, load, t, h, x, v, s, u):
    m, k0, k3, c, k, eta = model
    linear = _plus_damping(m / (h * h), c, h)
    offset = -m * v / h - force_at(load, t + h)
    w = solve_increment(x, linear, offset, k0, k3, k, eta, u)
    s = shift(k, eta, u, w)
    return x + w, w / h, s


@kernel
def _plus_damping(value, c, h):
    """value + c / h; just value without a dashpot."""
    if c is None:
        return value
    return value + c / h


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

    ``linear`` > 0. The returned w is exact to rounding.
    """
    direction = 1.0
    g, sticking, room = residual(0.0, x, linear, offset, k0, k3, k, eta, u, direction)
    if g == 0.0:
        return 0.0
    if g > 0.0:
        direction = -1.0
        g, sticking, room = residual(0.0, x, linear, offset, k0, k3, k, eta, u, direction)
    lo = 0.0  # direction * G(lo) < 0: the root lies beyond lo
    hi = direction * np.inf  # direction * G(hi) > 0
    n = 0 if k is None else k.shape[0]
    for _ in range(4 * n + 64):
        if direction * g >= 0.0:  # zero, or past zero by rounding only
            return lo
        end = lo + direction * room  # next kink: the smooth piece is [lo, end]
        if end == lo:
            end = np.nextafter(lo, hi)
        last_piece = direction * (end - hi) >= 0.0  # the root is in this piece
        if last_piece:
            end = hi
        # Root of the piece without the growth of the cubic term: the cubic
        # only adds a term of the sign of (w - lo), so the piece's root lies
        # between lo and this one.
        slope_linear = _plus_spring(linear + sticking, k0)
        tangent_root = lo - g / slope_linear
        if k3 is None:
            if direction * (tangent_root - end) <= 0.0:
                return tangent_root
            if last_piece:  # only rounding can put the tangent root beyond hi
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
    raise RuntimeError("implicit step: the scalar solve did not terminate")


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
            return trial  # Newton's step is at the rounding level: converged
        w = trial
        q = g_lo + slope_linear * (w - lo) + _cubic_change(x, lo, w, k3)
        if q == 0.0:
            return w
        if (q > 0.0) == (g_lo > 0.0):
            a = w
        else:
            b = w
    return w
