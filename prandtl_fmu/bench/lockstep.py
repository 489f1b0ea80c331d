"""The paper's Table 1 measured in lockstep: a run at h and one at h/2 side by side, and the distance between
them at every node, computed on the memory stack's own representation (``kernels/stack.py``).

Bastien & Schatzman (M2AN 2002, section 8) define eps(h) = || u_h - u_{h/2} ||_{C^0([0, T], l^q_{n+2})}, with
u = (x, y, u_1 .. u_n) (y = v, eq. 7.8) and u_h the piecewise-linear interpolant of the nodes U^p of scheme (5.1)
(the paper's introduction). The difference of two piecewise-linear functions is linear between the fine nodes,
so its maximum over [0, T] is the maximum over the fine nodes: at the coarse nodes t_p = p h, U_h^p - U_{h/2}^{2p},
and at the fine nodes in between, (U_h^p + U_h^{p+1}) / 2 - U_{h/2}^{2p+1}.

On the memory stack an elongation profile i -> u_i (branches in eta order) is a list of pieces, on each of which
u_i = A + B eta_i + G c_i (the top piece: A = 0, B = d; a sticking piece: A = a + x, B = beta, G = gamma; c = u0).
A weighted sum of such profiles (the difference of two runs, or of an interpolant and a run) is again affine on
each cell of the merged list of piece boundaries, so its norms come from the ends of each cell (the max of an
affine function of eta) and from prefix sums (the sum of squares): the cost of a node is the depth of the stacks,
not n. A short cell (at most ``SHORT`` branches, where two runs' boundaries differ and the closed form would
subtract large nearly equal terms) is summed branch by branch; so is any cell when u0 != 0 and the runs' gamma
differ (c_i has no structure in i).

Per node, ``MEASURES`` quantities of the difference (dx, dv, du, dw with w_i = x - u_i the slider displacement,
eq. 7.4): the components the norms of the convention search (``bench/table1.py``) are built from. Two of them
are the displacement other schemes would give from the same (y, u) (with k0 = 0, x does not act back on them):
x^{p+1} = x^p + h y^{p+1} sums to x^p + h y^p (``x_new``, from y^0 = 0), the trapezoid x^{p+1} = x^p + h (y^p +
y^{p+1}) / 2 to x^p + h y^p / 2 (``x_trap``). Their maxima
over the nodes are kept for three kinds of node (``KINDS``): the coarse nodes, the fine nodes in between against
the coarse run's linear interpolant, and the same fine nodes against the coarse run held constant over its step.
"""
import numpy as np

from .._jit import generic_kernel, kernel
from ..memory import prepare
from ..kernels import stack

SHORT = 64  # a cell of at most this many branches is summed branch by branch

# what is measured of the difference at a node (columns of ``maxima``)
DX, DV, U_MAX, W_MAX, L2, L2_U, L2_ENERGY, L2_MEAN, L2_SLIDER, L2_XV, L2_VU, X_NEW, X_TRAP = range(13)
MEASURES = ("x", "v", "u_max", "w_max", "l2", "l2_u", "l2_energy", "l2_mean", "l2_slider", "l2_xv", "l2_vu",
            "x_new", "x_trap")
COUNT = len(MEASURES)
# the nodes (rows of ``maxima``): coarse nodes; fine nodes against the linear interpolant; against the held value.
# int64, not the constants 0, 1, 2, for each of which numba would compile _keep once more (tests/compiled_copies.py)
COARSE, LINEAR, HELD = np.int64(0), np.int64(1), np.int64(2)
KINDS = ("coarse", "linear", "held")
# the three profiles a difference is made of (rows of ``states``): the coarse run, the fine run, the coarse run's
# previous node
NEW, FINE, OLD = range(3)

# rows of ``plain``: prefix sums over the branches in eta order of 1, eta, eta^2, c, eta c, c^2
P_COUNT, P_ETA, P_ETA2, P_C, P_ETAC, P_C2 = range(6)


def plain_sums(params):
    """The prefix sums (6, n + 1) of 1, eta, eta^2, c, eta c, c^2 over the branches in eta order (stack.prepare's
    ``params``): what the unweighted sums of squares need (the k-weighted ones are in ``params`` itself)."""
    n = params.shape[1] - 1
    eta, c = params[stack.ETA_ROW, :n], params[stack.C_ROW, :n]
    out = np.zeros((6, n + 1))
    for row, values in ((P_COUNT, np.ones(n)), (P_ETA, eta), (P_ETA2, eta * eta), (P_C, c), (P_ETAC, eta * c),
                        (P_C2, c * c)):
        out[row, 1:] = np.cumsum(values)
    return out


@kernel
def _cell(params, plain, with_c, lo, hi, a, b, g):
    """(max_i |D_i|, sum_i D_i^2, sum_i k_i D_i^2) over the branches [lo, hi) of D_i = a + b eta_i + g c_i."""
    eta, c, k = params[stack.ETA_ROW], params[stack.C_ROW], params[stack.K_ROW]
    if b == 0.0 and (g == 0.0 or not with_c):  # the same slope on both sides (the usual case): D_i = a
        k1 = params[stack.K_SUM, hi] - params[stack.K_SUM, lo]
        return abs(a), (hi - lo) * a * a, k1 * a * a
    if hi - lo <= SHORT or (with_c and g != 0.0):
        largest = square = weighted = 0.0
        for i in range(lo, hi):
            d = a + b * eta[i] + g * c[i]
            largest = max(largest, abs(d))
            square += d * d
            weighted += k[i] * d * d
        return largest, square, weighted
    # g = 0 here (or c = 0): D_i = a0 + b (eta_i - eta_lo), centred at the cell's first branch
    e0 = eta[lo]
    a0 = a + b * e0
    largest = max(abs(a0), abs(a + b * eta[hi - 1]))
    count = plain[P_COUNT, hi] - plain[P_COUNT, lo]
    s1 = plain[P_ETA, hi] - plain[P_ETA, lo]
    s2 = plain[P_ETA2, hi] - plain[P_ETA2, lo]
    first = s1 - count * e0
    second = max(s2 - 2.0 * e0 * s1 + count * e0 * e0, 0.0)
    square = count * a0 * a0 + 2.0 * a0 * b * first + b * b * second
    k1 = params[stack.K_SUM, hi] - params[stack.K_SUM, lo]
    m1 = params[stack.M_SUM, hi] - params[stack.M_SUM, lo]
    e2 = params[stack.E_SUM, hi] - params[stack.E_SUM, lo]
    k_first = m1 - e0 * k1
    k_second = max(e2 - 2.0 * e0 * m1 + e0 * e0 * k1, 0.0)
    weighted = k1 * a0 * a0 + 2.0 * a0 * b * k_first + b * b * k_second
    return largest, max(square, 0.0), max(weighted, 0.0)


@kernel
def _advance(states, s, cursor, ends, coef, x):
    """Move profile ``s``'s cursor to its next piece (the stack's rows run from the largest eta down)."""
    cursor[s] -= 1
    row = stack.HEADER + stack.ROW * cursor[s]
    ends[s] = states[s, row + 1]
    coef[s, 0] = states[s, row + 2] + x
    coef[s, 1] = states[s, row + 3]
    coef[s, 2] = states[s, row + 4]


@kernel
def difference(params, plain, with_c, states, xs, vs, hs, weights, m, k0, out):
    """The measures (``MEASURES``) of the weighted sum of the profiles ``states`` (3, L), at displacements ``xs``
    and velocities ``vs`` (3,) of runs with steps ``hs`` (3,), with ``weights`` (3,), into ``out``. The merged
    cells cost O(depth of the stacks).
    Returns False if the pieces do not tile the branches (then ``out`` holds NaN)."""
    return _difference(params, plain, with_c, states, xs, vs, hs, weights, m, k0, out,
                       np.empty(3, dtype=np.int64), np.empty(3), np.zeros((3, 3)))


@kernel
def _difference(params, plain, with_c, states, xs, vs, hs, weights, m, k0, out, cursor, ends, coef):
    """:func:`difference` with its scratch arrays given (the lockstep allocates them once, not per node)."""
    n = params.shape[1] - 1
    for s in range(3):
        cursor[s] = int(states[s, stack.COUNT])
        ends[s] = states[s, stack.TOP] if weights[s] != 0.0 else float(n)
        coef[s, 0], coef[s, 1], coef[s, 2] = 0.0, states[s, stack.DIRECTION], 0.0
        if weights[s] != 0.0:
            while ends[s] <= 0.0 and cursor[s] > 0:
                _advance(states, s, cursor, ends, coef, xs[s])
    dx = weights[0] * xs[0] + weights[1] * xs[1] + weights[2] * xs[2]
    dv = weights[0] * vs[0] + weights[1] * vs[1] + weights[2] * vs[2]
    u_max = w_max = u_sq = u_ksq = w_sq = 0.0
    pos = 0.0
    tiled = True
    while pos < n:
        end = min(ends[0], min(ends[1], ends[2]))
        if not end > pos:
            tiled = False
            break
        a = b = g = 0.0
        for s in range(3):
            if weights[s] != 0.0:
                a += weights[s] * coef[s, 0]
                b += weights[s] * coef[s, 1]
                g += weights[s] * coef[s, 2]
        lo, hi = int(pos), int(end)
        largest, square, weighted = _cell(params, plain, with_c, lo, hi, a, b, g)
        u_max = max(u_max, largest)
        u_sq += square
        u_ksq += weighted
        largest, square, weighted = _cell(params, plain, with_c, lo, hi, dx - a, -b, -g)  # w_i = x - u_i
        w_max = max(w_max, largest)
        w_sq += square
        pos = end
        for s in range(3):
            if weights[s] != 0.0:
                while ends[s] <= pos and cursor[s] > 0:
                    _advance(states, s, cursor, ends, coef, xs[s])
    if not tiled:
        out[:] = np.nan
        return False
    out[DX] = abs(dx)
    out[DV] = abs(dv)
    out[U_MAX] = u_max
    out[W_MAX] = w_max
    out[L2] = np.sqrt(dx * dx + dv * dv + u_sq)
    out[L2_U] = np.sqrt(u_sq)
    out[L2_ENERGY] = np.sqrt(k0 * dx * dx + m * dv * dv + u_ksq)
    out[L2_MEAN] = np.sqrt(dx * dx + dv * dv + u_sq / n)
    out[L2_SLIDER] = np.sqrt(dx * dx + dv * dv + w_sq)
    out[L2_XV] = np.sqrt(dx * dx + dv * dv)
    out[L2_VU] = np.sqrt(dv * dv + u_sq)
    lead = weights[0] * hs[0] * vs[0] + weights[1] * hs[1] * vs[1] + weights[2] * hs[2] * vs[2]
    out[X_NEW] = abs(dx + lead)
    out[X_TRAP] = abs(dx + 0.5 * lead)
    return True


@kernel
def _keep(maxima, when, kind, values, t):
    for j in range(values.shape[0]):
        if not values[j] <= maxima[kind, j]:  # a NaN is kept too: it must show
            maxima[kind, j] = values[j]
            when[kind, j] = t


def lockstep_for(step):
    """The lockstep loop over a stepper's compiled ``step`` (a closure, compiled; wrapped in a cached kernel per
    stepper below, as ``kernels/loop.py`` does for the time loop)."""

    def lockstep(model, load, plain, with_c, states, h, theta, held_too, first, steps, maxima, when, state):
        """Advance the run at ``h`` (profile ``states[NEW]``) by ``steps`` steps from step number ``first`` and
        the run at h/2 (``states[FINE]``) by twice as many, measuring the difference at every node. A step
        from t_p sees the load at t_p + theta h (theta = 0: scheme 5.1; theta = 1: the g(t_{p+1}) of (1.12)).

        ``state`` (4,) = x and v of the coarse run, then of the fine run, updated in place. ``maxima`` and
        ``when`` (3, len(MEASURES)): the largest value of each measure over the nodes of each kind and the time
        of the node where it was reached, updated.
        Returns the number of coarse steps taken (fewer if a state stops being finite or the pieces stop
        tiling the branches)."""
        m, k0, k3, c, k, eta, cs, friction, memory = model
        params = k
        half = 0.5 * h
        prepare(memory, h)
        xc, vc, xf, vf = state[0], state[1], state[2], state[3]
        sc = stack.force(params, states[NEW])
        sf = stack.force(params, states[FINE])
        values = np.empty(COUNT)
        cursor = np.empty(3, dtype=np.int64)
        ends = np.empty(3)
        coef = np.zeros((3, 3))
        xs = np.empty(3)
        vs = np.empty(3)
        hs = np.array([h, half, h])
        linear = np.array([0.5, -1.0, 0.5])
        held = np.array([0.0, -1.0, 1.0])
        nodes = np.array([1.0, -1.0, 0.0])
        k0_value = 0.0 if k0 is None else k0
        for p in range(first, first + steps):
            used = stack.HEADER + stack.ROW * int(states[NEW, stack.COUNT])
            for q in range(used):  # (element by element: a slice assignment compiles numba's shape check)
                states[OLD, q] = states[NEW, q]
            xo, vo = xc, vc
            xc, vc, sc = step(model, load, (p + theta) * h, h, xc, vc, sc, states[NEW], None)
            xf, vf, sf = step(model, load, (2 * p + theta) * half, half, xf, vf, sf, states[FINE], None)
            xs[NEW], xs[FINE], xs[OLD] = xc, xf, xo
            vs[NEW], vs[FINE], vs[OLD] = vc, vf, vo
            t_mid = (2 * p + 1) * half
            ok = _difference(params, plain, with_c, states, xs, vs, hs, linear, m, k0_value, values, cursor, ends, coef)
            _keep(maxima, when, LINEAR, values, t_mid)
            if held_too:
                ok = _difference(params, plain, with_c, states, xs, vs, hs, held, m, k0_value, values, cursor, ends,
                                 coef) and ok
                _keep(maxima, when, HELD, values, t_mid)
            xf, vf, sf = step(model, load, (2 * p + 1 + theta) * half, half, xf, vf, sf, states[FINE], None)
            xs[FINE], vs[FINE] = xf, vf
            ok = _difference(params, plain, with_c, states, xs, vs, hs, nodes, m, k0_value, values, cursor, ends,
                             coef) and ok
            _keep(maxima, when, COARSE, values, (p + 1) * h)
            state[0], state[1], state[2], state[3] = xc, vc, xf, vf
            if not (ok and abs(xc) < np.inf and abs(vc) < np.inf and abs(xf) < np.inf and abs(vf) < np.inf):
                return p - first + 1
        return steps

    lockstep.__qualname__ = f"lockstep_for.<locals>.lockstep_{step.__module__.rpartition('.')[2]}_{step.__name__}"
    return generic_kernel(lockstep)


from ..steppers import projected as _projected, symplectic as _symplectic  # noqa: E402

_projected_lockstep = lockstep_for(_projected.step)
_symplectic_lockstep = lockstep_for(_symplectic.step)


@kernel
def lockstep_projected(model, load, plain, with_c, states, h, theta, held_too, first, steps, maxima, when, state):
    """:func:`lockstep_for` over ``projected``'s step (scheme 5.1), cached."""
    return _projected_lockstep(model, load, plain, with_c, states, h, theta, held_too, first, steps, maxima, when,
                               state)


@kernel
def lockstep_symplectic(model, load, plain, with_c, states, h, theta, held_too, first, steps, maxima, when, state):
    """:func:`lockstep_for` over ``symplectic``'s step (x with the old velocity, v with the new forces), cached."""
    return _symplectic_lockstep(model, load, plain, with_c, states, h, theta, held_too, first, steps, maxima, when,
                                state)


LOCKSTEPS = {"projected": lockstep_projected, "symplectic": lockstep_symplectic}
