"""The friction branches at a cost independent of n: the memory stack.

Used by the explicit steppers (projected, symplectic, verlet) for scenes
with many branches and an admissible initial state, when no energy account
is asked for (see ``driver.compile_model``); tests/test_stack.py shows it
equals the O(n) play kernel.

Sort the branches by elastic range, eta_1 <= ... <= eta_n. From an admissible
state (|u_i| <= eta_i and u 1-Lipschitz in eta: |u_i - u_j| <= |eta_i - eta_j|),
moving x monotonically keeps u admissible, and the profile i -> u_i is made of
consecutive index blocks ("pieces"):

* the top piece [0, top): the branches that slid in the last direction d of
  motion, u_i = d eta_i;
* below it, pieces [lo, hi) of sticking branches, u_i = a + x + beta eta_i
  (+ c_i for the initial piece, c_i = u0_i - x0), beta in {-1, 0, +1}: each
  moves with x, so its force is (a + x) K + beta M (+ C) with the prefix sums
  K = sum k_i, M = sum k_i eta_i, C = sum k_i c_i over the piece.

Moving x by a monotone increment in direction s: a reversal (s != d) first
turns the top piece into a sticking piece (a = -x, beta = d); then, from the
top down, a piece whose largest-eta branch reaches s eta_i is popped whole
(its branches slide), and at most one piece is split where its branches stop
reaching (binary search: the condition s u_i >= eta_i is monotone in i within
a piece). The force sum_i k_i u_i = S0 + x SK + d M(top) is kept as running
totals, updated on every pop, split and push: O(1) amortised plus a binary
search per move, whatever n. The totals are recomputed from the pieces every
``RESYNC`` moves so that rounding does not drift.

State layout (one float64 array, so that it can be copied and saved as plain
data): ``state[:HEADER]`` = count of pieces, top, d, SK, S0, moves since the
last resync, x; then ``count`` rows of (lo, hi, a, beta, gamma), bottom
(largest eta) first.
"""
import numpy as np

from .._jit import kernel

HEADER = 7
ROW = 5
RESYNC = 1024
COUNT, TOP, DIRECTION, SK, S0, MOVES, X = range(HEADER)


def prepare(stiffness, yield_displacement, u0, x0):
    """(params, state, order) for branches k, eta with elongations u0 at x = x0.

    ``order`` sorts the branches by eta; ``params`` is one (7, n + 1) array
    whose rows are k, eta, c (sorted, padded), the prefix sums K, M, C (of
    length n + 1) and the order (one array rather than a tuple of seven: the
    steppers pass it on every step). ValueError if u0 is not admissible (then
    the O(n) kernel must be used).
    """
    order = np.argsort(yield_displacement, kind="stable")
    k = np.ascontiguousarray(stiffness[order], dtype=float)
    eta = np.ascontiguousarray(yield_displacement[order], dtype=float)
    u = np.asarray(u0, dtype=float)[order]
    if not admissible(eta, u):
        raise ValueError("the initial elongations are not 1-Lipschitz in eta: the memory stack does not apply")
    c = u - x0
    prefix = lambda values: np.concatenate([[0.0], np.cumsum(values)])  # noqa: E731
    n = len(k)
    params = np.zeros((7, n + 1))
    params[0, :n], params[1, :n], params[2, :n] = k, eta, c
    params[3], params[4], params[5] = prefix(k), prefix(k * eta), prefix(k * c)
    params[6, :n] = order
    return params, fresh_state(params, x0), order


def fresh_state(params, x0):
    """The state of :func:`prepare`'s initial elongations at x = x0: one piece, u_i = c_i + x."""
    n = params.shape[1] - 1
    state = np.zeros(HEADER + ROW * (n + 1))
    state[X] = x0
    state[COUNT] = 1.0
    state[HEADER:HEADER + ROW] = (0.0, n, 0.0, 0.0, 1.0)
    resync(params, state)
    return state


@kernel
def _rows(params):
    return params[0], params[1], params[2], params[3], params[4], params[5], params[6]


def admissible(eta, u):
    """|u_i| <= eta_i and |u_i - u_j| <= eta_j - eta_i for eta sorted (to rounding)."""
    if np.any(np.abs(u) > eta):
        return False
    tolerance = 1e-12 * max(1.0, float(np.max(eta, initial=0.0)))
    return bool(np.all(np.abs(np.diff(u)) <= np.diff(eta) + tolerance))


@kernel
def resync(params, state):
    """Recompute the running totals SK and S0 from the pieces."""
    k, eta, c, K, M, C, order = _rows(params)
    sk = 0.0
    s0 = 0.0
    for j in range(int(state[COUNT])):
        row = HEADER + ROW * j
        lo, hi = int(state[row]), int(state[row + 1])
        a, beta, gamma = state[row + 2], state[row + 3], state[row + 4]
        piece_k = K[hi] - K[lo]
        sk += piece_k
        s0 += a * piece_k + beta * (M[hi] - M[lo]) + gamma * (C[hi] - C[lo])
    state[SK] = sk
    state[S0] = s0
    state[MOVES] = 0.0


@kernel
def force(params, state):
    """sum_i k_i u_i (N) at the current displacement."""
    x = state[X]
    k, eta, c, K, M, C, order = _rows(params)
    return state[S0] + x * state[SK] + state[DIRECTION] * M[int(state[TOP])]


@kernel
def _slides(params, state, row, i, x, s):
    """Whether branch i of the piece at ``row`` has reached s eta_i at x (it slides in direction s)."""
    k, eta, c, K, M, C, order = _rows(params)
    u = state[row + 2] + x + state[row + 3] * eta[i] + state[row + 4] * c[i]
    return s * u >= eta[i]


@kernel
def _add(params, state, lo, hi, a, beta, gamma, sign):
    """Add (sign = 1) or remove (sign = -1) the block [lo, hi) of a piece to the running totals."""
    k, eta, c, K, M, C, order = _rows(params)
    piece_k = K[hi] - K[lo]
    state[SK] += sign * piece_k
    state[S0] += sign * (a * piece_k + beta * (M[hi] - M[lo]) + gamma * (C[hi] - C[lo]))


@kernel
def move(params, state, dx):
    """Move the displacement by the monotone increment dx; return the new force."""
    x = state[X]
    x_new = x + dx
    if x_new == x:
        return force(params, state)
    s = 1.0 if x_new > x else -1.0
    top = int(state[TOP])
    if s != state[DIRECTION] and top > 0:
        # reversal: the branches that slid stick again, u_i = d eta_i = (-x) + x + d eta_i
        count = int(state[COUNT])
        row = HEADER + ROW * count
        d = state[DIRECTION]
        state[row] = 0.0
        state[row + 1] = top
        state[row + 2] = -x
        state[row + 3] = d
        state[row + 4] = 0.0
        _add(params, state, 0, top, -x, d, 0.0, 1.0)
        state[COUNT] = count + 1
        top = 0
    state[DIRECTION] = s
    while state[COUNT] > 0:
        count = int(state[COUNT])
        row = HEADER + ROW * (count - 1)  # the sticking piece with the smallest eta
        lo, hi = int(state[row]), int(state[row + 1])
        a, beta, gamma = state[row + 2], state[row + 3], state[row + 4]
        if _slides(params, state, row, hi - 1, x_new, s):
            _add(params, state, lo, hi, a, beta, gamma, -1.0)  # the whole piece slides
            state[COUNT] = count - 1
            top = hi
            continue
        if _slides(params, state, row, lo, x_new, s):
            first, last = lo, hi - 1  # slides at first, not at last: find the boundary
            while last - first > 1:
                middle = (first + last) // 2
                if _slides(params, state, row, middle, x_new, s):
                    first = middle
                else:
                    last = middle
            _add(params, state, lo, last, a, beta, gamma, -1.0)
            state[row] = last
            top = last
        break
    state[TOP] = top
    state[X] = x_new
    state[MOVES] += 1.0
    if state[MOVES] >= RESYNC:
        resync(params, state)
    return force(params, state)


@kernel
def elongations(params, state, out):
    """Write u_i into ``out`` (length n, the scene's order): O(n), for output rows only."""
    k, eta, c, K, M, C, order = _rows(params)
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
