"""The scalar equation of an implicit step, solved to rounding.

Every implicit update of the element reduces to one equation in the
increment w = x1 - x of the displacement,

    G(w) = linear w + offset + k0 (x+w) + k3 (x+w)^3 + sum_i k_i clip(u_i + w, -eta_i, eta_i) = 0,

(with series dashpots, the branch terms are k_i clip((u_i + w) / (1 + h k_i / c_i)): the same shape),

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
import math

import numpy as np

from .. import libm
from .._jit import kernel
from .play import branch_count
from .friction import sliding_force
from .series import branch_piece
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


NEWTON_STEPS = 200  # of _piece_root before it bisects
BISECTIONS = 2200  # halvings that exhaust the doubles between any two finite bounds


@kernel
def residual(w, x, linear, offset, k0, k3, k, eta, cs, u, h, direction):
    """G(w); the stiffness of the branches sticking beyond w in ``direction``; the room to the next kink.
    ``cs``: the series dashpots of the branches (None: plain branches), taken by the BACKWARD rule over h."""
    branches, sticking, room = branch_piece(k, eta, cs, u, w, h, direction)
    g = linear * w + offset + elastic_force(x + w, k0, k3) + branches
    return g, sticking, room


@kernel
def solve_increment(x, linear, offset, k0, k3, k, eta, cs, u, h):
    """The root w of G(w) = linear w + offset + k0 (x+w) + k3 (x+w)^3 + sum k_i clip(u_i + w).

    ``linear`` >= 0. The returned w is exact to rounding. G is non-decreasing;
    when it stays short of zero for ever (``linear`` = 0, no hardening spring
    and |offset| above the strength of the branches) there is no root and
    the result is NaN.
    """
    direction = 1.0
    g, sticking, room = residual(0.0, x, linear, offset, k0, k3, k, eta, cs, u, h, direction)
    if g == 0.0:
        return 0.0
    if g > 0.0:
        direction = -1.0
        g, sticking, room = residual(0.0, x, linear, offset, k0, k3, k, eta, cs, u, h, direction)
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
            g_jump, sticking_jump, room_jump = residual(jump, x, linear, offset, k0, k3, k, eta, cs, u, h, direction)
            if g_jump == 0.0:
                return jump
            if direction * g_jump < 0.0:
                lo, g, sticking, room = jump, g_jump, sticking_jump, room_jump
                continue
            hi = jump
        lo = end
        g, sticking, room = residual(lo, x, linear, offset, k0, k3, k, eta, cs, u, h, direction)
    return _bisect(x, linear, offset, k0, k3, k, eta, cs, u, h, direction, lo, hi)


@kernel
def _bisect(x, linear, offset, k0, k3, k, eta, cs, u, h, direction, lo, hi):
    """The root beyond ``lo`` by bisection on the doubles: direction G(lo) < 0, direction G(hi) > 0 (hi may
    be infinite: a bracket is found by doubling first). NaN when G has no root (collapse) or is not
    representable. Always terminates: at most ~2100 doublings and ~2100 halvings."""
    if not abs(hi) < np.inf:
        width = max(abs(lo), 1e-300)
        while True:
            trial = lo + direction * width
            if not abs(trial) < np.inf:
                return np.nan  # G stays short of zero up to the largest double: no representable root
            g = residual(trial, x, linear, offset, k0, k3, k, eta, cs, u, h, direction)[0]
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
        g = residual(middle, x, linear, offset, k0, k3, k, eta, cs, u, h, direction)[0]
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

    q is strictly increasing; q(lo) and q(hi) bracket zero. Newton, falling back on bisection whenever
    Newton would leave the bracket, until the bracket cannot shrink any more in floating point. Newton from
    a bracket of many decades creeps (a cubic's Newton steps shrink the distance by 2/3 each): past
    NEWTON_STEPS the bracket is first cut to the cubic's own bound, |w - lo| <= (4 |g_lo| / k3)^(1/3)
    (since a^3 - b^3 >= (a - b)^3 / 4 for a >= b), then halved to the rounding: at most BISECTIONS halvings
    (the doubles' range), never a silent unconverged w.
    """
    a, b = lo, hi  # q(a) has the sign of q(lo), q(b) the other
    w = lo
    q = g_lo
    for _ in range(NEWTON_STEPS):
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
    reach = libm.cbrt(4.0 * abs(g_lo) / abs(k3))
    if abs(b - lo) > reach:  # the cubic alone balances g_lo within reach of lo: b may come nearer
        b = lo + math.copysign(reach, b - lo)
    for _ in range(BISECTIONS):
        middle = a + 0.5 * (b - a)
        if middle == a or middle == b:
            return middle
        q = g_lo + slope_linear * (middle - lo) + _cubic_change(x, lo, middle, k3)
        if q == 0.0:
            return middle
        if (q > 0.0) == (g_lo > 0.0):
            a = middle
        else:
            b = middle
    return a + 0.5 * (b - a)  # (never reached: the doubles between a and b run out first)


@kernel
def _cubic_only_root(x, lo, g, k3):
    """Root of g + k3 ((x+w)^3 - (x+lo)^3), or NaN when there is no cubic spring (or k3 = 0)."""
    if k3 is None:
        return np.nan
    if k3 == 0.0:
        return np.nan
    return libm.cbrt((x + lo) ** 3 - g / k3) - x


_EPS = 2.220446049250313e-16
SETTLED = 2.0 ** -26  # a new position within this fraction of itself from the root is kept as it is
SETTLING = 4400  # evaluations of the settling's search: 2100 doublings, then halvings (see settle)


@kernel
def _residual_at(y, x1, w, linear, offset, k0, k3, k, eta, cs, u, h):
    """G at the position ``y`` near x1 = x + w: the smooth springs at y itself, the branches and the inertia at
    w + (y - x1) (x + that increment, rounded, may not hold y)."""
    moved = w + (y - x1)
    direction = 1.0 if moved >= 0.0 else -1.0  # (the branches' force does not depend on it)
    branches = branch_piece(k, eta, cs, u, moved, h, direction)[0]
    return linear * moved + offset + elastic_force(y, k0, k3) + branches


@kernel
def _between(lo, hi):
    """A point strictly between lo < hi that halves the doubles' span: the midpoint, or the geometric mean
    where they are of one sign and decades apart, or 0 across it; lo or hi when none is left."""
    if lo < 0.0 < hi:
        return 0.0
    a, b = abs(lo), abs(hi)
    small, large = min(a, b), max(a, b)
    if small == 0.0:
        middle = large * 2.0 ** -64 if large * 2.0 ** -64 > 0.0 else large * 0.5
    elif large > 4.0 * small:
        middle = math.sqrt(small) * math.sqrt(large)
    else:
        middle = small + 0.5 * (large - small)
    return middle if hi > 0.0 else -middle


@kernel
def settle(w, x, linear, offset, k0, k3, k, eta, cs, u, h):
    """The new position x1 = x + w of a solved increment w, settled where w cannot carry it.

    The solvers work on w = x1 - x and are exact to w's rounding, ulp(x): that is x1's error, nothing while
    |x1| is of the order of |x|. When x1 falls far below x in one step (the force dropped by 1e15 on a cubic
    spring; a coefficient changed by 1e100 mid-run) it may be: ulp(x) can exceed x1 itself (1e160 + w gave
    0 where x1 = 1e60), and the cubic's residual, taken relative to x, keeps only eps k3 x^3 of accuracy (a
    3e-3 error on x1 = 1 from x = 1e5). So when |x1| < |x| / 2 the step's equation is evaluated at x1
    itself (:func:`_residual_at`; ``offset`` holds every constant, the friction's and Dahl's forces too), and
    if x1 misses its root by more than SETTLED x1, the root is searched in x1 itself: G is non-decreasing
    there, so a bracket from x1 (steps doubling from G's own estimate, at most 2100) and halvings of the
    doubles between its ends (:func:`_between`: about 64) find it to rounding, within SETTLING evaluations;
    past them x1 is kept (never expected: the doubles run out first). Bit for bit x + w in every other step.
    x1 is kept only if its residual is small against a slope the root surely sees: the springs' and the
    inertia's, and the sticking branches' only if the root lies before their next kink in the step's own
    direction (the pieces are known in that direction only). The branches' elongations still move by w
    (an elongation as large as x keeps w's rounding: a limit, docs/stability.md).
    """
    x1 = x + w
    if not abs(x1) < 0.5 * abs(x):
        return x1
    g = _residual_at(x1, x1, w, linear, offset, k0, k3, k, eta, cs, u, h)
    if g == 0.0 or g != g:
        return x1
    d = -1.0 if g > 0.0 else 1.0  # the root lies beyond x1 in this direction
    forward = 1.0 if w >= 0.0 else -1.0  # the branches' piece is known in the direction of the step only
    _, sticking, room = branch_piece(k, eta, cs, u, w, h, forward)
    slope = _plus_spring(linear, k0) + _cubic_stiffness(x1, k3)  # the slope of G near x1, at least
    if d == forward and abs(g) <= room * (slope + sticking):
        slope += sticking  # the root lies before the next kink: the sticking branches hold there
    if abs(g) <= SETTLED * abs(x1) * slope:
        return x1  # a root to SETTLED of itself: kept, bit for bit
    reach = abs(g) / slope if slope > 0.0 else max(abs(x1), 1e-300)
    lo, hi, g_lo, g_hi = x1, x1, g, g  # d G(lo) < 0 <= d G(hi) once bracketed
    bracketed = False
    for _ in range(SETTLING):
        if not bracketed:
            trial = x1 + d * reach
            if not abs(trial) < np.inf:
                return x1  # no root below the largest double (never expected: the solver found one)
            g_trial = _residual_at(trial, x1, w, linear, offset, k0, k3, k, eta, cs, u, h)
            if g_trial != g_trial:
                return x1
            if d * g_trial < 0.0:
                lo, g_lo, reach = trial, g_trial, 2.0 * reach
                continue
            hi, g_hi, bracketed = trial, g_trial, True
            if g_trial == 0.0:
                return trial
            continue
        middle = _between(min(lo, hi), max(lo, hi))
        if middle == lo or middle == hi:  # adjacent doubles: the nearer to the root
            return lo if abs(g_lo) < abs(g_hi) else hi
        g_middle = _residual_at(middle, x1, w, linear, offset, k0, k3, k, eta, cs, u, h)
        if g_middle == 0.0:
            return middle
        if g_middle != g_middle:
            return x1
        if d * g_middle < 0.0:
            lo, g_lo = middle, g_middle
        else:
            hi, g_hi = middle, g_middle
    return x1


@kernel
def solve_held_increment(x, linear, offset, k0, k3, k, eta, cs, u, h, friction):
    """The increment w of an implicit step of a mass with friction on the ground: ``(w, resisted, stuck)``.

    w solves G(w) + A(w / h - v_b) ∋ 0 (G of :func:`solve_increment`, ``linear`` > 0: the mass's m / h^2 at
    least; A the friction law of ``kernels/friction.py``, all of it at the new velocity); ``resisted`` is the
    value of A taken (N; the friction force on the mass is its opposite).

    * The mass sticks, w = h v_b, when |G(h v_b)| <= alpha (then A = -G(h v_b)).
    * Otherwise it slides in the direction d = -sign G(h v_b). With plain Coulomb friction A = d alpha
      is a constant: :func:`solve_increment` with the offset moved by d alpha, exact to rounding.
    * With Stribeck's drop, phi(r) = d G(h v_b + d r) + g(r / h) (g the sliding force, r >= 0 the slip over
      the step) starts below 0 and is increasing wherever the drop g' is gentler than ``linear``: beyond
      r_c = h v_S ln((alpha - alpha_kinetic) / (v_S h linear)), always; below r_c it may cross 0 several
      times. **The rule: the root of least slip** (the first crossing from the stick, what a mass that
      starts to slide meets first). Below r_c it is found by bounds that are proofs: on [a, b],
      phi >= d G(a') + g(b / h) and phi <= d G(b') + g(a / h) (d G increases, g decreases), so an interval
      whose upper bound is < 0 holds no root and is skipped; one that may hold one is halved down to the
      rounding of w. Beyond r_c (or from the start when the drop is never steeper than ``linear``, the case
      the stability check does not warn about) the root is unique: bracketed, then Illinois to rounding.
    """
    alpha, kinetic, stribeck, belt = friction
    stuck_at = h * belt
    g_stuck = residual(stuck_at, x, linear, offset, k0, k3, k, eta, cs, u, h, 1.0)[0]
    if abs(g_stuck) <= alpha:
        return stuck_at, -g_stuck, True
    if g_stuck != g_stuck:
        return np.nan, 0.0, False
    d = -math.copysign(1.0, g_stuck)
    if kinetic == alpha:
        w = solve_increment(x, linear, offset + d * alpha, k0, k3, k, eta, cs, u, h)
        if d * (w - stuck_at) < 0.0:  # rounding only: the root is within an ulp of the stick
            w = stuck_at
        return w, d * alpha, False
    drop = (alpha - kinetic) / (stribeck * h)  # the steepest slope of g(r / h) in r
    a = 0.0
    phi_a = -abs(g_stuck) + alpha
    if drop > linear:
        r_c = h * stribeck * libm.log(drop / linear)
        length = r_c / 16.0
        while a < r_c:
            b = min(a + length, r_c)
            p_b = d * residual(stuck_at + d * b, x, linear, offset, k0, k3, k, eta, cs, u, h, d)[0]
            if p_b + sliding_force(friction, a / h) < 0.0:  # phi < 0 on all of [a, b]
                a, phi_a = b, p_b + sliding_force(friction, b / h)
                length *= 2.0
                continue
            if b - a <= 4.0 * _EPS * max(abs(stuck_at + d * b), b):  # at the rounding of w
                phi_b = p_b + sliding_force(friction, b / h)
                if phi_b >= 0.0:
                    return stuck_at + d * b, d * sliding_force(friction, b / h), False
                a, phi_a = b, phi_b
                length = 4.0 * _EPS * max(abs(stuck_at + d * b), b) + 1e-300
                continue
            length = 0.5 * (b - a)
    # phi increases on [a, inf) and phi(a) < 0: bracket the root by doubling, then Illinois
    lo, phi_lo = a, phi_a
    length = max(-phi_a / linear, 1e-300)
    while True:
        hi = lo + length
        if not hi < np.inf:
            return np.nan, 0.0, False
        phi_hi = d * residual(stuck_at + d * hi, x, linear, offset, k0, k3, k, eta, cs, u, h, d)[0] \
            + sliding_force(friction, hi / h)
        if phi_hi != phi_hi:
            return np.nan, 0.0, False
        if phi_hi >= 0.0:
            break
        lo, phi_lo = hi, phi_hi
        length *= 2.0
    side = 0
    while hi - lo > 4.0 * _EPS * max(abs(stuck_at + d * hi), hi):
        middle = (lo * phi_hi - hi * phi_lo) / (phi_hi - phi_lo) if phi_hi != phi_lo else 0.5 * (lo + hi)
        if not (lo < middle < hi):
            middle = 0.5 * (lo + hi)
        if not (lo < middle < hi):
            break
        phi_middle = d * residual(stuck_at + d * middle, x, linear, offset, k0, k3, k, eta, cs, u, h, d)[0] \
            + sliding_force(friction, middle / h)
        if phi_middle >= 0.0:
            hi, phi_hi = middle, phi_middle
            if side == 1:
                phi_lo *= 0.5
            side = 1
        else:
            lo, phi_lo = middle, phi_middle
            if side == -1:
                phi_hi *= 0.5
            side = -1
    return stuck_at + d * hi, d * sliding_force(friction, hi / h), False
