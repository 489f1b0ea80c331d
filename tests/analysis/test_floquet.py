"""The finite-difference multipliers' extrapolation and refinement, Arnoldi's iteration on small matrices, and the
verdict of a monotone scene (``prandtl_fmu/frequency/floquet.py``, ``curve.py``): each against what it must
give by construction, and a joint whose finite differences paired two different multipliers."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main
from prandtl_fmu.frequency import floquet

from tests.analysis.test_describe_cli import read_csv
from tests.analysis.test_harmonic_balance_network_friction import network_text


def test_a_pair_that_is_one_multiplier_is_extrapolated_in_its_logarithm_and_others_not():
    """0.070 at M and 0.207 at 2 M steps, each the other's nearest (backward Euler's e^-2.16 and e^-1.08 on
    0.612): 0.207^2 / 0.070. 0.1481 at 2 M whose nearest at M is 0.0005, whose nearest at 2 M is 0.0003 (not one
    multiplier: a slip between steps at one resolution): kept as it is, where the logarithm gave 44. A ratio
    past e^1.5 (0.5 and 0.05): kept. A coarse value below NOISE: kept. A complex pair at 2 M nearest to a real
    one at M (two real multipliers that met): kept, where paired they made 1.21 and 1.18."""
    assert floquet.extrapolated(np.array([0.207]), np.array([0.070])) == pytest.approx([0.207**2 / 0.070])
    assert floquet.extrapolated(np.array([0.1481]), np.array([0.0005, -0.5]), np.array([0.1481, 0.0003])) == \
        pytest.approx([0.1481])
    assert floquet.extrapolated(np.array([0.5]), np.array([0.05])) == pytest.approx([0.5])
    assert floquet.extrapolated(np.array([1e-7]), np.array([1e-9])) == pytest.approx([1e-7])
    met = np.array([0.9067 - 0.3136j, 0.9067 + 0.3136j])
    assert floquet.extrapolated(met, np.array([1.1357, 0.7834])) == pytest.approx(met)
    assert not np.any(floquet.pairs(met, np.array([1.1357, 0.7834]))[1])
    # a complex pair: each with its own conjugate's partner
    fine, coarse = np.array([0.9 * np.exp(0.3j), 0.9 * np.exp(-0.3j)]), np.array([0.8 * np.exp(0.31j),
                                                                                0.8 * np.exp(-0.31j)])
    assert floquet.extrapolated(fine, coarse) == pytest.approx(fine**2 / coarse)


@pytest.mark.parametrize("ratio, known", [(3.0, True), (30.0, False)])
def test_the_refinement_gives_a_value_in_range_or_none(ratio, known):
    """A multiplier mu = 0.6 e^(0.2 i) seen through backward Euler's shrinking exp(-a / M), a = (2 pi ratio)^2 / 2
    (a motion ratio times the forcing's frequency): at ratio 3 the refinement reaches a pair whose shrinking is
    within SHRINK and gives mu to 1e-3; at ratio 30 even 16384 steps shrink it by e^-1.1 from 8192: the
    multipliers are not computed (None: unknown), where the verdict would have been "stable" for any mu (it
    was, with the value off by a factor). (A multiplier that the shrinking hides below another one is not
    seen at all: floquet.py says so.)"""
    a = (2 * math.pi * ratio) ** 2 / 2
    mu = 0.6 * np.exp(0.2j)

    def at(steps):
        return np.array([mu * math.exp(-a / steps)])

    values = floquet.refined(at, floquet.STEPS)
    if known:
        assert abs(np.max(np.abs(values)) - abs(mu)) <= 1e-3
    else:
        assert values is None


def test_arnoldi_fills_a_small_space_whose_spectrum_lies_on_one_circle():
    """A cyclic shift of 300 (every eigenvalue a 300th root of unity: no largest to converge on) is within
    FULL_BASIS: the basis fills the space, which is then invariant, and its Ritz values are eigenvalues:
    |lambda| = 1 and lambda^300 = 1 to 1e-9 (a restarted basis of 80 reached no answer)."""
    n = 300
    assert n <= floquet.FULL_BASIS
    found = floquet.arnoldi(lambda w: np.roll(w, 1), n, 8)
    assert found is not None and len(found) == 8
    assert np.abs(found) == pytest.approx(1.0, abs=1e-9)
    assert np.abs(found**300 - 1.0) == pytest.approx(0.0, abs=1e-6)


def test_a_monotone_scene_s_points_are_stable_whatever_its_finite_differences_say(monkeypatch):
    """Where every periodic state is stable by the energy (floquet.monotone) a point whose multipliers say
    otherwise is the finite differences' artefact: stable, its multiplier not given (NaN), the others'
    verdicts and values as computed."""
    from prandtl_fmu.frequency import parse_scene
    from prandtl_fmu.frequency.curve import harmonic_response

    from tests.analysis.test_harmonic_balance import MASSLESS_JOINT

    scene = parse_scene(MASSLESS_JOINT, networks=True)[0]
    calls = []
    real = floquet.multipliers

    def faked(balance, q, omega, steps=floquet.STEPS):
        calls.append(omega)
        return np.array([1.5]) if len(calls) == 2 else real(balance, q, omega, steps)

    monkeypatch.setattr(floquet, "multipliers", faked)
    curve = harmonic_response(scene, 0.2, [0.05, 0.1], harmonics=3)
    assert np.all(curve.stable)
    assert math.isnan(curve.multiplier[1]) and np.all(np.isfinite(np.delete(curve.multiplier, 1)))
    assert np.all(np.delete(curve.multiplier, 1) <= 1.0 + floquet.MARGIN)


@pytest.mark.slow
def test_a_joint_behind_a_massless_node_is_stable_everywhere(tmp_path):
    """A joint behind a massless node, its far node a light mass (0.1 kg): monotone, so every point is stable.
    Its finite differences at 2048 and 4096 steps paired 0.148 with 0.0005 (a slip between steps at one
    resolution) and the logarithm's extrapolation said 45.3 (and 1.94, 1.65 at two more points): each point's
    multiplier now at most 1 + MARGIN where it is given, every point stable; not given at a few points (at
    0.01 Hz, a sixteenth of the first resonance, backward Euler still shrinks the largest past SHRINK at 4096
    steps; at three more the pairs' verdicts still move at 4096 steps, a slip starting between steps): there
    the verdict is the proof's."""
    path = tmp_path / "joint.toml"
    path.write_text(network_text(["a", "j", "b"], [1.0, 0.0, 0.1], [
        ("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.0}),
        ("spring", ["a", "j"], {"k": 5.0}), ("spring", ["j", "ground"], {"k": 0.5}),
        ("branch", ["j", "b"], {"k": 2.0, "eta": 0.05}), ("dashpot", ["a", "ground"], {"c": 0.02}),
        ("dashpot", ["b", "ground"], {"c": 0.02})], load_node="a"))
    out = tmp_path / "curve.csv"
    assert main(["describe", str(path), "--force-amplitude", "1", "--frequencies", "0.01,0.6", "--harmonics", "5",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    assert set(table["stable"]) == {"true"}
    given = [(float(f), m) for f, m in zip(table["frequency"], table["multiplier"])]
    assert sum(m == "" for _, m in given) <= 6 and sum(m != "" for _, m in given) > 100
    assert max(float(m) for _, m in given if m) <= 1.0 + floquet.MARGIN


def test_a_multiplier_shrunk_to_zero_is_unknown_not_stable():
    """Far below a delay's unstable resonance backward Euler shrinks a multiplier of 5e5 to 0 at 256 and 512
    steps (a review's find: written stable, its multiplier 0.0): the largest at both resolutions 0 is no value,
    and one still shrinking at 16384 steps (7e-5 to 6.7 from 8192 to 16384) neither: unknown."""
    assert floquet.refined(lambda steps: np.zeros(2), floquet.STEPS) is None
    seen = {256: 0.0, 512: 0.0, 1024: 0.0, 2048: 0.0, 4096: 7e-5 * 1e-6, 8192: 7e-5, 16384: 6.7}
    assert floquet.refined(lambda steps: np.array([seen[steps], 0.0]), floquet.STEPS) is None


def test_a_step_the_check_s_stepper_refuses_leaves_the_point_unknown(monkeypatch):
    """The finite differences' implicit stepper refusing a step (its active-set search past its budget, met on
    a joint with a cubic spring at 1 N) ended the command on an internal error: the point's multipliers are
    not computed now (None: an empty field and a warning line)."""
    from prandtl_fmu.frequency import parse_scene
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system
    from prandtl_fmu.stepping import ElementError

    from tests.analysis.test_harmonic_balance import MASSLESS_JOINT

    def refused(*args):
        raise ElementError("the implicit step refused: the active-set search did not end within its budget")

    monkeypatch.setattr(floquet, "_monodromy", refused)
    balance = HarmonicBalance(periodic_system(parse_scene(MASSLESS_JOINT, networks=True)[0]), 3, 0.2)
    omega = 2 * math.pi * 0.1
    assert floquet.multipliers(balance, balance.solve_at(omega), omega) is None


def test_a_verdict_still_in_doubt_at_the_finest_steps_is_unknown():
    """Largest multipliers that keep moving about 1 from one resolution to the next (a slip starting between
    steps at one and not at the next: on a joint with a cubic spring 0.760, 0.871, 0.936, 0.896 at 1024 ... 8192
    steps) leave the verdict in doubt at the finest pair: unknown (None), where the pair 4096 and 2048's value
    (1.006, "unstable") was taken; a pair that settles away from 1 is taken as before."""
    seen = {256: 0.90, 512: 0.96, 1024: 0.93, 2048: 0.99, 4096: 0.95, 8192: 1.01, 16384: 0.97}
    assert floquet.refined(lambda steps: np.array([seen[steps]]), floquet.STEPS) is None
    steady = {256: 0.70, 512: 0.71, 1024: 0.715, 2048: 0.7175, 4096: 0.71875}
    values = floquet.refined(lambda steps: np.array([steady[steps]]), floquet.STEPS)
    assert values is not None and abs(abs(values[0]) - 0.72) <= 2e-3


def test_two_real_multipliers_that_become_a_complex_pair_are_not_called_unstable():
    """A joint with a cubic spring at 0.48 Hz, F0 = 1 N (its monodromies at 256 ... 4096 steps, measured: a real
    multiplier of the coarse steps, 2.02, 1.58, 1.14, meets a real one and is a complex pair from 2048 on): the
    pair at 2048 and 1024 steps has no partner for it, so the refinement goes on to 4096 and gives 0.976 (the
    pair that met, 0.9594 and 0.9678 in modulus at 2048 and 4096 steps), stable, where it said 1.206, unstable."""
    seen = {256: [2.0199, -0.4716 + 0.8446j, -0.4716 - 0.8446j, 0.3629],
            512: [1.5760, -0.4737 + 0.8481j, -0.4737 - 0.8481j, 0.5282],
            1024: [1.1357, -0.4748 + 0.8499j, -0.4748 - 0.8499j, 0.7834],
            2048: [-0.4753 - 0.8507j, -0.4753 + 0.8507j, 0.9067 - 0.3136j, 0.9067 + 0.3136j],
            4096: [-0.4756 - 0.8512j, -0.4756 + 0.8512j, 0.8787 - 0.4056j, 0.8787 + 0.4056j]}
    asked = []

    def at(steps):
        asked.append(steps)
        return np.array(seen[steps], dtype=complex)

    values = floquet.refined(at, floquet.STEPS)
    assert values is not None and 4096 in asked
    assert floquet.is_stable(values) and abs(np.max(np.abs(values)) - 0.9763) <= 2e-4


def test_multipliers_are_not_paired_nearest_first_over_all_pairs():
    """A joint with a cubic spring at 0.0587 Hz, F0 = 1 N (measured): two real multipliers growing with the steps,
    0.5861 and 0.4885 at 512, 0.7473 and 0.6180 at 1024. Matched nearest first over all pairs, 0.6180 took
    0.5861 and 0.7473 took 0.4885, whose logarithm made 1.14, then 1.17 at the next pair: unstable, where 8192
    steps give 0.9795. Each with its nearest, 0.7473 has no partner until the values settle: stable, 0.98."""
    seen = {256: [0.3439 + 0.0041j, 0.3439 - 0.0041j, 0.1796 - 0.1644j, 0.1796 + 0.1644j],
            512: [0.5861, 0.4885, 0.3014 - 0.2671j, 0.3014 + 0.2671j],
            1024: [0.7473, 0.6180, 0.3899 - 0.3161j, 0.3899 + 0.3161j],
            2048: [0.8498, 0.7045, 0.4411 - 0.3295j, 0.4411 + 0.3295j],
            4096: [0.9105, 0.7531, 0.4664 - 0.3287j, 0.4664 + 0.3287j],
            8192: [0.9443, 0.7783, 0.4776 - 0.3224j, 0.4776 + 0.3224j]}
    values = floquet.refined(lambda steps: np.array(seen[steps], dtype=complex), floquet.STEPS)
    assert values is not None and floquet.is_stable(values)
    assert abs(np.max(np.abs(values)) - 0.9443**2 / 0.9105) <= 1e-9


@pytest.mark.parametrize("r, a", [(0.99, 50.0), (0.995, 20.0)])
def test_a_double_multiplier_gets_both_its_partners(r, a):
    """Three identical arms on a joint have double multipliers: with each multiplier paired to its nearest alone,
    one of the two never had a partner (both nearest the same), and every point went to 8192 steps, 7 times the
    work (a review's find). Matched nearest first, each used once, a double complex pair shrunk by backward Euler
    (r e^(0.4 i) exp(-a / M)) is found as the single one is, within 1e-3, before the finest steps."""
    asked = []

    def at(steps, count=2):
        asked.append(steps)
        mu = r * np.exp(0.4j) * math.exp(-a / steps)
        return np.array([mu, np.conj(mu)] * count)

    single = floquet.refined(lambda steps: at(steps, 1), floquet.STEPS)
    steps_single = max(asked)
    asked.clear()
    double = floquet.refined(at, floquet.STEPS)
    assert single is not None and double is not None
    assert abs(np.max(np.abs(double)) - r) <= 1e-3 and abs(np.max(np.abs(single)) - r) <= 1e-3
    assert max(asked) == steps_single < floquet.STEPS * 2**floquet.REFINEMENTS


@pytest.mark.parametrize("gap", [3e-5, 8e-5])
def test_an_unstable_multiplier_crossing_a_double_is_not_given_its_spare_copy(gap):
    """A double multiplier (0.9, two identical arms, barely shrunk) and an unstable one (1.1573, shrunk by
    backward Euler as exp(-128.7 / M)) that crosses the double at 512 steps, within ``gap`` of it: the unstable
    one took the double's spare copy at 256 steps as its partner (it is within DOUBLE of a copy at 512), was
    extrapolated to 0.9 and the point called stable (a second review's find). Three copies at 512 against two
    at 256 are not a double's: no spare copy is given, and the refinement goes on to find 1.1573."""
    def at(steps):
        double = 0.9 * math.exp(-0.005 / steps)
        crossing = double + gap if steps == 512 else 1.1573 * math.exp(-128.7 / steps)
        return np.array([crossing, double + 1e-9, double - 1e-9, 0.3 + 0.2j, 0.3 - 0.2j], dtype=complex)

    values = floquet.refined(at, floquet.STEPS)
    assert values is not None and not floquet.is_stable(values)
    assert abs(np.max(np.abs(values)) - 1.1573) <= 1e-3


@pytest.mark.slow
def test_a_point_that_stays_unstable_on_a_joint_with_a_cubic_spring_leaves_its_orbit():
    """A joint behind a massless node with a cubic spring on a (not monotone: no proof), F0 = 1 N, H = 5: the
    point near 0.1464 Hz keeps its largest multiplier about 1.08 at every resolution (unstable, not made
    unknown by the doubt rule), and integrated from its orbit's state (4096 implicit steps a period) it leaves
    it: the distance grows more than tenfold in 80 periods, where a stable neighbour's (0.131 Hz) does not."""
    from prandtl_fmu.frequency import parse_scene
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    scene = parse_scene(network_text(["a", "j", "b"], [1.0, 0.0, 1.0], [
        ("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.0}),
        ("spring", ["a", "j"], {"k": 5.0}), ("branch", ["j", "b"], {"k": 2.0, "eta": 0.05}),
        ("spring", ["j", "ground"], {"k": 0.5}), ("dashpot", ["a", "ground"], {"c": 0.02}),
        ("dashpot", ["b", "ground"], {"c": 0.02}), ("cubic", ["a", "ground"], {"k3": 0.5})], load_node="a"),
        networks=True)[0]
    curve = harmonic_response(scene, 1.0, [0.1, 0.2], harmonics=5)
    balance = HarmonicBalance(periodic_system(scene), 5, 1.0)
    growth = {}
    for target in (0.1464, 0.131):
        index = int(np.argmin(np.abs(curve.frequency - target)))
        omega = 2 * math.pi * curve.frequency[index]
        state = floquet.orbit_start(balance, curve.coefficients[index].reshape(-1)[balance.free], omega)
        distance = []
        moved = state
        for _ in range(8):
            _, moved = floquet.run_periods(balance, omega, moved, 10, 4096)
            distance.append(float(np.max(np.abs(np.array(moved[0]) - state[0]))))
        growth[target] = (bool(curve.stable[index]), curve.multiplier[index], distance[-1] / distance[0])
    unstable, stays = growth[0.1464], growth[0.131]
    assert unstable[0] is False and unstable[1] > 1.05 and unstable[2] > 10.0, unstable
    assert stays[0] is True and stays[2] < 2.0, stays
