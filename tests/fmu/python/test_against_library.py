"""The packaged FMU, driven by FMPy, against the library it bundles."""
import html
import json
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from prandtl_fmu import Element, load_scene, parse_scene, simulate
from prandtl_fmu.stepping import energy_columns
from prandtl_fmu.fmu.build import build_fmu
from prandtl_fmu.fmu.description import scene_load_notice
from prandtl_fmu.fmu.documentation import equations
from prandtl_fmu.steppers import STEPPERS

from tests.conftest import SCENES, base_tables, scene_text
from tests.fmu_tools import Slave, held_input
from tests.paths import TESTS

EFFECT_SETS = {
    "paper": None,  # scenes/paper-section-8.toml: mass, spring (k0 = 0), 100 branches
    "all-effects": base_tables(),
    "damper-only": base_tables(spring=None, cubic=None, mass={"m": 2.0, "x0": 0.1, "v0": 0.0}),
    # a mass on a spring: the fewest kernels (what the FMU's own copy of the library compiles under its name)
    "oscillator": base_tables(cubic=None, damper=None, branches=None),
    "continuum": base_tables(cubic=None, damper=None, mass={"m": 1.0, "x0": 0.05, "v0": 0.0},
                             branches={"continuum": True, "k_total": 1.0, "eta_range": [0.0, 1.0]}),
    "iwan": base_tables(cubic=None, damper=None, mass={"m": 1.0, "x0": 0.05, "v0": 0.0},
                        branches={"continuum": True, "density": {"kind": "iwan", "F_S": 0.5, "K_T": 2.0,
                                                                 "chi": -0.5, "beta": 0.3}}),
    # friction on the mass (Stribeck, a moving belt) and series dashpots in the branches (issue 25)
    "stribeck-series": base_tables(cubic=None, friction={"alpha": 0.25, "alpha_kinetic": 0.15,
                                                         "stribeck_velocity": 0.1, "belt_velocity": 0.05},
                                   branches={"k": [0.5, 0.3, 0.2], "eta": [0.1, 0.3, 0.6], "c": [0.4, 2.0, 9.0]}),
    # what exact takes of both: plain Coulomb friction and series dashpots
    "coulomb-series": base_tables(cubic=None, friction={"alpha": 0.2},
                                  branches={"k": [0.5, 0.3, 0.2], "eta": [0.1, 0.3, 0.6], "u0": [0.05, -0.1, 0.0],
                                            "c": [0.4, 2.0, 9.0]}),
}


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """name -> (fmu path, scene path), built once for the module."""
    folder = tmp_path_factory.mktemp("fmus")
    built = {}
    for name, tables in EFFECT_SETS.items():
        if tables is None:
            scene_path = SCENES / "paper-section-8.toml"
        else:
            scene_path = folder / f"{name}.toml"
            scene_path.write_text(scene_text(tables))
        built[name] = (build_fmu(scene_path, folder / f"{name}.fmu"), scene_path)
    return built


@pytest.mark.parametrize("name", list(EFFECT_SETS))
def test_model_description_is_valid_and_complete(fmus, name):
    fmu, scene_path = fmus[name]
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(fmu)
    scene = load_scene(scene_path)
    variables = {v.name: v for v in md.modelVariables}
    assert variables["F"].causality == "input" and variables["F"].unit == "N"
    for out, unit in (("x", "m"), ("v", "m/s"), ("reaction", "N"), ("stiffness", "N/m")):
        assert variables[out].causality == "output" and variables[out].unit == unit
    for v in md.modelVariables:
        assert v.description
        if v.type == "Real":
            assert v.unit, v.name
    # parameters only for the effects present
    expected = {"m", "x0", "v0", "step", "stepper", "scene_load", "noise_intensity", "noise_seed", "noise_unit"}
    expected |= {"k0"} if scene.spring else set()
    expected |= {"k3"} if scene.cubic else set()
    expected |= {"c"} if scene.damper else set()
    if scene.friction:
        expected |= {"alpha", "belt_velocity"} | ({"alpha_kinetic", "stribeck_velocity"}
                                                  if scene.friction.stribeck_velocity else set())
    if scene.has_series_dashpots:
        expected |= {f"c_branch[{i + 1}]" for i in range(scene.branches.n)}
    assert {v.name for v in md.modelVariables if v.causality == "parameter"} == expected
    n = 0 if scene.branches is None else -1 if scene.branches.continuum else scene.branches.n
    assert variables["n"].variability == "constant" and int(variables["n"].start) == n
    energy_outputs = {v.name for v in md.modelVariables if v.causality == "output" and v.unit == "J"}
    assert {"kinetic_energy", "stored_energy", "work"} <= energy_outputs <= set(energy_columns(scene))  # as the CSV
    assert ("dissipated_friction" in energy_outputs) == (scene.friction is not None)
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    assert md.coSimulation.canHandleVariableCommunicationStepSize
    assert md.defaultExperiment.stopTime == str(scene.solver.stop_time) or \
        float(md.defaultExperiment.stopTime) == scene.solver.stop_time
    with zipfile.ZipFile(fmu) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
        doc = html.unescape(archive.read("documentation/index.html").decode())
        names = archive.namelist()
    outputs = root.find("ModelStructure/Outputs")
    # no direct feedthrough of F, except the reaction with friction on the mass (a stuck mass: reaction = F)
    feedthrough = {str(i + 1) for i, v in enumerate(root.find("ModelVariables")) if v.get("name") == "F"}
    reaction_index = next(str(i + 1) for i, v in enumerate(root.find("ModelVariables")) if v.get("name") == "reaction")
    assert all(u.get("dependencies") == ("".join(feedthrough) if scene.friction and u.get("index") == reaction_index
                                         else "") for u in outputs)
    assert len(root.find("ModelStructure/InitialUnknowns")) == len(outputs) >= 3
    # the page describes this FMU: the equations of its effects only, every stepper, readable bounds
    assert equations(scene) in doc
    assert ("k3" in doc) == (scene.cubic is not None) and ("c v" in doc) == scene.has_dashpot
    assert all(f"<td>{name}</td>" in doc for name in STEPPERS) and "1.797" not in doc
    assert root.get("modelName") == scene.name and root.find("CoSimulation").get("modelIdentifier") == \
        "PrandtlElement"
    assert "resources/scene.toml" in names and "resources/prandtl_fmu/steppers/projected.py" in names
    slave_modules = [n for n in names if n.startswith("resources/prandtl_slave_") and n.endswith(".py")]
    assert len(slave_modules) == 1


def element_run(scene_path, stepper, times, forces):
    """The library's Element driven as FMPy drives the FMU: F set at each communication point, then the outputs
    read (with friction on the mass the reaction holds a stuck mass against the F set now), then a step."""
    element = Element(load_scene(scene_path), stepper=stepper)
    element.reset(forces[0])
    rows = [(element.x, element.v, element.reaction_under(forces[0]))]
    for k in range(len(times) - 1):
        element.advance(times[k + 1] - times[k], forces[k])
        rows.append((element.x, element.v, element.reaction_under(forces[k + 1])))
    return np.array(rows)


@pytest.mark.parametrize("stepper", ["projected", "implicit"])
@pytest.mark.parametrize("name", [name for name in EFFECT_SETS if name not in ("continuum", "iwan")])
def test_simulate_fmu_agrees_with_the_library(fmus, name, stepper):
    fmu, scene_path = fmus[name]
    dt, stop = 0.05, 20.0
    times = np.round(np.arange(0, stop + dt / 2, dt), 12)
    forces = 0.6 * np.cos(0.7 * times) + 0.2 * np.sin(2.3 * times)
    result = simulate_fmu(str(fmu), stop_time=stop, output_interval=dt, input=held_input(times, forces),
                          start_values={"stepper": stepper, "scene_load": False}, output=["x", "v", "reaction"])
    expected = element_run(scene_path, stepper, times, forces)
    assert len(result) == len(times)
    got = np.column_stack([result["x"], result["v"], result["reaction"]])
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
    assert np.abs(expected[:, 0]).max() > 1e-2  # it moved


# exact's runs through the FMU take half a minute each: under the slow marker (tests/fmu/native/test_against_library.py and
# test_every_stepper_runs_inside_the_fmu keep exact in the quick suite)
@pytest.mark.parametrize("stepper", ["projected", "implicit", "verlet", pytest.param("exact", marks=pytest.mark.slow)])
@pytest.mark.parametrize("name", ["paper", "all-effects", "stribeck-series", "coulomb-series"])
def test_with_scene_load_and_no_input_the_fmu_reproduces_the_library(fmus, name, stepper):
    """The README route: simulate_fmu with no input and scene_load = true is the library's run of the scene
    (the load evaluated at every internal step), not F held per communication step."""
    fmu, scene_path = fmus[name]
    scene = load_scene(scene_path)
    stribeck = scene.friction is not None and scene.friction.alpha_kinetic < scene.friction.alpha
    if stepper == "exact" and (scene.cubic is not None or stribeck):
        pytest.skip("exact does not apply to a cubic spring nor to Stribeck friction (refused: tests/models/test_friction.py)")
    stop = min(scene.solver.stop_time, 60.0)
    # with the energy account, as the FMU's element keeps it: one compiled loop for both (the account never changes
    # the motion: test_the_energy_account_never_changes_the_motion)
    library = simulate(scene.with_solver(stop_time=stop), stepper=stepper, energy=True)
    result = simulate_fmu(str(fmu), stop_time=stop, output_interval=scene.solver.output_interval,
                          start_values={"scene_load": True, "stepper": stepper}, output=["x", "v", "reaction"])
    assert len(result) == len(library.time)
    # bit for bit (issue 23, item 10): the element keeps its clock on the step grid, so FMPy's communication
    # points (which drift by ulps from k H) and step sizes (an ulp off H) take the very steps simulate takes
    for column in ("x", "v", "reaction"):
        np.testing.assert_array_equal(result[column], getattr(library, column))
    assert np.abs(library.x).max() > 1e-2
    without = simulate_fmu(str(fmu), stop_time=stop, output_interval=scene.solver.output_interval,
                           start_values={"stepper": stepper, "scene_load": False}, output=["x"])
    assert np.abs(without["x"] - library.x).max() > 1e-6  # the switch matters: F alone is 0 here


@pytest.mark.parametrize("stepper", ["projected", "implicit", "verlet", pytest.param("symplectic", marks=pytest.mark.slow),
                                     pytest.param("exact", marks=pytest.mark.slow)])
# the paper's loops both ways compile for other tests anyway; the others' loops without the account for this test alone
@pytest.mark.parametrize("name", ["paper", pytest.param("stribeck-series", marks=pytest.mark.slow),
                                  pytest.param("coulomb-series", marks=pytest.mark.slow)])
def test_the_energy_account_never_changes_the_motion(fmus, name, stepper):
    """A run that keeps the energy account (the FMU's element always does) moves as one that does not, bit for
    bit: the booking reads the step's forces and never writes the state (exact: the same matrix exponential)."""
    scene = load_scene(fmus[name][1])
    try:
        scene.with_solver(stepper=stepper)
    except ValueError:
        pytest.skip(f"{stepper} does not apply to this scene")
    scene = scene.with_solver(stepper=stepper, stop_time=min(scene.solver.stop_time, 20.0))
    plain, booked = simulate(scene, states=True), simulate(scene, states=True, energy=True)
    for column in ("x", "v", "reaction", "u"):
        np.testing.assert_array_equal(getattr(booked, column), getattr(plain, column))
    assert booked.energy is not None and np.abs(plain.x).max() > 1e-3


def logged(messages):
    """An FMI 2.0 logger for FMPy that keeps (status, category, message)."""
    def logger(env, instance, status, category, message):
        messages.append((status, category.decode("utf-8"), message.decode("utf-8")))
    return logger


def test_a_fresh_fmu_of_a_scene_with_a_load_runs_that_load(fmus):
    """Issue 44.3: ``fmpy simulate`` of a fresh FMU (no start values, logging off) is the library's run of its
    scene, not a flat line: scene_load starts true when the scene names a load, and the FMU says so once, as a
    warning that reaches the logger whatever loggingOn says."""
    fmu, scene_path = fmus["paper"]
    scene = load_scene(scene_path)
    variables = {v.name: v for v in read_model_description(fmu).modelVariables}
    assert variables["scene_load"].start == "true"
    messages = []
    result = simulate_fmu(str(fmu), output=["x", "v", "reaction"], logger=logged(messages))
    interval = result["time"][1]  # FMPy's own output grid (it takes stop_time / 500 here), on the step grid
    library = simulate(scene.with_solver(output_interval=round(interval, 12)))
    assert len(result) == len(library.time) and result["time"][-1] == pytest.approx(scene.solver.stop_time)
    for column in ("x", "v", "reaction"):
        np.testing.assert_array_equal(result[column], getattr(library, column))
    assert np.abs(library.x).max() > 0.1  # not a flat line
    notice = scene_load_notice(scene, "the element")
    assert messages == [(1, "logStatusWarning", notice)]  # fmi2Warning, once, with logging off


def test_scene_load_false_drives_the_element_by_f_alone(fmus):
    fmu, scene_path = fmus["paper"]
    messages = []
    times = np.round(np.arange(0, 20.0 + 0.05, 0.1), 12)
    forces = 0.3 * np.sin(0.9 * times)
    result = simulate_fmu(str(fmu), stop_time=20.0, output_interval=0.1, start_values={"scene_load": False},
                          input=held_input(times, forces), output=["x", "v", "reaction"], logger=logged(messages))
    expected = element_run(scene_path, "projected", times, forces)  # F alone
    np.testing.assert_allclose(np.column_stack([result["x"], result["v"], result["reaction"]]), expected,
                               rtol=0, atol=1e-12)  # (the library's steps are cut at the rounded times)
    assert np.abs(expected[:, 0]).max() > 1e-2 and messages == []  # nothing to say: no load is added


def test_the_stiffness_output_is_the_tangent_of_the_sticking_branches(fmus):
    """Against the rule written out: k0 + 3 k3 x^2 + k_i of every branch not pushed on its threshold by v."""
    fmu, scene_path = fmus["all-effects"]
    scene = load_scene(scene_path)
    element = Element(scene)
    slave = Slave(fmu)
    k, eta = scene.branches.stiffness, scene.branches.yield_displacement
    seen = set()
    try:
        for j in range(400):
            force = 1.5 * np.sin(0.05 * j)
            slave.step(0.05, force)
            element.advance(0.05, force)
            x, v, stiffness = slave.get("x", "v", "stiffness")
            u = element.elongations()
            direction = -1.0 if v < 0 else 1.0
            sliding = (np.abs(u) >= eta) & (np.sign(u) == direction)
            expected = scene.spring.k0 + 3 * scene.cubic.k3 * x * x + k[~sliding].sum()
            assert stiffness == pytest.approx(expected, rel=1e-12, abs=1e-15)
            seen.add(int(sliding.sum()))
    finally:
        slave.close()
    assert len(seen) >= 3  # sticking, some and all branches sliding were all met


def test_held_input_of_the_library_equals_a_constant_load_scene():
    """Element.advance under a held force is simulate() with a constant load."""
    tables = base_tables(load={"kind": "constant", "value": 0.9})
    scene = parse_scene(scene_text(tables), "const.toml")
    for stepper in ("projected", "implicit"):
        expected = simulate(scene.with_solver(stop_time=5.0, output_interval=0.1), stepper)
        element = Element(scene, stepper=stepper)
        xs = [element.x]
        for _ in range(50):
            element.advance(0.1, 0.9)
            xs.append(element.x)
        np.testing.assert_array_equal(xs, expected.x)


@pytest.mark.parametrize("stepper", ["projected", "implicit"])
def test_hand_stepped_variable_steps_agree_with_the_library(fmus, stepper):
    fmu, scene_path = fmus["all-effects"]
    rng = np.random.default_rng(3)
    # multiples of h, non-multiples, tiny, zero and very large steps
    sizes = np.concatenate([[1e-3, 2.5e-3, 0.0, 1e-7, 0.3337, 7.0], rng.uniform(1e-4, 0.2, 60)])
    forces = rng.uniform(-2, 2, len(sizes))
    slave = Slave(fmu, start_values={"stepper": stepper})
    element = Element(load_scene(scene_path), stepper=stepper)
    try:
        for size, force in zip(sizes, forces):
            slave.step(size, force)
            element.advance(size, force)
            np.testing.assert_allclose(slave.get("x", "v", "reaction"),
                                       [element.x, element.v, element.reaction], rtol=0, atol=1e-12)
    finally:
        slave.close()


def test_outputs_are_consistent_after_initialization(fmus):
    fmu, scene_path = fmus["all-effects"]
    slave = Slave(fmu, start_values={"x0": 0.3, "v0": -0.5, "k0": 2.0})
    try:
        x, v, reaction = slave.get("x", "v", "reaction")
        scene = load_scene(scene_path)
        u0 = scene.branches.u0
        expected = 2.0 * 0.3 + 0.05 * 0.3**3 + 0.01 * -0.5 + scene.branches.stiffness @ u0
        assert (x, v) == (0.3, -0.5)
        assert reaction == pytest.approx(expected, rel=1e-15)
    finally:
        slave.close()


def test_state_rollback_and_serialization_give_identical_continuations(fmus):
    fmu, _ = fmus["paper"]
    slave = Slave(fmu, start_values={"stepper": "implicit"})
    other = Slave(fmu, unzipdir=slave.unzipdir, name="other")
    try:
        for k in range(40):
            slave.step(0.25, 0.45 * np.cos(0.5 * slave.time))
        slave.set("step", 2e-3)  # settings are part of the state too
        state = slave.fmu.getFMUstate()
        blob = slave.fmu.serializeFMUstate(state)
        data = json.loads(bytes(blob))  # plain JSON: nothing in it can run
        element = data["element"]  # n = 100 branches: the memory stack, its pieces and the elongations they refer to
        assert element["branch_kernel"] == "stack" and len(element["u_reference"]) == 100
        assert data["settings"]["step"] == 2e-3

        def continuation(s):
            out = []
            for k in range(30):
                s.step(0.3, 0.6 * np.sin(0.9 * k))
                out.append(s.get("x", "v", "reaction"))
            return np.array(out)

        start = slave.time
        first = continuation(slave)
        slave.fmu.setFMUstate(state)
        slave.time = start
        second = continuation(slave)
        np.testing.assert_array_equal(first, second)
        # another instance, restored from the serialized bytes
        restored = other.fmu.deSerializeFMUstate(blob)
        other.fmu.setFMUstate(restored)
        other.time = start
        np.testing.assert_array_equal(continuation(other), first)
        slave.fmu.freeFMUstate(state)
        other.fmu.freeFMUstate(restored)
    finally:
        slave.close()
        other.close()


@pytest.mark.parametrize("name, value, culprit", [
    ("F", float("nan"), "F = nan"),
    ("F", float("inf"), "F = inf"),
    ("m", 0.0, "m: must be > 0, got 0.0"),
    ("m", -1.0, "m: must be > 0, got -1.0"),
    ("k0", -3.0, "k0: must be >= 0, got -3.0"),
    ("c", float("nan"), "c: must be finite, got nan"),
    ("step", 0.0, "step = 0.0"),
    ("stepper", "rk4", "stepper = 'rk4'"),
])
def test_bad_values_are_refused_and_the_state_is_unchanged(fmus, name, value, culprit):
    fmu, _ = fmus["all-effects"]
    slave = Slave(fmu)
    try:
        for _ in range(10):
            slave.step(0.1, 0.8)
        before = slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())
        outputs = slave.get("x", "v", "reaction")
        slave.set(name, value)
        with pytest.raises(FMICallException) as refused:
            slave.fmu.doStep(slave.time, 0.1)
        assert refused.value.status == 2  # fmi2Discard, not fatal
        assert any(culprit in message for _, message in slave.messages), slave.messages
        assert slave.get("x", "v", "reaction") == outputs
        after = json.loads(bytes(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())))
        assert after["element"] == json.loads(bytes(before))["element"]
        # a good value again, and the element goes on
        good = {"F": 0.8, "m": 1.0, "k0": 0.2, "c": 0.01, "step": 1e-3, "stepper": "projected"}[name]
        slave.set(name, good)
        slave.step(0.1)
        assert slave.get("x") != outputs[0]
    finally:
        slave.close()


def test_instances_are_independent_and_reset_works(fmus):
    fmu, scene_path = fmus["all-effects"]
    first = Slave(fmu, name="first")
    second = Slave(fmu, unzipdir=first.unzipdir, name="second", start_values={"stepper": "implicit"})
    one, two = Element(load_scene(scene_path)), Element(load_scene(scene_path), stepper="implicit")
    try:
        for k in range(50):
            first.step(0.1, 1.5)
            second.step(0.1, -0.7)
            one.advance(0.1, 1.5)
            two.advance(0.1, -0.7)
        assert first.get("x") == pytest.approx(one.x, abs=1e-12)
        assert second.get("x") == pytest.approx(two.x, abs=1e-12)
        first.fmu.reset()
        first.fmu.setupExperiment(startTime=0.0)
        first.fmu.enterInitializationMode()
        first.fmu.exitInitializationMode()
        first.time = 0.0
        assert first.get("x", "v") == [0.0, 0.0]
        assert second.get("x") == pytest.approx(two.x, abs=1e-12)
    finally:
        first.close()
        second.close()


CYCLES = """
import gc, sys
sys.path.insert(0, sys.argv[2])
from fmu_tools import Slave, rss_bytes
fmu = sys.argv[1]
first = Slave(fmu)
unzipdir = first.unzipdir
first.close()

def cycles(count):
    for _ in range(count):
        slave = Slave(fmu, unzipdir=unzipdir)
        slave.step(0.01, 0.1)
        slave.close()

cycles(400)  # warm up: allocator pools, compiled kernels (the first few hundred cycles grow ~3.5 MiB, then ~1 KiB each)
gc.collect()
before = rss_bytes()
cycles(500)
gc.collect()
print(rss_bytes() - before)
"""


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_instantiate_free_cycles_do_not_grow_memory(fmus):
    """Measured in a process of its own, so that nothing else the tests do is counted."""
    import subprocess
    import sys

    fmu, _ = fmus["paper"]
    run = subprocess.run([sys.executable, "-c", CYCLES, str(fmu), str(TESTS)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    grown = int(run.stdout.strip().splitlines()[-1])
    assert grown < 2 * 2**20, f"grew by {grown / 2**20:.1f} MiB over 500 cycles"  # 4 KiB a cycle at most


@pytest.mark.parametrize("stepper", ["symplectic", "verlet", "exact"])
def test_every_stepper_runs_inside_the_fmu(fmus, stepper):
    fmu, scene_path = fmus["damper-only"]
    sizes = [0.1, 0.25, 0.037, 1.0, 0.5]
    slave = Slave(fmu, start_values={"stepper": stepper})
    element = Element(load_scene(scene_path), stepper=stepper)
    try:
        for k, size in enumerate(sizes * 4):
            force = 0.7 * np.cos(0.3 * k)
            slave.step(size, force)
            element.advance(size, force)
            np.testing.assert_allclose(slave.get("x", "v", "reaction"), [element.x, element.v, element.reaction],
                                       rtol=0, atol=1e-12)
    finally:
        slave.close()


def test_a_stepper_that_does_not_apply_is_refused(fmus):
    fmu, _ = fmus["all-effects"]  # has a cubic spring: `exact` does not apply
    slave = Slave(fmu)
    try:
        slave.step(0.1, 0.5)
        slave.set("stepper", "exact")
        with pytest.raises(FMICallException) as refused:
            slave.fmu.doStep(slave.time, 0.1)
        assert refused.value.status == 2
        assert any("no [cubic]" in message for _, message in slave.messages)
    finally:
        slave.close()


@pytest.mark.parametrize("name, stepper", [("continuum", "projected"), ("continuum", "verlet"), ("iwan", "verlet")])
def test_the_continuous_element_as_an_fmu(fmus, name, stepper):
    """The continuum (infinitely many branches; the paper's spectrum, Segalman's Iwan model) in an FMU: equal
    to the library, its state saved and restored as plain data, and a stepper that cannot take it refused."""
    fmu, scene_path = fmus[name]
    dt, stop = 0.05, 20.0
    times = np.round(np.arange(0, stop + dt / 2, dt), 12)
    forces = 0.6 * np.cos(0.7 * times) + 0.2 * np.sin(2.3 * times)
    result = simulate_fmu(str(fmu), stop_time=stop, output_interval=dt, input=held_input(times, forces),
                          start_values={"stepper": stepper, "scene_load": False},
                          output=["x", "v", "reaction", "dissipated_sliders"])
    expected = element_run(scene_path, stepper, times, forces)
    np.testing.assert_allclose(np.column_stack([result["x"], result["v"], result["reaction"]]), expected,
                               rtol=0, atol=1e-12)
    assert result["dissipated_sliders"][-1] > 0
    slave = Slave(fmu, start_values={"stepper": stepper})
    try:
        for k in range(30):
            slave.step(0.2, 0.7 * np.cos(0.4 * k))
        blob = slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())
        assert json.loads(bytes(blob))["element"]["branch_kernel"] == "stack"
        first = [slave.step(0.2, 0.3) or slave.get("x", "reaction") for _ in range(10)]
        slave.fmu.setFMUstate(slave.fmu.deSerializeFMUstate(blob))
        slave.time -= 2.0
        np.testing.assert_array_equal([slave.step(0.2, 0.3) or slave.get("x", "reaction") for _ in range(10)], first)
        slave.set("stepper", "implicit")
        with pytest.raises(FMICallException):
            slave.fmu.doStep(slave.time, 0.1)
        assert any("continuum" in message for _, message in slave.messages)
    finally:
        slave.close()


SHARED_LIBRARY_RUN = """
import json, shutil, sys
sys.path[:0] = sys.argv[1].split("|")
from fmpy import extract
from tests.conftest import restore_fmpy_logger
import fmpy
runs = []
for fmu, column in zip(sys.argv[2::2], sys.argv[3::2]):
    folder = extract(fmu)
    result = fmpy.simulate_fmu(folder, stop_time=2.0, output_interval=0.1, output=[column])
    restore_fmpy_logger()
    shutil.rmtree(folder)  # as FMPy does with its own extraction: the library must not need it any more
    runs.append([float(value) for value in result[column]])
libraries = {name: module.__name__ for name, module in sys.modules.items()
             if name.startswith("_prandtl_slave_") and "." not in name}
private = sorted(name for name in sys.modules if name.startswith("_prandtl_slave_") and "." in name)
print(json.dumps({"runs": runs, "libraries": libraries, "private_modules": len(private),
                  "host": getattr(sys.modules.get("prandtl_fmu"), "__file__", None)}))
"""


def run_in_a_host(fmus_and_columns, path=(), bundled=False):
    """Run the FMUs in a fresh Python (``path`` first on its sys.path, then the project), in one process; what
    it reports (SHARED_LIBRARY_RUN)."""
    import os
    import subprocess
    import sys

    from tests.conftest import ROOT

    env = {**os.environ, "PRANDTL_FMU_BUNDLED_LIBRARY": "1" if bundled else "0"}
    arguments = [str(part) for fmu, column in fmus_and_columns for part in (fmu, column)]
    done = subprocess.run([sys.executable, "-c", SHARED_LIBRARY_RUN, "|".join([*map(str, path), str(ROOT)]),
                           *arguments], capture_output=True, text=True, timeout=900, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def library_runs(scene_paths_and_columns):
    return [simulate(load_scene(path).with_solver(stop_time=2.0, output_interval=0.1)).columns()[column]
            for path, column in scene_paths_and_columns]


@pytest.mark.slow  # a long check (the quick suite's cold budget, README): a second library compiles for the FMU
@pytest.mark.parametrize("second", ["damper-only", "network"])
def test_fmus_of_one_library_share_it_whatever_their_scenes(fmus, tmp_path, second):
    """The FMUs built from the same sources import one library under one name (fmu/python/entry.py), so their
    kernels compile once, and a second FMU runs after the first one's extraction folder is gone (a mass on a
    dashpot: other kernels). The FMU's own copy is forced (PRANDTL_FMU_BUNDLED_LIBRARY=1): the host's prandtl_fmu has the same
    sources. The network (slow: its kernels compile for the FMU's library) needs modules an element's FMU never
    imports: they come from the library's lasting copy. The first FMU is a mass on a spring: the copy compiles
    every kernel it runs under its own name, the fewest here."""
    element, element_scene = fmus["oscillator"]
    if second == "network":
        other_scene, column = SCENES / "networks" / "two-masses-slider.toml", "x_b"
        other = build_fmu(other_scene, tmp_path / "network.fmu")
    else:
        (other, other_scene), column = fmus[second], "x"
    found = run_in_a_host([(element, "x"), (other, column)], bundled=True)
    assert len(found["libraries"]) == 1, found["libraries"]
    (name, package), = found["libraries"].items()
    assert package == name and found["private_modules"] > 0  # the copy, under its private name
    for run, library in zip(found["runs"], library_runs([(element_scene, "x"), (other_scene, column)])):
        np.testing.assert_array_equal(run, library)


def test_the_host_s_prandtl_fmu_runs_the_fmu_only_if_its_sources_are_the_fmu_s(fmus, tmp_path):
    """An FMU whose host has a prandtl_fmu with its sources, file for file, runs that one (its kernels are those
    the host compiled: no copy compiles them again); a host whose prandtl_fmu differs by one file gets the FMU's
    own copy under its private name. Both are the library's numbers, bit for bit."""
    import shutil

    from tests.conftest import ROOT

    element, element_scene = fmus["paper"]
    expected = library_runs([(element_scene, "x")])

    same = run_in_a_host([(element, "x")])
    (name, package), = same["libraries"].items()
    assert package == "prandtl_fmu" and same["private_modules"] == 0
    assert same["host"] == str(ROOT / "prandtl_fmu" / "__init__.py")
    np.testing.assert_array_equal(same["runs"][0], expected[0])

    other_host = tmp_path / "other"
    shutil.copytree(ROOT / "prandtl_fmu", other_host / "prandtl_fmu", ignore=shutil.ignore_patterns("__pycache__"))
    (other_host / "prandtl_fmu" / "edited.py").write_text('"""One more module: other sources."""\n')
    small, small_scene = fmus["oscillator"]  # the copy's kernels: a mass on a spring's (the test above's)
    other = run_in_a_host([(small, "x")], path=[other_host])
    assert other["host"] is None or other["host"].startswith(str(other_host))
    (name, package), = other["libraries"].items()
    assert package == name and other["private_modules"] > 0
    np.testing.assert_array_equal(other["runs"][0], library_runs([(small_scene, "x")])[0])
