"""``[masing]``: a backbone curve turned into the Iwan spectrum of branches (prandtl_fmu/masing.py).

The element, run as a connector (displacement in, force out), against the extended Masing rules written out
here with their reversal stack: exactly for the bilinear backbone, within the interpolation bound for the
smooth ones (and second order in the number of branches); the backbone at the nodes; the refusals.
"""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from prandtl_fmu import load_scene, parse_scene, simulate
from prandtl_fmu.connector import displacement_response
from prandtl_fmu.masing import Hyperbolic, RambergOsgood, interpolation_error
from prandtl_fmu.scene import SceneError

from tests.conftest import scene_text

SOLVER = {"step": 0.01, "stop_time": 1.0, "output_interval": 0.01}
BILINEAR = {"kind": "bilinear", "k": 100.0, "f_y": 1.0, "alpha": 0.1}
HYPERBOLIC = {"kind": "hyperbolic", "k": 1000.0, "f_u": 10.0, "x_max": 0.1}
RAMBERG_OSGOOD = {"kind": "ramberg_osgood", "k": 1000.0, "f_y": 10.0, "a": 0.5, "r": 5.0, "x_max": 0.1}


def connector(masing, **tables):
    return parse_scene(scene_text({"masing": masing, **tables, "fmu": {"causality": "displacement"},
                                   "solver": SOLVER}))


# ---------------------------------------------------------------- backbones, written out independently

def bilinear(k, f_y, alpha):
    def force(x):
        x_y = f_y / k
        return math.copysign(k * abs(x) if abs(x) <= x_y else f_y + alpha * k * (abs(x) - x_y), x)
    return force


def hyperbolic(k, f_u):
    return lambda x: k * x / (1.0 + k * abs(x) / f_u)


def ramberg_osgood(k, f_y, a, r):
    """F_b by bracketing the root of F/k (1 + a (F/f_y)^(r-1)) = |x| on [0, k |x|] (scipy's brentq)."""
    def force(x):
        if x == 0.0:
            return 0.0
        target = abs(x)
        root = brentq(lambda f: f / k * (1.0 + a * (f / f_y) ** (r - 1.0)) - target, 0.0, k * target,
                      xtol=1e-300, rtol=1e-15, maxiter=500)
        return math.copysign(root, x)
    return force


def backbone_of(table):
    if table["kind"] == "bilinear":
        return bilinear(table["k"], table["f_y"], table.get("alpha", 0.0))
    if table["kind"] == "hyperbolic":
        return hyperbolic(table["k"], table["f_u"])
    return ramberg_osgood(table["k"], table["f_y"], table["a"], table["r"])


def library_backbone(table):
    if table["kind"] == "hyperbolic":
        return Hyperbolic(table["k"], table["f_u"])
    return RambergOsgood(table["k"], table["f_y"], table["a"], table["r"])


def masing_rules(backbone, xs):
    """The extended Masing rules along a displacement history ``xs`` (linear between samples), from x = 0.

    Virgin curve: F = F_b(x). A reversal at (x_r, F_r) starts the branch F = F_r + 2 F_b((x - x_r) / 2).
    Reversals are kept on a stack; a branch that reaches the point where the branch below it started (the
    previous reversal) closes that loop: both reversals are forgotten and the motion continues on the
    earlier curve (return-point memory); the first reversal's branch rejoins the backbone at -x_1 (the
    largest excursion so far, mirrored). Returns the forces and the number of reversals on the stack."""
    stack = []
    x, force, direction = 0.0, 0.0, 0.0
    forces, depths = np.empty(len(xs)), np.empty(len(xs), dtype=int)
    for j, target in enumerate(xs):
        step = math.copysign(1.0, target - x) if target != x else 0.0
        if step:
            if direction and step != direction:
                stack.append((x, force))
            direction = step
            while stack:
                end = stack[-2][0] if len(stack) >= 2 else -stack[0][0]
                if (target - end) * step < 0:
                    break
                del stack[-2 if len(stack) >= 2 else -1:]
            x = target
            if stack:
                x_r, f_r = stack[-1]
                force = f_r + 2.0 * backbone((x - x_r) / 2.0)
            else:
                force = backbone(x)
        forces[j], depths[j] = force, len(stack)
    return forces, depths


def history(seed, x_max, reversals=60, samples=8):
    """Reversal points drawn at random within [-x_max, x_max] (big loops, a random walk's small ones, a
    decaying sweep), each leg sampled at ``samples`` points, some legs ending on an earlier reversal."""
    rng = np.random.default_rng(seed)
    big = rng.uniform(-1.0, 1.0, reversals // 3)
    walk = np.clip(np.cumsum(rng.normal(0.0, 0.15, reversals // 3)), -1.0, 1.0)
    decay = np.cos(np.pi * np.arange(reversals // 3)) * np.linspace(1.0, 0.05, reversals // 3)
    ends = np.concatenate([big, walk, decay])
    for i in (2, 9, 16):  # back exactly to the turning point before last: a loop closes on the dot
        ends[i + 2] = ends[i]
    legs = [np.linspace(a, b, samples + 1)[1:] for a, b in zip(np.concatenate([[0.0], ends[:-1]]), ends)]
    return x_max * np.concatenate(legs)


# ---------------------------------------------------------------- the rules themselves

def test_the_reference_rules_close_loops_and_rejoin_the_backbone():
    """The test's own rules on a hand-made history: a loop closes where it started, then the backbone."""
    f = hyperbolic(1000.0, 10.0)
    xs = np.array([0.05, -0.02, 0.03, -0.02, 0.05, 0.08, -0.08])
    forces, depths = masing_rules(f, xs)
    assert list(depths) == [0, 1, 2, 1, 0, 0, 0]  # back at -0.02 the inner loop closes, at 0.05 the outer
    assert forces[3] == pytest.approx(forces[1], abs=1e-14) and forces[4] == pytest.approx(f(0.05), abs=1e-14)
    assert forces[5] == f(0.08) and forces[6] == pytest.approx(-f(0.08), abs=1e-14)


# ---------------------------------------------------------------- the element against the rules

@pytest.mark.parametrize("alpha", [0.0, 0.1, 0.6])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_bilinear_element_follows_the_masing_rules_to_rounding(seed, alpha):
    table = {**BILINEAR, "alpha": alpha}
    scene = connector(table)
    assert scene.branches.n == 1 and (scene.spring is None) == (alpha == 0.0)
    xs = history(seed, 0.05)  # five times the yield displacement
    expected, depths = masing_rules(backbone_of(table), xs)
    forces = displacement_response(scene, xs)
    assert depths.max() >= 3  # the stack was used
    np.testing.assert_allclose(forces, expected, rtol=0, atol=1e-13 * (1.0 + 100.0 * 0.05))


def dense_interpolation_error(backbone, points, per_cell=64):
    """max of F_b minus its chord over each cell, sampled: the test's own estimate of the bound."""
    t = np.linspace(0.0, 1.0, per_cell + 1)
    worst = 0.0
    for a, b in zip(points[:-1], points[1:]):
        fa, fb = backbone(a), backbone(b)
        gap = [backbone(a + s * (b - a)) - (fa + s * (fb - fa)) for s in t]
        worst = max(worst, max(gap))
    return worst


@pytest.mark.parametrize("table", [HYPERBOLIC, RAMBERG_OSGOOD], ids=["hyperbolic", "ramberg_osgood"])
@pytest.mark.parametrize("spacing", ["force", "displacement"])
def test_a_smooth_backbone_follows_the_rules_within_the_interpolation_bound(table, spacing):
    table = {**table, "count": 40, "spacing": spacing}
    scene = connector(table)
    backbone = backbone_of(table)
    points = np.concatenate([[0.0], scene.branches.yield_displacement])
    bound = dense_interpolation_error(backbone, points)
    library = interpolation_error(library_backbone(table), points)
    assert bound <= library <= bound * (1 + 1e-3)  # the closed-form peak, not below the sampled one
    xs = history(4, table["x_max"], reversals=30, samples=6)
    expected, depths = masing_rules(backbone, xs)
    error = np.abs(displacement_response(scene, xs) - expected)
    assert np.all(error <= (depths + 1) * library + 1e-12)  # (D + 1) e_max: docs/masing.md
    assert error.max() > 0.1 * library  # the bound is not vacuous


@pytest.mark.parametrize("table", [HYPERBOLIC, RAMBERG_OSGOOD], ids=["hyperbolic", "ramberg_osgood"])
def test_the_error_falls_like_one_over_count_squared(table):
    xs = history(5, table["x_max"], reversals=30, samples=6)
    expected, _ = masing_rules(backbone_of(table), xs)
    counts = [25, 50, 100, 200, 400]
    errors, bounds = [], []
    for n in counts:
        scene = connector({**table, "count": n})
        errors.append(np.abs(displacement_response(scene, xs) - expected).max())
        points = np.concatenate([[0.0], scene.branches.yield_displacement])
        bounds.append(interpolation_error(library_backbone(table), points))
    # the max over one history scatters by where its reversals fall between nodes (single halvings: 1.6 to
    # 2.5); the fit over a 16-fold range is the order, as the bound's (1.94 and 2.00: h^2 F_b'' / 8)
    assert -np.polyfit(np.log(counts), np.log(errors), 1)[0] == pytest.approx(2.0, abs=0.2)
    assert -np.polyfit(np.log(counts), np.log(bounds), 1)[0] == pytest.approx(2.0, abs=0.1)


def test_a_ramberg_osgood_exponent_below_two_converges_like_count_to_the_minus_r():
    """F_b = k x - O(x^r) at 0: the first cell's gap is O(h^r), the others' O(h^2) (docs/masing.md)."""
    table = {**RAMBERG_OSGOOD, "r": 1.5}
    counts = [50, 100, 200, 400]
    bounds = []
    for n in counts:
        points = np.concatenate([[0.0], connector({**table, "count": n}).branches.yield_displacement])
        bounds.append(interpolation_error(library_backbone(table), points))
        if n == 50:
            assert bounds[-1] == pytest.approx(dense_interpolation_error(backbone_of(table), points), rel=1e-3)
    assert -np.polyfit(np.log(counts), np.log(bounds), 1)[0] == pytest.approx(1.5, abs=0.1)


@pytest.mark.slow
@pytest.mark.parametrize("table", [BILINEAR, HYPERBOLIC, RAMBERG_OSGOOD], ids=["bilinear", "hyperbolic",
                                                                               "ramberg_osgood"])
@pytest.mark.parametrize("seed", range(10, 20))
def test_long_random_histories(table, seed):
    table = dict(table) if table["kind"] == "bilinear" else {**table, "count": 300}
    scene = connector(table)
    x_max = table.get("x_max", 0.05)
    xs = history(seed, x_max, reversals=300, samples=5)
    expected, depths = masing_rules(backbone_of(table), xs)
    error = np.abs(displacement_response(scene, xs) - expected)
    if table["kind"] == "bilinear":
        assert error.max() <= 1e-12
    else:
        points = np.concatenate([[0.0], scene.branches.yield_displacement])
        bound = dense_interpolation_error(backbone_of(table), points, per_cell=16)
        assert np.all(error <= (depths + 1) * bound * 1.01 + 1e-12)


# ---------------------------------------------------------------- the backbone at the nodes

@pytest.mark.parametrize("table", [HYPERBOLIC, RAMBERG_OSGOOD], ids=["hyperbolic", "ramberg_osgood"])
@pytest.mark.parametrize("spacing", ["force", "displacement"])
def test_the_virgin_curve_interpolates_the_backbone_at_the_nodes(table, spacing):
    table = {**table, "count": 30, "spacing": spacing}
    scene = connector(table)
    backbone = backbone_of(table)
    points = np.concatenate([[0.0], scene.branches.yield_displacement])
    assert points[-1] == table["x_max"] and np.all(np.diff(points) > 0)
    if spacing == "displacement":
        np.testing.assert_allclose(np.diff(points), table["x_max"] / 30, rtol=1e-12)
    else:
        np.testing.assert_allclose(np.diff([backbone(x) for x in points]), backbone(table["x_max"]) / 30,
                                   rtol=1e-9)
    middles = 0.5 * (points[:-1] + points[1:])
    xs = np.sort(np.concatenate([points[1:], middles]))
    forces = displacement_response(scene, xs)
    on_nodes = np.array([backbone(x) for x in points[1:]])
    np.testing.assert_allclose(forces[1::2], on_nodes, rtol=1e-13)
    chords = 0.5 * (np.concatenate([[0.0], on_nodes[:-1]]) + on_nodes)
    np.testing.assert_allclose(forces[0::2], chords, rtol=1e-13)
    np.testing.assert_allclose(-displacement_response(scene, -xs), forces, rtol=1e-13)  # odd


def test_the_bilinear_backbone_is_one_branch_and_the_post_yield_spring():
    scene = connector(BILINEAR)
    assert scene.spring.k0 == 10.0
    assert list(scene.branches.stiffness) == [90.0] and list(scene.branches.yield_displacement) == [0.01]
    xs = np.array([0.005, 0.01, 0.03])
    np.testing.assert_allclose(displacement_response(scene, xs), [0.5, 1.0, 1.2], rtol=1e-15)


# ---------------------------------------------------------------- the packaged scene

def test_the_packaged_scene_is_the_bilinear_branch_and_spring():
    scene = load_scene("masing-bilinear")
    assert scene.effects == ["mass", "spring", "damper", "branches"] and scene.spring.k0 == 10.0
    assert list(scene.branches.stiffness) == [90.0] and list(scene.branches.yield_displacement) == [0.01]


@pytest.mark.slow
def test_the_packaged_scene_runs_and_its_loops_stay_within_the_bilinear_bounds(tmp_path):
    from prandtl_fmu.cli import main

    scene = load_scene("masing-bilinear").with_solver(stop_time=10.0)
    run = simulate(scene)
    out = tmp_path / "masing.csv"
    assert main(["run", "masing-bilinear", "--stop-time", "10", "--out", str(out)]) == 0
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(table[:, 1], run.x)  # prandtl-fmu run: the same numbers
    hysteretic = run.reaction - 10.0 * run.x - 0.2 * run.v  # 90 u_1, |u_1| <= 0.01
    assert np.all(np.abs(hysteretic) <= 0.9 * (1 + 1e-12)) and np.abs(hysteretic).max() > 0.89
    assert np.abs(run.x).max() > 10 * 0.01  # it yields


@pytest.mark.slow
@pytest.mark.parametrize("runtime", ["python", "native"])
def test_both_fmu_runtimes_run_the_packaged_scene_as_the_library(runtime, tmp_path):
    """[masing] is branches and a spring: each FMU runtime is the library bit for bit, unchanged."""
    fmpy = pytest.importorskip("fmpy")
    from prandtl_fmu.fmu.build import build_fmu
    from prandtl_fmu.scene import scene_path

    path = build_fmu(scene_path("masing-bilinear"), tmp_path / "masing.fmu", runtime=runtime)
    result = fmpy.simulate_fmu(str(path), stop_time=5.0, output_interval=0.01, start_values={"scene_load": True})
    expected = simulate(load_scene("masing-bilinear").with_solver(stop_time=5.0))
    assert len(result) == len(expected.time)
    np.testing.assert_array_equal(result["x"], expected.x)
    np.testing.assert_array_equal(result["reaction"], expected.reaction)


# ---------------------------------------------------------------- refusals, one line each

REFUSALS = [
    ({"kind": "trilinear", "k": 1.0}, "[masing] kind: must be one of 'bilinear', 'hyperbolic', 'ramberg_osgood'"),
    ({**BILINEAR, "f_u": 1.0}, "[masing] f_u: unknown key"),
    ({**BILINEAR, "count": 10}, "[masing] count: the bilinear backbone is one branch"),
    ({**BILINEAR, "k": 0.0}, "[masing] k: must be > 0"),
    ({**BILINEAR, "k": -5.0}, "[masing] k: must be > 0"),
    ({**BILINEAR, "alpha": 1.0}, "[masing] alpha: must be < 1"),
    ({**BILINEAR, "alpha": -0.1}, "[masing] alpha: must be >= 0"),
    ({"kind": "bilinear", "k": 1.0}, "[masing] f_y: missing"),
    ({**HYPERBOLIC, "f_u": 0.0}, "[masing] f_u: must be > 0"),
    ({k: v for k, v in HYPERBOLIC.items() if k != "x_max"}, "[masing] x_max: missing (required: the largest |x|"),
    ({**HYPERBOLIC, "x_max": -1.0}, "[masing] x_max: must be > 0"),
    ({**HYPERBOLIC, "count": 0}, "[masing] count: must be >= 1"),
    ({**HYPERBOLIC, "count": 2.5}, "[masing] count: must be an integer"),
    ({**HYPERBOLIC, "spacing": "log"}, "[masing] spacing: must be one of 'force', 'displacement'"),
    ({**HYPERBOLIC, "count": 10**5, "x_max": 1e8, "spacing": "displacement"}, "[masing] count: the chord slopes"),
    ({**RAMBERG_OSGOOD, "r": 1.0}, "[masing] r: must be > 1"),
    ({**RAMBERG_OSGOOD, "a": 0.0}, "[masing] a: must be > 0"),
    ({**RAMBERG_OSGOOD, "r": "5"}, "[masing] r: must be a number"),
    ({**RAMBERG_OSGOOD, "r": 1e6, "x_max": 1e40}, "[masing] count: the chord slopes"),  # a flat curve
]


@pytest.mark.parametrize("table, message", REFUSALS)
def test_a_broken_masing_table_is_refused_in_one_line(table, message):
    with pytest.raises(SceneError) as info:
        connector(table)
    text = str(info.value)
    assert "\n" not in text and message in text, text


@pytest.mark.parametrize("other, message", [
    ({"branches": {"k": [1.0], "eta": [0.1]}}, "remove [branches] (a scene gives its branches one way)"),
    ({"spring": {"k0": 1.0}}, "remove [spring]"),
])
def test_masing_with_branches_or_a_spring_is_refused(other, message):
    with pytest.raises(SceneError, match=r"\[masing\]: gives the branches") as info:
        connector(BILINEAR, **other)
    assert message in str(info.value) and "\n" not in str(info.value)
