"""``exact`` for branches with series dashpots (the series model, eq. 15 of ``004``): closed form between events.

A branch with a dashpot c_i in series with its spring k_i and slider (threshold k_i eta_i) has an elongation
u_i that relaxes while the slider sticks, u_i' = v - lambda_i u_i (lambda_i = k_i / c_i), and stays at
+-eta_i while the slider slips, which it does while the flow pushes outwards: sign(u_i)(v - lambda_i u_i) > 0.
Between two events the set of slipping branches is fixed, so the element with its load is the linear system
y' = A y of dimension 6 + n:

    y = (xi, v, load (2 states), load and the spring's force at the phase's start / m, the friction / m, u_1..u_n)

with xi = x - x(t_e) (lengths stay exact relative to the phase's start), the harmonic or ramp part of the load
generated as in ``exact.py``, and y(tau) = expm(A tau) y(0) (``exact_common._expm_times``: one scaled Taylor series
for every case, A holding only rates). Friction on the mass (plain Coulomb on a fixed ground) adds the
constant force -alpha sign(v) while the mass slides; while it sticks (v = 0, x frozen) the branches still
relax, so the net force F(t) - reaction(t) moves and the stick ends where it leaves [-alpha, alpha].

Events are the zeros of linear functionals g_j(tau) = l_j . y(tau) - level_j, each negative while its phase
lasts: a sticking branch reaches +-eta_i (it slips from then on); a slipping branch's inflow
sign(u_i)(v - lambda_i u_i) reaches 0 (it sticks again: v = lambda_i eta_i, not a reversal of v); with
friction, v reaches 0 (the mass may stick), or at rest F - reaction reaches +-alpha. Unlike the Prandtl
branch, a reversal of v is no event for the branches.

Why no event can be missed: validated subdivision, as ``exact.py`` does for harmonic loads, for every
functional at once. On [a, a + L], |g_j^(p)(a + s)| <= |l_j A^p| e^(|A| L) |y(a)| (weighted max norms), so
g_j(a) < -L max|g_j'| proves no zero of g_j, and |g_j'(a)| > L max|g_j''| proves g_j monotone (a sign test at
a + L decides), as does a curvature that keeps its sign (|g_j''(a)| > L max|g_j^(3)|) with the slope growing
away from 0; a concave g_j from g_j(a) <= 0, g_j'(a) <= 0 stays <= 0 (this decides in O(1) intervals a
functional that starts on its level and leaves it tangentially). Otherwise the interval is halved, down to
the rounding level of t where signs decide. Among
the functionals that change sign on the interval, each zero is located by Illinois' method and the first is
the event; every functional positive there fires with it (branches of equal thresholds).

The bounds are also taken through |A y(a)| (g_j^(p) = l_j A^(p-1) e^(A s) A y(a)), whichever is smaller: where
the state barely moves (a net force that tends to the threshold as the branches relax, a fixed point) they
vanish with the motion, and the walk takes O(1) intervals per relaxation time instead of crawling at the
rounding of the load's size (issue 31, item 2). A phase with A y0 = 0 is a fixed point: no event.

The mode of a branch on its threshold at the start of a phase: it slips if its inflow is positive, or zero
with a positive derivative (sign(u_i) v' > 0); otherwise it sticks. A branch of elastic range 0 (u_i = 0 on
both thresholds) slips to the side of v, else of v', and sticks only with no flow (issue 31, item 1: it
stuck, fired its level at once, stuck again, ... for ever). An event is a sign change beyond the rounding of
g_j's terms (8 ulps), so a branch that has just stuck on its threshold, or creeps exactly at v = lambda_i eta_i,
fires nothing. Events at one instant are finitely many: more than 16 + 4 n phases in a row that do not
advance t fail the step, as do the budgets of ``exact.py`` (phases per simulated second, walk intervals per event, refinement
iterations): the driver reports a failed step, never a silent stop, never a loop.

The cost of a phase is a few dozen (6 + n)-square matrix exponentials per interval of the walk, whose length
is at most 1 / |A| (no energy bound for long quiet stretches here, unlike the 6 x 6 case): O(n^3) per
exponential, meant for the few branches a series model has. The energy account is booked exactly, phase by
phase, from the Gramian int y y^T of the phase (:func:`_book`).
"""
import math

import numpy as np

from .. import libm
from .._jit import inline_kernel, kernel
from ..kernels.batch import summary_loop
from ..kernels.loop import time_loop
from ..kernels.play import branch_force
from ..loads import CONSTANT, HARMONIC, force_at
from .exact_common import (_EPS, ILLINOIS_LIMIT, NOT_FINITE, REFINE_LIMIT, SEARCH_EXHAUSTED, STALLED,
                           TOO_MANY_PHASES, TOOK_STEP, WALK_BUDGET, phase_budget, _damping, _expm_times,
                           _linear_spring, _motion, _next_break, _restore, _saved, _threshold, explain)

XI, V, LOAD_VARYING, LOAD_RATE, LOAD_CONSTANT, FRICTION, BRANCH0 = 0, 1, 2, 3, 4, 5, 6
# what an event does: a sticking branch slips (up, down), a slipping one sticks, the mass stops, it is released
UP, DOWN, STOPS, REVERSAL, RELEASE = 0, 1, 2, 3, 4
EXHAUSTED = -2  # an event search over its budget


@kernel
def _system(m, k0, c, k, rate, load, t, x, v, u, direction, alpha, stuck, slipping):
    """A and y(0) of the phase from time t; ``stuck``: the mass sticks (v = 0, x frozen), ``direction`` the
    sign of its motion (the friction's sign), ``slipping[i]``: 1 or -1 where branch i slips at +-eta_i, 0 where it sticks."""
    n = k.shape[0]
    size = BRANCH0 + n
    a = np.zeros((size, size))
    y0 = np.zeros(size)
    kind, offset, amplitude, omega, times, forces = load
    if not stuck:
        a[XI, V] = 1.0
        a[V, XI] = -_linear_spring(k0) / m
        a[V, V] = -_damping(c) / m
        a[V, LOAD_VARYING] = 1.0
        a[V, LOAD_CONSTANT] = 1.0
        a[V, FRICTION] = 1.0
        for i in range(n):
            a[V, BRANCH0 + i] = -k[i] / m
    spring = _linear_spring(k0) * x
    if kind == HARMONIC:  # (amplitude / m) (cos, sin)(omega t), rotating
        a[LOAD_VARYING, LOAD_RATE] = -omega
        a[LOAD_RATE, LOAD_VARYING] = omega
        sine, cosine = libm.sincos(omega * t)
        y0[LOAD_VARYING] = amplitude / m * cosine
        y0[LOAD_RATE] = amplitude / m * sine
        y0[LOAD_CONSTANT] = (offset - spring) / m
    elif kind == CONSTANT:
        y0[LOAD_CONSTANT] = (offset - spring) / m
    else:  # a piece of a table: the ramp (slope / m) tau and its rate
        j = np.searchsorted(times, t, side="right")
        if 0 < j < times.shape[0]:
            y0[LOAD_RATE] = (forces[j] - forces[j - 1]) / (times[j] - times[j - 1]) / m
        a[LOAD_VARYING, LOAD_RATE] = 1.0
        y0[LOAD_CONSTANT] = (force_at(load, t) - spring) / m
    y0[V] = v
    y0[FRICTION] = -alpha * direction / m
    for i in range(n):
        y0[BRANCH0 + i] = u[i]
        if not slipping[i]:
            a[BRANCH0 + i, V] = 1.0
            a[BRANCH0 + i, BRANCH0 + i] = -rate[i]
    return a, y0


@kernel
def _events(k, eta, rate, m, alpha, direction, stuck, slipping, size):
    """The phase's event functionals: rows of ``ell`` with their ``level``, ``what`` happens and to which
    branch (``whom``)."""
    # with the mass stuck (v = 0) every branch sticks and relaxes, u_i' = -lambda_i u_i: |u_i| never grows, so no
    # level can be reached before the mass moves (its release is the phase's event). A branch of range 0 sits
    # exactly on both levels there, its functionals identically 0, which no walk can decide: the search ran out
    # of its 100 000 intervals (a review's find: friction beside a branch k = 1, eta = 0, c = 2)
    n = 0 if stuck else k.shape[0]
    count = 0
    for i in range(n):
        count += 1 if slipping[i] else 2
    if alpha > 0.0:
        count += 2 if stuck else 1
    ell = np.zeros((count, size))
    level = np.zeros(count)
    what = np.zeros(count, dtype=np.int64)
    whom = np.zeros(count, dtype=np.int64)
    j = 0
    for i in range(n):
        if slipping[i]:  # sticks again when the inflow sign(u_i) (v - lambda_i u_i) reaches 0
            sign = float(slipping[i])
            ell[j, V] = -sign
            ell[j, BRANCH0 + i] = sign * rate[i]
            what[j], whom[j] = STOPS, i
            j += 1
        else:
            ell[j, BRANCH0 + i] = 1.0
            level[j] = eta[i]
            what[j], whom[j] = UP, i
            ell[j + 1, BRANCH0 + i] = -1.0
            level[j + 1] = eta[i]
            what[j + 1], whom[j + 1] = DOWN, i
            j += 2
    if alpha > 0.0:
        if stuck:  # (F - reaction) / m = load states - sum (k_i / m) u_i (x frozen) leaves [-alpha, alpha] / m
            for sign in (1.0, -1.0):
                ell[j, LOAD_VARYING] = sign
                ell[j, LOAD_CONSTANT] = sign
                for i in range(k.shape[0]):
                    ell[j, BRANCH0 + i] = -sign * k[i] / m
                level[j] = alpha / m
                what[j] = RELEASE
                j += 1
        else:
            ell[j, V] = -direction
            what[j] = REVERSAL
    return ell, level, what, whom


@kernel
def _value(ell, j, y):
    total = 0.0
    for i in range(y.shape[0]):
        total += ell[j, i] * y[i]
    return total


@kernel
def _excess(ell, j, y, level):
    """g_j = ell[j] . y - level beyond its rounding (a few ulps of its terms): > 0 only for a real crossing. A
    functional that starts at 0 and moves inwards (a branch that has just stuck on its threshold) must not
    fire on the noise of the matrix exponential."""
    total = 0.0
    size = abs(level)
    for i in range(y.shape[0]):
        term = ell[j, i] * y[i]
        total += term
        size += abs(term)
    return total - level - 8.0 * _EPS * size


@kernel
def _first_event(a, y0, ell, level, t, span, rho, budget):
    """(tau, j): the first sign change of ``ell[j] . y - level[j]`` (beyond rounding: :func:`_excess`) in
    (0, span], or (span, -1); (span, EXHAUSTED) when the step's ``budget`` of intervals (counted down) ran
    out. ``t``: the phase's start (the rounding level of tau), ``rho`` its rate (1/s)."""
    count, size = ell.shape
    if count == 0:
        return span, -1
    weights = np.empty(size)  # lengths 1, velocities 1/rho, accelerations 1/rho^2 (see exact._scales)
    balance = min(max(rho, 1e-100), 1e100)
    for i in range(size):
        weights[i] = 1.0
    weights[V] = 1.0 / balance
    for i in range(LOAD_VARYING, BRANCH0):
        weights[i] = 1.0 / (balance * balance)
    norm = 0.0
    for i in range(size):
        row = 0.0
        for j in range(size):
            row += abs(a[i, j]) * weights[i] / weights[j]
        norm = max(norm, row)
    slope = _matmul_rows(ell, a)  # l_j A, l_j A^2, l_j A^3: the first three derivatives of g_j, and their bounds
    curve = _matmul_rows(slope, a)
    third = _matmul_rows(curve, a)
    bound1 = np.zeros(count)
    bound2 = np.zeros(count)
    bound3 = np.zeros(count)
    for j in range(count):
        for i in range(size):
            bound1[j] += abs(slope[j, i]) / weights[i]
            bound2[j] += abs(curve[j, i]) / weights[i]
            bound3[j] += abs(third[j, i]) / weights[i]
    bound0 = np.zeros(count)  # |l_j| in the weighted norm: g_j^(p) = l_j A^(p-1) e^(A s) (A y) also bounds
    for j in range(count):
        for i in range(size):
            bound0[j] += abs(ell[j, i]) / weights[i]
    longest = 1.0 / max(norm, 1e-300)
    lo = 0.0
    length = min(span, longest)
    if not np.any(_matvec(a, y0)):
        return span, -1  # a fixed point (A y0 = 0): every g_j is constant, nothing happens in the phase
    while lo < span:
        budget[0] -= 1
        if budget[0] < 0:
            return span, EXHAUSTED  # the step's budget ran out: the step fails
        y = _expm_times(a, lo, y0)
        b = min(span, lo + length)
        length = b - lo
        ay = _matvec(a, y)
        size_y = 0.0
        rate_y = 0.0
        for i in range(size):
            size_y = max(size_y, abs(y[i]) * weights[i])
            rate_y = max(rate_y, abs(ay[i]) * weights[i])
        spread = libm.exp(norm * length)
        rounding = 8.0 * _EPS * (abs(t) + lo + 1.0 / rho)
        decided = True
        for j in range(count):
            # bounds of the first three derivatives of g_j on [lo, b], through |y| or |A y|, whichever is smaller
            # (|A y| vanishes where the state barely moves: a net force tending to the threshold as branches relax)
            first = spread * min(bound1[j] * size_y, bound0[j] * rate_y)
            second = spread * min(bound2[j] * size_y, bound1[j] * rate_y)
            third = spread * min(bound3[j] * size_y, bound2[j] * rate_y)
            g = _value(ell, j, y) - level[j]
            if g < -length * first:
                continue  # no zero of g_j on [lo, b]
            d1 = _beyond_rounding(slope, j, y)
            if abs(d1) > length * second or length <= rounding:
                continue  # g_j monotone on [lo, b] (or the interval is at rounding): its sign at b decides
            d2 = _value(curve, j, y)
            if abs(d2) > length * third and ((d2 < 0.0 and g <= 0.0 and d1 <= 0.0) or d2 * d1 >= 0.0):
                # the curvature keeps its sign on [lo, b]: concave from g <= 0 going down, g stays <= 0 (a
                # functional that starts on its level and leaves it inwards: a branch that has just stuck on its
                # threshold, the mass released at net force +-alpha); a slope that grows away from 0 keeps its
                # sign (monotone: the sign at b decides)
                continue
            decided = False
            break
        if not decided:
            length *= 0.5
            continue
        y_b = _expm_times(a, b, y0)
        best, which = span, -1
        for j in range(count):
            if _excess(ell, j, y_b, level[j]) > 0.0:
                tau = _refine(a, y0, ell, j, level[j], lo, b)
                if which < 0 or tau < best:
                    best, which = tau, j
        if which >= 0:
            return best, which
        lo = b
        length = min(2.0 * length, longest)
    return span, -1


@kernel
def _matvec(a, y):
    out = np.zeros(a.shape[0])
    for i in range(a.shape[0]):
        total = 0.0
        for j in range(a.shape[1]):
            total += a[i, j] * y[j]
        out[i] = total
    return out


@kernel
def _beyond_rounding(rows, j, y):
    """rows[j] . y, or 0 when it is within the rounding of its terms (8 ulps): the slope of a functional at
    a release from a stick (net force +-alpha to rounding) is 0, not the noise of its sum."""
    total = 0.0
    size = 0.0
    for i in range(y.shape[0]):
        term = rows[j, i] * y[i]
        total += term
        size += abs(term)
    if abs(total) <= 8.0 * _EPS * size:
        return 0.0
    return total


@kernel
def _matmul_rows(rows, a):
    out = np.zeros(rows.shape)
    for j in range(rows.shape[0]):
        for i in range(a.shape[0]):
            r = rows[j, i]
            if r != 0.0:
                for col in range(a.shape[1]):
                    out[j, col] += r * a[i, col]
    return out


@kernel
def _refine(a, y0, ell, j, level, lo, hi):
    """The tau in (lo, hi] where :func:`_excess` turns > 0, to rounding (Illinois); it is > 0 at hi."""
    g_lo = _excess(ell, j, _expm_times(a, lo, y0), level)
    g_hi = _excess(ell, j, _expm_times(a, hi, y0), level)
    side = 0
    for iteration in range(REFINE_LIMIT):  # Illinois, then bisection: bounded (see exact._refine)
        if not hi - lo > 4.0 * _EPS * hi:
            break
        mid = 0.5 * (lo + hi)
        if g_hi != g_lo and iteration < ILLINOIS_LIMIT:
            mid = (lo * g_hi - hi * g_lo) / (g_hi - g_lo)
        if not (lo < mid < hi):
            mid = 0.5 * (lo + hi)
        if not (lo < mid < hi):
            break
        g_mid = _excess(ell, j, _expm_times(a, mid, y0), level)
        if g_mid > 0.0:
            hi, g_hi = mid, g_mid
            if side == 1:
                g_lo *= 0.5
            side = 1
        else:
            lo, g_lo = mid, g_mid
            if side == -1:
                g_hi *= 0.5
            side = -1
    return hi


@kernel
def _slipping(k, eta, rate, m, c, k0, load, t, x, v, u, direction, alpha, stuck):
    """Which branches slip from now on (1 at +eta, -1 at -eta, 0 sticking): those on their threshold whose
    inflow sign(u_i) (v - lambda_i u_i) is positive, or zero with sign(u_i) v' > 0."""
    n = k.shape[0]
    out = np.zeros(n, dtype=np.int64)
    if stuck:
        return out  # v = 0: every inflow is -lambda_i eta_i < 0
    acceleration = (force_at(load, t) - _linear_spring(k0) * x - _damping(c) * v - alpha * direction
                    - branch_force(k, u)) / m
    for i in range(n):
        if abs(u[i]) < eta[i]:
            continue
        # on its threshold; u = 0 only for eta = 0, whose side is where the flow goes: v, else v'
        sign = 1.0 if u[i] > 0.0 else -1.0
        if u[i] == 0.0:
            if v == 0.0 and acceleration == 0.0:
                continue  # no flow: it sticks (and carries nothing, u = 0)
            sign = math.copysign(1.0, v if v != 0.0 else acceleration)
        inflow = sign * (v - rate[i] * u[i])
        if inflow > 0.0 or (inflow == 0.0 and sign * acceleration > 0.0):
            out[i] = 1 if sign > 0.0 else -1
    return out


@inline_kernel  # a thin wrapper of attempt (_jit.inline_kernel: a kernel of its own would optimise attempt again)
def step(model, load, t, h, x, v, s, u, energy):
    """One exact step from t to t + h (:func:`attempt`); a failed step returns a non-finite x with u and the
    energy account as they were."""
    x1, v1, failure, when = attempt(model, load, t, h, x, v, u, energy)
    if failure != TOOK_STEP:
        return np.nan, np.nan, branch_force(model[4], u)  # reported by the driver: never a silent stop
    return x1, v1, branch_force(model[4], u)


@kernel
def attempt(model, load, t, h, x, v, u, energy):
    """The exact motion from t to t + h: (x, v, failure, when), as ``exact.attempt`` (the same budgets and
    failures; at most 16 + 4 n phases in a row that do not advance t)."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    saved_u = _saved(u)
    saved_energy = _saved(energy)
    alpha = _threshold(friction)
    n = k.shape[0]
    rate = k / cs
    end = t + h
    stalled = 0
    stall_limit = 16 + 4 * n
    released = False  # a stick just ended with the net force at the threshold: slide now
    failure = TOOK_STEP
    phases = 0
    most_phases = phase_budget(h)
    budget = np.full(1, WALK_BUDGET)  # the intervals the search for the next event may take
    while t < end:  # phases; each ends at an event, a load kink or t + h
        phases += 1
        budget[0] = WALK_BUDGET
        if phases > most_phases:
            failure = TOO_MANY_PHASES
            break
        span = min(end, _next_break(load, t)) - t
        stuck = False
        direction = 0.0
        if v != 0.0:
            direction = math.copysign(1.0, v)
        elif alpha > 0.0:  # at rest: the mass sticks while |F - reaction| <= alpha
            push = force_at(load, t) - (_linear_spring(k0) * x + branch_force(k, u))
            if released or abs(push) > alpha:
                direction = math.copysign(1.0, push)
            else:
                stuck = True
        released = False
        slipping = _slipping(k, eta, rate, m, c, k0, load, t, x, v, u, direction, alpha, stuck)
        a, y0 = _system(m, k0, c, k, rate, load, t, x, v, u, direction, alpha, stuck, slipping)
        ell, level, what, whom = _events(k, eta, rate, m, alpha, direction, stuck, slipping, a.shape[0])
        stiffness = _linear_spring(k0)
        relaxation = 0.0
        for i in range(n):
            stiffness += k[i]
            relaxation += rate[i]
        rho = math.sqrt(stiffness / m) + _damping(c) / m + abs(load[3]) + relaxation  # > 0: every k_i > 0
        tau, fired = _first_event(a, y0, ell, level, t, span, rho, budget)
        if fired == EXHAUSTED:
            failure = SEARCH_EXHAUSTED
            break
        y, gramian = _motion(a, tau, y0, energy)
        _book(energy, gramian, y, y0, tau, m, c, k, eta, rate, _linear_spring(k0) * x, stuck, slipping, alpha)
        x = x + y[XI]
        v = y[V]
        for i in range(n):
            u[i] = min(max(y[BRANCH0 + i], -eta[i]), eta[i])
        if fired >= 0:
            for j in range(ell.shape[0]):  # every functional positive at the event fires with it
                if j != fired and not _excess(ell, j, y, level[j]) > 0.0:
                    continue
                if what[j] == UP:
                    u[whom[j]] = eta[whom[j]]
                elif what[j] == DOWN:
                    u[whom[j]] = -eta[whom[j]]
                elif what[j] == REVERSAL:
                    v = 0.0
                elif what[j] == RELEASE:
                    released = True
        t_next = t + tau if fired >= 0 else t + span
        stalled = stalled + 1 if t_next <= t else 0
        if stalled > stall_limit:
            failure = STALLED
            break
        if not (abs(x) < np.inf and abs(v) < np.inf):
            failure = NOT_FINITE
            break
        t = t_next
    if failure != TOOK_STEP:
        _restore(u, saved_u)
        _restore(energy, saved_energy)
    return x, v, failure, t


def failure_reason(model, load, t: float, h: float, x: float, v: float, u) -> str:
    """Why the exact step from t cannot be taken, in words, or "" (``exact.failure_reason`` for this module)."""
    u_copy = np.array(u, dtype=float)
    x1, v1, failure, when = attempt(model, load, float(t), float(h), float(x), float(v), u_copy, None)
    return explain(int(failure), float(when))


@kernel
def _book(energy, gramian, y, y0, tau, m, c, k, eta, rate, spring, stuck, slipping, alpha):
    """Book a phase exactly. F = m (y2 + y4) + k0 x_e (x_e the phase's start; y4 constant), so the load's work
    is k0 x_e dx + m (int y2 v + y4 dx); the dashpot's c int v^2; a sticking branch's series dashpot
    (k_i u_i)^2 / c_i = k_i lambda_i u_i^2, integrated; a slipping one (u_i = s eta_i fixed): its dashpot
    k_i lambda_i eta_i^2 tau, its slider k_i eta_i (s dx - lambda_i eta_i tau) (the inflow, >= 0); the
    friction alpha |dx| (v keeps its sign: a reversal is an event). Integrals from the Gramian int y y^T."""
    if energy is None:
        return
    moved = y[XI]
    if not stuck:
        energy[0] += spring * moved + m * (gramian[V, LOAD_VARYING] + y0[LOAD_CONSTANT] * moved)
        if c is not None:
            energy[2] += c * max(gramian[V, V], 0.0)
        energy[3] += alpha * abs(moved)
    for i in range(k.shape[0]):
        if slipping[i]:
            sign = float(slipping[i])
            energy[1] += k[i] * eta[i] * max(sign * moved - rate[i] * eta[i] * tau, 0.0)
            energy[2] += k[i] * rate[i] * eta[i] * eta[i] * tau
        else:
            energy[2] += k[i] * rate[i] * max(gramian[BRANCH0 + i, BRANCH0 + i], 0.0)


_loop = time_loop(step)


@kernel
def run(model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy):
    """The time loop (``kernels/loop.py``) over :func:`step`, cached."""
    return _loop(model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy)


_summary = summary_loop(step)


@kernel
def run_summary(template, batch):
    """The summary loop (``kernels/batch.py``) over :func:`step`, cached."""
    _summary(template, batch)
