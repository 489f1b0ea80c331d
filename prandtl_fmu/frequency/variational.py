"""The monodromy of a periodic state from its variational equation along the harmonic balance's own orbit.

For a network whose nodes all have a mass, with springs, dashpots, cubic springs and Prandtl branches (no
series dashpot, no effect with memory), a perturbation (dx, dv, du) of the orbit obeys, between the instants where
a branch switches,

    dx' = dv,   M dv' = -C dv - K dx - sum_c 3 k3 e_c(t)^2 B_c' B_c dx - sum_b k_b B_b' du_b,
    du_b' = B_b dv while branch b sticks, du_b = 0 while it slides,

B the elongation's row (e = x_p - x_q). A branch that reaches its threshold (stick to slip) has its du_b set to 0
there: the perturbed motion slides from there on too, a little earlier or later, and loses the difference; one
that stops sliding (slip to stick, where its elongation turns) starts from du_b = 0, the vector field being
continuous there (v = 0). The orbit is the balance's: x and v from its harmonics at the N samples of ``aft.py``
(linear between samples), u from the same play operator on the samples, the switches located inside each
sample interval (a threshold where the sampled elongation reaches it, a turn where the velocity changes sign).
The equation is integrated with the classical Runge-Kutta method of order 4, ``substeps`` steps per sample interval
(:func:`substeps`: as many as the fastest rate of the stuck network asks, see below), cut at the switches, from
each unit perturbation in turn: Phi, the monodromy over the state (x, v, u). A branch
that never slides on the orbit keeps any offset: du - B dx is constant for it, a multiplier 1 whatever the
motion does (the family of stuck positions, neutral). Its u is therefore not a state of its own: a perturbation
moves it with x (du = B dx, the invariant subspace du - B dx = 0), and Phi is taken over x, v and the u of the
branches that slide (``floquet.variational_monodromy``).

Its error: that of the orbit's samples (the switch instants within O(h^2) of the sampled model's) and RK4's.
RK4 shrinks an undamped oscillation of phase theta per step by about theta^6 / 144, so over a period whose
fastest rate r (the stuck network's highest frequency, bounded by Gershgorin's rows of M^-1 K with every branch
stuck and every cubic spring at its steepest, or a dashpot's rate) turns a phase r T, the steps keep theta <=
(144 ACCURACY / (r T))^(1/5) (and <= 1/2): a multiplier off by at most about ACCURACY = MARGIN / 20. One step
per sample where the orbit is slow beside its samples (the usual case); many where a stiff branch rings far
above the forcing (1e6 N/m on 1 kg driven at 0.1 Hz: 1414 rad/s over 10 s; one step per sample there was
unstable, and the multipliers came out NaN: a packaged scene's find). Bounded: :func:`work` is the cost, which
``floquet.py`` holds against its budget before it runs. No backward Euler's damping to extrapolate away, and one
pass instead of 4 n + 2 periods of the stepper: about a hundredth of the cost, which is what lets every point of
a curve get its multipliers.
"""
from __future__ import annotations

import math

import numpy as np

from .._jit import kernel

ACCURACY = 1e-4  # a multiplier's error from RK4 over one period (floquet.MARGIN / 20)


def fastest_rate(system, cubic_elongation: np.ndarray) -> float:
    """A bound on the fastest rate (1/s) of the variational equation of ``system``: Gershgorin's rows of
    M^-1 (K + every branch stuck + every cubic spring at 3 k3 e^2, e its largest |elongation|
    ``cubic_elongation``) under a square root, or a dashpot's rows of M^-1 C."""
    n = system.n
    rows = np.abs(system.stiffness).sum(axis=1)
    damping = np.abs(system.damping).sum(axis=1)
    for ends, k in ((system.branch_ends, np.abs(system.branch_k)),
                    (system.cubic_ends, 3.0 * np.abs(system.cubic_k3) * np.asarray(cubic_elongation) ** 2)):
        for (p, q), value in zip(ends.tolist(), k.tolist()):
            for end in (p, q):
                if 0 <= end < n:
                    rows[end] += 2.0 * value
    return float(max(np.max(np.sqrt(rows / system.mass)), np.max(damping / system.mass), 0.0))


def substeps(rate: float, period: float, samples: int) -> int:
    """RK4 steps per sample interval for an error of about ACCURACY on the multipliers over one period whose
    fastest rate is ``rate`` (see the module)."""
    turn = rate * period
    if turn <= 0.0:
        return 1
    theta = min(0.5, (144.0 * ACCURACY / turn) ** 0.2)
    # at most 2^62 (a period of 1e300 s, a frequency of 1e-300 Hz, overflowed the integer): the work's bound
    # refuses far below that
    return max(1, math.ceil(min(turn / samples / theta, 2.0**62)))


def work(samples: int, steps: int, n: int, rows: int, columns: int, switches: int) -> float:
    """The cost of :func:`monodromy` in multiply-adds: four stages per RK4 step, each rows x columns and the
    dense K and C of the n nodes (2 n^2) per column."""
    return 4.0 * (samples * steps + switches) * (rows + 2.0 * n * n) * columns


@kernel
def _derivative(z, out, inverse_mass, C, K, cubic_ends, cubic_k3, cubic_e, branch_ends, branch_k, sticking, columns):
    """out = z' for the perturbations z (2 n + nb, columns) at one instant (cubic_e: the cubic springs'
    elongations then; sticking: 1 for the branches that stick)."""
    n = inverse_mass.shape[0]
    nb = branch_k.shape[0]
    for col in range(columns):
        for i in range(n):
            out[i, col] = z[n + i, col]
        for i in range(n):
            force = 0.0
            for j in range(n):
                force -= C[i, j] * z[n + j, col] + K[i, j] * z[j, col]
            out[n + i, col] = force
        for c in range(cubic_k3.shape[0]):
            p, q = cubic_ends[c, 0], cubic_ends[c, 1]
            slope = 3.0 * cubic_k3[c] * cubic_e[c] * cubic_e[c]
            de = z[p, col] - (z[q, col] if q >= 0 else 0.0)
            out[n + p, col] -= slope * de
            if q >= 0:
                out[n + q, col] += slope * de
        for b in range(nb):
            p, q = branch_ends[b, 0], branch_ends[b, 1]
            force = branch_k[b] * z[2 * n + b, col]
            out[n + p, col] -= force
            if q >= 0:
                out[n + q, col] += force
            if sticking[b]:
                out[2 * n + b, col] = z[n + p, col] - (z[n + q, col] if q >= 0 else 0.0)
            else:
                out[2 * n + b, col] = 0.0
        for i in range(n):
            out[n + i, col] *= inverse_mass[i]


@kernel
def _advance(z, duration, start, h, inverse_mass, C, K, cubic_ends, cubic_k3, cubic_samples, j, branch_ends,
             branch_k, sticking, stages, cubic_e, samples):
    """z advanced by ``duration`` (one RK4 step) from the fraction ``start`` of sample interval j, of length h
    (the cubic springs' elongations linear between its samples)."""
    rows, columns = z.shape[0], z.shape[1]
    k1, k2, k3, k4, trial = stages[0], stages[1], stages[2], stages[3], stages[4]
    fraction = duration / h
    nxt = j + 1 if j + 1 < samples else 0
    for stage in range(4):
        where = start + (0.0 if stage == 0 else 0.5 * fraction if stage < 3 else fraction)
        for c in range(cubic_k3.shape[0]):
            cubic_e[c] = (1.0 - where) * cubic_samples[c, j] + where * cubic_samples[c, nxt]
        if stage == 0:
            _derivative(z, k1, inverse_mass, C, K, cubic_ends, cubic_k3, cubic_e, branch_ends, branch_k, sticking,
                        columns)
            _step(trial, z, k1, 0.5 * duration, rows, columns)
        elif stage == 1:
            _derivative(trial, k2, inverse_mass, C, K, cubic_ends, cubic_k3, cubic_e, branch_ends, branch_k,
                        sticking, columns)
            _step(trial, z, k2, 0.5 * duration, rows, columns)
        elif stage == 2:
            _derivative(trial, k3, inverse_mass, C, K, cubic_ends, cubic_k3, cubic_e, branch_ends, branch_k,
                        sticking, columns)
            _step(trial, z, k3, duration, rows, columns)
        else:
            _derivative(trial, k4, inverse_mass, C, K, cubic_ends, cubic_k3, cubic_e, branch_ends, branch_k,
                        sticking, columns)
    sixth = duration / 6.0
    for r in range(rows):
        for col in range(columns):
            z[r, col] += sixth * (k1[r, col] + 2.0 * k2[r, col] + 2.0 * k3[r, col] + k4[r, col])


@kernel
def _step(out, z, slope, span, rows, columns):
    """out = z + span slope, in place."""
    for r in range(rows):
        for col in range(columns):
            out[r, col] = z[r, col] + span * slope[r, col]


@kernel
def monodromy(period, samples, inverse_mass, C, K, cubic_ends, cubic_k3, cubic_samples, branch_ends, branch_k,
              branch_eta, e, velocity, u0, steps, z, since):
    """z (2 n + nb, columns), in place: the perturbations (x, v, u) at t = 0 in, at t = T out (see the module),
    over one period of ``samples`` intervals; ``e`` and ``velocity`` (nb, samples): the branches' elongations and
    their rates at the samples; ``u0`` (nb,): u at sample 0; ``cubic_samples`` (nc, samples): the cubic springs'
    elongations; ``steps``: RK4 steps per sample interval (:func:`substeps`), a piece of it cut at a switch
    taking its share. ``since`` (nb,) out: the instant each branch last started to stick from du = 0 (2 j + 1: a
    turn inside interval j; 2 j: at sample j, 2 ``samples`` the period's end), -1 if it never did, -2 if it
    slides at the period's end (its du is 0 there): the branches of one pair with the same instant end the
    period with the same du - B dx (:func:`reduced`)."""
    n = inverse_mass.shape[0]
    nb = branch_k.shape[0]
    h = period / samples
    dim = 2 * n + nb
    stages = np.zeros((5, dim, z.shape[1]))
    cubic_e = np.zeros(cubic_k3.shape[0])
    u = u0.copy()
    sticking = np.ones(nb, dtype=np.int64)
    events = np.empty(nb)
    due = np.empty(nb, dtype=np.int64)
    for b in range(nb):
        since[b] = -1
    for interval in range(samples + 1):
        j = interval if interval < samples else 0
        _resynchronise(u, velocity, branch_eta, j, sticking, z, n, since, 2 * interval)  # as the orbit's u says
        if interval == samples:  # (back at sample 0: the period's end)
            for b in range(nb):
                if not sticking[b]:
                    since[b] = -2
            break
        nxt = j + 1 if j + 1 < samples else 0
        # each branch's switch inside this interval (fraction in [0, 1)), or 2 for none
        for b in range(nb):
            events[b] = 2.0
            de = e[b, nxt] - e[b, j]
            if sticking[b]:
                if de > 0.0 and u[b] + de > branch_eta[b]:
                    events[b] = (branch_eta[b] - u[b]) / de
                elif de < 0.0 and u[b] + de < -branch_eta[b]:
                    events[b] = (-branch_eta[b] - u[b]) / de
            elif velocity[b, j] * velocity[b, nxt] < 0.0:
                events[b] = velocity[b, j] / (velocity[b, j] - velocity[b, nxt])
        # the switches inside the interval in the order of their instants (each branch at most once here)
        count = 0
        for b in range(nb):
            if events[b] < 1.0:
                due[count] = b
                count += 1
        order = np.argsort(events[due[:count]])
        start = 0.0
        for k in range(count + 1):
            first, which = 1.0, -1
            if k < count:
                which = due[order[k]]
                first = events[which]
            span = (first - start) * h
            if span > 0.0:
                pieces = max(1, int(math.ceil(steps * (first - start))))
                for piece in range(pieces):
                    _advance(z, span / pieces, start + piece * (first - start) / pieces, h, inverse_mass, C, K,
                             cubic_ends, cubic_k3, cubic_samples, j, branch_ends, branch_k, sticking, stages,
                             cubic_e, samples)
            if which < 0:
                break
            if sticking[which]:  # reaches its threshold: slides, its perturbation lost
                sticking[which] = 0
                for col in range(z.shape[1]):
                    z[2 * n + which, col] = 0.0
            else:  # turns: sticks from du = 0 (it was 0 while it slid)
                sticking[which] = 1
                since[which] = 2 * interval + 1
            start = first
        for b in range(nb):  # the orbit's u at the next sample (the play operator on the samples)
            moved = u[b] + e[b, nxt] - e[b, j]
            if moved > branch_eta[b]:
                moved = branch_eta[b]
            elif moved < -branch_eta[b]:
                moved = -branch_eta[b]
            u[b] = moved


@kernel
def _resynchronise(u, velocity, branch_eta, j, sticking, z, n, since, instant):
    """At sample j, each branch sticks or slides as the orbit's u and velocity say (a branch on its threshold
    with the motion pushing on slides, its perturbation lost; any other sticks: from du = 0 if it slid, at
    ``instant``)."""
    for b in range(u.shape[0]):
        sliding = (u[b] >= branch_eta[b] * (1.0 - 1e-12) and velocity[b, j] > 0.0) or \
            (u[b] <= -branch_eta[b] * (1.0 - 1e-12) and velocity[b, j] < 0.0)
        if sliding and sticking[b]:
            for col in range(z.shape[1]):
                z[2 * n + b, col] = 0.0
        if not sliding and not sticking[b]:
            since[b] = instant
        sticking[b] = 0 if sliding else 1
