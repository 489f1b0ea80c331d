"""The native FMU (``--runtime native``, issue 24): the library's kernels and a C FMI layer, no Python in the binary.

Bit for bit the library (every native stepper, random communication steps, every output), in FMPy and in the
small C host of tests/c_host run with no Python at all; a binary that names no Python symbol; refusals as the
PythonFMU FMU makes them; a checked FMU state; two instances on two threads."""
import contextlib
import json
import math
import os
import shutil
import subprocess
import sys
import threading
import zipfile

import numpy as np
import pytest

from prandtl_fmu import load_scene, parse_scene, simulate
from prandtl_fmu.element import Element
from prandtl_fmu.fmu.native.kernels import NATIVE_STEPPERS

from tests.conftest import ROOT, SCENES as SCENE_FOLDER, base_tables, scene_text
from tests.native_host import Extracted, compile_host, run_host

pytest.importorskip("fmpy")
if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)

PAPER = SCENE_FOLDER / "paper-section-8.toml"
ENERGIES = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
            "dissipated_friction", "energy_residual")
SOLVER = {"stepper": "implicit", "step": 0.01, "stop_time": 10.0, "output_interval": 0.1}
SCENES = {
    # mass, spring, dashpot, branches, a harmonic load (cubic: the default tables have one)
    "smooth": base_tables(mass={"m": 1.0, "x0": 0.05, "v0": 0.0}, solver=SOLVER,
                          load={"kind": "harmonic", "amplitude": 0.8, "omega": 1.3}),
    # friction on the mass (Stribeck, a belt) and series dashpots, a table load
    "friction": base_tables(cubic=None, solver=SOLVER,
                            friction={"alpha": 0.3, "alpha_kinetic": 0.2, "stribeck_velocity": 0.1,
                                      "belt_velocity": 0.05},
                            branches={"k": [0.5, 0.3, 0.2], "eta": [0.1, 0.3, 0.6], "c": [0.4, 2.0, 9.0]},
                            load={"kind": "table", "time": [0.0, 3.0, 6.0, 10.0], "force": [0.0, 0.6, -0.5, 0.2]}),
    # what exact takes: Coulomb friction, series dashpots (exact in the native FMU allocates: numba's runtime in C)
    "coulomb": base_tables(cubic=None, solver=dict(SOLVER, stepper="exact"), friction={"alpha": 0.1},
                           branches={"k": [0.5, 2.0, 0.3], "eta": [0.1, 0.3, 0.05], "c": [0.4, 2.0, 9.0]},
                           load={"kind": "harmonic", "amplitude": 0.8, "omega": 1.3}),
    # massless: the dashpot sets the rate
    "massless": base_tables(mass=None, cubic=None, solver=dict(SOLVER, stepper="implicit"),
                            load={"kind": "harmonic", "amplitude": 0.6, "omega": 0.9}),
    # massless and no dashpot: x is the equilibrium of F at every step (implicit only)
    "rigid": base_tables(mass=None, damper=None, solver=dict(SOLVER, stepper="implicit"),
                         load={"kind": "harmonic", "amplitude": 0.6, "omega": 0.9}),
    # the paper's section 8: 100 branches on the memory stack (unfolded to 100 elongations for exact)
    "paper": None,
    # the continuum (a spectrum on the memory stack)
    "continuum": base_tables(cubic=None, damper=None, mass={"m": 1.0, "x0": 0.05, "v0": 0.0},
                             branches={"continuum": True, "k_total": 1.0, "eta_range": [0.0, 1.0]},
                             solver=dict(SOLVER, stepper="verlet"),
                             load={"kind": "harmonic", "amplitude": 0.8, "omega": 1.3}),
}


class Built(dict):
    """FMUs built on first use (``build(name)``): a run of the quick suite builds only the scenes it tests."""

    def __init__(self, build):
        super().__init__()
        self.build = build

    def __missing__(self, name):
        self[name] = self.build(name)
        return self[name]


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    from prandtl_fmu.fmu.build import build_fmu

    folder = tmp_path_factory.mktemp("native")

    def build(name):
        path = folder / f"{name}.toml"
        path.write_text(scene_text(SCENES[name]) if SCENES[name] else PAPER.read_text())
        return build_fmu(path, folder / f"{name}.fmu", runtime="native"), path

    return Built(build)


# The scenes whose FMUs the tests of the C layer use (states, refusals, hosts, warnings, threads, FMI 3.0) hold only
# the steppers those tests set (build --steppers): fewer loops to compile. The comparisons of every stepper build them
# whole (``fmus``).
HELD = {"friction": "projected,implicit", "smooth": "projected,implicit,verlet"}


@pytest.fixture(scope="module")
def held(tmp_path_factory):
    from prandtl_fmu.fmu.build import build_fmu

    folder = tmp_path_factory.mktemp("held")

    def build(name):
        path = folder / f"{name}.toml"
        path.write_text(scene_text(SCENES[name]))
        return build_fmu(path, folder / f"{name}.fmu", runtime="native", steppers=HELD[name]), path

    return Built(build)


# the scenes whose FMU comparisons run in the quick suite; the others (also covered by the random native scenes)
# under the slow marker ("coulomb", exact with friction, 47 s cold; "friction", a native build and its runs, 52 s
# on a loaded machine: the quick suite's budget)
QUICK = ("paper",)


def quick_or_slow(names):
    return [name if name in QUICK else pytest.param(name, marks=pytest.mark.slow) for name in names]


def steppers_of(scene):
    from prandtl_fmu.fmu.native.kernels import applicable

    return applicable(scene)


def outputs(slave, names):
    return slave.fmu.getReal([slave.vr[name] for name in names])


def expected(element, names):
    values = {"x": element.x, "v": element.v, "reaction": element.reaction, "stiffness": element.stiffness()}
    return [values[name] if name in values else element.energy_of(name) for name in names]


def same(got, want):
    """To the bit, NaN as NaN (a NaN output would itself be a refusal the test reports elsewhere)."""
    return len(got) == len(want) and all(a == b or (a != a and b != b) for a, b in zip(got, want))


def step_both(slave, element, rng, names, label):
    """One random communication step (not always a multiple of the step) under a random force, in the FMU and
    in the library's Element; every output in ``names`` to the bit."""
    size, force = float(rng.choice([0.013, 0.05, 0.1, 0.0371])), float(rng.uniform(-1, 1))
    time = slave.time
    slave.step(size, force)
    element.time = time
    element.advance(size, force)
    assert same(outputs(slave, names), expected(element, names)), (label, time)


@contextlib.contextmanager
def fmu_and_element(fmu, scene, stepper):
    """``(slave, element, names)``: the FMU in FMPy and the library's Element of its scene, both on ``stepper``,
    and the outputs to compare (the motion, the stiffness and the energy account the FMU has); the slave closed
    after."""
    from tests.fmu_tools import Slave

    slave = Slave(fmu, start_values={"stepper": stepper})
    try:
        yield slave, Element(scene, stepper=stepper), ["x", "v", "reaction", "stiffness"] + [
            name for name in ENERGIES if name in slave.vr]
    finally:
        slave.close()


@pytest.mark.parametrize("name", quick_or_slow(SCENES))
def test_the_native_fmu_in_fmpy_is_the_library_bit_for_bit(fmus, name):
    """Every native stepper, random communication steps (some not multiples of the step) and forces: x, v, the
    reaction, the stiffness and the energy account equal Element.advance's to the bit."""
    fmu, scene_path = fmus[name]
    scene = load_scene(scene_path)
    tried = steppers_of(scene)
    assert tried and ("exact" in tried) == (name in ("coulomb", "paper"))
    for stepper in tried:
        rng = np.random.default_rng(7)
        with fmu_and_element(fmu, scene, stepper) as (slave, element, names):
            for _ in range(40):
                step_both(slave, element, rng, names, stepper)
        assert abs(element.x) > 1e-3  # it moved


def test_on_the_memory_stack_exact_unfolds_and_folds_back_as_the_library(fmus):
    """The paper's 100 branches run on the memory stack, which exact does not take: switching to exact unfolds
    them to 100 elongations and switching back folds them into a stack that refers to the elongations of then
    (driver.Element._use_branch_kernel); every output stays the library's to the bit, through every switch and
    an FMU state saved while unfolded."""
    from tests.fmu_tools import Slave

    fmu, scene_path = fmus["paper"]
    scene = load_scene(scene_path)
    plan = ["projected", "exact", "implicit", "exact", "exact", "verlet", "symplectic", "exact", "projected"]
    slave = Slave(fmu, start_values={"stepper": plan[0], "step": 0.01})
    element = Element(scene, stepper=plan[0], step=0.01)
    names = ["x", "v", "reaction", "stiffness", "stored_energy", "dissipated_sliders", "energy_residual"]
    rng = np.random.default_rng(3)
    kernels, saved = [], None
    try:
        for k, stepper in enumerate(plan):
            if k:
                slave.fmu.setString([slave.vr["stepper"]], [stepper])
                element.set_stepper(stepper)
            kernels.append(element.branch_kernel)
            for _ in range(12):
                step_both(slave, element, rng, names, stepper)
            if k == 3:  # unfolded: the state holds the elongations and the stack's parameters as folded last
                saved, checkpoint, at = slave.fmu.getFMUstate(), element.get_state(), slave.time
        assert kernels == ["stack", "play", "stack", "play", "play", "stack", "stack", "play", "stack"]
        slave.fmu.setFMUstate(saved)
        element.set_state(checkpoint)
        slave.time = at
        for stepper in ("exact", "projected"):  # the saved stepper runs on, then a fold from the restored state
            slave.fmu.setString([slave.vr["stepper"]], [stepper])
            element.set_stepper(stepper)
            for size, force in ((0.05, 0.3), (0.1, -0.7)):
                time = slave.time
                slave.step(size, force)
                element.time = time
                element.advance(size, force)
                assert same(outputs(slave, names), expected(element, names)), stepper
    finally:
        slave.close()


def test_a_state_whose_memory_stack_parameters_are_not_the_scene_s_is_refused(fmus):
    """The element's state holds the stack's parameters as folded last (their rows of the elongations change at a
    fold, the others are the scene's): a blob whose eta row was changed, its checksum made right, is refused
    with fmi2Error and its reason; the instance steps on."""
    import struct

    from fmpy.fmi1 import FMICallException

    from tests.fmu_tools import Slave

    from prandtl_fmu.kernels import stack

    fmu, scene_path = fmus["paper"]
    branches = load_scene(scene_path).branches
    params, _ = stack.prepare(branches.stiffness, branches.yield_displacement, branches.u0)
    slave = Slave(fmu)
    try:
        slave.step(0.3, 0.4)
        blob = bytearray(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate()))
        row = params[stack.ETA_ROW].tobytes()
        at = bytes(blob).find(row)
        assert at > 0 and bytes(blob).find(row, at + 1) < 0
        blob[at + 8 * 5:at + 8 * 6] = struct.pack("<d", params[stack.ETA_ROW, 5] * 1.5)
        digest = 1469598103934665603
        for byte in blob[:-8]:  # common.h's fnv1a: the checksum is the blob's last field
            digest = ((digest ^ byte) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
        blob[-8:] = struct.pack("<Q", digest)
        slave.messages.clear()
        with pytest.raises(FMICallException) as refused:
            slave.fmu.deSerializeFMUstate(bytes(blob))
        assert refused.value.status == 3
        assert any("memory-stack parameters are not this scene's" in message for _, message in slave.messages), \
            slave.messages
        slave.step(0.1, 0.2)
    finally:
        slave.close()


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_with_scene_load_the_native_fmu_reproduces_simulate_with_each_stepper_it_holds(held):
    """The friction FMU holds projected and implicit (build --steppers): each is the library's run, bit for bit
    (the library keeps the energy account, as the FMU's element does: one compiled loop for both)."""
    from fmpy import simulate_fmu

    fmu, scene_path = held["friction"]
    scene = load_scene(scene_path)
    for stepper in HELD["friction"].split(","):
        library = simulate(scene, stepper=stepper, energy=True)
        result = simulate_fmu(str(fmu), stop_time=scene.solver.stop_time, output_interval=scene.solver.output_interval,
                              start_values={"scene_load": True, "stepper": stepper}, output=["x", "v", "reaction"])
        for column in ("x", "v", "reaction"):
            np.testing.assert_array_equal(result[column], getattr(library, column))
        assert np.abs(library.x).max() > 1e-2


@pytest.mark.slow  # (the quick suite does not build this scene)
def test_a_step_longer_than_the_communication_step_is_cut_to_it(held):
    """step = 1e300 s: each doStep of 1 s is one step of 1 s, as Element(scene, step=1e300) takes it (the FMU
    returned fmi2OK and never moved: the whole communication step counted as a clock's rounding)."""
    from tests.fmu_tools import Slave

    fmu, scene_path = held["smooth"]
    scene = load_scene(scene_path)
    slave = Slave(fmu, start_values={"stepper": "implicit", "step": 1e300})
    element = Element(scene, stepper="implicit", step=1e300)
    names = ["x", "v", "reaction"]
    try:
        for force in (5.0, 5.0, -2.0, 0.0):
            slave.step(1.0, force)
            element.advance(1.0, force)
            assert same(outputs(slave, names), expected(element, names)), force
        assert element.x != 0.0 and element.time == 4.0
        assert not [m for m in slave.messages if m[0] != 0], slave.messages
    finally:
        slave.close()


def test_a_dashpot_set_to_zero_and_back_mid_run_is_the_library_bit_for_bit(held):
    """A massive element's dashpot set to c = 0 (and -0.0) by the master and back, mid-run, under every stepper
    the FMU holds: x, v, the reaction, the stiffness and the energy account equal Element.advance's with the same
    coefficients to the bit, the sign of a zero too (c = 0 runs the same compiled functions as c > 0: for a mass,
    no dashpot is the dashpot of c = 0; -0.0 is handed on as 0.0, as the library's model has it)."""
    fmu, scene_path = held["smooth"]
    scene = load_scene(scene_path)
    assert scene.mass is not None and scene.damper is not None
    for stepper in HELD["smooth"].split(","):
        rng = np.random.default_rng(11)
        with fmu_and_element(fmu, scene, stepper) as (slave, element, names):
            for j in range(60):
                if j in (15, 30, 40, 50):
                    c = {15: 0.0, 30: 0.35, 40: -0.0, 50: 0.35}[j]
                    slave.set("c", c)
                    element.set_coefficients(c=c)
                step_both(slave, element, rng, names, (stepper, j))
                got = np.array(outputs(slave, names)).tobytes()
                assert got == np.array(expected(element, names)).tobytes(), (stepper, j)  # -0.0 apart too
        assert abs(element.x) > 1e-3 and element.scene.damper.c == 0.35


def test_an_fmu_built_with_some_steppers_names_them_and_refuses_the_others(held):
    """The model description's stepper parameter and the page name the steppers held; another one that applies to
    the scene is refused at doStep with a logged reason that lists them, and the instance stays usable."""
    from fmpy import read_model_description
    from fmpy.fmi1 import FMICallException

    from tests.fmu_tools import Slave

    fmu, _ = held["friction"]
    stepper = next(v for v in read_model_description(str(fmu)).modelVariables if v.name == "stepper")
    assert stepper.description.startswith("time stepper: projected, implicit (the steppers this FMU holds")
    page = zipfile.ZipFile(fmu).read("documentation/index.html").decode("utf-8")
    for name in ("symplectic", "verlet"):
        assert f"<td>{name}</td><td>no: not in this FMU (built with --steppers projected,implicit)</td>" in page
    assert "<td>implicit</td><td>default</td>" in page and "<td>projected</td><td>yes</td>" in page
    assert "<td>exact</td><td>no: " in page and "not in this FMU" not in page.split("<td>exact</td>")[1][:80]
    slave = Slave(fmu)
    try:
        slave.step(0.1, 0.5)
        slave.set("stepper", "verlet")
        slave.messages.clear()
        with pytest.raises(FMICallException):
            slave.fmu.doStep(slave.time, 0.1)
        assert any("must be one of projected, implicit (the steppers this FMU holds)" in message
                   for _, message in slave.messages), slave.messages
        slave.set("stepper", "projected")
        slave.step(0.1, 0.5)
        assert np.isfinite(slave.get("x"))
    finally:
        slave.close()


@pytest.mark.parametrize("fmi", [2, pytest.param(3, marks=pytest.mark.slow)])
def test_a_fresh_fmu_in_fmpy_runs_its_scene_and_says_so(fmus, fmus3, fmi):
    """Issue 44.3: ``fmpy simulate`` of a fresh paper-section-8 FMU (no start value, no input) is the library's
    ``simulate`` of the scene, bit for bit at the output grid, not a flat line: scene_load starts true when the
    scene names a load. Leaving initialization with it true logs the scene_load notice as a warning (category
    logStatusWarning) with logging off, and the call returns OK."""
    from fmpy import simulate_fmu

    from prandtl_fmu.fmu.description import scene_load_notice

    fmu, scene_path = (fmus if fmi == 2 else fmus3)["paper"]
    scene = load_scene(scene_path)
    library = simulate(scene)
    logged = []

    def logger(*arguments):  # FMI 2.0: env, instance, status, category, message; FMI 3.0: env, status, ...
        logged.append((arguments[-3], arguments[-2].decode(), arguments[-1].decode()))

    result = simulate_fmu(str(fmu), output_interval=scene.solver.output_interval, output=["x", "v", "reaction"],
                          logger=logger, debug_logging=False)  # (FMPy's own default grid is 1/500 of the run)
    assert result["time"][-1] == pytest.approx(scene.solver.stop_time)
    assert np.abs(result["x"]).max() > 0.01  # not a flat line
    for column in ("x", "v", "reaction"):
        np.testing.assert_array_equal(result[column], getattr(library, column), err_msg=column)
    assert logged == [(1, "logStatusWarning", scene_load_notice(scene, "the element"))]


FMPY_AFTER_A_LOGGER = """
import gc, sys
sys.path.insert(0, sys.argv[2])
import fmpy
from tests.conftest import restore_fmpy_logger
fmpy.simulation.simulate_fmu.__wrapped__(sys.argv[1], stop_time=1.0, logger=lambda *arguments: None)
gc.collect()  # the first call's logger callback is freed
if sys.argv[3] == "restore":
    restore_fmpy_logger()
fmpy.simulation.simulate_fmu.__wrapped__(sys.argv[1], stop_time=1.0)  # FMPy's default logger: it prints
print("second run ended")
"""


@pytest.mark.parametrize("restore", ["restore", pytest.param("no", marks=pytest.mark.slow)])
def test_fmpy_after_a_run_with_its_own_logger(fmus, restore):
    """FMPy 0.3.x's logger proxy keeps the last logger given to simulate_fmu(logger=...) in a C global: a later
    run without a logger, whose FMU logs (ours warn at the end of initialization when the scene's load runs),
    calls that freed callback. tests/conftest.py points the proxy back at a living logger after every
    simulate_fmu of the tests; without it (the slow case) the process dies, as it did in CI."""
    fmu, _ = fmus["paper"]
    done = subprocess.run([sys.executable, "-c", FMPY_AFTER_A_LOGGER, str(fmu), str(ROOT), restore],
                          capture_output=True, text=True, timeout=300)
    if restore == "restore":
        assert done.returncode == 0, done.stderr
        assert "[WARNING]" in done.stdout and "second run ended" in done.stdout, done.stdout
    else:  # FMPy's defect: should a later FMPy fix it, this says so
        assert done.returncode != 0, "FMPy no longer calls a freed logger: drop restore_fmpy_logger (conftest)"


def test_the_binary_holds_no_python(fmus, tmp_path, held):
    fmu, _ = held["friction"]
    extracted = Extracted(fmu, tmp_path / "x")
    assert not (tmp_path / "x" / "resources" / "prandtl_fmu").exists()  # no library copy, no Python source
    needed = subprocess.run(["ldd", str(extracted.library)], capture_output=True, text=True).stdout
    assert "python" not in needed.lower(), needed
    undefined = subprocess.run(["nm", "-D", "--undefined-only", str(extracted.library)], capture_output=True,
                               text=True).stdout.split()
    assert not [s for s in undefined if s.startswith(("Py", "_Py", "numba", "NRT"))], undefined
    defined = subprocess.run(["nm", "-D", "--defined-only", str(extracted.library)], capture_output=True,
                             text=True).stdout.split()[2::3]
    assert defined and all(symbol.startswith("fmi2") for symbol in defined), defined
    description = zipfile.ZipFile(fmu).read("modelDescription.xml").decode()
    assert 'needsExecutionTool="false"' in description


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    return compile_host(tmp_path_factory.mktemp("c_host"))


NO_PYTHON = {"PATH": os.environ.get("PATH", "/usr/bin:/bin")}  # no LD_PRELOAD, no PYTHONPATH


def test_in_a_c_host_with_no_python_the_native_fmu_is_the_library(fmus, host, tmp_path, held):
    fmu, scene_path = held["friction"]
    extracted = Extracted(fmu, tmp_path / "x")
    rng = np.random.default_rng(3)
    commands, t = ["setup", "enter", "setb:scene_load:0", "exit"], 0.0  # F alone, as the element is driven
    element = Element(load_scene(scene_path))
    assert element.scene.damper is not None
    reference = []
    for j in range(25):
        if j in (10, 18):  # the dashpot off and on again: c = 0 runs the functions of c > 0 (kernels.variants)
            c = 0.0 if j == 10 else 0.3
            commands.append(f"setr:c:{c!r}")
            element.set_coefficients(c=c)
        size, force = float(rng.choice([0.013, 0.05, 0.1])), float(rng.uniform(-1, 1))
        commands += [f"setr:F:{force!r}", f"step:{t!r}:{size!r}", "getr:x", "getr:v", "getr:reaction"]
        element.time = t
        element.advance(size, force)
        reference += [element.x, element.v, element.reaction]
        t += size
    code, calls, logs, values, out = run_host(host, extracted, commands + ["term", "free"], env=NO_PYTHON)
    assert code == 0, out
    assert [value for _, value in values] == reference


@pytest.mark.parametrize("logging", [False, True])
def test_refusals_in_a_c_host_are_logged_with_a_category(fmus, host, tmp_path, logging, held):
    """A bad start value: fmi2Error at fmi2ExitInitializationMode, its reason logged (logging off too) under a
    declared category; set right, the instance initializes; a non-finite F: fmi2Discard, then a good step; a
    stepper the FMU does not hold (built with ``--steppers projected,implicit``): fmi2Discard at the next step, the
    steppers it holds logged, then a good step with one of them."""
    fmu, _ = held["friction"]
    extracted = Extracted(fmu, tmp_path / "x")
    code, calls, logs, values, out = run_host(host, extracted, [
        "setup", "enter", "setr:alpha_kinetic:0.5", "exit", "setr:alpha_kinetic:0.25", "exit",
        "setr:F:inf", "step:0:0.1", "setr:F:0.5", "step:0:0.1", "getr:x",
        "sets:stepper:verlet", "step:0.1:0.1", "sets:stepper:projected", "step:0.1:0.1", "getr:x", "term", "free"],
        logging=logging, env=NO_PYTHON)
    assert code == 0, out
    assert calls["exit"] == ["3", "0"], out
    assert calls["step:0:0.1"] == ["2", "0"], out
    assert calls["sets:stepper:verlet"] == ["0"] and calls["step:0.1:0.1"] == ["2", "0"], out
    errors = [entry for entry in logs if entry[0] == 3]
    assert errors and "alpha_kinetic" in errors[0][2] and errors[0][1] == "logStatusError", logs
    assert [entry for entry in logs if entry[0] == 2 and "F = inf" in entry[2]], logs
    assert [entry for entry in logs if entry[0] == 2 and "'verlet'" in entry[2]
            and "must be one of projected, implicit (the steppers this FMU holds)" in entry[2]], logs
    assert all(category.startswith("log") for _, category, _ in logs), logs
    assert len(values) == 2 and np.isfinite(values[0][1]) and values[1][1] != values[0][1]


def test_the_fmu_state_is_a_checked_blob(fmus, held):
    """Get, step, set back, step again: the same numbers. A serialized state with one byte changed, one of another
    scene and garbage are refused with fmi2Error and their reason; the instance is unchanged."""
    from fmpy.fmi1 import FMICallException

    from tests.fmu_tools import Slave

    slave = Slave(held["friction"][0])
    other = Slave(held["smooth"][0])
    try:
        slave.step(0.3, 0.4)
        state = slave.fmu.getFMUstate()
        slave.step(0.2, -0.3)
        after = slave.get("x", "v", "reaction")
        slave.fmu.setFMUstate(state)
        slave.time -= 0.2
        slave.step(0.2, -0.3)
        assert slave.get("x", "v", "reaction") == after
        blob = bytearray(slave.fmu.serializeFMUstate(state))
        restored = slave.fmu.deSerializeFMUstate(bytes(blob))
        slave.fmu.setFMUstate(restored)
        blob[len(blob) // 2] ^= 0x01
        foreign = other.fmu.serializeFMUstate(other.fmu.getFMUstate())
        for bad, reason in ((bytes(blob), "checksum"), (foreign, "another scene"), (b"garbage", "not a serialized")):
            slave.messages.clear()
            with pytest.raises(FMICallException) as refused:
                slave.fmu.deSerializeFMUstate(bad)
            assert refused.value.status == 3
            assert any(reason in message for _, message in slave.messages), (reason, slave.messages)
        slave.step(0.1, 0.2)  # still usable
    finally:
        slave.close()
        other.close()


def test_two_instances_on_two_threads_give_the_library_numbers(fmus, held):
    """ctypes lets go of the GIL in a foreign call: both instances step at once, each its own numbers."""
    from tests.fmu_tools import Slave

    fmu, scene_path = held["smooth"]
    scene = load_scene(scene_path)
    results, errors = {}, []

    def drive(seed):
        try:
            slave = Slave(fmu, name=f"element{seed}")
            element = Element(scene)
            rng = np.random.default_rng(seed)
            for _ in range(300):
                size, force = float(rng.choice([0.01, 0.05])), float(rng.uniform(-1, 1))
                time = slave.time
                slave.step(size, force)
                element.time = time
                element.advance(size, force)
                assert slave.get("x", "v") == [element.x, element.v]
            slave.close()
            results[seed] = element.x
        except BaseException as exc:  # reported by the main thread
            errors.append(exc)

    threads = [threading.Thread(target=drive, args=(seed,)) for seed in (1, 2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not errors, errors
    assert len(results) == 2 and results[1] != results[2]


@pytest.mark.parametrize("arguments, culprit", [
    (["--runtime", "python", "--fmi", "3"], "FMI 2.0"),
])
def test_what_a_runtime_does_not_build_is_refused_in_one_line(tmp_path, arguments, culprit):
    path = tmp_path / "scene.toml"
    path.write_text(scene_text(SCENES["smooth"]))
    out = tmp_path / "out.fmu"
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "build", str(path), "-o", str(out), *arguments],
                          capture_output=True, text=True)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert culprit in done.stderr and not out.exists()


class CompiledAnyway(Exception):
    """Raised by a compile_kernels that a build must not call."""


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_the_native_kernels_call_the_library_s_loops_not_copies_for_writable_arrays():
    """The C functions hand the branches' coefficients typed read-only and the rows they do not record as arrays
    with no column, as the library does (fmu/native/kernels.py): numba then compiles no second loop for them."""
    from prandtl_fmu.fmu.native import kernels
    from prandtl_fmu.steppers import get_stepper

    scene = load_scene("paper-section-8")
    kernels.compile_kernels(scene, ["projected"])
    signatures = get_stepper("projected").loop_for(scene).signatures
    plain = 0
    for signature in signatures:
        model, out_u, out_energy = signature[0], signature[10], signature[12]
        for array in model[4:7]:  # k, eta, cs: the O(n) kernel's read-only arrays (the stack's table is its own)
            if getattr(array, "ndim", 0) == 1:
                assert not array.mutable, signature
                plain += 1
        assert out_u.ndim == 2 and out_energy.ndim == 2, signature  # never None
    assert plain  # the scene's O(n) kernel (the element unfolds the stack for some steppers) was among them


def refuse_to_compile(*arguments):
    raise CompiledAnyway()


def test_a_second_build_of_the_same_kernels_only_links(fmus, tmp_path, monkeypatch):
    """The native build's objects are kept (fmu/native/object_cache.py): building the paper scene again compiles
    nothing, and the FMU runs as the first, bit for bit; the FMI 3.0 build of the scene takes the same objects."""
    from fmpy import simulate_fmu

    from prandtl_fmu import compiling
    from prandtl_fmu.fmu.build import build_fmu
    from prandtl_fmu.fmu.native import kernels, platforms

    first, scene_path = fmus["paper"]
    monkeypatch.setattr(kernels, "compile_kernels", refuse_to_compile)
    said = []

    class Line:  # what a terminal's status line is told (compiling.stage)
        staged = said.append

    monkeypatch.setattr(compiling, "_ACTIVE", [Line()])
    again = build_fmu(scene_path, tmp_path / "again.fmu", runtime="native")
    host = platforms.host_target().name
    assert said == [f"native build: the objects for {host} (from the cache)", f"native build: linking {host}",
                    "native build: the FMU archive"], said
    build_fmu(scene_path, tmp_path / "again3.fmu", runtime="native", fmi=3)
    runs = [simulate_fmu(str(fmu), stop_time=20.0, output_interval=0.1, output=["x", "v", "reaction"])
            for fmu in (first, again)]
    for column in ("x", "v", "reaction"):
        np.testing.assert_array_equal(runs[0][column], runs[1][column], err_msg=column)


def test_other_kernels_or_a_damaged_entry_compile_again(fmus, tmp_path, monkeypatch):
    """A scene with another coefficient is another entry; an entry with an object missing is not used, nor one
    whose objects are of another entry than its symbols (a build that read it while another build replaced it:
    their tokens differ). The entries damaged are copies in a cache folder of the test's own: the run's other
    builds of the paper scene keep theirs."""
    from prandtl_fmu import _jit
    from prandtl_fmu.fmu.archive import built_scene
    from prandtl_fmu.fmu.build import build_fmu
    from prandtl_fmu.fmu.native import kernels, platforms
    from prandtl_fmu.fmu.native.build import element_objects

    scene_path = fmus["paper"][1]
    scene, scene_bytes = built_scene(scene_path, None)
    objects = element_objects(scene, scene_bytes, kernels.applicable(scene), platforms.resolve(None, 2))
    assert objects.cached, "the fixture's build kept no entry"
    kept = _jit.cache_root() / "native-objects" / objects.digest
    own_root = tmp_path / "cache"
    entry = own_root / "native-objects" / objects.digest
    kept_objects = sorted(kept.rglob("*.o"))
    shutil.copytree(kept, entry)
    monkeypatch.setattr(_jit, "cache_root", lambda: own_root)
    monkeypatch.setattr(kernels, "compile_kernels", refuse_to_compile)
    other = tmp_path / "other.toml"
    text = scene_path.read_text()
    assert "count = 100" in text
    other.write_text(text.replace("count = 100", "count = 99"))
    with pytest.raises(CompiledAnyway):
        build_fmu(other, tmp_path / "other.fmu", runtime="native")
    host = platforms.host_target().triple  # the target this build reads (the entry may hold others too)
    next((entry / host).glob("*.o")).unlink()
    with pytest.raises(CompiledAnyway):
        build_fmu(scene_path, tmp_path / "damaged.fmu", runtime="native")
    assert not entry.exists()  # removed: the build that compiles writes it again
    shutil.copytree(kept, entry)
    build_fmu(scene_path, tmp_path / "intact.fmu", runtime="native")  # the copy whole: used, nothing compiled
    externals = entry / host / "external.json"
    externals.write_text(json.dumps(dict(json.loads(externals.read_text()), token="another entry's")))
    with pytest.raises(CompiledAnyway):
        build_fmu(scene_path, tmp_path / "mixed.fmu", runtime="native")
    assert sorted(kept.rglob("*.o")) == kept_objects


def test_the_cli_builds_a_native_fmu(tmp_path):
    """With --osp, beside it the OSP description the PythonFMU build writes (libcosim reads it there)."""
    path = tmp_path / "scene.toml"
    path.write_text(scene_text(SCENES["smooth"]))
    sidecars = {}
    for runtime in ("native", "python"):
        folder = tmp_path / runtime
        folder.mkdir()
        # --steppers as the held smooth FMU's: its objects, so the native build only links
        held = ["--steppers", HELD["smooth"]] if runtime == "native" else []
        done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "build", str(path), "--runtime", runtime,
                               "--osp", "-o", str(folder / "element.fmu"), *held], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        sidecars[runtime] = [(p.name, p.read_bytes()) for p in folder.glob("*_OspModelDescription.xml")]
        assert done.stdout.strip().splitlines()[0] == str(folder / "element.fmu")
    assert sidecars["native"] == sidecars["python"] and len(sidecars["native"]) == 1
    assert parse_scene(scene_text(SCENES["smooth"]), "s.toml").solver.stepper in NATIVE_STEPPERS


# ---------------------------------------------------------------- FMI 3.0


@pytest.fixture(scope="module")
def fmus3(tmp_path_factory):
    from prandtl_fmu.fmu.build import build_fmu

    folder = tmp_path_factory.mktemp("native3")

    def build(name):
        path = folder / f"{name}.toml"
        path.write_text(scene_text(SCENES[name]) if SCENES[name] else PAPER.read_text())
        return build_fmu(path, folder / f"{name}.fmu", runtime="native", fmi=3, steppers=HELD.get(name)), path

    return Built(build)


@pytest.mark.parametrize("name", quick_or_slow(["friction", "paper", "continuum"]))
def test_the_fmi3_fmu_validates_and_reproduces_simulate_with_its_elongations(fmus3, name):
    """FMPy's validator finds nothing; simulate_fmu with the scene's load gives the library's x, v, reaction and the
    elongations, the scalars u_1 .. u_n (n, a local constant as in FMI 2.0; the arrays' option:
    tests/masters/test_host_compatibility.py), bit for bit."""
    from fmpy import read_model_description, simulate_fmu
    from fmpy.validation import validate_fmu

    fmu, scene_path = fmus3[name]
    assert validate_fmu(str(fmu)) == []
    description = read_model_description(str(fmu))
    assert description.fmiVersion == "3.0"
    by_name = {v.name: v for v in description.modelVariables}
    scene = load_scene(scene_path)
    continuum = scene.branches.continuum
    n = -1 if continuum else scene.branches.n
    elongations = [f"u_{i}" for i in range(1, n + 1)]  # none for the continuum: no elongation per branch
    assert by_name["n"].causality == "local" and by_name["n"].type == "Int32" and int(by_name["n"].start) == n
    assert "u" not in by_name and [name for name in by_name if name.startswith("u_")] == elongations
    assert not [v.name for v in description.modelVariables if v.dimensions]
    stop = min(scene.solver.stop_time, 20.0)
    library = simulate(scene.with_solver(stop_time=stop), states=not continuum)
    result = simulate_fmu(str(fmu), stop_time=stop, output_interval=scene.solver.output_interval,
                          start_values={"scene_load": True}, output=["x", "v", "reaction"] + elongations)
    for column in ("x", "v", "reaction"):
        np.testing.assert_array_equal(result[column], getattr(library, column))
    if not continuum:
        np.testing.assert_array_equal(np.column_stack([result[u] for u in elongations]), library.u)
    if name == "paper":  # exact: the stack unfolded, u read from the n elongations
        library = simulate(scene.with_solver(stop_time=stop), "exact", states=True)
        result = simulate_fmu(str(fmu), stop_time=stop, output_interval=scene.solver.output_interval,
                              start_values={"scene_load": True, "stepper": "exact"}, output=["x"] + elongations)
        np.testing.assert_array_equal(result["x"], library.x)
        np.testing.assert_array_equal(np.column_stack([result[u] for u in elongations]), library.u)


def test_the_fmi3_fmu_steps_as_the_library_and_refuses_a_tampered_state(fmus3):
    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Slave

    fmu, scene_path = fmus3["friction"]
    description = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    messages = []

    def log(env, status, category, message):
        messages.append(message.decode())

    slave = FMU3Slave(guid=description.instantiationToken, unzipDirectory=extract(str(fmu)),
                      modelIdentifier=description.coSimulation.modelIdentifier)
    slave.instantiate(loggingOn=False, logMessage=log)
    slave.enterInitializationMode()
    slave.setBoolean([vr["scene_load"]], [False])  # F alone, as the element is driven
    slave.exitInitializationMode()
    element = Element(load_scene(scene_path))
    rng = np.random.default_rng(11)
    t = 0.0
    try:
        for _ in range(30):
            size, force = float(rng.choice([0.013, 0.05, 0.1])), float(rng.uniform(-1, 1))
            slave.setFloat64([vr["F"]], [force])
            slave.doStep(t, size)
            element.time = t
            element.advance(size, force)
            t += size
            assert slave.getFloat64([vr["x"], vr["v"], vr["reaction"]]) == [element.x, element.v, element.reaction]
            assert slave.getFloat64([vr["u_1"], vr["u_2"], vr["u_3"]]) == element.elongations().tolist()
        state = slave.getFMUState()
        blob = bytearray(slave.serializeFMUState(state))
        blob[-12] ^= 0x40
        with pytest.raises(FMICallException):
            slave.deserializeFMUState(bytes(blob))
        assert any("checksum" in message or "altered" in message for message in messages), messages
        slave.setFMUState(state)
        assert slave.getFloat64([vr["x"]]) == [element.x]
    finally:
        slave.terminate()
        slave.freeInstance()


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_the_toolbox_checker_finds_nothing_in_the_native_fmus(fmus, fmus3, connectors):
    """The FMU Manipulation Toolbox's checker (fmutool -check: the FMI schemas and the semantic rules of causality,
    variability, initial, start and the model structure) on the element and the connector, FMI 2.0 and 3.0."""
    pytest.importorskip("fmu_manipulation_toolbox", reason="pip install 'prandtl_fmu[test]'")
    checked = {"element FMI 2.0": fmus["paper"][0], "element FMI 3.0": fmus3["friction"][0],
               "connector FMI 2.0": connectors["series"]["native"], "connector FMI 3.0": connectors["stack"]["fmi3"]}
    for what, fmu in checked.items():
        done = subprocess.run([sys.executable, "-m", "fmu_manipulation_toolbox", "-input", str(fmu), "-check"],
                              capture_output=True, text=True, timeout=300)
        report = done.stdout + done.stderr
        version = what[-3:]
        assert done.returncode == 0, report
        assert f"This FMU seems to be compliant with FMI-{version}." in report, (what, report)
        assert f"No semantic error against the FMI-{version[0]} standard." in report, (what, report)
        assert not [line for line in report.splitlines() if "ERROR" in line or "WARNING" in line], (what, report)


# ---------------------------------------------------------------- the connector


CONNECTORS = {
    # spring, dashpot, branches with series dashpots: the O(n) kernel
    "series": base_tables(mass=None, cubic=None, solver=SOLVER, fmu={"causality": "displacement"},
                          branches={"k": [1.0, 0.6, 2.0], "eta": [0.1, 0.3, 0.05], "c": [0.5, 2.0, 8.0]}),
    # 80 branches on the memory stack, a cubic spring
    "stack": base_tables(mass=None, damper=None, solver=SOLVER, fmu={"causality": "displacement"},
                         branches={"k": [0.02] * 80, "eta": np.linspace(0.01, 0.8, 80).tolist()}),
}


@pytest.fixture(scope="module")
def connectors(tmp_path_factory):
    from prandtl_fmu.fmu.build import build_fmu

    folder = tmp_path_factory.mktemp("connectors")
    built = {}
    for name, tables in CONNECTORS.items():
        path = folder / f"{name}.toml"
        path.write_text(scene_text(tables))
        built[name] = {runtime: build_fmu(path, folder / f"{name}-{runtime}.fmu", runtime=runtime)
                       for runtime in ("python", "native")}
        built[name]["fmi3"] = build_fmu(path, folder / f"{name}-3.fmu", runtime="native", fmi=3)
    return built


@pytest.mark.parametrize("name", list(CONNECTORS))
def test_the_native_connector_is_the_pythonfmu_connector_bit_for_bit(connectors, name):
    """Random inputs, read before and after each step (the preview of an input set but not stepped, then the
    committed sample), steps of random sizes, c set to 0 and back where there is a dashpot: every output to
    the bit (the PythonFMU connector is the library's Connector, tests/models/test_connector.py)."""
    from tests.fmu_tools import Slave

    python, native = (Slave(connectors[name][runtime], start_values={"x": 0.02}) for runtime in ("python", "native"))
    names = [v.name for v in python.md.modelVariables if v.causality == "output"]
    assert names == [v.name for v in native.md.modelVariables if v.causality == "output"]
    rng = np.random.default_rng(4)
    try:
        for j in range(150):
            x, v = float(rng.uniform(-0.6, 0.6)), float(rng.uniform(-1, 1))
            for slave in (python, native):
                slave.set("x", x)
                slave.set("v", v)
                if j == 50 and "c" in slave.vr:
                    slave.set("c", 0.0)
                if j == 100 and "c" in slave.vr:
                    slave.set("c", 0.3)
            assert native.get(*names) == python.get(*names), j
            size = float(rng.choice([0.01, 0.05, 0.1]))
            python.step(size)
            native.step(size)
            assert native.get(*names) == python.get(*names), j
    finally:
        python.close()
        native.close()


def test_the_fmi3_connector_validates_and_gives_the_force_and_the_elongations(connectors):
    from fmpy import simulate_fmu
    from fmpy.validation import validate_fmu

    fmus = connectors["series"]
    assert validate_fmu(str(fmus["fmi3"])) == []
    t = np.arange(0, 5.0 + 1e-9, 0.05)
    signal = np.zeros(len(t), dtype=[("time", float), ("x", float), ("v", float)])
    signal["time"], signal["x"], signal["v"] = t, 0.3 * np.sin(t), 0.3 * np.cos(t)
    three = simulate_fmu(str(fmus["fmi3"]), stop_time=5.0, output_interval=0.05, input=signal,
                         output=["force", "u_1", "u_2", "u_3"])
    two = simulate_fmu(str(fmus["python"]), stop_time=5.0, output_interval=0.05, input=signal, output=["force"])
    np.testing.assert_array_equal(three["force"], two["force"])
    assert np.ptp(three["force"]) > 0.1 and min(np.ptp(three[f"u_{i}"]) for i in (1, 2, 3)) > 0


@pytest.mark.parametrize("name, settings", [
    ("smooth", {"stepper": "projected", "step": 0.5}),
    ("smooth", {"stepper": "verlet", "step": 3.0}),
    ("friction", {"stepper": "projected", "step": 0.9}),
    ("friction", {"stepper": "implicit", "step": 2.0}),
    pytest.param("massless", {"stepper": "projected", "step": 1.0}, marks=pytest.mark.slow),
    ("smooth", {"stepper": "implicit", "step": 0.5}),
])
def test_stability_warnings_are_the_pythonfmu_fmus(fmus, held, tmp_path, name, settings):
    """The same one-line warning (or none) as the PythonFMU FMU of the scene, at initialization and when a
    setting changes during the run."""
    from prandtl_fmu.fmu.build import build_fmu

    from tests.fmu_tools import Slave

    native_fmu, scene_path = (held if name in HELD else fmus)[name]
    python_fmu = build_fmu(scene_path, tmp_path / "python.fmu")
    warnings = {}
    for runtime, fmu in (("python", python_fmu), ("native", native_fmu)):
        slave = Slave(fmu, start_values=settings)
        try:
            slave.step(0.01, 0.1)
            slave.set("step", settings["step"] * 1.5)  # a change during the run: warned again
            slave.step(0.01, 0.1)
            warnings[runtime] = [message for status, message in slave.messages if status == 1]
        finally:
            slave.close()
    assert warnings["native"] == warnings["python"]
    assert bool(warnings["native"]) == (settings["stepper"] != "implicit" or name == "friction")


def test_the_native_stability_kernel_calls_the_library_s_compiled_check(fmus, held):
    """The native build's stability kernel hands check() the element's having a mass as a bool, not the constant
    True numba compiled check() once more for: after the module's builds, the cache of this run holds no kernel
    signature with a literal (tests/compiled_copies.py)."""
    from tests.compiled_copies import literal_signatures

    assert held["smooth"][0].is_file()
    assert literal_signatures("stability.check") == []


# ------------------------------------------------------------------ the package (issue 33, items 2-4)

def _entries(path):
    import zipfile

    with zipfile.ZipFile(path) as archive:
        return {info.filename: ((info.external_attr >> 16) & 0o777, archive.read(info)) for info in archive.infolist()}


def test_every_entry_of_every_fmu_is_readable_by_all(fmus, fmus3, connectors, tmp_path, held):
    """Entries were written 0600 (ZipFile.writestr's default): unpacked, a master running as another user could
    not read them. 0644 as every FMU has, the binary 0755."""
    from prandtl_fmu.fmu.build import build_fmu

    python_fmu = build_fmu(held["smooth"][1], tmp_path / "python.fmu")
    paths = [held["smooth"][0], fmus3["paper"][0], connectors["series"]["fmi3"], python_fmu]
    for path in paths:
        for name, (mode, _) in _entries(path).items():
            if not name.endswith("/"):
                assert mode & 0o644 == 0o644 and not mode & 0o022, (path.name, name, oct(mode))


def test_the_native_fmu_s_page_describes_the_native_fmu_and_its_own_variables(fmus, fmus3):
    for path in (fmus["paper"][0], fmus3["paper"][0]):
        entries = _entries(path)
        page = entries["documentation/index.html"][1].decode("utf-8")
        assert "native" in page and "no Python" in page and "LD_PRELOAD=&lt;" not in page, path.name
        assert "PythonFMU's own binary" not in page
        description = entries["modelDescription.xml"][1].decode("utf-8")
        version = "fmi3" if 'fmiVersion="3.0"' in description else "fmi2"
        assert f"{version}Discard" in page
        if version == "fmi3":
            assert "fmi2" not in page
        if version == "fmi3":
            assert "<td>u_1</td>" in page and "<td>Float64</td>" in page


def test_the_fmi3_description_speaks_fmi3_and_gives_every_output_its_dependencies(fmus3):
    import xml.etree.ElementTree as ET

    from prandtl_fmu import load_scene

    for name in ("paper", "friction"):
        root = ET.fromstring(_entries(fmus3[name][0])["modelDescription.xml"][1])
        categories = [category.get("description", "") for category in root.find("LogCategories")]
        assert categories and not any("fmi2" in text for text in categories), categories
        for unknown in root.find("ModelStructure"):
            assert unknown.get("dependencies") is not None, ET.tostring(unknown)
        n = root.find("ModelVariables/Int32[@name='n']")  # FMI 2.0's local constant (arrays: UInt64, structural)
        scene = load_scene(fmus3[name][1])
        assert n is not None and int(n.get("start")) == scene.branches.n >= 0


# ------------------------------------------------------------------ F given with its derivatives (issue 61)

def _set_derivatives(slave, orders, values):
    """fmi2SetRealInputDerivatives of F: ``orders`` and ``values`` alike long."""
    slave.fmu.setRealInputDerivatives([slave.vr["F"]] * len(orders), list(orders), list(values))


def test_input_derivatives_drive_the_native_fmu_as_the_library_bit_for_bit(fmus):
    """The paper's FMU (projected, implicit, verlet), F set with random F' and F'' before each of 30 random steps
    (some not multiples of the step; every fifth step F alone, held): x, v, the reaction, the stiffness and the
    energy account equal Element.advance(..., force_derivatives=(F', F'')) to the bit. A state saved with
    derivatives set carries them: restored, the next step is the same again."""
    fmu, scene_path = fmus["paper"]
    scene = load_scene(scene_path)
    description = zipfile.ZipFile(fmu).read("modelDescription.xml").decode()
    assert 'canInterpolateInputs="true"' in description
    for stepper in ("projected", "implicit", "verlet"):
        rng = np.random.default_rng(5)
        with fmu_and_element(fmu, scene, stepper) as (slave, element, names):
            for j in range(30):
                size, force = float(rng.choice([0.013, 0.05, 0.1, 0.0371])), float(rng.uniform(-0.6, 0.6))
                rate, curvature = (float(value) for value in rng.uniform(-2.0, 2.0, 2))
                time = slave.time
                slave.set("F", force)
                if j % 5:
                    _set_derivatives(slave, (2, 1), (curvature, rate))  # any order of entries
                else:
                    rate = curvature = 0.0
                if j == 17:
                    saved, checkpoint = slave.fmu.getFMUstate(), element.get_state()
                    slave.fmu.doStep(time, size)  # a step from the state saved, then the state restored
                    slave.fmu.setFMUstate(saved)
                    slave.fmu.freeFMUstate(saved)
                    element.set_state(checkpoint)
                slave.step(size)
                element.time = time
                element.advance(size, force, force_derivatives=(rate, curvature))
                assert same(outputs(slave, names), expected(element, names)), (stepper, j)
            assert abs(element.x) > 1e-3


def test_derivatives_hold_for_one_step_and_a_new_f_clears_them(fmus):
    """The derivatives describe F over the step that starts where they were set (FMI 2.0: inputs and their
    derivatives refer to the start of a communication step): the step after is held unless they are set again,
    and fmi2SetReal of F sets them to zero (the master's new value has no derivative until it gives one)."""
    fmu, scene_path = fmus["paper"]
    scene = load_scene(scene_path)
    with fmu_and_element(fmu, scene, "projected") as (slave, element, names):
        slave.set("F", 0.3)
        _set_derivatives(slave, (1, 2), (0.5, -0.4))
        slave.step(0.2)
        element.advance(0.2, 0.3, force_derivatives=(0.5, -0.4))
        slave.step(0.2)  # held at 0.3
        element.time = 0.2
        element.advance(0.2, 0.3)
        assert same(outputs(slave, names), expected(element, names))
        _set_derivatives(slave, (1,), (0.7,))
        slave.set("F", -0.1)  # clears the 0.7 just set
        slave.step(0.2)
        element.time = 0.4
        element.advance(0.2, -0.1)
        assert same(outputs(slave, names), expected(element, names))


def test_bad_input_derivatives_are_refused_with_their_reason(fmus):
    """fmi2SetRealInputDerivatives refuses (fmi2Error, logged, nothing set) a value reference that is not F, an
    order other than 1 and 2, a value that is not finite; a step with derivatives under scene_load or with
    'exact' (closed forms of the scene's load kinds) is discarded naming why, the state unchanged."""
    from fmpy.fmi1 import FMICallException

    fmu, _ = fmus["paper"]
    from tests.fmu_tools import Slave

    slave = Slave(fmu)
    try:
        for vrs, orders, values, words in (([slave.vr["x"]], [1], [0.1], "is not the continuous input F"),
                                           ([slave.vr["F"]], [3], [0.1], "order 3 of F"),
                                           ([slave.vr["F"]], [0], [0.1], "order 0 of F"),
                                           ([slave.vr["F"], slave.vr["F"]], [1, 2], [0.1, float("nan")],
                                            "order 2 = nan must be finite")):
            slave.messages.clear()
            with pytest.raises(FMICallException):
                slave.fmu.setRealInputDerivatives(vrs, orders, values)
            assert any(words in message for _, message in slave.messages), (words, slave.messages)
        x = slave.get("x")
        slave.step(0.1, 0.2)  # nothing was set: held
        held_x = slave.get("x")
        assert held_x != x
        for setting, words in ((("scene_load", True), "force derivatives with scene_load"),
                               (("stepper", "exact"), "force derivatives with stepper 'exact'")):
            slave.set(*setting)
            _set_derivatives(slave, (1,), (0.5,))
            slave.messages.clear()
            with pytest.raises(FMICallException):
                slave.fmu.doStep(slave.time, 0.1)
            assert any(words in message for _, message in slave.messages), slave.messages
            assert slave.get("x") == held_x
            slave.set(*{"scene_load": ("scene_load", False), "stepper": ("stepper", "projected")}[setting[0]])
    finally:
        slave.close()


SPACINGS = np.array([0.5, 0.2, 0.1, 0.05, 0.02, 0.01])


def _tabulated_error(fmu, reference, spacing, derivatives):
    """|x(STOP) - reference| of the FMU in FMPy's simulate_fmu under the paper's force tabulated every ``spacing``
    s (FMPy interpolates it linearly and, with ``derivatives``, hands the slope as F')."""
    from fmpy import simulate_fmu

    times = np.arange(0.0, 12.0 + spacing / 2, spacing)
    table = np.array(list(zip(times, 0.45 * np.cos(0.5 * times))), dtype=[("time", float), ("F", float)])
    result = simulate_fmu(str(fmu), stop_time=12.0, output_interval=spacing, input=table, output=["x"],
                          start_values={"scene_load": False, "stepper": "projected"},
                          set_input_derivatives=derivatives)
    assert result["time"][-1] == pytest.approx(12.0)
    return abs(result["x"][-1] - reference)


def _fmpy_derivative_buffers_sized(monkeypatch):
    """FMPy 0.3.32's simulate_fmu(set_input_derivatives=True) gives each type of continuous input a buffer of 9
    derivatives and assigns the inputs' derivatives to it whole: with fewer than 9 inputs (ours has one) it raises
    "Can only assign sequence of same size" at the first step. Its Input objects get buffers of their inputs'
    count instead (what FMPy means to hand: one first derivative per input)."""
    import ctypes

    from fmpy import simulation

    original = simulation.Input.__init__

    def sized(self, *arguments, **keywords):
        original(self, *arguments, **keywords)
        self.continuous = [info._replace(derivatives=(ctypes.c_double * len(info.vrs))()) for info in self.continuous]

    monkeypatch.setattr(simulation.Input, "__init__", sized)


@pytest.mark.parametrize("spacings", [SPACINGS[:4], pytest.param(SPACINGS, marks=pytest.mark.slow)],
                         ids=["0.5-0.05", "0.5-0.01"])
def test_a_tabulated_force_in_simulate_fmu_converges_at_second_order_with_input_derivatives(fmus, monkeypatch,
                                                                                           spacings):
    """The paper's FMU in FMPy's simulate_fmu under its force 0.45 cos(0.5 t) given as a table at spacings 0.5 ...
    0.05 s (0.01 s under the slow marker), against the library's element under the continuous force (the same internal steps): the error in x at
    t = 12 s falls at order ~1 with the input held over a step, >= 1.8 with set_input_derivatives=True (FMPy hands
    the slope of the table's piece as F'; its buffer defect worked around: see _fmpy_derivative_buffers_sized,
    which says so should FMPy fix it)."""
    fmu, scene_path = fmus["paper"]
    element = Element(load_scene(scene_path), stepper="projected")
    element.advance(12.0, 0.0, scene_load=True)
    with pytest.raises(ValueError, match="Can only assign sequence of same size"):  # FMPy's defect, still there
        _tabulated_error(fmu, element.x, 0.5, True)
    _fmpy_derivative_buffers_sized(monkeypatch)
    for derivatives, least, most in ((False, 0.8, 1.3), (True, 1.8, 2.5)):
        errors = np.array([_tabulated_error(fmu, element.x, spacing, derivatives) for spacing in spacings])
        slope = np.polyfit(np.log(spacings), np.log(errors), 1)[0]
        assert least <= slope <= most, (derivatives, errors, slope)


# ------------------------------------------------------------------ output derivatives (issue 61)

ASKED = [("x", 1), ("x", 2), ("v", 1), ("v", 2), ("reaction", 1)]


def _output_derivatives(slave, asked=ASKED):
    return slave.fmu.getRealOutputDerivatives([slave.vr[name] for name, _ in asked], [order for _, order in asked])


def test_output_derivatives_are_the_library_s_and_the_slopes_of_the_fmu_s_own_outputs(fmus):
    """The paper's FMU after random steps: x's derivatives (v, a), v's (a, a') and the reaction's rate equal
    Element.output_derivatives to the bit; and they are the slopes of the FMU's own outputs: from a saved state,
    exact steps of delta and 2 delta under F held give forward differences (Richardson's for order 1) that agree
    to 1e-6 relative (order 1) and 1e-4 (order 2)."""
    fmu, scene_path = fmus["paper"]
    scene = load_scene(scene_path)
    description = zipfile.ZipFile(fmu).read("modelDescription.xml").decode()
    assert 'maxOutputDerivativeOrder="2"' in description
    rng = np.random.default_rng(9)
    with fmu_and_element(fmu, scene, "projected") as (slave, element, names):
        for j in range(12):
            step_both(slave, element, rng, names, j)
        force = float(slave.get("F"))
        wanted = element.output_derivatives(force)
        got = _output_derivatives(slave)
        assert same(got, [wanted[key] for key in ASKED])
        assert got[0] == slave.get("v") and got[1] == got[2] and abs(got[1]) > 1e-3
        slave.set("stepper", "exact")  # x, v exact over a step under F held: differences show the derivatives
        saved, start = slave.fmu.getFMUstate(), slave.time
        delta = 1e-5
        values = [slave.get("x", "v", "reaction")]
        for span in (delta, 2 * delta):
            slave.fmu.setFMUstate(saved)
            slave.fmu.doStep(start, span)
            values.append(slave.get("x", "v", "reaction"))
        slave.fmu.setFMUstate(saved)
        slave.fmu.freeFMUstate(saved)
        y0, y1, y2 = (np.array(row) for row in values)
        first = (4 * (y1 - y0) - (y2 - y0)) / (2 * delta)  # y' + O(delta^2)
        second = (y2 - 2 * y1 + y0) / delta ** 2  # y'' + O(delta)
        after = _output_derivatives(slave)
        assert same(after, got)  # the state set back: the same derivatives
        x1, x2, v1, v2, r1 = got
        for slope, derivative, tolerance in ((first[0], x1, 1e-6), (first[1], v1, 1e-6), (first[2], r1, 1e-6),
                                             (second[0], x2, 1e-4), (second[1], v2, 1e-4)):
            assert slope == pytest.approx(derivative, rel=tolerance, abs=1e-9), (slope, derivative)


def test_output_derivatives_refuse_what_they_do_not_give(fmus):
    """An order other than 1 and 2, the reaction's order 2, an output that has none (stiffness), an input (F), a
    NULL order: fmi2Error with the reason, nothing written."""
    from fmpy.fmi1 import FMICallException

    from tests.fmu_tools import Slave

    fmu, _ = fmus["paper"]
    slave = Slave(fmu)
    try:
        slave.step(0.1, 0.3)
        for asked, words in (([("x", 3)], "order 3"), ([("x", 0)], "order 0"),
                             ([("reaction", 2)], "the reaction's derivative of order 2 is not given"),
                             ([("x", 1), ("stiffness", 1)], "not an output whose derivatives"),
                             ([("F", 1)], "not an output whose derivatives")):
            slave.messages.clear()
            with pytest.raises(FMICallException):
                _output_derivatives(slave, asked)
            assert any(words in message for _, message in slave.messages), (words, slave.messages)
        assert _output_derivatives(slave, [("x", 1)]) == [slave.get("v")]
    finally:
        slave.close()


# ------------------------------------------------------------------ the connector's directional derivatives (issue 61)

def _directional(slave, knowns, seeds):
    return slave.fmu.getDirectionalDerivative([slave.vr["force"]], [slave.vr[name] for name in knowns], list(seeds))


@pytest.mark.parametrize("name", list(CONNECTORS))
def test_the_connector_s_directional_derivatives_are_the_slopes_of_its_force(connectors, name):
    """d force/d x (the tangent stiffness for the move from the committed x to the x set) and d force/d v (the
    dashpot's c) of the native connector: both are the slopes of its own force output under the input moved a little
    further (the outputs preview the inputs set last), to 1e-6 relative; the first is the output stiffness where
    v points the way of that move; a combined seed is their sum."""
    from tests.fmu_tools import Slave

    slave = Slave(connectors[name]["native"], start_values={"x": 0.02})
    description = zipfile.ZipFile(connectors[name]["native"]).read("modelDescription.xml").decode()
    assert 'providesDirectionalDerivative="true"' in description
    rng = np.random.default_rng(6)
    committed, compared = 0.02, 0
    try:
        for j in range(20):
            x, v = float(rng.uniform(-0.4, 0.4)), float(rng.uniform(-1, 1))
            if j:
                slave.step(0.05)
                committed = slave.get("x")
            slave.set("x", x)
            slave.set("v", v)
            by_x, = _directional(slave, ["x"], [1.0])
            by_v, = _directional(slave, ["v"], [1.0])
            if (x - committed) * v > 0:
                assert by_x == slave.get("stiffness")
                compared += 1
            force = slave.get("force")
            ahead = math.copysign(1e-7, x - committed)  # further along the move the force is a function of
            slave.set("x", x + ahead)
            slope_x = (slave.get("force") - force) / ahead
            slave.set("x", x)
            slave.set("v", v + 1e-3)
            slope_v = (slave.get("force") - force) / 1e-3
            slave.set("v", v)
            assert by_x == pytest.approx(slope_x, rel=1e-6, abs=1e-6), (j, by_x, slope_x)
            assert by_v == pytest.approx(slope_v, rel=1e-9, abs=1e-12), (j, by_v, slope_v)
            both, = _directional(slave, ["v", "x"], [0.5, 2.0])
            assert both == pytest.approx(2.0 * by_x + 0.5 * by_v, rel=1e-15)
        assert compared >= 5
    finally:
        slave.close()


def test_the_connector_refuses_directional_derivatives_it_does_not_have(connectors):
    """An unknown other than force, a known other than x and v or listed twice, a NaN seed: fmi2Error with the
    reason logged; the element FMU declares none and refuses them as before."""
    from fmpy.fmi1 import FMICallException

    from tests.fmu_tools import Slave

    slave = Slave(connectors["series"]["native"], start_values={"x": 0.02})
    try:
        for unknown, knowns, seeds, words in (("stiffness", ["x"], [1.0], "is not the output force"),
                                              ("force", ["x", "x"], [1.0, 1.0], "listed twice"),
                                              ("force", ["c"], [1.0], "is not the input x or v"),
                                              ("force", ["x"], [float("nan")], "is not finite")):
            slave.messages.clear()
            with pytest.raises(FMICallException):
                slave.fmu.getDirectionalDerivative([slave.vr[unknown]], [slave.vr[n] for n in knowns], seeds)
            assert any(words in message for _, message in slave.messages), (words, slave.messages)
    finally:
        slave.close()


# ------------------------------------------------------------------ the connector's input derivatives (issue 61)

def _connector_outputs(connector, names):
    """The library connector's value of each FMU output ``names``."""
    found = {"force": connector.force, "stiffness": connector.stiffness(), **connector.energy()}
    return [found[name] for name in names]


def _set_motion_derivatives(slave, xd, vd):
    """fmi2SetRealInputDerivatives of x and v, orders 2 then 1 (any order of entries)."""
    slave.fmu.setRealInputDerivatives([slave.vr["x"], slave.vr["v"], slave.vr["x"], slave.vr["v"]], [2, 2, 1, 1],
                                      [xd[1], vd[1], xd[0], vd[0]])


def test_the_connector_s_input_derivatives_drive_it_as_the_library_bit_for_bit(connectors):
    """The 80-branch connector (canInterpolateInputs="true"), x and v set with random x', x'', v', v'' before each
    of 40 steps of random sizes (every fifth held, their turning points inside the step every third): force,
    stiffness and energies before and after each step equal Connector.advance(x, v, t, H, x_derivatives,
    v_derivatives) to the bit, and the inputs read back the path's end. A state saved with derivatives set carries
    them (restored, the step is the same again); a step that overflows is discarded and keeps them; fmi2SetReal of x
    clears x's."""
    from fmpy.fmi1 import FMICallException

    from prandtl_fmu.connector import Connector
    from tests.fmu_tools import Slave

    fmu = connectors["stack"]["native"]
    assert 'canInterpolateInputs="true"' in zipfile.ZipFile(fmu).read("modelDescription.xml").decode()
    assert 'canInterpolateInputs="false"' in zipfile.ZipFile(connectors["series"]["native"]).read(
        "modelDescription.xml").decode()
    slave = Slave(fmu, start_values={"x": 0.02})
    names = [v.name for v in slave.md.modelVariables if v.causality == "output"]
    connector = Connector(_scene_of(connectors, "stack"))
    connector.move_to(0.02, 0.0, 0.0)
    rng = np.random.default_rng(8)
    turned = 0
    try:
        assert slave.get(*names) == _connector_outputs(connector, names)
        for j in range(40):
            x, v = float(rng.uniform(-0.6, 0.6)), float(rng.uniform(-1, 1))
            xd, vd = rng.uniform(-3, 3, 2), rng.uniform(-3, 3, 2)
            size = float(rng.choice([0.01, 0.05, 0.3]))
            if j % 3 == 0:
                xd[1] = -xd[0] / (0.5 * size)  # a turn at half the step
            if j % 5 == 0:
                xd[:] = vd[:] = 0.0
            turned += bool(xd[1]) and 0 < -xd[0] / xd[1] < size
            slave.set("x", x)
            slave.set("v", v)
            if j % 5:
                _set_motion_derivatives(slave, xd, vd)
            if j == 17:
                saved = slave.fmu.getFMUstate()
                slave.fmu.doStep(slave.time, size)
                slave.fmu.setFMUstate(saved)
                slave.fmu.freeFMUstate(saved)
            slave.step(size)
            connector.advance(x, v, slave.time - size, size, x_derivatives=xd.tolist(), v_derivatives=vd.tolist())
            assert slave.get(*names) == _connector_outputs(connector, names), j
            assert slave.get("x", "v") == [connector.x, connector.v], j
        assert turned >= 5
        before = slave.get(*names)
        slave.set("x", 0.1)
        _set_motion_derivatives(slave, (0.0, 1e300), (0.0, 0.0))  # the cubic spring's force overflows
        for _ in range(2):  # discarded, the derivatives kept: discarded again
            with pytest.raises(FMICallException):
                slave.fmu.doStep(slave.time, 1.0)
        slave.set("x", 0.1)  # a new x: its derivatives cleared, the step held
        slave.step(1.0)
        connector.advance(0.1, connector.v, slave.time - 1.0, 1.0)
        assert slave.get(*names) == _connector_outputs(connector, names) != before
    finally:
        slave.close()


def _scene_of(connectors, name):
    return load_scene(os.fspath(connectors[name]["native"]).replace(f"{name}-native.fmu", f"{name}.toml"))


def test_the_connector_refuses_input_derivatives_with_their_reason(connectors):
    """fmi2SetRealInputDerivatives refuses (fmi2Error, logged, nothing set) a value reference other than x and v,
    orders 0 and 3, a NaN, and any on the connector whose branches have series dashpots."""
    from fmpy.fmi1 import FMICallException

    from tests.fmu_tools import Slave

    for name, cases in (("stack", ((["force"], [1], [0.1], "is not the input x or v"),
                                   (["x"], [3], [0.1], "order 3 of x"), (["v"], [0], [0.1], "order 0 of v"),
                                   (["x", "v"], [1, 2], [0.1, float("nan")], "order 2 = nan must be finite"))),
                        ("series", ((["x"], [1], [0.1], "with series dashpots or effects with memory"),))):
        slave = Slave(connectors[name]["native"], start_values={"x": 0.02})
        try:
            for names, orders, values, words in cases:
                slave.messages.clear()
                with pytest.raises(FMICallException):
                    slave.fmu.setRealInputDerivatives([slave.vr[n] for n in names], orders, values)
                assert any(words in message for _, message in slave.messages), (words, slave.messages)
            force = slave.get("force")
            slave.step(0.1)  # nothing was set: held
            assert slave.get("force") == force and slave.get("x") == 0.02
        finally:
            slave.close()


def test_the_connector_s_force_derivatives_are_the_library_s_and_the_slopes_of_its_own_force(connectors):
    """The 80-branch connector (maxOutputDerivativeOrder="2"): after random steps along random paths, with x and v
    set and, every other time, their derivatives, fmi2GetRealOutputDerivatives of force (orders 1 and 2) equals
    Connector.output_derivatives to the bit; and they are the slopes of the FMU's own force along that path: from a
    saved state, doSteps of delta, 2 delta, 3 delta with the derivatives set (x' = v, x'' = v' = 0 where none are)
    give one-sided differences that agree to 1e-6 relative (order 1) and 1e-4 (order 2). The connector with series
    dashpots declares none and refuses them with the reason; order 3 and another output are refused."""
    from fmpy.fmi1 import FMICallException

    from prandtl_fmu.connector import Connector
    from tests.fmu_tools import Slave

    fmu = connectors["stack"]["native"]
    assert 'maxOutputDerivativeOrder="2"' in zipfile.ZipFile(fmu).read("modelDescription.xml").decode()
    assert "maxOutputDerivativeOrder" not in zipfile.ZipFile(connectors["series"]["native"]).read(
        "modelDescription.xml").decode()
    slave = Slave(fmu, start_values={"x": 0.02})
    connector = Connector(_scene_of(connectors, "stack"))
    connector.move_to(0.02, 0.0, 0.0)
    rng = np.random.default_rng(61)
    force = [slave.vr["force"]] * 2
    compared = 0
    try:
        for j in range(16):
            x, v = float(rng.uniform(-0.6, 0.6)), float(rng.uniform(-1, 1))
            xd, vd = rng.uniform(-3, 3, 2), rng.uniform(-3, 3, 2)
            slave.set("x", x)
            slave.set("v", v)
            given = j % 2 == 1
            if given:
                _set_motion_derivatives(slave, xd, vd)
            got = slave.fmu.getRealOutputDerivatives(force, [1, 2])
            wanted = connector.output_derivatives(x, v, *((xd.tolist(), vd.tolist()) if given else ()))
            assert got == [wanted[("force", 1)], wanted[("force", 2)]], j
            saved, start = slave.fmu.getFMUstate(), slave.time
            delta = 1e-4
            values = []
            for span in (delta, 2 * delta, 3 * delta):
                slave.fmu.setFMUstate(saved)
                if not given:  # the path the derivatives describe when none are set: x' = v
                    _set_motion_derivatives(slave, (v, 0.0), (0.0, 0.0))
                slave.fmu.doStep(start, span)
                values.append(slave.get("force"))
            slave.fmu.setFMUstate(saved)
            slave.fmu.freeFMUstate(saved)
            assert slave.fmu.getRealOutputDerivatives(force, [1, 2]) == got  # the state set back, derivatives too
            f0, (f1, f2, f3) = slave.get("force"), values
            first, second = (-3 * f0 + 4 * f1 - f2) / (2 * delta), (2 * f0 - 5 * f1 + 4 * f2 - f3) / delta ** 2
            if not (first == pytest.approx(got[0], rel=1e-6, abs=1e-7)):
                continue  # a branch reached its threshold within 3 delta: the difference straddles a switch
            assert second == pytest.approx(got[1], rel=1e-4, abs=1e-4), (j, second, got)
            compared += 1
            slave.step(0.05)
            connector.advance(x, v, slave.time - 0.05, 0.05, *((xd.tolist(), vd.tolist()) if given else ()))
        assert compared >= 10
        for asked, orders, words in (([slave.vr["force"]], [3], "order 3"),
                                     ([slave.vr["stiffness"]], [1], "not an output whose derivatives")):
            slave.messages.clear()
            with pytest.raises(FMICallException):
                slave.fmu.getRealOutputDerivatives(asked, orders)
            assert any(words in message for _, message in slave.messages), (words, slave.messages)
    finally:
        slave.close()
    series = Slave(connectors["series"]["native"], start_values={"x": 0.02})
    try:
        with pytest.raises(FMICallException):
            series.fmu.getRealOutputDerivatives([series.vr["force"]], [1])
        assert any("not given with series dashpots" in message for _, message in series.messages), series.messages
    finally:
        series.close()


def test_the_fmi3_connector_gives_its_force_s_derivatives_as_the_library(connectors):
    """The 80-branch FMI 3.0 connector (maxOutputDerivativeOrder="2"): after samples at random, fmi3GetOutputDerivatives
    of force (orders 1 and 2, x' = v, v held) equals Connector.output_derivatives at the inputs set, to the bit."""
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave

    from prandtl_fmu.connector import Connector

    fmu = connectors["stack"]["fmi3"]
    md = read_model_description(str(fmu))
    assert md.coSimulation.maxOutputDerivativeOrder == 2
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="connector")
    slave.instantiate()
    slave.enterInitializationMode(startTime=0.0)
    slave.setFloat64([vr["x"]], [0.02])
    slave.exitInitializationMode()
    connector = Connector(_scene_of(connectors, "stack"))
    connector.move_to(0.02, 0.0, 0.0)
    rng = np.random.default_rng(3)
    t = 0.0
    try:
        for j in range(12):
            x, v = float(rng.uniform(-0.6, 0.6)), float(rng.uniform(-1, 1))
            slave.setFloat64([vr["x"], vr["v"]], [x, v])
            wanted = connector.output_derivatives(x, v)
            assert slave.getOutputDerivatives([vr["force"]] * 2, [1, 2]) == [wanted[("force", 1)],
                                                                              wanted[("force", 2)]], j
            slave.doStep(t, 0.1)
            connector.move_to(x, v, t)
            t += 0.1
    finally:
        slave.terminate()
        slave.freeInstance()


# ------------------------------------------------------------------ FMI 3.0: intermediate update (issue 61)

def test_fmi3_intermediate_update_sets_f_at_every_internal_step_as_the_library(fmus3):
    """The paper's FMI 3.0 FMU instantiated with an intermediate update callback (what FMPy's
    instantiate_fmu(..., intermediate_update=...) hands): the FMU calls it at the start of every internal step
    (the first of a doStep with intermediateStepFinished false), the master sets F there to the paper's force of
    that instant, and x, v equal the library's Element advanced step by step under the same F, to the bit
    (projected and implicit, steps not multiples of h); a setter of anything but F in the callback is refused
    (only F is intermediateUpdate="true"); fmi3GetOutputDerivatives gives x's order 1 = v."""
    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Slave

    from prandtl_fmu.stepping import split_duration

    fmu, scene_path = fmus3["paper"]
    scene = load_scene(scene_path)
    description = zipfile.ZipFile(fmu).read("modelDescription.xml").decode()
    assert 'providesIntermediateUpdate="true"' in description and 'intermediateUpdate="true"' in description
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(str(fmu))
    for stepper in ("projected", "implicit"):
        slave = FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                          instanceName=stepper)
        asked, refused, messages = [], [], []

        def update(env, time, set_requested, get_requested, finished, can_return_early, early, early_time):
            asked.append((time, bool(finished)))
            slave.setFloat64([vr["F"]], [0.45 * math.cos(0.5 * time)])
            if len(asked) == 7:  # a parameter in intermediate update mode
                try:
                    slave.setFloat64([vr["m"]], [2.0])
                except FMICallException as error:
                    refused.append(error.status)

        def logger(env, status, category, message):
            messages.append(message.decode())

        slave.instantiate(intermediateUpdate=update, logMessage=logger)
        slave.enterInitializationMode(startTime=0.0)
        slave.setBoolean([vr["scene_load"]], [False])
        slave.setString([vr["stepper"]], [stepper])
        slave.exitInitializationMode()
        element = Element(scene, stepper=stepper)
        t = 0.0
        try:
            for size in (0.05, 0.0137, 0.1, 0.02):
                start = len(asked)
                slave.doStep(t, size)
                t += size
                assert asked[start][1] is False and all(finished for _, finished in asked[start + 1:])
                whole, rest = split_duration(size, element.h)  # the doStep's split, as the FMU makes it
                spans = [element.h] * int(whole) + ([rest] if rest else [])
                assert len(spans) == len(asked) - start
                for (time, _), span in zip(asked[start:], spans):
                    element.time = time
                    element.advance(span, 0.45 * math.cos(0.5 * time))
                assert slave.getFloat64([vr["x"], vr["v"]]) == [element.x, element.v], (stepper, t)
            assert refused == [3] and any("only F may be set there" in message for message in messages)
            assert slave.getOutputDerivatives([vr["x"]], [1]) == [element.v]
            assert abs(element.x) > 1e-3
        finally:
            slave.terminate()
            slave.freeInstance()
