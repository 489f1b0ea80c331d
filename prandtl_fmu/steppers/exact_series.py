"""``exact`` for branches with series dashpots (the series model, eq. 15 of ``004``): closed form between events.

A branch with a dashpot c_i in series with its spring k_i and slider (threshold k_i eta_i) has an elongation
u_i that relaxes while the slider sticks, u_i' = v - lambda_i u_i (lambda_i = k_i / c_i), and stays at
+-eta_i while the slider slips, which it does while the flow pushes outwards: sign(u_i)(v - lambda_i u_i) > 0.
Between two events the set of slipping branches is fixed, so the element with its load is the linear system
y' = A y of dimension 6 + n:

    y = (xi, v, load (2 states), load and the spring's force at the phase's start / m, the friction / m, u_1..u_n)

with xi = x - x(t_e) (lengths stay exact relative to the phase's start), the harmonic or ramp part of the load
generated as in ``exact.py``, and y(tau) = expm(A tau) y(0) (``exact._expm_times``: one scaled Taylor series
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

The mode of a branch on its threshold at the start of a phase: it slips if its inflow is positive, or zero
with a positive derivative (sign(u_i) v' > 0); otherwise it sticks. An event is a sign change beyond the rounding of g_j's terms (8 ulps), so
a branch that has just stuck on its threshold, or creeps exactly at v = lambda_i eta_i, fires nothing. Events at one instant are finitely many: more
than 16 + 4 n phases in a row that do not advance t end the step with a non-finite state, which the driver
reports as a failed step: never a silent stop.

The cost of a phase is a few dozen (6 + n)-square matrix exponentials per interval of the walk, whose length
is at most 1 / |A| (no energy bound for long quiet stretches here, unlike the 6 x 6 case): O(n^3) per
exponential, meant for the few branches a series model has. No energy account (as ``exact``: NaN).
"""
import math

import numpy as np

from .._jit import kernel
from ..kernels.batch import summary_loop
from ..kernels.loop import time_loop
from ..kernels.play import branch_force
from ..loads import CONSTANT, HARMONIC, force_at
from .exact import _EPS, _damping, _expm_times, _linear_spring, _next_break, _threshold

XI, V, LOAD_VARYING, LOAD_RATE, LOAD_CONSTANT, FRICTION, BRANCH0 = 0, 1, 2, 3, 4, 5, 6
# what an event does: a sticking branch slips (up, down), a slipping one sticks, the mass stops, it is released
UP, DOWN, STOPS, REVERSAL, RELEASE = 0, 1, 2, 3, 4


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
        y0[LOAD_VARYING] = amplitude / m * math.cos(omega * t)
        y0[LOAD_RATE] = amplitude / m * math.sin(omega * t)
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
    n = k.shape[0]
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
                for i in range(n):
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
def _first_event(a, y0, ell, level, t, span, rho):
    """(tau, j): the first sign change of ``ell[j] . y - level[j]`` (beyond rounding: :func:`_excess`) in
    (0, span], or (span, -1). ``t``: the phase's start (the rounding level of tau), ``rho`` its rate (1/s)."""
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
    longest = 1.0 / max(norm, 1e-300)
    lo = 0.0
    length = min(span, longest)
    while lo < span:
        y = _expm_times(a, lo, y0)
        b = min(span, lo + length)
        length = b - lo
        size_y = 0.0
        for i in range(size):
            size_y = max(size_y, abs(y[i]) * weights[i])
        growth = math.exp(norm * length) * size_y
        rounding = 8.0 * _EPS * (abs(t) + lo + 1.0 / rho)
        decided = True
        for j in range(count):
            g = _value(ell, j, y) - level[j]
            if g < -length * bound1[j] * growth:
                continue  # no zero of g_j on [lo, b]
            d1 = _value(slope, j, y)
            if abs(d1) > length * bound2[j] * growth or length <= rounding:
                continue  # g_j monotone on [lo, b] (or the interval is at rounding): its sign at b decides
            d2 = _value(curve, j, y)
            if abs(d2) > length * bound3[j] * growth and ((d2 < 0.0 and g <= 0.0 and d1 <= 0.0) or d2 * d1 >= 0.0):
                # the curvature keeps its sign on [lo, b]: concave from g <= 0 going down, g stays <= 0 (a
                # functional that starts on its level and leaves it inwards: a branch that has just stuck on its
                # threshold); a slope that grows away from 0 keeps its sign (monotone: the sign at b decides)
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
    while hi - lo > 4.0 * _EPS * hi:
        mid = 0.5 * (lo + hi)
        if g_hi != g_lo:
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
        sign = 1.0 if u[i] > 0.0 else -1.0
        inflow = sign * (v - rate[i] * u[i])
        if inflow > 0.0 or (inflow == 0.0 and sign * acceleration > 0.0):
            out[i] = 1 if sign > 0.0 else -1
    return out


@kernel
def step(model, load, t, h, x, v, s, u, energy):
    m, k0, k3, c, k, eta, cs, friction = model
    alpha = _threshold(friction)
    n = k.shape[0]
    rate = k / cs
    end = t + h
    stalled = 0
    stall_limit = 16 + 4 * n
    released = False  # a stick just ended with the net force at the threshold: slide now
    while t < end:  # phases; each ends at an event, a load kink or t + h
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
        tau, fired = _first_event(a, y0, ell, level, t, span, rho)
        y = _expm_times(a, tau, y0)
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
        if stalled > stall_limit or not (abs(x) < np.inf and abs(v) < np.inf):
            return np.nan, np.nan, branch_force(k, u)  # reported by the driver: never a silent stop
        t = t_next
    return x, v, branch_force(k, u)


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
