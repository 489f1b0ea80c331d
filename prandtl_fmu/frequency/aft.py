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
"""
import numpy as np

from .._jit import kernel


@kernel
def restoring_samples(x, basis, cubic_ends, cubic_k3, cubic_pair, branch_ends, branch_k, branch_eta, branch_pair,
                      forces, tangent, elongations):
    """Fill ``forces`` (n, N) with the restoring force g of the nonlinear elements at each sample and ``tangent``
    (pairs, N, L) with dS/dc of each pair of nodes (see the module); ``elongations`` (branches,) gets u at
    sample 0 of each branch (the state a time integration starts the orbit from). ``x``: (n, N) samples;
    ``basis``: (N, L); ``*_ends`` (count, 2) with -1 for the ground; ``*_pair``: the pair index of each."""
    samples = x.shape[1]
    forces[:, :] = 0.0
    tangent[:, :, :] = 0.0
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
            slope = 3.0 * cubic_k3[c] * e[j] * e[j]
            for l in range(basis.shape[1]):
                tangent[pair, j, l] += slope * basis[j, l]
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
                for l in range(basis.shape[1]):
                    tangent[pair, j, l] += k * (basis[j, l] - 0.5 * (basis[top, l] + basis[bottom, l]))
            elongations[b] = e[0] - centre
            continue
        u = eta
        anchor = top
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
            if u > eta:
                u = eta
                anchor = j
            elif u < -eta:
                u = -eta
                anchor = j
            else:
                for l in range(basis.shape[1]):
                    tangent[pair, j, l] += k * (basis[j, l] - basis[anchor, l])
            forces[p, j] += k * u
            if q >= 0:
                forces[q, j] -= k * u
            if j == 0:
                elongations[b] = u
