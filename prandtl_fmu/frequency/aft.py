"""Alternating frequency-time: the forces of the nonlinear elements over one steady cycle, and their Jacobian.

The motion of the nodes is given by its samples x[i, j] at theta_j = 2 pi j / N over one period. Each
nonlinear element acts on its elongation e_j = x[p, j] - x[q, j] (x of the ground: 0) with a tension s_j, and
pushes node p by -s_j and node q by +s_j; :func:`restoring_samples` writes g[p, j] += s_j, g[q, j] -= s_j (the
restoring force, on the left of M x'' + C x' + K x + g = F).

* cubic spring: s_j = k3 e_j^3, ds_j / de_j = 3 k3 e_j^2;
* Prandtl branch (k, eta): s_j = k u_j with u the play operator of e on its steady cycle. Between two samples
  e is taken linear (monotone), and the play operator is rate independent, so one clipped move per sample is
  exact at the samples (``kernels/drive.py`` drives the element the same way). The steady cycle: a branch with
  max e - min e <= 2 eta never slips and sticks with u = e - (max e + min e) / 2 (the centred cycle: the one a
  branch reaches from rest at the centre of the motion; a branch that never slips keeps any offset, and this
  one has none); any other branch slips up to the maximum of e, so u = eta there, and one period driven from
  that sample is its steady cycle (it slips down and back up before it returns).

The Jacobian is exact for this sampled map (piecewise linear in the samples): a branch that slips into sample
j has du_j / de = 0; one that sticks since its last slip at sample a (its anchor) has u_j = u_a + e_j - e_a, so
du_j / de = delta_j - delta_a; one that never slips has du_j / de = delta_j - (delta_jmax + delta_jmin) / 2.
With the basis T (N, L) of the harmonics (e = T c), :func:`restoring_samples` writes the rows
(dS / dc)[j, :] = sum over the pair's elements of ds_j / de T[., :] into ``tangent[pair]`` (N, L); the
caller projects them on the harmonics (a sum over j). Only at a sample that lands exactly on a slip threshold
is the map not differentiable (a choice of side, of measure zero).

Dahl's friction (``memory/dahl.py``, on one node to the ground) follows the same samples in
:func:`dahl_cycle`: dF/dx = sigma (1 - F / F_c s)^exponent along a move of sign s is rate independent and
``dahl.after`` integrates it exactly over a monotone move, so F is exact at the samples along the path taken
linear between them. One period driven from F at sample 0 is a map P(F), increasing with slope in [0, 1); the
steady cycle is its fixed point, found by Newton's method on P(F) - F kept inside a bracket (bisection where
a Newton step leaves it), each iteration one period driven, at most DAHL_PERIODS (-1 returned past them: the
caller refuses). With exponent 1 P is affine (each move is F1 = e^-d F + s F_c (1 - e^-d)) and one step is
exact. The tangent is exact for the sampled map: each move's dF_1 = a dF + b d(dx), a = dF_1/dF and b =
sigma y_1^exponent, carried over the period from dF = 0 and closed by periodicity, dF_0 = (what one period
adds) / (1 - prod a) (0 where prod a = 1: no motion, F stays where it is, the cycle from rest F = 0).
"""
import numpy as np

from .._jit import kernel
from ..libm import exp, pow
from ..memory.dahl import after

DAHL_PERIODS = 64


@kernel
def restoring_samples(x, basis, cubic_ends, cubic_k3, cubic_pair, branch_ends, branch_k, branch_eta, branch_pair,
                      forces, tangent, elongations):
    """Fill ``forces`` (n, N) with the restoring force g of the nonlinear elements at each sample and ``tangent``
    (pairs, N, L) with dS/dc of each pair of nodes (see the module); ``elongations`` (branches,) gets u at
    sample 0 of each branch (the state a time integration starts the orbit from). ``x``: (n, N) samples;
    ``basis``: (N, L); ``*_ends`` (count, 2) with -1 for the ground; ``*_pair``: the pair index of each.

    dS_j/dc is ``weight[pair, j]`` basis[j] less the sum over the branches stuck at j of k basis[anchor]; the
    second is kept as runs of samples with one anchor, added at a run's first sample and taken off after its
    last, summed over j at the end: a branch costs N plus L per run (a few a period), not N L (a thousand
    branches on one pair, 256 samples and 15 harmonics: a hundredth of the work)."""
    samples = x.shape[1]
    width = basis.shape[1]
    forces[:, :] = 0.0
    tangent[:, :, :] = 0.0
    weight = np.zeros((tangent.shape[0], samples))
    spread = np.zeros((tangent.shape[0], samples + 1, width))
    e = np.empty(samples)
    for c in range(cubic_k3.shape[0]):
        p, q = cubic_ends[c, 0], cubic_ends[c, 1]
        pair = cubic_pair[c]
        for j in range(samples):
            e[j] = x[p, j] - (x[q, j] if q >= 0 else 0.0)
            s = cubic_k3[c] * e[j] ** 3
            forces[p, j] += s
            if q >= 0:
                forces[q, j] -= s
            weight[pair, j] += 3.0 * cubic_k3[c] * e[j] * e[j]
    for b in range(branch_k.shape[0]):
        p, q = branch_ends[b, 0], branch_ends[b, 1]
        pair = branch_pair[b]
        k, eta = branch_k[b], branch_eta[b]
        top, bottom = 0, 0
        for j in range(samples):
            e[j] = x[p, j] - (x[q, j] if q >= 0 else 0.0)
            if e[j] > e[top]:
                top = j
            if e[j] < e[bottom]:
                bottom = j
        if e[top] - e[bottom] <= 2.0 * eta:
            centre = 0.5 * (e[top] + e[bottom])
            for j in range(samples):
                s = k * (e[j] - centre)
                forces[p, j] += s
                if q >= 0:
                    forces[q, j] -= s
                weight[pair, j] += k
            for l in range(width):  # anchored at the centre of the motion over the whole period
                value = 0.5 * k * (basis[top, l] + basis[bottom, l])
                spread[pair, 0, l] -= value
                spread[pair, samples, l] += value
            elongations[b] = e[0] - centre
            continue
        u = eta
        anchor = top
        run = -1  # the step at which the branch's present stuck run began (-1: it slips)
        forces[p, top] += k * eta
        if q >= 0:
            forces[q, top] -= k * eta
        if top == 0:
            elongations[b] = eta
        for step in range(1, samples):
            j = top + step
            if j >= samples:
                j -= samples
            before = j - 1 if j > 0 else samples - 1
            u += e[j] - e[before]
            if u > eta or u < -eta:
                u = eta if u > eta else -eta
                if run >= 0:
                    _anchored(spread[pair], basis[anchor], k, top + run, step - run, samples)
                    run = -1
                anchor = j
            else:
                weight[pair, j] += k
                if run < 0:
                    run = step
            forces[p, j] += k * u
            if q >= 0:
                forces[q, j] -= k * u
            if j == 0:
                elongations[b] = u
        if run >= 0:
            _anchored(spread[pair], basis[anchor], k, top + run, samples - run, samples)
    for pair in range(tangent.shape[0]):
        for l in range(width):
            running = 0.0
            for j in range(samples):
                running += spread[pair, j, l]
                tangent[pair, j, l] = weight[pair, j] * basis[j, l] + running


@kernel
def _anchored(spread, row, k, first, length, samples):
    """-k ``row`` (the basis at a branch's anchor) on the ``length`` samples from ``first`` (taken modulo
    ``samples``, wrapping round the period) as differences in ``spread`` (samples + 1, L)."""
    if first >= samples:
        first -= samples
    last = first + length
    for l in range(row.shape[0]):
        value = k * row[l]
        spread[first, l] -= value
        if last <= samples:
            spread[last, l] += value
        else:
            spread[samples, l] += value
            spread[0, l] -= value
            spread[last - samples, l] += value


@kernel
def dahl_cycle(e, basis, sigma, level, exponent, forces, tangent):
    """Dahl's force (sigma, F_c = ``level``, ``exponent``) on its steady cycle along the samples ``e`` (N,):
    ``forces`` (N,) its value at each sample, ``tangent`` (N, L) dF_j / dc with e = ``basis`` c (see the
    module). Returns the periods driven, or -1 if the cycle was not found within DAHL_PERIODS."""
    samples = e.shape[0]
    part = ((sigma, level, exponent), np.zeros(1))
    low, high = -level, level
    start = 0.0
    slopes = np.empty(samples)
    pushes = np.empty(samples)
    periods = -1
    for period in range(DAHL_PERIODS):
        f = start
        product = 1.0
        for j in range(1, samples + 1):
            f, a, b = _dahl_move(part, f, e[j % samples] - e[j - 1], sigma, level, exponent)
            product *= a
        gap = f - start  # P(F) - F: decreasing in F, >= 0 at -F_c, <= 0 at F_c
        if gap > 0.0:
            low = start
        else:
            high = start
        if abs(gap) <= 1e-15 * level or high - low <= 1e-14 * level:
            periods = period + 1
            break
        guess = start + gap / (1.0 - product) if product < 1.0 else 0.5 * (low + high)
        if not low < guess < high:
            guess = 0.5 * (low + high)
        start = guess
    if periods < 0:
        return -1
    f = start
    for j in range(1, samples + 1):
        forces[j - 1] = f
        f, a, b = _dahl_move(part, f, e[j % samples] - e[j - 1], sigma, level, exponent)
        slopes[j % samples] = a
        pushes[j % samples] = b
    product = 1.0
    for j in range(samples):
        product *= slopes[j]
    for l in range(basis.shape[1]):
        change = 0.0
        for j in range(1, samples + 1):
            change = slopes[j % samples] * change + pushes[j % samples] * (basis[j % samples, l] - basis[j - 1, l])
        change = change / (1.0 - product) if product < 1.0 else 0.0
        for j in range(1, samples + 1):
            tangent[j - 1, l] = change
            change = slopes[j % samples] * change + pushes[j % samples] * (basis[j % samples, l] - basis[j - 1, l])
    return periods


@kernel
def _dahl_move(part, f, dx, sigma, level, exponent):
    """(F_1, dF_1/dF, dF_1/d(dx)) of Dahl's exact move ``dahl.after`` by ``dx`` from F = ``f``."""
    f1, push = after(part, f, dx)
    if dx == 0.0:
        return f1, 1.0, push
    s = 1.0 if dx > 0.0 else -1.0
    y = max(1.0 - s * f / level, 0.0)
    d = sigma * abs(dx) / level
    if exponent == 1.0:
        return f1, exp(-d), push
    if exponent > 1.0:
        p = exponent - 1.0
        return f1, pow(1.0 + p * d * pow(y, p), -1.0 / p - 1.0), push
    y1 = 1.0 - s * f1 / level
    if y1 <= 0.0 or y <= 0.0:
        return f1, 0.0, push
    return f1, pow(y1 / y, exponent), push
