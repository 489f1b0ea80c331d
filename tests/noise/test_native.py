"""The white noise in the native FMUs (issue 34): the element and the network, FMI 2.0 and 3.0, draw the library's
Brownian path (noise.py, compiled into the binary) bit for bit.

The noise's path is a function of (seed, time) alone: the native FMU run with its scene's load equals the library's
run, the parameters noise_intensity, noise_seed and noise_unit set on a deterministic scene's FMU give the path of
the scene's own keys, a rolled-back or restored state redraws the same increments and two half communication steps
equal one. A bad value is a logged Discard with the PythonFMU FMU's words (tests/noise/test_pythonfmu.py asserts the same
words of it), a stepper that takes no noise refuses with the library's reason, a forged noise in a saved state is
refused, and the binary runs clean under AddressSanitizer and UBSan in the small C host of tests/c_host.
"""
import dataclasses
import os
import shutil
import struct

import numpy as np
import pytest

from prandtl_fmu import load_scene, parse_scene, simulate
from prandtl_fmu.element import Element
from prandtl_fmu.loads import WhiteNoise
from prandtl_fmu.fmu.native.kernels import applicable, noise_refusal
from prandtl_fmu.network import simulate as simulate_network

from tests.fmu_tools import DISCARD, OK, NativeInstance
from tests.noise.scenes import noisy_element
from tests.paths import ROOT

pytest.importorskip("fmpy")
if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)

# every test builds native FMUs (30-60 s each): under -m slow
pytestmark = pytest.mark.slow

REFUSED_UNTIL = "; steps are refused until it is set right"

ELEMENT = noisy_element(3.0)
# the same element without its noise: the FMU's parameters bring it back
QUIET = "\n".join(line for line in ELEMENT.splitlines() if not line.startswith("noise_")).replace(
    "noisy-element", "quiet-element") + "\n"
NOISE_KEYS = {"noise_intensity": 0.4, "noise_seed": 7, "noise_unit": 0.01}

# the load's node b has no dashpot: massless (m_b = 0) it takes no noise; 'projected' applies (masses, branches)
NETWORK = """name = "noisy-network"

[network]
nodes = ["a", "b"]
mass = [1.0, 0.5]

[[network.spring]]
between = ["a", "ground"]
k = 1.0

[[network.dashpot]]
between = ["a", "ground"]
c = 0.3

[[network.branch]]
between = ["a", "b"]
k = 2.0
eta = 0.1

[[network.spring]]
between = ["a", "b"]
k = 0.5

[load]
kind = "white_noise"
intensity = 0.8
seed = 21
noise_unit = 0.01
offset = 0.1

[solver]
stepper = "implicit"
step = 0.005
stop_time = 3.0
output_interval = 0.1
"""
# massless with a dashpot: backward Euler-Maruyama on c x' = F + sigma xi - ... ('implicit'), Euler-Maruyama
# ('projected', which books the dashpot's rate as dx / h under a noise, v without: with sigma = 0 the noisy kernel
# would not be the deterministic one to the bit, so the native FMU runs the deterministic one then)
MASSLESS = """name = "noisy-massless"

[spring]
k0 = 1.0

[damper]
c = 0.5

[branches]
k = [0.5, 0.3]
eta = [0.1, 0.4]

[load]
kind = "harmonic"
amplitude = 0.5
omega = 1.1
noise_intensity = 0.4
noise_seed = 7
noise_unit = 0.01

[solver]
stepper = "implicit"
step = 0.005
stop_time = 3.0
output_interval = 0.1
"""
SCENES = ROOT / "scenes"
TEXTS = {"element": ELEMENT, "quiet": QUIET, "network": NETWORK, "massless": MASSLESS,
         "white-noise": (SCENES / "white-noise.toml").read_text()}
ENERGY = ["work", "dissipated_sliders", "dissipated_damper", "energy_residual"]
COLUMNS = {"element": ["x", "v", "reaction"] + ENERGY, "quiet": ["x", "v", "reaction"] + ENERGY,
           "massless": ["x", "v", "reaction"] + ENERGY, "network": ["x_a", "v_a", "x_b", "v_b", "reaction"]}


class Built(dict):
    """Native FMUs built on first use, by (scene, fmi): a test run with -k builds only what it needs."""

    def __init__(self, folder):
        super().__init__()
        self.folder = folder

    def __missing__(self, key):
        from prandtl_fmu.fmu.build import build_fmu

        name, fmi = key
        path = self.folder / f"{name}.toml"
        path.write_text(TEXTS[name])
        self[key] = (str(build_fmu(path, self.folder / f"{name}-{fmi}.fmu", runtime="native", fmi=fmi)), path)
        return self[key]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    return Built(tmp_path_factory.mktemp("native_noise"))


def with_text(path, old, new):
    """The scene at ``path`` with ``old`` replaced by ``new`` in its text."""
    text = path.read_text()
    assert old in text
    return parse_scene(text.replace(old, new), str(path))


def library_columns(name, scene):
    """The library's run of ``scene``: time and each of COLUMNS[name]."""
    if name == "network":
        run = simulate_network(scene)
        return run.time, [run.x[:, 0], run.v[:, 0], run.x[:, 1], run.v[:, 1], run.reaction]
    run = simulate(scene, energy=True)
    return run.time, [run.x, run.v, run.reaction] + [run.energy[name] for name in ENERGY]


def fmu_columns(fmu, name, **start):
    from fmpy import simulate_fmu

    result = simulate_fmu(fmu, start_values=dict(scene_load=True, **start), output=COLUMNS[name],
                          fmi_call_logger=None)
    return result["time"], [result[column] for column in COLUMNS[name]]


class Instance(NativeInstance):
    """A native FMU's instance as these tests drive it: under the scene's own load unless ``start`` turns it off,
    one output at a time (an Integer one too), a refused initialization raised as FMPy raises it."""

    def __init__(self, fmu, start=None, name="noisy"):
        from fmpy.fmi1 import FMICallException

        super().__init__(fmu, name=name, start=start, driven=False)
        if self.refused is not None:
            raise FMICallException("exitInitializationMode", self.refused)

    def get(self, name):
        if self.types[name] in ("Integer", "Int32"):
            return (self.fmu.getInteger if self.fmi == 2 else self.fmu.getInt32)([self.vr[name]])[0]
        return super().get(name)[0]

    def step(self, size):
        """One doStep under the scene's load; its status."""
        return self.do_step(size)


# ------------------------------------------------------------------ the library's path, bit for bit


@pytest.mark.parametrize("name, fmi", [("element", 2), ("element", 3), ("network", 2), ("network", 3),
                                       ("massless", 2)])
def test_the_native_fmu_with_its_scene_load_is_the_library_bit_for_bit(built, name, fmi):
    """simulate_fmu with scene_load: the noisy run of the library (x, v, reaction and the energy account; the
    network's nodes); with noise_intensity = 0 the deterministic kernels: the library's run of the scene without
    its noise, bit for bit. FMPy's validator finds nothing in the description with the noise's parameters."""
    from fmpy.validation import validate_fmu

    fmu, path = built[name, fmi]
    assert validate_fmu(fmu) == []
    scene = load_scene(path)
    time, expected = library_columns(name, scene)
    got_time, got = fmu_columns(fmu, name)
    np.testing.assert_allclose(got_time, time, rtol=0, atol=1e-12)  # (FMPy adds up its steps)
    for column, fmu_values, values in zip(COLUMNS[name], got, expected):
        np.testing.assert_array_equal(fmu_values, values, err_msg=column)
    _, quiet = fmu_columns(fmu, name, noise_intensity=0.0)
    assert np.abs(quiet[0] - got[0]).max() > 0.01  # the noise moves it
    _, deterministic = library_columns(name, dataclasses.replace(scene, load=dataclasses.replace(scene.load,
                                                                                                 noise=None)))
    for column, fmu_values, values in zip(COLUMNS[name], quiet, deterministic):
        np.testing.assert_array_equal(fmu_values, values, err_msg=column)


@pytest.mark.parametrize("name", ["element", "network", "massless"])
def test_the_projected_stepper_draws_the_library_path(built, name):
    """'projected' (Euler-Maruyama) set on the FMU: the library's run of the scene with that stepper, with its
    noise and, noise_intensity = 0, without."""
    fmu, path = built[name, 2]
    scene = with_text(path, 'stepper = "implicit"', 'stepper = "projected"')
    for noise, start in ((scene.load.noise, {}), (None, {"noise_intensity": 0.0})):
        _, expected = library_columns(name, dataclasses.replace(scene, load=dataclasses.replace(scene.load,
                                                                                                noise=noise)))
        _, got = fmu_columns(fmu, name, stepper="projected", **start)
        for column, fmu_values, values in zip(COLUMNS[name], got, expected):
            np.testing.assert_array_equal(fmu_values, values, err_msg=f"{column} {noise}")


@pytest.mark.parametrize("fmi", [2, 3])
def test_the_parameters_on_a_deterministic_scene_are_its_noise_keys(built, fmi):
    """The FMU of the scene without noise: its parameters start at no noise (0, 0, 1 s); set to the noisy scene's
    keys they give the library's run of that scene bit for bit. noise_seed is an Integer (FMI 3.0: Int32)."""
    from fmpy import read_model_description

    fmu, path = built["quiet", fmi]
    variables = {v.name: v for v in read_model_description(fmu).modelVariables}
    assert variables["noise_seed"].type == ("Integer" if fmi == 2 else "Int32")
    assert [float(variables[name].start) for name in NOISE_KEYS] == [0.0, 0.0, 1.0]
    assert variables["noise_intensity"].unit == "N.s0.5" and variables["noise_unit"].unit == "s"
    for keys in (NOISE_KEYS, {"noise_intensity": 1.3, "noise_seed": 12345, "noise_unit": 0.25}):
        text = ELEMENT
        for key, value in NOISE_KEYS.items():
            text = text.replace(f"{key} = {value!r}", f"{key} = {keys[key]!r}")
        _, expected = library_columns("element", parse_scene(text, "element.toml"))
        _, got = fmu_columns(fmu, "quiet", **keys)
        for column, fmu_values, values in zip(COLUMNS["quiet"], got, expected):
            np.testing.assert_array_equal(fmu_values, values, err_msg=f"{column} {keys}")


@pytest.mark.parametrize("name, fmi", [("element", 2), ("element", 3), ("network", 2)])
def test_rollback_and_split_steps_redraw_the_same_path(built, name, fmi):
    """A state taken and set back, two half communication steps and a serialized state restored in another
    instance: the same increments, bit for bit (the cache of the Brownian tree is scratch, never state)."""
    fmu, _ = built[name, fmi]
    out = "x" if name == "element" else "x_b"
    one = Instance(fmu, {"scene_load": True})
    assert one.step(0.5) == OK
    state = one.get_state()
    assert one.step(0.25) == OK
    first = one.get(out)
    one.set_state(state)
    one.time = 0.5
    assert one.step(0.25) == OK
    assert one.get(out) == first  # the rolled-back step drew the same increments
    two = Instance(fmu, {"scene_load": True}, name="halves")
    for _ in range(6):  # 0.125 s each: whole numbers of internal steps of 0.005 s
        assert two.step(0.125) == OK
    assert two.get(out) == first
    blob = two.serialize()
    three = Instance(fmu, {"scene_load": True}, name="restored")
    three.restore(blob)
    three.time = two.time
    assert two.step(0.3) == OK and three.step(0.3) == OK
    assert three.get(out) == two.get(out)
    for instance in (one, two, three):
        instance.close()


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_step_below_rounding_of_h_changes_nothing_but_the_time(built, fmi):
    """Issue 44.2: OMSimulator's clock (2000 x 0.1 s) ends 7.1e-12 s short and steps that remainder; a doStep of
    7e-12 s (below 1e-9 h, the rounding docs/fmus.md drops) on the white-noise scene changes x, v and every output
    not at all (its Brownian increment moved v by 2e-6), and the steps after it are the library's run, bit for
    bit, and those of an instance that never took it."""
    from fmpy import read_model_description

    fmu, path = built["white-noise", fmi]
    scene = load_scene(path).with_solver(stop_time=2.0)
    short = 7e-12
    assert short < 1e-9 * scene.solver.step
    outputs = [v.name for v in read_model_description(fmu).modelVariables if v.causality == "output"]
    assert {"x", "v", "reaction", "stiffness", "work"} <= set(outputs)
    library = simulate(scene)
    one, twin = Instance(fmu, name="short"), Instance(fmu, name="twin")
    for instance in (one, twin):
        for _ in range(10):
            assert instance.step(0.1) == OK
    before = [one.get(name) for name in outputs]
    assert one.step(short) == OK
    assert [one.get(name) for name in outputs] == before  # nothing moved: x, v, every output
    for j in range(11, 21):
        assert one.step(0.1) == OK and twin.step(0.1) == OK
        assert [one.get(name) for name in outputs] == [twin.get(name) for name in outputs]
        assert (one.get("x"), one.get("v")) == (library.x[j], library.v[j]), j
    assert not [message for status, message in one.messages if status != OK]
    for instance in (one, twin):
        instance.close()


def test_a_restored_state_carries_the_noise_settings(built):
    """The state holds noise_intensity, noise_seed and noise_unit (not what was drawn): restored into an instance
    whose settings differ, the next steps are those of the saved settings."""
    fmu, _ = built["element", 2]
    saved = Instance(fmu, {"scene_load": True, "noise_seed": 99, "noise_intensity": 0.9})
    assert saved.step(0.2) == OK
    blob = saved.serialize()
    assert saved.step(0.2) == OK
    other = Instance(fmu, {"scene_load": True}, name="other")
    other.restore(blob)
    other.time = 0.2
    assert (other.get("noise_seed"), other.get("noise_intensity")) == (99, 0.9)
    assert other.step(0.2) == OK and other.get("x") == saved.get("x")
    saved.close()
    other.close()


# ------------------------------------------------------------------ refusals


def pythonfmu_words(settings) -> str:
    """What the PythonFMU FMU says of these noise settings (description.check_noise_settings, which its slave
    calls: the seed an FMU takes, then loads.white_noise's rules), after "parameter "."""
    from prandtl_fmu.fmu.description import check_noise_settings

    with pytest.raises(ValueError) as refused:
        check_noise_settings(settings["noise_intensity"], settings["noise_seed"], settings["noise_unit"])
    return str(refused.value)


@pytest.mark.parametrize("name", ["element", "network"])
@pytest.mark.parametrize("parameter, value", [
    ("noise_intensity", -1.0), ("noise_intensity", float("nan")), ("noise_intensity", float("inf")),
    ("noise_seed", -3), ("noise_seed", -2 ** 31), ("noise_unit", 0.0), ("noise_unit", -float("inf")),
    ("noise_unit", float("nan")),
])
def test_a_bad_noise_parameter_is_a_logged_discard_with_the_pythonfmu_words(built, name, parameter, value):
    """The PythonFMU FMU's message (its slave's noise hand-over), the state unchanged; set right, steps go on."""
    fmu, _ = built[name, 2]
    out = "x" if name == "element" else "x_b"
    slave = Instance(fmu, {"scene_load": True})
    assert slave.step(0.1) == OK
    before = slave.get(out)
    settings = {key: slave.get(key) for key in NOISE_KEYS}
    slave.set(parameter, value)
    assert slave.step(0.1) == DISCARD
    words = pythonfmu_words(dict(settings, **{parameter: value}))
    assert words.startswith(f"{parameter} = ")
    assert slave.said(f"parameter {words}{REFUSED_UNTIL}"), (words, slave.messages)
    assert slave.get(out) == before
    slave.set(parameter, settings[parameter])
    assert slave.step(0.1) == OK
    slave.close()


@pytest.mark.parametrize("name", ["element", "network"])
def test_a_noise_unit_too_coarse_for_the_step_is_refused_with_the_library_words(built, name):
    """loads.noise_problem: below 2^-40 units a step's increment would be rounded away (the adversarial review's
    silent zero); the native FMU refuses it as Element/NetworkElement.set_noise do, in their words."""
    from prandtl_fmu.loads import WhiteNoise, noise_problem

    fmu, _ = built[name, 2]
    out = "x" if name == "element" else "x_b"
    slave = Instance(fmu, {"scene_load": True})
    assert slave.step(0.1) == OK
    before = slave.get(out)
    step = slave.get("step")
    slave.set("noise_unit", 1e20)
    assert slave.step(0.1) == DISCARD
    words = noise_problem(WhiteNoise(slave.get("noise_intensity"), 0, 1e20), step)
    assert slave.said(f"parameter {words}{REFUSED_UNTIL}"), (words, slave.messages[-1])
    assert slave.get(out) == before
    slave.close()


def test_a_value_in_a_message_is_written_as_python_writes_it(built):
    """The refused value as Python's repr shows it (the PythonFMU's message): the shortest digits, '.0' on an
    integral value, an exponent below 1e-4 and from 1e16 on."""
    fmu, _ = built["element", 2]
    slave = Instance(fmu, {"scene_load": True})
    for value in (-2.5e-17, -1e16, -9999999999999998.0, -123456.0, -1e-05, -0.00015, -0.1, -1 / 3, -5e-324):
        slave.set("noise_intensity", value)
        assert slave.step(0.1) == DISCARD
        words = pythonfmu_words({"noise_intensity": value, "noise_seed": 7, "noise_unit": 0.01})
        assert slave.said(f"parameter {words}{REFUSED_UNTIL}"), (value, slave.messages[-1])
    slave.close()


def test_a_bad_start_value_fails_initialization(built):
    """At fmi2ExitInitializationMode a bad value is an error with the reason (as a coefficient's)."""
    from fmpy.fmi1 import FMICallException

    fmu, _ = built["element", 2]
    with pytest.raises(FMICallException):
        Instance(fmu, {"noise_seed": -1})


def test_a_stepper_that_takes_no_noise_refuses_it_with_the_library_reason(built):
    """Every native stepper of the scene that takes no noise (symplectic, verlet, exact) refuses it with the
    library's words: switched to under a noise (Element.set_stepper), or the noise turned on under it
    (Element.set_noise); without the noise each applies."""
    fmu, path = built["element", 2]
    scene = load_scene(path, check_stepper=False)
    refusing = [name for name in applicable(scene) if noise_refusal(scene, name)]
    assert {"exact", "symplectic", "verlet"} <= set(refusing)
    for stepper in refusing:
        reason = noise_refusal(scene, stepper)
        slave = Instance(fmu, {"scene_load": True})
        slave.set("stepper", stepper)
        assert slave.step(0.1) == DISCARD
        assert slave.said(f"parameter stepper = '{stepper}' refused: {reason}"), slave.messages
        slave.set("noise_intensity", 0.0)  # a noise turned off goes first: the stepper applies
        assert slave.step(0.1) == OK
        slave.set("noise_intensity", 0.4)  # turned on last, under the stepper: its own refusal
        assert slave.step(0.1) == DISCARD
        assert slave.said(f"parameter {reason}{REFUSED_UNTIL}"), slave.messages
        slave.close()


def test_a_massless_load_node_without_a_dashpot_refuses_the_noise(built):
    """network.model.stepper_problem: m_b = 0 set under the noise is refused (set_parameters), and so is the noise
    turned on over a massless b (set_noise), with the library's words; without the noise m_b = 0 applies."""
    from prandtl_fmu.fmu.native.network_build import noise_rule

    fmu, path = built["network", 2]
    damped, reason = noise_rule(load_scene(path))
    assert not damped and reason.startswith("a white noise on the massless node b with no dashpot on it")
    slave = Instance(fmu, {"scene_load": True})
    assert slave.step(0.1) == OK
    slave.set("m_b", 0.0)
    assert slave.step(0.1) == DISCARD
    assert slave.said(f"parameter m_b: {reason}{REFUSED_UNTIL}"), slave.messages
    slave.set("noise_intensity", 0.0)
    assert slave.step(0.1) == OK
    slave.set("noise_intensity", 0.8)
    assert slave.step(0.1) == DISCARD
    assert slave.said(f"parameter {reason}{REFUSED_UNTIL}"), slave.messages
    slave.set("m_b", 0.5)
    assert slave.step(0.1) == OK
    slave.close()


def fnv1a(data: bytes) -> int:
    value = 1469598103934665603
    for byte in data:
        value = ((value ^ byte) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return value


@pytest.mark.parametrize("name", ["element", "network"])
def test_a_forged_noise_in_a_state_is_refused(built, name):
    """The state's noise settings sit just before its checksum (sigma, seed, unit: 24 bytes): a negative
    intensity or seed written there, the checksum recomputed, is refused at deserialization with the rule's
    words; the instance steps on."""
    from fmpy.fmi1 import FMICallException

    fmu, _ = built[name, 2]
    slave = Instance(fmu, {"scene_load": True})
    assert slave.step(0.1) == OK
    blob = bytearray(slave.serialize())
    at = len(blob) - 8 - 24
    assert struct.unpack_from("<dqd", blob, at) == (slave.get("noise_intensity"), slave.get("noise_seed"),
                                                      slave.get("noise_unit"))  # the layout holds
    for field, packed, words in ((0, struct.pack("<d", -1.0), "noise_intensity = -1.0: must be a finite number"),
                                 (8, struct.pack("<q", -5), "noise_seed = -5: must be an integer"),
                                 (16, struct.pack("<d", float("inf")), "noise_unit = inf: must be a finite number")):
        forged = bytearray(blob)
        forged[at + field:at + field + 8] = packed
        forged[-8:] = struct.pack("<Q", fnv1a(bytes(forged[:-8])))
        with pytest.raises(FMICallException):
            slave.deserialize(bytes(forged))
        assert slave.said(words), slave.messages
    assert slave.step(0.1) == OK
    slave.close()


# ------------------------------------------------------------------ the binary in a C host, sanitized


@pytest.fixture(scope="module")
def sanitized(tmp_path_factory):
    """The noisy element's native FMU (FMI 2.0) built with the sanitizers where they run, and the trust host."""
    from tests.native_host import Native, compile_trust_host, sanitizers

    from prandtl_fmu.fmu.build import build_fmu

    folder = tmp_path_factory.mktemp("native_noise_host")
    path = folder / "element.toml"
    path.write_text(ELEMENT)
    saved = os.environ.get("PRANDTL_NATIVE_CFLAGS")
    os.environ["PRANDTL_NATIVE_CFLAGS"] = " ".join(sanitizers())
    try:
        fmu = build_fmu(path, folder / "element.fmu", runtime="native", fmi=2)
    finally:
        if saved is None:
            del os.environ["PRANDTL_NATIVE_CFLAGS"]
        else:
            os.environ["PRANDTL_NATIVE_CFLAGS"] = saved
    return compile_trust_host(folder, 2), Native(fmu, folder / "element", 2), path


def test_the_noisy_binary_runs_clean_in_a_sanitized_c_host_and_is_the_library(sanitized, tmp_path):
    """Steps of random sizes under random forces, the seed and intensity changed between them, a bad seed refused,
    a state saved, dumped, loaded and restored over other settings: every x, v and reaction is Element's (its
    noise set alike), and AddressSanitizer and UBSan find no leak, no invalid access, no undefined behaviour."""
    from tests.native_host import run_trust

    host, fmu, path = sanitized
    element = Element(load_scene(path))
    rng = np.random.default_rng(34)
    commands, expected, t = ["setup:0", "enter", "setb:scene_load:0", "exit"], [], 0.0  # F alone
    blob = tmp_path / "state.bin"
    for i in range(14):
        size, force = float(rng.choice([0.013, 0.05, 0.1, 0.0371])), float(rng.uniform(-1, 1))
        if i == 5:  # another path from here on: the seed and intensity set between steps
            commands += ["seti:noise_seed:2024", "setr:noise_intensity:1.1"]
            element.set_noise(WhiteNoise(1.1, 2024, 0.01))
        if i == 9:
            commands += ["save", f"dump:{blob}"]
            saved, saved_at = element.get_state(), t
        commands += [f"setr:F:{force!r}", f"step:{t!r}:{size!r}", "getr:x", "getr:v", "getr:reaction"]
        element.time = t
        element.advance(size, force)
        expected += [element.x, element.v, element.reaction]
        t += size
    element.set_state(saved)  # (its noise stays (1.1, 2024), the state's)
    element.time = saved_at
    element.advance(0.05, 0.3)
    expected.append(element.x)
    commands += ["seti:noise_seed:-1", f"step:{t!r}:0.1", "seti:noise_seed:5", "setr:noise_intensity:0.2",
                 f"load:{blob}", "restore", "geti:noise_seed", "setr:F:0.3", f"step:{saved_at!r}:0.05", "getr:x",
                 "term", "free"]
    run = run_trust(host, fmu, commands)
    assert run.code == 0 and run.ended, run.out[-3000:]
    values = [value for _, value in run.values]
    assert values[:-2] == expected[:-1]
    assert values[-2:] == [2024, expected[-1]]  # the state's seed, and its path
    assert run.status(f"step:{t!r}:0.1") == DISCARD and run.status("restore") == OK, run.out[-3000:]
    assert run.said("noise_seed = -1: must be an integer, 0 <= seed < 2^31"), run.logs
