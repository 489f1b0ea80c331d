"""Elements in series through a massless node joined into one (``frequency/series.py``): the joined network moves
as the one written with its nodes (the implicit stepper, which solves a massless node's balance at every step,
is the independent check), and a joint written as springs and sliders with their nodes has the curve and the
backbone of its branches, by harmonic balance and by shooting."""
import dataclasses
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main

from tests.analysis.test_describe_cli import read_csv
from tests.analysis.test_harmonic_balance_network_friction import network, network_text

ELEMENTS = {"spring": ("spring", {"k": 3.0}), "slider": ("slider", {"alpha": 0.4}),
            "branch": ("branch", {"k": 5.0, "eta": 0.06})}
# (stiffness, threshold) of each, as the series rules read them: a slider has no compliance, a spring no threshold
RULES = {"spring": (3.0, math.inf), "slider": (math.inf, 0.4), "branch": (5.0, 0.3)}
HELD = [("spring", ["a", "ground"], {"k": 2.0}), ("dashpot", ["a", "ground"], {"c": 0.1})]


def _run(scene):
    from prandtl_fmu.loads import HarmonicLoad
    from prandtl_fmu.network.driver import simulate
    from prandtl_fmu.scene_tables import Solver

    run = dataclasses.replace(scene, load=HarmonicLoad(1.0, 1.3), solver=Solver("implicit", 1e-3, 30.0, 0.01))
    return simulate(run, progress=False).x[:, 0]


@pytest.mark.parametrize("pair", [("spring", "slider"), ("slider", "spring"), ("spring", "branch"),
                                  ("slider", "branch"), ("branch", "branch"), ("spring", "spring")])
def test_two_elements_in_series_through_a_massless_node_are_one(tmp_path, pair):
    """A mass held to the ground by two elements in series through a massless node: joined, one element whose
    stiffness and threshold are the series rule's (written out here), and the mass's motion under a harmonic
    force is the one the implicit stepper gives the network as written (it solves the massless node's balance
    at every step), to rounding."""
    from prandtl_fmu.frequency.series import joined

    first, second = (ELEMENTS[kind] for kind in pair)
    if pair[0] == pair[1]:
        second = (second[0], {key: 1.7 * value for key, value in second[1].items()})
    text = network_text(["a", "j"], [1.0, 0.0], HELD + [(first[0], ["a", "j"], first[1]),
                                                        (second[0], ["j", "ground"], second[1])], load_node="a")
    scene = network(tmp_path, text)
    one = joined(scene)
    assert one.network.nodes == ("a",)
    (k1, a1), (k2, a2) = RULES[pair[0]], RULES[pair[1]]
    if pair[0] == pair[1]:
        k2, a2 = 1.7 * k2, 1.7 * 1.7 * a2 if pair[0] == "branch" else 1.7 * a2
    k = 1.0 / ((0.0 if math.isinf(k1) else 1.0 / k1) + (0.0 if math.isinf(k2) else 1.0 / k2))
    alpha = min(a1, a2)
    element = one.network.elements[-1]
    assert element.between == (0, -1)
    if math.isinf(alpha):
        assert element.kind == "spring" and element.value == pytest.approx(k, rel=1e-15)
    else:
        assert element.kind == "branch" and element.value == pytest.approx(k, rel=1e-15)
        assert element.value * element.eta == pytest.approx(alpha, rel=1e-15)
    written, joined_motion = _run(scene), _run(one)
    assert np.max(np.abs(written - joined_motion)) <= 1e-12 * np.max(np.abs(written))
    assert np.max(np.abs(written)) > 0.5  # the force moves it, and the branch slips (alpha <= 0.4 < 1 N)


def test_three_in_series_and_a_node_kept(tmp_path):
    """Two massless nodes in a row (spring, branch, slider) join into one branch; the same network with the
    first node named to be kept joins only the second."""
    from prandtl_fmu.frequency.series import joined

    text = network_text(["a", "j1", "j2"], [1.0, 0.0, 0.0], HELD + [
        ("spring", ["a", "j1"], {"k": 4.0}), ("branch", ["j1", "j2"], {"k": 4.0, "eta": 0.1}),
        ("slider", ["j2", "ground"], {"alpha": 0.25})], load_node="a")
    scene = network(tmp_path, text)
    one = joined(scene)
    assert one.network.nodes == ("a",)
    branch = one.network.elements[-1]
    assert (branch.kind, branch.value, branch.value * branch.eta) == ("branch", pytest.approx(2.0), pytest.approx(0.25))
    assert np.max(np.abs(_run(scene) - _run(one))) <= 1e-12 * np.max(np.abs(_run(scene)))
    assert joined(scene, keep=("j1",)).network.nodes == ("a", "j1")


def test_a_massless_node_named_has_the_stability_of_the_scene_without_it(tmp_path):
    """A mass on a spring and a dashpot (c = 0.02), and in series to the ground a spring, a branch and a spring:
    every periodic state is stable (floquet.monotone). Named by --node, the node between the first spring and
    the branch is kept for its motion (x_p = x_a / 2 while the branch sticks: the tension of the series, of
    stiffness 1, is x_a, and the first spring k = 2 carries it), and the multipliers are those of the joined
    scene: at 0.1 Hz, where the branch sticks, the damped oscillator's exp(-c T / 2 m) (it was 0.897 against
    0.905, from the finite differences of the implicit stepper with the massless node), at both ends the same as
    without --node, and every point stable (it was 1.08 to 1.15 where the branch slides)."""
    text = network_text(["a", "p1", "p2"], [1.0, 0.0, 0.0], [
        ("spring", ["a", "ground"], {"k": 1.0}), ("dashpot", ["a", "ground"], {"c": 0.02}),
        ("spring", ["a", "p1"], {"k": 2.0}), ("branch", ["p1", "p2"], {"k": 4.0, "eta": 0.05}),
        ("spring", ["p2", "ground"], {"k": 4.0})], load_node="a")
    path = tmp_path / "series.toml"
    path.write_text(text)
    tables = {}
    for named in ([], ["--node", "p1"]):
        out = tmp_path / f"curve{len(named)}.csv"
        assert main(["describe", str(path), "--force-amplitude", "0.01", "--frequencies", "0.1,0.3", *named,
                     "--out", str(out)]) == 0
        tables[len(named)] = read_csv(out)
    plain, kept = tables[0], tables[2]
    assert float(kept["amplitude"][0]) == pytest.approx(0.5 * float(kept["amplitude_a"][0]), rel=1e-9)
    assert float(kept["multiplier"][0]) == pytest.approx(math.exp(-0.01 * 10.0), rel=1e-6)
    for row in (0, -1):
        assert float(kept["multiplier"][row]) == pytest.approx(float(plain["multiplier"][row]), rel=1e-6)
    assert set(kept["stable"]) == {"true"} and max(float(m) for m in kept["multiplier"]) < 1.0
    assert max(float(a) for a in kept["amplitude_a"]) > 0.15  # through the resonance: the branch slides


@pytest.mark.slow  # 5 s: the quick suite has the extrapolation on the delay (test_harmonic_balance_memory.py)
def test_a_massless_node_that_cannot_join_has_the_linear_multiplier_where_its_branches_stick(tmp_path):
    """A massless node between two branches and a spring joins nothing: its multipliers come from the finite
    differences of the implicit stepper (backward Euler at 256 and 512 steps a period, extrapolated). Where
    both branches stick the scene is linear, whatever its stiffness the multiplier is exp(-c T / 2 m): to 3e-4
    (the extrapolation of the multipliers themselves gave 0.9018 for 0.9048 at 0.1 Hz); every point stable and
    below 1 + 2e-3 (the scene is monotone)."""
    text = network_text(["a", "p"], [1.0, 0.0], [
        ("spring", ["a", "ground"], {"k": 1.0}), ("dashpot", ["a", "ground"], {"c": 0.02}),
        ("branch", ["a", "p"], {"k": 2.0, "eta": 0.05}), ("branch", ["p", "ground"], {"k": 4.0, "eta": 0.03}),
        ("spring", ["p", "ground"], {"k": 1.0})], load_node="a")
    path = tmp_path / "node.toml"
    path.write_text(text)
    out = tmp_path / "curve.csv"
    assert main(["describe", str(path), "--force-amplitude", "0.01", "--frequencies", "0.1,0.3", "--out",
                 str(out)]) == 0
    table = read_csv(out)
    frequency, amplitude = (np.array(table[k], dtype=float) for k in ("frequency", "amplitude"))
    multiplier = np.array(table["multiplier"], dtype=float)
    # stuck, x_p = 2 x_a / 7 (2 in series with 4 + 1): the first branch's tension 10 x_a / 7 below its alpha
    # 0.1 while x_a < 0.07, the second's 8 x_a / 7 below 0.12 while x_a < 0.105
    stuck = amplitude < 0.069
    assert stuck.sum() >= 2 and (~stuck).sum() >= 5
    assert multiplier[stuck] == pytest.approx(np.exp(-0.01 / frequency[stuck]), rel=3e-4)
    assert set(table["stable"]) == {"true"} and np.all(multiplier <= 1.0 + 2e-3)


@pytest.mark.parametrize("options", [["--force-amplitude", "0.01", "--frequencies", "0.1,0.3", "--node", "zzz"],
                                     ["--force-amplitude", "0.01", "--frequencies", "0.1,0.3", "--load-node", "zzz"],
                                     ["--mode", "1", "--amplitudes", "0.01", "--node", "zzz"]])
def test_a_node_named_that_is_none_lists_the_nodes_as_written(tmp_path, capsys, options):
    """The refusal of an unknown --node or --load-node lists the network's nodes as written, massless ones
    too (it listed those left once the massless nodes were joined: a alone)."""
    path = tmp_path / "series.toml"
    path.write_text(network_text(["a", "p1", "p2"], [1.0, 0.0, 0.0], [
        ("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["a", "p1"], {"k": 2.0}),
        ("branch", ["p1", "p2"], {"k": 4.0, "eta": 0.05}), ("spring", ["p2", "ground"], {"k": 4.0})],
        load_node="a"))
    assert main(["describe", str(path), *options, "--out", str(tmp_path / "out.csv")]) == 2
    err = capsys.readouterr().err
    assert "'zzz'" in err and "(a, p1, p2)" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out.csv").exists()


IWAN_EXPLICIT = network_text(["a", "j1", "b", "j2"], [1.0, 0.0, 1.0, 0.0], [
    ("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.0}),
    ("dashpot", ["a", "ground"], {"c": 0.02}), ("dashpot", ["b", "ground"], {"c": 0.02}),
    ("spring", ["a", "j1"], {"k": 2.0}), ("slider", ["j1", "b"], {"alpha": 0.1}),
    ("slider", ["j2", "a"], {"alpha": 0.05}), ("spring", ["b", "j2"], {"k": 1.0})], load_node="a")
IWAN_BRANCHES = network_text(["a", "b"], [1.0, 1.0], [
    ("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.0}),
    ("dashpot", ["a", "ground"], {"c": 0.02}), ("dashpot", ["b", "ground"], {"c": 0.02}),
    ("branch", ["a", "b"], {"k": 2.0, "eta": 0.05}), ("branch", ["a", "b"], {"k": 1.0, "eta": 0.05})],
    load_node="a")


def test_a_joint_written_with_its_nodes_has_the_curve_and_backbone_of_its_branches(tmp_path):
    """Two Jenkins elements between two masses, each written as a spring to a massless node and a slider on
    from it (the slider was refused by harmonic balance, the massless node by shooting): from the command line
    the curve of the network of two branches, point for point, and the same backbone."""
    from prandtl_fmu.frequency.modes import nonlinear_mode

    tables = {}
    for name, text in (("explicit", IWAN_EXPLICIT), ("branches", IWAN_BRANCHES)):
        path, out = tmp_path / f"{name}.toml", tmp_path / f"{name}.csv"
        path.write_text(text)
        assert main(["describe", str(path), "--force-amplitude", "0.1", "--frequencies", "0.1,0.4",
                     "--harmonics", "5", "--out", str(out)]) == 0
        tables[name] = read_csv(out)
    assert list(tables["explicit"]) == list(tables["branches"])
    assert len(tables["explicit"]["frequency"]) == len(tables["branches"]["frequency"]) > 10
    for column in ("frequency", "amplitude", "phase", "amplitude_a", "amplitude_b"):
        assert np.allclose(np.array(tables["explicit"][column], float), np.array(tables["branches"][column], float),
                           rtol=1e-9, atol=1e-12), column
    assert tables["explicit"]["stable"] == tables["branches"]["stable"]
    backbones = [nonlinear_mode(network(tmp_path, text, f"{i}.toml"), 1, [0.01, 0.05, 0.2], harmonics=5)
                 for i, text in enumerate((IWAN_EXPLICIT, IWAN_BRANCHES))]
    assert np.allclose(backbones[0].frequency, backbones[1].frequency, rtol=1e-9)
    assert np.allclose(backbones[0].damping_ratio, backbones[1].damping_ratio, rtol=1e-7, atol=1e-12)


@pytest.mark.slow
def test_a_jenkins_element_written_with_its_node_beside_a_rigid_slider_is_shot(tmp_path):
    """A rigid slider between the masses (shooting) and a Jenkins element written with its massless node
    (refused by shooting before): the curve is the one with the element as a branch."""
    from prandtl_fmu.frequency.curve import harmonic_response

    common = [("spring", ["a", "ground"], {"k": 100.0}), ("spring", ["b", "ground"], {"k": 400.0}),
              ("slider", ["a", "b"], {"alpha": 2.0}), ("dashpot", ["b", "ground"], {"c": 0.5})]
    explicit = network_text(["a", "j", "b"], [1.0, 0.0, 2.0], common + [
        ("spring", ["a", "j"], {"k": 50.0}), ("slider", ["j", "b"], {"alpha": 1.0})], load_node="a")
    branch = network_text(["a", "b"], [1.0, 2.0], common + [("branch", ["a", "b"], {"k": 50.0, "eta": 0.02})],
                          load_node="a")
    curve = harmonic_response(network(tmp_path, explicit, "explicit.toml"), 3.0, [1.0, 3.0], stability=False)
    assert curve.method == "shooting" and len(curve.frequency) > 10
    # the branch's periodic state at some of the curve's own frequencies, each solved alone (the elements are
    # summed in another order: the rounding may move the stepping's choices, so not its points)
    scene = network(tmp_path, branch, "branch.toml")
    for index in np.linspace(0, len(curve.frequency) - 1, 6).astype(int):
        frequency = float(curve.frequency[index])
        alone = harmonic_response(scene, 3.0, [frequency], stability=False)
        assert alone.amplitude[0] == pytest.approx(curve.amplitude[index], rel=1e-6), frequency
        assert alone.amplitudes["b"][0] == pytest.approx(curve.amplitudes["b"][index], rel=1e-6), frequency


def test_the_scene_s_load_node_is_joined_where_no_force_acts_on_it(tmp_path):
    """The explicit joint with its load_node on a massless node (j2, the last): where the force acts elsewhere
    (``--load-node a``) or the support moves instead (``--base-amplitude``), j2 carries no load and joins, and
    the curve is the branches' (it was kept as the load's node, and harmonic balance refused its slider; joined,
    the network's load node pointed past its last node: an internal error)."""
    explicit = IWAN_EXPLICIT.replace('load_node = "a"', 'load_node = "j2"')
    assert explicit != IWAN_EXPLICIT
    for options in (["--force-amplitude", "0.1", "--load-node", "a"], ["--base-amplitude", "0.05"]):
        tables = []
        for name, text in (("explicit", explicit), ("branches", IWAN_BRANCHES)):
            path, out = tmp_path / f"{name}.toml", tmp_path / f"{name}.csv"
            path.write_text(text)
            assert main(["describe", str(path), *options, "--frequencies", "0.1,0.4", "--harmonics", "3",
                         "--out", str(out)]) == 0, options
            tables.append(read_csv(out))
        assert len(tables[0]["frequency"]) == len(tables[1]["frequency"]) > 10
        for column in ("frequency", "amplitude", "phase", "amplitude_a", "amplitude_b"):
            assert np.allclose(np.array(tables[0][column], float), np.array(tables[1][column], float),
                               rtol=1e-9, atol=1e-12), (options, column)


def test_a_massless_load_node_is_kept_in_the_backbone_its_synthesis_loads(tmp_path):
    """The force on the massless node j of a spring and a branch in series: the forced curve keeps j, and so
    must the backbone drawn over it, whose single-mode synthesis loads j (it was joined away there, and the
    plot failed with an internal error after the CSV was written). The mode's shape at j is the series rule's
    static split of the relative motion, (x_j - x_a) / (x_b - x_a) = k_branch / (k_spring + k_branch), while
    the branch sticks (small amplitude)."""
    from prandtl_fmu.frequency.modes import nonlinear_mode, synthesis
    from prandtl_fmu.frequency.series import joined

    text = network_text(["a", "j", "b"], [1.0, 0.0, 1.0], [
        ("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.0}),
        ("dashpot", ["a", "ground"], {"c": 0.02}), ("dashpot", ["b", "ground"], {"c": 0.02}),
        ("spring", ["a", "j"], {"k": 5.0}), ("branch", ["j", "b"], {"k": 2.0, "eta": 0.05})], load_node="a")
    scene = network(tmp_path, text)
    assert joined(scene).network.nodes == ("a", "b")  # j joins unless it is kept
    backbone = nonlinear_mode(scene, 2, [1e-3, 0.2], harmonics=1, load_node="j")  # a and b apart
    assert backbone.nodes == ("a", "j", "b")
    a, j, b = backbone.shape[0]
    assert abs((j - a) / (b - a) - 2.0 / 7.0) <= 1e-9
    frequency, amplitude = synthesis(backbone, 0.05, "j")
    assert frequency.size and np.all(np.isfinite(frequency)) and np.all(amplitude > 0)
    path, out, plot = tmp_path / "joint.toml", tmp_path / "curve.csv", tmp_path / "curve.png"
    path.write_text(text)
    assert main(["describe", str(path), "--force-amplitude", "0.05", "--frequencies", "0.1,0.2", "--load-node", "j",
                 "--mode", "2", "--amplitudes", "0.1,0.2", "--harmonics", "1", "--out", str(out),
                 "--plot", str(plot)]) == 0
    assert plot.stat().st_size > 0 and len(read_csv(out)["frequency"]) > 2


@pytest.mark.slow  # (43 s on a cold cache: the README's command stays within its 10 minutes)
def test_a_massless_node_held_by_springs_alone_is_their_schur_complement(tmp_path):
    """A massless node j held by three springs (to a, b and the ground) beside a rigid slider between a and b:
    j sits at the springs' weighted mean, so the three are springs k_i k_j / K between each pair of far ends
    (written out here: 1.5 N/m a-b, 0.6 a-ground, 1.0 b-ground), the motion the implicit stepper gives the
    network as written (it solves j's balance at every step) to rounding; and the forced response by shooting
    runs (it was refused: j is massless), the same as the hand-condensed network's. A node with one element
    carries nothing and goes."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.series import joined

    common = [("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 2.0}),
              ("dashpot", ["a", "ground"], {"c": 0.05}), ("slider", ["a", "b"], {"alpha": 0.3})]
    star = network_text(["a", "j", "b", "d"], [1.0, 0.0, 1.5, 0.0], common + [
        ("spring", ["a", "j"], {"k": 3.0}), ("spring", ["j", "b"], {"k": 5.0}), ("spring", ["ground", "j"], {"k": 2.0}),
        ("spring", ["b", "d"], {"k": 7.0})], load_node="a")
    by_hand = network_text(["a", "b"], [1.0, 1.5], common + [
        ("spring", ["a", "b"], {"k": 1.5}), ("spring", ["a", "ground"], {"k": 0.6}),
        ("spring", ["b", "ground"], {"k": 1.0})], load_node="a")
    scene, condensed = network(tmp_path, star, "star.toml"), network(tmp_path, by_hand, "hand.toml")
    one = joined(scene)
    assert one.network.nodes == ("a", "b")
    springs = sorted((e.between, e.value) for e in one.network.elements if e.kind == "spring" and "(" in e.name)
    assert springs == [((0, -1), pytest.approx(0.6)), ((1, -1), pytest.approx(1.0)), ((1, 0), pytest.approx(1.5))]
    written = _run(scene)
    assert np.max(np.abs(written - _run(one))) <= 1e-12 * np.max(np.abs(written))
    curves = [harmonic_response(s, 1.0, [0.1, 0.4], stability=False) for s in (scene, condensed)]
    assert curves[0].method == "shooting" and len(curves[0].frequency) == len(curves[1].frequency) > 5
    assert np.allclose(curves[0].amplitude, curves[1].amplitude, rtol=1e-9)


@pytest.mark.parametrize("around", [[("a", 0.0), ("b", 0.0), ("ground", 0.0)], [("a", 0.0), ("b", 1.0)]],
                         ids=["star of zero springs", "a zero spring in series"])
def test_springs_of_zero_stiffness_at_a_massless_node_carry_nothing(tmp_path, around):
    """A massless node j held by springs of which one or all have k = 0 (the scene reader takes k >= 0): the
    springs carry no force, and j goes with them, leaving nothing between their far ends (the series rule
    and the star's K = 0 divided by zero: an internal error, a review's find); the curve is the network's
    without them."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.series import joined

    common = [("spring", ["a", "ground"], {"k": 1.0}), ("dashpot", ["a", "ground"], {"c": 0.05}),
              ("spring", ["b", "ground"], {"k": 1.0}), ("slider", ["a", "b"], {"alpha": 0.2})]
    springs = [("spring", [end, "j"], {"k": k}) for end, k in around]
    scene = network(tmp_path, network_text(["a", "b", "j"], [1.0, 1.0, 0.0], common + springs, load_node="a"),
                    "with.toml")
    bare = network(tmp_path, network_text(["a", "b"], [1.0, 1.0], common, load_node="a"), "without.toml")
    one = joined(scene)
    assert one.network.nodes == ("a", "b")
    assert [(e.kind, e.between, e.value) for e in one.network.elements] == \
        [(e.kind, e.between, e.value) for e in bare.network.elements]
    curves = [harmonic_response(s, 0.1, [0.1, 0.3], stability=False) for s in (scene, bare)]
    assert np.array_equal(curves[0].amplitude, curves[1].amplitude)


def test_a_node_that_does_not_move_has_no_truncation_to_report(tmp_path):
    """A free mass (held to a massless node by a spring and a dashpot, nothing to the ground) under base
    excitation does not move: its first harmonic is rounding at every H, and its change from H = 3 to 5 is no
    change (it read 5.75e17, relative, rounding over rounding, with a warning: a review's find)."""
    from prandtl_fmu.frequency.curve import harmonic_response

    scene = network(tmp_path, network_text(["a", "j"], [1.0, 0.0], [
        ("spring", ["a", "j"], {"k": 1.0}), ("dashpot", ["a", "j"], {"c": 0.05})], load_node="a"))
    curve = harmonic_response(scene, None, [0.1, 0.3], base_amplitude=0.05, harmonics=3, stability=False)
    assert np.all(curve.amplitude < 1e-15) and curve.change is not None and curve.change < 1e-6


# a massless node j between two masses, held by springs and one threshold element (series.condensed: a lever)
LEVERED = [("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.5}),
           ("dashpot", ["a", "ground"], {"c": 0.05}), ("dashpot", ["b", "ground"], {"c": 0.08})]
ON_J = {"slider": [("spring", ["a", "j"], {"k": 2.0}), ("spring", ["j", "b"], {"k": 1.0}),
                   ("slider", ["j", "ground"], {"alpha": 0.3})],
        "branch": [("spring", ["a", "j"], {"k": 2.0}), ("spring", ["j", "b"], {"k": 1.0}),
                   ("branch", ["j", "ground"], {"k": 4.0, "eta": 0.075})],
        # j2 between j and b: condensed after j (node order), the lever then has a weight on j2
        "two nodes": [("spring", ["a", "j"], {"k": 2.0}), ("spring", ["j", "j2"], {"k": 3.0}),
                      ("spring", ["j2", "b"], {"k": 1.5}), ("spring", ["j2", "ground"], {"k": 0.5}),
                      ("slider", ["j", "ground"], {"alpha": 0.3})]}


def _levered(tmp_path, case):
    nodes, mass = (["a", "j", "b"], [1.0, 0.0, 2.0]) if case != "two nodes" else \
        (["a", "j", "j2", "b"], [1.0, 0.0, 0.0, 2.0])
    return network(tmp_path, network_text(nodes, mass, LEVERED + ON_J[case], load_node="a"), f"{case}.toml")


def _harmonic(x, t, omega):
    return 2.0 / len(t) * np.sum(x * np.exp(-1j * omega * t))


def implicit_agrees(scene, shooting, F, omega, periods, ratio=0.1, nodes="ab"):
    """Shooting's first harmonic of ``nodes`` (a and b) at omega against the implicit stepper on ``scene`` (the network
    as written) run ``periods`` periods from rest at 1000 and 2000 steps a period: the stepper's error halves
    with h (order 1, within ``ratio``) and its Richardson extrapolation lands within 5 % of that error on
    shooting's. Returns shooting's first harmonics."""
    from prandtl_fmu.loads import HarmonicLoad
    from prandtl_fmu.network.driver import simulate
    from prandtl_fmu.scene_tables import Solver

    s = shooting.solve_at(omega)
    assert s is not None
    coefficients = shooting.coefficients(s, omega)
    X = (coefficients[:, 1] - 1j * coefficients[:, 2])[[shooting.node_index(n) for n in nodes]]
    period = 2.0 * math.pi / omega
    harmonics = []
    for per in (1000, 2000):
        h = period / per
        run = dataclasses.replace(scene, load=HarmonicLoad(F, omega),
                                  solver=Solver("implicit", h, periods * period, h))
        result = simulate(run, progress=False)
        t = result.time[-per - 1:-1]
        harmonics.append(np.array([_harmonic(result.column(f"x_{n}")[-per - 1:-1], t, omega) for n in nodes]))
    coarse, fine = (np.abs(Y - X) for Y in harmonics)
    assert np.all(fine > 0) and np.all(np.abs(coarse / fine - 2.0) < ratio), (coarse, fine)
    assert np.all(np.abs(2.0 * harmonics[1] - harmonics[0] - X) < 0.05 * fine), (harmonics, X)
    return X


@pytest.mark.parametrize("case", list(ON_J))
def test_a_massless_node_on_a_slider_is_a_lever_and_moves_as_written(tmp_path, case):
    """Shooting's periodic state of the network with its massless node condensed (``series.condensed``) against
    the implicit stepper on the network as written (it solves the massless node's balance, with its slider, at
    every step), run from rest to its steady state: the stepper's error in the first harmonic of both masses
    halves with h (order 1, measured), and its Richardson extrapolation lands within 5 % of that error on the
    shooting's (an error of the condensation's weights or compliance would leave a gap of its own)."""
    from prandtl_fmu.frequency.series import condensed
    from prandtl_fmu.frequency.shooting import NetworkShooting

    scene = _levered(tmp_path, case)
    lever = condensed(scene, None, "a")
    assert lever.network.nodes == ("a", "b") and [e.kind for e in lever.network.elements].count("lever") == 1
    if case == "slider":  # the closed form: weights k_i / S, stiffness S (a rigid slider), spring k_a k_b / S
        element = next(e for e in lever.network.elements if e.kind == "lever")
        assert element.weights == pytest.approx((2.0 / 3.0, 1.0 / 3.0), rel=1e-15)
        assert (element.value, element.alpha) == (pytest.approx(3.0, rel=1e-15), 0.3)
        assert next(e.value for e in lever.network.elements if e.name == "j(b,a)") == pytest.approx(2.0 / 3.0)
    F, omega = 1.0, 1.3
    X = implicit_agrees(scene, NetworkShooting(lever, F, None, 1024, 7, omega), F, omega, 80)
    assert np.min(np.abs(X)) > 0.3  # both masses move (the slider slips: 0.3 N against springs of 3 N/m)


def test_a_massless_node_on_a_slider_with_springs_to_one_mass_is_its_branch(tmp_path):
    """From the command line, a mass with a massless node on a slider (refused by shooting before): the curve's
    every point is the periodic state of the mass with the branch worked out by hand (the node's springs 1 to
    the mass and 0.5 to the ground: a spring 1/3 to the ground, and the slider through the lever 2/3: a branch
    k = 2/3, eta = 0.1), which shooting solves for at the point's frequency; the backbone is the branch's."""
    from prandtl_fmu.frequency.modes import nonlinear_mode
    from prandtl_fmu.frequency.shooting import NetworkShooting, prepared_network

    common = [("spring", ["a", "ground"], {"k": 1.0}), ("dashpot", ["a", "ground"], {"c": 0.05})]
    written = network_text(["a", "b"], [1.0, 0.0], common + [
        ("spring", ["a", "b"], {"k": 1.0}), ("slider", ["b", "ground"], {"alpha": 0.1}),
        ("spring", ["b", "ground"], {"k": 0.5})], load_node="a")
    hand = network_text(["a"], [1.0], common + [
        ("spring", ["a", "ground"], {"k": 1.0 / 3.0}), ("branch", ["a", "ground"], {"k": 2.0 / 3.0, "eta": 0.1}),
        ("slider", ["a", "ground"], {"alpha": 0.0})], load_node="a")  # alpha 0: carries nothing
    path, out = tmp_path / "written.toml", tmp_path / "written.csv"
    path.write_text(written)
    assert main(["describe", str(path), "--force-amplitude", "0.2", "--frequencies", "0.1,0.3",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    frequency, amplitude = (np.array(table[column], float) for column in ("frequency", "amplitude"))
    assert len(frequency) > 10 and set(table["stable"]) == {"true"}
    assert "amplitude_a" in table and "amplitude_b" not in table  # the massless node's motion is not computed
    shooting = NetworkShooting(prepared_network(network(tmp_path, hand, "hand.toml")), 0.2, None, 1024, 7, 1.0)
    for f, A in zip(frequency, amplitude):
        omega = 2.0 * math.pi * f
        s = shooting.solve_at(omega)
        assert abs(abs(shooting.first_harmonic(s, omega)) - A) <= 1e-6 * A, f
    assert np.max(amplitude) > 5 * amplitude[0]  # the resonance is on the curve
    # and its nonlinear mode (EPMC by shooting, slider_modes.py) is the branch's
    backbones = [nonlinear_mode(network(tmp_path, text, f"mode{i}.toml"), 1, [0.05, 0.2, 1.0])
                 for i, text in enumerate((written, hand))]
    assert np.allclose(backbones[0].frequency, backbones[1].frequency, rtol=1e-7)
    assert np.allclose(backbones[0].damping_ratio, backbones[1].damping_ratio, rtol=1e-6)
    assert backbones[0].nodes == ("a",) and np.ptp(backbones[0].frequency) > 0.1 * backbones[0].frequency[0]


@pytest.mark.parametrize("elements, options, culprit", [
    (ON_J["slider"] + [("slider", ["j", "b"], {"alpha": 0.2})], [], "node j is massless between slider_1 and"),
    (ON_J["slider"] + [("dashpot", ["j", "b"], {"c": 0.2})], [], "node j is massless, with dashpot"),
    (ON_J["slider"], ["--load-node", "j"], "node j is massless, with slider slider_1 on it, and the force acts on it"),
    (ON_J["slider"] + [("spring", ["j", "k"], {"k": 1.0}), ("spring", ["k", "b"], {"k": 1.0})], ["--load-node", "k"],
     "node j is massless, with slider slider_1 on it, and the force acts on it (through it from k)"),
    (ON_J["slider"] + [("spring", ["j", "k"], {"k": 1.0}), ("slider", ["k", "b"], {"alpha": 0.1})], ["--node", "k"],
     "--node: k is massless and moves with massless j, between slider_1 and slider_2 (through massless k)")],
    ids=["two sliders", "dashpot", "loaded", "loaded through", "named through two sliders"])
def test_what_a_massless_node_on_a_slider_cannot_be_is_one_line(tmp_path, capsys, elements, options, culprit):
    """A massless node loaded is taken where springs alone hold it, one named where springs and one slider or
    branch at most do, and each massless node their force or motion passes through: else one line names it
    (and the node it came from)."""
    path, out = tmp_path / "scene.toml", tmp_path / "out.csv"
    through = any("k" in e[1] for e in elements)  # k before j: condensed first, springs alone hold it
    nodes, mass = (["a", "k", "j", "b"], [1.0, 0.0, 0.0, 2.0]) if through else (["a", "j", "b"], [1.0, 0.0, 2.0])
    path.write_text(network_text(nodes, mass, LEVERED + elements, load_node="a"))
    assert main(["describe", str(path), "--force-amplitude", "1", "--frequencies", "0.1,0.2", "--out", str(out),
                 *options]) == 2
    err = capsys.readouterr().err
    assert culprit in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert not out.exists()


@pytest.mark.parametrize("ka, kb", [(1.0, 2.0), (0.7, 1.3), (0.1, 0.2), (3.0, 0.3)])
def test_a_cluster_of_massless_nodes_hung_from_one_passes_it_no_force_whatever_its_springs(ka, kb):
    """Massless j0 and j1 (a slider between them) hang from massless j2 alone: they pass it no force, so j2 is
    held by its springs and its own slider only, whatever the cluster's springs (the lever of the inner slider
    had a weight of rounding on j2, 1e-17, which refused some stiffnesses for two thresholds: a review's find).
    j2's slider is then the lever of weights k_i / S on a and b."""
    from prandtl_fmu.frequency.series import condensed
    from prandtl_fmu.network.model import Element, Network, NetworkScene

    elements = (Element("spring", "ka", (2, 3), ka), Element("spring", "kb", (2, 4), kb),
                Element("slider", "inner", (2, 3), 0.2), Element("spring", "kc", (3, 4), 1.0),
                Element("spring", "s2a", (4, 0), 1.0), Element("spring", "s2b", (4, 1), 1.5),
                Element("slider", "outer", (4, -1), 0.3), Element("spring", "ga", (0, -1), 1.0),
                Element("spring", "gb", (1, -1), 1.0))
    written = Network(("a", "b", "j0", "j1", "j2"), np.array([1.0, 2.0, 0.0, 0.0, 0.0]), np.zeros(5), np.zeros(5),
                      elements, 0)
    levers = [e for e in condensed(NetworkScene("x", written, None, None, "x.toml")).network.elements
              if e.kind == "lever"]
    assert [lever.name for lever in levers] == ["outer"]
    assert levers[0].between == (0, 1) and levers[0].weights == pytest.approx((0.4, 0.6), rel=1e-15)


CHAIN_OF_TWO = network_text(["a", "j", "j2", "b"], [1.0, 0.0, 0.0, 2.0], HELD + [
    ("spring", ["b", "ground"], {"k": 1.0}), ("spring", ["a", "j"], {"k": 1.0}), ("spring", ["j", "j2"], {"k": 1.0}),
    ("spring", ["j2", "b"], {"k": 1.0}), ("slider", ["j", "ground"], {"alpha": 0.3}),
    ("slider", ["j2", "ground"], {"alpha": 0.3}), ("slider", ["j", "b"], {"alpha": 0.0})], load_node="a")


@pytest.mark.parametrize("options, culprit", [
    (["--force-amplitude", "1", "--frequencies", "0.1,0.2"],
     "node j2 is massless between slider_2 and slider_1 (through massless j)"),
    (["--force-amplitude", "1", "--frequencies", "0.1,0.2", "--node", "zz"], "scene.toml (a, j, j2, b)"),
    (["--force-amplitude", "1", "--frequencies", "0.1,0.2", "--load-node", "zz"], "(a, j, j2, b)"),
    (["--mode", "1", "--amplitudes", "0.1", "--node", "j"],
     "--node: j is massless and moves with massless j2, between slider_2 and slider_1 (through massless j): the "
     "nonlinear modes of"),
    (["--force-amplitude", "1", "--frequencies", "0.1,0.2", "--node", "j", "--load-node", "j"],
     "node j is massless, with slider slider_1 on it, and the force acts on it")],
    ids=["a lever through a node", "--node", "--load-node", "modes", "loaded on a slider"])
def test_a_massless_node_s_refusals_name_what_the_scene_wrote(tmp_path, capsys, options, culprit):
    """A second slider that reaches a massless node through another is named with that node; an unknown node is
    listed against every node written (the condensed ones too); a refusal of the modes says modes. The slider of
    alpha = 0 on j carries nothing and is not counted (review items)."""
    path, out = tmp_path / "scene.toml", tmp_path / "out.csv"
    path.write_text(CHAIN_OF_TWO)
    assert main(["describe", str(path), *options, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert culprit in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert not out.exists()


# the force on massless j, held by springs alone (to a, b and the ground), beside a rigid slider between a and b
STAR = [("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 2.0}),
        ("dashpot", ["a", "ground"], {"c": 0.05}), ("dashpot", ["b", "ground"], {"c": 0.05}),
        ("slider", ["a", "b"], {"alpha": 0.3}), ("spring", ["a", "j"], {"k": 3.0}),
        ("spring", ["j", "b"], {"k": 5.0}), ("spring", ["ground", "j"], {"k": 2.0})]


def test_a_massless_node_held_by_springs_may_be_loaded_and_named(tmp_path):
    """The force on massless j, held by springs alone, and j's motion asked for (both refused before: shooting
    needs a mass at every node): j's balance puts it at (3 x_a + 5 x_b + F) / 10 and passes 3/10 of the force to
    a and 5/10 to b. Shooting's first harmonics of a, b and j are the implicit stepper's on the network as written
    (which solves j's balance at every step) by Richardson extrapolation; from the command line the curve's
    amplitude and phase are j's, its load node j."""
    from prandtl_fmu.frequency.shooting import NetworkShooting, prepared

    scene = network(tmp_path, network_text(["a", "j", "b"], [1.0, 0.0, 1.5], STAR, load_node="j"), "star.toml")
    condensed, observed = prepared(scene, "j", "j", observe=True)
    assert condensed.network.nodes == ("a", "b")
    assert observed.load == {"a": pytest.approx(0.3), "b": pytest.approx(0.5)}
    weights, gain, tensions = observed.views["j"]
    assert weights == {"a": pytest.approx(0.3), "b": pytest.approx(0.5), None: pytest.approx(0.2)}
    assert gain == pytest.approx(0.1) and tensions == {}
    F, omega = 1.0, 2.0 * math.pi * 0.2
    shooting = NetworkShooting(condensed, F, None, 1024, 7, omega, "j", observed)
    X = implicit_agrees(scene, shooting, F, omega, 80, nodes="abj")
    out = tmp_path / "star.csv"
    assert main(["describe", str(tmp_path / "star.toml"), "--force-amplitude", str(F), "--frequencies", "0.2",
                 "--node", "j", "--out", str(out)]) == 0
    table = read_csv(out)
    assert float(table["amplitude"][0]) == pytest.approx(abs(X[2]), rel=1e-6)
    assert float(table["phase"][0]) == pytest.approx(float(np.angle(X[2])), abs=1e-6)
    assert "amplitude_j" not in table and "amplitude_a" in table


@pytest.mark.parametrize("seed", range(6))
def test_what_a_cluster_of_massless_nodes_held_by_springs_passes_on_is_its_schur_complement(seed):
    """Random springs among two nodes with a mass, three massless ones and the ground, the force on one massless
    node and the motion of another asked for: the shares of the force on the nodes with a mass and the named
    node's weights and gain are those of the Schur complement, written here with numpy: with K the stiffness
    over (masses m, massless z), z = K_zz^-1 (f_z - K_zm x_m), the force K_mz K_zz^-1 f_z passed on."""
    from prandtl_fmu.frequency.series import condensed
    from prandtl_fmu.network.model import Element, Network, NetworkScene

    rng = np.random.default_rng(seed)
    names = ("a", "b", "j0", "j1", "j2")
    elements, K = [], np.zeros((6, 6))  # the ground last
    for p in range(5):
        for q in list(range(p + 1, 5)) + [-1]:
            if (p < 2 and 0 <= q < 2) or rng.random() < 0.4:  # no spring between the masses, a share of none
                continue
            k = float(rng.uniform(0.5, 3.0))
            elements.append(Element("spring", f"s{p}{q}", (p, q), k))
            for i, j in ((p, p), (q, q), (p, q), (q, p)):
                K[i, j] += k if i == j else -k
    for z in range(2, 5):  # every massless node held: a spring to the ground at least
        if K[z, z] == 0.0:
            elements.append(Element("spring", f"g{z}", (z, -1), 1.0))
            K[z, z] += 1.0
            K[z, 5] -= 1.0
            K[5, z] -= 1.0
            K[5, 5] += 1.0
    elements += [Element("slider", "rub", (0, 1), 0.2), Element("spring", "ga", (0, -1), 1.0)]
    written = Network(names, np.array([1.0, 2.0, 0.0, 0.0, 0.0]), np.zeros(5), np.zeros(5), tuple(elements), 2)
    _, observed = condensed(NetworkScene("x", written, None, None, "x.toml"), "j1", "j0", observe=True)
    m, z = [0, 1], [2, 3, 4]
    inverse = np.linalg.inv(K[np.ix_(z, z)])
    passed = -K[np.ix_(m, z)] @ inverse[:, 0]  # of a unit force on j0
    for node, share in zip("ab", passed):
        assert observed.load.get(node, 0.0) == pytest.approx(share, rel=1e-12, abs=1e-15)
    weights, gain, tensions = observed.views["j1"]
    row = -inverse[1] @ K[np.ix_(z, m + [5])]  # j1's weights on a, b and the ground
    for node, weight in zip(["a", "b", None], row):
        assert weights.get(node, 0.0) == pytest.approx(weight, rel=1e-12, abs=1e-15)
    assert gain == pytest.approx(inverse[1, 0], rel=1e-12) and tensions == {}


def test_the_backbone_at_a_massless_node_held_by_springs_is_the_mode_s_at_its_weighted_mean(tmp_path):
    """The nonlinear mode (EPMC by shooting) asked for at massless j, held by springs alone (refused before):
    the backbone at node a at amplitudes where the slider sticks and slips, then at j at the amplitudes j has on
    those points (x_j = 0.3 x_a + 0.5 x_b, worked out by hand from the springs): the same frequencies and damping
    ratios, to 1e-9, and j's column of the shape is 1 (its amplitude). From the command line too."""
    from prandtl_fmu.frequency.modes import nonlinear_mode

    text = network_text(["a", "j", "b"], [1.0, 0.0, 1.5], STAR, load_node="j")
    scene = network(tmp_path, text, "star.toml")
    amplitudes = np.array([0.5, 2.0, 5.0])
    at_a = nonlinear_mode(scene, 1, amplitudes, node="a")
    assert np.ptp(at_a.damping_ratio) > 0.1 * at_a.damping_ratio[0]  # the slider slips on some of them
    at_j = nonlinear_mode(scene, 1, np.abs(0.3 * at_a.shape[:, 0] + 0.5 * at_a.shape[:, 1]) * amplitudes, node="j")
    assert at_j.node == "j" and at_j.nodes == ("a", "b", "j")
    assert np.allclose(at_j.frequency, at_a.frequency, rtol=1e-9, atol=0.0)
    assert np.allclose(at_j.damping_ratio, at_a.damping_ratio, rtol=1e-9, atol=0.0)
    assert np.allclose(np.abs(at_j.shape[:, 2]), 1.0, rtol=1e-12)
    out = tmp_path / "mode.csv"
    assert main(["describe", str(tmp_path / "star.toml"), "--mode", "1", "--amplitudes", "0.4,1.5", "--node", "j",
                 "--out", str(out)]) == 0
    assert len(read_csv(out)["frequency"]) == 2


# (each case is 80 periods of the implicit stepper twice: the one through two massless nodes in the quick suite)
@pytest.mark.parametrize("case", [pytest.param(case, marks=pytest.mark.slow) if case != "two nodes" else case
                                  for case in ON_J])
def test_a_massless_node_on_a_slider_named_moves_as_written(tmp_path, case):
    """--node j, massless and held by springs and a slider or a branch (refused before): its motion is its
    springs' weighted mean less the lever's tension times d_j / S, the tension k u of the lever's branch along
    the orbit (``network_orbit.run`` writes u too); j's first harmonic, with a's and b's, is the implicit
    stepper's on the network as written by Richardson extrapolation (through a second massless node too)."""
    from prandtl_fmu.frequency.shooting import NetworkShooting, prepared

    scene = _levered(tmp_path, case)
    F, omega = 1.0, 2.0 * math.pi * 0.2
    condensed, observed = prepared(scene, "j", "a", observe=True)
    assert list(observed.views["j"][2]) == ["slider_1" if case != "branch" else "branch_1"]
    implicit_agrees(scene, NetworkShooting(condensed, F, None, 1024, 7, omega, "a", observed), F, omega, 80,
                    nodes="abj")


@pytest.mark.parametrize("case", ["branch", pytest.param("slider", marks=pytest.mark.slow), "two nodes"])
def test_the_backbone_at_a_massless_node_on_a_slider_is_its_motion_along_the_mode(tmp_path, case):
    """--mode at massless j held by springs and a slider or a branch (refused before: j's motion needs that
    lever's tension along the mode). j's first harmonic in the mode's equations is the forced response's at the
    same state and damping (``NetworkShooting.coefficients`` with ``series.Observed``, which the tests above
    hold against the implicit stepper on the network as written). The backbone at j is the one at a node with a
    mass, at that node's amplitudes along it (one family, two parametrisations): the same frequencies and
    damping ratios to 1e-5, j's column of the shape of modulus 1. On a rigid
    slider j stands still while the slider sticks, where the mode starts: the family starts at the amplitude of
    the node with a mass that moves most, and its phase is that node's (j's is not defined while it stands)."""
    from prandtl_fmu.frequency.modes import nonlinear_mode
    from prandtl_fmu.frequency.shooting import NetworkShooting, prepared
    from prandtl_fmu.frequency.slider_modes import _family_equations, _free_systems

    scene = _levered(tmp_path, case)
    condensed, observed = prepared(scene, "j", None, observe=True)
    weights, _, tensions = observed.views["j"]
    assert tensions
    nodes = condensed.network.nodes
    probe = np.array([weights.get(node, 0.0) for node in nodes])
    _, make = _free_systems(condensed, probe, "j", tensions)
    free = make(128, 1.0)
    forced = NetworkShooting(condensed, 0.0, None, 128, 7, 1.0, None, observed)
    rng = np.random.default_rng(3)
    for _ in range(3):
        s = rng.normal(0.0, 0.3, free.dimension)
        omega, xi = rng.uniform(0.6, 1.4), rng.uniform(0.0, 0.1)
        node = _family_equations(free, np.concatenate((s, [omega, xi])))[2]
        forced.damping = free.viscous - xi * np.diag(free.system.mass)
        row = forced.coefficients(s, omega)[forced.node_index("j")]
        assert node == pytest.approx(complex(row[1], -row[2]), rel=1e-12, abs=1e-14)
    amplitudes = np.array([0.05, 0.3, 1.0])
    at_j = nonlinear_mode(scene, 1, amplitudes, node="j")
    assert at_j.node == "j" and np.allclose(np.abs(at_j.shape[:, at_j.nodes.index("j")]), 1.0, rtol=1e-12)
    assert np.ptp(at_j.damping_ratio) > 0.1 * np.max(np.abs(at_j.damping_ratio))  # the lever slips on some
    other = max("ab", key=lambda name: abs(at_j.shape[0, at_j.nodes.index(name)]))
    at_other = nonlinear_mode(scene, 1, np.abs(at_j.shape[:, at_j.nodes.index(other)]) * at_j.amplitude,
                              node=other)
    # (each refined by doubling its samples to the default tolerance: 1e-16 to 1.4e-6 apart, measured)
    assert np.allclose(at_other.frequency, at_j.frequency, rtol=1e-5, atol=0.0)
    assert np.allclose(at_other.damping_ratio, at_j.damping_ratio, rtol=1e-5, atol=0.0)


def test_a_massless_node_held_by_a_slider_that_sticks_stands_still_at_its_node(tmp_path):
    """--node at a massless node p between a spring (2 N/m, to the mass) and a slider (0.1 N, to the ground): the
    slider sticks while 2 |x_a| < 0.1, and p stands still. Its first harmonic is then rounding against rounding,
    whose relative change between resolutions (5e280) refused the curve whatever the tolerance (a review's
    find); now p's amplitude is 0 to rounding there, and the mass's is that of the same mass with the Jenkins
    branch k = 2, eta = 0.05 the node and its slider make, at both ends."""
    common = [("spring", ["ground", "a"], {"k": 1.0}), ("dashpot", ["ground", "a"], {"c": 0.02})]
    written = network_text(["a", "p"], [1.0, 0.0], common + [
        ("spring", ["a", "p"], {"k": 2.0}), ("slider", ["p", "ground"], {"alpha": 0.1})], load_node="a")
    branch = network_text(["a"], [1.0], common + [("branch", ["a", "ground"], {"k": 2.0, "eta": 0.05})],
                          load_node="a")
    tables = {}
    for name, text, options in (("written", written, ["--node", "p"]), ("branch", branch, [])):
        path, out = tmp_path / f"{name}.toml", tmp_path / f"{name}.csv"
        path.write_text(text)
        assert main(["describe", str(path), "--force-amplitude", "0.1", "--frequencies", "0.12,0.2",
                     "--out", str(out)] + options) == 0
        tables[name] = {column: np.array(values, float) for column, values in read_csv(out).items()
                        if column not in ("stable", "fold")}
    at_p, at_a = tables["written"]["amplitude"], tables["written"]["amplitude_a"]
    stuck, slipping = at_a < 0.045, at_a > 0.055
    assert np.any(stuck) and np.any(slipping)
    assert np.all(at_p[stuck] <= 1e-12 * at_a[stuck]) and np.all(at_p[slipping] > 1e-4)
    for end in (0, -1):
        assert tables["written"]["frequency"][end] == pytest.approx(tables["branch"]["frequency"][end], rel=1e-12)
        assert at_a[end] == pytest.approx(tables["branch"]["amplitude"][end], rel=2e-3)


# a massless node j held by springs and one dashpot, in a network that a slider between the masses sends to
# shooting (series._maxwell)
def _shot(tmp_path, nodes, mass, elements, name, named=None, F=1.0, omega=1.1):
    """``(the network with its massless nodes condensed, the first harmonics of x at a and b, and at ``named``
    too)``: the network of ``elements`` loaded at a by F cos(omega t), by shooting on its exact motion (``named``:
    a massless node kept for its motion, ``series.Observed``)."""
    from prandtl_fmu.frequency.series import condensed
    from prandtl_fmu.frequency.shooting import NetworkShooting, prepared

    scene = network(tmp_path, network_text(nodes, mass, elements, load_node="a"), name)
    if named is None:
        joined = condensed(scene, None, "a")
        shooting = NetworkShooting(joined, F, None, 1024, 7, omega)
    else:
        joined, observed = prepared(scene, named, "a", observe=True)
        shooting = NetworkShooting(joined, F, None, 1024, 7, omega, "a", observed)
    state = shooting.solve_at(omega)
    assert state is not None
    coefficients = shooting.coefficients(state, omega)
    rows = [shooting.node_index(node) for node in ("a", "b") + ((named,) if named else ())]
    return joined, coefficients[rows, 1] - 1j * coefficients[rows, 2]


VISCOUS_J = {"maxwell": [("spring", ["a", "j"], {"k": 2.0}), ("dashpot", ["j", "b"], {"c": 0.6})],
             "zener": [("spring", ["a", "j"], {"k": 2.0}), ("spring", ["j", "ground"], {"k": 1.0}),
                       ("dashpot", ["j", "b"], {"c": 0.6})],
             "to the ground": [("spring", ["a", "j"], {"k": 2.0}), ("spring", ["j", "b"], {"k": 0.7}),
                               ("dashpot", ["ground", "j"], {"c": 0.6})]}


@pytest.mark.parametrize("case", list(VISCOUS_J))
def test_a_massless_node_between_springs_and_a_dashpot_beside_a_slider_is_the_light_node_s_limit(tmp_path, case):
    """A massless node j held by springs and one dashpot, nothing else on it, in a network that a slider between
    the masses sends to shooting: j was refused ("a first-order motion"). Its balance makes the springs their
    Schur complement and a lever on their weighted mean less the dashpot's end, of stiffness S = sum k_i, with
    that series dashpot and a range it never reaches (``series._maxwell``; one spring: the Maxwell element
    between a and b). Against the same network with a light mass mu on j, solved as written (j a node of the
    orbit, its dashpot a dashpot): the first harmonics of a and b at a frequency where the slider slips move by
    O(mu) (halved with mu, to 5 %), and the extrapolation 2 X(mu) - X(2 mu) lands within 2 % of that move on the
    massless node's (measured 0.02 to 0.4 %; with the dashpot 17 % off, the gap stays as large as the move).
    And the curve from the command line, every point stable (all of it dissipates)."""
    from prandtl_fmu.frequency.series import NEVER

    elements = LEVERED + VISCOUS_J[case] + [("slider", ["a", "b"], {"alpha": 0.2})]

    def first_harmonics(mu):
        return _shot(tmp_path, ["a", "j", "b"], [1.0, mu, 2.0], elements, f"viscous-{mu!r}.toml")

    joined, X = first_harmonics(0.0)
    assert joined.network.nodes == ("a", "b")
    (lever,) = [e for e in joined.network.elements if e.kind == "lever"]
    springs = [values["k"] for kind, _, values in VISCOUS_J[case] if kind == "spring"]
    assert (lever.value, lever.c, lever.alpha / lever.value) == (sum(springs), 0.6, NEVER)
    assert np.min(np.abs(X)) > 0.2 and abs(X[0] - X[1]) > 0.05  # both move, and not as one: the slider slips
    (_, heavier), (_, light) = first_harmonics(2e-3), first_harmonics(1e-3)
    moved = np.abs(light - X)
    assert np.all(moved > 1e-5) and np.all(np.abs(np.abs(heavier - X) / moved - 2.0) < 0.1), (heavier, light, X)
    assert np.all(np.abs(2.0 * light - heavier - X) < 0.02 * moved), (heavier, light, X)
    path, out = tmp_path / "viscous-cli.toml", tmp_path / "viscous.csv"
    path.write_text(network_text(["a", "j", "b"], [1.0, 0.0, 2.0], elements, load_node="a"))
    assert main(["describe", str(path), "--force-amplitude", "1", "--frequencies", "0.1,0.3",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    assert len(table["frequency"]) > 10 and set(table["stable"]) == {"true"}


BINGHAM_J = {"to the ground": [("spring", ["a", "j"], {"k": 2.0}), ("spring", ["j", "b"], {"k": 0.7}),
                               ("slider", ["j", "ground"], {"alpha": 0.15}), ("dashpot", ["ground", "j"], {"c": 0.6})],
             "between the masses": [("spring", ["a", "j"], {"k": 2.0}), ("slider", ["j", "b"], {"alpha": 0.15}),
                                    ("dashpot", ["b", "j"], {"c": 0.6})]}
# a lever with a dashpot passed on through a second massless node (k its springs: compliances in series add)
PASSED_ON = {"bingham": [("spring", ["a", "j"], {"k": 2.0}), ("spring", ["j", "i"], {"k": 1.5}),
                         ("spring", ["i", "b"], {"k": 3.0}), ("slider", ["i", "ground"], {"alpha": 0.15}),
                         ("dashpot", ["ground", "i"], {"c": 0.6})],
             "series dashpot": [("spring", ["a", "j"], {"k": 2.0}), ("spring", ["j", "b"], {"k": 0.7}),
                                ("branch", ["j", "ground"], {"k": 4.0, "eta": 0.05, "c": 0.6})]}


@pytest.mark.parametrize("case", list(BINGHAM_J))
def test_a_massless_node_on_a_slider_and_a_dashpot_side_by_side_is_the_light_node_s_limit(tmp_path, case):
    """A massless node j held by springs and by a slider and a dashpot side by side to one end (a Bingham element
    in series with the springs), in a network that a slider between the masses sends to shooting: j was refused
    ("a first-order motion"). Its balance makes the springs their Schur complement and a lever of stiffness S =
    sum k_i whose u sticks within alpha / S and, past it, relaxes back at S / c (``series._bingham``). Against
    the same network with a light mass mu on j, solved as written (j a node of the orbit, its slider and dashpot
    ordinary ones): the first harmonics of a and b move by O(mu) (halved with mu, to 5 %), and 2 X(mu) - X(2 mu)
    lands within 2 % of that move on the massless node's (measured 0.08 to 0.4 %). The slider both sticks and
    slips on the orbit: held (alpha = 100) or let go (alpha = 1e-9) it moves a and b by 0.04 to 1.3. Two
    dashpots of c / 2 side by side are the one of c. And the curve from the command line, every point stable
    (all of it dissipates)."""
    def first_harmonics(mu, alpha=None, joint=BINGHAM_J[case]):
        elements = LEVERED + [(kind, between, {"alpha": alpha} if kind == "slider" and alpha else values)
                              for kind, between, values in joint] + [("slider", ["a", "b"], {"alpha": 0.2})]
        return _shot(tmp_path, ["a", "j", "b"], [1.0, mu, 2.0], elements, f"bingham-{mu!r}-{alpha!r}-{len(joint)}.toml")

    joined, X = first_harmonics(0.0)
    assert joined.network.nodes == ("a", "b")
    (lever,) = [e for e in joined.network.elements if e.kind == "lever"]
    springs = sum(values["k"] for kind, _, values in BINGHAM_J[case] if kind == "spring")
    assert (lever.value, lever.alpha, lever.c, lever.bingham) == (springs, 0.15, 0.6, True)
    for alpha in (100.0, 1e-9):  # held, let go: the orbit's slips and sticks both count
        assert np.max(np.abs(first_harmonics(0.0, alpha)[1] - X)) > 0.04
    halves = [(kind, between, {"c": 0.3}) if kind == "dashpot" else (kind, between, values)
              for kind, between, values in BINGHAM_J[case]]
    halves += [(kind, list(reversed(between)), values) for kind, between, values in halves if kind == "dashpot"]
    halved = first_harmonics(0.0, joint=halves)[1]
    assert np.max(np.abs(halved - X)) < 1e-12  # two dashpots of c / 2 side by side are one of c
    (_, heavier), (_, light) = first_harmonics(2e-3), first_harmonics(1e-3)
    moved = np.abs(light - X)
    assert np.all(moved > 1e-5) and np.all(np.abs(np.abs(heavier - X) / moved - 2.0) < 0.1), (heavier, light, X)
    assert np.all(np.abs(2.0 * light - heavier - X) < 0.02 * moved), (heavier, light, X)
    path, out = tmp_path / "bingham-cli.toml", tmp_path / "bingham.csv"
    path.write_text(network_text(["a", "j", "b"], [1.0, 0.0, 2.0], LEVERED + BINGHAM_J[case] + [
        ("slider", ["a", "b"], {"alpha": 0.2})], load_node="a"))
    assert main(["describe", str(path), "--force-amplitude", "1", "--frequencies", "0.1,0.3",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    assert len(table["frequency"]) > 10 and set(table["stable"]) == {"true"}


NAMED_ON_A_DASHPOT = {"zener": VISCOUS_J["zener"], "bingham": BINGHAM_J["between the masses"],
                      "series dashpot": PASSED_ON["series dashpot"]}


@pytest.mark.parametrize("case", list(NAMED_ON_A_DASHPOT))
def test_a_massless_node_named_on_a_dashpot_moves_as_the_light_node(tmp_path, capsys, case):
    """--node j, massless and held by springs and a dashpot (a standard linear solid), by springs and a slider
    and a dashpot side by side, or by springs and a branch with a series dashpot (refused before: its motion
    needs the lever's u, a state of the orbit's series rows): x_j is the springs' weighted mean less the lever's
    tension over S (``network_orbit.run`` writes the series rows' u too). Against the same network with a light
    mass mu on j, where j is a node of the orbit: j's first harmonic moves by O(mu) (halved, to 10 %) and 2
    X(mu) - X(2 mu) lands within 5 % of that move on the massless node's. The nonlinear modes refuse such a
    node in one line (their start has no state for the lever's u)."""
    from prandtl_fmu.frequency.shooting import prepared

    elements = LEVERED + NAMED_ON_A_DASHPOT[case] + [("slider", ["a", "b"], {"alpha": 0.2})]

    def first_harmonic(mu):
        return None, complex(_shot(tmp_path, ["a", "j", "b"], [1.0, mu, 2.0], elements, f"named-{mu!r}.toml",
                                   named="j")[1][2])

    _, observed = prepared(network(tmp_path, network_text(["a", "j", "b"], [1.0, 0.0, 2.0], elements,
                                                          load_node="a"), "named.toml"), "j", "a", observe=True)
    _, X = first_harmonic(0.0)
    assert len(observed.views["j"][2]) == 1 and abs(X) > 0.1  # one lever's tension moves j
    mu = 2.5e-4 if case == "series dashpot" else 1e-3
    (_, heavier), (_, light) = first_harmonic(2 * mu), first_harmonic(mu)
    moved = abs(light - X)
    assert moved > 1e-6 and abs(abs(heavier - X) / moved - 2.0) < 0.2, (heavier, light, X)
    assert abs(2.0 * light - heavier - X) < 0.05 * moved, (heavier, light, X)
    path = tmp_path / "named.toml"
    path.write_text(network_text(["a", "j", "b"], [1.0, 0.0, 2.0], elements, load_node="a"))
    assert main(["describe", str(path), "--mode", "1", "--amplitudes", "0.1", "--node", "j"]) == 2
    err = capsys.readouterr().err
    assert "--node: j is massless, on the lever" in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("case", list(PASSED_ON))
def test_a_lever_with_a_dashpot_passed_on_is_the_light_nodes_limit(tmp_path, case):
    """A Bingham element on massless node i held by springs to j and b, j massless too (between a and i), and a
    branch with a series dashpot on massless node j: all in series, the compliances add and the dashpot stays
    where it is (beside the slider, or in series with it), so each is one lever with its dashpot
    (``series._levered``). Both were refused ("a first-order motion"). Against the same network with light
    masses mu on the massless nodes, solved as written: the first harmonics move by O(mu) (halved with mu, to 5 %)
    and 2 X(mu) - X(2 mu) lands within 5 % of that move on the massless nodes' (measured 0.5 to 1 % for the
    Bingham element at mu = 1e-3; 1.9 to 2.6 % for the series dashpot at 2.5e-4, whose move at 1e-3 is 10 % off
    linear; a lever whose stiffness or rate were wrong leaves a gap that does not shrink with mu)."""
    nodes = ["a", "j", "i", "b"] if case == "bingham" else ["a", "j", "b"]
    elements = LEVERED + PASSED_ON[case] + [("slider", ["a", "b"], {"alpha": 0.2})]

    def first_harmonics(mu):
        mass = [mu if name in "ij" else (1.0 if name == "a" else 2.0) for name in nodes]
        return _shot(tmp_path, nodes, mass, elements, f"passed-{mu!r}.toml")

    joined, X = first_harmonics(0.0)
    assert joined.network.nodes == ("a", "b")
    (lever,) = [e for e in joined.network.elements if e.kind == "lever"]
    assert lever.c == 0.6 and lever.bingham == (case == "bingham")
    assert np.min(np.abs(X)) > 0.2
    mu = 1e-3 if case == "bingham" else 2.5e-4  # (the series dashpot's O(mu^2) is 10 % of the move at 1e-3)
    (_, heavier), (_, light) = first_harmonics(2 * mu), first_harmonics(mu)
    moved = np.abs(light - X)
    assert np.all(moved > 1e-5) and np.all(np.abs(np.abs(heavier - X) / moved - 2.0) < 0.1), (heavier, light, X)
    assert np.all(np.abs(2.0 * light - heavier - X) < 0.05 * moved), (heavier, light, X)


def _random_dashpot_node(rng) -> list:
    """Two masses on springs and dashpots to the ground, a slider between them, and massless j: springs to one
    or two of a, b and the ground, and on it a dashpot, a slider and a dashpot side by side, or a branch with a
    series dashpot, to one of them, or two dashpots to two of them."""
    ends = ["a", "b", "ground"]
    elements = [("spring", ["a", "ground"], {"k": float(rng.uniform(0.5, 2))}),
                ("spring", ["b", "ground"], {"k": float(rng.uniform(0.5, 2))}),
                ("dashpot", ["a", "ground"], {"c": 0.05}), ("dashpot", ["b", "ground"], {"c": 0.08}),
                ("slider", ["a", "b"], {"alpha": float(rng.uniform(0.1, 0.4))})]
    for end in rng.choice(3, size=int(rng.integers(1, 3)), replace=False).tolist():
        elements.append(("spring", ["j", ends[end]], {"k": float(rng.uniform(0.5, 3))}))
    far, kind = ends[int(rng.integers(3))], int(rng.integers(4))
    if kind == 1:
        elements.append(("slider", ["j", far], {"alpha": float(rng.uniform(0.05, 0.3))}))
    if kind < 2:
        elements.append(("dashpot", [far, "j"], {"c": float(rng.uniform(0.2, 1))}))
    elif kind == 2:
        elements.append(("branch", ["j", far], {"k": float(rng.uniform(1, 4)), "eta": float(rng.uniform(0.02, 0.1)),
                                                "c": float(rng.uniform(0.2, 1))}))
    else:  # two dashpots to two ends
        for end in rng.choice(3, size=2, replace=False).tolist():
            elements.append(("dashpot", ["j", ends[end]], {"c": float(rng.uniform(0.2, 1))}))
    return elements


@pytest.mark.slow
def test_random_massless_nodes_on_dashpots_are_the_light_node_s_limit(tmp_path):
    """Random networks whose massless node j is held by springs and a dashpot, a slider and a dashpot side by
    side, a branch with a series dashpot, or two dashpots (levers of ``series._maxwell``, ``series._bingham``,
    ``series._levered``), to random far ends among the masses and the ground, j named: solved as written with a
    light mass mu on j (j an ordinary node of the orbit), the first harmonics of a, b and j come to the massless
    solution's as mu: the distance at mu / 8 is an eighth of that at mu (measured 0.123 to 0.131), where a lever
    with a wrong stiffness, rate or weight would leave a distance that does not shrink."""
    rng = np.random.default_rng(2026)
    for case in range(8):
        elements = _random_dashpot_node(rng)

        def first_harmonics(mu):
            return _shot(tmp_path, ["a", "j", "b"], [1.0, mu, 2.0], elements, f"random-{case}-{mu!r}.toml",
                         named="j")[1]

        X = first_harmonics(0.0)
        far, near = (float(np.max(np.abs(first_harmonics(mu) - X))) for mu in (2.5e-4, 3.125e-5))
        if far < 1e-7:  # j held to the ground alone: it moves nothing, and the two agree to the solver's rounding
            assert near < 1e-7, (case, elements, far, near)
            continue
        assert 0.1 < near / far < 0.16, (case, elements, far, near)


@pytest.mark.slow
def test_a_massless_node_between_dashpots_alone_is_their_schur_complement(tmp_path):
    """A massless node j between three dashpots (to a, to b, to the ground) and nothing else, beside a slider
    between the masses: j follows the dashpots' weighted mean of its ends' velocities, and the three are the
    dashpots c_i c_l / C between each pair of their far ends (refused before: "a first-order motion").
    Against the light-node limit: the distance at mu / 8 is an eighth of that at mu."""
    c = {"a": 0.5, "b": 0.4, "ground": 0.3}
    elements = LEVERED + [("dashpot", [end, "j"], {"c": value}) for end, value in c.items()] + [
        ("slider", ["a", "b"], {"alpha": 0.2})]

    def first_harmonics(mu):
        return _shot(tmp_path, ["a", "j", "b"], [1.0, mu, 2.0], elements, f"dashpots-{mu!r}.toml")

    joined, X = first_harmonics(0.0)
    total = sum(c.values())
    added = {tuple(sorted(e.between)): e.value for e in joined.network.elements if e.name.endswith(" dashpot")}
    assert added == pytest.approx({(0, 1): c["a"] * c["b"] / total, (-1, 0): c["a"] * c["ground"] / total,
                                   (-1, 1): c["b"] * c["ground"] / total})
    assert not any(e.kind == "lever" for e in joined.network.elements)
    far, near = (float(np.max(np.abs(first_harmonics(mu)[1] - X))) for mu in (2.5e-4, 3.125e-5))
    assert far > 1e-6 and 0.1 < near / far < 0.16, (far, near)


@pytest.mark.slow
def test_a_bingham_node_moves_as_the_implicit_stepper_runs_it_as_written(tmp_path):
    """The Bingham lever against an independent stepper: the implicit stepper on the network as written (it
    solves the massless node's balance, with its slider and dashpot, at every step), 150 periods from rest at
    1000 and 2000 steps a period: its error halves with h and its Richardson extrapolation lands within 5 % of
    that error on shooting's first harmonics of a and b (measured: 1.2e-4 and 1.5e-4 relative), the slider and
    dashpot between the masses. With them to the ground the extrapolation lands within 10 % only: the stepper's
    first order is noisy at the slider's events there (as for the Maxwell lever), so the light-node limit above
    is the sharper reference."""
    case = "between the masses"
    from prandtl_fmu.frequency.series import condensed
    from prandtl_fmu.frequency.shooting import NetworkShooting

    F, omega = 1.0, 2.0 * math.pi * 0.175
    scene = network(tmp_path, network_text(["a", "j", "b"], [1.0, 0.0, 2.0], LEVERED + BINGHAM_J[case] + [
        ("slider", ["a", "b"], {"alpha": 0.2})], load_node="a"), "bingham-implicit.toml")
    implicit_agrees(scene, NetworkShooting(condensed(scene, None, "a"), F, None, 1024, 7, omega), F, omega, 150)
