"""The compiled steps of a network: ``implicit`` (an exact active-set method) and ``projected``.

A compiled network is the tuple ``model = (mass, kind, ends, coef, load_node, has_cubic)``:

* ``mass[j]`` (kg, 0: a massless node) for the nodes j = 0 .. n-1;
* element e has ``kind[e]`` (SPRING, DASHPOT, SLIDER, BRANCH, CUBIC), ``ends[e] = (i, j)`` with i a node and
  j a node or GROUND (-1), and ``coef[e] = (a, eta, c)``: a = k, c, alpha, k or k3 by kind; eta and c the
  elastic range and the series dashpot of a branch (c = 0: none);
* ``load_node``: the node the load F acts on (or whose motion is imposed: the connector).

The state is x, v (per node), ``u[e]`` the elongation of branch e (0 for the other kinds) and ``piece[e]``
(which piece of its law element e was on at the last step: the warm start of the next one).

``implicit``: backward Euler on everything. With the increment d = x1 - x of every node, v1 = d / h, and
delta_e = d_i - d_j the relative increment of element e, the step is the minimiser of the strictly convex

    J(d) = sum_j m_j / (2 h^2) (d_j - h v_j)^2 - F(t+h) d_L
         + sum_springs k/2 (e_e + delta_e)^2 + sum_cubic k3/4 (e_e + delta_e)^4 + sum_dashpots c/(2h) delta_e^2
         + sum_sliders alpha |delta_e| + sum_branches Phi_e(delta_e)

(e_e = x_i - x_j; Phi_e the convex potential whose derivative is the branch force k clip(r (u_e + delta),
-eta, eta), r = 1 / (1 + h k / c), i.e. u1 = clip(r (u + delta), -eta, eta)). J is piecewise quadratic (plus
quartic terms) over regions cut by the kinks: a slider's delta = 0 and a branch's r (u + delta) = +-eta.

:func:`implicit_step` minimises J by a primal active-set method, the finite method of convex quadratic
programming applied to the pieces: a stuck slider or a branch at its kink is an equality constraint
(delta_e = its value), every other element sits on one piece of its law. On the current working set the
piece's quadratic is minimised exactly (the stuck elements merge their nodes into clusters; a linear solve
over the clusters: banded LDL^T, tridiagonal for a chain); the step towards that minimiser stops at the first
kink it meets, which joins the working set; at a minimiser of the working set, the forces the constraints
carry (the multipliers, from the equilibrium of each cluster's tree of constraints) say which constraint to
release: a stuck slider whose force exceeds alpha slips, a branch at its kink goes to the piece its force
asks for. J decreases strictly from working set to working set, so no working set repeats and the search
ends; the result is exact up to rounding (no tolerance but rounding's in the comparisons). With cubic
springs the piece's quadratic is their Newton model, and the step is taken with an exact line search along
it: Newton's iteration, converged to rounding. Every search has a stated budget (:func:`search_budget`); past
it the step fails (NaN) and the driver says so.

A white noise on the load (``[load] kind = "white_noise"`` or ``noise_intensity``: F + sigma xi(t) on the load's
node) enters both steps as the step's mean force, F + sigma (B(t + h) - B(t)) / h (:func:`loads.impulse`):
backward Euler-Maruyama for ``implicit`` (every multivalued part stays implicit), Euler-Maruyama for
``projected``. Without a noise the load tuple has no noise entry and nothing of it is compiled.

``projected`` (where every node has a mass and all plasticity is in branches): the paper's scheme
(M2AN 2002, eq. 5.1) on the network, every force at the old state:

    u_e <- clip(u_e + h (v_i - v_j) - h k_e u_e / c_e, -eta_e, eta_e),   x <- x + h v,   v <- v + h a(old).
"""
import numpy as np

from .._jit import generic_kernel, inline_kernel, kernel
from ..loads import force_at, impulse, with_noise
from .chain import chain_step
from .chain import scratch as chain_scratch

SPRING, DASHPOT, SLIDER, BRANCH, CUBIC = 0, 1, 2, 3, 4
GROUND = -1
# ``fixed_node`` of a step that imposes no node's increment. An int64, not the constant -1: numba compiles a
# kernel called with a constant argument again for that constant (a literal is a signature of its own), so the
# counters and flags handed to kernels below start as np.int64 / np.bool_ too (tests/networks/test_mechanics.py)
NO_NODE = np.int64(-1)
# pieces: a slider 0 (stuck: a constraint), +1 / -1 (slipping forwards / backwards); a branch 0 (elastic),
# +1 / -1 (clipped at +eta / -eta), +2 / -2 (at its kink +eta / -eta: a constraint)
STUCK, ELASTIC = 0, 0
KINK = 2

# Budget of one implicit step: active-set iterations per element and node, plus this constant.
SEARCH_PER_TERM = 8
SEARCH_CONSTANT = 200
SETTLE_ITERATIONS = 64  # Newton's corrections of a settled step (:func:`settle`): one for linear pieces
SETTLED = 2.0 ** -26  # a new position within this fraction of itself from the root is kept as it is (settle)
# a node that falls below this fraction of its place in one step may miss its root by SETTLED of itself (x + d
# rounds at a few ulps of x: 4 eps |x| = 2^-24 |x| SETTLED); above it, x + d is within SETTLED of the root
FALLEN = 2.0 ** -24
LINE_SEARCH_LIMIT = 200  # bisection/Newton iterations of one line search along a cubic spring's Newton step
ROUNDING = 64.0 * np.finfo(np.float64).eps  # relative size of a rounding error in a force balance


@kernel
def search_budget(n, elements):
    """The most active-set iterations one implicit step may take before it is refused."""
    return SEARCH_PER_TERM * (n + elements) + SEARCH_CONSTANT


@kernel
def workspace(n, elements):
    """Arrays an implicit step works in (allocated once per run): d, grad, p, parent, cluster, term, subtree,
    queue, degree, links, scale."""
    return (np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n + 1, np.int64), np.zeros(n + 1, np.int64),
            np.zeros(elements), np.zeros(n + 1), np.zeros(n + 1, np.int64), np.zeros(n + 1, np.int64),
            np.zeros(n + 1, np.int64), np.zeros(n))


@inline_kernel
def _ratio(coef, e, h):
    """r = 1 / (1 + h k / c) of branch e (1 without a series dashpot)."""
    c = coef[e, 2]
    if c > 0.0:
        return 1.0 / (1.0 + h * coef[e, 0] / c)
    return 1.0


@inline_kernel
def is_constraint(kd, p):
    """Whether an element of kind kd on piece p is a constraint: a stuck slider, a branch at its kink."""
    if kd == SLIDER:
        return p == STUCK
    if kd == BRANCH:
        return abs(p) == KINK
    return False


@inline_kernel
def _relative(ends, d, e):
    """d_i - d_j of element e (d of the ground: 0)."""
    j = ends[e, 1]
    if j == GROUND:
        return d[ends[e, 0]]
    return d[ends[e, 0]] - d[j]


@inline_kernel
def _relative_x(ends, x, e):
    j = ends[e, 1]
    if j == GROUND:
        return x[ends[e, 0]]
    return x[ends[e, 0]] - x[j]


@inline_kernel
def term_force(kd, a, eta, c, p, rel_x, delta, u_e, h):
    """(force, curvature) of an element of kind ``kd``, coefficients a, eta, c, on piece p, at the relative
    increment delta (rel_x: its relative displacement at the step's start, u_e: a branch's elongation there):
    force the derivative of its potential in delta (the pull on node i towards j), curvature the second
    derivative (0 on a flat piece). A constraint's force here is its piece's value (0 for a stuck slider,
    +-k eta at a kink): the multiplier comes on top (:func:`_multipliers`). Scalars only: the hot loops pass
    what they read once."""
    if kd == SPRING:
        return a * (rel_x + delta), a
    if kd == DASHPOT:
        return a * delta / h, a / h
    if kd == CUBIC:
        y = rel_x + delta
        return a * y * y * y, 3.0 * a * y * y
    if kd == SLIDER:
        if p == STUCK:
            return 0.0, 0.0
        return a * p, 0.0
    if p == ELASTIC:
        r = 1.0 / (1.0 + h * a / c) if c > 0.0 else 1.0
        return a * r * (u_e + delta), a * r
    if p > 0:
        return a * eta, 0.0
    return -a * eta, 0.0


@kernel
def _find(parent, a):
    root = a
    while parent[root] != root:
        root = parent[root]
    while parent[a] != root:  # path compression
        a, parent[a] = parent[a], root
    return root


@kernel
def _clusters(n, kind, ends, piece, parent, cluster, held_node):
    """Union the nodes the constraints join (the ground is node n; ``held_node`` >= 0, the connector's node
    whose motion is imposed, is held with it); cluster[j] = the free cluster of node j, numbered in the order
    of their first node, or -1 for a node held. Returns the number of free clusters."""
    for a in range(n + 1):
        parent[a] = a
    if held_node >= 0:
        parent[held_node] = n
    for e in range(kind.shape[0]):
        if is_constraint(kind[e], piece[e]):
            j = ends[e, 1]
            ra = _find(parent, ends[e, 0])
            rb = _find(parent, n if j == GROUND else j)
            if ra == rb:
                continue
            if ra == n or rb == n:
                parent[min(ra, rb)] = n
            else:
                parent[max(ra, rb)] = min(ra, rb)
    for a in range(n + 1):
        cluster[a] = -2
    count = 0
    for j in range(n):
        root = _find(parent, j)
        if root == n:
            cluster[j] = -1
        else:  # the root is the cluster's first node: it is numbered first
            if cluster[root] == -2:
                cluster[root] = count
                count += 1
            cluster[j] = cluster[root]
    return count


@kernel
def _start_pieces(model, x, u, piece, d, h):
    """Put every element on the piece its relative increment at the start point d lies on, keeping the last
    step's piece where it still holds (the warm start); a branch's kink is a constraint within a step only."""
    mass, kind, ends, coef, load_node, has_cubic = model
    for e in range(kind.shape[0]):
        i, j = ends[e, 0], ends[e, 1]
        delta = d[i] if j == GROUND else d[i] - d[j]
        if kind[e] == SLIDER:
            if piece[e] == STUCK and delta != 0.0 or piece[e] * delta < 0.0:
                piece[e] = 1 if delta > 0.0 else -1
        elif kind[e] == BRANCH:
            p = piece[e]
            if abs(p) == KINK:
                p = p // KINK
            r = 1.0 / (1.0 + h * coef[e, 0] / coef[e, 2]) if coef[e, 2] > 0.0 else 1.0
            y = r * (u[e] + delta)
            eta = coef[e, 1]
            if y > eta or p > 0 and y == eta:
                p = 1
            elif y < -eta or p < 0 and y == -eta:
                p = -1
            else:
                p = ELASTIC
            piece[e] = p


@kernel
def _gradient(model, x, v, u, piece, d, h, force, grad, term, scale, cluster, a, anchor, degree, links, at_end):
    """grad_j = dJ/dd_j on the current pieces (constraints without their multipliers); term[e] = the force of
    element e; scale[j] = the sum of the magnitudes of the forces at node j (for rounding tolerances).

    ``at_end`` (np.bool_): ``x`` is the step's end x1 = x + d itself (:func:`settle`): a spring's and a cubic
    spring's force from x1_i - x1_j alone (not from their elongation at the step's start plus delta_e, whose
    sum rounds at the start's size); the inertia, the dashpots and the branches from d as always.

    In the same pass over the elements (each pass costs as much as the arithmetic: the arrays of a large
    network do not fit in the cache), where not None:

    * ``a``, ``anchor`` (zeros; ``cluster`` from :func:`_clusters`): the clusters' matrix, banded (a[c, t] =
      H[c, c - t]), and anchors: the part of each cluster's diagonal that no other cluster shares (its inertia,
      its elements to held nodes). A pivot of the LDL^T factorization is at least its cluster's anchor (a Schur
      complement of a sum of positive semidefinite matrices is at least the sum of theirs). Returns the half
      bandwidth the matrix needs: beyond ``a``'s width, ``a`` is incomplete and the caller assembles it again,
      wider;
    * ``degree``, ``links``: each node's count of constraints and the XOR of their ids (:func:`_multipliers`).
    """
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    width = 0 if a is None else a.shape[1] - 1
    band = 0
    for j in range(n):
        inertia = mass[j] / (h * h) * (d[j] - h * v[j])
        grad[j] = inertia
        scale[j] = mass[j] / (h * h) * (abs(d[j]) + abs(h * v[j]))  # the rounding's size, not the value's
        if a is not None:
            c = cluster[j]
            if c >= 0:
                a[c, 0] += mass[j] / (h * h)
                anchor[c] += mass[j] / (h * h)
    if degree is not None:
        for q in range(n + 1):
            degree[q] = 0
            links[q] = 0
    grad[load_node] -= force
    scale[load_node] += abs(force)
    for e in range(kind.shape[0]):
        i, j = ends[e, 0], ends[e, 1]
        if j == GROUND:
            rel_x, delta = x[i], d[i]
        else:
            rel_x, delta = x[i] - x[j], d[i] - d[j]
        if at_end and (kind[e] == SPRING or kind[e] == CUBIC):
            delta = 0.0
        f, kappa = term_force(kind[e], coef[e, 0], coef[e, 1], coef[e, 2], piece[e], rel_x, delta, u[e], h)
        term[e] = f
        size = abs(f) + kappa * (abs(rel_x) + abs(delta) + abs(u[e]))  # f and what it cancelled
        grad[i] += f
        scale[i] += size
        if j != GROUND:
            grad[j] -= f
            scale[j] += size
        constraint = is_constraint(kind[e], piece[e])
        if degree is not None and constraint:
            jj = n if j == GROUND else j
            degree[i] += 1
            links[i] ^= e
            degree[jj] += 1
            links[jj] ^= e
        if a is not None and not constraint and kappa != 0.0:
            ci = cluster[i]
            cj = -1 if j == GROUND else cluster[j]
            if ci == cj:
                continue  # both ends move together (or stay): no curvature along any direction
            if ci >= 0 and cj >= 0:
                w = abs(ci - cj)
                band = max(band, w)
                if w <= width:
                    a[ci, 0] += kappa
                    a[cj, 0] += kappa
                    a[max(ci, cj), w] -= kappa
            elif ci >= 0:
                a[ci, 0] += kappa
                anchor[ci] += kappa
            else:
                a[cj, 0] += kappa
                anchor[cj] += kappa
    return band


@kernel
def _factor(a, band, first_row, anchor):
    """In-place banded LDL^T of the clusters' matrix H (a[c, 0] = D_c, a[c, t] = L[c, c - t] on return), from
    row ``first_row`` on (the rows above are factored). Returns the first cluster whose pivot vanishes (-1:
    none): the matrix is singular there (a floppy cluster: no mass and no stiffness to anything held); its
    pivot is left unset.

    H is a graph Laplacian of the elements' stiffnesses (off the diagonal -kappa <= 0) plus its anchors (each
    cluster's own inertia and elements to held nodes: the row sums). Its pivots are computed without a single
    subtraction (Grassmann, Taksar and Heyman's elimination for M-matrices): eliminating cluster k keeps every
    off-diagonal entry <= 0 and adds |H[m, k]| s_k / D_k to the row sum s_m of each cluster m it touches, and
    D_k = s_k + sum of |H[m, k]| over the clusters not yet eliminated. The diagonal as assembled (a sum that
    rounds a soft spring beside a stiff one away) is never read: a pivot is exact to a few roundings whatever
    the stiffnesses' contrast (a ground spring of 1e-20 beside a spring of 1 keeps its 1e-20), and it is 0
    only where a cluster truly has nothing to hold it. ``anchor`` holds the row sums as they are eliminated.
    """
    count = a.shape[0]
    for k in range(first_row, count):
        last = min(count, k + band + 1)
        pivot = anchor[k]
        for m in range(k + 1, last):
            pivot -= a[m, m - k]  # (<= 0: a sum of magnitudes)
        if not pivot > 0.0:
            return k
        a[k, 0] = pivot
        for m in range(k + 1, last):
            coupling = a[m, m - k]
            if coupling == 0.0:
                continue
            anchor[m] -= coupling * (anchor[k] / pivot)
            for c in range(m + 1, last):  # the Schur complement's couplings grow in magnitude only
                a[c, c - m] -= a[c, c - k] * (coupling / pivot)
        for m in range(k + 1, last):
            a[m, m - k] /= pivot
    return -1


@kernel
def _solve(a, band, rhs):
    """Solve L D L^T q = rhs in place."""
    count = a.shape[0]
    for c in range(count):
        for m in range(max(0, c - band), c):
            rhs[c] -= a[c, c - m] * rhs[m]
    for c in range(count):
        rhs[c] /= a[c, 0]
    for c in range(count - 1, -1, -1):
        for r in range(c + 1, min(count, c + band + 1)):
            rhs[c] -= a[r, r - c] * rhs[r]
    return rhs


@kernel
def _null_vector(a, band, singular):
    """A vector z with z_singular = 1 and H z = 0 on the clusters up to ``singular`` (L^T z = 0 above it)."""
    z = np.zeros(a.shape[0])
    z[singular] = 1.0
    for c in range(singular - 1, -1, -1):
        s = 0.0
        for r in range(c + 1, min(singular + 1, c + band + 1)):
            s -= a[r, r - c] * z[r]
        z[c] = s
    return z


@inline_kernel
def _room(kd, eta, r, p, delta, u_e, rate):
    """How far (in units of the direction) an element of kind kd on piece p may move its relative increment
    delta at ``rate`` before it meets a kink of its piece; inf if never. Constraints and smooth elements never
    block. A branch's eta and r = 1 / (1 + h k / c)."""
    if rate == 0.0:
        return np.inf
    if kd == SLIDER:
        if p == 0:
            return np.inf
        if p * rate < 0.0:  # slipping towards delta = 0
            return max(0.0, -delta / rate)
        return np.inf
    if kd != BRANCH or abs(p) == KINK:
        return np.inf
    y = r * (u_e + delta)  # the elongation this increment gives, unclipped
    slope = r * rate
    if p == ELASTIC:
        bound = eta if slope > 0.0 else -eta
        return max(0.0, (bound - y) / slope)
    if p * slope < 0.0:  # clipped, going back towards the elastic range
        bound = eta if p > 0 else -eta
        return max(0.0, (bound - y) / slope)
    return np.inf


@kernel
def _multipliers(model, piece, grad, queue, degree, links, subtree, term, scale, held_node, single):
    """The force each constraint carries, from the equilibrium of each cluster's tree of constraints: term[e]
    (the piece's force) is increased by the multiplier, so that term[e] is then the whole force the
    constraint carries. grad: the nodes' residual forces at a minimiser of the working set.

    Each constraint's force is final once its leaf is peeled: it is then released where it is beyond what
    lets it stay (:func:`_release`), or, with ``single``, only the one furthest beyond (the first in the
    elements' order among equals). Returns the number released. (A constraint between two roots, the ground
    and the held node, is never peeled: its force is not determined, and it stays.)

    The trees are peeled from their leaves: a leaf's one constraint balances the leaf's residual and passes it
    on. A node's remaining constraint is found as the XOR of the ids of its constraints (``links``): O(n + E),
    no adjacency lists (``degree`` and ``links`` come from :func:`_gradient`'s pass). The ground (node n) and the
    held node are never peeled: they take what is left."""
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    for a in range(n + 1):
        subtree[a] = grad[a] if a < n else 0.0
    released = 0
    best = -1
    worst = 0.0
    size = 0
    for a in range(n):
        if degree[a] == 1 and a != held_node:
            queue[size] = a
            size += 1
    head = 0
    while head < size:
        a = queue[head]
        head += 1
        if degree[a] != 1:  # the last node of a free tree (degree 0): its balance holds by the solve
            continue
        e = links[a]
        i, j = ends[e, 0], ends[e, 1]
        jj = n if j == GROUND else j
        # the multiplier mu enters grad_i as +mu and grad_j as -mu; the leaf's balance is subtree + (+-mu) = 0
        if i == a:
            term[e] -= subtree[a]
            other = jj
        else:
            term[e] += subtree[a]
            other = i
        subtree[other] += subtree[a]
        degree[a] = 0
        links[other] ^= e
        degree[other] -= 1
        if degree[other] == 1 and other != n and other != held_node:
            queue[size] = other
            size += 1
        if single:
            excess = _excess(kind, coef, piece, term, scale, ends, e)
            if excess > worst or (excess == worst and excess > 0.0 and e < best):
                worst = excess
                best = e
        elif _release(kind, coef, piece, term, scale, ends, e):
            released += 1
    if single and best >= 0:
        _release(kind, coef, piece, term, scale, ends, best)
        released = 1
    return released


@kernel
def _release(kind, coef, piece, term, scale, ends, e):
    """Whether constraint e, carrying the force term[e], is to be released (and then releases it)."""
    i, j = ends[e, 0], ends[e, 1]
    tolerance = ROUNDING * (scale[i] + (0.0 if j == GROUND else scale[j]))
    f = term[e]
    if kind[e] == SLIDER:
        alpha = coef[e, 0]
        if f > alpha + tolerance:
            piece[e] = 1
            return True
        if f < -alpha - tolerance:
            piece[e] = -1
            return True
        return False
    limit = coef[e, 0] * coef[e, 1]  # k eta
    side = 1 if piece[e] > 0 else -1
    excess = side * f - limit  # > 0: the branch is pulled beyond its kink: it slips; < 0: back to elastic
    if excess > tolerance:
        piece[e] = side
        return True
    if excess < -tolerance:
        piece[e] = ELASTIC
        return True
    return False


@kernel
def _line_search(model, x, u, piece, d, p, h, force, v, top):
    """The minimiser of J(d + tau p) over tau in [0, top] (J smooth and convex there: the pieces hold),
    by safeguarded Newton on its derivative, to rounding (a slope within the rounding of its own terms is
    zero); ``top`` may be inf. Returns NaN if the derivative is not finite."""
    lo, hi = 0.0, top
    tau = 1.0 if top >= 1.0 else top
    best, least = 0.0, np.inf
    width = np.inf  # the bracket's width two iterations ago
    last_width = np.inf
    for _ in range(LINE_SEARCH_LIMIT):
        slope, curvature, size = _directional(model, x, u, piece, d, p, h, force, v, tau)
        if not (abs(slope) < np.inf and abs(curvature) < np.inf):
            return np.nan
        if abs(slope) <= ROUNDING * size:
            return tau
        if abs(slope) < least:
            best, least = tau, abs(slope)
        if slope > 0.0:
            hi = tau
        else:
            lo = tau
            if tau == top:
                return tau
        newton = tau - slope / curvature if curvature > 0.0 else np.nan
        if hi == np.inf:
            # no upper bound yet: three Newton steps at once (a root of a cubic spring at rest is triple, where
            # Newton goes a third of the way; past a simple root this gives the bound)
            step = tau + 3.0 * (newton - tau) if newton > tau else 2.0 * tau + 1.0
        else:
            # Newton inside the bracket while the bracket halves every two iterations; bisection otherwise
            step = newton
            if not (step > lo and step < hi) or hi - lo > 0.5 * width:
                step = 0.5 * (lo + hi)
            if hi - lo <= 4.0 * np.finfo(np.float64).eps * max(abs(hi), 1.0):
                return step
            width, last_width = last_width, hi - lo
        if step == tau:
            return step
        tau = step
    return best  # the budget ran out: the point of least slope seen


@kernel
def _directional(model, x, u, piece, d, p, h, force, v, tau):
    """(dJ/dtau, d2J/dtau2, the sum of the magnitudes of the slope's terms) at d + tau p."""
    mass, kind, ends, coef, load_node, has_cubic = model
    slope = 0.0
    curvature = 0.0
    size = 0.0
    for j in range(mass.shape[0]):
        if p[j] != 0.0:
            term = mass[j] / (h * h) * (d[j] + tau * p[j] - h * v[j]) * p[j]
            slope += term
            size += abs(term)
            curvature += mass[j] / (h * h) * p[j] * p[j]
    slope -= force * p[load_node]
    size += abs(force * p[load_node])
    for e in range(kind.shape[0]):
        rate = _relative(ends, p, e)
        if rate == 0.0:
            continue
        i, j = ends[e, 0], ends[e, 1]
        rel_x = x[i] if j == GROUND else x[i] - x[j]
        delta = (d[i] if j == GROUND else d[i] - d[j]) + tau * rate
        f, kappa = term_force(kind[e], coef[e, 0], coef[e, 1], coef[e, 2], piece[e], rel_x, delta, u[e], h)
        slope += f * rate
        size += abs(f * rate)
        curvature += kappa * rate * rate
    return slope, curvature, size


@inline_kernel  # thin: a kernel of its own would optimise the active-set method again (_jit.inline_kernel)
def solve_step(model, x, v, u, piece, h, force, fixed_node, fixed_increment, work, chain_work=None):
    """The increment d (work[0]) of one implicit step and the force each element carries (work[5]); the
    pieces are updated in place. ``fixed_node`` >= 0: that node's increment is imposed (the connector).
    Returns the number of iterations taken, or -1 when the budget ran out, -2 when no equilibrium exists
    (a floppy part of the network is pushed with nothing to stop it), -3 on a non-finite number. A massless
    chain takes its O(n) programme (``chain.py``), every other network (or a chain past that programme's
    budget) the active-set method. ``chain_work``: the arrays the chain's programme works in
    (``chain.scratch``; None: allocated by it). The kernels here always hand it: one compiled solve_step, not a
    second for an omitted argument."""
    status = chain_step(model, x, piece, force, fixed_node, work[0], work[5], chain_work)
    if status != -1:
        return status
    return active_set_step(model, x, v, u, piece, h, force, fixed_node, fixed_increment, work)


@kernel
def active_set_step(model, x, v, u, piece, h, force, fixed_node, fixed_increment, work):
    """:func:`solve_step` by the active-set method of the module docstring, for every network."""
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    elements = kind.shape[0]
    d, grad, p, parent, cluster, term, subtree, queue, degree, links, scale = work
    for j in range(n):
        d[j] = 0.0
    if fixed_node >= 0:
        d[fixed_node] = fixed_increment
    _start_pieces(model, x, u, piece, d, h)
    budget = search_budget(n, elements)
    width = np.int64(1)  # the half bandwidth of the clusters' matrix allocated (grown when a working set needs more)
    room = np.empty(elements)  # how far each element may move along the direction (np.inf: unbounded)
    moving = np.empty(elements, np.int64)  # the elements the direction moves (their force changes)
    single = np.bool_(False)  # release one constraint at a time (after a release of several met a kink at once)
    released_many = False
    last_correction = np.inf  # the largest of Newton's last corrections (cubic springs)
    for iteration in range(budget):
        count = _clusters(n, kind, ends, piece, parent, cluster, fixed_node)
        while True:  # the gradient and the clusters' matrix in one pass (again, wider, if the band grew)
            a = np.zeros((count, width + 1))
            anchor = np.zeros(count)
            band = _gradient(model, x, v, u, piece, d, h, force, grad, term, scale, cluster, a, anchor, degree,
                             links, np.bool_(False))
            if band <= width:
                break
            width = band
        band = width
        rhs = np.zeros(count)
        for j in range(n):
            if not abs(grad[j]) < np.inf:
                return -3
            if cluster[j] >= 0:
                rhs[cluster[j]] -= grad[j]
        balanced = True  # every free cluster's forces balance to their rounding (Newton's test, cubic springs)
        if has_cubic:
            size = np.zeros(count)
            for j in range(n):
                if cluster[j] >= 0:
                    size[cluster[j]] += scale[j]
            for c in range(count):
                if abs(rhs[c]) > ROUNDING * size[c]:
                    balanced = False
        top = 1.0
        row = np.int64(0)
        while True:
            singular = _factor(a, band, row, anchor)
            if singular < 0:
                break
            # a floppy cluster (no mass, no stiffness along z): J is linear along the null vector z
            z = _null_vector(a, band, singular)
            slope = 0.0
            size = 0.0
            for j in range(n):
                if cluster[j] >= 0:
                    slope += grad[j] * z[cluster[j]]
                    size += scale[j] * abs(z[cluster[j]])
            if abs(slope) > ROUNDING * size:  # descend along z until a kink stops it (or nothing does)
                sign = -1.0 if slope > 0.0 else 1.0
                for j in range(n):
                    p[j] = sign * z[cluster[j]] if cluster[j] >= 0 else 0.0
                top = np.inf
                break
            a[singular, 0] = 1.0  # balanced along z: no move along it (the forward solve gives 0 there)
            row = singular + 1
        if top == 1.0:
            q = _solve(a, band, rhs)
            for j in range(n):
                p[j] = q[cluster[j]] if cluster[j] >= 0 else 0.0
        converged = False
        if has_cubic and top == 1.0:
            # Newton has converged when the forces balance to their rounding, or when its step no longer
            # changes anything: below a few ulps of the increment, or, at a massless node, below the rounding
            # of its position (a massless node held by a cubic spring at rest: a triple root, where the force
            # vanishes faster than the position can be resolved); or when its corrections have stopped
            # shrinking at the rounding of the step as a whole (the coupled solve's: a node with a mass that
            # nearly stops while the rest moves fast, on a joint with a cubic spring at 5 m, moved 1.8e-9 m in a
            # step, and Newton's corrections there, 1e-19 m, came and went with the rounding of the others'
            # forces: the search ran out of its budget)
            converged = balanced
            if not converged:
                converged = True
                for j in range(n):
                    if abs(p[j]) <= 4.0 * np.finfo(np.float64).eps * abs(d[j]):
                        continue
                    if not mass[j] > 0.0 and abs(p[j]) <= ROUNDING * (abs(x[j]) + abs(d[j])):
                        continue
                    converged = False
                    break
            if not converged:
                largest_p = 0.0
                largest_d = 0.0
                for j in range(n):
                    largest_p = max(largest_p, abs(p[j]))
                    largest_d = max(largest_d, abs(d[j]))
                converged = largest_p <= ROUNDING * largest_d and largest_p >= last_correction
                last_correction = largest_p
        # the farthest the move may go: to the working set's minimiser (tau = 1), or, along a floppy direction
        # or a cubic spring's Newton direction (searched exactly: it may go past 1, where Newton falls short
        # of a triple root), as far as no kink stops it
        tau = 0.0 if converged else (np.inf if has_cubic else top)
        blocker = -1
        count_moving = np.int64(0)
        for e in range(elements if not converged else 0):
            kd = kind[e]
            room[e] = np.inf
            i, j = ends[e, 0], ends[e, 1]
            if j == GROUND:
                rate, delta = p[i], d[i]
            else:
                rate, delta = p[i] - p[j], d[i] - d[j]
            if rate == 0.0:
                continue
            moving[count_moving] = e
            count_moving += 1
            if kd != SLIDER and kd != BRANCH:
                continue
            r = 1.0
            if kd == BRANCH and coef[e, 2] > 0.0:
                r = 1.0 / (1.0 + h * coef[e, 0] / coef[e, 2])
            room[e] = _room(kd, coef[e, 1], r, piece[e], delta, u[e], rate)
            if room[e] < tau:
                tau = room[e]
                blocker = e
        if tau == np.inf and top == np.inf:  # a floppy direction no kink stops: only a cubic spring it stretches
            bounded = False
            for e in range(elements if has_cubic else 0):
                if kind[e] == CUBIC and coef[e, 0] > 0.0:
                    i, j = ends[e, 0], ends[e, 1]
                    rate = p[i] if j == GROUND else p[i] - p[j]
                    size = abs(p[i]) + (0.0 if j == GROUND else abs(p[j]))
                    if abs(rate) > ROUNDING * size:  # (a rigid motion's rate is 0 but for rounding)
                        bounded = True
            if not bounded:
                return -2
        step_taken = tau
        if has_cubic and not converged:
            step_taken = _line_search(model, x, u, piece, d, p, h, force, v, tau)
            if not step_taken < np.inf:
                return -2 if step_taken == np.inf else -3
            if step_taken < tau:
                blocker = -1
        # the move ends at the working set's minimiser, where the constraints' forces are read: the forces change
        # only at the elements and nodes that move, so where those are few (a large network that mostly sticks)
        # they are updated there, else recomputed in one pass over every element
        update = blocker < 0 and not (has_cubic and not converged) and step_taken != 0.0
        if update and 4 * count_moving <= elements:
            _moved(model, x, v, u, piece, d, p, step_taken, h, grad, term, scale, moving, count_moving)
            update = False
        for j in range(n):
            d[j] += step_taken * p[j]
        if update:
            _gradient(model, x, v, u, piece, d, h, force, grad, term, scale, cluster, None, None, None, None,
                      np.bool_(False))
        if blocker >= 0:
            if step_taken == 0.0 and released_many:
                single = True
            released_many = False
            # every element that meets its kink at this same tau joins the working set (at a load reversal a
            # whole slip front sticks at once), unless the constraints joined so far already tie its ends (a
            # loop of constraints would be redundant): parent is the union-find of the working set
            for e in range(elements):
                if room[e] != tau or (e != blocker and step_taken != tau):
                    continue
                i, j = ends[e, 0], ends[e, 1]
                ra = _find(parent, i)
                rb = _find(parent, n if j == GROUND else j)
                if ra == rb:
                    continue
                if ra == n or rb == n:
                    parent[min(ra, rb)] = n
                else:
                    parent[max(ra, rb)] = min(ra, rb)
                if kind[e] == SLIDER:
                    piece[e] = STUCK
                else:  # the kink it moved onto: the side its motion goes (eta = 0: both kinks are at 0)
                    rate = p[i] if j == GROUND else p[i] - p[j]
                    if piece[e] == ELASTIC:
                        piece[e] = KINK if rate > 0.0 else -KINK
                    else:  # clipped, coming back: the kink of its side
                        piece[e] = KINK if piece[e] > 0 else -KINK
            continue
        released_many = False
        if has_cubic and not converged:
            continue
        # a minimiser of the working set: the constraints' forces decide (grad, term and scale are those of d
        # now, degree and links those of the working set: from this iteration's pass and the move's update)
        released = _multipliers(model, piece, grad, queue, degree, links, subtree, term, scale, fixed_node, single)
        if released == 0:
            return iteration + 1
        released_many = released > 1
    return -1


@kernel
def _moved(model, x, v, u, piece, d, p, step, h, grad, term, scale, moving, count):
    """grad, term and scale (as :func:`_gradient` computes them at d) brought to d + step p: the inertia of every
    node that moves and the force of each of the ``count`` elements in ``moving`` (those the direction p moves;
    the others' forces do not change), each recomputed at the new point and its change added at its ends."""
    mass, kind, ends, coef, load_node, has_cubic = model
    for q in range(count):
        e = moving[q]
        i, j = ends[e, 0], ends[e, 1]
        if j == GROUND:
            rel_x, delta = x[i], d[i]
            rate = p[i]
        else:
            rel_x, delta = x[i] - x[j], d[i] - d[j]
            rate = p[i] - p[j]
        f0, kappa0 = term_force(kind[e], coef[e, 0], coef[e, 1], coef[e, 2], piece[e], rel_x, delta, u[e], h)
        new = delta + step * rate
        f1, kappa1 = term_force(kind[e], coef[e, 0], coef[e, 1], coef[e, 2], piece[e], rel_x, new, u[e], h)
        term[e] = f1
        change = (abs(f1) + kappa1 * (abs(rel_x) + abs(new) + abs(u[e]))) - (
            abs(f0) + kappa0 * (abs(rel_x) + abs(delta) + abs(u[e])))
        grad[i] += f1 - f0
        scale[i] += change
        if j != GROUND:
            grad[j] -= f1 - f0
            scale[j] += change
    for j in range(mass.shape[0]):
        if p[j] != 0.0 and mass[j] > 0.0:
            inertia = mass[j] / (h * h)
            new = d[j] + step * p[j]
            grad[j] += inertia * (new - h * v[j]) - inertia * (d[j] - h * v[j])
            scale[j] += inertia * ((abs(new) + abs(h * v[j])) - (abs(d[j]) + abs(h * v[j])))


@kernel
def _excess(kind, coef, piece, term, scale, ends, e):
    """How far constraint e's force is beyond what lets it stay (0 if it may stay)."""
    i, j = ends[e, 0], ends[e, 1]
    tolerance = ROUNDING * (scale[i] + (0.0 if j == GROUND else scale[j]))
    f = term[e]
    if kind[e] == SLIDER:
        return max(0.0, abs(f) - coef[e, 0] - tolerance)
    side = 1 if piece[e] > 0 else -1
    return max(0.0, abs(side * f - coef[e, 0] * coef[e, 1]) - tolerance)


@kernel
def settle(model, x, v, u, piece, h, force, fixed_node, work):
    """The new positions of a solved step, settled where the increment's rounding swamps them: True when
    they are (then in work[2], d and the elements' forces in work[0] and work[5] brought to them), False
    (nothing changed) in every other step.

    The step is solved for the increments d, exact to their rounding, ulp(x): nothing while the new
    positions are of the order of the old ones. A node that falls by decades in one step (a load of 1e17 N
    released, a spring made 1e20 times stiffer) may land anywhere within ulp(x) of its place: 1e17 + d gave
    0 where the answer is 3 (:func:`prandtl_fmu.kernels.increment.settle` is the element's cure of the same).
    So when a node's new position is below FALLEN of its old one (where that rounding can reach SETTLED of it;
    a node that crosses 0 in a dynamic run is not checked, at no cost), the step's equations are evaluated at
    the new positions themselves (:func:`_gradient` with ``at_end``) on the step's final pieces; where a node
    misses its root by more than SETTLED of itself, Newton's corrections on the free clusters (the step's own
    linear algebra) bring every free node to the root: one correction for the linear
    pieces, Newton's convergence with cubic springs, at most SETTLE_ITERATIONS. The constraints' forces are
    then read again (the reaction). The pieces are kept: a correction is of the order of ulp(x) and moves no
    element over a kink but one within that rounding of it. The positions are kept as they are where the
    clusters' matrix is singular there (a cubic spring at rest alone)."""
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    d, grad, x1, parent, cluster, term, subtree, queue, degree, links, scale = work
    fell = False
    for j in range(n):
        x1[j] = x[j] + d[j]
        if abs(x1[j]) < FALLEN * abs(x[j]):
            fell = True
    if not fell:
        return False
    count = _clusters(n, kind, ends, piece, parent, cluster, fixed_node)
    band = np.int64(0)  # (not the constant 0: a literal argument compiles _factor again)
    for e in range(kind.shape[0]):
        j = ends[e, 1]
        if j != GROUND and not is_constraint(kind[e], piece[e]) and cluster[ends[e, 0]] >= 0 and cluster[j] >= 0:
            band = max(band, abs(cluster[ends[e, 0]] - cluster[j]))
    trial = np.empty(kind.shape[0])  # the elements' forces while settling (term keeps the solve's until then)
    for iteration in range(SETTLE_ITERATIONS):
        a = np.zeros((count, band + 1))
        anchor = np.zeros(count)
        _gradient(model, x1, v, u, piece, d, h, force, grad, trial, scale, cluster, a, anchor, None, None,
                  np.bool_(True))
        rhs = np.zeros(count)
        size = np.zeros(count)
        for j in range(n):
            if cluster[j] >= 0:
                rhs[cluster[j]] -= grad[j]
                size[cluster[j]] += scale[j]
        balanced = True
        for c in range(count):
            if not abs(rhs[c]) <= ROUNDING * size[c]:
                balanced = False
        if balanced and iteration == 0:
            return False  # at the root already: kept, bit for bit
        if balanced or _factor(a, band, np.int64(0), anchor) >= 0:
            break
        q = _solve(a, band, rhs)
        finite = True
        for c in range(count):
            if not abs(q[c]) < np.inf:
                finite = False
        if not finite:
            break
        if iteration == 0:
            near = True  # every node within SETTLED of itself from the root: kept, bit for bit
            for j in range(n):
                if cluster[j] >= 0 and not abs(q[cluster[j]]) <= SETTLED * abs(x1[j]):
                    near = False
            if near:
                return False
        moved = False
        for j in range(n):
            if cluster[j] >= 0:
                correction = q[cluster[j]]
                if x1[j] + correction != x1[j]:
                    moved = True
                x1[j] += correction
                d[j] += correction
        if not moved:
            break
    _gradient(model, x1, v, u, piece, d, h, force, grad, term, scale, cluster, None, None, degree, links,
              np.bool_(True))
    _multipliers(model, piece.copy(), grad, queue, degree, links, subtree, term, scale, fixed_node, np.bool_(False))
    return True


@kernel
def commit(model, x, v, u, piece, h, force, fixed_node, work, energy, dissipated):
    """Apply the increment found by :func:`solve_step`: x, v, the branches' elongations (the new positions
    settled where the increment's rounding swamps them: :func:`settle`; ``fixed_node`` the node whose motion
    was imposed, or NO_NODE); book the energy (``energy`` = [work of the load, dissipated by sliders, by
    dashpots], or None) and each element's dissipation (``dissipated``, or None). Returns the reaction on the
    ground."""
    mass, kind, ends, coef, load_node, has_cubic = model
    settled = settle(model, x, v, u, piece, h, force, fixed_node, work)
    d = work[0]
    term = work[5]
    reaction = 0.0
    for e in range(kind.shape[0]):
        delta = _relative(ends, d, e)
        kd = kind[e]
        loss = 0.0
        slip = 0.0
        if kd == DASHPOT:
            loss = coef[e, 0] * delta * delta / h
        elif kd == SLIDER:
            if piece[e] != STUCK:
                slip = coef[e, 0] * abs(delta)
        elif kd == BRANCH:
            r = _ratio(coef, e, h)
            eta = coef[e, 1]
            if piece[e] == ELASTIC:
                u1 = r * (u[e] + delta)
            else:
                u1 = eta if piece[e] > 0 else -eta
                slip = coef[e, 0] * eta * abs(u[e] + delta - u1 / r)
            if coef[e, 2] > 0.0:
                loss = h * coef[e, 0] * coef[e, 0] * u1 * u1 / coef[e, 2]
            u[e] = u1
        if energy is not None:
            energy[1] += slip
            energy[2] += loss
        if dissipated is not None:
            dissipated[e] += slip + loss
        if ends[e, 1] == GROUND:
            reaction += term[e]
    if energy is not None:
        energy[0] += force * d[load_node]
    settled_x = work[2]
    for j in range(mass.shape[0]):
        x[j] = settled_x[j] if settled else x[j] + d[j]
        v[j] = d[j] / h
    return reaction


@inline_kernel  # thin: a kernel of its own would optimise the active-set method again (_jit.inline_kernel)
def implicit_step(model, load, t, h, x, v, u, piece, work, energy, dissipated, chain_work=None):
    """One implicit step from t to t + h (the load at t + h). Returns (status, reaction): status the
    iterations taken, or < 0 when the step could not be taken (see :func:`solve_step`; the state is then
    unchanged but for the pieces)."""
    force = force_at(load, t + h)
    force = with_noise(load, force, force + impulse(load, t, h) / h)  # a white noise: the step's mean force
    status = solve_step(model, x, v, u, piece, h, force, NO_NODE, 0.0, work, chain_work)
    if status < 0:
        return status, np.nan
    return status, commit(model, x, v, u, piece, h, force, NO_NODE, work, energy, dissipated)


@kernel
def forces_now(model, x, v, u, term):
    """term[e] = the force of every element that is not a slider in the state (x, v, u), a dashpot at the
    velocities v (the projected scheme's forces); returns the reaction of those on the ground."""
    mass, kind, ends, coef, load_node, has_cubic = model
    reaction = 0.0
    for e in range(kind.shape[0]):
        kd = kind[e]
        a = coef[e, 0]
        if kd == SPRING:
            f = a * _relative_x(ends, x, e)
        elif kd == CUBIC:
            y = _relative_x(ends, x, e)
            f = a * y * y * y
        elif kd == DASHPOT:
            f = a * _relative(ends, v, e)
        elif kd == BRANCH:
            f = a * u[e]
        else:
            f = 0.0
        term[e] = f
        if ends[e, 1] == GROUND:
            reaction += f
    return reaction


@kernel
def projected_step(model, load, t, h, x, v, u, piece, work, energy, dissipated, chain_work=None):
    """One step of the paper's scheme (every force at t, the load at t): see the module's docstring.
    Every node has a mass and there is no slider (the driver checks). (``chain_work``: the time loop's, unused
    here.)"""
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    force = force_at(load, t)
    force = with_noise(load, force, force + impulse(load, t, h) / h)  # a white noise: the step's mean force
    grad = work[1]
    term = work[5]
    forces_now(model, x, v, u, term)
    for j in range(n):
        grad[j] = 0.0
    grad[load_node] = force
    for e in range(kind.shape[0]):
        grad[ends[e, 0]] -= term[e]
        if ends[e, 1] != GROUND:
            grad[ends[e, 1]] += term[e]
    for e in range(kind.shape[0]):
        kd = kind[e]
        if kd == BRANCH:
            a = coef[e, 0]
            eta = coef[e, 1]
            rate = _relative(ends, v, e)
            relax = h * a * u[e] / coef[e, 2] if coef[e, 2] > 0.0 else 0.0
            y = u[e] + h * rate - relax
            u1 = min(max(y, -eta), eta)
            slip = a * eta * abs(y - u1) if u1 != y else 0.0
            loss = relax * a * u[e]
            if energy is not None:
                energy[1] += slip
                energy[2] += loss
            if dissipated is not None:
                dissipated[e] += slip + loss
            u[e] = u1
        elif kd == DASHPOT:
            rate = _relative(ends, v, e)
            if energy is not None:
                energy[2] += coef[e, 0] * rate * rate * h
            if dissipated is not None:
                dissipated[e] += coef[e, 0] * rate * rate * h
    if energy is not None:
        energy[0] += force * h * v[load_node]
    for j in range(n):
        x[j] += h * v[j]
        v[j] += h * grad[j] / mass[j]
    return 0, forces_now(model, x, v, u, term)


@kernel
def kinetic(mass, v):
    total = 0.0
    for j in range(mass.shape[0]):
        total += 0.5 * mass[j] * v[j] * v[j]
    return total


@kernel
def stored(model, x, u):
    """The energy in the springs, cubic springs and branches (J)."""
    mass, kind, ends, coef, load_node, has_cubic = model
    total = 0.0
    for e in range(kind.shape[0]):
        kd = kind[e]
        if kd == SPRING:
            y = _relative_x(ends, x, e)
            total += 0.5 * coef[e, 0] * y * y
        elif kd == CUBIC:
            y = _relative_x(ends, x, e)
            total += 0.25 * coef[e, 0] * y * y * y * y
        elif kd == BRANCH:
            total += 0.5 * coef[e, 0] * u[e] * u[e]
    return total


@kernel
def write_row(model, load, time, x, v, u, reaction, row, energy, energy_row, u_row):
    """One output row: x and v of every node, F, the reaction; the energy columns (kinetic, stored, work,
    sliders, dashpots) and the elongations where asked (not None, and not an array with no entry)."""
    n = x.shape[0]
    for j in range(n):
        row[2 * j] = x[j]
        row[2 * j + 1] = v[j]
    row[2 * n] = force_at(load, time)
    row[2 * n + 1] = reaction
    if energy_row is not None:
        if energy is not None:
            if energy_row.shape[0] > 0:  # none: not asked for (network.driver.run_loop)
                mass = model[0]
                energy_row[0] = kinetic(mass, v)
                energy_row[1] = stored(model, x, u)
                energy_row[2] = energy[0]
                energy_row[3] = energy[1]
                energy_row[4] = energy[2]
    if u_row is not None:
        if u_row.shape[0] > 0:
            kind = model[1]
            m = 0
            for e in range(kind.shape[0]):
                if kind[e] == BRANCH:
                    u_row[m] = u[e]
                    m += 1


def _time_loop(step):
    def loop(model, load, x, v, u, piece, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy,
             dissipated, out_dissipated, work):
        """``out.shape[0] * steps_per_row`` steps of ``step`` from step number first_step (t_p = t_base + p h,
        from p alone); row j of ``out`` (and of out_u, out_energy, out_dissipated where not None nor without
        columns: ``network.driver.run_loop``) after every ``steps_per_row`` steps. Returns (steps taken, status of
        the last step): fewer steps than asked when a step failed (status < 0; the state is the one before that
        step)."""
        p = 0
        status = 0
        chain_work = chain_scratch(x.shape[0])  # once per run of steps (chain.py: a massless chain's own step)
        for j in range(out.shape[0]):
            reaction = 0.0
            for _ in range(steps_per_row):
                status, reaction = step(model, load, t_base + (first_step + p) * h, h, x, v, u, piece, work,
                                        energy, dissipated, chain_work)
                if status < 0:
                    return p, status
                p += 1
            write_row(model, load, t_base + (first_step + p) * h, x, v, u, reaction, out[j], energy,
                      None if out_energy is None else out_energy[j], None if out_u is None else out_u[j])
            if out_dissipated is not None:
                if dissipated is not None:
                    for e in range(out_dissipated.shape[1]):  # not [j, :] = (libm's log10 in the shape check)
                        out_dissipated[j, e] = dissipated[e]
        return p, status

    loop.__qualname__ = f"network_loop_{step.__name__}"  # unique: see kernels/loop.py
    return generic_kernel(loop)


_implicit_loop = _time_loop(implicit_step)
_projected_loop = _time_loop(projected_step)


@kernel
def run_implicit(model, load, x, v, u, piece, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy,
                 dissipated, out_dissipated, work):
    """The implicit time loop (see _time_loop), cached."""
    return _implicit_loop(model, load, x, v, u, piece, t_base, first_step, h, steps_per_row, out, out_u, energy,
                          out_energy, dissipated, out_dissipated, work)


@kernel
def run_projected(model, load, x, v, u, piece, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy,
                  dissipated, out_dissipated, work):
    """The projected time loop (see _time_loop), cached."""
    return _projected_loop(model, load, x, v, u, piece, t_base, first_step, h, steps_per_row, out, out_u, energy,
                           out_energy, dissipated, out_dissipated, work)


@kernel
def move_node(model, x, v, u, piece, work, energy, dissipated, node, target, whole, h, rest):
    """The connector's motion: node ``node`` moves along the line from its x to ``target`` over ``whole``
    implicit steps of h and a last one of ``rest`` (if > 0), the rest of the network responding. Returns
    (status, steps taken): status < 0 (see :func:`solve_step`) when a step could not be taken."""
    start = x[node]
    total = whole * h + rest
    done = 0.0
    count = whole + (1 if rest > 0.0 else 0)
    chain_work = chain_scratch(x.shape[0])
    for p in range(count):
        size = h if p < whole else rest
        done += size
        there = target if p == count - 1 else start + (target - start) * (done / total)
        status = solve_step(model, x, v, u, piece, size, 0.0, node, there - x[node], work, chain_work)
        if status < 0:
            return status, p
        commit(model, x, v, u, piece, size, 0.0, node, work, energy, dissipated)
        if energy is not None:  # the work of what imposes the motion: its force (at t + h) times the move
            energy[0] += node_force(model, work[5], node) * work[0][node]
    return 0, count


@kernel
def node_force(model, term, node):
    """The force the elements exert on ``node`` against its motion (what holds it there): the connector's
    output."""
    mass, kind, ends, coef, load_node, has_cubic = model
    total = 0.0
    for e in range(kind.shape[0]):
        if ends[e, 0] == node:
            total += term[e]
        elif ends[e, 1] == node:
            total -= term[e]
    return total


# ------------------------------------------------------------------ t = 0

@kernel
def instant_model(model):
    """The model of an instant (h -> 0), and the number of elements put first: every massive node held (a
    stuck slider of infinite threshold to the ground, listed first), every dashpot with c > 0 rigid (the same;
    c = 0 is no dashpot), no series dashpot relaxing, no mass."""
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    extra = 0
    for j in range(n):
        if mass[j] > 0.0:
            extra += 1
    count = kind.shape[0]
    kind2 = np.empty(extra + count, np.int64)
    ends2 = np.empty((extra + count, 2), np.int64)
    coef2 = np.empty((extra + count, 3))
    e = 0
    for j in range(n):
        if mass[j] > 0.0:
            kind2[e] = SLIDER
            ends2[e, 0], ends2[e, 1] = j, GROUND
            coef2[e, 0], coef2[e, 1], coef2[e, 2] = np.inf, 0.0, 0.0
            e += 1
    for f in range(count):
        kind2[extra + f] = kind[f]
        ends2[extra + f, 0], ends2[extra + f, 1] = ends[f, 0], ends[f, 1]
        coef2[extra + f, 0], coef2[extra + f, 1], coef2[extra + f, 2] = coef[f, 0], coef[f, 1], coef[f, 2]
        if kind[f] == DASHPOT:
            if coef[f, 0] > 0.0:
                kind2[extra + f] = SLIDER
                coef2[extra + f, 0] = np.inf
            else:
                coef2[extra + f, 0] = 0.0
        elif kind[f] == BRANCH:
            coef2[extra + f, 2] = 0.0
    return (np.zeros(n), kind2, ends2, coef2, load_node, has_cubic), extra


@kernel
def initial_state(model, x, v, u, piece, force):
    """The state at t = 0 in place: x, v, u hold the scene's x0, v0, u0, piece zeros; every massless node
    is brought to equilibrium with the force F(0) (an instant: the masses and dashpots do not move, as the
    element's massless start) and gets v = 0. Returns 0, or the status of the equilibrium that failed
    (:func:`solve_step`)."""
    mass = model[0]
    kind = model[1]
    n = mass.shape[0]
    massless = False
    for j in range(n):
        if not mass[j] > 0.0:
            v[j] = 0.0
            massless = True
    for e in range(kind.shape[0]):
        piece[e] = 0
    if not massless:
        return 0
    instant, extra = instant_model(model)
    count = instant[1].shape[0]
    work = workspace(n, count)
    piece2 = np.zeros(count, np.int64)
    u2 = np.zeros(count)
    for e in range(u.shape[0]):  # not u2[extra:] = u, whose shape check formats its message with libm's log10
        u2[extra + e] = u[e]
    status = solve_step(instant, x, np.zeros(n), u2, piece2, 1.0, force, NO_NODE, 0.0, work, chain_scratch(n))
    if status < 0:
        return status
    commit(instant, x, np.zeros(n), u2, piece2, 1.0, force, NO_NODE, work, None, None)
    for e in range(kind.shape[0]):  # the elements keep the pieces they reached; a rigid dashpot is a dashpot
        u[e] = u2[extra + e]
        if kind[e] == SLIDER or kind[e] == BRANCH:
            p = piece2[extra + e]
            piece[e] = p // KINK if abs(p) == KINK else p
    return 0


@kernel
def initial_reaction(model, x, v, u, force):
    """The reaction at t = 0: the elements' forces on the ground in the initial state. What holds a massless
    node (a dashpot's force c v at t = 0+ included: a massless network passes the whole of F(0) to the ground)
    is the instant's equilibrium; a slider of a massive node slips against its velocity, or holds the other
    forces on its node up to alpha."""
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    count = kind.shape[0]
    term = np.zeros(count)
    forces_now(model, x, v, u, term)
    massless = False
    for j in range(n):
        if not mass[j] > 0.0:
            massless = True
    if massless:  # the instant's forces (its solve from the equilibrium initial_state found)
        instant, extra = instant_model(model)
        work = workspace(n, instant[1].shape[0])
        piece = np.zeros(instant[1].shape[0], np.int64)
        u2 = np.zeros(instant[1].shape[0])
        for e in range(u.shape[0]):  # not u2[extra:] = u (libm's log10 in numba's shape check)
            u2[extra + e] = u[e]
        status = solve_step(instant, x.copy(), np.zeros(n), u2, piece, 1.0, force, NO_NODE, 0.0, work,
                            chain_scratch(n))
        if status >= 0:
            held = work[5]
            for e in range(count):
                j = ends[e, 1]
                if not mass[ends[e, 0]] > 0.0 or (j != GROUND and not mass[j] > 0.0):
                    term[e] = held[extra + e]
    net = np.zeros(n)
    net[load_node] += force
    for e in range(count):
        if kind[e] != SLIDER:
            net[ends[e, 0]] -= term[e]
            if ends[e, 1] != GROUND:
                net[ends[e, 1]] += term[e]
    total = 0.0
    for e in range(count):
        if ends[e, 1] != GROUND:
            continue
        i = ends[e, 0]
        if kind[e] == SLIDER and mass[i] > 0.0:
            alpha = coef[e, 0]
            if v[i] != 0.0:
                total += alpha if v[i] > 0.0 else -alpha
            else:
                total += min(max(net[i], -alpha), alpha)
        else:
            total += term[e]
    return total


SAVED_REACTION = 1e-8  # a saved reaction within this of the forces' scale from what the state fixes: its rounding


@kernel
def reaction_fits(model, x, v, u, piece, stepped, reaction):
    """Whether ``reaction``, a saved state's, is one its x, v, u and pieces allow (:func:`reaction_range`)."""
    fixed, free, scale = reaction_range(model, x, v, u, piece, stepped)
    return abs(reaction - fixed) <= free + SAVED_REACTION * scale


@kernel
def reaction_range(model, x, v, u, piece, stepped):
    """``(fixed, free, scale)``: what a state's x, v, u and pieces fix of the reaction, how far from it the
    reaction may lie, and the forces' scale (a restored state's reaction is checked, not trusted: a forged one
    was shown as it was).

    The reaction is the elements' force on the ground. The state fixes that of every element to the ground but
    a stuck slider: a spring's k x_i, a cubic spring's k3 x_i^3, a dashpot's c v_i (v the last step's d / h), a
    branch's k u (u the clipped elongation, at a kink too), a slipping slider's alpha times its direction; a
    stuck slider carries anything within alpha (its node's balance over the last step, which the state does
    not hold). Before any step (``stepped`` False) a dashpot at a massless node was rigid in the instant's
    equilibrium (:func:`initial_reaction`): it may carry anything. A saved reaction fits when it lies within
    the stuck sliders' (and rigid dashpots') range of what is fixed, to SAVED_REACTION of the forces' scale."""
    mass, kind, ends, coef, load_node, has_cubic = model
    fixed = 0.0
    free = 0.0
    scale = 0.0
    for e in range(kind.shape[0]):
        if ends[e, 1] != GROUND:
            continue
        i = ends[e, 0]
        kd = kind[e]
        a = coef[e, 0]
        if kd == SPRING:
            f = a * x[i]
        elif kd == CUBIC:
            f = a * x[i] * x[i] * x[i]
        elif kd == DASHPOT:
            if not stepped and not mass[i] > 0.0:
                free = np.inf
                f = 0.0
            else:
                f = a * v[i]
        elif kd == BRANCH:
            f = a * u[e]
        elif piece[e] == STUCK:
            free += a
            scale += a
            f = 0.0
        else:
            f = a if piece[e] > 0 else -a
        fixed += f
        scale += abs(f)
    return fixed, free, scale


@kernel
def jump_node(model, x, v, u, piece, energy, dissipated, node, target):
    """An instant's move of ``node`` to ``target`` (a connector's sample at the time it already is at): the
    masses do not move and keep their velocities, the dashpots are rigid, no series dashpot relaxes (the
    instant's model, as at t = 0); the massless part follows in equilibrium, sliders and branches slip as
    they must. Returns (status, force): 0 and the force that holds the node, or the status of the equilibrium
    that failed (< 0; nothing changed then) and NaN."""
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    instant, extra = instant_model(model)
    count = instant[1].shape[0]
    work = workspace(n, count)
    piece2 = np.zeros(count, np.int64)
    u2 = np.zeros(count)
    for e in range(u.shape[0]):  # not u2[extra:] = u, whose shape check formats its message with libm's log10
        u2[extra + e] = u[e]
    for e in range(kind.shape[0]):
        piece2[extra + e] = piece[e]
    status = solve_step(instant, x, np.zeros(n), u2, piece2, 1.0, 0.0, node, target - x[node], work, chain_scratch(n))
    if status < 0:
        return status, np.nan
    d = work[0]
    rates = v.copy()
    commit(instant, x, np.zeros(n), u2, piece2, 1.0, 0.0, node, work, None, None)
    for j in range(n):
        v[j] = rates[j]
    term = work[5]
    for e in range(kind.shape[0]):
        i, j = ends[e, 0], ends[e, 1]
        delta = d[i] if j == GROUND else d[i] - d[j]
        slip = 0.0
        if kind[e] == SLIDER and piece2[extra + e] != STUCK:
            slip = coef[e, 0] * abs(delta)
        elif kind[e] == BRANCH:
            if piece2[extra + e] != ELASTIC:
                slip = coef[e, 0] * coef[e, 1] * abs(u[e] + delta - u2[extra + e])
            u[e] = u2[extra + e]
        if kind[e] == SLIDER or kind[e] == BRANCH:
            p = piece2[extra + e]
            piece[e] = p // KINK if abs(p) == KINK else p
        if energy is not None:
            energy[1] += slip
        if dissipated is not None:
            dissipated[e] += slip
    force = node_force(instant, term, node)
    if energy is not None:
        energy[0] += force * d[node]
    return 0, force
