"""The monodromy of many sliding branches, reduced (``floquet.reduced``): a sliding branch ends the period with
du = B dx(T) - B dx(tau), tau the instant it last started to stick, the same for every branch of its pair that
started then; so the monodromy over (x, v, u) factors through 2 n plus a few such instants, and the nonzero
multipliers come from a matrix of that size. Checked against the whole monodromy (one column per sliding branch,
the path the reduction replaces, itself checked against finite differences in test_harmonic_balance.py) on
random scenes, and on the packaged element of a thousand branches, which the whole monodromy left without
multipliers (past the work bound)."""
import math

import numpy as np
import pytest

from prandtl_fmu.frequency import floquet, parse_scene
from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

from tests.analysis.test_harmonic_balance import element
from tests.analysis.test_harmonic_balance_network_friction import network_text


def both(balance, q, omega):
    """(reduced, whole): the matrix variational_monodromy takes, and the whole monodromy (the reduction
    turned off: its size made larger than the whole's)."""
    reduced = floquet.variational_monodromy(balance, q, omega)
    plan = floquet.reduced
    try:
        floquet.reduced = lambda *args: (10**9,) + plan(*args)[1:]
        whole = floquet.variational_monodromy(balance, q, omega)
    finally:
        floquet.reduced = plan
    return reduced, whole


def nonzero(values, scale):
    """The multipliers above rounding (1e-9 of the largest), largest first."""
    values = values[np.abs(values) > 1e-9 * scale]
    return values[np.argsort(-np.abs(values), kind="stable")]


def same_spectrum(reduced, whole):
    got, wanted = np.linalg.eigvals(reduced), np.linalg.eigvals(whole)
    scale = float(np.max(np.abs(wanted)))
    got, wanted = nonzero(got, scale), nonzero(wanted, scale)
    assert got.size == wanted.size, (got, wanted)
    for value in wanted:  # each a partner among the other's (complex pairs in either order)
        assert np.min(np.abs(got - value)) <= 1e-9 * max(scale, 1.0), (got, wanted)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_reduced_monodromy_of_an_element_has_the_whole_one_s_multipliers(seed):
    """An element with 24 branches of random stiffness and range and a cubic spring, forced hard enough that
    most slide, at several harmonics (so that a branch can turn more than twice a period): the nonzero
    multipliers of the reduced matrix are the whole monodromy's to 1e-9, from a matrix of 2 plus the instants
    (at most a handful) instead of 2 plus the sliding branches."""
    rng = np.random.default_rng(seed)
    n = 24
    tables = {"mass": {"m": 1.0}, "spring": {"k0": 0.5}, "damper": {"c": 0.03},
              "cubic": {"k3": float(rng.uniform(0.0, 0.5))},
              "branches": {"k": rng.uniform(0.02, 0.1, n).tolist(), "eta": rng.uniform(0.02, 0.5, n).tolist()}}
    system = periodic_system(element(tables))
    omega = 2.0 * math.pi * float(rng.uniform(0.1, 0.3))
    balance = HarmonicBalance(system, 7, float(rng.uniform(0.3, 0.8)))
    q = balance.solve_at(omega)
    reduced, whole = both(balance, q, omega)
    sliding = whole.shape[0] - 2
    assert sliding >= n // 2, sliding
    assert reduced.shape[0] <= 2 + 6 < whole.shape[0], (reduced.shape, whole.shape)
    same_spectrum(reduced, whole)


@pytest.mark.parametrize("phase", [2.0 * math.pi * 4 / 12, math.pi])
def test_branches_of_one_pair_that_start_to_stick_at_two_instants_are_two_groups(phase):
    """Along a periodic motion with minor loops, x = 0.5 cos(w t) + 0.3 cos(3 w t + phase) (the variational
    equation is a linear periodic one along any periodic motion, a solution or not: the factorisation holds
    for it), the narrow branches last start to stick at a minor loop's turn and the wide ones at the major
    one's: two groups on one pair, and the same nonzero multipliers as the whole monodromy's."""
    n = 24
    tables = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.03},
              "branches": {"k": [0.05] * n, "eta": np.linspace(0.01, 0.5, n).tolist()}}
    system = periodic_system(element(tables))
    balance = HarmonicBalance(system, 5, 1.0)
    full = np.zeros(system.n * balance.L)
    full[1], full[5], full[6] = 0.5, 0.3 * math.cos(phase), 0.3 * math.sin(phase)
    q = full[balance.free]
    omega = 2.0 * math.pi * 0.1
    reduced, whole = both(balance, q, omega)
    assert reduced.shape[0] == 2 + 2, reduced.shape
    same_spectrum(reduced, whole)


def test_the_reduced_monodromy_of_a_network_with_two_joints_has_the_whole_one_s_multipliers():
    """Two masses, each joint a dozen branches (between the masses, and from b to the ground), a cubic spring:
    groups per pair of nodes, the ground's and the joint's; the same nonzero multipliers as the whole monodromy's
    to 1e-9."""
    rng = np.random.default_rng(7)
    elements = [("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.0}),
                ("dashpot", ["a", "ground"], {"c": 0.02}), ("dashpot", ["b", "ground"], {"c": 0.02}),
                ("cubic", ["a", "ground"], {"k3": 0.3})]
    for between in (["a", "b"], ["b", "ground"]):
        for k, eta in zip(rng.uniform(0.05, 0.2, 12), rng.uniform(0.01, 0.3, 12)):
            elements.append(("branch", between, {"k": k, "eta": eta}))
    scene = parse_scene(network_text(["a", "b"], [1.0, 1.0], elements, load_node="a"), networks=True)[0]
    system = periodic_system(scene)
    omega = 2.0 * math.pi * 0.17
    balance = HarmonicBalance(system, 5, 1.5)
    q = balance.solve_at(omega)
    reduced, whole = both(balance, q, omega)
    assert whole.shape[0] - 4 >= 12 and reduced.shape[0] < whole.shape[0], (reduced.shape, whole.shape)
    same_spectrum(reduced, whole)


SCENE_1000 = """
name = "many-branches-1000"
[mass]
m = 1.0
[branches]
count = 1000
k_total = 1.0
eta_range = [0.1, 1.1]
"""


@pytest.mark.parametrize("whole_too", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_a_thousand_branches_get_their_multipliers(monkeypatch, whole_too):
    """hard/many-branches's element (the paper's spectrum) with a thousand branches and no spring, at 0.0926 Hz,
    where most branches slide: the whole monodromy (a column per sliding branch) was past the work bound, so
    the point was stable by the energy with its multiplier unwritten; the reduced matrix, of a handful of rows,
    gives it, below 1 (the scene is monotone); and (slow: 8 s) it is the whole monodromy's, computed with the
    bound lifted."""
    system = periodic_system(parse_scene(SCENE_1000)[0])
    omega = 2.0 * math.pi * 0.0926
    balance = HarmonicBalance(system, 5, 0.3)
    q = balance.solve_at(omega)
    assert floquet._slides(system, balance.samples(balance.full(q))).sum() >= 500
    reduced = floquet.variational_monodromy(balance, q, omega)
    assert reduced is not None and reduced.shape[0] <= 8
    assert 0.0 < float(np.max(np.abs(np.linalg.eigvals(reduced)))) < 1.0
    if whole_too:
        monkeypatch.setattr(floquet, "WORK_LIMIT", math.inf)
        same_spectrum(*both(balance, q, omega))
