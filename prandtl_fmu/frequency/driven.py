"""Alternating frequency-time for rate-dependent elements: driven by the compiled kernels over whole periods.

A branch with a dashpot in series (a Maxwell branch: spring k, slider eta and dashpot c in series,
``kernels/series.py``) relaxes at k / c (1/s) while it sticks: its force over a periodic elongation depends on
the period, and its steady cycle is not the play operator's. Each one is driven along the sampled elongation
e_j (j = 1 ... N, the last sample the first again) by ``kernels/drive.py``'s :func:`drive`, as describe's
quadrature does: e is taken linear between samples, T / N apart, and the branch follows its exact flow along that
path (the FLOW rule). The elongations of the branches after one period are a map P(u) of those at its start;
each branch's is its own (the branches do not interact under a given e), monotone and piecewise affine (a
contraction exp(-T k / c) while it sticks, a constant once it slips). Its fixed point, the steady cycle, is
found by repeating the period with Aitken's extrapolation per branch (exact on one affine piece), until a
period moves no branch by more than REPEATS of its range (or of the elongation's and the start's size, where
that is smaller), at most MAX_PERIODS periods (FrequencyError past them).

The force is exact along the piecewise linear path between samples: a stated quadrature of the true (smooth)
motion, whose error falls like 1 / N^2 as the trapezoid rule of the harmonics' projection does. The Jacobian
of the force's harmonics with respect to the elongation's coefficients is by finite differences (one-sided, a
step of FINITE_STEP of the elongation's size, each column a steady cycle from the unperturbed one): not exact,
so Newton's method converges linearly near the solution (at the rate of the difference's error, ~1e-7 a step).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import FrequencyError

REPEATS = 1e-13
MAX_PERIODS = 400
FINITE_STEP = 1e-7


@dataclass(frozen=True, eq=False)
class SeriesBranches:
    """The Maxwell branches between one pair of nodes (``ends`` p, q; q = -1 the ground), pair index ``pair``,
    as the kernel form ``model`` of :func:`kernels.drive.drive`; ``index``: their indices among the network's
    elements."""

    ends: tuple
    pair: int
    model: tuple
    index: np.ndarray

    @property
    def eta(self) -> np.ndarray:
        return self.model[5]


def series_model(k, eta, c) -> tuple:
    """The kernel form (m, k0, k3, c, k, eta, cs, friction, memory) of branches k, eta with series dashpots c and
    nothing else."""
    from ..compiled import _read_only
    from ..memory import NONE

    return (None, 0.0, 0.0, 0.0, _read_only(k), _read_only(eta), _read_only(c), None, NONE)


def steady_cycle(group: SeriesBranches, elongation: np.ndarray, period: float, u: np.ndarray, source: str) -> tuple:
    """``(forces (N,), u)``: the force sum k_i u_i of ``group`` at the N samples of ``elongation`` (at theta_j =
    2 pi j / N, j = 0 ... N - 1) on its steady cycle, and u at sample 0 of it; ``u`` (in place): the
    elongations of the branches to start from (the last steady cycle's: a warm start)."""
    from ..kernels.drive import drive

    N = elongation.shape[0]
    xs = np.roll(elongation, -1)  # samples 1 ... N - 1, then 0 again
    vs = np.zeros(N)
    durations = np.full(N, period / N)
    forces = np.empty(N)
    eta = group.eta
    # u's scale: its range eta, or what the elongation and the start move it by when that is less (an elastic
    # range of 5e5 m made the cycle's 1e-13 of it 5e-8 m, the finite differences of its forces 10 % off, and the
    # continuation crept at steps of 5e-7 whose correctors converged linearly)
    scale = max(min(float(np.max(eta)), float(np.max(np.abs(elongation))) + float(np.max(np.abs(u)))), 1e-300)
    history = []
    for _ in range(MAX_PERIODS):
        start = u.copy()
        drive(group.model, u, elongation[0], xs, vs, durations, forces, None)
        moved = np.abs(u - start)
        if np.max(moved) <= REPEATS * scale:
            return np.roll(forces, 1), u
        history.append((start, u.copy()))
        if len(history) >= 2:  # Aitken: u* = u1 + (u2 - u1) / (1 - s), s = (u2 - u1) / (u1 - u0) per branch
            (u0, u1), (_, u2) = history[-2], history[-1]
            first, second = u1 - u0, u2 - u1
            ratio = np.divide(second, first, out=np.zeros_like(first), where=first != 0.0)
            ratio = np.minimum(ratio, 0.99)
            u[:] = np.clip(u2 + second * ratio / (1.0 - ratio), -eta, eta)
            history.clear()
    raise FrequencyError(f"{source}: the branches with series dashpots did not reach a periodic cycle within "
                         f"{MAX_PERIODS} periods (f = {1.0 / float(period)!r} Hz)")
