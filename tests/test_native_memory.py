"""The effects with memory ([delay], [history], [dahl]) in the native FMU (issue 35), FMI 2.0 and 3.0.

The kernels rebuild the library's memory tuple from the C layer's arrays (native/kernels.py: memory_layout), so the
native FMU is driver.Element bit for bit: over uneven communication steps for both steppers that carry memory
(implicit, projected), through a refused step (the memory's checkpoint), after a state serialized and restored in
another instance, with memory parameters set before initialization (Element.set_coefficients), and for a massless
element without a dashpot, which starts at the library's equilibrium with its delay's history and Dahl force. A
fixed parameter is refused after initialization, a bad one at initialization with the library's words, a forged
memory in a state is refused; the binary runs clean under AddressSanitizer and UBSan in the C host.
"""
import ctypes
import os
import shutil
import struct

import numpy as np
import pytest

from prandtl_fmu import load_scene
from prandtl_fmu.driver import Element, ElementError
from prandtl_fmu.memory import delay as memory_delay
from prandtl_fmu.native.kernels import memory_layout

pytest.importorskip("fmpy")
if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)

pytestmark = pytest.mark.slow  # four native builds (30-60 s each)

OK, DISCARD, ERROR = 0, 2, 3

# the scene of tests/test_memory_fmu.py (the PythonFMU FMU's): every effect with memory, the history on v
SCENE = """name = "memory-native"

[mass]
m = 0.8
x0 = 0.1

[spring]
k0 = 5.0

[branches]
k = [2.0, 1.0]
alpha = [0.1, 0.3]

[delay]
gain = 0.7
tau = 0.023

[history]
weight = [0.4, -0.1]
rate = [1.3, 0.0]
acts_on = "v"

[dahl]
sigma = 30.0
force = 0.2

[load]
kind = "harmonic"
amplitude = 1.0
omega = 3.0

[solver]
stepper = "implicit"
step = 0.001
stop_time = 1.0
output_interval = 0.01
"""

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
        from .native_host import sanitizers

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
    return {fmi: _build(folder, SCENE, "memory", fmi) for fmi in (2, 3)}


@pytest.fixture(scope="module")
def massless(tmp_path_factory):
    return _build(tmp_path_factory.mktemp("native_memory_massless"), MASSLESS, "massless", 2)


class Instance:
    """One instance of a native FMU (FMI 2.0 or 3.0) through FMPy, its messages kept; ``start``: values set in
    initialization mode."""

    def __init__(self, fmu, name="element", start=None):
        from fmpy import extract, read_model_description

        md = read_model_description(fmu)
        self.fmi = 3 if md.fmiVersion.startswith("3") else 2
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
        self.messages = []
        self.time = 0.0
        folder = extract(fmu)
        if self.fmi == 2:
            from fmpy import calloc, free
            from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                                   fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

            self._logger = fmi2CallbackLoggerTYPE(self._log2)  # kept alive with the instance
            callbacks = fmi2CallbackFunctions()
            callbacks.logger = self._logger
            callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            self._callbacks = callbacks
            self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                                 modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
            self.fmu.instantiate(callbacks=callbacks, loggingOn=False)
            self.fmu.setupExperiment(startTime=0.0)
        else:
            from fmpy.fmi3 import FMU3Slave

            self.fmu = FMU3Slave(guid=md.instantiationToken, unzipDirectory=folder,
                                 modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
            self.fmu.instantiate(loggingOn=False, logMessage=self._log3)
        self.fmu.enterInitializationMode()
        for key, value in (start or {}).items():
            self.set(key, value)
        from fmpy.fmi1 import FMICallException

        try:
            self.fmu.exitInitializationMode()
            self.refused = None
        except FMICallException as exc:  # (kept: the refusal's words are in the messages)
            self.refused = exc.status

    def _log2(self, env, instance, status, category, message):
        self.messages.append((status, message.decode("utf-8", "replace")))

    def _log3(self, env, status, category, message):
        self.messages.append((status, message.decode("utf-8", "replace")))

    def set(self, name, value):
        kind, vr = self.types[name], [self.vr[name]]
        if kind == "String":
            self.fmu.setString(vr, [value])
        elif kind == "Boolean":
            self.fmu.setBoolean(vr, [value])
        else:
            (self.fmu.setReal if self.fmi == 2 else self.fmu.setFloat64)(vr, [value])

    def get(self, *names):
        return list((self.fmu.getReal if self.fmi == 2 else self.fmu.getFloat64)([self.vr[n] for n in names]))

    def step(self, size, force):
        """One doStep from the instance's time under ``force``; its status (FMPy raises beyond a warning)."""
        from fmpy.fmi1 import FMICallException

        self.set("F", force)
        try:
            self.fmu.doStep(self.time, size)
        except FMICallException as exc:
            return exc.status
        self.time += size
        return OK

    def serialize(self) -> bytes:
        if self.fmi == 2:
            return bytes(self.fmu.serializeFMUstate(self.fmu.getFMUstate()))
        return bytes(self.fmu.serializeFMUState(self.fmu.getFMUState()))

    def restore(self, blob):
        if self.fmi == 2:
            self.fmu.setFMUstate(self.fmu.deSerializeFMUstate(blob))
        else:
            self.fmu.setFMUState(self.fmu.deserializeFMUState(blob))

    def said(self, words):
        return [message for _, message in self.messages if words in message]

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


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

    mpar = tail - 8 - 24 - 8 * len(layout["names"])  # the parameters the master set: before the noise's settings
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
    from .native_host import Native, compile_trust_host

    folder = tmp_path_factory.mktemp("native_memory_host")
    fmu, path = _build(folder, SCENE, "memory-sanitized", 2, sanitized=True)
    return compile_trust_host(folder, 2), Native(fmu, folder / "element", 2), path


def test_the_memory_binary_runs_clean_in_a_sanitized_c_host_and_is_the_library(sanitized, tmp_path):
    """A tau set before initialization (another buffer size), steps of uneven sizes, a refused overflow, a fixed
    parameter refused after initialization with the PythonFMU FMU's words, a bad parameter refused at the next
    initialization with the library's words, a state dumped, loaded and restored (its buffer size differs from the
    instance's after a reset), a reset: every value is Element's, and AddressSanitizer and UBSan find no leak, no
    invalid access, no undefined behaviour."""
    from .native_host import run_trust

    host, fmu, path = sanitized
    element = Element(load_scene(path))
    element.set_coefficients(delay_tau=0.031)
    commands, expected, t = ["setup:0", "setr:delay_tau:0.031", "enter", "exit"], [], 0.0
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


def test_the_native_connector_refuses_the_memory_in_one_line(tmp_path):
    """The library's connector carries memory (kernels/drive.py), the native connector's kernels not yet: the build
    stops before anything is compiled, naming the tables and what to do."""
    from prandtl_fmu.native.build import NativeBuildError, build_native_fmu

    path = tmp_path / "connector.toml"
    path.write_text(MASSLESS.replace('name = "massless-delay"', 'name = "connector-delay"\n\n[fmu]\ncausality = '
                                     '"displacement"'))
    with pytest.raises(NativeBuildError, match=r"\[delay\], \[dahl\]: the native connector does not carry the effects "
                                               r"with memory yet") as refused:
        build_native_fmu(path, tmp_path / "connector.fmu")
    assert "\n" not in str(refused.value)
