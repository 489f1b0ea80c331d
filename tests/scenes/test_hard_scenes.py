"""The catalog of hard scenes (scenes/hard): each keeps the property its header states."""
import dataclasses
import math
import tracemalloc
import warnings

import numpy as np
import pytest

from prandtl_fmu import Element, STEPPERS, load_scene, parse_scene, simulate
from prandtl_fmu.cli import main
from prandtl_fmu.stepping import ElementError
from prandtl_fmu.effects import Branches, Mass
from prandtl_fmu.loads import HarmonicLoad
from prandtl_fmu.stability import StabilityWarning, stability_problem
from prandtl_fmu.steppers import get_stepper

from tests.conftest import SCENES

HARD = SCENES / "hard"
CATALOG = sorted(path.stem for path in HARD.glob("*.toml"))


def hard(name):
    return load_scene(HARD / f"{name}.toml")


def applies(scene, stepper):
    try:
        get_stepper(stepper).loop_for(scene)
        return True
    except ValueError:
        return False


# The runs keep the energy account even where a test reads none of it: test_properties_checked_everywhere keeps it on
# the same scenes, and a loop with and one without the account are two compilations (the account never changes the
# motion: tests/fmu/python/test_against_library.py's test_the_energy_account_never_changes_the_motion).


def run(scene, stepper, **kwargs):
    """simulate(), asserting it warns exactly when the step is beyond the stepper's stability limit."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", StabilityWarning)
        result = simulate(scene, stepper, **kwargs)
    flagged = any(issubclass(w.category, StabilityWarning) for w in caught)
    assert flagged == bool(stability_problem(scene, stepper, scene.solver.step))
    return result, flagged


def energy_scale(result):
    e = result.energy
    return max(np.abs(e["work"]).max(), e["stored_energy"].max(), e["kinetic_energy"].max(), 1e-300)


def test_every_scene_of_the_catalog_has_its_own_test():
    tested = {"stiff-branches", "tiny-thresholds", "single-branch", "many-branches", "overload", "step-load",
              "long-horizon", "large-forces", "large-displacements", "stick-slip-below", "stick-slip-above",
              "massless-quasi-static", "massless-collapse", "massless-dashpot", "breakaway-ramp", "belt-stick-slip"}
    assert set(CATALOG) == tested


# ------------------------------------------------------------------ everywhere

# exact's column in the slow suite: a loop of exact costs 8 to 16 s to compile for each hard scene's effects (52 s
# of the quick suite's compiling); its own tests (test_exact*.py, test_trust*.py) stay quick
@pytest.mark.parametrize("stepper", [pytest.param(name, marks=pytest.mark.slow) if name == "exact" else name
                                     for name in STEPPERS])
@pytest.mark.parametrize("name", [n for n in CATALOG if n not in ("massless-collapse", "long-horizon",
                                                                   "many-branches")])
def test_properties_checked_everywhere(name, stepper):
    """Finite, |u_i| <= eta_i exactly, and the energy balance of the stepper's kind."""
    scene = hard(name)
    if not applies(scene, stepper):  # refused, with a reason, never run wrong
        with pytest.raises(ValueError, match="needs|quasi-static"):
            simulate(scene, stepper)
        return
    module = get_stepper(stepper)
    result, flagged = run(scene, stepper, states=True, energy=True)
    if flagged:
        return  # beyond the stability limit: said, not silently wrong (see test_stiff_branches)
    assert all(np.all(np.isfinite(column)) for column in result.columns().values())
    assert np.all(np.abs(result.u) <= scene.branches.yield_displacement)
    residual = result.energy["energy_residual"]
    tolerance = 1e-10 * energy_scale(result)
    if stepper == "implicit":
        assert residual.min() >= -tolerance  # never creates energy
    elif stepper == "projected" and scene.friction is None:
        # the explicit scheme creates energy, never dissipates it (with friction on the mass, booked at the
        # new velocity while x moves at the old one, the sign is not kept: projected.py)
        assert residual.max() <= tolerance
    # and every stepper's balance is within its own order: residual = O(h^order); the stick-slip switches of
    # friction on the mass make every scheme order 1 (verlet.py)
    order = 1 if scene.friction is not None else module.ORDER
    work = max(np.abs(result.energy["work"]).max(), 1e-300)
    # (exact, of infinite order, books the integrals in closed form: its residual is rounding)
    assert np.abs(residual).max() <= max(10 * scene.solver.step ** order, 1e-12) * work


# ------------------------------------------------------------------ one scene each

@pytest.mark.parametrize("omega_h", [1, 10, 100, 1000])
def test_stiff_branches(omega_h):
    base = hard("stiff-branches")
    h, m = base.solver.step, base.mass.m
    total = (omega_h / h) ** 2 * m  # sum k_i for sqrt(sum k_i / m) h = omega_h
    alpha = base.branches.threshold  # keep the thresholds: same strength at every stiffness
    k = base.branches.stiffness / base.branches.stiffness.sum() * total
    scene = dataclasses.replace(base, branches=Branches(k, alpha / k, np.zeros(2)))
    result, _ = run(scene, "implicit", states=True, energy=True)
    assert np.all(np.isfinite(result.x)) and np.abs(result.x).max() < 100
    assert np.all(np.abs(result.u) <= scene.branches.yield_displacement)
    assert result.energy["energy_residual"].min() >= -1e-10 * energy_scale(result)  # dissipative
    assert np.abs(result.reaction).max() <= alpha.sum() * (1 + 1e-12)
    with pytest.warns(StabilityWarning, match="omega h"):
        try:
            simulate(scene, "projected", energy=True)
        except ElementError as exc:  # or it blows up: also said, never silent
            assert "non-finite" in str(exc)


# exact's case slow: its loop compiled for this scene alone (10 s cold)
@pytest.mark.parametrize("stepper", [pytest.param(name, marks=pytest.mark.slow) if name == "exact" else name
                                     for name in STEPPERS])
def test_tiny_thresholds(stepper):
    scene = hard("tiny-thresholds")
    result = simulate(scene, stepper, states=True, energy=True)
    assert np.all(result.u[:, 0] == 0.0)  # eta = 0: the slider takes all the motion
    assert np.all(np.abs(result.u[:, 1]) <= 1e-12)
    assert np.abs(result.u[:, 3]).max() > 0.1


def test_single_branch_steppers_converge_to_the_same_motion():
    scene = hard("single-branch")
    gaps = []
    for h in (4e-3, 1e-3, 2.5e-4):
        s = scene.with_solver(step=h, output_interval=0.02)
        gaps.append(np.abs(simulate(s, "projected", energy=True).x - simulate(s, "implicit", energy=True).x).max())
    assert 3.0 < gaps[0] / gaps[1] < 5.5 and 3.0 < gaps[1] / gaps[2] < 5.5, gaps  # both order 1, one limit


def test_many_branches():
    scene = hard("many-branches")
    assert scene.branches.n == 100_000
    result, _ = run(scene, "projected", energy=True)
    assert np.all(np.isfinite(result.x))
    assert result.energy["energy_residual"].max() <= 1e-10 * energy_scale(result)
    paper = load_scene(SCENES / "paper-section-8.toml").with_solver(stop_time=8.0, output_interval=0.05)
    # right-end-point sampling: the motion converges like 1/n to the continuous element's
    assert np.abs(simulate(paper, energy=True).x - result.x).max() < 5 / 100
    element = Element(scene, stepper="implicit")
    element.advance(8.0, 0.45)
    assert element.branch_kernel == "stack"  # implicit with the memory stack: O(log n) per kink crossed
    u = element.elongations()
    assert np.all(np.abs(u) <= scene.branches.yield_displacement) and np.any(np.abs(u) == scene.branches.yield_displacement)


@pytest.mark.parametrize("stepper", list(STEPPERS))
def test_overload_closed_form(stepper):
    scene = hard("overload")
    strength, m, force = scene.branches.strength, scene.mass.m, scene.load.value
    result = simulate(scene, stepper, states=True, energy=True)
    full = np.all(np.abs(result.u) == scene.branches.yield_displacement, axis=1)
    assert full[-1] and full.sum() > 500  # every slider slips for most of the run
    first = int(np.argmax(full)) + 1
    np.testing.assert_allclose(result.reaction[first:], strength, rtol=1e-13)
    h, per_row = scene.solver.step, scene.solver.steps_per_output
    np.testing.assert_allclose(np.diff(result.v[first:]), per_row * h * (force - strength) / m, rtol=1e-9)


def test_step_load():
    scene = hard("step-load")
    for stepper in STEPPERS:
        result = simulate(scene, stepper, energy=True)
        # after the 40 N step the load far exceeds the strength: the mass runs away, as it should
        assert result.x[-1] > 10 and np.all(np.isfinite(result.x))
        before = result.time < 5.0
        assert np.abs(result.x[before]).max() < 5.0


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_long_horizon_in_constant_memory():
    scene = hard("long-horizon")
    steps = round(scene.solver.stop_time / scene.solver.step)
    assert steps == 10**7
    for stepper in ("projected", "implicit"):
        simulate(scene.with_solver(stop_time=1.0), stepper, energy=True)  # compile outside the measure
        tracemalloc.start()
        result = simulate(scene, stepper, energy=True)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert peak < 2 * 2**20, f"{stepper}: {peak} bytes for 10^7 steps"
        assert len(result.time) == 1001 and np.all(np.isfinite(result.x))
        residual = result.energy["energy_residual"]
        tolerance = 1e-9 * energy_scale(result)
        assert residual.min() >= -tolerance if stepper == "implicit" else residual.max() <= tolerance


@pytest.mark.parametrize("name, force_scale, length_scale", [
    ("large-forces", 1e6, 1e-6), ("large-displacements", 1e-6, 1e6)])
def test_extreme_scales_keep_relative_accuracy(name, force_scale, length_scale):
    scene = hard(name)
    stiffness = force_scale / length_scale
    unit = dataclasses.replace(
        scene, mass=Mass(scene.mass.m / stiffness),
        branches=Branches(scene.branches.stiffness / stiffness, scene.branches.yield_displacement / length_scale,
                          scene.branches.u0 / length_scale),
        load=HarmonicLoad(scene.load.amplitude / force_scale, scene.load.omega))
    assert unit.branches.strength == pytest.approx(0.625, rel=1e-12)  # the paper's spectrum, n = 20
    for stepper in STEPPERS:
        scaled, reference = simulate(scene, stepper, energy=True), simulate(unit, stepper, energy=True)
        x_error = np.abs(scaled.x / length_scale - reference.x).max() / np.abs(reference.x).max()
        r_error = np.abs(scaled.reaction / force_scale - reference.reaction).max() / np.abs(reference.reaction).max()
        assert x_error < 1e-11 and r_error < 1e-11, (stepper, x_error, r_error)


@pytest.mark.parametrize("name", ["stick-slip-below", "stick-slip-above"])
@pytest.mark.parametrize("stepper", list(STEPPERS))
def test_stick_slip_has_no_chattering_beyond_the_order(name, stepper):
    """Near the threshold the reaction converges at order 1: no O(1) chattering between stick and slip."""
    scene = hard(name)
    runs = [simulate(scene.with_solver(step=h, output_interval=0.04), stepper, energy=True).reaction
            for h in (4e-3, 2e-3, 1e-3)]
    first, second = np.abs(runs[0] - runs[1]).max(), np.abs(runs[1] - runs[2]).max()
    order = get_stepper(stepper).ORDER
    if math.isinf(order):  # `exact`: h only sets the grid
        assert first < 1e-12 and second < 1e-12
    else:
        # at least order 1 (an O(1) chattering would not shrink), at most the scheme's own order
        assert 1.6 < first / second < 1.25 * 2**order, (first, second)
    assert second < 2e-2 * np.abs(runs[2]).max()
    strength = scene.branches.strength
    assert np.abs(runs[2]).max() <= strength * (1 + 1e-12)
    if name == "stick-slip-above":
        assert np.abs(runs[2]).max() > strength * (1 - 1e-9)  # it does reach full slip


def test_massless_quasi_static():
    scene = hard("massless-quasi-static")
    assert scene.mass is None and scene.damper is None
    result = simulate(scene, "implicit", states=True, energy=True)
    force = scene.load.amplitude * np.cos(scene.load.omega * result.time)
    np.testing.assert_allclose(result.reaction, force, rtol=0, atol=1e-13)  # equilibrium at every row
    assert result.reaction[0] == pytest.approx(0.6, rel=1e-15) and result.x[0] > 0  # the jump to equilibrium at t = 0
    assert np.all(np.abs(result.u) <= scene.branches.yield_displacement)
    assert np.all(result.energy["kinetic_energy"] == 0.0)
    assert result.energy["energy_residual"].min() >= -1e-12
    with pytest.raises(ValueError, match="quasi-static"):
        simulate(scene, "projected")


def test_massless_collapse_is_a_clear_error(tmp_path, capsys):
    path = HARD / "massless-collapse.toml"
    assert main(["run", str(path), "--out", str(tmp_path / "out.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    line = err[0]
    assert "plastic collapse" in line and "t = 5.001 s" in line and "strength sum alpha_i = 1.7 N" in line
    force = float(line.split("the load F = ")[1].split(" N")[0])
    assert force == pytest.approx(3.4 * 5.001 / 10, rel=1e-12) and force > 1.7
    element = Element(load_scene(path))
    element.advance(1.0, 1.6)
    state = element.get_state()
    with pytest.raises(ElementError, match="plastic collapse"):
        element.advance(1.0, 1.8)
    assert element.get_state() == state  # unchanged


@pytest.mark.parametrize("stepper", list(STEPPERS))
def test_massless_dashpot_closed_form_and_order(stepper):
    scene = hard("massless-dashpot")
    if not applies(scene, stepper):
        with pytest.raises(ValueError, match="mass"):
            simulate(scene, stepper)
        return
    stiffness, c, force = 0.5 + 1.5, scene.damper.c, scene.load.value
    errors = []
    for h in (4e-3, 2e-3, 1e-3):
        result = simulate(scene.with_solver(step=h, output_interval=0.04), stepper, energy=True)
        exact = force / stiffness * (1 - np.exp(-stiffness * result.time / c))
        errors.append(np.abs(result.x - exact).max())
        np.testing.assert_allclose(result.reaction, force, rtol=0, atol=1e-12)  # massless: reaction = F
    order = math.log(errors[0] / errors[2], 4)
    assert abs(order - 1) < 0.05, errors


def test_loads_that_start_inconsistent_jump_at_time_zero():
    text = (HARD / "massless-quasi-static.toml").read_text().replace("amplitude = 0.6", "amplitude = 1.2")
    scene = parse_scene(text, "jump.toml")
    result = simulate(scene.with_solver(stop_time=0.1), "implicit", energy=True)
    assert result.reaction[0] == pytest.approx(1.2, rel=1e-15)
    # 0.1 x + min(x, 0.2) + min(x, 0.5) + min(x, 1.0) = 1.2: x = 1 / 2.1 (in the piece 0.2 < x < 0.5)
    assert result.x[0] == pytest.approx(1 / 2.1, rel=1e-14)


# ------------------------------------------------------------------ friction on the mass (issue 25)

@pytest.mark.parametrize("stepper", [name for name in STEPPERS if name != "exact"])
def test_breakaway_ramp_holds_the_mass_exactly_until_the_threshold(stepper):
    scene = hard("breakaway-ramp")
    result, flagged = run(scene, stepper, energy=True)
    assert not flagged
    held = result.time < 0.6 / 0.5 - 2 * scene.solver.step
    assert np.all(result.x[held] == 0.0) and np.all(result.v[held] == 0.0)
    np.testing.assert_allclose(result.reaction[held], 0.5 * result.time[held], rtol=1e-12, atol=1e-15)  # = F
    assert result.x[-1] > 0.5  # and then it slides


def test_breakaway_ramp_is_refused_by_exact_in_words():
    with pytest.raises(ValueError, match="'exact' needs plain Coulomb friction"):
        simulate(hard("breakaway-ramp"), "exact")


def cycle_peaks(result):
    """The maxima of x, one per stick-slip cycle (the end of each slip back)."""
    inside = np.flatnonzero((result.x[1:-1] >= result.x[:-2]) & (result.x[1:-1] > result.x[2:])) + 1
    return result.time[inside], result.x[inside]


@pytest.mark.parametrize("stepper", ["implicit", "symplectic", "verlet", "projected"])
def test_belt_stick_slip_settles_on_a_limit_cycle_and_sticks_to_the_bit(stepper):
    scene = hard("belt-stick-slip")
    result, flagged = run(scene, stepper, energy=True)
    assert not flagged
    stuck = result.v == 0.1  # moving with the belt, exactly
    assert 0.6 < stuck.mean() < 0.8  # most of a cycle sticks, the rest slips back
    times, peaks = cycle_peaks(result)
    assert len(peaks) >= 5
    # the cycle repeats: the last peaks and periods agree (the transient dies out geometrically)
    assert np.ptp(peaks[-3:]) < 2e-3 and np.ptp(np.diff(times[-4:])) < 0.05
    # while stuck the spring and the branch pull on the mass with at most alpha
    assert np.all(np.abs(result.reaction[stuck]) <= 1.0 + 1e-12)
    reference = simulate(scene.with_solver(step=1e-4), "verlet", energy=True)
    assert abs(peaks[-1] - cycle_peaks(reference)[1][-1]) < 5e-3  # every stepper on the same cycle, O(h)
