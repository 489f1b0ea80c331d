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

The programme's lazy sums carry roundings that grow with n and with the spread of the stiffnesses (a
segment's slope is a difference of two running sums of 1 / k), so only its decisions are kept: node c_j
sticks where its window did not clip g_j, and the others slip the way their force says. From those, the
tensions and places are settled exactly (:func:`_settle`: between two sticking nodes, one unknown tension
that the springs' elongations fix; the same linear algebra the active-set method does at its last
iteration), and the answer is checked: every sticking slider within its range, every slipping node moving
its slider's way. A sticking node keeps its place exactly.

Work: a stated budget of crossings (:data:`BUDGET_PER_NODE`). Past it, where the chain's form is not met, or
where the settled answer fails its check (a decision the roundings turned: a slider within a rounding of its
threshold), :func:`chain_step` returns -1 and the active-set method takes the step, warm-started from the
programme's pieces.
"""
import numpy as np

from .._jit import inline_kernel, kernel

SPRING, SLIDER = 0, 2  # kernels.py's kinds (a test checks they agree)
GROUND = -1
BUDGET_PER_NODE = 64  # segments a step's zero searches may cross, per node (plus a constant): then refused
BUDGET_CONSTANT = 1000
# a node's slider in the programme's answer: slipping (at its force, a tie included) or sticking
SLIPPING, STUCK = 0, 1
# the settled answer's check: a rounding of each of the n terms summed along the chain, relative to the largest
# force and place (past it the active-set method takes the step)
ROUNDING = 64.0 * np.finfo(np.float64).eps


@kernel
def chain_form(model, fixed_node, order, spring_to, slider_at, links=None):
    """Whether ``model`` is a massless chain (:func:`_chain_form`); ``links``: (n, 4) integers it works in (None:
    allocated here)."""
    if links is None:
        links = np.empty((model[0].shape[0], 4), np.int64)
        return _chain_form(model, fixed_node, order, spring_to, slider_at, links)
    return _chain_form(model, fixed_node, order, spring_to, slider_at, links)


@kernel
def _chain_form(model, fixed_node, order, spring_to, slider_at, links):
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
    neighbours = links[:, 0:2]  # the two springs of each node, its degree, its slider
    degree = links[:, 2]
    slider_of = links[:, 3]
    neighbours[:] = -1
    degree[:] = 0
    slider_of[:] = -1
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
def chain_tensions(k, y, alpha, wall, force, budget, g, stuck, stacks=None):
    """:func:`_tensions`; ``stacks``: the arrays it works in (:func:`scratch`'s first; None: allocated here)."""
    if stacks is None:
        n = k.shape[0]
        return _tensions(k, y, alpha, wall, force, budget, g, stuck, (np.empty((2, 2 * n + 4, 4)), np.empty((3, n))))
    return _tensions(k, y, alpha, wall, force, budget, g, stuck, stacks)


@kernel
def _tensions(k, y, alpha, wall, force, budget, g, stuck, stacks):
    """The programme of the module docstring on N springs: ``k[j]``, ``y[j]`` = k_j e_j, ``alpha[j]`` the
    slider at node j (the node after spring j), ``wall`` whether spring 0 exists (else g_0 = 0 and the
    programme starts at spring 1), ``force`` the load on node N-1. Writes the tensions ``g`` and ``stuck[j]``
    (SLIPPING or STUCK). Returns 1, -2 when no tensions balance the load (it
    is beyond the sliders' reach), -1 past ``budget`` crossings."""
    n = k.shape[0]
    first = 0 if wall else 1
    if first == n:  # one node, no wall: its slider alone
        if not abs(force) <= alpha[0]:
            return -2
        g[0] = 0.0
        stuck[0] = STUCK if abs(force) < alpha[0] else SLIPPING
        return 1
    left, right = stacks[0][0], stacks[0][1]
    lo = -np.inf if wall else -alpha[0]
    hi = np.inf if wall else alpha[0]
    minimiser, lows, highs = stacks[1][0], stacks[1][1], stacks[1][2]
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
            excess = max(low_window - highs[j], lows[j] - high_window)
            reach = abs(force)
            for i in range(n):
                reach += alpha[i]
            return -2 if excess > ROUNDING * n * reach else -1  # (a tie the sums' roundings decide: not here)
        value = minimiser[j]
        state = STUCK
        if value <= low_window:  # (a tie is a clip: the slider is at its force)
            value = low_window
            state = SLIPPING
        elif value >= high_window:
            value = high_window
            state = SLIPPING
        g[j] = min(max(value, lows[j]), highs[j])
        stuck[j] = state
        following = g[j]
    if not wall:
        g[0] = 0.0
        stuck[0] = STUCK if abs(g[1]) < alpha[0] else SLIPPING
    return 1


@kernel
def scratch(n):
    """The arrays a chain step of n nodes works in, allocated once for a run of steps (the time loops): a large
    array allocated at every step is fresh memory from the system, a page fault for every page it touches."""
    return (np.empty((2, 2 * n + 4, 4)), np.empty((3, n))), np.empty((6, n)), np.empty((4, n), np.int64), \
        np.empty((n, 4), np.int64)


@kernel
def chain_step(model, x, piece, force, fixed_node, d, term, work=None):
    """The implicit step of a massless chain: the increments ``d`` of the nodes, each element's force
    ``term`` and the sliders' pieces (0 sticking, +-1 slipping). Returns 1, -2 when no equilibrium exists, -3
    on a non-finite number, -1 when the active-set method is to take the step: the network is not a massless
    chain, the programme ran past its budget, or its answer did not pass the check of :func:`_settle` (only
    the pieces may then have been written: the programme's, a warm start). ``work``: :func:`scratch` (None:
    allocated here)."""
    if work is None:
        return _chain_step(model, x, piece, force, fixed_node, d, term, scratch(model[0].shape[0]))
    return _chain_step(model, x, piece, force, fixed_node, d, term, work)


@kernel
def _chain_step(model, x, piece, force, fixed_node, d, term, work):
    mass, kind, ends, coef, load_node, has_cubic = model
    n = mass.shape[0]
    stacks, reals, integers, links = work
    order, spring_to, slider_at, stuck = integers[0], integers[1], integers[2], integers[3]
    stiffness, y, alpha, g, slip, places = reals[0], reals[1], reals[2], reals[3], reals[4], reals[5]
    if not chain_form(model, fixed_node, order, spring_to, slider_at, links):
        return -1
    if not abs(force) < np.inf:
        return -3
    wall = spring_to[0] >= 0
    for j in range(n):
        stiffness[j], y[j], alpha[j] = 1.0, 0.0, 0.0
        e = spring_to[j]
        if e >= 0:
            stiffness[j] = coef[e, 0]
            elongation = x[order[j]] - (x[order[j - 1]] if j > 0 else 0.0)
            y[j] = stiffness[j] * elongation
            if not abs(y[j]) < np.inf:
                return -3
        if slider_at[j] >= 0:
            alpha[j] = coef[slider_at[j], 0]
    status = chain_tensions(stiffness, y, alpha, wall, force, BUDGET_PER_NODE * n + BUDGET_CONSTANT, g, stuck,
                            stacks)
    if status < 0:
        return status
    # the programme's answer says which sliders stick and which way the others slip; the tensions and places
    # are then settled exactly from that (its lazy sums carry roundings that grow with n and the spread of k)
    held = links[:, 0]  # (chain_form is done with it) 1 where the node keeps its place
    for j in range(n):
        slip[j] = 0.0  # a slipping node's slider force: +-alpha (0 for a node that sticks or has none)
        held[j] = 1 if stuck[j] != SLIPPING and alpha[j] > 0.0 else 0
        if not held[j]:
            following = g[j + 1] if j + 1 < n else force
            slip[j] = alpha[j] if following - g[j] > 0.0 else -alpha[j]
        e = slider_at[j]
        if e >= 0:
            piece[e] = 0 if held[j] else (1 if slip[j] > 0.0 else -1)
    if not _settle(x, order, stiffness, alpha, force, wall, held, slip, g, places):
        return -1
    for j in range(n):
        node = order[j]
        d[node] = 0.0 if held[j] else places[j] - x[node]
        e = spring_to[j]
        if e >= 0:
            term[e] = g[j] if ends[e, 1] == GROUND or ends[e, 0] == node else -g[j]
        e = slider_at[j]
        if e >= 0:
            term[e] = ((g[j + 1] if j + 1 < n else force) - g[j]) if held[j] else slip[j]
    return 1


@kernel
def _settle(x, order, stiffness, alpha, force, wall, held, slip, g, places):
    """The tensions ``g`` and places of the chain where the ``held`` nodes keep their place and every other
    node's slider pulls with ``slip``: between two held nodes the tensions are G + (the slips' partial
    sums), G such that the springs' elongations add up to the held nodes' distance; from the last held node
    on, the load sets them; before the first one, the wall's place (0) or g_0 = 0 without a wall. Then the
    check: every held slider's force within its range, every slipping node moving its slider's way (to a
    rounding). False where it fails, or where nothing holds the chain (no wall, no node held)."""
    n = g.shape[0]
    previous = -1  # the last held node
    for b in range(n + 1):
        if b < n and not held[b]:
            continue
        if b == n:  # the tail: from the load's node back to the last held node, the load sets the tensions
            following = force
            for j in range(n - 1, previous, -1):
                g[j] = following - slip[j]
                following = g[j]
            if previous < 0:
                if not wall:
                    return False  # nothing holds the chain: the active-set method says why (or how)
                places[0] = g[0] / stiffness[0]
                previous = 0
            for j in range(previous + 1, n):
                places[j] = places[j - 1] + g[j] / stiffness[j]
            break
        places[b] = x[order[b]]
        if previous < 0 and not wall:  # springs 1 .. b, g_0 = 0: set by the slips; places back from b
            following = 0.0
            for j in range(1, b + 1):
                following += slip[j - 1]
                g[j] = following
            g[0] = 0.0
            for j in range(b - 1, -1, -1):
                places[j] = places[j + 1] - g[j + 1] / stiffness[j + 1]
        else:  # springs first .. b: g_j = G + partial sums, their elongations fill the distance
            first = previous + 1
            distance = places[b] - (places[previous] if previous >= 0 else 0.0)
            partial = 0.0
            weights = 0.0
            known = 0.0
            for j in range(first, b + 1):
                g[j] = partial
                weights += 1.0 / stiffness[j]
                known += partial / stiffness[j]
                if j < b:
                    partial += slip[j]
            common = (distance - known) / weights
            for j in range(first, b + 1):
                g[j] += common
            for j in range(first, b):
                places[j] = (places[j - 1] if j > 0 else 0.0) + g[j] / stiffness[j]
        previous = b
    # the check (the tolerance: a rounding of each term summed along the chain, at the largest force and place)
    forces = abs(force)
    lengths = 0.0
    for j in range(n):
        if not abs(g[j]) < np.inf or not abs(places[j]) < np.inf:
            return False
        forces = max(forces, alpha[j], abs(g[j]))
        lengths = max(lengths, abs(places[j]), abs(x[order[j]]))
    for j in range(n):
        if held[j]:
            following = g[j + 1] if j + 1 < n else force
            if abs(following - g[j]) > alpha[j] + ROUNDING * n * forces:
                return False
        elif slip[j] != 0.0 and (places[j] - x[order[j]]) * slip[j] < -ROUNDING * n * lengths * alpha[j]:
            return False
    return True
