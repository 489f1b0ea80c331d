"""The effects with memory ([delay], [history], [dahl]) in the native FMU (issue 35), FMI 2.0 and 3.0.

The kernels rebuild the library's memory tuple from the C layer's arrays (fmu/native/kernels.py: memory_layout), so the
native FMU is driver.Element bit for bit: over uneven communication steps for both steppers that carry memory
(implicit, projected), through a refused step (the memory's checkpoint), after a state serialized and restored in
another instance, with memory parameters set before initialization (Element.set_coefficients), and for a massless
element without a dashpot, which starts at the library's equilibrium with its delay's history and Dahl force. A
fixed parameter is refused after initialization, a bad one at initialization with the library's words, a forged
memory in a state is refused; the binary runs clean under AddressSanitizer and UBSan in the C host.

The native connector (x, v in, force out) carries them too: its outputs at the inputs set and after every step are
connector.Connector's (and the PythonFMU connector's) bit for bit, for each effect and all three; its state
continues bit for bit in the same and in another instance, a forged one is refused; its parameters are fixed and
checked as the PythonFMU connector's; its binary runs clean in the sanitized C host.
"""
import ctypes
import os
import shutil
import struct

import numpy as np
import pytest

from prandtl_fmu import load_scene
from prandtl_fmu.element import Element
from prandtl_fmu.stepping import ElementError
from prandtl_fmu.memory import delay as memory_delay
from prandtl_fmu.fmu.native.kernels import memory_layout

pytest.importorskip("fmpy")
from tests.fmu_tools import NativeInstance as Instance  # noqa: E402  (after the skip: it imports FMPy)
from tests.memory.scenes import EVERY_EFFECT  # noqa: E402
if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)

pytestmark = pytest.mark.slow  # native builds (10-60 s each): the element's four, the connector's ten

OK, DISCARD, ERROR = 0, 2, 3

# massless without a dashpot: x is the equilibrium at every step; at t = 0 the delay's history is that equilibrium
MASSLESS = """name = "massless-delay"

[spring]
k0 = 2.0

[branches]
k = [1.0, 0.5]
alpha = [0.2, 0.1]

[delay]
gain = 0.6
tau = 0.013

[dahl]
sigma = 20.0
force = 0.15

[load]
kind = "harmonic"
amplitude = 0.5
omega = 4.0

[solver]
stepper = "implicit"
step = 0.002
stop_time = 1.0
output_interval = 0.01
"""


def _build(folder, text, name, fmi, sanitized=False):
    from prandtl_fmu.fmu.build import build_fmu

    path = folder / f"{name}.toml"
    path.write_text(text)
    saved = os.environ.get("PRANDTL_NATIVE_CFLAGS")
    if sanitized:
        from tests.native_host import sanitizers

        os.environ["PRANDTL_NATIVE_CFLAGS"] = " ".join(sanitizers())
    try:
        return build_fmu(path, folder / f"{name}-{fmi}.fmu", runtime="native", fmi=fmi), path
    finally:
        if saved is None:
            os.environ.pop("PRANDTL_NATIVE_CFLAGS", None)
        else:
            os.environ["PRANDTL_NATIVE_CFLAGS"] = saved


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("native_memory")
    return {fmi: _build(folder, EVERY_EFFECT, "memory", fmi) for fmi in (2, 3)}


@pytest.fixture(scope="module")
def massless(tmp_path_factory):
    return _build(tmp_path_factory.mktemp("native_memory_massless"), MASSLESS, "massless", 2)


@pytest.mark.parametrize("fmi", [2, 3])
def test_the_memory_parameters_are_fixed_with_their_units_and_the_fmu_validates(fmus, fmi):
    """The memory's parameters are the PythonFMU FMU's (fixed, their units and start values); FMPy's validator finds
    nothing."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    path, _ = fmus[fmi]
    assert validate_fmu(str(path)) == []
    variables = {v.name: v for v in read_model_description(str(path)).modelVariables}
    expected = {"delay_gain": ("N/m", 0.7), "delay_tau": ("s", 0.023), "history_weight[1]": ("N/m", 0.4),
                "history_weight[2]": ("N/m", -0.1), "history_rate[1]": ("1/s", 1.3), "history_rate[2]": ("1/s", 0.0),
                "dahl_sigma": ("N/m", 30.0), "dahl_force": ("N", 0.2), "dahl_exponent": ("1", 1.0)}
    for name, (unit, start) in expected.items():
        assert variables[name].causality == "parameter" and variables[name].variability == "fixed"
        assert (variables[name].unit, float(variables[name].start)) == (unit, start)
    instance = Instance(str(path))
    assert instance.get(*expected) == [start for _, start in expected.values()]
    instance.close()


def uneven_steps(seed, count=60):
    """(size, force): communication steps of 1 to 8 internal steps, not multiples of each other in sequence."""
    rng = np.random.default_rng(seed)
    return [(int(rng.integers(1, 9)) * 0.001 + float(rng.choice([0.0, 0.00037])), float(rng.normal()))
            for _ in range(count)]


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("stepper", ["implicit", "projected"])
def test_the_native_fmu_is_the_library_bit_for_bit_over_uneven_steps(fmus, fmi, stepper):
    """x, v, reaction and the work after every step equal Element's; a step refused for an overflow rolls the memory
    back with the rest (the steps after it still agree)."""
    path, scene_path = fmus[fmi]
    element = Element(load_scene(scene_path))
    element.set_stepper(stepper)
    instance = Instance(str(path), start={"scene_load": True, "stepper": stepper})
    for j, (size, force) in enumerate(uneven_steps(3)):
        t = instance.time
        if j == 25:  # the delay's buffer, the history and the Dahl force moved in the refused steps: rolled back
            assert instance.step(0.5, 1e308) == DISCARD
            with pytest.raises(ElementError):
                element.time = t
                element.advance(0.5, 1e308, scene_load=True)
        assert instance.step(size, force) == OK, instance.messages[-3:]
        element.time = t
        element.advance(size, force, scene_load=True)
        assert instance.get("x", "v", "reaction", "work") == [element.x, element.v, element.reaction,
                                                               element.energy_of("work")], (j, stepper)
    instance.close()


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_serialized_state_restored_in_another_instance_continues_bit_for_bit(fmus, fmi):
    """The state holds the delay's buffer, the history's variables and the Dahl force: another instance, whose own
    tau differs (another buffer size), takes it and continues as the first did."""
    path, scene_path = fmus[fmi]
    steps = uneven_steps(5, 50)
    first = Instance(str(path), start={"scene_load": True})
    blob, rest = None, []
    for j, (size, force) in enumerate(steps):
        assert first.step(size, force) == OK
        if j == 24:
            blob, time = first.serialize(), first.time
        elif j > 24:
            rest.append(first.get("x", "v", "reaction"))
    first.close()
    other = Instance(str(path), name="other", start={"scene_load": True, "delay_tau": 0.05})
    other.step(0.01, 0.2)  # its own memory, then the state's
    other.restore(blob)
    other.time = time
    for (size, force), expected in zip(steps[25:], rest):
        assert other.step(size, force) == OK
        assert other.get("x", "v", "reaction") == expected
    other.close()


def fnv1a(data: bytes) -> int:
    value = 1469598103934665603
    for byte in data:
        value = ((value ^ byte) * 1099511628211) % 2**64
    return value


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_state_whose_memory_does_not_fit_is_refused(fmus, fmi):
    """The state's memory follows its fixed part (element.h: STATE_EXTRA), under the checksum: a Dahl force beyond
    F_c, a delay buffer's grid index that is not one (checksums recomputed) and a cut blob are refused with the
    reason, the instance unchanged."""
    path, scene_path = fmus[fmi]
    scene = load_scene(scene_path)
    layout = memory_layout(scene)
    length = layout["fixed"] + memory_delay.size(scene.delay, scene.solver.step)
    instance = Instance(str(path))
    assert instance.step(0.05, 0.7) == OK
    blob = instance.serialize()
    tail = len(blob) - 8 * length  # the memory's values; the checksum just before them
    assert struct.unpack_from("<d", blob, tail + 8 * layout["dahl_state"])[0] != 0.0  # the layout holds

    def forged(offset, value):
        data = bytearray(blob)
        data[offset:offset + 8] = struct.pack("<d", value)
        data[tail - 8:tail] = struct.pack("<Q", fnv1a(bytes(data[:tail - 8]) + bytes(data[tail:])))
        return bytes(data)

    from fmpy.fmi1 import FMICallException

    # the parameters the master set: before F's two input derivatives and the noise's settings
    mpar = tail - 8 - 24 - 16 - 8 * len(layout["names"])
    assert struct.unpack_from("<d", blob, mpar + 8)[0] == 0.023  # delay_tau
    for bad, words in ((forged(tail + 8 * layout["dahl_state"], 5.0), "beyond its level F_c = 0.2"),
                       (forged(mpar + 8, 0.05), "its memory's parameters in use are not those set"),
                       (forged(tail + 8 * layout["fixed"], -3.0), "grid index is -3"),
                       (blob[:-8], "not a serialized state of this FMU")):
        with pytest.raises(FMICallException):
            instance.restore(bad)
        assert instance.said(words), (words, instance.messages[-2:])
    # a state in the master's memory whose count of values was written over: refused before it is read
    state = instance.fmu.getFMUstate() if fmi == 2 else instance.fmu.getFMUState()
    assert ctypes.string_at(state.value, len(blob)) == blob
    at = blob.find(struct.pack("<qq", length - layout["fixed"], length))  # Element's nd, mem_len
    assert at > 0 and blob.find(struct.pack("<qq", length - layout["fixed"], length), at + 1) < 0
    ctypes.memmove(state.value + at + 8, struct.pack("<q", length + 1000), 8)
    with pytest.raises(FMICallException):
        instance.fmu.setFMUstate(state) if fmi == 2 else instance.fmu.setFMUState(state)
    assert instance.said("its memory's count of values is not the one it was made with")
    x = instance.get("x")
    instance.restore(blob)  # the genuine one
    assert instance.get("x") == x and instance.step(0.01, 0.1) == OK
    instance.close()


@pytest.mark.parametrize("fmi", [2, 3])
def test_memory_parameters_set_before_initialization_are_set_coefficients(fmus, fmi):
    """delay_gain, delay_tau (a larger buffer), a history rate and the Dahl level set in initialization mode: the
    library's element with them (Element.set_coefficients), bit for bit."""
    path, scene_path = fmus[fmi]
    values = {"delay_gain": -0.3, "delay_tau": 0.05, "history_rate[2]": 2.0, "dahl_force": 0.4}
    element = Element(load_scene(scene_path))
    element.set_coefficients(**values)
    instance = Instance(str(path), start=values)
    assert instance.get(*values) == list(values.values())
    for size, force in uneven_steps(9, 40):
        t = instance.time
        assert instance.step(size, force) == OK
        element.time = t
        element.advance(size, force)
        assert instance.get("x", "v", "reaction") == [element.x, element.v, element.reaction]
    instance.close()


def test_a_memory_parameter_is_fixed_and_checked_with_the_library_s_rules(fmus):
    """After initialization a memory parameter is refused (the PythonFMU FMU's words); at initialization a bad one is
    refused with the library's reason (set_coefficients), and a tau whose buffer is beyond the native bound with
    the number."""
    from fmpy.fmi1 import FMICallException

    path, scene_path = fmus[2]
    instance = Instance(str(path))
    assert instance.step(0.01, 0.0) == OK
    with pytest.raises(FMICallException):
        instance.set("delay_tau", 0.5)
    assert instance.said("parameter delay_tau = 0.5 refused: delay_tau is fixed (the initial state, or an effect with "
                         "memory) and cannot change after initialization")
    instance.set("delay_tau", 0.023)  # the same value: allowed
    element = Element(load_scene(scene_path))
    element.advance(0.01, 0.0)
    with pytest.raises(ElementError) as library:  # a master going back before what the delay recorded
        element.time = 0.002
        element.advance(0.01, 0.0)
    instance.time = 0.002
    assert instance.step(0.01, 0.0) == DISCARD
    words = "the time goes back to 0.002 s, before what the [delay]'s buffer recorded (up to "
    assert words in str(library.value) and instance.said(words + "0.01 s): its past would be wrong"), \
        (library.value, instance.messages[-1])
    instance.close()
    with pytest.raises(ValueError) as library:
        Element(load_scene(scene_path)).set_coefficients(delay_gain=-0.3, delay_tau=0.0005)
    reason = str(library.value).split(": ", 1)[1]
    element = Element(load_scene(scene_path))
    element.set_coefficients(delay_gain=-0.3)
    with pytest.raises(ValueError) as library:
        element.set_step(0.05)
    step_reason = str(library.value)
    for start, words in (({"delay_gain": -0.3, "delay_tau": 0.0005}, reason),
                         ({"delay_gain": -0.3, "step": 0.05}, "parameter " + step_reason),
                         ({"dahl_exponent": 150.0}, "parameter dahl_exponent: must be <= 100 (sigma 2^exponent"),
                         ({"dahl_sigma": -1.0}, "parameter dahl_sigma: must be > 0, got -1"),
                         ({"history_rate[1]": -2.0}, "parameter history_rate[1]: must be >= 0, got -2"),
                         ({"delay_tau": 1e6}, "tau / step = 1e+09 values in the delay's buffer, more than the native "
                                              "runtime's bound of 67108864 (512 MiB)")):
        refused = Instance(str(path), name="refused", start=start)
        assert refused.refused == ERROR and refused.said("initialization refused: "), start
        assert refused.said(words), (words, refused.messages)
        refused.fmu.freeInstance()


def test_a_massless_element_with_a_delay_starts_at_the_library_s_equilibrium(massless):
    """Massless, no dashpot: the initialization solves the equilibrium under F with the delay as a spring of its
    gain and the Dahl force moved along the jump (driver._initial_with_memory); then every step is the library's."""
    path, scene_path = massless
    element = Element(load_scene(scene_path))
    element.reset(0.4)
    instance = Instance(str(path), start={"F": 0.4})
    assert instance.get("x", "v", "reaction") == [element.x, element.v, element.reaction]
    assert element.x != 0.0
    for size, force in uneven_steps(11, 40):
        size *= 2  # the scene's step is 2 ms
        t = instance.time
        assert instance.step(size, force) == OK
        element.time = t
        element.advance(size, force)
        assert instance.get("x", "reaction") == [element.x, element.reaction]
    instance.close()


# ------------------------------------------------------------------ the binary in a C host, sanitized


@pytest.fixture(scope="module")
def sanitized(tmp_path_factory):
    """The memory scene's native FMU (FMI 2.0) built with the sanitizers where they run, and the trust host."""
    from tests.native_host import Native, compile_trust_host

    folder = tmp_path_factory.mktemp("native_memory_host")
    fmu, path = _build(folder, EVERY_EFFECT, "memory-sanitized", 2, sanitized=True)
    return compile_trust_host(folder, 2), Native(fmu, folder / "element", 2), path


def test_the_memory_binary_runs_clean_in_a_sanitized_c_host_and_is_the_library(sanitized, tmp_path):
    """A tau set before initialization (another buffer size), steps of uneven sizes, a refused overflow, a fixed
    parameter refused after initialization with the PythonFMU FMU's words, a bad parameter refused at the next
    initialization with the library's words, a state dumped, loaded and restored (its buffer size differs from the
    instance's after a reset), a reset: every value is Element's, and AddressSanitizer and UBSan find no leak, no
    invalid access, no undefined behaviour."""
    from tests.native_host import run_trust

    host, fmu, path = sanitized
    element = Element(load_scene(path))
    element.set_coefficients(delay_tau=0.031)
    commands, expected, t = ["setup:0", "setr:delay_tau:0.031", "enter", "setb:scene_load:0", "exit"], [], 0.0
    blob = tmp_path / "state.bin"
    for i, (size, force) in enumerate(uneven_steps(21, 16)):
        if i == 6:
            overflow = f"step:{t!r}:0.5"
            commands += ["setr:F:1e308", overflow]
        if i == 10:
            commands += ["save", f"dump:{blob}"]
            saved, saved_at = element.get_state(), t
        commands += [f"setr:F:{force!r}", f"step:{t!r}:{size!r}", "getr:x", "getr:v", "getr:reaction"]
        element.time = t
        element.advance(size, force)
        expected += [element.x, element.v, element.reaction]
        t += size
    element.set_state(saved)
    element.time = saved_at
    element.advance(0.0123, 0.3)
    expected.append(element.x)
    commands += ["setr:delay_tau:0.5", "reset", "setup:0", "setr:delay_tau:2.0", "enter", "exit",  # another size
                 f"load:{blob}", "restore", "setr:F:0.3", f"step:{saved_at!r}:0.0123", "getr:x",
                 "reset", "setup:0", "setr:dahl_exponent:0", "enter", "exit", "term", "free"]
    run = run_trust(host, fmu, commands)
    assert run.code == 0 and run.ended, run.out[-3000:]
    assert [value for _, value in run.values] == expected
    assert run.status(overflow) == DISCARD
    assert run.status("setr:delay_tau:0.5") == ERROR and run.status("restore") == OK, run.out[-3000:]
    assert run.said("delay_tau is fixed (the initial state, or an effect with memory)"), run.logs
    assert run.said("initialization refused: parameter dahl_exponent: must be > 0, got 0"), run.logs


# ------------------------------------------------------------------ the connector (x, v in, force out)

# Massless scenes with [fmu] causality = "displacement", one effect with memory each (its own kernel form in the
# layout), then all three. A connector's scene may not put a delay or a history on v (the reader refuses it: "v"
# needs [mass]), so both act on x; the [solver] stepper is not the connector's (it moves along the given path), only
# the step is read: the delay's grid.
CONNECTOR_SCENES = {
    # a negative gain with tau below the step: the element refuses it, the connector solves nothing and takes it
    "delay": """name = "connector-delay"

[spring]
k0 = 25.0

[damper]
c = 0.05

[branches]
k = [2.0, 1.0]
alpha = [0.1, 0.3]

[delay]
gain = -0.4
tau = 0.0007

[fmu]
causality = "displacement"

[solver]
stepper = "projected"
step = 0.001
stop_time = 1.0
output_interval = 0.01
""",
    # a negative weight and a zero rate, beside series dashpots (rate dependent too) and a cubic spring
    "history": """name = "connector-history"

[spring]
k0 = 10.0

[cubic]
k3 = 300.0

[branches]
k = [2.0, 1.0]
alpha = [0.1, 0.3]
c = [0.02, 0.05]

[history]
weight = [2.0, -0.5]
rate = [30.0, 0.0]

[fmu]
causality = "displacement"

[solver]
stepper = "implicit"
step = 0.001
stop_time = 1.0
output_interval = 0.01
""",
    # exponent 2, beside 80 branches on the memory stack
    "dahl": """name = "connector-dahl"

[spring]
k0 = 25.0

[branches]
count = 80
k_total = 20.0
eta_range = [0.001, 0.02]

[dahl]
sigma = 400.0
force = 1.5
exponent = 2.0

[fmu]
causality = "displacement"

[solver]
stepper = "projected"
step = 0.001
stop_time = 1.0
output_interval = 0.01
""",
    "all": """name = "connector-memory"

[spring]
k0 = 25.0

[damper]
c = 0.05

[branches]
k = [2.0, 1.0]
alpha = [0.1, 0.3]

[delay]
gain = 0.7
tau = 0.023

[history]
weight = [2.0, -0.5]
rate = [30.0, 0.0]

[dahl]
sigma = 400.0
force = 1.5

[fmu]
causality = "displacement"

[solver]
stepper = "implicit"
step = 0.001
stop_time = 1.0
output_interval = 0.01
""",
}
OUTPUTS = ("force", "stiffness", "stored_energy", "dissipated_sliders", "dissipated_damper")


@pytest.fixture(scope="module")
def connector_fmu(tmp_path_factory):
    """connector_fmu(effect, fmi) -> (the native connector FMU of CONNECTOR_SCENES[effect], its scene), each built
    once (on first use)."""
    folder = tmp_path_factory.mktemp("native_memory_connector")
    built = {}

    def get(effect, fmi):
        if (effect, fmi) not in built:
            built[effect, fmi] = _build(folder, CONNECTOR_SCENES[effect], f"connector-{effect}", fmi)
        return built[effect, fmi]

    return get


class DrivenConnector:
    """connector.Connector driven as fmu/python/kinds.py ConnectorKind drives it: memory coefficients ``start`` set before
    the first move, reset at the start time and moved to the first input; the outputs at the inputs set last are a
    copy's moved there (the preview), the dashpots' account the committed one's; a doStep commits the inputs at the
    communication point."""

    def __init__(self, scene, start=None, x=0.0, v=0.0, time=0.0):
        from prandtl_fmu.connector import Connector

        self.connector = Connector(scene)
        if start:
            self.connector.set_coefficients(**start)
        self.connector.reset()
        self.connector.time = time
        self.connector.move_to(x, v)
        self.x, self.v = x, v

    def outputs(self, names):
        twin = self.connector.copy()
        twin.move_to(self.x, self.v)
        values = {"force": twin.force, "stiffness": twin.stiffness(), "stored_energy": twin.stored_energy(),
                  "dissipated_sliders": twin.energy()["dissipated_sliders"],
                  "dissipated_damper": self.connector.energy()["dissipated_damper"]}
        return [values[name] for name in names]

    def step(self, t, x, v):
        self.x, self.v = x, v
        self.connector.move_to(x, v, max(t, self.connector.time))


def motion(seed, count=60):
    """(size, x, v): communication steps of 1 to 8 delay grid steps, not multiples of each other in sequence, along
    a random walk of x with reversals, and a velocity of its own (the dashpot's)."""
    rng = np.random.default_rng(seed)
    x, samples = 0.0, []
    for _ in range(count):
        x += float(rng.normal(0.0, 0.01))
        samples.append((int(rng.integers(1, 9)) * 0.001 + float(rng.choice([0.0, 0.00037])), x,
                        float(rng.normal(0.0, 0.5))))
    return samples


def _outputs(instance):
    return [name for name in OUTPUTS if name in instance.vr]


@pytest.mark.parametrize("fmi", [2, 3])
def test_the_native_connector_s_memory_parameters_are_fixed_with_their_units_and_the_fmu_validates(connector_fmu,
                                                                                                    fmi):
    """The native connector is built with its memory (the build refused it before): its memory parameters are the
    PythonFMU connector's (fixed, their units and start values), readable before a step; FMPy's validator finds
    nothing."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    path, _ = connector_fmu("all", fmi)
    assert validate_fmu(str(path)) == []
    variables = {v.name: v for v in read_model_description(str(path)).modelVariables}
    expected = {"delay_gain": ("N/m", 0.7), "delay_tau": ("s", 0.023), "history_weight[1]": ("N/(m.s)", 2.0),
                "history_weight[2]": ("N/(m.s)", -0.5), "history_rate[1]": ("1/s", 30.0),
                "history_rate[2]": ("1/s", 0.0), "dahl_sigma": ("N/m", 400.0), "dahl_force": ("N", 1.5),
                "dahl_exponent": ("1", 1.0)}
    for name, (unit, start) in expected.items():
        assert variables[name].causality == "parameter" and variables[name].variability == "fixed", name
        assert (variables[name].unit, float(variables[name].start)) == (unit, start)
    instance = Instance(str(path), name="connector")
    assert instance.get(*expected) == [start for _, start in expected.values()]
    instance.close()


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("effect", ["delay", "history", "dahl", "all"])
def test_the_native_connector_is_the_library_s_connector_bit_for_bit(connector_fmu, effect, fmi):
    """Every output at the inputs set (the preview) and after every doStep equals connector.Connector's, over uneven
    communication steps with reversals; an input set twice at one communication point (an iteration) moves
    nothing; a step of length 0 commits at the same time; a sample whose outputs would overflow is refused and rolls
    the memory back with the rest (the steps after it still agree)."""
    path, scene_path = connector_fmu(effect, fmi)
    samples = motion(31)
    instance = Instance(str(path), name="connector", start={"x": 0.004, "v": 0.2})
    library = DrivenConnector(load_scene(scene_path, check_stepper=False), x=0.004, v=0.2)
    names = _outputs(instance)
    assert instance.get(*names) == library.outputs(names)
    for j, (size, x, v) in enumerate(samples):
        t = instance.time
        if j == 20:  # the memory moved in the refused sample: rolled back
            assert instance.move(0.003, 1e200, library.v) == DISCARD
            assert instance.said("would be inf, not finite (an overflow); the state is unchanged")
            with pytest.raises(ElementError):
                library.connector.copy().move_to(1e200, library.v, t)  # (the library refuses it too)
        if j == 30:
            size = 0.0
        instance.set("x", x + 0.5)  # an iteration of the master: outputs at this input, nothing committed
        library.x = x + 0.5
        assert instance.get(*names) == library.outputs(names), (effect, j)
        instance.set("x", x)
        instance.set("v", v)
        library.x, library.v = x, v
        assert instance.get(*names) == library.outputs(names), (effect, j)
        assert instance.move(size, x, v) == OK, instance.messages[-3:]
        library.step(t, x, v)
        assert instance.get(*names) == library.outputs(names), (effect, j)
    instance.close()


def test_the_native_connector_is_the_pythonfmu_connector_bit_for_bit(connector_fmu, tmp_path):
    """The PythonFMU connector FMU of the same scene, driven by the same master (FMPy) with memory parameters set in
    initialization mode: the same outputs after every step, bit for bit."""
    from prandtl_fmu.fmu.build import build_fmu

    path, scene_path = connector_fmu("all", 2)
    python_fmu = build_fmu(scene_path, tmp_path / "python.fmu")
    start = {"x": 0.002, "v": -0.1, "delay_tau": 0.0171, "history_weight[2]": -1.5, "dahl_exponent": 1.5}
    native = Instance(str(path), name="native", start=start)
    python = Instance(str(python_fmu), name="python", start=start)
    names = _outputs(native)
    assert native.get(*names) == python.get(*names)
    for size, x, v in motion(41, 50):
        assert native.move(size, x, v) == OK and python.move(size, x, v) == OK
        assert native.get(*names) == python.get(*names)
    native.close()
    python.close()


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_connector_state_restored_mid_run_continues_bit_for_bit(connector_fmu, fmi):
    """The state holds the delay's buffer, the history's variables, the Dahl force and the inputs: set back into the
    same instance (an FMU state) it continues as the first time; serialized and restored in another instance, whose
    own tau differs (another buffer size), it continues the same."""
    path, _ = connector_fmu("all", fmi)
    samples = motion(5, 50)
    first = Instance(str(path), name="connector")
    names = _outputs(first)
    for size, x, v in samples[:25]:
        assert first.move(size, x, v) == OK
    state = first.fmu.getFMUstate() if fmi == 2 else first.fmu.getFMUState()
    blob, time = first.serialize(), first.time
    rest = []
    for size, x, v in samples[25:]:
        assert first.move(size, x, v) == OK
        rest.append(first.get(*names))
    first.fmu.setFMUstate(state) if fmi == 2 else first.fmu.setFMUState(state)
    first.time = time
    assert [first.move(size, x, v) == OK and first.get(*names) for size, x, v in samples[25:]] == rest
    first.close()
    other = Instance(str(path), name="other", start={"delay_tau": 0.05})
    assert other.move(0.01, 0.02, 0.1) == OK  # its own memory, then the state's
    other.restore(blob)
    other.time = time
    assert [other.move(size, x, v) == OK and other.get(*names) for size, x, v in samples[25:]] == rest
    other.close()


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_forged_connector_state_is_refused(connector_fmu, fmi):
    """The connector's state carries its memory after its fixed part, under the checksum: a state whose memory
    does not fit is refused with the reason (checksums recomputed: a Dahl force beyond F_c, memory parameters in use
    that are not those set, a grid index that is not the time's, a NaN in the delay's buffer, history variables whose
    force overflows), as are a garbled and a cut blob and one whose count of values the master wrote over; the
    instance is unchanged and takes the genuine state."""
    from fmpy.fmi1 import FMICallException

    path, scene_path = connector_fmu("all", fmi)
    scene = load_scene(scene_path, check_stepper=False)
    layout = memory_layout(scene)
    nd = memory_delay.size(scene.delay, scene.solver.step)
    length = layout["fixed"] + nd
    instance = Instance(str(path), name="connector")
    for size, x, v in motion(7, 20):
        assert instance.move(size, x, v) == OK
    blob = instance.serialize()
    # the memory's values; the checksum just before them, x's and v's input derivatives (four values) before it,
    # the parameters set before those
    tail = len(blob) - 8 * length
    mpar = tail - 8 - 32 - 8 * len(layout["names"])
    assert struct.unpack_from("<d", blob, mpar + 8)[0] == 0.023  # delay_tau: the layout holds
    assert struct.unpack_from("<d", blob, tail + 8 * layout["dahl_state"])[0] != 0.0

    def forged(offset, value, checksum=True):
        data = bytearray(blob)
        data[offset:offset + 8] = struct.pack("<d", value)
        if checksum:
            data[tail - 8:tail] = struct.pack("<Q", fnv1a(bytes(data[:tail - 8]) + bytes(data[tail:])))
        return bytes(data)

    history_z = tail + 8 * (1 + 2 * 2)  # the history's data: its cache's step, the weights, the rates, then z
    for bad, words in ((forged(tail + 8 * layout["dahl_state"], 5.0), "a Dahl force 5.0 beyond its level F_c = 1.5"),
                       (forged(mpar + 8, 0.05), "its memory's parameters in use are not those set"),
                       (forged(tail + 8 * layout["fixed"], 3.0), "grid index is 3.0, at t = "),
                       (forged(tail + 8 * (layout["fixed"] + 5), float("nan")), "its memory holds a non-finite value"),
                       (forged(history_z, 1e308), "its force or energy is not finite"),
                       (forged(tail + 8 * layout["dahl_state"], 0.5, checksum=False), "its checksum does not match"),
                       (blob[:-8], "not a serialized state of this FMU")):
        with pytest.raises(FMICallException):
            instance.restore(bad)
        assert instance.said(words), (words, instance.messages[-2:])
    state = instance.fmu.getFMUstate() if fmi == 2 else instance.fmu.getFMUState()
    assert ctypes.string_at(state.value, len(blob)) == blob
    at = blob.find(struct.pack("<qq", nd, length))  # Element's nd, mem_len
    assert at > 0 and blob.find(struct.pack("<qq", nd, length), at + 1) < 0
    ctypes.memmove(state.value + at + 8, struct.pack("<q", length + 1000), 8)
    with pytest.raises(FMICallException):
        instance.fmu.setFMUstate(state) if fmi == 2 else instance.fmu.setFMUState(state)
    assert instance.said("its memory's count of values is not the one it was made with")
    force = instance.get("force")
    instance.restore(blob)  # the genuine one
    assert instance.get("force") == force and instance.move(0.01, 0.01, 0.1) == OK
    instance.close()


def test_the_connector_s_memory_parameters_are_fixed_and_checked_with_the_library_s_rules(connector_fmu):
    """Set in initialization mode they are Connector.set_coefficients, bit for bit; after initialization a change is
    refused in the PythonFMU connector's words; a sample beyond what the delay's grid counts is a Discard in the
    library's words; at initialization a bad one is refused with the library's reason, a tau whose buffer is
    beyond the native bound with the number, a start time the delay cannot count from with the library's words
    (Connector.move_to)."""
    from fmpy.fmi1 import FMICallException
    from prandtl_fmu.connector import Connector

    path, scene_path = connector_fmu("all", 2)
    scene = load_scene(scene_path, check_stepper=False)
    values = {"delay_gain": -0.3, "delay_tau": 0.05, "history_rate[2]": 2.0, "dahl_force": 0.4}
    instance = Instance(str(path), name="connector", start=values)
    library = DrivenConnector(scene, start=values)
    names = _outputs(instance)
    assert instance.get(*values) == list(values.values())
    for size, x, v in motion(9, 40):
        t = instance.time
        assert instance.move(size, x, v) == OK
        library.step(t, x, v)
        assert instance.get(*names) == library.outputs(names)
    with pytest.raises(FMICallException):
        instance.set("dahl_force", 2.0)
    assert instance.said("parameter dahl_force = 2.0 refused: dahl_force is fixed (an effect with memory) and cannot "
                         "change after initialization; the connector is unchanged")
    instance.set("dahl_force", 0.4)  # the same value: allowed
    with pytest.raises(ValueError) as library_refusal:  # beyond 2^52 of the delay's grid steps
        library.connector.copy().move_to(0.01, 0.1, 1e13)
    instance.time = 1e13
    assert instance.move(0.001, 0.01, 0.1) == DISCARD
    assert instance.said(str(library_refusal.value) + "; the state is unchanged"), (library_refusal.value,
                                                                                 instance.messages[-1])
    instance.close()
    reasons = {}
    for start in ({"dahl_exponent": 150.0}, {"dahl_sigma": -1.0}, {"history_rate[1]": -2.0}):
        with pytest.raises(ValueError) as library_refusal:
            Connector(scene).set_coefficients(**start)
        reasons[next(iter(start))] = "parameter " + str(library_refusal.value)
    with pytest.raises(ValueError) as library_refusal:
        connector = Connector(scene)
        connector.time = -1.0
        connector.move_to(0.0, 0.0)
    for start, words in (({"dahl_exponent": 150.0}, reasons["dahl_exponent"]),
                         ({"dahl_sigma": -1.0}, reasons["dahl_sigma"]),
                         ({"history_rate[1]": -2.0}, reasons["history_rate[1]"]),
                         ({"delay_tau": 1e6}, "tau / step = 1e+09 values in the delay's buffer, more than the native "
                                              "runtime's bound of 67108864 (512 MiB)")):
        refused = Instance(str(path), name="refused", start=start)
        assert refused.refused == ERROR and refused.said("initialization refused: parameter "), start
        assert refused.said(words), (words, refused.messages)
        refused.fmu.freeInstance()
    early = Instance(str(path), name="early", start_time=-1.0)
    assert early.refused == ERROR
    assert early.said("initialization refused: " + str(library_refusal.value)), (library_refusal.value, early.messages)
    early.fmu.freeInstance()


@pytest.fixture(scope="module")
def sanitized_connector(tmp_path_factory):
    """The connector scene with every effect with memory as a native FMU (FMI 2.0) built with the sanitizers where
    they run, and the trust host."""
    from tests.native_host import Native, compile_trust_host

    folder = tmp_path_factory.mktemp("native_memory_connector_host")
    fmu, path = _build(folder, CONNECTOR_SCENES["all"], "connector-sanitized", 2, sanitized=True)
    return compile_trust_host(folder, 2), Native(fmu, folder / "connector", 2), path


def test_the_connector_memory_binary_runs_clean_in_a_sanitized_c_host_and_is_the_library(sanitized_connector,
                                                                                          tmp_path):
    """A tau set before initialization (another buffer size), uneven steps with previews, a refused overflow, a state
    dumped, a fixed parameter refused after initialization, a reset with another tau, the state loaded and restored
    into it (its buffer size differs), a bad parameter refused at the next initialization: every value is
    connector.Connector's, and AddressSanitizer and UBSan find no leak, no invalid access, no undefined behaviour."""
    from tests.native_host import run_trust

    host, fmu, path = sanitized_connector
    scene = load_scene(path, check_stepper=False)
    library = DrivenConnector(scene, start={"delay_tau": 0.031}, x=0.001, v=0.1)
    names = ["force", "stiffness", "stored_energy", "dissipated_sliders", "dissipated_damper"]
    commands = ["setup:0", "setr:delay_tau:0.031", "enter", "setr:x:0.001", "setr:v:0.1", "exit"]
    expected, t = [], 0.0
    blob = tmp_path / "state.bin"
    for i, (size, x, v) in enumerate(motion(21, 16)):
        if i == 6:
            overflow = f"step:{t!r}:0.5"
            commands += ["setr:x:1e200", overflow]
        if i == 10:
            commands += ["save", f"dump:{blob}"]
            saved, saved_at = library.connector.get_state(), t
        commands += [f"setr:x:{x!r}", f"setr:v:{v!r}", "getr:force", f"step:{t!r}:{size!r}"]
        library.x, library.v = x, v
        expected.append(library.outputs(["force"])[0])
        library.step(t, x, v)
        commands += [f"getr:{name}" for name in names]
        expected += library.outputs(names)
        t += size
    library.connector.set_state(saved)
    library.step(saved_at, 0.03, -0.2)
    expected += library.outputs(names)
    commands += ["setr:delay_tau:0.5", "reset", "setup:0", "setr:delay_tau:2.0", "enter", "exit",  # another size
                 f"load:{blob}", "restore", "setr:x:0.03", "setr:v:-0.2", f"step:{saved_at!r}:0.0123",
                 *[f"getr:{name}" for name in names],
                 "reset", "setup:0", "setr:dahl_exponent:0", "enter", "exit", "term", "free"]
    run = run_trust(host, fmu, commands)
    assert run.code == 0 and run.ended, run.out[-3000:]
    assert [value for _, value in run.values] == expected
    assert run.status(overflow) == DISCARD
    assert run.status("setr:delay_tau:0.5") == ERROR and run.status("restore") == OK, run.out[-3000:]
    assert run.said("delay_tau is fixed (an effect with memory)"), run.logs
    assert run.said("initialization refused: parameter dahl_exponent: must be > 0, got 0"), run.logs


def test_a_connector_scene_cannot_put_its_delay_or_history_on_v():
    """Why the connector's tests have the delay and the history on x: the scene's reader refuses them on v without
    [mass] (the massless element's velocity is not a degree of freedom), so no connector carries them."""
    from prandtl_fmu.scene import SceneError, parse_scene

    for table in ("[delay]\ngain = 0.7\ntau = 0.023", "[history]\nweight = [1.0]\nrate = [2.0]"):
        text = CONNECTOR_SCENES["dahl"].replace("[dahl]", f"{table}\nacts_on = \"v\"\n\n[dahl]")
        with pytest.raises(SceneError, match='"v" needs \\[mass\\]'):
            parse_scene(text)


def test_the_memory_builds_compile_no_copy_of_a_library_kernel_for_a_constant(fmus, connector_fmu):
    """The generated memory source handed the history's term count as a constant (``2``): numba typed it as a literal
    and compiled the library's loop, its step and every memory kernel under them once more for it, in every native
    build with a history (tests/compiled_copies.py). After the element's and a connector's builds with a history,
    the cache of this run holds no kernel signature with a literal."""
    from tests.compiled_copies import literal_signatures

    assert fmus[2][0].is_file() and connector_fmu("all", 2)[0].is_file()
    assert literal_signatures("history.prepare", "__init__.force_now") == []
