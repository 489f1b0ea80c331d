"""What both phase systems of ``exact`` share (``exact.py``: the 6 x 6 system of plain branches,
``exact_series.py``: 6 + n with series dashpots): the bounds on the work of one step and the words of a failed
one, the matrix exponential and its Gramian, and the kernel form's optional parts read as numbers.

* the step's budgets (:data:`PHASE_BUDGET`, :data:`WALK_BUDGET`, :data:`REFINE_LIMIT`) and why a step failed
  (``TOOK_STEP``, ``TOO_MANY_PHASES``, ``STALLED``, ``SEARCH_EXHAUSTED``, ``NOT_FINITE``; :func:`explain`);
* y(tau) = expm(A tau) y0 by scaling and squaring a Taylor series (:func:`_expm_times`), with Van Loan's
  integral int_0^tau y y^T ds beside it when an energy account is kept (:func:`_expm_gramian`,
  :func:`_motion`): one formula for every case, A holding only rates;
* ``k0``, ``c``, the friction's alpha (0 when absent), the next kink of a table load, and a copy of an
  optional array to restore after a failed step.
"""
import math

import numpy as np

from .. import libm
from .._jit import kernel


_EPS = 2.220446049250313e-16

# The bounds on the work of one step (issue 31): a step that needs more fails (the loop returns fewer steps,
# the driver's ElementError / fmi2Discard; each module's ``failure_reason`` says which bound ran out), never a loop.
# The bounds are per event and per simulated second, never per step: a step of any length (one output interval
# of 500 s, a master's long communication step) runs, and the answer does not depend on how the run is cut.
EVENT_FLOOR = 100_000  # phases (events) any step may take ...
EVENT_RATE = 100_000  # ... plus this many per simulated second of the step (Zeno: events piling up in finite time)
WALK_BUDGET = 100_000  # intervals of the validated subdivisions (and zeros of v walked over) searching one event


@kernel
def phase_budget(h):
    """The phases (events) a step of length ``h`` (s) may take: EVENT_FLOOR + EVENT_RATE h."""
    return EVENT_FLOOR + EVENT_RATE * h
ILLINOIS_LIMIT = 64  # Illinois iterations of one root refinement, then bisection ...
REFINE_LIMIT = 64 + 1200  # ... which reaches adjacent doubles from any bracket within 1200 halvings

# why a step failed (``attempt`` of exact.py and exact_series.py)
TOOK_STEP, TOO_MANY_PHASES, STALLED, SEARCH_EXHAUSTED, NOT_FINITE = 0, 1, 2, 3, 4


def explain(failure: int, when: float) -> str:
    """The line that says which bound of the step ran out (``failure``, from ``attempt``) at time ``when``."""
    return {TOOK_STEP: "",
            TOO_MANY_PHASES: f"more than {EVENT_FLOOR} + {EVENT_RATE} events per simulated second in one step, "
                             f"at t = {when!r} s (events piling up in time: a Zeno motion the exact stepper cannot "
                             "follow; use another stepper)",
            STALLED: f"more than 16 + 2 n events at one instant t = {when!r} s (events that do not advance time)",
            SEARCH_EXHAUSTED: f"the search for one event took more than {WALK_BUDGET} intervals, at t = "
                              f"{when!r} s (a search of 'exact' takes at most that many: use another stepper)",
            NOT_FINITE: f"the state became non-finite at t = {when!r} s"}.get(failure, f"failure {failure}")


@kernel
def _motion(a, tau, y0, energy):
    """y(tau) = expm(A tau) y0 and, when an energy account is kept, the Gramian int_0^tau y y^T (else a
    1 x 1 placeholder). y is the same to the bit either way."""
    if energy is None:
        return _expm_times(a, tau, y0), np.zeros((1, 1))
    return _expm_gramian(a, tau, y0)


@kernel
def _expm_times(a, tau, y):
    """expm(a tau) @ y for a square a (6x6 in exact.py; 6 + n with series dashpots in exact_series.py): Taylor
    series after scaling, then squaring."""
    size = a.shape[0]
    result, b, scale, squarings = _scaled_taylor(a, tau)
    if squarings < 0:  # an overflow: no squaring count (the step fails on the non-finite state)
        return np.full(size, np.nan)
    for _ in range(squarings):
        result = _matmul(result, result)
    return _matvec(result, y)


@kernel
def _scaled_taylor(a, tau):
    """``(expm(b), b, scale, q)``: b = a scale with scale = tau / 2^q, q the squarings that bring |a tau|_1 to
    <= 1/4, expm(b) by its Taylor series; q = -1 when |a tau| overflows. What :func:`_expm_times` and
    :func:`_expm_gramian` share, so that both compute the same exponential, operation for operation."""
    size = a.shape[0]
    norm = 0.0
    for j in range(size):
        column = 0.0
        for i in range(size):
            column += abs(a[i, j])
        norm = max(norm, column)
    norm *= tau
    if not norm < 2.0**1000:  # (norm / 0.25 must stay finite: int() of an infinite log2 is undefined in
        # compiled code, and LLVM, seeing through our own log2, once turned it into ~2^63 squarings)
        return np.eye(size), a * 0.0, 0.0, -1
    squarings = 0
    if norm > 0.25:
        squarings = int(math.ceil(libm.log2(norm / 0.25)))  # log2 is exact at powers of two; <= 1002 here
    scale = libm.scalbn(tau, -squarings)  # tau / 2^squarings, rounded once
    b = a * scale
    result = np.eye(size)
    term = np.eye(size)
    for k in range(1, 30):
        term = _matmul(term, b) / k
        result += term
        if _converged(term, result):
            break
    return result, b, scale, squarings


@kernel
def _expm_gramian(a, tau, y0):
    """(expm(a tau) y0, int_0^tau y(s) y(s)^T ds) with y(s) = expm(a s) y0 (Van Loan's integral, by scaling and
    squaring). The exponential is :func:`_expm_times`'s, operation for operation (the same y to the bit). On
    the scaled step sigma = tau / 2^q, W(sigma) = sum_k sigma^(k+1) L^k(M) / (k+1)!, L(X) = A X + X A^T,
    M = y0 y0^T: with B = A sigma, W = sum_k T_k, T_0 = sigma M, T_k = (B T_(k-1) + T_(k-1) B^T) / (k + 1); then
    W(2 s) = W(s) + E(s) W(s) E(s)^T, E(2 s) = E(s)^2 (no growing exponential: stable wherever expm is)."""
    size = a.shape[0]
    result, b, scale, squarings = _scaled_taylor(a, tau)
    if squarings < 0:
        return np.full(size, np.nan), np.full((size, size), np.nan)
    outer = np.empty((size, size))
    for i in range(size):
        for j in range(size):
            outer[i, j] = y0[i] * y0[j]
    piece = outer * scale
    gramian = piece.copy()
    for k in range(1, 40):
        piece = (_matmul(b, piece) + _matmul(piece, b.T)) / (k + 1)
        gramian += piece
        if _converged(piece, gramian):
            break
    for _ in range(squarings):
        gramian = gramian + _matmul(_matmul(result, gramian), result.T)
        result = _matmul(result, result)
    return _matvec(result, y0), gramian


@kernel
def _converged(term, result):
    """Whether every entry of the Taylor series has converged to rounding, entry by entry: for a tiny tau the
    entries of order tau^2 (how v leaves 0 when v = v' = 0, e.g. from rest on a ramp) are far below the
    identity's, and a test on the largest entry dropped them (v(tau) came out exactly 0, a false reversal)."""
    for i in range(term.shape[0]):
        for j in range(term.shape[1]):
            if abs(term[i, j]) > 1e-18 * abs(result[i, j]):
                return False
    return True


@kernel
def _matmul(a, b):
    size = a.shape[0]
    out = np.zeros((size, size))
    for i in range(size):
        for k in range(size):
            aik = a[i, k]
            if aik != 0.0:
                for j in range(size):
                    out[i, j] += aik * b[k, j]
    return out


@kernel
def _matvec(a, y):
    size = a.shape[0]
    out = np.zeros(size)
    for i in range(size):
        total = 0.0
        for j in range(size):
            total += a[i, j] * y[j]
        out[i] = total
    return out


@kernel
def _linear_spring(k0):
    if k0 is None:
        return 0.0
    return k0


@kernel
def _damping(c):
    if c is None:
        return 0.0
    return c


@kernel
def _threshold(friction):
    """alpha of the friction on the mass, 0 without."""
    if friction is None:
        return 0.0
    return friction[0]


@kernel
def _next_break(load, t):
    """Time of the next kink or jump of a table load after t (inf for other loads)."""
    kind, offset, amplitude, omega, times, forces = load
    if kind != 2:
        return np.inf
    j = np.searchsorted(times, t, side="right")
    if j < times.shape[0]:
        return times[j]
    return np.inf


@kernel
def _saved(values):
    """A copy of an optional array (u, the energy account), to restore after a failed step."""
    if values is None:
        return None
    return values.copy()


@kernel
def _restore(values, saved):
    if values is None or saved is None:
        return
    for i in range(saved.shape[0]):  # not values[:] = saved, whose shape check formats its message with libm's log10
        values[i] = saved[i]
