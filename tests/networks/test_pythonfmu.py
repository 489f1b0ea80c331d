"""The FMUs of network scenes (issue 32), driven by FMPy, against the library they bundle."""
import html
import json
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from prandtl_fmu import load_scene
from prandtl_fmu.stepping import ElementError
from prandtl_fmu.fmu.build import build_fmu
from prandtl_fmu.fmu.description import scene_load_notice
from prandtl_fmu.fmu.documentation import network_equations
from prandtl_fmu.network import NetworkConnector, NetworkElement, simulate
from prandtl_fmu.scene import SceneError

from tests.conftest import SCENES
from tests.fmu_tools import Slave, held_input

# every FMU of a network compiles the network kernels in its own process (40 s cold): under -m slow, which CI
# runs; the quick suite keeps the library's networks (networks/test_mechanics.py) and the element's FMUs
pytestmark = pytest.mark.slow

# three masses sliding on the support, held to the wall by a spring (the dynamic chain of Bastien & Lamarque)
CHAIN = """name = "chain3"

[chain]
n = 3
m = [1.0, 0.5, 2.0]
k = 2.0
alpha = [0.3, 0.2, 0.4]
k_wall = 1.5

[load]
kind = "harmonic"
amplitude = 1.5
omega = 0.8

[solver]
stepper = "implicit"
step = 1e-3
stop_time = 10.0
output_interval = 0.1
"""

# the quasi-static chain with a dashpot at every node: the dashpots set the rate
MASSLESS_CHAIN = """name = "massless_chain"

[chain]
n = 4
m = 0.0
k = 1.0
alpha = 0.25
c = 0.5

[load]
kind = "harmonic"
amplitude = 2.0
omega = 1.0

[solver]
stepper = "implicit"
step = 1e-3
stop_time = 10.0
output_interval = 0.1
"""

# a connector: the motion of the massless node b imposed, every kind of element behind it
CONNECTOR = """name = "network_connector"

[network]
nodes = ["a", "b"]
mass = [1.0, 0.0]
load_node = "b"

[[network.spring]]
between = ["a", "b"]
k = 1.0

[[network.branch]]
name = "joint"
between = ["b", "a"]
k = 2.0
eta = 0.1
c = 3.0

[[network.dashpot]]
between = ["a", "ground"]
c = 0.5

[[network.slider]]
between = ["a", "ground"]
alpha = 0.2

[[network.cubic]]
between = ["a", "ground"]
k3 = 0.3

[solver]
stepper = "implicit"
step = 1e-3
stop_time = 10.0
output_interval = 0.1

[fmu]
causality = "displacement"
"""

SCENE_TEXTS = {"chain": CHAIN, "massless": MASSLESS_CHAIN, "connector": CONNECTOR}


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """name -> (fmu path, scene path), built once for the module."""
    folder = tmp_path_factory.mktemp("network_fmus")
    built = {}
    for name, text in SCENE_TEXTS.items():
        scene_path = folder / f"{name}.toml"
        scene_path.write_text(text)
        built[name] = (build_fmu(scene_path, folder / f"{name}.fmu"), scene_path)
    return built


def variables_of(fmu):
    return {v.name: v for v in read_model_description(fmu).modelVariables}


@pytest.mark.parametrize("name", list(SCENE_TEXTS))
def test_model_description_names_every_node_and_parameter(fmus, name):
    fmu, scene_path = fmus[name]
    assert validate_fmu(str(fmu)) == []
    scene = load_scene(scene_path)
    network = scene.network
    load = network.nodes[network.load_node]
    md = read_model_description(fmu)
    variables = variables_of(fmu)
    assert all(v.description for v in md.modelVariables)
    assert all(v.unit for v in md.modelVariables if v.type == "Real")
    parameters = {v.name for v in md.modelVariables if v.causality == "parameter"}
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    inputs = {v.name for v in md.modelVariables if v.causality == "input"}
    if scene.causality == "force":
        assert md.coSimulation.modelIdentifier == "PrandtlNetwork"
        assert inputs == {"F"} and variables["F"].unit == "N"
        assert parameters == set(network.parameters()) | {"step", "stepper", "scene_load", "noise_intensity",
                                                          "noise_seed", "noise_unit"}
        nodes = network.nodes
        assert outputs[:2 * network.n + 1] == [f"{q}_{node}" for node in nodes for q in "xv"] + ["reaction"]
    else:
        assert md.coSimulation.modelIdentifier == "PrandtlNetworkConnector"
        assert inputs == {"x", "v"} and variables["x"].unit == "m" and variables["v"].unit == "m/s"
        # the load node's mass is not a parameter: the motion is imposed there
        assert parameters == set(network.parameters()) - {f"m_{load}"} | {"step"}
        nodes = [node for node in network.nodes if node != load]
        assert outputs[0] == "force" and outputs[1:1 + 2 * len(nodes)] == [f"{q}_{node}" for node in nodes
                                                                             for q in "xv"]
    units = {"m": "kg", "k": "N/m", "c": "N.s/m", "alpha": "N", "eta": "m", "k3": "N/m3"}
    for parameter in parameters - {"step", "stepper", "scene_load", "noise_intensity", "noise_seed", "noise_unit"}:
        assert variables[parameter].unit == units[parameter.split("_")[0]], parameter
        assert variables[parameter].variability == "tunable"
        assert float(variables[parameter].start) == network.parameters()[parameter]
    assert {"kinetic_energy", "stored_energy", "work", "energy_residual"} <= set(outputs)
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    with zipfile.ZipFile(fmu) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
        doc = html.unescape(archive.read("documentation/index.html").decode())
        osp = archive.read(f"resources/{md.coSimulation.modelIdentifier}_OspModelDescription.xml").decode()
    index = {v.get("name"): str(i + 1) for i, v in enumerate(root.find("ModelVariables"))}
    dependencies = {u.get("index"): u.get("dependencies") for u in root.find("ModelStructure/Outputs")}
    if scene.causality == "force":  # the outputs are those of the last step: no direct feedthrough of F
        assert set(dependencies.values()) == {""} and f'ref="x_{load}"' in osp and f'ref="v_{load}"' in osp
    else:  # the outputs show the network moved to the inputs set now
        assert set(dependencies.values()) == {f"{index['x']} {index['v']}"} and 'ref="force"' in osp
    assert len(dependencies) == len(outputs) == len(root.find("ModelStructure/InitialUnknowns"))
    # the page describes this network: its equations, every node, element and parameter
    assert network_equations(scene) in doc
    assert all(f"<td>{node}</td>" in doc for node in network.nodes)
    assert all(f"<td>{e.name}</td>" in doc for e in network.elements)
    assert all(parameter in doc for parameter in network.parameters())
    assert "Generalized Prandtl element" not in doc and "1.797" not in doc


@pytest.mark.parametrize("name", list(SCENE_TEXTS))
def test_the_toolbox_checker_passes(fmus, name):
    fmu, _ = fmus[name]
    run = subprocess.run([sys.executable, "-m", "fmu_manipulation_toolbox", "-input", str(fmu), "-check"],
                         capture_output=True, text=True, timeout=300)
    text = run.stdout + run.stderr
    assert run.returncode == 0, text
    assert "compliant with FMI-2.0" in text and "No semantic error" in text, text
    assert "ERROR" not in text, text


@pytest.mark.parametrize("name", ["chain", "massless"])
def test_with_scene_load_and_no_input_the_fmu_is_the_library_run(fmus, name):
    """simulate_fmu with scene_load = true and no input takes the very steps network.simulate takes: every output
    the CSV also has, bit for bit."""
    fmu, scene_path = fmus[name]
    scene = load_scene(scene_path)
    library = simulate(scene, energy=True, states=True)
    names = [c for c in library.names if c in variables_of(fmu) and c != "F"]
    assert len(names) >= 2 * scene.network.n + 6
    result = simulate_fmu(str(fmu), stop_time=scene.solver.stop_time, output_interval=scene.solver.output_interval,
                          start_values={"scene_load": True}, output=names)
    assert len(result) == len(library.time)
    for column in names:
        np.testing.assert_array_equal(result[column], library.column(column), err_msg=column)
    assert np.abs(library.x).max() > 0.1 and library.column("dissipated_sliders")[-1] > 0  # it moved and slid
    without = simulate_fmu(str(fmu), stop_time=scene.solver.stop_time, output_interval=scene.solver.output_interval,
                           start_values={"scene_load": False}, output=names[:1])
    assert np.all(without[names[0]] == 0)  # F alone (0): the switch matters


def test_a_fresh_network_fmu_runs_its_scene_load_and_says_so(fmus):
    """Issue 44.3: with no start values (``fmpy simulate``) the network's FMU runs its scene's load, and logs once
    (a warning, with logging off) that the load is added to F."""
    fmu, scene_path = fmus["chain"]
    scene = load_scene(scene_path)
    messages = []

    def logger(env, instance, status, category, message):
        messages.append((status, category.decode("utf-8"), message.decode("utf-8")))

    names = ["x_n3", "v_n3", "reaction"]
    result = simulate_fmu(str(fmu), stop_time=scene.solver.stop_time, output_interval=scene.solver.output_interval,
                          output=names, logger=logger)
    library = simulate(scene)
    for column in names:
        np.testing.assert_array_equal(result[column], library.column(column), err_msg=column)
    assert np.abs(library.column("x_n3")).max() > 0.1
    assert messages == [(1, "logStatusWarning", scene_load_notice(scene, "the load's node"))]


def step_sizes(rng, count):
    """Multiples of h, remainders, tiny, zero and long communication steps."""
    return np.concatenate([[1e-3, 2.5e-3, 0.0, 1e-7, 0.3337, 3.0], rng.uniform(1e-4, 0.3, count)])


@pytest.mark.parametrize("name", ["chain", "massless"])
def test_hand_stepped_fmu_agrees_with_the_network_element(fmus, name):
    fmu, scene_path = fmus[name]
    scene = load_scene(scene_path)
    rng = np.random.default_rng(7)
    sizes = step_sizes(rng, 50)
    forces = rng.uniform(-1.5, 1.5, len(sizes))
    element = NetworkElement(scene)
    names = [f"{q}_{node}" for node in scene.network.nodes for q in "xv"] + ["reaction", "work", "stored_energy",
                                                                            "kinetic_energy"]
    slave = Slave(fmu)
    try:
        for size, force in zip(sizes, forces):
            slave.step(size, force)
            element.advance(size, force)
            energy = element.energy()
            expected = np.concatenate([np.column_stack([element.x, element.v]).ravel(), [element.reaction],
                                       [energy["work"], energy["stored_energy"], energy["kinetic_energy"]]])
            np.testing.assert_allclose(slave.get(*names), expected, rtol=0, atol=1e-13)
        assert np.abs(element.x).max() > 0.1
    finally:
        slave.close()


def test_parameters_by_name_change_the_run_as_set_parameters_does(fmus):
    fmu, scene_path = fmus["chain"]
    scene = load_scene(scene_path)
    first = {"k_spring_1": 3.5, "alpha_n3": 0.25, "m_n2": 0.7, "k_wall": 0.9}
    later = {"alpha_n1": 0.1, "k_spring_2": 0.6}
    element = NetworkElement(scene)
    element.set_parameters(**first)
    plain = NetworkElement(scene)
    slave = Slave(fmu, start_values=first)
    names = [f"x_{node}" for node in scene.network.nodes] + ["reaction"]
    try:
        for k in range(60):
            if k == 30:
                for key, value in later.items():
                    slave.set(key, value)
                element.set_parameters(**later)
            force = 1.2 * np.sin(0.3 * k)
            slave.step(0.1, force)
            element.advance(0.1, force)
            plain.advance(0.1, force)
            np.testing.assert_allclose(slave.get(*names), list(element.x) + [element.reaction], rtol=0, atol=1e-13)
        assert np.abs(element.x - plain.x).max() > 1e-2  # they mattered
        assert slave.fmu.getReal([slave.vr["alpha_n1"]]) == [0.1]
    finally:
        slave.close()


def test_state_round_trip_gives_identical_continuations(fmus):
    fmu, scene_path = fmus["chain"]
    slave = Slave(fmu)
    other = Slave(fmu, unzipdir=slave.unzipdir, name="other")
    names = ["x_n1", "v_n2", "x_n3", "reaction", "dissipated_sliders"]
    try:
        for k in range(25):
            slave.step(0.2, 1.1 * np.cos(0.4 * slave.time))
        slave.set("step", 2e-3)  # settings are part of the state too
        slave.set("alpha_n2", 0.15)
        slave.step(0.2, 0.5)
        state = slave.fmu.getFMUstate()
        blob = slave.fmu.serializeFMUstate(state)
        data = json.loads(bytes(blob))  # plain JSON: the whole network
        assert len(data["network"]["x"]) == 3 and data["network"]["parameters"]["alpha_n2"] == 0.15
        assert data["settings"]["step"] == 2e-3

        def continuation(s):
            out = []
            for k in range(20):
                s.step(0.3, 0.9 * np.sin(0.9 * k))
                out.append(s.get(*names))
            return np.array(out)

        start = slave.time
        first = continuation(slave)
        slave.fmu.setFMUstate(state)
        slave.time = start
        np.testing.assert_array_equal(continuation(slave), first)
        restored = other.fmu.deSerializeFMUstate(blob)  # another instance, from the bytes
        other.fmu.setFMUstate(restored)
        other.time = start
        np.testing.assert_array_equal(continuation(other), first)
        assert other.fmu.getReal([other.vr["alpha_n2"]]) == [0.15]
        # a forged state is refused with the library's reason, the instance unchanged
        before = other.get(*names)
        data["network"]["u"] = [0.0] * (len(data["network"]["u"]) + 1)
        forged = other.fmu.deSerializeFMUstate(json.dumps(data).encode())
        with pytest.raises(FMICallException):
            other.fmu.setFMUstate(forged)
        assert any("state refused" in m and "u must be" in m for _, m in other.messages), other.messages
        assert other.get(*names) == before
        slave.fmu.freeFMUstate(state)
        other.fmu.freeFMUstate(restored)
    finally:
        slave.close()
        other.close()


def serialized(slave):
    return json.loads(bytes(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())))


def test_a_massless_chain_pulled_beyond_its_friction_is_a_discard_and_nothing_changes(fmus):
    """Without its dashpots (c = 0 by name) the massless chain holds at most the sum of the alphas (1 N): beyond,
    the library has no equilibrium, the step is fmi2Discard with its reason and the state stays; FMPy's
    simulate_fmu ends the run there."""
    fmu, scene_path = fmus["massless"]
    no_dashpots = {f"c_n{i}": 0.0 for i in range(1, 5)}
    element = NetworkElement(load_scene(scene_path))
    element.set_parameters(**no_dashpots)
    slave = Slave(fmu, start_values=no_dashpots)
    try:
        for force in (0.3, 0.6, 0.9):
            slave.step(0.5, force)
            element.advance(0.5, force)
        before, outputs = serialized(slave), slave.get("x_n4", "reaction")
        assert outputs == [element.x[3], element.reaction]
        with pytest.raises(ElementError, match="no equilibrium"):
            element.advance(0.5, 1.2)
        slave.set("F", 1.2)
        with pytest.raises(FMICallException) as refused:
            slave.fmu.doStep(slave.time, 0.5)
        assert refused.value.status == 2  # fmi2Discard
        assert any("no equilibrium" in m and "F = 1.2" in m for _, m in slave.messages), slave.messages
        assert serialized(slave)["network"] == before["network"] and slave.get("x_n4", "reaction") == outputs
        slave.step(0.5, 0.95)  # within the friction again: it goes on
        element.advance(0.5, 0.95)
        assert slave.get("x_n4") == element.x[3] != outputs[0]
    finally:
        slave.close()
    times = np.round(np.arange(0.0, 10.05, 0.1), 12)
    run = simulate_fmu(str(fmu), stop_time=10.0, output_interval=0.1, output=["x_n4"],
                       start_values={"scene_load": False, **no_dashpots}, input=held_input(times, 0.2 * times))
    assert 4.0 < run["time"][-1] < 6.0  # F = 0.2 t: ended early, silently, at the first Discard (F > 1 N)
    with pytest.raises(FMICallException):  # the scene's load starts at 2 N: no equilibrium at the start
        simulate_fmu(str(fmu), stop_time=1.0, start_values={"scene_load": True, **no_dashpots})


@pytest.mark.parametrize("name, value, culprit", [
    ("F", float("nan"), "F = nan"),
    ("alpha_n2", -1.0, "alpha_n2: must be >= 0.0, got -1.0"),
    ("m_n1", float("inf"), "m_n1: must be a finite number"),
    ("stepper", "projected", "this network has sliders"),
    ("stepper", "verlet", "a network takes 'implicit' or 'projected'"),
    ("step", 0.0, "step"),
])
def test_bad_values_are_a_discard_with_the_reason_and_nothing_changes(fmus, name, value, culprit):
    fmu, _ = fmus["chain"]
    slave = Slave(fmu)
    try:
        for _ in range(10):
            slave.step(0.1, 0.8)
        before, outputs = serialized(slave), slave.get("x_n3", "v_n3", "reaction")
        slave.set(name, value)
        with pytest.raises(FMICallException) as refused:
            slave.fmu.doStep(slave.time, 0.1)
        assert refused.value.status == 2  # fmi2Discard, not fatal
        assert any(culprit in message for _, message in slave.messages), slave.messages
        assert slave.get("x_n3", "v_n3", "reaction") == outputs
        assert serialized(slave)["network"] == before["network"]
        slave.set(name, {"F": 0.8, "alpha_n2": 0.2, "m_n1": 1.0, "stepper": "implicit", "step": 1e-3}[name])
        slave.step(0.1)
        assert slave.get("x_n3") != outputs[0]
    finally:
        slave.close()


def test_the_step_budget_is_a_discard(fmus):
    fmu, _ = fmus["chain"]
    slave = Slave(fmu)
    try:
        slave.step(0.1, 0.8)
        before = serialized(slave)
        with pytest.raises(FMICallException) as refused:
            slave.fmu.doStep(slave.time, 1e6)  # 1e9 steps of h
        assert refused.value.status == 2
        assert any("budget" in message for _, message in slave.messages), slave.messages
        assert serialized(slave)["network"] == before["network"]
    finally:
        slave.close()


def test_a_bad_start_value_fails_initialization_with_the_reason(fmus):
    fmu, _ = fmus["chain"]
    slave = Slave.__new__(Slave)  # built by hand, to read its messages after the refusal
    with pytest.raises(FMICallException):
        Slave.__init__(slave, fmu, start_values={"k_spring_1": -2.0})
    try:
        assert any("initialization refused" in m and "k_spring_1: must be >= 0.0, got -2.0" in m
                   for _, m in slave.messages), slave.messages
    finally:
        slave.fmu.freeInstance()


def connector_motion(k, dt):
    t = k * dt
    return t, 0.4 * np.sin(0.7 * t) + 0.1 * np.sin(2.9 * t), 0.28 * np.cos(0.7 * t) + 0.29 * np.cos(2.9 * t)


def test_the_connector_fmu_is_the_library_connector(fmus):
    """Inputs set at t, outputs read at once (the network moved to them), then doStep(t, H): the library's
    move_to(x, v, t) at every communication point; a parameter by name as set_parameters."""
    fmu, scene_path = fmus["connector"]
    scene = load_scene(scene_path)
    connector = NetworkConnector(scene)
    joint = [e.name for e in scene.network.elements].index("joint")
    slave = Slave(fmu)
    names = ["force", "x_a", "v_a", "stored_energy", "dissipated_sliders", "dissipated_damper", "u_joint", "work"]
    dt = 0.05
    try:
        for k in range(200):
            t, x, v = connector_motion(k, dt)
            slave.set("x", x)
            slave.set("v", v)
            if k == 100:  # the outputs show the parameters set now too
                assert slave.get("force") == pytest.approx(connector.force, abs=0.2)
                slave.set("k_spring_1", 2.5)
                connector.set_parameters(k_spring_1=2.5)
            got = slave.get(*names)
            connector.move_to(x, v, t)
            energy = connector.energy()
            expected = [connector.force, connector.x[0], connector.v[0], energy["stored_energy"],
                        energy["dissipated_sliders"], energy["dissipated_damper"], connector.elongation(joint),
                        energy["work"]]
            np.testing.assert_allclose(got, expected, rtol=0, atol=1e-13)
            assert slave.get("force") == got[0]  # reading again moves nothing
            slave.step(dt)
        assert energy["dissipated_sliders"] > 0 and abs(connector.u[joint]) > 0
    finally:
        slave.close()


def test_the_connector_state_round_trip_and_a_refused_motion(fmus):
    fmu, _ = fmus["connector"]
    slave = Slave(fmu)
    other = Slave(fmu, unzipdir=slave.unzipdir, name="other")
    dt = 0.05
    try:
        for k in range(40):
            _, x, v = connector_motion(k, dt)
            slave.set("x", x)
            slave.set("v", v)
            slave.step(dt)
        blob = slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())

        def continuation(s):
            out = []
            for k in range(40, 60):
                _, x, v = connector_motion(k, dt)
                s.set("x", x)
                s.set("v", v)
                out.append(s.get("force", "x_a", "stored_energy"))
                s.step(dt)
            return np.array(out)

        start = slave.time
        first = continuation(slave)
        other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(blob))
        other.time = start
        np.testing.assert_array_equal(continuation(other), first)
        before = serialized(other)
        other.set("x", float("inf"))
        with pytest.raises(FMICallException) as refused:
            other.fmu.doStep(other.time, dt)
        assert refused.value.status == 2
        assert any("x = inf" in message for _, message in other.messages), other.messages
        assert serialized(other)["network"] == before["network"]
        with pytest.raises(FMICallException):  # no output at a motion that is not finite
            other.get("force")
    finally:
        slave.close()
        other.close()


def test_a_native_host_runs_the_network_fmu_with_the_recipe(fmus, tmp_path):
    """The C host of tests/c_host (no Python of its own) with docs/masters.md's variables, PYTHONHOME included:
    the network FMU steps there as the library does, and a refusal reaches the host's logger as a Discard."""
    from tests.native_host import Extracted, compile_host, python_recipe, run_host

    fmu, scene_path = fmus["chain"]
    extracted = Extracted(fmu, tmp_path / "chain")
    env = dict(python_recipe(), PYTHONHOME=sys.base_prefix)
    code, calls, logs, values, out = run_host(
        compile_host(tmp_path), extracted, ["setup", "enter", "setb:scene_load:0", "exit", "setr:F:1.0",
                                            "steps:0:0.1:10", "getr:x_n3", "getr:reaction", "setr:alpha_n2:-1",
                                            "step:1:0.1", "getr:x_n3", "term", "free"], logging=True, env=env)
    assert code == 0, out
    element = NetworkElement(load_scene(scene_path))
    for _ in range(10):
        element.advance(0.1, 1.0)
    assert [value for _, value in values] == [element.x[2], element.reaction, element.x[2]]
    assert calls["step:1:0.1"] == ["2"]  # fmi2Discard
    assert any(status == 2 and "alpha_n2: must be >= 0.0" in message for status, _, message in logs), out


def test_the_native_runtime_takes_the_native_builder_or_says_networks_are_not_there(fmus, tmp_path, monkeypatch):
    """Without prandtl_fmu.fmu.native.build.build_native_network_fmu the native runtime refuses a network with one
    line; with it, build_fmu hands it the scene, the target and the options."""
    from prandtl_fmu.fmu.native import build as native_build

    _, scene_path = fmus["chain"]
    monkeypatch.delattr(native_build, "build_native_network_fmu", raising=False)
    with pytest.raises(ValueError, match="^--runtime native: networks are not in the native runtime yet$"):
        build_fmu(scene_path, tmp_path / "chain.fmu", runtime="native")
    calls = []

    def builder(path, out, fmi=2, causality=None, **options):  # (arrays, platforms: their defaults here)
        calls.append((path, out, fmi, causality))
        assert not options.get("arrays") and options.get("platforms") in (None, [], ())
        return out

    monkeypatch.setattr(native_build, "build_native_network_fmu", builder, raising=False)
    assert build_fmu(scene_path, tmp_path / "chain.fmu", runtime="native", fmi=3, osp=True) == tmp_path / "chain.fmu"
    assert calls == [(str(scene_path), tmp_path / "chain.fmu", 3, None)]
    assert 'ref="x_n3"' in (tmp_path / "chain3_OspModelDescription.xml").read_text()


def test_a_connector_of_a_massive_load_node_is_refused_at_build(tmp_path):
    scene_path = tmp_path / "chain.toml"
    scene_path.write_text(CHAIN)
    with pytest.raises(SceneError, match="must then be massless"):
        build_fmu(scene_path, tmp_path / "chain.fmu", causality="displacement")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["chain-dynamic", "chain-massless", "two-masses-slider"])
def test_the_packaged_network_scenes_as_fmus_are_their_library_runs(tmp_path, name):
    scene_path = SCENES / "networks" / f"{name}.toml"
    fmu = build_fmu(scene_path, tmp_path / f"{name}.fmu")
    assert validate_fmu(str(fmu)) == []
    scene = load_scene(scene_path)
    library = simulate(scene, energy=True)
    names = [c for c in library.names if c in variables_of(fmu) and c != "F"]
    result = simulate_fmu(str(fmu), stop_time=scene.solver.stop_time, output_interval=scene.solver.output_interval,
                          start_values={"scene_load": True}, output=names)
    for column in names:
        np.testing.assert_array_equal(result[column], library.column(column), err_msg=column)
