"""The massless chain's O(n) step (prandtl_fmu/network/chain.py) against independent solutions.

* random massless chains (springs in any orientation and order, with or without a wall, sliders of any
  threshold, 0 included) against a brute force written here: every slider state (stuck, slipping either way)
  enumerated, each one's linear equilibrium solved, the one that satisfies every slider's law kept;
* the same chains, stepped many times, against the active-set method (kernels.active_set_step), the general
  solver it stands beside;
* what is not a massless chain is left to the active-set method; the programme's budget is a refusal, and
  a load beyond the sliders' reach has no equilibrium.

All under the slow marker but the first (they compile the chain's kernels for their own models: ~12 s); the
quick suite's network tests take the programme through solve_step on the massless chains.
"""
import itertools

import numpy as np
import pytest

from prandtl_fmu.network import chain, kernels

SPRING, SLIDER, GROUND = kernels.SPRING, kernels.SLIDER, kernels.GROUND


def test_kinds_agree_with_the_kernels():
    assert (chain.SPRING, chain.SLIDER, chain.GROUND) == (kernels.SPRING, kernels.SLIDER, kernels.GROUND)


def random_chain(rng, n, wall=None):
    """A massless chain of n nodes in a random numbering, its elements in a random order: (model, path) with
    path the nodes from the far end to the load's node."""
    path = rng.permutation(n)
    elements = []
    for j in range(1, n):
        a, b = path[j - 1], path[j]
        if rng.random() < 0.5:
            a, b = b, a
        elements.append((SPRING, a, b, rng.uniform(0.3, 3.0)))
    if wall if wall is not None else rng.random() < 0.5:
        elements.append((SPRING, path[0], GROUND, rng.uniform(0.3, 3.0)))
    for node in path:
        if rng.random() < 0.85:
            elements.append((SLIDER, node, GROUND, rng.uniform(0.0, 1.0) if rng.random() < 0.9 else 0.0))
    order = rng.permutation(len(elements))
    kind = np.array([elements[e][0] for e in order], np.int64)
    ends = np.array([[elements[e][1], elements[e][2]] for e in order], np.int64).reshape(-1, 2)
    coef = np.zeros((len(elements), 3))
    coef[:, 0] = [elements[e][3] for e in order]
    return (np.zeros(n), kind, ends, coef, int(path[-1]), False), path


def has_wall(model):
    kind, ends = model[1], model[2]
    return bool(np.any((kind == SPRING) & (ends[:, 1] == GROUND)))


def brute_force(model, x, force):
    """The step's increments d by enumeration: for every node a slider state (0 stuck: d = 0, its force
    unknown; +-1: its force +-alpha, d of that sign), the linear equilibrium K (x + d) + s = F e_load, kept
    where every law holds. Returns the list of valid d (one, but for ties)."""
    mass, kind, ends, coef, load, _ = model
    n = mass.shape[0]
    stiffness = np.zeros((n, n))
    alpha = np.zeros(n)
    has_slider = np.zeros(n, bool)
    for e in range(kind.shape[0]):
        i, j, a = ends[e, 0], ends[e, 1], coef[e, 0]
        if kind[e] == SPRING:
            stiffness[i, i] += a
            if j != GROUND:
                stiffness[j, j] += a
                stiffness[i, j] -= a
                stiffness[j, i] -= a
        else:
            alpha[i] += a
            has_slider[i] = True
    load = np.zeros(n)
    load[model[4]] = force
    found = []
    for states in itertools.product((0, 1, -1), repeat=n):
        states = np.array(states)
        if np.any((states == 0) & ~has_slider):
            continue
        free = states != 0
        d = np.zeros(n)
        rhs = load - stiffness @ x - states * alpha
        if free.any():
            block = stiffness[np.ix_(free, free)]
            if abs(np.linalg.det(block)) < 1e-12:
                continue
            d[free] = np.linalg.solve(block, rhs[free])
        residual = load - stiffness @ (x + d)  # the sliders' forces
        scale = 1e-9 * (1.0 + np.abs(load).sum() + np.abs(stiffness @ x).sum())
        ok = all(abs(residual[j]) <= alpha[j] + scale for j in range(n) if states[j] == 0)
        ok = ok and all(states[j] * d[j] >= -scale for j in range(n) if states[j] != 0)
        ok = ok and np.allclose(residual[free], (states * alpha)[free], atol=scale)
        if ok:
            found.append(d)
    return found


def chain_solution(model, x, force):
    n = model[0].shape[0]
    d = np.full(n, np.nan)
    term = np.full(model[1].shape[0], np.nan)
    piece = np.zeros(model[1].shape[0], np.int64)
    status = chain.chain_step(model, x, piece, force, -1, d, term)
    return status, d, term, piece


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(6))
def test_random_chains_against_the_brute_force(seed):
    rng = np.random.default_rng(seed)
    checked = 0
    for _ in range(60):
        n = int(rng.integers(1, 6))
        model, path = random_chain(rng, n)
        x = rng.normal(0.0, 1.0, n)
        force = rng.normal(0.0, 2.0)
        status, d, term, piece = chain_solution(model, x, force)
        valid = brute_force(model, x, force)
        if not valid:
            assert status in (-2, -1), (status, d)  # no equilibrium (or left to the active-set method)
            continue
        if status == -1:  # nothing holds the chain but a tie: the active-set method decides
            assert not has_wall(model)
            continue
        assert status == 1
        assert min(np.max(np.abs(d - other)) for other in valid) < 1e-9, (d, valid)
        # every element's force balances each node, and the load reaches the ground whole
        balance = np.zeros(n)
        reaction = 0.0
        for e in range(model[1].shape[0]):
            i, j = model[2][e]
            balance[i] += term[e]
            if j == GROUND:
                reaction += term[e]
            else:
                balance[j] -= term[e]
        balance[model[4]] -= force
        assert np.max(np.abs(balance)) < 1e-9 * (1 + abs(force))
        assert reaction == pytest.approx(force, abs=1e-9 * (1 + abs(force)))
        checked += 1
    assert checked > 30


@pytest.mark.slow
def test_a_held_node_keeps_its_place_exactly():
    rng = np.random.default_rng(7)
    model, path = random_chain(rng, 8, wall=True)
    sliders = model[1] == SLIDER
    model[3][sliders, 0] = 1.0  # beyond every spring's force below
    x = rng.normal(0.0, 0.01, 8)
    status, d, term, piece = chain_solution(model, x, 0.0)
    assert status == 1 and np.all(piece[sliders] == 0)
    assert np.all(d[model[2][sliders, 0]] == 0.0)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(4))
def test_stepped_chains_follow_the_active_set_method(seed):
    """Two copies of a chain, one stepped by the programme, one by the active-set method, under the same
    random load history (reversals, slip fronts running both ways): the same places and forces."""
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(5, 40))
    model, path = random_chain(rng, n, wall=bool(seed % 2))
    alpha_total = model[3][model[1] == SLIDER, 0].sum()
    loads = np.cumsum(rng.normal(0.0, 0.15 * alpha_total + 0.1, 120))
    loads = np.clip(loads, -0.95 * alpha_total, 0.95 * alpha_total) if not has_wall(model) else loads
    work = kernels.workspace(n, model[1].shape[0])
    x_chain, x_active = np.zeros(n), np.zeros(n)
    piece_chain = np.zeros(model[1].shape[0], np.int64)
    piece_active = piece_chain.copy()
    v, u = np.zeros(n), np.zeros(model[1].shape[0])
    compared = 0
    for force in loads:
        status = chain.chain_step(model, x_chain, piece_chain, force, -1, work[0], work[5])
        if status == -1:  # a tie with nothing holding the chain: both take the active-set method
            status = kernels.active_set_step(model, x_chain, v, u, piece_chain, 1.0, force, -1, 0.0, work)
        assert status >= 1
        x_chain += work[0]
        term_chain = work[5].copy()
        status = kernels.active_set_step(model, x_active, v, u, piece_active, 1.0, force, -1, 0.0, work)
        assert status >= 1
        x_active += work[0]
        scale = 1e-9 * (1.0 + np.abs(x_active).max())
        assert np.max(np.abs(x_chain - x_active)) < scale
        assert np.max(np.abs(term_chain - work[5])) < 1e-9 * (1.0 + abs(force))
        compared += 1
    assert compared == len(loads)


@pytest.mark.slow
def test_what_is_not_a_massless_chain_goes_to_the_active_set_method():
    rng = np.random.default_rng(3)
    model, path = random_chain(rng, 5, wall=True)
    order = np.empty(5, np.int64)
    spring_to, slider_at = np.empty(5, np.int64), np.empty(5, np.int64)
    assert chain.chain_form(model, -1, order, spring_to, slider_at)
    assert list(order) == list(path)
    mass, kind, ends, coef, load, cubic = model
    variants = {
        "a node with a mass": (np.where(np.arange(5) == path[2], 1.0, 0.0), kind, ends, coef, load, cubic),
        "a cubic spring": (mass, kind, ends, coef, load, True),
        "the load not at an end": (mass, kind, ends, coef, int(path[2]), cubic),
    }
    dashpot = kind.copy()
    dashpot[np.flatnonzero(kind == SPRING)[0]] = kernels.DASHPOT
    variants["a dashpot"] = (mass, dashpot, ends, coef, load, cubic)
    wall_elsewhere = ends.copy()
    wall_elsewhere[np.flatnonzero((kind == SPRING) & (ends[:, 1] == GROUND))[0], 0] = path[3]
    variants["the wall not at the far end"] = (mass, kind, wall_elsewhere, coef, load, cubic)
    tree = np.vstack([ends, [[path[1], 5]]])  # a sixth node hanging from the second: a tree, not a path
    variants["a branching"] = (np.zeros(6), np.append(kind, SPRING), tree, np.vstack([coef, [1.0, 0, 0]]), load,
                               cubic)
    infinite = coef.copy()
    infinite[np.flatnonzero(kind == SLIDER)[0], 0] = np.inf
    variants["a held node (an instant's infinite slider)"] = (mass, kind, ends, infinite, load, cubic)
    for why, variant in variants.items():
        size = variant[0].shape[0]
        assert not chain.chain_form(variant, -1, np.empty(size, np.int64), np.empty(size, np.int64),
                                    np.empty(size, np.int64)), why
    assert not chain.chain_form(model, int(path[-1]), order, spring_to, slider_at), "a node's motion imposed"


@pytest.mark.slow
def test_the_budget_refuses_and_a_load_beyond_the_sliders_has_no_equilibrium():
    k = np.ones(6)
    y = np.array([3.0, -3.0, 3.0, -3.0, 3.0, -3.0])
    alpha = np.full(6, 0.1)
    g, stuck = np.empty(6), np.empty(6, np.int64)
    assert chain.chain_tensions(k, y, alpha, True, 0.0, 0, g, stuck) == -1
    assert chain.chain_tensions(k, y, alpha, True, 0.0, 10**6, g, stuck) == 1
    assert chain.chain_tensions(k, y, alpha, False, 0.61, 10**6, g, stuck) == -2  # beyond 6 x 0.1 (no wall)
    assert chain.chain_tensions(k, y, alpha, False, 0.59, 10**6, g, stuck) == 1


def path_model(k, alpha, wall_k=None):
    """The chain 0 - 1 - ... - n-1 (load on n-1), springs k[j] between j-1 and j, sliders alpha[j]."""
    n = len(alpha)
    kind, ends, coef = [], [], []
    if wall_k is not None:
        kind.append(SPRING), ends.append((0, GROUND)), coef.append((wall_k, 0, 0))
    for j in range(1, n):
        kind.append(SPRING), ends.append((j, j - 1)), coef.append((k[j], 0, 0))
    for j in range(n):
        kind.append(SLIDER), ends.append((j, GROUND)), coef.append((alpha[j], 0, 0))
    return (np.zeros(n), np.array(kind, np.int64), np.array(ends, np.int64), np.array(coef, float), n - 1, False)


@pytest.mark.slow
def test_a_load_at_the_total_friction_within_its_rounding_is_left_to_the_active_set_method():
    """sum([0.1] * 10) rounds below 1.0: the programme's reach is short of the load by a rounding, which is
    not "no equilibrium" (the active-set method finds one)."""
    model = path_model(np.ones(10), np.full(10, 0.1))
    work = kernels.workspace(10, model[1].shape[0])
    x = np.zeros(10)
    piece = np.zeros(model[1].shape[0], np.int64)
    assert chain.chain_step(model, x, piece.copy(), 1.0, -1, work[0], work[5]) == -1
    status = kernels.solve_step(model, x, np.zeros(10), np.zeros(model[1].shape[0]), piece, 1.0, 1.0, -1, 0.0, work)
    assert status >= 1
    assert work[0] == pytest.approx(np.cumsum(np.arange(10) * 0.1), abs=1e-12)  # node j: sum of (j - q) 0.1
    assert chain.chain_step(model, x, piece, 1.0 + 1e-6, -1, work[0], work[5]) == -2


@pytest.mark.slow
def test_forces_stay_exact_across_a_spread_of_stiffness():
    """Stiffnesses from 1e-6 to 1e6 (the programme's running sums of 1/k then cancel): the settled forces are
    k (x_i - x_j) of the places to rounding, the sliders' forces balance each node."""
    k = np.array([1e-6] * 3 + [1e6] * 3)
    alpha = np.array([1.0, 0.7, 0.9, 0.6, 0.8, 0.9])
    model = path_model(k, alpha, wall_k=1e-6)
    x = np.cumsum(np.array([0.2, 0.1, 0.4, 0.6, 1.0, 1.2]) / np.concatenate([[1e-6], k[1:]]))
    status, d, term, piece = chain_solution(model, x, 0.7)
    assert status == 1 and np.all(d == 0.0)  # every slider holds
    springs = model[1] == SPRING
    x1 = x + d
    expected = [model[3][e, 0] * (x1[i] - (x1[j] if j != GROUND else 0.0))
                for e, (i, j) in enumerate(model[2]) if springs[e]]
    assert term[springs] == pytest.approx(expected, rel=1e-12)


@pytest.mark.slow
def test_a_non_finite_load_is_refused():
    model = path_model(np.ones(3), np.full(3, 1.0), wall_k=1.0)
    assert chain_solution(model, np.zeros(3), np.nan)[0] == -3
    assert chain_solution(model, np.array([0.0, np.inf, 0.0]), 0.5)[0] == -3
