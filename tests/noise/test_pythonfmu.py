"""The white noise an FMU generates (issue 34), PythonFMU runtime, driven by FMPy against the library.

The noise's path is a function of (seed, time) alone: the FMU run with its scene's load equals the library's
run bit for bit, a rolled-back step redraws the same increments, and two half communication steps equal one.
"""
import json

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException

from prandtl_fmu import load_scene, simulate
from prandtl_fmu.fmu.build import build_fmu
from prandtl_fmu.network import simulate as simulate_network

from tests.conftest import SCENES
from tests.fmu_tools import Slave
from tests.noise.scenes import noisy_element

# every FMU here compiles the noisy kernels in its own process: under -m slow, which CI runs
pytestmark = pytest.mark.slow

ELEMENT = noisy_element(4.0)

NETWORK = """name = "noisy-network"

[network]
nodes = ["a", "b"]
mass = [1.0, 0.5]

[[network.spring]]
between = ["a", "ground"]
k = 1.0

[[network.slider]]
between = ["a", "b"]
alpha = 0.2

[[network.spring]]
between = ["a", "b"]
k = 2.0

[[network.dashpot]]
between = ["b", "ground"]
c = 0.3

[load]
kind = "white_noise"
intensity = 0.8
seed = 21
noise_unit = 0.01

[solver]
stepper = "implicit"
step = 0.005
stop_time = 4.0
output_interval = 0.1
"""


def step_status(slave, time, size):
    """The status of one fmi2DoStep (FMPy raises on anything beyond a warning)."""
    try:
        slave.fmu.doStep(time, size)
    except FMICallException as exc:
        return exc.status
    return 0


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("noise_fmus")
    built = {}
    for name, text in (("element", ELEMENT), ("network", NETWORK)):
        scene_path = folder / f"{name}.toml"
        scene_path.write_text(text)
        built[name] = (str(build_fmu(scene_path, folder / f"{name}.fmu")), scene_path)
    return built


def fmu_run(fmu, names, **start):
    result = simulate_fmu(fmu, start_values=dict(scene_load=True, **start), output=list(names),
                          fmi_call_logger=None)
    return result


@pytest.mark.parametrize("name", ["element", "network"])
def test_parameters_start_at_the_scene_noise(fmus, name):
    fmu, scene_path = fmus[name]
    noise = load_scene(scene_path).load.noise
    variables = {v.name: v for v in read_model_description(fmu).modelVariables}
    assert float(variables["noise_intensity"].start) == noise.intensity
    assert int(variables["noise_seed"].start) == noise.seed and variables["noise_seed"].type == "Integer"
    assert float(variables["noise_unit"].start) == noise.unit
    assert variables["noise_intensity"].unit == "N.s0.5" and variables["noise_unit"].unit == "s"


@pytest.mark.parametrize("name", ["element", "network"])
def test_fmu_with_its_scene_load_is_the_library_bit_for_bit(fmus, name):
    fmu, scene_path = fmus[name]
    scene = load_scene(scene_path)
    if name == "element":
        library = simulate(scene)
        names, expected = ["x", "v"], [library.x, library.v]
    else:
        library = simulate_network(scene)
        names, expected = ["x_a", "v_a", "x_b", "v_b"], [library.x[:, 0], library.v[:, 0], library.x[:, 1],
                                                           library.v[:, 1]]
    result = fmu_run(fmu, names)
    np.testing.assert_allclose(result["time"], library.time, rtol=0, atol=1e-12)  # (FMPy adds up its steps)
    quiet = fmu_run(fmu, names, noise_intensity=0.0)
    assert np.abs(quiet[names[0]] - result[names[0]]).max() > 0.01  # the noise moves it
    for column, values in zip(names, expected):
        np.testing.assert_array_equal(result[column], values)


@pytest.mark.parametrize("name", ["element", "network"])
def test_noise_set_on_the_fmu_is_the_scene_noise(fmus, name):
    """noise_intensity, noise_seed and noise_unit set by the master give the path the scene's keys give."""
    fmu, scene_path = fmus[name]
    text = scene_path.read_text()
    other = text.replace("seed = 7", "seed = 12345").replace("seed = 21", "seed = 12345")
    other = other.replace("intensity = 0.4", "intensity = 1.3").replace("intensity = 0.8", "intensity = 1.3")
    changed = scene_path.with_name(f"{name}-other.toml")
    changed.write_text(other)
    scene = load_scene(changed)
    library = simulate(scene) if name == "element" else simulate_network(scene)
    column = "x" if name == "element" else "x_b"
    result = fmu_run(fmu, [column], noise_intensity=1.3, noise_seed=12345)
    np.testing.assert_array_equal(result[column], library.x if name == "element" else library.x[:, 1])


@pytest.mark.parametrize("name", ["element", "network"])
def test_rollback_and_split_steps_redraw_the_same_path(fmus, name):
    fmu, _ = fmus[name]
    out = "x" if name == "element" else "x_b"
    one = Slave(fmu, start_values={"scene_load": True})
    one.step(0.5)
    state = one.fmu.getFMUstate()
    one.step(0.25)
    first = one.get(out)
    one.fmu.setFMUstate(state)
    one.time = 0.5
    one.step(0.25)
    assert one.get(out) == first  # the rolled-back step drew the same increments
    two = Slave(fmu, start_values={"scene_load": True}, name="halves")
    for _ in range(6):  # 0.125 s each: whole numbers of internal steps of 0.005 s
        two.step(0.125)
    assert two.get(out) == first
    blob = two.fmu.serializeFMUstate(two.fmu.getFMUstate())
    three = Slave(fmu, start_values={"scene_load": True}, name="restored")
    three.fmu.setFMUstate(three.fmu.deSerializeFMUstate(blob))
    three.time = two.time
    two.step(0.3)
    three.step(0.3)
    assert three.get(out) == two.get(out)
    for slave in (one, two, three):
        slave.close()


@pytest.mark.parametrize("name", ["element", "network"])
@pytest.mark.parametrize("parameter,value,reason", [
    ("noise_intensity", -1.0, "noise_intensity = -1.0: must be a finite number >= 0"),
    ("noise_seed", -3, "noise_seed = -3: must be an integer"),
    ("noise_unit", 0.0, "noise_unit = 0.0: must be a finite number > 0"),
])
def test_bad_noise_parameter_is_a_logged_discard(fmus, name, parameter, value, reason):
    fmu, _ = fmus[name]
    slave = Slave(fmu, start_values={"scene_load": True})
    slave.step(0.1)
    out = "x" if name == "element" else "x_b"
    before = slave.get(out)
    slave.set(parameter, value)
    assert step_status(slave, slave.time, 0.1) == 2  # fmi2Discard
    assert any(reason in message for _, message in slave.messages), slave.messages
    assert slave.get(out) == before
    slave.close()


def test_a_stepper_without_noise_refuses_it(fmus):
    fmu, _ = fmus["element"]
    slave = Slave(fmu, start_values={"scene_load": True})
    slave.set("stepper", "exact")
    assert step_status(slave, 0.0, 0.1) == 2
    assert any("'exact' has no exact solution under a white noise" in message for _, message in slave.messages)
    slave.set("noise_intensity", 0.0)  # without the noise 'exact' applies
    assert step_status(slave, 0.0, 0.1) == 0
    slave.close()


def outputs_of(fmu):
    return [v.name for v in read_model_description(fmu).modelVariables if v.causality == "output"]


@pytest.mark.parametrize("name", ["white-noise", "element", "network"])
def test_a_step_below_rounding_changes_nothing_but_the_time(fmus, tmp_path, name):
    """Issue 44, item 2: OMSimulator's clock (2000 x 0.1 s) ends 7.1e-12 s short of 200 s and steps that
    remainder. A communication step below 1e-9 h changes no output (a white noise's increment over it would move
    v by sigma sqrt(7e-12)); the FMU takes the master's time (its clock within 1e-9 h of it), and the steps after
    it are the library's run without it, bit for bit."""
    if name == "white-noise":
        scene_path = SCENES / "white-noise.toml"
        fmu = str(build_fmu(scene_path, tmp_path / "white-noise.fmu"))
    else:
        fmu, scene_path = fmus[name]
    scene = load_scene(scene_path)
    short = 7e-12 if name == "white-noise" else 0.7e-9 * scene.solver.step
    assert short < 1e-9 * scene.solver.step < 2 * short
    names = outputs_of(fmu)
    slave = Slave(fmu, start_values={"scene_load": True})
    for _ in range(10):
        slave.step(0.1)
    before = slave.get(*names)
    slave.step(short)
    assert slave.get(*names) == before
    state = json.loads(bytes(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())))
    clock = state["element" if name != "network" else "network"]["time"]
    assert abs(clock - slave.time) < 1e-9 * scene.solver.step
    for _ in range(3):
        slave.step(0.1)
    library = (simulate if name != "network" else simulate_network)(scene.with_solver(stop_time=1.3))
    column = "x" if name != "network" else "x_b"
    expected = library.x[-1] if name != "network" else library.x[-1, 1]
    assert slave.get(column) == expected
    slave.close()
