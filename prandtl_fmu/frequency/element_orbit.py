"""The motion of an element with friction on its mass whose forces are not linear between events (a cubic spring,
Stribeck's drop), event by event, by Taylor series: the orbit that ``shooting.py`` solves for where the exact
stepper does not go.

The mass under F cos(omega t) (x, v, the branches' u, the history's z; every force of ``[spring]``,
``[damper]``, ``[cubic]``, ``[branches]`` (with series dashpots or without), ``[history]`` and ``[friction]`` on
a fixed ground):

    m v' = F cos(omega t) - k0 x - k3 x^3 - c v - sum_i k_i u_i - sum_j w_j z_j - A(v),
    z_j' = -r_j z_j + y   (y = x, or v),
    A(v) = sigma (alpha_k + (alpha - alpha_k) exp(-|v| / v_s))   (sliding, sigma = sign v; Coulomb: alpha),

while it sticks (v = 0) the friction holds whatever the other forces N(t) = F cos(omega t) - k0 x - k3 x^3 -
sum_i k_i u_i - sum_j w_j z_j(t) ask while |N| <= alpha. The motion is smooth between events: a slide of
fixed direction sigma ends where v reaches 0 (the mass sticks if |N| <= alpha there, else it turns back); a
stick ends where N leaves [-alpha, alpha]; a sticking branch starts to slide where its u reaches +-eta in the
direction of motion; a sliding branch sticks where v reaches 0 (the slide's end). So the orbit is a chain of
smooth phases:

* **A slide** is the solution of an ODE whose right-hand side is a polynomial in (x, v), an exponential of v
  and a cosine of t: its Taylor series about the phase's start follows from the recurrences of products and of
  the exponential (k E_k = -(sigma / v_s) sum_j j v_j E_(k-j)) to TERMS terms, in time scaled by the phase's
  fastest rate rho (so that every coefficient is a length). The step is chosen by the coefficients' decay
  (Jorba & Zou's rule: the last two terms below TRUNCATION of the state), the state at its end summed; not a
  proven bound, as the linear phases of the exact stepper and ``network_orbit.py`` have, but the series'
  truncation kept at rounding. The tests measure it against the exact stepper where both apply (linear
  forces: to 1e-12) and against an independent integration written in the test.
* **A stick** is x fixed and N(t) a cosine, a constant and the history's exponentials: its Taylor series on
  intervals of rho tau <= 1 (rho the larger of omega and the rates) has a proven remainder ((rho tau)^TERMS /
  TERMS! e^(rho tau) times F and the exponentials' amplitudes).

**Branches behind series dashpots** (rate lambda_i = k_i / c_i): a sticking one relaxes, u_i' = v - lambda_i
u_i, so it is a term of the history's form on v (weight k_i, rate lambda_i) in both phases (in a stick, v = 0:
it decays); a sliding one holds u_i = +-eta_i, a constant force, while its inflow v - lambda_i u_i pushes
outwards. Its events, in a slide of the mass: a sticking u_i reaches +-eta_i (either way), a sliding one's
inflow +-v - lambda_i eta_i reaches 0; at rest every inflow, -lambda_i u_i, turns inwards: they all stick.

**Events** are found as ``network_orbit.py`` finds them (its validated subdivision of each event function's
polynomial, the first crossing refined by bisection): the event functions are sigma v (a slide's end), eta_i -
sigma u_i (a branch's level) and alpha -+ N (a stick's end), each crossing below -tol, tol EVENT_TOLERANCE of
its size, so an event that starts at its level (a slide from rest, a branch just at its level) waits for the
motion to leave it by more than rounding. At a slide's end v is set to 0 and the sliding branches stick.

**Bounded work.** A run takes at most PHASES_PER_SAMPLE (1 + branches) max(samples, 256) phases (PILED_UP),
at most STEPS_PER_SAMPLE max(samples, 32) Taylor steps (TOO_STIFF), each event search at most WALK_LIMIT
intervals (WALK_EXHAUSTED) and each refinement REFINE_LIMIT bisections (network_orbit.py's).
"""
import math

import numpy as np

from .._jit import kernel
from .network_orbit import _crossing, _horner

TERMS = 28
TRUNCATION = 1e-17  # each of the last two terms of a step's series, relative to the state
EVENT_TOLERANCE = 1e-12
WALK_LIMIT = 400
PHASES_PER_SAMPLE = 64
STEPS_PER_SAMPLE = 8192

OK = 0
PILED_UP = 1
WALK_EXHAUSTED = 2
TOO_STIFF = 5


def explain(status: int) -> str:
    """The run's failure in words."""
    return {
        PILED_UP: f"more than {PHASES_PER_SAMPLE} (1 + branches) max(samples, 256) stick and slip events in one "
                  "run (events that pile up: a Zeno motion)",
        WALK_EXHAUSTED: f"an event search went past its bound of {WALK_LIMIT} intervals (an event function that "
                        "stays within rounding of its level)",
        TOO_STIFF: f"more than {STEPS_PER_SAMPLE} max(samples, 32) Taylor steps in one run (too stiff, or a "
                   "motion too fast for its samples)",
    }.get(status, f"status {status}")


@kernel
def _earlier(c, span, first, r0, r1, budget, shifted):
    """The first crossing of the event function c (its rest bounded by r0, its derivative's by r1) before the
    earliest event found so far, ``first`` (-1: none yet, the search goes to ``span``), with a fresh walk budget:
    its time, -1 where there is none earlier, NaN past the walk's bound (network_orbit._crossing)."""
    budget[0] = WALK_LIMIT
    s = _crossing(c, span if first < 0.0 else first, r0, r1, budget, shifted)
    if s >= 0.0 and first >= 0.0 and not s < first:
        return -1.0
    return s


@kernel
def _slide_series(x0, v0, t0, sigma, rho, mass, stiffness, damping, k3, alpha, alpha_k, vs, belt, hw, hr, on_v,
                  z0, constant, G, X, V, Z):
    """The Taylor coefficients X[k], V[k] (k < TERMS) of x and v / rho about t0 in the scaled time s = rho (t -
    t0), in a slide of direction ``sigma``: m v' = f(t) - stiffness x - k3 x^3 - damping v + constant
    - sigma (alpha_k + (alpha - alpha_k) exp(-sigma (v - belt) / vs)) (vs 0: Coulomb, alpha) - sum_j hw_j z_j,
    and Z[j, k] those of the terms z_j' = -hr_j z_j + y (y = v where ``on_v[j]`` is 1, else x) from z0; G[k] those of the
    force f(t) (:func:`_forcing_series`)."""
    terms = X.shape[0]
    square = np.zeros(terms)
    cube = np.zeros(terms)
    exponential = np.zeros(terms)
    X[0] = x0
    V[0] = v0 / rho
    scale = 1.0 / (mass * rho * rho)  # a force over m rho^2: a length
    stribeck = vs > 0.0 and alpha > alpha_k
    if stribeck:
        exponential[0] = math.exp(-sigma * (v0 - belt) / vs)
    for j in range(hw.shape[0]):
        Z[j, 0] = z0[j]
    for k in range(terms - 1):
        # x^2 and x^3 at order k (Cauchy products)
        total = 0.0
        for j in range(k + 1):
            total += X[j] * X[k - j]
        square[k] = total
        total = 0.0
        for j in range(k + 1):
            total += square[j] * X[k - j]
        cube[k] = total
        if stribeck and k > 0:
            total = 0.0
            for j in range(1, k + 1):
                total += j * V[j] * exponential[k - j]
            exponential[k] = -sigma * rho / vs * total / k
        force = G[k] - stiffness * X[k] - k3 * cube[k] - damping * rho * V[k]
        for j in range(hw.shape[0]):
            force -= hw[j] * Z[j, k]
        if stribeck:
            force -= sigma * (alpha - alpha_k) * exponential[k]
        if k == 0:
            force += constant - sigma * (alpha_k if stribeck else alpha)
        V[k + 1] = force * scale / (k + 1)
        X[k + 1] = V[k] / (k + 1)
        for j in range(hw.shape[0]):
            y = V[k] * rho if on_v[j] != 0.0 else X[k]
            Z[j, k + 1] = (y - hr[j] * Z[j, k]) / (rho * (k + 1))


@kernel
def _forcing_series(t0, amplitude, omega, extra, rho, constant, out):
    """The Taylor coefficients of f(t) + constant about t0 in s = rho (t - t0), f(t) = F cos(omega t) + sum_r
    (a_r cos(p_r omega t) + b_r sin(p_r omega t)), the rows of ``extra`` (p_r, a_r, b_r): each term Re(w e^(i p
    omega t)), w = a - i b, whose k-th coefficient is Re(w e^(i p omega t0) (i p omega / rho)^k / k!)."""
    for k in range(out.shape[0]):
        out[k] = 0.0
    for r in range(-1, extra.shape[0]):
        if r < 0:
            rate, zr, zi = omega / rho, amplitude * math.cos(omega * t0), amplitude * math.sin(omega * t0)
        else:
            p, a, b = extra[r, 0], extra[r, 1], extra[r, 2]
            c, s = math.cos(p * omega * t0), math.sin(p * omega * t0)
            rate, zr, zi = p * omega / rho, a * c + b * s, a * s - b * c
        for k in range(out.shape[0]):
            out[k] += zr
            zr, zi = -zi * rate / (k + 1), zr * rate / (k + 1)
    out[0] += constant


@kernel
def _forcing_size(amplitude, omega, extra):
    """(the sum of the forcing's amplitudes, its fastest angular frequency)."""
    size = abs(amplitude)
    fastest = abs(omega)
    for r in range(extra.shape[0]):
        size += abs(extra[r, 1]) + abs(extra[r, 2])
        fastest = max(fastest, abs(extra[r, 0] * omega))
    return size, fastest


@kernel
def _stuck_history(z0, y, slope, hr, rho, Z):
    """The Taylor coefficients Z[j, k] of the terms z_j' = -hr_j z_j + y_j + slope_j (t - t0) (x of a stuck mass,
    moving with its belt, or its v: 0, or the belt's speed) about the stick's start, in s = rho (t - t0)."""
    for j in range(hr.shape[0]):
        Z[j, 0] = z0[j]
        for k in range(Z.shape[1] - 1):
            drive = y[j] if k == 0 else (slope[j] / rho if k == 1 else 0.0)
            Z[j, k + 1] = (drive - hr[j] * Z[j, k]) / (rho * (k + 1))


@kernel
def _held(x, k0, k3, bk, beta, bmode, u, hw, z, amplitude, omega, extra, t):
    """N: the force on the mass at rest (v = 0) without the friction."""
    total = amplitude * math.cos(omega * t) - k0 * x - k3 * x * x * x
    for r in range(extra.shape[0]):
        total += extra[r, 1] * math.cos(extra[r, 0] * omega * t) + extra[r, 2] * math.sin(extra[r, 0] * omega * t)
    for j in range(hw.shape[0]):
        total -= hw[j] * z[j]
    for i in range(bk.shape[0]):
        total -= bk[i] * (bmode[i] * beta[i] if bmode[i] != 0 else u[i])
    return total


@kernel
def _terms(hw, hr, on_v, z, bk, beta, lam, smode, W, R, Y, zz):
    """The terms z_j' = -R_j z_j + y of a phase (weights W, on v where Y_j is 1): the history's, then the series
    branches' (weight k_i while the branch sticks, 0 while it slides at smode_i eta_i, which the phase's
    constant carries; rate lambda_i, on v). Their values into ``zz`` from z and u (a sliding branch at its
    level); returns the sliding branches' force."""
    nz = hw.shape[0]
    slid = 0.0
    for j in range(nz):
        W[j] = hw[j]
        R[j] = hr[j]
        Y[j] = 1.0 if on_v else 0.0
        zz[j] = z[j]
    for i in range(lam.shape[0]):
        R[nz + i] = lam[i]
        Y[nz + i] = 1.0
        if smode[i] == 0:
            W[nz + i] = bk[i]
        else:
            W[nz + i] = 0.0
            zz[nz + i] = smode[i] * beta[i]
            slid += bk[i] * smode[i] * beta[i]
    return slid


@kernel
def run(mass, k0, damping, k3, alpha, alpha_k, vs, bk, beta, lam, hw, hr, on_v, amplitude, omega, state, u, z, h,
        steps, out, belt):
    """``steps`` steps of h from ``state`` = (x, v), the branches' ``u`` and the history's ``z`` (weights ``hw``,
    rates ``hr``, on v if ``on_v``, else on x; none: empty) at t = 0 (updated in place to the end), x at each
    step's end in ``out`` (steps,); returns (status, steps taken). ``lam`` (n,): the branches' relaxation rates
    k_i / c_i through series dashpots (empty: Prandtl branches). The force F cos(omega t) (``amplitude``); the
    friction on the slip v - ``belt`` (a moving belt: see the module)."""
    return run_forced(mass, k0, damping, k3, alpha, alpha_k, vs, bk, beta, lam, hw, hr, on_v, amplitude, omega,
                      np.zeros((0, 3)), np.zeros(0), np.zeros(0), state, u, z, h, steps, out, belt)


@kernel
def _delayed_force(t, start, h, delay, ybuf):
    """(value at t, slope) of the delay's force -g y(t - tau) in the piece that holds t of the step that starts
    at ``start`` (= step h; a float: an int argument typed as a literal compiled a copy per constant): y between
    the grid points of ``ybuf`` (y at t_k = k h, k = -(N + 1) ... at ybuf[k + N + 1]) linearly interpolated;
    tau = N h + delta, ``delay`` = (g, N, delta, on v)."""
    gain, lag, delta = delay[0], int(delay[1]), delay[2]
    step = int(start / h + 0.5)
    before = step - lag - 1 if t < start + delta else step - lag
    ya, yb = ybuf[before + lag + 1], ybuf[before + lag + 2]
    fraction = (t - lag * h - delta - before * h) / h
    return -gain * (ya + (yb - ya) * fraction), -gain * (yb - ya) / h


@kernel
def run_forced(mass, k0, damping, k3, alpha, alpha_k, vs, bk, beta, lam, hw, hr, on_v, amplitude, omega, extra, delay,
               ybuf, state, u, z, h, steps, out, belt):
    """:func:`run` under F cos(omega t) and the harmonics of ``extra``, rows (p, a, b): a cos(p omega t) + b
    sin(p omega t) (a delay's force on the periodic orbit, ``shooting.py``); and, where ``delay`` = (g, N, delta,
    on v) is given (else empty), the delay's force -g y(t - tau), tau = N h + delta (N >= 1), from y at the grid
    points t_k = k h: ``ybuf`` (N + 2 + steps,) holds k = -(N + 1) ... 0 on entry and gets y (x, or v where
    delay[3] is 1) at each step's end (the semi-discretisation of the delay equation: y linear between grid
    points, so each step has a knot at t_k + delta where t - tau passes one; the stability of shooting.py).
    ``belt``: the friction's support moves at this speed: the friction acts on the slip v - belt, a stuck mass
    moves with it (x a polynomial in t, its branches, series branches and history driven by it), and within a
    slide v may turn (the sliding branches stick there). Not with a delay (shooting.py refuses it)."""
    nb = bk.shape[0]
    nz = hw.shape[0]
    series = lam.shape[0] > 0
    plain = 0 if series else nb  # the Prandtl branches (without series dashpots)
    nt = nz + (nb if series else 0)  # the terms: the history's z, then the series branches' u
    Z = np.empty((nt, TERMS))
    W = np.empty(nt)
    R = np.empty(nt)
    Y = np.empty(nt)
    zz = np.empty(nt)
    held_y = np.empty(nt)
    held_slope = np.empty(nt)
    smode = np.zeros(nb if series else 0, dtype=np.int64)
    terms = TERMS
    x = state[0]
    v = state[1]
    bmode = np.zeros(plain, dtype=np.int64)
    for i in range(nb):
        u[i] = min(max(u[i], -beta[i]), beta[i])
    for j in range(nz):
        zz[j] = z[j]
    for i in range(nt - nz):
        zz[nz + i] = u[i]
    X = np.empty(terms)
    V = np.empty(terms)
    c = np.empty(terms)
    shifted = np.empty(terms)
    budget = np.zeros(1, dtype=np.int64)
    factorial = 1.0
    for k in range(1, terms + 1):
        factorial *= k
    forcing, fastest = _forcing_size(amplitude, omega, extra)
    G = np.empty(terms)
    delayed = delay.shape[0] > 0
    lag = int(delay[1]) if delayed else 0
    size_force = forcing + alpha + k0 * abs(x) + k3 * abs(x) ** 3 + damping * abs(belt)
    ahead = 1 if belt > 0.0 else (-1 if belt < 0.0 else 0)  # the direction a stuck mass moves in
    if delayed:
        for i in range(lag + 2):
            size_force = max(size_force, forcing + abs(delay[0] * ybuf[i]))
    for i in range(nb):
        size_force += bk[i] * beta[i]
    for j in range(nz):
        size_force += abs(hw[j] * z[j])
    t = 0.0
    sigma = 0
    decide = True  # the phase's direction to be decided from the state
    x_phase = x
    u_phase = u.copy()
    phases = 0
    phase_limit = PHASES_PER_SAMPLE * (1 + nb) * max(steps, 256)
    taylor_steps = 0
    step_limit = STEPS_PER_SAMPLE * max(steps, 32)
    step = 0
    while step < steps:
        if decide:
            decide = False
            phases += 1
            if phases > phase_limit:
                return PILED_UP, step
            if v > belt:
                sigma = 1
            elif v < belt:
                sigma = -1
            else:
                # at rest on its support: the branches stick (on a belt those at their level ahead go on sliding);
                # the mass slides where the other forces exceed alpha
                for i in range(plain):
                    if bmode[i] != 0 and bmode[i] != ahead:
                        u[i] = bmode[i] * beta[i]
                        bmode[i] = 0
                for i in range(smode.shape[0]):  # a series branch's inflow at rest, belt - lambda u, turns inwards
                    if smode[i] * belt - lam[i] * beta[i] <= 0.0:  # (unless the belt pushes it on)
                        smode[i] = 0
                slid_at_rest = _terms(hw, hr, on_v, z, bk, beta, lam, smode, W, R, Y, zz)
                held = _held(x, k0, k3, bk[:plain], beta[:plain], bmode, u[:plain], W, zz, amplitude, omega, extra, t)
                held -= slid_at_rest
                if delayed:
                    held += _delayed_force(t, step * h, h, delay, ybuf)[0]
                held -= damping * belt
                sigma = 0
                if held > alpha:
                    sigma = 1
                elif held < -alpha:
                    sigma = -1
            # the branches at their level in the direction of motion (of v: on a belt, not the slip's) slide
            moving = sigma if v == 0.0 else (1 if v > 0.0 else -1)
            for i in range(plain):
                if moving != 0 and bmode[i] == 0 and moving * u[i] >= beta[i]:
                    u[i] = moving * beta[i]
                    bmode[i] = moving
            # a series branch at its level slides where its inflow v - lambda u pushes out
            for i in range(smode.shape[0]):
                level = zz[nz + i]
                if smode[i] == 0 and abs(level) >= beta[i] and level * (v - lam[i] * level) > 0.0:
                    smode[i] = 1 if level > 0.0 else -1
            x_phase = x
            u_phase = u.copy()
        taylor_steps += 1
        if taylor_steps > step_limit:
            return TOO_STIFF, step
        target = (step + 1) * h
        stop_at = target  # a step's end, or the delay's knot within it
        if delayed and t < step * h + delay[2]:
            stop_at = step * h + delay[2]
        lagged, lagged_slope = _delayed_force(t, step * h, h, delay, ybuf) if delayed else (0.0, 0.0)
        slid = _terms(hw, hr, on_v, z, bk, beta, lam, smode, W, R, Y, zz)
        if sigma == 0:
            # a stick: x fixed (on a belt x moving with it, a polynomial in t), N(t) a cosine and a polynomial
            rho = max(fastest, 1e-300)
            for j in range(nt):
                rho = max(rho, R[j])
            constant = -k0 * x - k3 * x * x * x - damping * belt - slid
            for i in range(plain):
                constant -= bk[i] * u[i]
            to_target = (stop_at - t) * rho
            span = min(to_target, 1.0)
            _forcing_series(t, amplitude, omega, extra, rho, constant + lagged, X)
            X[1] += lagged_slope / rho
            reached = -1  # on a belt: the first sticking branch to reach its level ahead (u moves with x), exactly
            if ahead != 0:
                slope = belt / rho  # x's in the scaled time
                X[1] -= (k0 + 3.0 * k3 * x * x) * slope
                X[2] -= 3.0 * k3 * x * slope * slope
                X[3] -= k3 * slope * slope * slope
                for i in range(plain):
                    if bmode[i] == 0:
                        X[1] -= bk[i] * slope
                        level = max(beta[i] - ahead * u[i], 0.0) / abs(belt) * rho
                        if level < span:
                            span = level
                            reached = i
            # the terms' z_j(t) = p(t) + (z_j - p(t0)) exp(-r_j (t - t0)), p the particular solution (y + y' (t -
            # t0) driving: p = (y - y' / r_j) / r_j + y' / r_j (t - t0); r_j = 0: a polynomial), y = x (moving with
            # the belt) or v (the belt's speed)
            for j in range(nt):
                held_y[j] = belt if Y[j] != 0.0 else x
                held_slope[j] = 0.0 if Y[j] != 0.0 else belt
            _stuck_history(zz, held_y, held_slope, R, rho, Z)
            reach = forcing
            for j in range(nt):
                for k in range(terms):
                    X[k] -= W[j] * Z[j, k]
                if R[j] > 0.0:
                    reach += abs(W[j] * (zz[j] - (held_y[j] - held_slope[j] / R[j]) / R[j]))
            rest0 = span ** terms / factorial * math.exp(span) * reach
            rest1 = span ** (terms - 1) / factorial * terms * math.exp(span) * reach
            tol = EVENT_TOLERANCE * size_force
            first = -1.0
            event = 0
            for side in (1, -1):
                for k in range(terms):
                    c[k] = -side * X[k]
                c[0] += alpha + tol
                s = _earlier(c, span, first, rest0, rest1, budget, shifted)
                if math.isnan(s):
                    return WALK_EXHAUSTED, step
                if s >= 0.0:
                    first = s
                    event = side
            # on a belt a sticking series branch relaxes towards belt / lambda, which may be beyond its level: its
            # u crossing +-eta (it slides)
            series_event = -1
            series_side = 0
            for i in range(smode.shape[0] if ahead != 0 else 0):
                if smode[i] != 0:
                    continue
                j = nz + i
                amplitude_z = abs(zz[j] - (held_y[j] - held_slope[j] / R[j]) / R[j]) if R[j] > 0.0 else 0.0
                rest_z = span ** terms / factorial * math.exp(span) * amplitude_z
                for side in (1, -1):
                    for k in range(terms):
                        c[k] = -side * Z[j, k]
                    c[0] += beta[i] + EVENT_TOLERANCE * max(beta[i], abs(zz[j]))
                    s = _earlier(c, span, first, rest_z, rest_z * terms / max(span, 1e-300), budget, shifted)
                    if math.isnan(s):
                        return WALK_EXHAUSTED, step
                    if s >= 0.0:
                        first = s
                        series_event = i
                        series_side = side
            stop = span if first < 0.0 else first
            for j in range(nt):
                zz[j] = _horner(Z[j], stop)
            for i in range(smode.shape[0]):  # within its range (a sliding one at its level)
                zz[nz + i] = smode[i] * beta[i] if smode[i] != 0 else min(max(zz[nz + i], -beta[i]), beta[i])
            t_end = t + stop / rho
            if first < 0.0 and to_target <= span:
                t_end = stop_at
            if ahead != 0:  # the mass and the sticking branches move with the belt
                x += belt * (t_end - t)
                for i in range(plain):
                    if bmode[i] == 0:
                        u[i] = min(max(u[i] + belt * (t_end - t), -beta[i]), beta[i])
            t = t_end
            if first < 0.0 and reached >= 0 and to_target > span:  # a branch at its level: it slides on
                phases += 1
                if phases > phase_limit:
                    return PILED_UP, step
                u[reached] = ahead * beta[reached]
                bmode[reached] = ahead
            if series_event >= 0:  # the series branch slides at its level; the stick goes on
                phases += 1
                if phases > phase_limit:
                    return PILED_UP, step
                smode[series_event] = series_side
                zz[nz + series_event] = series_side * beta[series_event]
                first = -1.0
            if first >= 0.0:
                sigma = event
                decide = False
                phases += 1
                if phases > phase_limit:
                    return PILED_UP, step
                moving = ahead if ahead != 0 else sigma
                for i in range(plain):
                    if bmode[i] == 0 and moving * u[i] >= beta[i]:
                        u[i] = moving * beta[i]
                        bmode[i] = moving
                x_phase = x
                u_phase = u.copy()
        else:
            # a slide of direction sigma: its Taylor series in s = rho (t - t0)
            stiffness = k0
            constant = -slid
            for i in range(plain):
                if bmode[i] == 0:  # u = u_phase + x - x_phase
                    stiffness += bk[i]
                    constant -= bk[i] * (u_phase[i] - x_phase)
                else:
                    constant -= bk[i] * bmode[i] * beta[i]
            curvature = stiffness + 3.0 * k3 * x * x
            rho = max(math.sqrt(curvature / mass), damping / mass, fastest, 1e-300)
            if vs > 0.0 and alpha > alpha_k:
                rho = max(rho, (alpha - alpha_k) / (mass * vs))
            for j in range(nt):
                rho = max(rho, R[j], math.sqrt(abs(W[j]) / mass))
            _forcing_series(t, amplitude, omega, extra, rho, lagged, G)
            G[1] += lagged_slope / rho
            _slide_series(x, v, t, sigma, rho, mass, stiffness, damping, k3, alpha, alpha_k, vs, belt, W, R, Y, zz,
                          constant, G, X, V, Z)
            # the state's size, at least the forces' length (from rest, x = v = 0, the truncation test had 0 to
            # compare with and took steps of 0 until refused: a review's find)
            # (not the branches' ranges: a range far larger than the motion made the slide's end overshoot v = 0
            # by 1e-12 eta rho, and with a delay's harmonics in rho the error grew with them: a review's find)
            size = max(abs(X[0]), abs(V[0]), size_force / (mass * rho * rho), 1e-300)
            # Jorba & Zou: the last two terms below TRUNCATION of the state (z_j weighed by its force, as a length)
            span = math.inf
            for k in (terms - 2, terms - 1):
                top = max(abs(X[k]), abs(V[k]))
                for j in range(nt):
                    top = max(top, abs(W[j] * Z[j, k]) / (mass * rho * rho))
                for j in range(nz, nt):  # a series branch's u: a length of its own
                    top = max(top, abs(Z[j, k]))
                if top > 0.0:
                    span = min(span, (TRUNCATION * size / top) ** (1.0 / k))
            span = min(span, 1.0 if math.isinf(span) else span, (stop_at - t) * rho)
            if vs > 0.0 and alpha > alpha_k:
                # the drop's exp(-sigma v / vs): its coefficients carry its value at the start, which the last terms
                # hide where the slide is fast (1e-33) and the step then crosses the drop with the series' 1e-11
                # (a review's find: v_s = 0.003 m/s, 3e-4 off at 128 samples a period). The step changes the
                # exponent by at most 2, unless the slide is still fast at its end (exp(-40): nothing to see)
                exponent_rate = abs(V[1]) * rho / vs
                if span * exponent_rate > 2.0 and sigma * (_horner(V, span) * rho - belt) < 40.0 * vs:
                    limit = 2.0 / exponent_rate
                    if sigma * (V[0] * rho - belt) > 40.0 * vs:
                        # fast at the start (the drop below exp(-40)): the step goes on to where sigma v falls to
                        # 40 vs, then by steps of 2 in the exponent. Cut at 2 / rate all along, a slide of speed v
                        # took v / (2 vs) steps to its end (measured: 42 000 a half period at 2e5 m, linear in the
                        # amplitude)
                        for k in range(terms):
                            c[k] = sigma * V[k]
                        c[0] -= (40.0 * vs + sigma * belt) / rho  # (the slip: on a belt, a review's find)
                        rest = (abs(X[terms - 1]) + abs(V[terms - 1])) * span ** (terms - 1)
                        budget[0] = WALK_LIMIT
                        s = _crossing(c, span, rest, rest * terms / max(span, 1e-300), budget, shifted)
                        if math.isnan(s):
                            return WALK_EXHAUSTED, step
                        if s > limit:
                            limit = s
                    span = limit
            reach = span
            rest = (abs(X[terms - 1]) + abs(V[terms - 1])) * reach ** (terms - 1)
            for j in range(nz, nt):
                rest += abs(Z[j, terms - 1]) * reach ** (terms - 1)
            first = -1.0
            event = -1
            # the slide's end: the slip sigma (v - belt) crosses below -tol
            for k in range(terms):
                c[k] = sigma * V[k]
            c[0] += EVENT_TOLERANCE * size - sigma * belt / rho
            budget[0] = WALK_LIMIT
            s = _crossing(c, span, rest, rest * terms / max(span, 1e-300), budget, shifted)
            if math.isnan(s):
                return WALK_EXHAUSTED, step
            if s >= 0.0:
                first = s
            # a sticking branch's level: side u = side (u_phase + x - x_phase) crosses eta, side sigma (on a belt
            # v may turn within the slide: either side)
            side_of = 0
            for i in range(plain):
                if bmode[i] != 0:
                    continue
                for side in (1, -1):
                    if ahead == 0 and side != sigma:
                        continue
                    for k in range(terms):
                        c[k] = -side * X[k]
                    c[0] += beta[i] - side * (u_phase[i] - x_phase) + EVENT_TOLERANCE * max(size, beta[i])
                    s = _earlier(c, span, first, rest, rest * terms / max(span, 1e-300), budget, shifted)
                    if math.isnan(s):
                        return WALK_EXHAUSTED, step
                    if s >= 0.0:
                        first = s
                        event = i
                        side_of = side
            # on a belt, v turning within the slide: the sliding branches (all at their level ahead of v) stick
            turning = 0
            for i in range(plain):
                if bmode[i] != 0:
                    turning = bmode[i]
            if ahead != 0 and turning != 0:
                for k in range(terms):
                    c[k] = turning * V[k]
                c[0] += EVENT_TOLERANCE * size
                s = _earlier(c, span, first, rest, rest * terms / max(span, 1e-300), budget, shifted)
                if math.isnan(s):
                    return WALK_EXHAUSTED, step
                if s >= 0.0:
                    first = s
                    event = -2
            # a series branch: sticking, its u crosses +-eta (either way: it relaxes too); sliding, its inflow
            # smode (v - lambda smode eta) crosses 0 (it sticks again at its level)
            for i in range(smode.shape[0]):
                for side in (1, -1):
                    if smode[i] == 0:
                        for k in range(terms):
                            c[k] = -side * Z[nz + i, k]
                        c[0] += beta[i] + EVENT_TOLERANCE * max(size, beta[i])
                    elif side == smode[i]:
                        for k in range(terms):
                            c[k] = side * V[k]
                        c[0] += -lam[i] * beta[i] / rho + EVENT_TOLERANCE * size
                    else:
                        continue
                    s = _earlier(c, span, first, rest, rest * terms / max(span, 1e-300), budget, shifted)
                    if math.isnan(s):
                        return WALK_EXHAUSTED, step
                    if s >= 0.0:
                        first = s
                        event = i
                        side_of = side
            stop = span if first < 0.0 else first
            x = _horner(X, stop)
            v = _horner(V, stop) * rho
            for j in range(nt):
                zz[j] = _horner(Z[j], stop)
            for i in range(smode.shape[0]):
                if smode[i] != 0:
                    zz[nz + i] = smode[i] * beta[i]
                else:
                    zz[nz + i] = min(max(zz[nz + i], -beta[i]), beta[i])
            t_end = t + stop / rho
            if first < 0.0 and stop >= (stop_at - t) * rho:
                t_end = stop_at
            t = t_end
            if first >= 0.0:
                for i in range(plain):
                    if bmode[i] == 0:
                        u[i] = min(max(u_phase[i] + x - x_phase, -beta[i]), beta[i])
                if event == -1:  # the slide ends: v = belt, the mass sticks or turns back
                    v = belt
                    decide = True
                elif event == -2:  # v turns: the sliding branches stick at their level
                    phases += 1
                    if phases > phase_limit:
                        return PILED_UP, step
                    v = 0.0
                    for i in range(plain):
                        if bmode[i] != 0:
                            u[i] = bmode[i] * beta[i]
                            bmode[i] = 0
                        u_phase[i] = u[i]
                    x_phase = x
                else:
                    phases += 1
                    if phases > phase_limit:
                        return PILED_UP, step
                    if series:  # a series branch reaches its level (it slides) or its inflow stops (it sticks)
                        if smode[event] == 0:
                            smode[event] = side_of
                            zz[nz + event] = side_of * beta[event]
                        else:
                            smode[event] = 0
                    else:  # the branch slides; the phase goes on with it
                        u[event] = side_of * beta[event]
                        bmode[event] = side_of
                        for i in range(nb):
                            if bmode[i] == 0:
                                u_phase[i] = u[i]
                        x_phase = x
        for j in range(nz):
            z[j] = zz[j]
        if t == target:
            out[step] = x
            if delayed:
                ybuf[lag + 2 + step] = v if delay[3] != 0.0 else x
            step += 1
    # the end state
    if sigma != 0:
        for i in range(plain):
            if bmode[i] == 0:
                u[i] = min(max(u_phase[i] + x - x_phase, -beta[i]), beta[i])
    for i in range(nt - nz):
        u[i] = zz[nz + i]
    state[0] = x
    state[1] = v
    return OK, steps
