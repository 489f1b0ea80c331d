"""The massless chain's implicit step in O(n): a dynamic programme over the springs' tensions, exact and finite.

A network is a *massless chain* when every node is massless, the springs between nodes form one path whose end
is the load's node, every other element is a slider from a node to the ground (at most one per node) or one
spring from the path's far end to the ground (the wall), and no node's motion is imposed. Its implicit step
(``kernels.py``: J(d) with no masses, no dashpots) is then, in the springs' tensions g_j (spring j between
nodes c_(j-1) and c_j of the path, j = 0 the wall's spring, g_0 = 0 without a wall; g_N = F the load), the
dual problem

    min  sum_j (g_j - k_j e_j)^2 / (2 k_j)   subject to   |g_(j+1) - g_j| <= alpha_j,  j = 0 .. N-1,

e_j the spring's elongation at the step's start, alpha_j the slider at node c_j (0 without one): node c_j's
balance g_j - g_(j+1) + s_j = 0 with its slider's force |s_j| <= alpha_j. The objective is strictly convex,
so the tensions are unique. The active-set method (``kernels.solve_step``) finds them too, but a slip front
that moves by many nodes in one step costs it one O(n) iteration per node of the move; this programme costs
O(n) plus the segments its searches cross, whatever the front does.

The programme (forward): C_j(g) is the least cost of g_0 .. g_j with g_j = g; it is convex and piecewise
quadratic, and its derivative C_j' is increasing and piecewise linear (with jumps where a domain's end holds a
minimiser). From C_j, M_j(g) = min over |g' - g| <= alpha_j of C_j(g') splits C_j' at its zero g*_j and moves
the left part by -alpha_j, the right part by +alpha_j, with 0 between; C_(j+1) = M_j + the next spring's
term. C_j' is kept as segments (each linear) on two stacks, left and right of the last zero, each stack with
a lazy shift and a lazy added linear function, so a step of the programme costs O(1) plus the segments the
search for the next zero crosses. Backward: g_N = F, and g_j = the point of [g_(j+1) - alpha_j, g_(j+1) +
alpha_j] (within C_j's domain) nearest to g*_j.

Then node c_j sticks where its window did not clip g_j (its slider's force is strictly inside); a sticking
node keeps its place exactly, and the others follow from it through the elongations g_j / k_j (with no node
sticking, from the wall). Work: a stated budget of crossings (:data:`BUDGET_PER_NODE`); past it, or where the
chain's form is not met, :func:`chain_step` returns -1 and the active-set method takes the step.
"""
import numpy as np

from .._jit import inline_kernel, kernel

SPRING, SLIDER = 0, 2  # kernels.py's kinds (a test checks they agree)
GROUND = -1
BUDGET_PER_NODE = 64  # segments a step's zero searches may cross, per node (plus a constant): then refused
BUDGET_CONSTANT = 1000
# a node's slider: slipping (at its force, a tie included), sticking, or sticking with its force inside its range
# by more than MARGIN (relative): such a node keeps its place exactly (a tie computed with a rounding error
# never does)
SLIPPING, STUCK, STUCK_HELD = 0, 1, 2
MARGIN = 1e-9


@kernel
def chain_form(model, fixed_node, order, spring_to, slider_at):
    """Whether ``model`` is a massless chain (see the module docstring): fills ``order`` (the path's nodes
    from the far end to the load's node), ``spring_to[j]`` (the spring between order[j-1] and order[j]; for
    j = 0 the wall's spring or -1) and ``slider_at[j]`` (the slider at order[j] or -1)."""
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    if fixed_node >= 0 or has_cubic or n == 0:
        return False
    for j in range(n):
        if mass[j] != 0.0:
            return False
    neighbours = np.full((n, 2), -1, np.int64)
    degree = np.zeros(n, np.int64)
    slider_of = np.full(n, -1, np.int64)
    wall = -1
    for e in range(kind.shape[0]):
        i, j = ends[e, 0], ends[e, 1]
        if kind[e] == SPRING:
            if not coef[e, 0] > 0.0:
                return False
            if j == GROUND:
                if wall >= 0:
                    return False
                wall = e
                continue
            if i == j or degree[i] >= 2 or degree[j] >= 2:
                return False
            neighbours[i, degree[i]] = e
            degree[i] += 1
            neighbours[j, degree[j]] = e
            degree[j] += 1
        elif kind[e] == SLIDER:
            if j != GROUND or slider_of[i] >= 0 or not coef[e, 0] < np.inf:  # (an instant's held node: inf)
                return False
            slider_of[i] = e
        else:
            return False
    if degree[load_node] > 1:
        return False
    position = n - 1
    node = load_node
    order[position] = node
    came_by = -1
    while True:
        e = neighbours[node, 0] if neighbours[node, 0] != came_by else neighbours[node, 1]
        if e < 0:
            break
        spring_to[position] = e
        position -= 1
        if position < 0:
            return False
        node = ends[e, 0] if ends[e, 1] == node else ends[e, 1]
        order[position] = node
        came_by = e
    if position != 0:  # the path does not reach every node
        return False
    if wall >= 0 and ends[wall, 0] != order[0]:
        return False
    spring_to[0] = wall
    for j in range(n):
        slider_at[j] = slider_of[order[j]]
    return True


@inline_kernel
def _value(seg, top, shift, slope_added, value_added, at):
    """C'(at) on a stack's segment ``top`` (raw: p1, p2, a, b; actual: a (g - shift) + b + slope_added g +
    value_added, computed as slope g + intercept so that an infinite end gives an infinite value)."""
    slope = seg[top, 2] + slope_added
    return slope * at + (seg[top, 3] - seg[top, 2] * shift + value_added)


@inline_kernel
def _root(seg, top, shift, slope_added, value_added):
    """Where the line of a stack's segment ``top`` crosses 0 (its slope is > 0: every term adds 1 / k)."""
    slope = seg[top, 2] + slope_added
    return -(seg[top, 3] - seg[top, 2] * shift + value_added) / slope


@inline_kernel
def _move(src, i, s_shift, s_slope, s_value, dst, k, d_shift, d_slope, d_value):
    """Copy segment i of one stack (its lazy transform s_*) into row k of another (d_*), the same actual
    segment."""
    p1 = src[i, 0] + s_shift
    p2 = src[i, 1] + s_shift
    slope = src[i, 2] + s_slope
    intercept = src[i, 3] - src[i, 2] * s_shift + s_value
    a = slope - d_slope
    dst[k, 0] = p1 - d_shift
    dst[k, 1] = p2 - d_shift
    dst[k, 2] = a
    dst[k, 3] = intercept + a * d_shift - d_value


@kernel
def chain_tensions(k, y, alpha, wall, force, budget, g, stuck):
    """The programme of the module docstring on N springs: ``k[j]``, ``y[j]`` = k_j e_j, ``alpha[j]`` the
    slider at node j (the node after spring j), ``wall`` whether spring 0 exists (else g_0 = 0 and the
    programme starts at spring 1), ``force`` the load on node N-1. Writes the tensions ``g`` and ``stuck[j]``
    (SLIPPING, STUCK or STUCK_HELD). Returns 1, -2 when no tensions balance the load (it
    is beyond the sliders' reach), -1 past ``budget`` crossings."""
    n = k.shape[0]
    first = 0 if wall else 1
    if first == n:  # one node, no wall: its slider alone
        if not abs(force) <= alpha[0]:
            return -2
        g[0] = 0.0
        margin = alpha[0] - abs(force)
        stuck[0] = SLIPPING if margin <= 0.0 else (STUCK_HELD if margin > MARGIN * alpha[0] else STUCK)
        return 1
    capacity = 2 * n + 4
    left = np.empty((capacity, 4))
    right = np.empty((capacity, 4))
    lo = -np.inf if wall else -alpha[0]
    hi = np.inf if wall else alpha[0]
    minimiser = np.empty(n)
    lows = np.empty(n)
    highs = np.empty(n)
    # C_first' = (g - y) / k on [lo, hi], on the right stack; the left one is empty
    n_left, n_right = 0, 1
    l_shift, l_slope, l_value = 0.0, 0.0, 0.0
    r_shift, r_slope, r_value = 0.0, 0.0, 0.0
    right[0, 0], right[0, 1] = lo, hi
    right[0, 2], right[0, 3] = 1.0 / k[first], -y[first] / k[first]
    crossed = 0
    for j in range(first, n):
        # the zero of C_j' (or the end of the domain its sign points to)
        zero = np.nan
        if n_right > 0 and _value(right, n_right - 1, r_shift, r_slope, r_value,
                                  right[n_right - 1, 0] + r_shift) < 0.0:
            while n_right > 0:  # walk right
                top = n_right - 1
                end = right[top, 1] + r_shift
                if _value(right, top, r_shift, r_slope, r_value, end) < 0.0:
                    _move(right, top, r_shift, r_slope, r_value, left, n_left, l_shift, l_slope, l_value)
                    n_left += 1
                    n_right -= 1
                    crossed += 1
                    if crossed > budget:
                        return -1
                    continue
                start = right[top, 0] + r_shift
                zero = min(max(_root(right, top, r_shift, r_slope, r_value), start), end)
                if zero > start:  # the part before the zero goes left
                    _move(right, top, r_shift, r_slope, r_value, left, n_left, l_shift, l_slope, l_value)
                    left[n_left, 1] = zero - l_shift
                    n_left += 1
                    right[top, 0] = zero - r_shift
                break
            if n_right == 0:
                zero = hi
        elif n_left > 0 and _value(left, n_left - 1, l_shift, l_slope, l_value,
                                   left[n_left - 1, 1] + l_shift) > 0.0:
            while n_left > 0:  # walk left
                top = n_left - 1
                start = left[top, 0] + l_shift
                if _value(left, top, l_shift, l_slope, l_value, start) > 0.0:
                    _move(left, top, l_shift, l_slope, l_value, right, n_right, r_shift, r_slope, r_value)
                    n_right += 1
                    n_left -= 1
                    crossed += 1
                    if crossed > budget:
                        return -1
                    continue
                end = left[top, 1] + l_shift
                zero = min(max(_root(left, top, l_shift, l_slope, l_value), start), end)
                if zero < end:  # the part after the zero goes right
                    _move(left, top, l_shift, l_slope, l_value, right, n_right, r_shift, r_slope, r_value)
                    right[n_right, 0] = zero - r_shift
                    n_right += 1
                    left[top, 1] = zero - l_shift
                break
            if n_left == 0:
                zero = lo
        else:  # the zero is where the stacks meet
            zero = right[n_right - 1, 0] + r_shift if n_right > 0 else left[n_left - 1, 1] + l_shift
        if not abs(zero) < np.inf:
            return -3
        minimiser[j], lows[j], highs[j] = zero, lo, hi
        if j == n - 1:
            break
        # M_j: the left part moves by -alpha_j, the right part by +alpha_j, 0 in between; then + the next term
        a = alpha[j]
        l_shift -= a
        l_value += l_slope * a
        r_shift += a
        r_value -= r_slope * a
        lo -= a
        hi += a
        if a > 0.0:
            right[n_right, 0] = zero - a - r_shift
            right[n_right, 1] = zero + a - r_shift
            right[n_right, 2] = -r_slope
            right[n_right, 3] = -r_slope * r_shift - r_value
            n_right += 1
        inverse = 1.0 / k[j + 1]
        l_slope += inverse
        l_value -= y[j + 1] * inverse
        r_slope += inverse
        r_value -= y[j + 1] * inverse
    # backward: g_(N-1) in the load's window, then each g_j in its successor's (within C_j's domain: the two
    # meet for j < N-1 but for rounding, and a clip to the domain settles that)
    following = force
    for j in range(n - 1, first - 1, -1):
        a = alpha[j]
        low_window, high_window = following - a, following + a
        if j == n - 1 and (low_window > highs[j] or high_window < lows[j]):
            return -2
        value = minimiser[j]
        state = STUCK_HELD
        if value <= low_window:  # (a tie is a clip: the slider is at its force)
            value = low_window
            state = SLIPPING
        elif value >= high_window:
            value = high_window
            state = SLIPPING
        elif min(value - low_window, high_window - value) <= MARGIN * (abs(following) + a + abs(value)):
            state = STUCK
        g[j] = min(max(value, lows[j]), highs[j])
        stuck[j] = state
        following = g[j]
    if not wall:
        g[0] = 0.0
        margin = alpha[0] - abs(g[1])
        stuck[0] = SLIPPING if margin <= 0.0 else (STUCK_HELD if margin > MARGIN * alpha[0] else STUCK)
    return 1


@kernel
def chain_step(model, x, piece, force, fixed_node, d, term):
    """The implicit step of a massless chain: the increments ``d`` of the nodes, each element's force
    ``term`` and the sliders' pieces (0 sticking, +-1 slipping). Returns 1, -2 when no equilibrium exists, -3
    on a non-finite number, -1 when the network is not a massless chain or the programme ran past its
    budget (the active-set method then takes the step: nothing was written)."""
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    order = np.empty(n, np.int64)
    spring_to = np.empty(n, np.int64)
    slider_at = np.empty(n, np.int64)
    if not chain_form(model, fixed_node, order, spring_to, slider_at):
        return -1
    wall = spring_to[0] >= 0
    stiffness = np.ones(n)
    y = np.zeros(n)
    alpha = np.zeros(n)
    for j in range(n):
        e = spring_to[j]
        if e >= 0:
            stiffness[j] = coef[e, 0]
            elongation = x[order[j]] - (x[order[j - 1]] if j > 0 else 0.0)
            y[j] = stiffness[j] * elongation
        if slider_at[j] >= 0:
            alpha[j] = coef[slider_at[j], 0]
    g = np.empty(n)
    stuck = np.empty(n, np.int64)
    status = chain_tensions(stiffness, y, alpha, wall, force, BUDGET_PER_NODE * n + BUDGET_CONSTANT, g, stuck)
    if status < 0:
        return status
    held = np.empty(n, np.bool_)
    for j in range(n):
        held[j] = stuck[j] == STUCK_HELD and slider_at[j] >= 0
    places = np.empty(n)
    _places(x, order, stiffness, g, alpha, held, wall, force, places)
    for j in range(n):
        if not abs(places[j]) < np.inf:
            return -3
    for j in range(n):
        node = order[j]
        d[node] = 0.0 if held[j] else places[j] - x[node]
        e = spring_to[j]
        if e >= 0:
            term[e] = g[j] if ends[e, 1] == GROUND or ends[e, 0] == node else -g[j]
        e = slider_at[j]
        if e >= 0:
            following = g[j + 1] if j + 1 < n else force
            if stuck[j] != SLIPPING:
                piece[e] = 0
                term[e] = following - g[j]
            else:
                piece[e] = 1 if following - g[j] > 0.0 else -1
                term[e] = coef[e, 0] * piece[e]
    return 1


@kernel
def _places(x, order, stiffness, g, alpha, held, wall, force, places):
    """The nodes' new places from the tensions: node j is the one before it plus g_j / k_j, from the wall or
    from a node that keeps its place (``held``). Without a wall and with no node held (every slider at its
    force, or within MARGIN of it), the chain's place is the minimiser over its translation t of
    sum_j alpha_j |d_j(t)| - F d_(N-1)(t), the place where the sliders' forces balance F: a weighted median."""
    n = g.shape[0]
    places[0] = g[0] / stiffness[0] if wall else 0.0
    for j in range(1, n):
        places[j] = places[j - 1] + g[j] / stiffness[j]
    first = -1
    for j in range(n):
        if held[j]:
            first = j
            break
    if first < 0 and not wall:
        # d_j(t) = t - tau_j with tau_j = x_j - places_j: phi'(t) = sum_j alpha_j sign(t - tau_j) - F, which
        # rises from -sum alpha - F to sum alpha - F; its zero is at some tau_j (that node keeps its place)
        tau = np.empty(n)
        for j in range(n):
            tau[j] = x[order[j]] - places[j]
        ranked = np.argsort(tau)
        slope = -force
        for j in range(n):
            slope -= alpha[j]
        median = ranked[n - 1]
        for i in range(n):
            slope += 2.0 * alpha[ranked[i]]
            if slope >= 0.0:
                median = ranked[i]
                break
        held[median] = True
        first = median
    if first < 0:  # with a wall, nothing held: the places from the wall
        return
    places[first] = x[order[first]]
    if not wall:  # before the first node held: back from it (with a wall: from the wall)
        for j in range(first - 1, -1, -1):
            places[j] = places[j + 1] - g[j + 1] / stiffness[j + 1]
    for j in range(first + 1, n):
        places[j] = x[order[j]] if held[j] else places[j - 1] + g[j] / stiffness[j]
