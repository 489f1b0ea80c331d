"""The friction branches at a cost independent of n: the memory stack.

Used by every stepper but ``exact`` for scenes with many branches and an
admissible initial state, and for the continuous element (infinitely many
branches); see ``driver.choose_branch_kernel``. tests/steppers/test_memory_stack.py shows it
equals the O(n) play kernel, tests/models/test_continuum.py that the continuum is
the limit of the sampled branches.

Sort the branches by elastic range, eta_1 <= ... <= eta_n. From an admissible
state (|u_i| <= eta_i and u 1-Lipschitz in eta: |u_i - u_j| <= |eta_i - eta_j|),
moving x monotonically keeps u admissible, and the profile i -> u_i is made of
consecutive blocks ("pieces") of *positions*:

* the top piece [0, top): the branches that slid in the last direction d of
  motion, u_i = d eta_i;
* below it, pieces [lo, hi) of sticking branches, u_i = a + x + beta eta_i
  (+ c_i for the initial piece, c_i = u0_i), beta in {-1, 0, +1} (in [-1, 1]
  after a merge, see below; the rules only need |beta| <= 1): each moves
  with x, so its force is (a + x) K + beta M (+ C) with the sums K = sum k_i,
  M = sum k_i eta_i, C = sum k_i c_i over the piece.

Moving x by a monotone increment in direction s: a reversal (s != d) first
turns the top piece into a sticking piece (a = -x, beta = d); then, from the
top down, a piece whose largest-eta branch reaches s eta_i is popped whole
(its branches slide), and at most one piece is split where its branches stop
reaching (the condition s u_i >= eta_i is monotone in the position). The force
sum_i k_i u_i = S0 + x SK + d M(top) is kept as running totals, updated on every
pop, split and push: O(1) amortised plus a search per move, whatever n. The
totals are recomputed from the pieces every ``RESYNC`` moves so that rounding
does not drift.

Two kinds of spectrum share this code, told apart by the type of ``params``:

* n branches: ``params`` is one (10, n + 1) array (see :func:`prepare`),
  positions are branch indices in eta order, sums are differences of prefix
  sums, the split is a binary search;
* the continuum (Bastien, Schatzman & Lamarque 2002, and the spectra beyond
  it): branches s in [0, 1], virgin at the start, cut into segments
  [s_j, s_j+1) on which the elastic range eta(s) is linear (continuous and
  non-decreasing in s; a flat segment is a Dirac of the spectrum) and the
  stiffness density is k(s) = c_j eta(s)^p_j (p_j = 0: piecewise constant,
  the paper's section 8 is one segment; p_j = chi: Segalman's power law).
  ``params`` is the 1-tuple ``(table,)`` of :func:`segments`; positions are
  values of s, sums are integrals in closed form (cumulative values at the
  segment ends plus the part of one segment, found by a binary search over
  the segments), the split is the inverse of the piecewise-linear eta(s).
  The cost per move does not depend on any resolution. Its memory holds at
  most ``CONTINUUM_PIECES`` turning points: beyond that (thousands of
  reversals that are never wiped out, e.g. a free decay with eta_min = 0) the
  two adjacent pieces whose kink matters least are replaced by their chord,
  an approximation of second order in their width; see :func:`_compact`.

The energy account (optional) books the sliders' dissipation sum alpha_i |slip_i|
from the same sums (and those of k eta^2, k eta c, k c^2), so the stack keeps
the account at no extra cost per branch.

State layout (one float64 array, so that it can be copied and saved as plain
data): ``state[:HEADER]`` = count of pieces, top, d, SK, S0, moves since the
last resync, x; then ``count`` rows of (lo, hi, a, beta, gamma), bottom
(largest eta) first, and free rows up to the capacity.
"""
import numpy as np
from numba.core import types
from numba.extending import overload

from .. import libm
from .._jit import inline_kernel, kernel

HEADER = 7
ROW = 5
RESYNC = 1024
CONTINUUM_PIECES = 4096
COUNT, TOP, DIRECTION, SK, S0, MOVES, X = range(HEADER)
# rows of the parameters of n branches
K_ROW, ETA_ROW, C_ROW, K_SUM, M_SUM, C_SUM, ORDER_ROW, E_SUM, D_SUM, G_SUM = range(10)
# rows of the continuum's table (columns: the J + 1 segment ends; SLOPE, COEF, POWER: J segments + padding)
S_AT, ETA_AT, SLOPE, COEF, POWER, K_AT, M_AT, E_AT = range(8)


def prepare(stiffness, yield_displacement, u0):
    """(params, order) for branches k, eta with initial elongations u0.

    ``order`` sorts the branches by eta; ``params`` is one (10, n + 1) array
    whose rows are k, eta, c = u0 (sorted, padded), the prefix sums (of length
    n + 1) K, M, C, the order, and the prefix sums of k eta^2, k eta c, k c^2
    (one array rather than a tuple of ten: the steppers pass it on every
    step). ValueError if u0 is not admissible (then the O(n) kernel must be
    used). The rows of u0 are written by :func:`refer`.
    """
    order = np.argsort(yield_displacement, kind="stable")
    k = np.ascontiguousarray(stiffness[order], dtype=float)
    eta = np.ascontiguousarray(yield_displacement[order], dtype=float)

    def prefix(values):
        return np.concatenate([[0.0], np.cumsum(values)])

    n = len(k)
    params = np.zeros((10, n + 1))
    params[K_ROW, :n], params[ETA_ROW, :n] = k, eta
    params[K_SUM], params[M_SUM] = prefix(k), prefix(k * eta)
    params[ORDER_ROW, :n] = order
    params[E_SUM] = prefix(k * eta * eta)
    if not refer(params, np.ascontiguousarray(u0, dtype=float)):
        raise ValueError("the initial elongations are not 1-Lipschitz in eta: the memory stack does not apply")
    return params, order


@kernel
def refer(params, u0):
    """Make the elongations ``u0`` (the scene's order) those the initial piece refers to: the row c = u0 in eta
    order and the prefix sums of k c, k eta c, k c^2 of :func:`prepare`'s ``params``, in place (what a switch
    back to the stack from the O(n) kernel does, ``driver.Element``). False, ``params`` unchanged, when u0 is
    not admissible (:func:`admissible`)."""
    n = params.shape[1] - 1
    if not _admissible(params[ETA_ROW], u0, params[ORDER_ROW], n):
        return False
    c_sum = d_sum = g_sum = 0.0
    params[C_SUM, 0] = params[D_SUM, 0] = params[G_SUM, 0] = 0.0
    for j in range(n):
        k, eta, c = params[K_ROW, j], params[ETA_ROW, j], u0[int(params[ORDER_ROW, j])]
        params[C_ROW, j] = c
        if j == 0:  # numpy's cumsum starts from the first term (not 0.0 + it: the sign of a zero)
            c_sum, d_sum, g_sum = k * c, k * eta * c, k * c * c
        else:
            c_sum, d_sum, g_sum = c_sum + k * c, d_sum + k * eta * c, g_sum + k * c * c
        params[C_SUM, j + 1], params[D_SUM, j + 1], params[G_SUM, j + 1] = c_sum, d_sum, g_sum
    return True


@kernel
def _admissible(eta, u, order, n):
    """:func:`admissible` for ``eta`` sorted and ``u[order[j]]`` the elongation of the branch at position j."""
    largest = 0.0
    for j in range(n):
        if abs(u[int(order[j])]) > eta[j]:
            return False
        largest = max(largest, eta[j])
    tolerance = 1e-12 * max(1.0, largest)
    for j in range(n - 1):
        if not abs(u[int(order[j + 1])] - u[int(order[j])]) <= (eta[j + 1] - eta[j]) + tolerance:
            return False
    return True


def continuum(k_total, eta_min, eta_max):
    """The parameters of the paper's continuum: k(s) = k_total, eta(s) = eta_min + (eta_max - eta_min) s."""
    if not (k_total > 0 and 0 <= eta_min < eta_max):
        raise ValueError("the continuum needs k_total > 0 and 0 <= eta_min < eta_max")
    return segments([0.0, 1.0], [eta_min, eta_max], [k_total], [0.0])


def segments(s, eta, coefficient, power):
    """The parameters ``(table,)`` of a segmented spectrum on [0, 1].

    ``s`` (J + 1,): 0 = s_0 < ... < s_J = 1; ``eta`` (J + 1,): eta(s_j) (m),
    non-decreasing, eta linear in between; ``coefficient`` c_j and ``power``
    p_j (J,): stiffness density k(s) = c_j eta(s)^p_j (N/m per unit of s) on
    [s_j, s_j+1), with c_j >= 0, p_j > -1, and eta > 0 on a segment with p_j
    != 0 except at its lower end (where the density may be integrably
    infinite). ValueError otherwise.
    """
    s, eta = np.asarray(s, dtype=float), np.asarray(eta, dtype=float)
    coefficient, power = np.asarray(coefficient, dtype=float), np.asarray(power, dtype=float)
    count = len(coefficient)
    if (count < 1 or s.shape != (count + 1,) or eta.shape != (count + 1,) or power.shape != (count,)
            or not (np.all(np.isfinite(s)) and np.all(np.isfinite(eta)) and np.all(np.isfinite(coefficient))
                    and np.all(np.isfinite(power)))):
        raise ValueError("a spectrum needs J >= 1 segments: J + 1 finite ends s and eta, J coefficients and powers")
    if s[0] != 0.0 or s[-1] != 1.0 or np.any(np.diff(s) <= 0):
        raise ValueError("the segment ends s must rise from 0 to 1")
    if eta[0] < 0 or np.any(np.diff(eta) < 0):
        raise ValueError("eta(s) must be >= 0 and non-decreasing")
    if np.any(coefficient < 0) or np.any(power <= -1) or not np.any(coefficient > 0):
        raise ValueError("the density needs coefficients c_j >= 0 (not all 0) and powers p_j > -1")
    if np.any((power != 0) & (eta[1:] <= 0)):
        raise ValueError("a power-law segment needs eta > 0 beyond its lower end")
    table = np.zeros((8, count + 1))
    table[S_AT], table[ETA_AT] = s, eta
    table[SLOPE, :count] = np.diff(eta) / np.diff(s)
    table[COEF, :count], table[POWER, :count] = coefficient, power
    for j in range(count):
        k_part, m_part, e_part = _partial.py_func(table, j, s[j + 1] - s[j])  # no compilation for this
        table[K_AT, j + 1] = table[K_AT, j] + k_part
        table[M_AT, j + 1] = table[M_AT, j] + m_part
        table[E_AT, j + 1] = table[E_AT, j] + e_part
    if not (np.all(np.isfinite(table)) and table[K_AT, -1] > 0):
        raise ValueError("the spectrum's stiffness overflows or is zero")
    return (table,)


def spectrum_totals(params):
    """(integral k ds, integral k eta ds, integral k eta^2 ds) of a continuum: stiffness (N/m), strength (N),
    and twice the energy its sliders store at full slip (J)."""
    table = params[0]
    return float(table[K_AT, -1]), float(table[M_AT, -1]), float(table[E_AT, -1])


def spectrum_integrals(params, ends):
    """(K, M, E): arrays of the integrals of k, k eta, k eta^2 over the cells [ends_i, ends_i+1) of the
    positions of a continuum (``ends`` rising in [0, 1])."""
    ends = np.ascontiguousarray(ends, dtype=float)
    out = np.empty((3, max(ends.shape[0] - 1, 0)))
    _cells(params[0], ends, out)
    return out[0], out[1], out[2]


def eta_of(params, s):
    """eta(s) (m) of a continuum at the positions ``s`` (array)."""
    table = params[0]
    return np.interp(np.asarray(s, dtype=float), table[S_AT], table[ETA_AT])


def is_stack(params) -> bool:
    """Whether ``params`` (a model's ``k``) are memory-stack parameters rather than the O(n) kernel's k."""
    return isinstance(params, tuple) or (isinstance(params, np.ndarray) and params.ndim == 2)


def capacity(params) -> int:
    """How many pieces a state can hold: n + 1 (never reached), or CONTINUUM_PIECES + 1."""
    return CONTINUUM_PIECES + 1 if isinstance(params, tuple) else params.shape[1]


def fresh_state(params, x0):
    """The initial state at x = x0: one sticking piece, u = u0 (+ x - x0 as x moves); see :func:`start`."""
    state = np.empty(HEADER + ROW * capacity(params))
    start(params, float(x0), state)
    return state


@kernel
def start(params, x0, state):
    """Make ``state`` the initial state at x = x0, in place: one sticking piece, u = u0 + x - x0 (n branches)
    or u(s) = x - x0 (the continuum, virgin)."""
    state[:] = 0.0
    state[X] = x0
    state[COUNT] = 1.0
    end, gamma = _first_piece(params)
    state[HEADER + 1] = end
    state[HEADER + 2] = -x0
    state[HEADER + 4] = gamma
    resync(params, state)


def used(state) -> int:
    """The length of the part of ``state`` in use (header and pieces): what must be saved."""
    return HEADER + ROW * int(state[COUNT])


GAMMA_REFUSAL = "memory-stack state: a piece's weight of the initial elongations is not one the stack makes"


def restore(params, saved):
    """A full state from the used part of one (as saved by :func:`used`); ValueError if it is not one."""
    saved = np.asarray(saved, dtype=float).reshape(-1)
    state = np.zeros(HEADER + ROW * capacity(params))
    if saved.shape[0] < HEADER or (saved.shape[0] - HEADER) % ROW or not np.all(np.isfinite(saved)):
        raise ValueError("not a memory-stack state")
    count = int(saved[COUNT])
    end = 1.0 if isinstance(params, tuple) else float(params.shape[1] - 1)
    # n branches: at most n pieces; the continuum keeps a free row for the next reversal (see _compact)
    limit = capacity(params) - (2 if isinstance(params, tuple) else 1)
    if saved[COUNT] != count or saved.shape[0] != HEADER + ROW * count or count > limit:
        raise ValueError("memory-stack state: wrong count of pieces")
    rows = saved[HEADER:].reshape(count, ROW)
    bounds = np.concatenate([[end], rows[:, 0]])
    if (saved[DIRECTION] not in (-1.0, 0.0, 1.0) or not 0 <= saved[TOP] <= end
            or np.any(rows[:, 1] != bounds[:-1]) or np.any(rows[:, 0] > rows[:, 1])
            or (count and rows[-1, 0] != saved[TOP]) or (not count and saved[TOP] != end)
            or np.any(np.abs(rows[:, 3]) > 1.0)):
        raise ValueError("memory-stack state: the pieces do not tile the branches")
    if saved[DIRECTION] == 0.0 and saved[TOP] != 0.0:
        raise ValueError("memory-stack state: branches slid in no direction")
    # gamma, a piece's weight of the initial elongations: 1 on the piece that still refers to them, else 0 (the
    # continuum's are virgin: 0); the bounds of kernels/showable.py rely on it
    if np.any((rows[:, 4] != 0.0) & (rows[:, 4] != (0.0 if isinstance(params, tuple) else 1.0))):
        raise ValueError(GAMMA_REFUSAL)
    _check_admissible(params, saved, rows)
    state[:saved.shape[0]] = saved
    resync(params, state)  # the totals must be those of the pieces (to rounding) ...
    scale = 1.0 + abs(state[SK]) + abs(state[S0])
    if abs(state[SK] - saved[SK]) + abs(state[S0] - saved[S0]) > 1e-9 * scale or not 0 <= saved[MOVES] < RESYNC:
        raise ValueError("memory-stack state: the running totals do not match the pieces")
    state[:HEADER] = saved[:HEADER]  # ... and are kept as saved, so that the continuation is bit for bit the same
    return state


def _check_admissible(params, saved, rows):
    """ValueError unless every sticking piece keeps its elongations in their elastic ranges, |u| <= eta (and,
    for n branches, u 1-Lipschitz in eta: the stack's rules need it). Without this, a state whose pieces tile
    the branches and whose totals match them could carry a force beyond the element's strength."""
    x = saved[X]
    # u = a + x + ... is computed from numbers of the size of x: the rounding of that sum is allowed
    size = abs(x) + float(np.max(np.abs(rows[:, 2]), initial=0.0))
    if isinstance(params, tuple):  # the continuum: u(s) = a + x + beta eta(s) on a piece, |u| <= eta is linear
        table = params[0]           # in eta: checked at the piece's ends
        for lo, hi, a, beta, _ in rows:
            for position in (lo, hi):
                eta = _eta_at(table, position)
                if abs(a + x + beta * eta) > eta + 1e-12 * max(1.0, eta, size):
                    raise ValueError("memory-stack state: an elongation outside its elastic range")
        return
    n = params.shape[1] - 1
    eta, c = params[ETA_ROW, :n], params[C_ROW, :n]
    u = np.empty(n)
    top = int(saved[TOP])
    u[:top] = saved[DIRECTION] * eta[:top]
    for lo, hi, a, beta, gamma in rows:
        lo, hi = int(lo), int(hi)
        u[lo:hi] = a + x + beta * eta[lo:hi] + gamma * c[lo:hi]
    tolerance = 1e-12 * max(1.0, float(np.max(eta, initial=0.0)), size)
    if np.any(np.abs(u) > eta + tolerance):
        raise ValueError("memory-stack state: an elongation outside its elastic range")
    if not np.all(np.abs(np.diff(u)) <= np.diff(eta) + tolerance):
        raise ValueError("memory-stack state: the elongations are not admissible (|u_i - u_j| > |eta_i - eta_j|)")


def admissible(eta, u):
    """|u_i| <= eta_i and |u_i - u_j| <= eta_j - eta_i for eta sorted (to rounding)."""
    eta, u = np.ascontiguousarray(eta, dtype=float), np.ascontiguousarray(u, dtype=float)
    return bool(_admissible(eta, u, np.arange(len(eta), dtype=float), len(eta)))


# ------------------------------------------------ the continuum's segments (closed forms)

@kernel
def _partial(table, j, t):
    """Integrals of k, k eta, k eta^2 over [s_j, s_j + t) of segment j (0 <= t <= s_j+1 - s_j).

    With e = eta(s_j), g the slope, k = c eta^p: for p = 0, polynomials in t
    (no cancellation for a short part); for p != 0, (eta^(p+q) - e^(p+q)) /
    (g (p + q)), q = 1, 2, 3, or c e^(p+q-1) t on a flat segment (g = 0).
    """
    e, g, c, p = table[ETA_AT, j], table[SLOPE, j], table[COEF, j], table[POWER, j]
    if p == 0.0:
        return c * t, c * t * (e + 0.5 * g * t), c * t * (e * e + g * t * (e + g * t / 3.0))
    if g == 0.0:
        density = c * libm.pow(e, p)
        return density * t, density * e * t, density * e * e * t
    end = e + g * t
    end1, end2, end3 = libm.pow3(end, p + 1.0, p + 2.0, p + 3.0)  # libm.pow's bits, one logarithm per base
    e1, e2, e3 = libm.pow3(e, p + 1.0, p + 2.0, p + 3.0)
    return (c * (end1 - e1) / (g * (p + 1.0)),
            c * (end2 - e2) / (g * (p + 2.0)),
            c * (end3 - e3) / (g * (p + 3.0)))


@kernel
def _last_not_above(values, target):
    """The largest index b <= len(values) - 2 with values[b] <= target (0 if none): values non-decreasing."""
    first, last = 0, values.shape[0] - 2
    while first < last:
        middle = (first + last + 1) >> 1
        if values[middle] <= target:
            first = middle
        else:
            last = middle - 1
    return first


@kernel
def _segment_of(table, pos):
    """The segment j with s_j <= pos < s_j+1 (the last one for pos = 1)."""
    return _last_not_above(table[S_AT], pos)


@kernel
def _integrals_between(table, lo, hi):
    """Integrals of k, k eta, k eta^2 over [lo, hi): one segment's part, or cumulative values between."""
    i, j = _segment_of(table, lo), _segment_of(table, hi)
    k_lo, m_lo, e_lo = _partial(table, i, lo - table[S_AT, i])
    k_hi, m_hi, e_hi = _partial(table, j, hi - table[S_AT, j])
    if i == j:
        return k_hi - k_lo, m_hi - m_lo, e_hi - e_lo
    return (table[K_AT, j] + k_hi - table[K_AT, i] - k_lo, table[M_AT, j] + m_hi - table[M_AT, i] - m_lo,
            table[E_AT, j] + e_hi - table[E_AT, i] - e_lo)


@kernel
def _cells(table, ends, out):
    for i in range(ends.shape[0] - 1):
        out[0, i], out[1, i], out[2, i] = _integrals_between(table, ends[i], ends[i + 1])


@kernel
def _eta_at(table, pos):
    """eta(pos) (m)."""
    j = _segment_of(table, pos)
    return table[ETA_AT, j] + table[SLOPE, j] * (pos - table[S_AT, j])


@kernel
def _last_reached(table, target):
    """sup {pos in [0, 1]: eta(pos) <= target} (0 when eta(0) > target): the branches below it reach
    ``target``; a flat segment (a Dirac) at eta = target is reached whole."""
    eta = table[ETA_AT]
    ends = eta.shape[0]
    if not eta[0] <= target:
        return 0.0
    if eta[ends - 1] <= target:
        return 1.0
    first = _last_not_above(eta, target)  # then eta[first + 1] > target: the slope is > 0
    pos = table[S_AT, first] + (target - eta[first]) / table[SLOPE, first]
    return min(pos, table[S_AT, first + 1])


# ------------------------------------------------ the spectrum: sums, thresholds, split
# Compiled only; each has one implementation per kind of spectrum (the type of params).

def _sums(params, lo, hi):
    """(K, M, C): the sums of k, k eta, k c over the positions [lo, hi)."""
    raise NotImplementedError


def _squares(params, lo, hi):
    """(E, D, G): the sums of k eta^2, k eta c, k c^2 over the positions [lo, hi)."""
    raise NotImplementedError


def _moment(params, top):
    """M over [0, top): sum k eta (the force of the top piece is d times it)."""
    raise NotImplementedError


def _threshold(params, pos):
    """(eta, c) of the branch at position ``pos``."""
    raise NotImplementedError


def _split(params, state, row, x, s):
    """The position p in [lo, hi] of the piece at ``row`` such that, at x, [lo, p) slides in direction s."""
    raise NotImplementedError


def _is_discrete(params):
    return isinstance(params, types.Array)


def _first_piece(params):
    """(end, gamma) of a fresh state's one piece: all n branches referring to u0, or the virgin continuum."""
    raise NotImplementedError


@overload(_first_piece, inline="always")
def _first_piece_overload(params):
    if _is_discrete(params):
        return lambda params: (float(params.shape[1] - 1), 1.0)
    return lambda params: (1.0, 0.0)


@overload(_sums, inline="always")
def _sums_overload(params, lo, hi):
    if _is_discrete(params):
        def discrete(params, lo, hi):
            i, j = int(lo), int(hi)
            return (params[K_SUM, j] - params[K_SUM, i], params[M_SUM, j] - params[M_SUM, i],
                    params[C_SUM, j] - params[C_SUM, i])
        return discrete

    def continuous(params, lo, hi):
        k_sum, m_sum, e_sum = _integrals_between(params[0], lo, hi)
        return k_sum, m_sum, 0.0
    return continuous


@overload(_squares, inline="always")
def _squares_overload(params, lo, hi):
    if _is_discrete(params):
        def discrete(params, lo, hi):
            i, j = int(lo), int(hi)
            return (params[E_SUM, j] - params[E_SUM, i], params[D_SUM, j] - params[D_SUM, i],
                    params[G_SUM, j] - params[G_SUM, i])
        return discrete

    def continuous(params, lo, hi):
        return _integrals_between(params[0], lo, hi)[2], 0.0, 0.0
    return continuous


@overload(_moment, inline="always")
def _moment_overload(params, top):
    if _is_discrete(params):
        return lambda params, top: params[M_SUM, int(top)]

    def continuous(params, top):
        return _integrals_between(params[0], 0.0, top)[1]
    return continuous


@overload(_threshold, inline="always")
def _threshold_overload(params, pos):
    if _is_discrete(params):
        return lambda params, pos: (params[ETA_ROW, int(pos)], params[C_ROW, int(pos)])

    def continuous(params, pos):
        return _eta_at(params[0], pos), 0.0
    return continuous


@overload(_split, inline="always")
def _split_overload(params, state, row, x, s):
    if _is_discrete(params):
        def discrete(params, state, row, x, s):
            # branch i slides when s (a + x + beta eta_i + gamma c_i) >= eta_i
            eta = params[ETA_ROW]
            c = params[C_ROW]
            a_x, beta, gamma = state[row + 2] + x, state[row + 3], state[row + 4]
            lo, hi = int(state[row]), int(state[row + 1])
            if s * (a_x + beta * eta[hi - 1] + gamma * c[hi - 1]) >= eta[hi - 1]:
                return float(hi)
            if not s * (a_x + beta * eta[lo] + gamma * c[lo]) >= eta[lo]:
                return float(lo)
            first, last = lo, hi - 1  # slides at first, not at last: find the boundary
            while last - first > 1:
                middle = (first + last) >> 1
                if s * (a_x + beta * eta[middle] + gamma * c[middle]) >= eta[middle]:
                    first = middle
                else:
                    last = middle
            return float(last)
        return discrete

    def continuous(params, state, row, x, s):
        # s (a + x + beta eta) >= eta  <=>  eta (1 - s beta) <= s (a + x)
        lo, hi = state[row], state[row + 1]
        reach = s * (state[row + 2] + x)
        q = 1.0 - s * state[row + 3]
        if q <= 0.0:
            return hi if reach >= 0.0 else lo
        return min(max(_last_reached(params[0], reach / q), lo), hi)
    return continuous


# ------------------------------------------------ the energy account

@kernel
def _book_sliding(energy, params, top, distance):
    """The top piece slid by ``distance``: it dissipates distance * sum k eta."""
    if energy is None:
        return
    energy[1] += distance * _moment(params, top)


@kernel
def _book_reached(energy, params, lo, hi, a_x, beta, gamma, s):
    """The branches [lo, hi) of a piece reached their thresholds on the way to x: they slipped by
    s (a + x + beta eta + gamma c) - eta each; add sum k eta slip."""
    if energy is None:
        return
    m_sum = _sums(params, lo, hi)[1]
    e_sum, d_sum, g_sum = _squares(params, lo, hi)
    energy[1] += s * (a_x * m_sum + beta * e_sum + gamma * d_sum) - e_sum


@kernel
def stored_energy(params, state):
    """sum_i k_i u_i^2 / 2 (J): O(number of pieces)."""
    x = state[X]
    e_top, d_top, g_top = _squares(params, 0.0, state[TOP])
    total = e_top
    for j in range(int(state[COUNT])):
        row = HEADER + ROW * j
        a_x, beta, gamma = state[row + 2] + x, state[row + 3], state[row + 4]
        k_sum, m_sum, c_sum = _sums(params, state[row], state[row + 1])
        e_sum, d_sum, g_sum = _squares(params, state[row], state[row + 1])
        total += (a_x * (a_x * k_sum + 2.0 * beta * m_sum + 2.0 * gamma * c_sum)
                  + beta * (beta * e_sum + 2.0 * gamma * d_sum) + gamma * gamma * g_sum)
    return 0.5 * total


# ------------------------------------------------ moves

@kernel
def resync(params, state):
    """Recompute the running totals SK and S0 from the pieces."""
    sk = 0.0
    s0 = 0.0
    for j in range(int(state[COUNT])):
        row = HEADER + ROW * j
        a, beta, gamma = state[row + 2], state[row + 3], state[row + 4]
        k_sum, m_sum, c_sum = _sums(params, state[row], state[row + 1])
        sk += k_sum
        s0 += a * k_sum + beta * m_sum + gamma * c_sum
    state[SK] = sk
    state[S0] = s0
    state[MOVES] = 0.0


@kernel
def bounds(params):
    """(sum |k|, max eta) over every branch (the continuum: the integral of k, eta(1)), for the bounds of
    ``kernels/showable.py``. O(n), or O(1) for the continuum."""
    return _bounds(params)


def _bounds(params):
    raise NotImplementedError


@overload(_bounds)
def _bounds_overload(params):
    if _is_discrete(params):
        def discrete(params):
            total = 0.0
            largest = 0.0
            for i in range(params.shape[1] - 1):
                total += abs(params[K_ROW, i])
                largest = max(largest, abs(params[ETA_ROW, i]))
            return total, largest
        return discrete

    def continuous(params):
        table = params[0]
        return abs(table[K_AT, table.shape[1] - 1]), abs(table[ETA_AT, table.shape[1] - 1])
    return continuous


@kernel
def force(params, state):
    """sum_i k_i u_i (N) at the current displacement."""
    return state[S0] + state[X] * state[SK] + state[DIRECTION] * _moment(params, state[TOP])


@kernel
def move(params, state, dx, energy):
    """Move the displacement by the monotone increment dx; return the new force.

    With an ``energy`` account (not None), add the sliders' dissipation to energy[1].
    """
    x = state[X]
    if x + dx == x:
        return force(params, state)
    s = 1.0 if dx > 0.0 else -1.0
    result = _walk(params, state, dx, s, energy, True)
    return result[0]


@kernel
def peek(params, state, dx, direction):
    """The branch force as a function of the increment around ``dx`` (0 or of the sign of ``direction``),
    without moving: ``(force, stiffness, room)`` as :func:`play.piece`.

    ``stiffness`` is the sum of k over the branches that still stick just
    beyond dx in ``direction``; ``room`` how far the increment can go beyond
    dx before the next branch slips (``inf`` when none is left).
    """
    return _walk(params, state, dx, direction, None, False)


@inline_kernel
def _walk(params, state, dx, s, energy, commit):
    """Move by dx in direction s (dx = 0 or of sign s); write the new state only if ``commit``.

    Returns ``(force, stiffness, room)`` at x + dx (see :func:`peek`).
    """
    x = state[X]
    x_new = x + dx
    count = int(state[COUNT])
    top = state[TOP]
    d = state[DIRECTION]
    sk = state[SK]
    s0 = state[S0]
    if s != d and top > 0.0:
        # reversal: the branches that slid stick again, u_i = d eta_i = (-x) + x + d eta_i.
        # The row beyond the stack is free (kept so by _compact); without commit it is scratch.
        row = HEADER + ROW * count
        state[row] = 0.0
        state[row + 1] = top
        state[row + 2] = -x
        state[row + 3] = d
        state[row + 4] = 0.0
        k_sum, m_sum, c_sum = _sums(params, 0.0, top)
        sk += k_sum
        s0 += -x * k_sum + d * m_sum
        count += 1
        top = 0.0
    elif commit:
        _book_sliding(energy, params, top, abs(dx))
    d = s
    split_row = -1
    split_at = 0.0
    while count > 0:
        row = HEADER + ROW * (count - 1)  # the sticking piece with the smallest eta
        lo, hi = state[row], state[row + 1]
        p = _split(params, state, row, x_new, s)
        if p <= lo:
            break
        a, beta, gamma = state[row + 2], state[row + 3], state[row + 4]
        k_sum, m_sum, c_sum = _sums(params, lo, p)
        sk -= k_sum
        s0 -= a * k_sum + beta * m_sum + gamma * c_sum
        if commit:
            _book_reached(energy, params, lo, p, a + x_new, beta, gamma, s)
        top = p
        if p < hi:  # split: [lo, p) slides, [p, hi) sticks
            split_row = row
            split_at = p
            break
        count -= 1  # the whole piece slides
    if commit:
        state[COUNT] = count
        state[TOP] = top
        state[DIRECTION] = d
        state[SK] = sk
        state[S0] = s0
        state[X] = x_new
        if split_row >= 0:
            state[split_row] = split_at
        state[MOVES] += 1.0
        if state[MOVES] >= RESYNC:
            resync(params, state)
        if (count + 2) * ROW + HEADER > state.shape[0]:
            _compact(params, state)
        count = int(state[COUNT])
        sk = state[SK]
        s0 = state[S0]
        top = state[TOP]
    force_new = s0 + x_new * sk + d * _moment(params, top)
    room = np.inf
    if count > 0 and not commit:  # only a peek asks for the room (a move would only waste a memory access)
        row = HEADER + ROW * (count - 1)
        first = split_at if row == split_row else state[row]
        eta, c = _threshold(params, first)
        u = state[row + 2] + x_new + state[row + 3] * eta + state[row + 4] * c
        room = max(eta - s * u, 0.0)
    return force_new, sk, room


def _compact(params, state):
    """Make room for one more piece (the continuum only: see the overload)."""
    raise NotImplementedError


@overload(_compact, inline="always")
def _compact_overload(params, state):
    if _is_discrete(params):
        # n branches never need it: a reversal needs top > 0, so count <= n - 1 before its push,
        # and the state has n + 1 rows
        return lambda params, state: None
    return _compact_continuum


def _compact_continuum(params, state):
    """Make room for one more piece: replace two adjacent pieces by their chord.

    The two pieces u = a + x + beta eta meeting at a kink are
    replaced by the straight line through the ends of the pair (slope in
    [-1, 1]: the profile stays continuous, 1-Lipschitz and within |u| <= eta,
    so the stack's rules still hold); the pair chosen is the one where this
    changes the force least (kink height times the pair's stiffness). A pair
    of zero eta width (inside a Dirac) is never chosen: the stack never cuts
    a flat segment of eta(s) (a Dirac slides whole, see _last_reached).
    """
    table = params[0]
    x = state[X]
    count = int(state[COUNT])
    best = 0
    cost = np.inf
    for j in range(count - 1):
        deep = HEADER + ROW * j
        upper = deep + ROW
        eta_lo, eta_mid, eta_hi = _eta_at(table, state[upper]), _eta_at(table, state[deep]), _eta_at(
            table, state[deep + 1])
        if not eta_hi > eta_lo:
            continue
        u_lo = state[upper + 2] + x + state[upper + 3] * eta_lo
        u_mid = state[deep + 2] + x + state[deep + 3] * eta_mid
        u_hi = state[deep + 2] + x + state[deep + 3] * eta_hi
        chord_mid = u_lo + (u_hi - u_lo) * (eta_mid - eta_lo) / (eta_hi - eta_lo)
        change = abs(u_mid - chord_mid) * _integrals_between(table, state[upper], state[deep + 1])[0]
        if change < cost:
            cost = change
            best = j
    deep = HEADER + ROW * best
    upper = deep + ROW
    eta_lo, eta_hi = _eta_at(table, state[upper]), _eta_at(table, state[deep + 1])
    u_lo = state[upper + 2] + x + state[upper + 3] * eta_lo
    u_hi = state[deep + 2] + x + state[deep + 3] * eta_hi
    beta = min(max((u_hi - u_lo) / (eta_hi - eta_lo), -1.0), 1.0) if eta_hi > eta_lo else 0.0
    state[deep] = state[upper]
    state[deep + 2] = u_lo - x - beta * eta_lo
    state[deep + 3] = beta
    for j in range(best + 1, count - 1):
        for f in range(ROW):
            state[HEADER + ROW * j + f] = state[HEADER + ROW * (j + 1) + f]
    state[COUNT] = count - 1
    resync(params, state)


@kernel
def elongations(params, state, out):
    """Write u_i into ``out`` (length n, the scene's order): O(n), for output rows only (n branches)."""
    order = params[ORDER_ROW]
    eta = params[ETA_ROW]
    c = params[C_ROW]
    x = state[X]
    top = int(state[TOP])
    d = state[DIRECTION]
    for i in range(top):
        out[int(order[i])] = d * eta[i]
    for j in range(int(state[COUNT])):
        row = HEADER + ROW * j
        lo, hi = int(state[row]), int(state[row + 1])
        a, beta, gamma = state[row + 2], state[row + 3], state[row + 4]
        for i in range(lo, hi):
            out[int(order[i])] = min(max(a + x + beta * eta[i] + gamma * c[i], -eta[i]), eta[i])


@kernel
def profile(params, state, s, out):
    """The elongation u(s) (m) at the positions ``s`` of the continuum (for plots and tests)."""
    x = state[X]
    top = state[TOP]
    d = state[DIRECTION]
    for q in range(s.shape[0]):
        eta = _eta_at(params[0], s[q])
        out[q] = d * eta
        if s[q] < top:
            continue
        for j in range(int(state[COUNT])):
            row = HEADER + ROW * j
            if state[row] <= s[q] <= state[row + 1]:
                out[q] = min(max(state[row + 2] + x + state[row + 3] * eta, -eta), eta)
                break
