"""The effects with memory in the PythonFMU FMU, through FMPy: the parameters with their units, the library's
numbers bit for bit over uneven communication steps, the state (buffer, history, Dahl force) serialized and
restored into another instance, a fixed parameter refused after initialization."""
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from prandtl_fmu import load_scene
from prandtl_fmu.element import Element
from prandtl_fmu.fmu.build import build_fmu

from tests.fmu_tools import Slave
from tests.memory.scenes import EVERY_EFFECT
from tests.paths import ROOT

pytestmark = pytest.mark.slow  # each FMU compiles the memory kernels in its own process



@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    folder = tmp_path_factory.mktemp("memory_fmu")
    scene_path = folder / "memory.toml"
    scene_path.write_text(EVERY_EFFECT)
    return str(build_fmu(scene_path, folder / "memory.fmu")), scene_path


def test_the_memory_parameters_are_fixed_with_their_units(fmu):
    variables = {v.name: v for v in read_model_description(fmu[0]).modelVariables}
    expected = {"delay_gain": ("N/m", 0.7), "delay_tau": ("s", 0.023), "history_weight[1]": ("N/m", 0.4),
                "history_weight[2]": ("N/m", -0.1), "history_rate[1]": ("1/s", 1.3), "history_rate[2]": ("1/s", 0.0),
                "dahl_sigma": ("N/m", 30.0), "dahl_force": ("N", 0.2), "dahl_exponent": ("1", 1.0)}
    for name, (unit, start) in expected.items():
        assert variables[name].causality == "parameter" and variables[name].variability == "fixed"
        assert (variables[name].unit, float(variables[name].start)) == (unit, start)


def test_the_fmu_is_the_library_bit_for_bit_and_its_state_restores(fmu):
    path, scene_path = fmu
    element = Element(load_scene(scene_path))
    slave = Slave(path, start_values={"scene_load": True})
    rng = np.random.default_rng(3)
    blob = None
    for j in range(60):
        size = int(rng.integers(1, 9)) * 0.001
        force = float(rng.normal())
        slave.step(size, force)
        element.advance(size, force, scene_load=True)
        assert slave.get("x", "v", "reaction") == [element.x, element.v, element.reaction]
        if j == 30:
            blob = slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())
            time, rest = slave.time, []
        if blob is not None and j > 30:
            rest.append((size, force, element.x, element.reaction))
    other = Slave(path, name="other", start_values={"scene_load": True})
    other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(blob))
    other.time = time
    for size, force, x, reaction in rest:
        other.step(size, force)
        assert other.get("x", "reaction") == [x, reaction]
    slave.close()
    other.close()


def test_a_fixed_memory_parameter_is_refused_after_initialization(fmu):
    slave = Slave(fmu[0])
    slave.step(0.01, 0.0)
    with pytest.raises(FMICallException):
        slave.set("delay_tau", 0.5)
    assert any("delay_tau" in message and "fixed" in message for _, message in slave.messages)
    slave.close()


def test_memory_parameters_set_before_initialization_are_the_library_with_them(fmu):
    path, scene_path = fmu
    values = {"delay_gain": -0.3, "delay_tau": 0.05, "history_rate[2]": 2.0, "dahl_force": 0.4}
    element = Element(load_scene(scene_path))
    element.set_coefficients(**values)
    slave = Slave(path, start_values=values)
    for _ in range(50):
        slave.step(0.004, 0.5)
        element.advance(0.004, 0.5)
        assert slave.get("x", "reaction") == [element.x, element.reaction]
    slave.close()


CONNECTOR = """name = "tensioner-connector"

[spring]
k0 = 25.0

[dahl]
sigma = 400.0
force = 1.5

[history]
weight = [2.0]
rate = [30.0]

[fmu]
causality = "displacement"

[solver]
step = 0.001
stop_time = 1.0
output_interval = 0.01
"""


def test_the_connector_fmu_with_memory_is_the_library_bit_for_bit(tmp_path):
    from prandtl_fmu.connector import Connector

    scene_path = tmp_path / "connector.toml"
    scene_path.write_text(CONNECTOR)
    path = str(build_fmu(scene_path, tmp_path / "connector.fmu"))
    variables = {v.name: v for v in read_model_description(path).modelVariables}
    assert variables["dahl_sigma"].variability == "fixed" and variables["history_weight[1]"].unit == "N/(m.s)"
    connector = Connector(load_scene(scene_path))
    slave = Slave(path, start_values={"x": 0.0, "v": 0.0})
    connector.move_to(0.0, 0.0, 0.0)
    rng = np.random.default_rng(8)
    x = 0.0
    for _ in range(80):
        size = int(rng.integers(1, 6)) * 0.002
        x += float(rng.normal(0.0, 0.004))
        slave.set("x", x)
        slave.set("v", 0.1)
        assert slave.get("force") == connector.preview(x, 0.1)  # an input set, not stepped: the preview
        start = slave.time
        slave.step(size)  # the sample belongs to the step's start time, as the library's move_to at that time
        connector.move_to(x, 0.1, start)
        assert slave.get("force") == connector.force
    with pytest.raises(FMICallException):
        slave.set("dahl_force", 2.0)
    assert any("dahl_force" in message and "fixed" in message for _, message in slave.messages)
    slave.close()


def test_the_tensioner_connector_and_a_belt_span_network_fmu_converge_to_the_whole_element(tmp_path):
    """examples/cosim/tensioner: the connector FMU of the tensioner (spring, Dahl friction) and the element FMU of
    a belt-span network scene, coupled by a Gauss-Seidel master over FMPy, converge at order 1 in the
    communication step to the library's element of both together; so does libcosim on the example's SSP
    structure (the torque through a linear transformation of factor -1)."""
    import importlib.util

    path = ROOT / "examples" / "cosim" / "tensioner" / "run_tensioner.py"
    spec = importlib.util.spec_from_file_location("run_tensioner", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    folder = example.build(tmp_path)
    for master, bound in (("gauss-seidel", 2e-3), ("libcosim", 5e-3)):  # libcosim: the SSP structure, Jacobi
        rows = example.convergence(folder, stop_time=0.05, steps=(4e-4, 2e-4, 1e-4), master=master)
        errors = [error for _, error, _ in rows]
        orders = [order for _, _, order in rows[1:]]
        assert all(0.8 < order < 1.6 for order in orders), (master, rows)
        assert errors[-1] < 0.35 * errors[0] and errors[-1] < bound, (master, rows)
