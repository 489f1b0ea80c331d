"""Stability of a periodic state: Floquet multipliers from the monodromy of one period.

Where every node has a mass and there is no series dashpot and no effect with memory, the monodromy comes from
the variational equation along the balance's orbit (``variational.py``, :func:`variational_monodromy`): exact
for the sampled orbit, a hundredth of the cost of what follows, so every point of a curve gets its multipliers.

Elsewhere: the monodromy matrix by finite differences, each column one period integrated with the project's
own ``implicit`` network stepper (``network/kernels.py``: an exact active-set method for the branches, backward
Euler in time) from the harmonic balance's state at t = 0 with one component perturbed, the orbit's own period
integrated beside it; Phi[:, k] = (state(T) perturbed - state(T)) / epsilon over the state: the x and v of the
nodes with a mass (a massless node follows them) and the u of the branches that slide on the orbit (and of
those with series dashpots), u at t = 0 from the sampled cycle of ``aft.py``. A branch that never slides keeps
any offset (a neutral multiplier 1, the family of stuck positions): its u is no state of its own but moves with
x when x is perturbed (the invariant subspace du = dx_p - dx_q). Why not Hill's method: its eigenvalues come
from the Jacobian of the harmonic balance, whose truncation puts spurious eigenvalues beside the true ones, and
with the kinks of slipping branches the sorting of the physical ones is not reliable; the monodromy sees the
slips and sticks as they happen (the perturbed runs cross the same events a little earlier or later).

Under base excitation the runs are in absolute coordinates, the ground a massless node whose motion
y = Y0 cos(omega t) is imposed at each step (:func:`_based_period`), and the state in and out relative
(z = x - y): what the balance solves for. With one node with a mass this agrees with integrating the relative
coordinate under its force m omega^2 Y0 cos(omega t) (:func:`forced_scene`) to 2e-6 at 4096 steps on a mass
on a Jenkins element; the two discretize the base's motion differently and differ by up to 1 % at 256 steps.

Backward Euler damps: with M steps per period a multiplier is shrunk by about exp(-(2 pi)^2 / (2 M)
(omega_n / omega)^2) per period, omega_n the motion's frequency. The monodromy is taken at M and 2 M steps and
its multipliers extrapolated in their logarithm (Richardson, first order in the exponent: mu_2M^2 / mu_M, each
with its partner at M: each the other's nearest (a double multiplier's copies each with a copy), of one kind,
their ratio within e^GROWTH; one without a partner is not extrapolated: :func:`extrapolated`, :func:`pairs`; not the matrices, whose structure can differ where a slip starts between steps), which
leaves an error of order 1 / M^2 in the exponent. Until the largest's shrinking between the two is within
SHRINK (far below the resonance the value is not yet in the extrapolation's range, nor the verdict: a
multiplier above 1 can be shrunk below it) and the verdict is sure (the largest |mu| farther from 1 than 4 times
its last change, or that change below MARGIN / 2), the pair moves to 2 M and 4 M, and so on, at most
REFINEMENTS times (:func:`refined`); still shrinking past SHRINK there, or the verdict still in doubt, the
point's multipliers are not computed (unknown). At a lightly damped joint's resonance peak M = 256 and 512 give 0.878 and 0.913 and extrapolate to
0.94886, where the pair 4096 and 8192 gives 0.94890 (the extrapolation of the multipliers themselves, 2 mu_2M -
mu_M, gave 0.9475 from 256 and 512). Every point of a curve gets its own (a few tens of ms a point). What the
shrinking hides is not seen: a motion much faster than the forcing (omega_n / omega past about 26 at 16384
steps) whose multiplier falls below the largest one's at every resolution is not among those judged.

An element scene with effects with memory (``[delay]``, ``[history]``, ``[dahl]``: the network stepper knows none
of them) is integrated by the element's own ``implicit`` stepper instead (``memory/``: the delay from its
buffer, the history's variables integrated exactly along the step, Dahl's exact move), from the orbit's state
at t = 0 with the memory's state taken from the balance (:func:`_memory_period`), and the monodromy is over the
whole state: x, v, each history variable z_j (its steady value from the harmonics, z_j = (r_j + omega D)^-1 y),
F_d (from its sampled cycle), and the delay's buffer, the values of y at the grid points t - tau - h ... t
(ceil(tau / h) + 2 of them: a discretised delay is that many states). With at most DENSE_STATES states each
is perturbed in turn, one period's run each; past it (a delay's buffer) the monodromy is never formed: its
LARGEST multipliers come from Arnoldi's iteration (:func:`leading`, :func:`arnoldi`), each product with a
vector one period's run from the state moved along it, a few tens of runs where the whole matrix took one per
buffer value (Hill's method for the delay alone would need the branches' nonsmooth linearisation; the
propagation of the linear part alone does not see the branches). Bounded: at most KRYLOV_RUNS runs (not
converged by then: the point's stability is not computed, ``None``, an empty field, never a guess) and
MAX_DELAY_STATES buffer values at the finer resolution (a delay longer than about 64 periods at M = 512), and
a refinement past either keeps the pair before. With a delay the two resolutions have monodromies of
different sizes: the LARGEST multipliers at 2 M are extrapolated.

A point is ``stable`` when every multiplier has |mu| <= 1 + MARGIN (MARGIN covers the finite differences and
the extrapolation; a fold, where one multiplier crosses 1, is stable to either side within it).

**Bounded work.** A monodromy costs the state's size squared times the steps of a period: with many sliding
branches (the packaged ``many-branches``: 100 000 of them, a matrix of 74.5 GiB) that is out of reach. Each
point's cost is held against WORK_LIMIT multiply-adds before it runs (``variational.work``; for the finite
differences, a period per state of its steps over every element); past it the multipliers are not computed.
Then the verdict comes from the scene where it can (:func:`monotone`): linear springs and dashpots with positive
semi-definite matrices, branches (with or without series dashpots) and sliders are monotone, so the energy of
the difference of two motions, 1/2 dv' M dv + 1/2 dx' K dx + 1/2 sum k_b du_b^2, never grows: every multiplier
has |mu| <= 1, every point is stable, proven rather than measured (the curve's ``largest`` multiplier is NaN
there; and where the finite differences of such a scene say unstable, they are wrong: stable, the value NaN,
``curve.py``). Elsewhere (a cubic spring, memory) the point's stability is unknown: an empty field, never a
guess.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Optional

import numpy as np

STEPS = 256
MARGIN = 2e-3
PERTURBATION = 1e-6
MAX_DELAY_STATES = 2**15  # a delay's buffer values (about 64 periods at 512 steps)
DENSE_STATES = 64  # past it the largest multipliers by Arnoldi's iteration (leading), not the whole monodromy
KRYLOV_RUNS = 800  # Arnoldi's products (a period's run each) one monodromy may take: the work bound
KRYLOV_BASIS = 80  # Arnoldi's vectors at most (restarted past it): 81 x MAX_DELAY_STATES values, 21 MB
FULL_BASIS = 400  # up to this size the basis may hold the whole space (no restart: a spectrum on one circle)
KRYLOV_CHECK = 5  # the Ritz values are looked at every so many products
RITZ_TOLERANCE = 1e-6  # a Ritz value's residual, relative: far below MARGIN
NOISE = 1e-6  # a multiplier below it is rounding in the finite differences: no partner (not extrapolated)
SHRINK = 0.4  # log(mu_2M / mu_M) of the largest: past it the pair moves to finer steps (past it at the last: unknown)
DOUBLE = 1e-4  # two multipliers within this of each other (relative) are one double multiplier's copies (pairs)
GROWTH = 1.5  # |log(mu_2M / mu_M)| past which a pair is not extrapolated in the logarithm (extrapolated)
REFINEMENTS = 6  # of the steps per period of the finite differences: at most STEPS 2^6 (16384)
LARGEST = 8  # the multipliers extrapolated (with a delay the two resolutions have monodromies of different sizes)
# the multiply-adds one point's monodromy may cost (a few seconds); past it the multipliers are not computed
WORK_LIMIT = 4e9


def orbit_start(balance, q_free, omega) -> tuple:
    """(x, v, u) at t = 0 of the harmonic balance's orbit: per node, and per network element (u of branches)."""
    full = balance.full(q_free)
    coefficients = full.reshape(balance.system.n, balance.L)
    H = balance.H
    x = coefficients[:, 0] + coefficients[:, 1::2].sum(axis=1)
    v = omega * (coefficients[:, 2::2] * np.arange(1, H + 1)).sum(axis=1)
    balance.nonlinear(full, omega)  # the elongations of the branches at sample 0
    u = np.zeros(len(balance.system.network.elements))
    u[balance.system.branch_index] = balance.elongations
    for group, elongations in zip(balance.system.series, balance.series_u):
        u[group.index] = elongations
    return x, v, u


def variational(system) -> bool:
    """Whether the multipliers of ``system``'s points come from the variational equation (``variational.py``):
    every node with a mass, no series dashpot, no effect with memory; else from the finite differences of the
    steppers (see the module)."""
    return bool(np.all(system.mass > 0)) and not system.series and system.memory is None


def multipliers(balance, q_free, omega, steps: int = STEPS):
    """The Floquet multipliers (complex; the LARGEST, extrapolated, where they come from finite differences: see
    :func:`refined`) of the orbit of ``balance`` at ``omega`` (rad/s); None where they are not computed (past the
    work bound, a delay past MAX_DELAY_STATES, Arnoldi's iteration not converged, backward Euler's shrinking past
    SHRINK at the finest steps, a step of the finite differences refused by the stepper)."""
    if variational(balance.system):
        monodromy = variational_monodromy(balance, q_free, omega)
        return None if monodromy is None else np.linalg.eigvals(monodromy)
    system = balance.system
    _, states = _branch_states(balance, q_free)
    if system.memory is not None:
        def at(count):
            return _memory_multipliers(balance, q_free, omega, count)
    else:
        def at(count):
            # 2 n + states + 1 periods of count steps, each step over every node and element
            cost = (2.0 * system.n + states.size + 1) * count * (system.n + len(system.network.elements)) * 64
            if cost > WORK_LIMIT:
                return None
            return np.linalg.eigvals(_monodromy(balance, q_free, omega, count))

    def checked(count):
        from ..stepping import ElementError

        try:
            return at(count)
        except ElementError:  # a step of the check refused by its stepper (its own bound): not computed
            return None
    return refined(checked, steps)


def refined(at, steps: int):
    """The multipliers from ``at(M)`` (the eigenvalues of the monodromy at M steps per period, None where not
    computed), extrapolated from M and 2 M (:func:`extrapolated`: the LARGEST ones at 2 M), the pair moved to 2 M
    and 4 M ... until the largest has a partner at M (:func:`pairs`), its shrinking from M to 2 M, |log(mu_2M /
    mu_M)|, is at most SHRINK (its value in the extrapolation's range: within about 1e-3, measured far below an
    oscillator's resonance), every multiplier without a partner stays below 1 even moved 4 times as far as from
    its partner at M, and either |mu| - 1 of the largest is more than 4 times its last change (from the pair before,
    or for the first pair from its value at 2 M) or that change is below MARGIN / 2; at most REFINEMENTS times.
    None (unknown, never a guess) where ``at`` gives none before a first pair (a delay's buffer too long), or
    where the last pair reached (REFINEMENTS, or a finer one not computed) is still shrinking past SHRINK or its
    verdict still in doubt (a slip that starts between steps at one resolution and not at the next: on a joint
    with a cubic spring 0.760, 0.871, 0.936, 0.896 at 1024 ... 8192 steps, its pairs 0.98, 1.006, 0.858)."""
    fine = at(2 * steps)  # first: where the finer has none (a delay's buffer past its bound), nothing is run
    if fine is None:
        return None
    coarse = at(steps)
    if coarse is None:
        return None
    previous = None
    for level in range(1, REFINEMENTS + 1):
        if level > 1:
            fine = at(steps * 2**level)
        if fine is None:
            break
        kept = fine[np.argsort(-np.abs(fine))[:min(LARGEST, fine.size)]]
        values = extrapolated(kept, coarse, fine)
        partner, paired = pairs(kept, coarse, fine)
        largest = int(np.argmax(np.abs(values)))
        top = float(abs(values[largest]))
        change = abs(top - float(np.max(np.abs(fine)))) if previous is None else abs(top - previous)
        # backward Euler's shrinking of the largest over a period, log(mu_2M / mu_M) with its partner at M: past
        # SHRINK its value is not yet in the extrapolation's range (nor is the verdict: a multiplier above 1 can
        # be shrunk below it, down to rounding at M: 0.6 seen as 1e-15 and 6e-31 at 512 and 256 steps, and 5e5
        # as 0 at both, far below a delay's unstable resonance); the largest must have a partner, and one
        # without (not extrapolated) must stay below 1 even if it moved 4 times as far as from its partner at M
        at_fine, at_coarse = abs(kept[largest]), abs(partner[largest])
        settled = bool(paired[largest]) and min(at_fine, at_coarse) > 0.0 and \
            abs(math.log(at_fine / at_coarse)) <= SHRINK and \
            not np.any(~paired & (np.abs(kept) >= 1.0 - 4.0 * np.abs(kept - partner)))
        if settled and (abs(top - 1.0) > 4.0 * change or (previous is not None and change <= 0.5 * MARGIN)):
            return values
        previous, coarse = top, fine
    return None  # still shrinking, or the verdict still in doubt, at the finest pair: unknown, not a guess


def extrapolated(fine: np.ndarray, coarse: np.ndarray, among: Optional[np.ndarray] = None) -> np.ndarray:
    """Richardson's first-order extrapolation of multipliers in their logarithm, mu_2M^2 / mu_M, each of ``fine``
    (2 M steps) with its partner in ``coarse`` (M steps: :func:`pairs`). In the logarithm because backward
    Euler's error is in the exponent: with M steps a multiplier is shrunk by about exp(-a / M) (a = (2 pi
    omega_n / omega)^2 / 2 for a motion of frequency omega_n), and mu_2M^2 / mu_M removes that term, where 2
    mu_2M - mu_M (the same to first order near |mu| = 1) is off by a factor once a / M nears 1: 0.30 for 0.54 on
    an oscillator at omega_n / omega = 5.3 (256 and 512 steps), where this gives 0.539. A multiplier without a
    partner is not extrapolated: its value at 2 M (:func:`refined` goes on to finer steps while the largest has
    none, or one without a partner could reach 1).

    On the multipliers, not on the matrices: where a slip starts between two steps at one resolution and not at
    the other, the two monodromies differ in structure and 2 Phi_2M - Phi_M can have an eigenvalue that neither
    has (|mu| = 1.12 at a resonance peak whose multipliers are 0.87 at M = 256 and 0.90 at 512, 0.946 at 4096:
    a stable point called unstable)."""
    partner, paired = pairs(fine, coarse, among)
    out = np.array(fine, dtype=complex)
    out[paired] = fine[paired] ** 2 / partner[paired]
    return out


def pairs(fine: np.ndarray, coarse: np.ndarray, among: Optional[np.ndarray] = None) -> tuple:
    """``(partner, paired)``: for each of ``fine`` (2 M steps, some of ``among``: all the multipliers at 2 M,
    default ``fine``) its partner in ``coarse`` (M steps), and whether the two are one multiplier seen at two
    resolutions: each the other's nearest (of ``coarse`` and of ``among``), of one kind (real of one sign, or
    complex in the same half plane), the coarse one above NOISE, their ratio within e^GROWTH. A double
    multiplier (two at 2 M within DOUBLE of each other, relative) has both its copies' nearest at M the same, so
    the copy that is not that one's nearest takes its twin at M (another within DOUBLE of it, not yet taken),
    where there are as many copies at M as at 2 M: without it one copy never had a partner, and three identical
    arms on a massless joint took 8192 steps a point, 7 times the work (a review's find); without the count, an
    unstable multiplier that crosses a double at 2 M took the double's spare copy at M and was called stable (a
    second review's find). Elsewhere they are not one multiplier: where a slip starts
    between steps at one resolution and not at the other the monodromies differ in structure (0.148 at 4096
    steps nearest to 0.0005 at 2048 made 45 in the logarithm, on a scene whose every multiplier is at most 1);
    two real multipliers that become a complex pair (a joint with a cubic spring at 0.48 Hz: 1.136 and 0.783 at
    1024 steps, 0.907 +- 0.314 i at 2048) made 1.21 (unstable) linearly and 1.18 in the logarithm, where the pair
    at 4096 and 2048 steps gives 0.975. Not nearest first over all pairs: at 0.0587 Hz on that joint 0.7473 and
    0.6180 at 1024 steps against 0.5861 and 0.4885 at 512 would pair 0.6180 with 0.5861 first, then 0.7473 with
    0.4885, whose logarithm made 1.14 (and 1.17 at the next pair), unstable, where 8192 steps give 0.98."""
    fine = np.asarray(fine, dtype=complex)
    coarse = np.asarray(coarse, dtype=complex)
    among = fine if among is None else np.asarray(among, dtype=complex)
    nearest = np.array([int(np.argmin(np.abs(coarse - mu))) for mu in fine.tolist()], dtype=np.int64)
    back = np.array([among[np.argmin(np.abs(among - coarse[j]))] for j in nearest.tolist()], dtype=complex)
    mutual = back == fine
    taken = {int(j) for j in nearest[mutual]}
    for k in np.flatnonzero(~mutual).tolist():
        j = int(nearest[k])
        if abs(fine[k] - back[k]) > DOUBLE * abs(back[k]):
            continue  # not a copy of the multiplier that took its nearest
        copies = int(np.count_nonzero(np.abs(among - back[k]) <= DOUBLE * abs(back[k])))
        if copies != int(np.count_nonzero(np.abs(coarse - coarse[j]) <= DOUBLE * abs(coarse[j]))):
            continue  # as many copies at 2 M as at M, else another multiplier crosses the double there
        twins = [i for i in range(coarse.size)
                 if i not in taken and abs(coarse[i] - coarse[j]) <= DOUBLE * abs(coarse[j])]
        if twins:
            twin = min(twins, key=lambda i: abs(coarse[i] - fine[k]))
            nearest[k], mutual[k] = twin, True
            taken.add(twin)
    partner = coarse[nearest]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.abs(fine) / np.abs(partner)
    paired = mutual & (_kind(fine) == _kind(partner)) & (np.abs(partner) > NOISE) & \
        (ratio <= math.exp(GROWTH)) & (ratio >= math.exp(-GROWTH))
    return partner, paired


def _kind(values: np.ndarray) -> np.ndarray:
    """+-1: complex in the upper or lower half plane; +-2: real, positive or negative; 0: zero."""
    return np.where(values.imag != 0, np.sign(values.imag), 2 * np.sign(values.real))


def variational_monodromy(balance, q_free, omega):
    """A matrix whose eigenvalues are the multipliers of the orbit of ``balance`` at ``omega``, from its
    variational equation on the balance's N samples (``variational.py``); None where its work would pass
    WORK_LIMIT. The monodromy over x, v and the u of the branches that slide on the orbit (a stuck branch's u
    moves with x), or, where it is smaller, :func:`reduced`'s matrix: its nonzero eigenvalues are the
    monodromy's, its size 2 n plus the instants at which the sliding branches last start to stick (a few per
    pair of nodes however many branches it holds)."""
    from .variational import fastest_rate, monodromy, substeps, work

    system = balance.system
    full = balance.full(q_free)
    coefficients = full.reshape(system.n, balance.L)
    x = coefficients @ balance.basis.T  # (n, N)
    v = omega * (coefficients @ balance.derivative.T) @ balance.basis.T
    balance.nonlinear(full, omega)  # the elongations of the branches at sample 0

    ends = system.branch_ends

    def relative(values, pairs):
        if not len(pairs):
            return np.zeros((0, values.shape[1]))
        return values[pairs[:, 0]] - np.where(pairs[:, 1:] >= 0, values[np.maximum(pairs[:, 1], 0)], 0.0)

    n, nb = system.n, system.branch_k.shape[0]
    e = relative(x, ends)
    sliding = np.flatnonzero(_slides(system, x))
    cubic_e = relative(x, system.cubic_ends)
    period = 2.0 * math.pi / omega
    velocity = relative(v, ends)
    steps = substeps(fastest_rate(system, np.max(np.abs(cubic_e), axis=1, initial=0.0)), period, balance.N)
    # each reversal of a sliding branch: at most a turn and a threshold
    switches = 2 * int(np.sum(np.diff(np.sign(velocity[sliding]), axis=1) != 0)) + 2 * sliding.size
    since = np.empty(nb, dtype=np.int64)

    def run(z):
        monodromy(period, balance.N, 1.0 / system.mass, system.damping, system.stiffness, system.cubic_ends,
                  system.cubic_k3, cubic_e, ends, system.branch_k, system.branch_eta, e, velocity,
                  balance.elongations.copy(), steps, z, since)
        return z

    # the columns: unit x and v, a stuck branch's u moving with x (du = B dx)
    stuck = np.ones(nb, dtype=bool)
    stuck[sliding] = False
    columns = 2 * n + sliding.size
    if sliding.size > 1:  # the instants the sliding branches last start to stick (a run without columns)
        if work(balance.N, steps, n, 2 * n + nb, 1, switches) > WORK_LIMIT:
            return None
        run(np.zeros((2 * n + nb, 0)))
        plan = reduced(ends, sliding, since, n)
        columns = min(columns, plan[0])
    if work(balance.N, steps, n, 2 * n + nb, columns, switches) > WORK_LIMIT:
        return None
    if sliding.size > 1 and plan[0] < 2 * n + sliding.size:
        return _reduced_monodromy(run, plan, ends, stuck, n, nb)
    z = np.zeros((2 * n + nb, 2 * n + sliding.size))
    z[np.arange(2 * n), np.arange(2 * n)] = 1.0
    _moving_with_x(z, ends, stuck, n)
    z[2 * n + sliding, 2 * n + np.arange(sliding.size)] = 1.0
    run(z)
    return z[np.concatenate((np.arange(2 * n), 2 * n + sliding))]


def _moving_with_x(z, ends, which, n) -> None:
    """The u of the branches ``which`` (a mask) moving with x in the first n columns of z: du = B dx."""
    index = np.flatnonzero(which)
    z[2 * n + index, ends[index, 0]] = 1.0
    grounded = ends[index, 1] < 0
    z[2 * n + index[~grounded], ends[index[~grounded], 1]] = -1.0


def reduced(ends, sliding, since, n) -> tuple:
    """How the monodromy P over (dx, dv, du of the ``sliding`` branches) factors, P = D C. A sliding branch
    that ends the period stuck since an instant tau (``since``, from ``variational.monodromy``: it started to
    stick there from du = 0, and du - B dx is constant while it sticks) ends it with du = B dx(T) - W, W = B
    dx(tau) the same for every branch of its pair that started at tau: C maps the perturbation at t = 0 to
    w = (dx(T), dv(T), the du(T) of the branches that never started again (``since`` -1, kept as they are),
    the W of each group), D maps w back to the state (a branch sliding at T, ``since`` -2, has du = 0). The
    nonzero eigenvalues of P = D C are those of C D, of size 2 n + kept + groups: ``(size, kept, groups)``, the
    branch indices kept and one index array per group."""
    kept = [int(b) for b in sliding if since[b] == -1]
    groups = {}
    for b in sliding:
        if since[b] >= 0:
            groups.setdefault((int(ends[b, 0]), int(ends[b, 1]), int(since[b])), []).append(int(b))
    members = [np.array(group, dtype=np.int64) for group in groups.values()]
    return 2 * n + len(kept) + len(members), np.array(kept, dtype=np.int64), members


def _reduced_monodromy(run, plan, ends, stuck, n, nb) -> np.ndarray:
    """C D of :func:`reduced`'s factorisation: each column of D (an x or v, a kept branch's u, a group's W = 1)
    run over the period from the state it stands for, and C read off the end (a group's W from any of its
    branches: B dx(T) - du(T))."""
    size, kept, members = plan
    z = np.zeros((2 * n + nb, size))
    z[np.arange(2 * n), np.arange(2 * n)] = 1.0
    grouped = np.zeros(nb, dtype=bool)
    for group in members:
        grouped[group] = True
    _moving_with_x(z, ends, stuck | grouped, n)  # du = B dx - W with W = 0 in the x columns
    z[2 * n + kept, 2 * n + np.arange(kept.size)] = 1.0
    for g, group in enumerate(members):
        z[2 * n + group, 2 * n + kept.size + g] = -1.0  # W = 1: du = -1
    run(z)
    out = np.empty((size, size))
    out[:2 * n] = z[:2 * n]
    out[2 * n:2 * n + kept.size] = z[2 * n + kept]
    for g, group in enumerate(members):
        b = group[0]
        p, r = ends[b]
        out[2 * n + kept.size + g] = z[p] - (z[r] if r >= 0 else 0.0) - z[2 * n + b]
    return out


def is_stable(values: np.ndarray) -> bool:
    return bool(np.max(np.abs(values)) <= 1.0 + MARGIN)


def monotone(system) -> bool:
    """Whether every periodic state of ``system`` is stable whatever its multipliers, by the energy of the
    difference of two motions (see the module): linear springs and dashpots whose matrices are positive
    semi-definite, Prandtl branches (with or without series dashpots) and sliders, no cubic spring, no effect
    with memory."""
    if system.memory is not None or np.any(system.cubic_k3 != 0.0):
        return False
    if np.any(system.branch_k < 0.0):
        return False
    return positive_semidefinite(system.stiffness) and positive_semidefinite(system.damping)


def positive_semidefinite(matrix: np.ndarray) -> bool:
    """Whether the symmetric part of ``matrix`` has no eigenvalue below -1e-12 of its largest entry."""
    symmetric = 0.5 * (matrix + matrix.T)
    scale = float(np.max(np.abs(symmetric), initial=0.0))
    return not (scale > 0.0 and float(np.min(np.linalg.eigvalsh(symmetric))) < -1e-12 * scale)


def _memory_multipliers(balance, q_free, omega, steps):
    """The LARGEST multipliers of the period map of :func:`_memory_period` (:func:`leading`; None: a delay past
    MAX_DELAY_STATES values, or Arnoldi's iteration not converged within KRYLOV_RUNS runs)."""
    period = _memory_period(balance, q_free, omega, steps)
    if period is None:
        return None
    return leading(*period, LARGEST)


def leading(run, state: np.ndarray, scales: np.ndarray, count: int):
    """The multipliers of the period map ``run`` at its fixed point ``state`` (``scales``: each component's
    finite difference): all of them, from the Jacobian by :func:`differences`, where the state has at most
    DENSE_STATES components; else the ``count`` of largest modulus, by Arnoldi's iteration on the Jacobian
    without forming it (:func:`arnoldi`: each product one period's run), None where they have not converged
    within KRYLOV_RUNS runs (unknown, never a guess)."""
    if state.size <= DENSE_STATES:
        monodromy = differences(run, state, scales)
        return np.linalg.eigvals(monodromy) if np.all(np.isfinite(monodromy)) else None
    base = run(state)

    def product(w):
        """(the Jacobian in the coordinates state / scales) w, by a forward difference whose largest component
        is the scales' own."""
        size = float(np.max(np.abs(w)))
        if size == 0.0:
            return np.zeros_like(w)
        return (run(state + scales * (w / size)) - base) / scales * size

    return arnoldi(product, state.size, min(count, state.size))


def arnoldi(product, size: int, count: int):
    """The ``count`` eigenvalues of largest modulus of the matrix A whose products are ``product`` (size x size),
    by Arnoldi's iteration from a fixed random start (Gram-Schmidt twice), restarted as Stewart's Krylov-Schur
    method keeps its basis at most KRYLOV_BASIS vectors past FULL_BASIS (below, the basis may fill the space: a
    spectrum on one circle is found there, where a restart loses it): A V = V S + v b' with V orthonormal, grown
    a product at a time; every KRYLOV_CHECK products, and when the basis is full, the Ritz values (eigenvalues of S) and
    their residuals |b' y|; returned once each of the ``count`` largest has a residual of at most
    RITZ_TOLERANCE times the largest modulus (at least 1); a full basis restarts from the span of the Ritz
    vectors of the largest (:func:`_kept`: about half the basis, conjugate pairs whole, in real arithmetic) with S
    their projection. A delay's monodromy suits it: its multipliers gather at 0 (the buffer's shift) but for a
    few, and these converge within a few tens of products (a delay of 30 s at 0.15 Hz, 2308 states: 45
    products, 0.01 s, the dense matrix's largest multipliers to 1e-7, the matrix itself 26 s); where they crowd
    near 1 (a delay of 370 s, 30 315 states) 400 to 480 products and 1.2 to 1.4 s, where the basis unrestarted
    (every product kept) took 350 to 400 and 4.4 to 5.7 s, its Gram-Schmidt over the whole basis dominating. None
    where they have not within KRYLOV_RUNS products (the work bound), or a product is not finite."""
    dimension = size if size <= FULL_BASIS else KRYLOV_BASIS
    basis = np.zeros((dimension + 1, size))
    relation = np.zeros((dimension + 1, dimension))  # A basis[:m] = basis[:m + 1] relation[:m + 1, :m]
    start = np.random.default_rng(0).standard_normal(size)
    basis[0] = start / np.linalg.norm(start)
    m = 0
    for run in range(1, KRYLOV_RUNS + 1):
        w = product(basis[m])
        if not np.all(np.isfinite(w)):
            return None
        for _ in range(2):  # Gram-Schmidt twice: orthogonal to rounding
            c = basis[:m + 1] @ w
            w = w - c @ basis[:m + 1]
            relation[:m + 1, m] += c
        beta = float(np.linalg.norm(w))
        relation[m + 1, m] = beta
        m += 1
        scale = max(float(np.max(np.abs(relation[:m + 1, :m]))), 1e-300)
        invariant = beta <= 1e-13 * scale  # the Krylov space is invariant: its Ritz values are eigenvalues
        if not invariant:
            basis[m] = w / beta
        if invariant or m == dimension or (m >= count and run % KRYLOV_CHECK == 0):
            theta, vectors = np.linalg.eig(relation[:m, :m])
            order = np.argsort(-np.abs(theta))
            wanted = order[:count]
            residual = np.abs(relation[m, :m] @ vectors[:, wanted])
            if invariant or np.all(residual <= RITZ_TOLERANCE * max(1.0, float(np.abs(theta[wanted[0]])))):
                return theta[wanted]
            if m == dimension:
                q, _ = np.linalg.qr(_kept(theta, vectors, order, count + (dimension - count) // 2))
                p = q.shape[1]
                following = basis[m].copy()
                basis[:p] = q.T @ basis[:m]
                basis[p] = following
                projected, residuals = q.T @ relation[:m, :m] @ q, relation[m, :m] @ q
                relation[:] = 0.0
                relation[:p, :p], relation[p, :p] = projected, residuals
                m = p
    return None


def _kept(theta: np.ndarray, vectors: np.ndarray, order: np.ndarray, keep: int) -> np.ndarray:
    """A real basis of the span of the Ritz vectors ``vectors`` of the ``keep`` largest Ritz values ``theta``
    (``order``: by modulus, largest first), conjugate pairs whole: each real one's vector, each complex pair's
    real and imaginary parts (their span is invariant under the real matrix), taken once."""
    chosen = order[:keep]
    columns = []
    for i in chosen.tolist():
        partner = np.abs(theta[chosen] - np.conj(theta[i])) <= 1e-12 * abs(theta[i])
        if theta[i].imag == 0.0:
            columns.append(vectors[:, i].real)
        elif theta[i].imag > 0.0 or not np.any(partner):  # a pair's parts, from whichever of the two is kept
            columns += [vectors[:, i].real, vectors[:, i].imag]
    return np.column_stack(columns)


def differences(run, state: np.ndarray, scales: np.ndarray) -> np.ndarray:
    """The Jacobian of ``run`` (a period's map) at ``state`` by forward differences, ``scales`` each step."""
    base = run(state)
    columns = []
    for k in range(state.size):
        moved = state.copy()
        moved[k] += scales[k]
        columns.append((run(moved) - base) / scales[k])
    return np.array(columns).T


def _memory_period(balance, q_free, omega, steps):
    """``(run, state, perturbations)`` for an element scene with effects with memory: ``run`` integrates one
    period of ``steps`` implicit steps of the element under its force from a state vector (x, v, the history's
    z_j, Dahl's F_d, the delay's buffer: see the module) at t = 0 of the orbit and returns the same vector at
    t = T; ``state`` the orbit's; ``perturbations`` the finite difference of each component (toward 0 for F_d,
    which is bounded by F_c). None where the delay's buffer needs more than MAX_DELAY_STATES values."""
    from ..compiled import compile_loop, compile_model
    from ..effects import Branches
    from ..loads import HarmonicLoad
    from ..memory.delay import HEAD
    from ..memory.history import Z
    from ..scene_tables import Solver
    from ..stepping import ElementError, integrate

    system = balance.system
    memory = system.memory
    period = 2.0 * math.pi / omega
    h = period / steps
    delay, history, dahl = memory.delay, memory.history, memory.dahl
    extra = 0 if delay is None else math.ceil(delay.tau / h) + 2  # the buffer's values that y(t - tau) reads
    if extra > MAX_DELAY_STATES:
        return None
    scene = memory.scene
    amplitude = balance.force_amplitude
    if amplitude is None:  # base excitation, in relative coordinates: m Y0 omega^2 cos(omega t)
        amplitude = float(system.mass[memory.node]) * balance.base_amplitude * omega * omega
    changes = dict(load=HarmonicLoad(amplitude, omega), solver=Solver("implicit", h, period, h))
    if scene.branches is not None and scene.branches.continuum:  # the balance's branches at quadrature nodes
        changes["branches"] = Branches(system.branch_k.copy(), system.branch_eta.copy(),
                                       np.zeros(system.branch_k.shape[0]))
    scene = dataclasses.replace(scene, **changes)
    model = compile_model(scene, "play")
    loop = compile_loop(scene, "implicit")
    load = scene.load.compile()
    delay_part, history_part, dahl_part = model[8]

    x0, v0, u_network = orbit_start(balance, q_free, omega)
    branches = [i for i, e in enumerate(system.network.elements) if e.kind == "branch"]
    u0 = u_network[branches].copy() if branches else None
    stuck_network, sliding_network = _branch_states(balance, q_free)  # a stuck branch's u moves with x
    stuck = np.array([branches.index(i) for i in stuck_network], dtype=np.int64)
    sliding = np.array([branches.index(i) for i in sliding_network.tolist()], dtype=np.int64)
    coefficients = balance.full(q_free).reshape(system.n, balance.L)[memory.node]
    D = balance.derivative

    def y_coefficients(effect):
        return omega * D @ coefficients if effect.acts_on == "v" else coefficients

    def at(c, t):
        """The value at time t of the motion with harmonics c."""
        h_k = np.arange(1, balance.H + 1)
        return c[0] + c[1::2] @ np.cos(h_k * omega * t) + c[2::2] @ np.sin(h_k * omega * t)

    size = max(abs(x0[memory.node]), abs(v0[memory.node]) / omega, float(np.max(np.abs(coefficients))), 1e-300)
    state, scales = [x0[memory.node], v0[memory.node]], [PERTURBATION * size, PERTURBATION * size * omega]
    if history is not None:
        y = y_coefficients(history)
        y_size = size * (omega if history.acts_on == "v" else 1.0)
        for rate in history.rate:
            z = np.linalg.solve(rate * np.eye(balance.L) + omega * D, y)
            state.append(z[0] + z[1::2].sum())
            scales.append(PERTURBATION * y_size / max(rate, omega))
    if dahl is not None:
        state.append(balance.dahl_force)
        scales.append(-PERTURBATION * dahl.force if balance.dahl_force > 0 else PERTURBATION * dahl.force)
    first_step = 0
    if delay is not None:
        y = y_coefficients(delay)
        periods = math.ceil((delay.tau + 2.0 * h) / period)  # start late enough that y(t - tau) is on the buffer
        first_step = periods * steps
        buffer = delay_part[1]
        capacity = buffer.shape[0] - HEAD
        grid = np.arange(first_step - capacity + 1, first_step + 1)
        orbit_buffer = np.array([at(y, j * h) for j in grid.tolist()])
        y_size = size * (omega if delay.acts_on == "v" else 1.0)
        state.extend(orbit_buffer[-extra:].tolist())
        scales.extend([PERTURBATION * y_size] * extra)
    if u0 is not None:  # the sliding branches' u last
        at_u = len(state)
        state.extend(u0[sliding].tolist())
        scales.extend([PERTURBATION * size] * sliding.size)
    state, scales = np.array(state, dtype=float), np.array(scales)
    n_history = 0 if history is None else len(history.rate)
    out = np.empty((steps, 3))

    def run(values):
        x, v = float(values[0]), float(values[1])
        u = None if u0 is None else u0.copy()
        if u is not None:
            u[stuck] += x - state[0]
            u[sliding] = values[at_u:at_u + sliding.size]
        at_state = 2
        if history_part is not None:
            (n, _), data = history_part
            data[1 + Z * n:1 + (Z + 1) * n] = values[at_state:at_state + n_history]
            at_state += n_history
        if dahl_part is not None:
            dahl_part[1][0] = values[at_state]
            at_state += 1
        if delay_part is not None:
            buffer = delay_part[1]
            ring = np.array(orbit_buffer)
            ring[-extra:] = values[at_state:at_state + extra]
            buffer[0] = first_step
            buffer[1] = ring[0]
            buffer[HEAD + grid % capacity] = ring
        x, v, taken = integrate(loop, model, load, x, v, u, 0.0, first_step, h, 1, out, None, None, None)
        if taken < steps:
            raise ElementError(f"{system.source}: a step of the stability check failed at f = "
                               f"{float(omega) / (2 * math.pi)!r} Hz")
        result = [x, v]
        if history_part is not None:
            (n, _), data = history_part
            result.extend(data[1 + Z * n:1 + (Z + 1) * n].tolist())
        if dahl_part is not None:
            result.append(dahl_part[1][0])
        if delay_part is not None:
            buffer = delay_part[1]
            end = first_step + steps
            result.extend(buffer[HEAD + np.arange(end - extra + 1, end + 1) % capacity].tolist())
        if u is not None:
            result.extend(u[sliding].tolist())
        return np.array(result)

    return run, state, scales


def _monodromy(balance, q_free, omega, steps) -> np.ndarray:
    """The monodromy over x and v of the nodes with a mass and the u of the branches that slide on the orbit (and of
    the branches with series dashpots), by finite differences: each perturbed in turn, a stuck branch's u moved
    with x (see ``variational.py``: its offset is neutral), one period each; in the coordinates (x, v / omega, u)."""
    system = balance.system
    x, v, u = orbit_start(balance, q_free, omega)
    run_period = (_forced_period if balance.base_amplitude is None else _based_period)(balance, omega, steps)
    massive = system.massive
    stuck, states = _branch_states(balance, q_free)
    size = max(float(np.max(np.abs(x))), float(np.max(np.abs(v))) / omega, 1e-300)
    epsilon = PERTURBATION * size
    elements = system.network.elements

    def state_of(x_end, v_end, u_end):
        return np.concatenate((x_end[massive], v_end[massive], u_end[states]))

    base = state_of(*run_period(x, v, u))
    count = len(massive)
    columns = []
    for k in range(2 * count + len(states)):
        dx, dv, du = np.zeros(system.n), np.zeros(system.n), np.zeros(u.shape[0])
        if k < count:
            dx[massive[k]] = epsilon
        elif k < 2 * count:
            dv[massive[k - count]] = epsilon * omega
        else:
            du[states[k - 2 * count]] = epsilon
        for b in stuck:
            p, r = elements[b].between
            du[b] += dx[p] - (dx[r] if r >= 0 else 0.0)
        columns.append((state_of(*run_period(x + dx, v + dv, u + du)) - base) / epsilon)
    rows = np.concatenate((np.ones(count), np.full(count, omega), np.ones(len(states))))
    return np.array(columns).T / rows[:, None]  # in the coordinates (x, v / omega, u): dimensionless


def _slides(system, x: np.ndarray) -> np.ndarray:
    """For each plain branch of ``system``, whether it slides on the orbit sampled as ``x`` (n, N): max e - min e
    > 2 eta (``aft.py``'s test of a branch that never slips)."""
    ends = system.branch_ends
    e = x[ends[:, 0]] - np.where(ends[:, 1:] >= 0, x[np.maximum(ends[:, 1], 0)], 0.0)
    return np.ptp(e, axis=1) > 2.0 * system.branch_eta if ends.shape[0] else np.zeros(0, dtype=bool)


def _branch_states(balance, q_free) -> tuple:
    """``(stuck, states)``: the network indices of the plain branches that never slide on the orbit (max e - min e
    <= 2 eta over its samples), and of the branches whose u is a state of the monodromy (the others, and those with
    series dashpots)."""
    system = balance.system
    slides = _slides(system, balance.samples(balance.full(q_free)))
    stuck = [int(i) for i in system.branch_index[~slides]]
    states = [int(i) for i in system.branch_index[slides]]
    for group in system.series:
        states.extend(int(i) for i in group.index)
    return stuck, np.array(states, dtype=np.int64)


def _forced_period(balance, omega, steps):
    """One period of ``steps`` implicit steps under the force at the load's node: a function of (x, v, u) at t = 0
    (every node's, every element's) giving the same at t = T."""
    from ..network.driver import NetworkElement
    from ..scene_tables import Solver

    period = 2.0 * math.pi / omega
    h = period / steps
    element = NetworkElement(forced_scene(balance, omega, Solver("implicit", h, period, h)), "implicit", h)

    def run(x, v, u):
        element.reset()
        element.x[:] = x
        element.v[:] = v
        element.u[:] = u
        element.piece[:] = 0
        element.time = 0.0
        element.advance(period, 0.0, scene_load=True)
        return element.x.copy(), element.v.copy(), element.u.copy()

    return run


def _based_period(balance, omega, steps):
    """:func:`_forced_period` under base excitation: in absolute coordinates, the ground a massless node whose
    motion y = Y0 cos(omega t) is imposed step by step (the connector's kernel: each step moves it to y at the
    step's end), every element to the ground attached to it (it sees x_j - y = z_j, as in the balance). The state
    in and out is relative (z = x - y, z' = x' - y'): the multipliers are those of the relative motion."""
    from ..network import kernels

    system = balance.system
    network = system.network
    base = system.n
    elements = tuple(dataclasses.replace(e, between=tuple(base if end < 0 else end for end in e.between))
                     for e in network.elements)
    model = dataclasses.replace(network, nodes=network.nodes + ("base of the support",),
                                mass=np.append(network.mass, 0.0), x0=np.append(network.x0, 0.0),
                                v0=np.append(network.v0, 0.0), elements=elements, load_node=base).compile()
    h = 2.0 * math.pi / omega / steps
    Y0 = balance.base_amplitude
    path = Y0 * np.cos(omega * h * np.arange(1, steps + 1))
    work = kernels.workspace(base + 1, len(elements))
    account, dissipated = np.zeros(3), np.zeros(len(elements))  # as the connector passes them (one compile)

    def run(x, v, u):
        x_all = np.append(x, 0.0) + Y0  # y(0) = Y0, y'(0) = 0
        v_all = np.append(v, 0.0)
        u_all = np.array(u, dtype=float)
        piece = np.zeros(len(elements), dtype=np.int64)
        for step in range(steps):
            status, _ = kernels.move_node(model, x_all, v_all, u_all, piece, work, account, dissipated, base,
                                          float(path[step]), 1, h, 0.0)
            if status < 0:
                from ..stepping import ElementError

                raise ElementError(f"{system.source}: a step of the stability check failed at f = "
                                   f"{float(omega) / (2 * math.pi)!r} Hz")
        return x_all[:base] - Y0, v_all[:base], u_all  # y(T) = Y0, y'(T) = 0

    return run


def forced_scene(balance, omega, solver):
    """The network of ``balance`` under its force at ``omega`` as a scene the network steppers run: F0 cos(omega t)
    on the load's node; base excitation (in relative coordinates, see ``harmonic_balance.py``): m Y0 omega^2
    cos(omega t) on the one node with a mass (FrequencyError for several: the network's load acts on one node;
    the stability check imposes the base's motion instead, :func:`_based_period`)."""
    import dataclasses

    from ..loads import HarmonicLoad
    from ..network.model import NetworkScene
    from . import FrequencyError

    system = balance.system
    network = system.network
    if balance.base_amplitude is None:
        amplitude = balance.force_amplitude
    else:
        if len(system.massive) != 1:
            raise FrequencyError(f"{system.source}: base excitation as a force is integrated for one node with "
                                 f"a mass (here {len(system.massive)}): the network's load acts on one node")
        node = system.massive[0]
        network = dataclasses.replace(network, load_node=node)
        amplitude = float(system.mass[node]) * balance.base_amplitude * omega * omega
    return NetworkScene(system.name, network, HarmonicLoad(amplitude, omega), solver, system.source)


def run_periods(balance, omega, state, periods: int, steps: int) -> tuple:
    """Integrate ``balance``'s system under its force at ``omega`` (:func:`forced_scene`; base excitation: in
    relative coordinates) for ``periods`` periods of ``steps`` implicit steps from ``state`` (x, v, u) at t = 0
    (one compiled call per period): ``(x of the last period (steps, n), the state at the end)``. The reference
    the tests and the benchmark hold the harmonic balance against."""
    from ..network.driver import NetworkElement, loop_for, run_loop
    from ..scene_tables import Solver
    from ..stepping import ElementError

    system = balance.system
    period = 2.0 * math.pi / omega
    h = period / steps
    scene = forced_scene(balance, omega, Solver("implicit", h, period, h))
    runner = NetworkElement(scene, "implicit", h)
    x, v, u = (np.array(a, dtype=float) for a in state)
    piece = runner.piece.copy()
    piece[:] = 0
    out = np.empty((steps, 2 * system.n + 2))
    load = scene.load.compile()
    for number in range(periods):
        taken, _ = run_loop(loop_for("implicit"), runner.model, load, x, v, u, piece, 0.0, number * steps, h, 1,
                            out, None, runner.account, None, runner.dissipated, None, runner.work)
        if taken < steps:
            raise ElementError(f"{system.source}: a step failed at f = {float(omega) / (2 * math.pi)!r} Hz")
    return out[:, 0:2 * system.n:2].copy(), (x, v, u)
