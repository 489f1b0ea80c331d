"""The native FMU of a network (issue 32): the library's compiled network kernels and the C FMI layer
(fmu/native/network.h), no Python in the binary.

Bit for bit, not to round-off: the FMU calls the same kernels (``run_implicit``, ``run_projected``,
``initial_state``, ``initial_reaction``, ``move_node``, ``jump_node``, ``kinetic``, ``stored``), compiled by the
same numba from the same source for the same types (no fast-math: LLVM keeps every IEEE operation as written);
the glue around them does the library's few operations (the clock, the split of a duration, the energy residual)
in the library's order. So every output is compared with ``==``, NaN never.

Scenes: a chain of three masses on a support with a wall spring (sliders and dashpots on the support), a massless
chain with dashpots, and a network with a Prandtl branch (series dashpot, u0) and a slider between two masses, a
cubic spring and a third mass held by a slider alone; the element against NetworkElement and simulate, the
connector against NetworkConnector (as fmu/python/kinds.py NetworkConnectorKind drives it), FMI 2.0 and 3.0 (arrays x and
v), FMU states (a short, altered or forged blob refused), parameters refused in the library's words, and the
binary in the small C host (tests/c_host/trust_host.c) with the sanitizers: NULL pointers and bad value
references refused, no crash."""
import copy
import math
import os
import shutil
import struct

import numpy as np
import pytest

from prandtl_fmu.network import NetworkConnector, NetworkElement, simulate
from prandtl_fmu.scene import SceneError, parse_scene
from tests.networks.scenes import SCENES

# every test builds native FMUs (20-40 s each from a cold cache): the quick suite has the element's native
# route (fmu/native/test_against_library.py, fmu/native/test_c_host.py); the networks' run under -m slow, as CI does
pytestmark = pytest.mark.slow

pytest.importorskip("fmpy")
if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)

OK, DISCARD, ERROR = 0, 2, 3


class Built(dict):
    """Native FMUs built on first use, keyed (scene, fmi, causality, arrays, sanitized): a run builds what it
    tests, once per module."""

    def __init__(self, folder):
        super().__init__()
        self.folder = folder

    def __missing__(self, key):
        from prandtl_fmu.fmu.native.build import build_native_network_fmu

        from tests.native_host import sanitizers

        name, fmi, causality, arrays, sanitized = key
        scene = self.folder / f"{name}.toml"
        scene.write_text(SCENES[name])
        out = self.folder / f"{name}-{fmi}-{causality}-{int(arrays)}-{int(sanitized)}.fmu"
        saved = os.environ.get("PRANDTL_NATIVE_CFLAGS")
        if sanitized:
            os.environ["PRANDTL_NATIVE_CFLAGS"] = " ".join(sanitizers())
        try:
            self[key] = build_native_network_fmu(scene, out, fmi=fmi, causality=causality, arrays=arrays), scene
        finally:
            if saved is None:
                os.environ.pop("PRANDTL_NATIVE_CFLAGS", None)
            else:
                os.environ["PRANDTL_NATIVE_CFLAGS"] = saved
        return self[key]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    return Built(tmp_path_factory.mktemp("native_network"))


def scene_of(name, causality=None):
    text = SCENES[name] + (f'\n[fmu]\ncausality = "{causality}"\n' if causality else "")
    return parse_scene(text, f"{name}.toml", check_stepper=False)


# ------------------------------------------------------------------ FMPy drivers

class Slave2:
    """An FMI 2.0 instance through FMPy, by variable names, with its log (start values of any type)."""

    def __init__(self, fmu, start=None):
        from fmpy import calloc, extract, free, read_model_description
        from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

        md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.outputs = [v.name for v in md.modelVariables if v.causality == "output"]
        self.messages = []

        def logger(env, instance, status, category, message):
            self.messages.append((status, message.decode("utf-8", "replace")))

        self._logger = fmi2CallbackLoggerTYPE(logger)  # kept alive with the instance
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = self._logger
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)),
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName="network")
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=False)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        from tests.fmu_tools import driven_by_f

        types = {v.name: v.type for v in md.modelVariables}
        for name, value in driven_by_f(types, start).items():  # F alone unless start sets scene_load
            setter = {"String": self.fmu.setString, "Boolean": self.fmu.setBoolean}.get(types[name],
                                                                                     self.fmu.setReal)
            setter([self.vr[name]], [value])
        self.fmu.exitInitializationMode()

    def set(self, names, values):
        self.fmu.setReal([self.vr[n] for n in names], list(values))

    def get(self, names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def step(self, t, size):
        self.fmu.doStep(t, size)

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


class Slave3:
    """An FMI 3.0 instance through FMPy, the same interface."""

    def __init__(self, fmu):
        from fmpy import extract, read_model_description
        from fmpy.fmi3 import FMU3Slave

        md = read_model_description(str(fmu))
        self.md = md
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.outputs = [v.name for v in md.modelVariables if v.causality == "output" and not v.dimensions]
        self.messages = []

        def log(env, status, category, message):
            self.messages.append((status, message.decode("utf-8", "replace")))

        self._log = log
        self.fmu = FMU3Slave(guid=md.instantiationToken, unzipDirectory=extract(str(fmu)),
                             modelIdentifier=md.coSimulation.modelIdentifier)
        self.fmu.instantiate(loggingOn=False, logMessage=log)
        self.fmu.enterInitializationMode()
        if "scene_load" in self.vr:  # F alone (driven_by_f)
            self.fmu.setBoolean([self.vr["scene_load"]], [False])
        self.fmu.exitInitializationMode()

    def set(self, names, values):
        self.fmu.setFloat64([self.vr[n] for n in names], list(values))

    def get(self, names):
        return self.fmu.getFloat64([self.vr[n] for n in names])

    def step(self, t, size):
        self.fmu.doStep(t, size)

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def library_outputs(stepped, scene, names, force_name="force"):
    """The library's value of each FMU output (the PythonFMU kinds' contract, fmu/python/kinds.py)."""
    network = scene.network
    energy = stepped.energy()
    values = []
    for name in names:
        if name == force_name and isinstance(stepped, NetworkConnector):
            values.append(stepped.force)
        elif name == "reaction":
            values.append(stepped.reaction)
        elif name in energy:
            values.append(energy[name])
        elif name.startswith(("x_", "v_")) and name[2:] in network.nodes:
            values.append((stepped.x if name[0] == "x" else stepped.v)[network.nodes.index(name[2:])])
        elif name.startswith("u_"):
            values.append(stepped.elongation([e.name for e in network.elements].index(name[2:])))
        elif name.startswith("dissipated_"):
            keys = [f"dissipated_{e.kind}_{e.name}" for e in network.elements]
            values.append(stepped.dissipated[keys.index(name)])
        else:
            raise KeyError(name)
    return [float(value) for value in values]


def random_steps(count, seed, sizes=(0.013, 0.05, 0.1, 0.0371), forces=(-5.0, 5.0)):
    rng = np.random.default_rng(seed)
    return [(float(rng.choice(sizes)), float(rng.uniform(*forces))) for _ in range(count)]


def element_against_library(slave, scene, stepper, steps, start=0.0):
    """Random communication steps (not all multiples of h) under random forces in the FMU and in
    NetworkElement: every output equal."""
    element = NetworkElement(scene, stepper=stepper)
    assert slave.get(slave.outputs) == library_outputs(element, scene, slave.outputs)
    t = start
    for size, force in steps:
        slave.set(["F"], [force])
        slave.step(t, size)
        element.time = t
        element.advance(size, force)
        assert slave.get(slave.outputs) == library_outputs(element, scene, slave.outputs), (t, size, force)
        t += size
    return element


# ------------------------------------------------------------------ the element

@pytest.mark.parametrize("name", ["joint", pytest.param("massless", marks=pytest.mark.slow),
                                  pytest.param("chain3", marks=pytest.mark.slow)])
def test_the_element_fmu_in_fmpy_is_network_element_bit_for_bit(built, name):
    """x_<node>, v_<node>, the reaction, the energy account, each element's dissipation and each branch's u after
    random communication steps under random forces: NetworkElement.advance's numbers exactly (the same compiled
    kernels, the glue in the library's order)."""
    from fmpy.validation import validate_fmu

    fmu, _ = built[name, 2, None, False, False]
    assert validate_fmu(str(fmu)) == []
    slave = Slave2(fmu)
    try:
        element_against_library(slave, scene_of(name), "implicit", random_steps(40, 3))
    finally:
        slave.close()


@pytest.mark.slow
def test_both_steppers_of_a_network_of_branches(built):
    """A network that takes 'projected' too (every node massive, no slider): each stepper, set as the FMU's
    parameter, bit for bit NetworkElement with that stepper."""
    fmu, _ = built["branches", 2, None, False, False]
    for stepper in ("projected", "implicit"):
        slave = Slave2(fmu, start={"stepper": stepper})
        try:
            element_against_library(slave, scene_of("branches"), stepper, random_steps(30, 4, forces=(-3, 3)))
        finally:
            slave.close()


def test_with_the_scene_load_the_fmu_reproduces_simulate(built):
    """scene_load on, F = 0, one communication step per output interval: the rows of prandtl_fmu.network.simulate
    (the massless chain: its equilibrium at t = 0 under the load, with rigid dashpots, included)."""
    fmu, _ = built["massless", 2, None, False, False]
    scene = scene_of("massless")
    result = simulate(scene)
    slave = Slave2(fmu, start={"scene_load": True})
    try:
        names = [n for n in result.names if n not in ("time", "F")]
        got = [slave.get(names)]
        interval = scene.solver.output_interval
        for row in range(1, result.table.shape[0]):
            slave.step(result.time[row - 1], interval)
            got.append(slave.get(names))
        want = result.table[:, [result.names.index(n) for n in names]]
        assert np.array_equal(np.array(got), want)
    finally:
        slave.close()


@pytest.mark.parametrize("name, cases", [
    ("joint", [("k_spring_1", -1.0, "must be >= 0"), ("k_branch_1", 0.0, "must be > 0"),
               ("eta_branch_1", 0.001, "outside [-eta, eta]"), ("alpha_slider_1", 1e60, "is outside"),
               ("m_c", -1.0, "must be >= 0")]),
    ("slider_held", [("m_b", 0.0, "massless and held by sliders alone")])])
def test_a_parameter_is_refused_in_the_library_s_words_and_steps_go_on_when_set_right(built, name, cases):
    """Each rule of Network.with_parameters and check_topology a parameter can break: a negative coefficient, a
    branch's k of 0, an eta below |u0|, a magnitude out of range, a node held by a slider alone made massless;
    the library refuses the same value (SceneError); the FMU discards the step with the reason logged, the state
    unchanged, and steps on once the value is set right."""
    fmu, _ = built[name, 2, None, False, False]
    network = scene_of(name).network
    slave = Slave2(fmu)
    try:
        slave.set(["F"], [1.0])
        slave.step(0.0, 0.05)
        t = 0.05
        before = slave.get(slave.outputs)
        for name, value, words in cases:
            with pytest.raises(SceneError, match=words.replace("[", r"\[").replace("]", r"\]")):
                network.with_parameters(**{name: value})
            slave.set([name], [value])
            messages = len(slave.messages)
            try:
                slave.step(t, 0.05)
                pytest.fail(f"{name} = {value} stepped")
            except Exception:  # noqa: BLE001 (FMPy: an FMICallException on fmi2Discard)
                pass
            said = [text for status, text in slave.messages[messages:] if status == DISCARD]
            assert said and words in said[0] and name in said[0], (name, slave.messages[messages:])
            assert slave.get(slave.outputs) == before
            slave.set([name], [network.parameters()[name]])
        slave.step(t, 0.05)
        assert slave.get(slave.outputs) != before
    finally:
        slave.close()


def test_an_eta_below_the_branch_s_elongation_now_is_refused(built):
    """The branch pulled to its kink (|u| = eta = 0.02), then eta set to 0.006 (above |u0|, below |u| now): the
    library refuses it (the stored energy k u^2 / 2 would drop unbooked), and so does the FMU, with the reason; the
    state as it was."""
    from fmpy.fmi1 import FMICallException

    fmu, _ = built["joint", 2, None, False, False]
    element = NetworkElement(scene_of("joint"))
    slave = Slave2(fmu)
    try:
        t = 0.0
        for _ in range(10):
            slave.set(["F"], [40.0])
            slave.step(t, 0.05)
            element.advance(0.05, 40.0)
            t += 0.05
        assert slave.get(["u_branch_1"]) == [element.elongation(5)] and abs(element.u[5]) > 0.006
        with pytest.raises(SceneError, match="below the branch's elongation now"):
            element.set_parameters(eta_branch_1=0.006)
        before = slave.get(slave.outputs)
        slave.set(["eta_branch_1"], [0.006])
        count = len(slave.messages)
        with pytest.raises(FMICallException):
            slave.step(t, 0.05)
        assert any("below the branch's elongation now" in text for _, text in slave.messages[count:])
        assert slave.get(slave.outputs) == before
    finally:
        slave.close()


def test_a_step_with_no_equilibrium_is_discarded_with_the_library_s_reason(built):
    """The massless chain with its dashpots and its wall spring set to 0 (springs between the nodes and sliders on
    the support hold it) pulled beyond the total friction of its nodes: no quasi-static solution. NetworkElement refuses the advance
    (ElementError); the FMU discards the step with the reason logged (logging off), its outputs unchanged, and
    steps on under a force the chain can hold."""
    from fmpy.fmi1 import FMICallException

    from prandtl_fmu.stepping import ElementError

    fmu, _ = built["massless", 2, None, False, False]
    scene = scene_of("massless")
    no_dashpots = {f"c_{node}": 0.0 for node in scene.network.nodes} | {"k_wall": 0.0}
    element = NetworkElement(scene.with_network(scene.network.with_parameters(**no_dashpots)))
    element.advance(0.1, 1.0)
    with pytest.raises(ElementError, match="no equilibrium"):
        element.advance(0.1, 2.0)
    slave = Slave2(fmu)
    try:
        slave.set(list(no_dashpots), list(no_dashpots.values()))
        slave.set(["F"], [1.0])
        slave.step(0.0, 0.1)
        before = slave.get(slave.outputs)
        assert before == library_outputs(element, element.scene, slave.outputs)
        slave.set(["F"], [2.0])
        count = len(slave.messages)
        with pytest.raises(FMICallException):
            slave.step(0.1, 0.1)
        said = [text for status, text in slave.messages[count:] if status == DISCARD]
        assert said and "no equilibrium" in said[0], slave.messages[count:]
        assert slave.get(slave.outputs) == before
        slave.set(["F"], [-1.0])
        slave.step(0.1, 0.1)
        element.advance(0.1, -1.0)
        assert slave.get(slave.outputs) == library_outputs(element, element.scene, slave.outputs)
    finally:
        slave.close()


# ------------------------------------------------------------------ the connector

def connector_against_library(slave, scene, samples, h_fmu=0.05):
    """The connector slave's semantics (fmu/python/kinds.py NetworkConnectorKind) on NetworkConnector: the outputs show the
    committed connector moved to the inputs at the FMU's time (a copy); doStep(t, H) commits the sample at t."""
    committed = NetworkConnector(scene)
    time = 0.0

    def preview(x, v):
        moved = copy.deepcopy(committed)
        moved.move_to(x, v, max(time, committed.time))
        return moved

    x0 = float(scene.network.x0[scene.network.load_node])
    assert slave.get(slave.outputs) == library_outputs(preview(x0, 0.0), scene, slave.outputs)
    t = 0.0
    for x, v in samples:
        slave.set(["x", "v"], [x, v])
        assert slave.get(slave.outputs) == library_outputs(preview(x, v), scene, slave.outputs), ("preview", t)
        slave.step(t, h_fmu)
        time = t
        committed = preview(x, v)
        time = t + h_fmu
        assert slave.get(slave.outputs) == library_outputs(preview(x, v), scene, slave.outputs), ("after", t)
        t += h_fmu
    return committed


def motion(count):
    k = np.arange(count)
    return list(zip((2.5 * np.sin(0.3 * k)).tolist(), (0.75 * np.cos(0.3 * k)).tolist()))


@pytest.mark.parametrize("fmi", [2, pytest.param(3, marks=pytest.mark.slow)])
def test_the_connector_fmu_is_network_connector_bit_for_bit(built, fmi):
    """The massless chain as a connector (its last node's motion in, the force that holds it out): the force,
    the other nodes' x and v, the energies and dissipations, before a step (a preview at the inputs set) and after
    it, equal NetworkConnector.move_to's exactly; the chain slides beyond its friction (the motion's amplitude is
    2.5 m) and sticks again."""
    fmu, _ = built["massless", fmi, "displacement", False, False]
    slave = Slave2(fmu) if fmi == 2 else Slave3(fmu)
    try:
        connector = connector_against_library(slave, scene_of("massless", "displacement"), motion(50))
        assert connector.energy()["dissipated_sliders"] > 1.0  # the sliders slipped
    finally:
        slave.close()


# ------------------------------------------------------------------ FMI 3.0

def test_fmi3_element_with_arrays(built):
    """FMI 3.0 with the arrays option: validates, steps as NetworkElement (the scalars), and the arrays x and v
    (n_nodes long) hold the scalars x_<node>, v_<node> in the nodes' order."""
    from fmpy.validation import validate_fmu

    fmu, _ = built["chain3", 3, None, True, False]
    assert validate_fmu(str(fmu)) == []
    slave = Slave3(fmu)
    scene = scene_of("chain3")
    nodes = scene.network.nodes
    try:
        assert slave.fmu.getUInt64([slave.vr["n_nodes"]]) == [len(nodes)]
        element_against_library(slave, scene, "implicit", random_steps(15, 7, forces=(-3, 3)))
        x = slave.fmu.getFloat64([slave.vr["x"]], nValues=len(nodes))
        v = slave.fmu.getFloat64([slave.vr["v"]], nValues=len(nodes))
        assert x == slave.get([f"x_{n}" for n in nodes]) and v == slave.get([f"v_{n}" for n in nodes])
    finally:
        slave.close()


# ------------------------------------------------------------------ the edges of rounding (issue 59)

INERTIA = 1.0 / 1e-3 ** 2  # m / h^2 of one_node with m_a = 1
X1 = (1e10 - 1.0) / (INERTIA + 1.0)  # backward Euler from rest under 1e10 N (the branch clipped at +1)


@pytest.mark.parametrize("name, start, steps", [
    # a massless node released from a huge load: x = 3, reaction 2 (k x - 1 = 2, the branch clipped at -1)
    ("one_node", {}, [(1e-3, 1e17, {}, {}), (1e-3, 2.0, {}, {"x_a": 3.0, "reaction": 2.0}),
                      (1e-3, 1e30, {}, {}), (1e-3, 2.0, {}, {"x_a": 3.0, "reaction": 2.0})]),
    # a step of 1e300 s cut to each interval (it used to take none: x stayed 0); 0.5 N on the elastic branch and
    # the spring: x = 0.25
    ("one_node", {"step": 1e300}, [(1.0, 0.5, {}, {"x_a": 0.25}), (1.0, 1.5, {}, {}), (0.25, -3.0, {}, {})]),
    # a mass stopped by a spring made 1e20 and 1e50 times stiffer: backward Euler's x2 = (m/h^2 2 x1 + 1) /
    # (m/h^2 + k)
    ("one_node", {"m_a": 1.0}, [
        (1e-3, 1e10, {}, {"x_a": X1}),
        (1e-3, 0.0, {"k_spring_1": 1e20}, {"x_a": (INERTIA * 2.0 * X1 + 1.0) / (INERTIA + 1e20)}),
        (1e-3, 1e20, {"k_spring_1": 1.0}, {}), (1e-3, 0.0, {"k_spring_1": 1e50}, {})]),
    # a ground spring of 1e-14 beside one of 1 (once 'no equilibrium'): x_a = 1 / ks, the reaction 2
    ("contrast", {}, [(1e-3, 2.0, {}, {"x_a": 1e14, "reaction": 2.0}), (1e-3, 0.5, {}, {}),
                      (1e-3, -2.0, {}, {})]),
])
def test_the_fmu_steps_as_the_library_at_the_edges_of_rounding(built, name, start, steps):
    """The FMU's numbers are the library's to the bit, and where a closed form exists, it (tests/networks/
    test_rounding_edges.py has the library's own)."""
    fmu, _ = built[name, 2, None, False, False]
    slave = Slave2(fmu, start)
    scene = scene_of(name)
    element = NetworkElement(scene, step=start.get("step"))
    element.set_parameters(**{key: value for key, value in start.items() if key != "step"})
    try:
        t = 0.0
        for size, force, parameters, closed in steps:
            slave.set(list(parameters), list(parameters.values()))
            element.set_parameters(**parameters)
            slave.set(["F"], [force])
            slave.step(t, size)
            element.time = t
            element.advance(size, force)
            assert slave.get(slave.outputs) == library_outputs(element, scene, slave.outputs), (name, t, size, force)
            for output, value in closed.items():
                assert slave.get([output])[0] == pytest.approx(value, rel=1e-15), (output, t)
            t += size
        assert element.time == t and not [m for m in slave.messages if m[0] != OK], slave.messages
    finally:
        slave.close()


# ------------------------------------------------------------------ FMU states

def test_a_state_restores_and_continues_bit_for_bit_and_a_bad_blob_is_refused(built):
    """Get, serialize, deserialize, set: the continuation equals the one without the detour; a blob one byte short,
    a blob with a byte flipped (the checksum) are refused with a logged reason, the instance unchanged."""
    from fmpy.fmi1 import FMICallException

    fmu, _ = built["joint", 2, None, False, False]
    slave = Slave2(fmu)
    try:
        for t, (size, force) in zip(np.cumsum([0.0, 0.05, 0.05]), [(0.05, 3.0)] * 3):
            slave.set(["F"], [force])
            slave.step(float(t), size)
        state = slave.fmu.getFMUstate()
        blob = slave.fmu.serializeFMUstate(state)
        slave.set(["F"], [-4.0])
        slave.step(0.15, 0.1)
        first = slave.get(slave.outputs)
        restored = slave.fmu.deSerializeFMUstate(blob)
        slave.fmu.setFMUstate(restored)  # F = 3 with it: the state holds what the master set
        slave.set(["F"], [-4.0])
        slave.step(0.15, 0.1)
        assert slave.get(slave.outputs) == first
        now = slave.get(slave.outputs)
        middle = len(blob) // 2
        for bad, words in ((blob[:-1], "bytes"), (blob[:middle] + bytes([blob[middle] ^ 1]) + blob[middle + 1:],
                                                  "checksum")):
            count = len(slave.messages)
            with pytest.raises(FMICallException):
                slave.fmu.deSerializeFMUstate(bad)
            assert any(words in text for _, text in slave.messages[count:]), slave.messages[count:]
            assert slave.get(slave.outputs) == now
        slave.fmu.freeFMUstate(state)
        slave.fmu.freeFMUstate(restored)
    finally:
        slave.close()


# ------------------------------------------------------------------ the C host (sanitizers)

def fnv1a(data: bytes) -> int:
    value = 1469598103934665603
    for byte in data:
        value = ((value ^ byte) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return value


def forged(blob: bytes, changes) -> bytes:
    """``blob`` with 8-byte fields written at byte offsets {offset: double or ('q', int)} and its checksum
    recomputed (common.h: FNV-1a of every byte before it, the last field)."""
    data = bytearray(blob)
    for offset, value in changes.items():
        data[offset:offset + 8] = struct.pack("<q", value[1]) if isinstance(value, tuple) else struct.pack("<d", value)
    data[-8:] = struct.pack("<Q", fnv1a(bytes(data[:-8])))
    return bytes(data)


def layout(network):
    """Byte offsets of the network's fields in the State of network.h (x86-64): the head (magic 24, version and size
    8, digest 65) ends at 97, the Element starts at 104: mass[n], coef[3 E], the stepper (an int, padded), h, x[n],
    v[n], u[E], piece[E], account[3], dissipated[E], reaction."""
    n, count = network.n, max(len(network.elements), 1)
    x = 104 + 8 * n + 24 * count + 16
    u = x + 16 * n
    piece = u + 8 * count
    return {"mass": 104, "x": x, "v": x + 8 * n, "u": u, "piece": piece, "dissipated": piece + 8 * count + 24,
            "reaction": piece + 16 * count + 24}


FORGERIES = {  # (field, element or node index, value) -> what the refusal says
    "a slider on a branch's kink piece": (("piece", "slider_1", ("q", 2)), "piece 2, which its kind has not"),
    "a piece of 7": (("piece", "branch_1", ("q", 7)), "piece 7"),
    "a spring off its piece": (("piece", "spring_1", ("q", 1)), "piece 1"),
    "u beyond eta": (("u", "branch_1", 0.5), "outside its elastic range"),
    "u on a spring": (("u", "spring_2", 1e-3), "outside its elastic range"),
    "x = NaN": (("x", 1, math.nan), "x and v must be finite"),
    "a negative dissipation": (("dissipated", "slider_1", -1.0), "is not one"),
    "a mass of -1 in use": (("mass", 0, -1.0), "must be >= 0"),
    # a derived output is checked against the state (kernels.reaction_fits), not shown as it was (issue 59.6)
    "a reaction of 12345": (("reaction", 0, 12345.0), "its reaction (12345 N) is not the one its x, v and u give"),
}


@pytest.fixture(scope="module")
def host2(tmp_path_factory):
    from tests.native_host import compile_trust_host

    return compile_trust_host(tmp_path_factory.mktemp("network_host"), 2)


def native(built, name, fmi, folder, causality=None):
    from tests.native_host import Native

    fmu, _ = built[name, fmi, causality, fmi == 3, True]
    return Native(fmu, folder / f"{name}-{fmi}-{causality}-unpacked", fmi)


def ran(run):
    """The host ended by itself, no sanitizer spoke, every message has a declared category."""
    declared = {"logStatusWarning", "logStatusDiscard", "logStatusError", "logStatusFatal", "logAll"}
    assert run.code == 0 and run.ended, run.out[-3000:]
    assert all(category in declared for _, category, _ in run.logs), run.logs
    return run


START = ["setup:0", "enter", "exit"]
START_BY_F = ["setup:0", "enter", "setb:scene_load:0", "exit"]  # an element driven by F alone, as the library's


def test_the_c_host_steps_the_network_as_the_library_and_refuses_nulls_and_bad_references(built, host2,
                                                                                         tmp_path_factory):
    """In a C host with AddressSanitizer and UBSan (logging off): steps under forces give NetworkElement's
    numbers; every function with a NULL instance returns an error, every NULL pointer argument is refused with a
    logged reason; a value reference that is no variable, a Real set on an output, a non-finite time are refused;
    the instance steps on; no leak, no invalid access."""
    from tests.native_host import run_trust

    fmu = native(built, "joint", 2, tmp_path_factory.mktemp("joint_native"))
    scene = scene_of("joint")
    element = NetworkElement(scene)
    commands, t = list(START_BY_F), 0.0
    expected = []
    for size, force in random_steps(8, 9):
        commands += [f"setr:F:{force!r}", f"step:{t!r}:{size!r}", "getr:x_a", "getr:v_b", "getr:reaction",
                     "getr:energy_residual"]
        element.time = t
        element.advance(size, force)
        expected += library_outputs(element, scene, ["x_a", "v_b", "reaction", "energy_residual"])
        t += size
    run = ran(run_trust(host2, fmu, commands + ["term", "free"]))
    assert [value for _, value in run.values] == expected
    assert all(status == str(OK) for command, status in run.calls if command.startswith(("step", "set")))

    bad = ran(run_trust(host2, fmu, ["nullc"] + START + ["nulla:F", "getr:99999", "setr:99999:1", "setr:x_a:1",
                                                          "step:nan:0.1", "step:0:-1", "setr:F:1", "step:0:0.1",
                                                          "getr:x_a"]))
    nulls = [(command, status) for command, status in bad.calls
             if command.startswith("nullc:") or command.startswith("nulla:") and "(" in command]
    assert len(nulls) >= 40 and all(status in (str(ERROR), "-1") for _, status in nulls), nulls
    assert bad.said("is NULL"), bad.logs
    for command in ("getr:99999", "setr:99999:1", "setr:x_a:1", "step:nan:0.1", "step:0:-1"):
        assert bad.status(command) == ERROR, (command, bad.out)
    assert bad.said("value reference 99999") and bad.said("must be finite"), bad.logs
    assert bad.status("step:0:0.1") == OK and math.isfinite(bad.values[-1][1])


@pytest.mark.parametrize("forgery", list(FORGERIES))
def test_a_forged_network_state_is_refused_field_by_field(built, host2, forgery, tmp_path, tmp_path_factory):
    """A state blob with one field forged and its checksum recomputed: fmi2DeSerializeFMUstate refuses it, and so
    does fmi2SetFMUstate when the bytes are written over a state's memory, with the reason logged; the instance
    is unchanged and steps on. The layout is checked first (x of node a where the test looks for it), and the
    unforged blob is accepted."""
    from tests.native_host import run_trust

    (field, which, value), words = FORGERIES[forgery]
    fmu = native(built, "joint", 2, tmp_path_factory.mktemp("joint_forged"))
    network = scene_of("joint").network
    at = layout(network)
    index = which if isinstance(which, int) else [e.name for e in network.elements].index(which)
    blob_path = tmp_path / "state.bin"
    first = ran(run_trust(host2, fmu, START + ["setr:F:3", "step:0:0.2", "getr:x_a", "save", f"dump:{blob_path}"]))
    blob = blob_path.read_bytes()
    assert struct.unpack_from("<d", blob, at["x"])[0] == first.values[-1][1]  # the layout holds
    bad = tmp_path / "forged.bin"
    bad.write_bytes(forged(blob, {at[field] + 8 * index: value}))
    same = tmp_path / "same.bin"
    same.write_bytes(forged(blob, {}))
    run = ran(run_trust(host2, fmu, START + ["setr:F:3", "step:0:0.2", "save", f"load:{bad}", f"poke:{bad}",
                                             "restore", "step:0.2:0.1", "getr:x_a", f"load:{same}", "restore"]))
    assert run.status(f"load:{bad}") == ERROR and run.status("restore") == ERROR, run.out
    refusals = [text for text in run.said(words) if "FMU state refused" in text]
    assert len(refusals) == 2, (words, run.logs)
    assert run.status("step:0.2:0.1") == OK and math.isfinite(run.values[-1][1])
    assert run.status(f"load:{same}") == OK and run.status("restore", 1) == OK


@pytest.mark.slow
def test_the_fmi3_binary_in_the_c_host(built, tmp_path_factory):
    """The FMI 3.0 binary of the chain (arrays on) in the sanitized host: NULL instance and pointers refused, the
    arrays read, steps as the library."""
    from tests.native_host import compile_trust_host, run_trust

    folder = tmp_path_factory.mktemp("chain3_host3")
    host = compile_trust_host(folder, 3)
    fmu = native(built, "chain3", 3, folder)
    scene = scene_of("chain3")
    element = NetworkElement(scene)
    element.advance(0.1, 1.5)
    run = ran(run_trust(host, fmu, ["nullc", *START_BY_F, "nulla:F", "setr:F:1.5", "step:0:0.1",
                                    "getr:x_n3", "geta:x:3", "getr:99999"]))
    assert run.status("step:0:0.1") == OK and run.status("getr:99999") == ERROR
    values = [value for _, value in run.values]
    assert values[0] == element.x[2] and values[1:] == element.x.tolist()


@pytest.mark.slow
def test_the_connector_binary_in_the_c_host(built, host2, tmp_path_factory):
    """The massless chain's connector (FMI 2.0) in the sanitized host: samples of the motion committed at each
    doStep give NetworkConnector's force; a non-finite input is discarded with its reason, NULL pointers refused;
    no leak, no invalid access."""
    from tests.native_host import run_trust

    fmu = native(built, "massless", 2, tmp_path_factory.mktemp("massless_connector"), "displacement")
    scene = scene_of("massless", "displacement")
    committed, commands, expected, t = NetworkConnector(scene), list(START), [], 0.0
    for x, v in motion(12):
        commands += [f"setr:x:{x!r}", f"setr:v:{v!r}", f"step:{t!r}:0.05"]
        committed.move_to(x, v, t)
        preview = copy.deepcopy(committed)
        preview.move_to(x, v, t + 0.05)
        commands.append("getr:force")
        expected.append(preview.force)
        t += 0.05
    run = ran(run_trust(host2, fmu, commands + ["setr:x:nan", f"step:{t!r}:0.05", "nulla:x", "term", "free"]))
    assert [value for _, value in run.values] == expected
    assert run.status(f"step:{t!r}:0.05") == DISCARD and run.said("the inputs must be finite"), run.logs
    assert run.said("is NULL")
