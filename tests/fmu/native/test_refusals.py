"""The native FMU's C layer refuses what the library refuses, with the library's reasons (issue 36).

One table of rules, drawn from the library's own: every coefficient of the scene (``scene.COEFFICIENTS``) with the
values its rule refuses (not finite, no physical magnitude, the sign its rule asks for: ``scene.coefficient_problem``,
``scene.magnitude_problem``), the rules between coefficients (``with_coefficients``: alpha_kinetic <= alpha;
``scene._check_memory_rules``: Dahl's exponent, a negative delay gain with tau below the step) and the white noise's
parameters (``fmu.description.check_noise_settings``: the seed an FMI Integer holds, then ``loads.white_noise``).
Each row is run against the library (``Element.set_coefficients`` / ``Connector.set_coefficients``,
``Element.set_noise``), which must refuse it, and against the native FMU (FMI 2.0 and 3.0, through FMPy), which
must refuse it at the exit of initialization mode (Error) and, for a tunable parameter, at a step (Discard), its
logged message holding the library's reason word for word (the values as Python shows them).

The reasons are computed from the library here, never written down: a rule the library changes is a rule the C
layer must follow. tests/fmu/native/test_hostile_host.py (magnitudes in the C host under the sanitizers) and
tests/memory/test_native.py (fixed parameters, the memory's own cases) cover what a table cannot.
"""
import math
import os
import shutil

import pytest

from prandtl_fmu import scene as rules
from prandtl_fmu.connector import Connector
from prandtl_fmu.element import Element
from prandtl_fmu.fmu.description import check_noise_settings, variables
from prandtl_fmu.scene import load_scene

from tests.conftest import base_tables, scene_text

pytest.importorskip("fmpy")
if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)
from tests.fmu_tools import DISCARD, ERROR, OK, NativeInstance  # noqa: E402  (after the skip: it imports FMPy)

pytestmark = pytest.mark.slow  # five native builds (10-30 s each cold)

SOLVER = {"stepper": "implicit", "step": 0.001, "stop_time": 1.0, "output_interval": 0.01}
BRANCHES = {"k": [0.5, 0.3], "eta": [0.1, 0.3], "c": [0.7, 1.5]}  # with series dashpots
MEMORY = {"delay": {"gain": 0.4, "tau": 0.023}, "history": {"weight": [0.4, -0.1], "rate": [1.3, 0.0]}}
# every coefficient the element can have: mass, springs, dashpot, friction with a Stribeck drop, branches with
# series dashpots, a delay and a history (on v), a white noise; Dahl's friction instead of the friction on the
# ground (a scene has one law of it); the connector's: springs, dashpot, branches, the three effects with memory
ELEMENT = base_tables(
    solver=SOLVER, friction={"alpha": 0.5, "alpha_kinetic": 0.3, "stribeck_velocity": 0.1, "belt_velocity": 0.2},
    branches=BRANCHES, delay=MEMORY["delay"], history=dict(MEMORY["history"], acts_on="v"),
    load={"kind": "white_noise", "intensity": 0.1, "seed": 7, "noise_unit": 0.001})
DAHL = base_tables(solver=SOLVER, branches=BRANCHES, dahl={"sigma": 30.0, "force": 0.2}, **MEMORY)
CONNECTOR = base_tables(mass=None, solver=SOLVER, fmu={"causality": "displacement"}, branches=BRANCHES,
                        dahl={"sigma": 30.0, "force": 0.2}, **MEMORY)
SCENES = {"element": ELEMENT, "dahl": DAHL, "connector": CONNECTOR}
BUILDS = [("element", 2), ("element", 3), ("dahl", 2), ("connector", 2), ("connector", 3)]


def refused_values(name: str) -> list:
    """The values the rule of coefficient ``name`` refuses (scene.coefficient_problem): not finite, no physical
    magnitude (a value: the upper bound only), below zero or at zero as its sign rule says."""
    rule = rules.COEFFICIENTS[rules._coefficient_key(name)][1]
    values = [math.nan, math.inf, -math.inf, 1e60, -1e60]
    if name not in rules.VALUES:
        values += [1e-60, -1e-60]
    values += {"> 0": [0.0, -1.0], ">= 0": [-1.0], "finite": []}[rule]
    return [value for value in values if rules.coefficient_problem(name, value)]


def table(scene) -> list:
    """The rows (label, values set, parameter named, reason) of a scene: the library refuses each, with its reason
    (the words after the name it gives)."""
    library = Connector if scene.causality == "displacement" else Element
    rows = []
    coefficients = rules.coefficients_of(scene)
    for name in coefficients:
        for value in refused_values(name):
            rows.append((f"{name}={value!r}", {name: value}, name))
    if scene.friction is not None and scene.friction.stribeck_velocity is not None:  # with_coefficients
        rows.append(("alpha_kinetic>alpha", {"alpha_kinetic": 2.0 * coefficients["alpha"]}, "alpha_kinetic"))
    if scene.dahl is not None:  # _check_memory_rules: sigma 2^exponent would overflow
        rows.append(("dahl_exponent>max", {"dahl_exponent": 150.0}, "dahl_exponent"))
    if scene.delay is not None and scene.causality == "force":  # _check_memory_rules: a non-monotone step
        rows.append(("negative gain, tau<step", {"delay_gain": -0.3, "delay_tau": scene.solver.step / 2}, "delay_gain"))
    found = []
    for label, values, name in rows:
        with pytest.raises(ValueError) as refusal:
            library(scene).set_coefficients(**values)
        found.append((label, values, name, library_reason(str(refusal.value))))
    if scene.causality == "force":  # the white noise the FMU adds (its start values: the scene's)
        noise = scene.load.noise
        start = (noise.intensity, noise.seed, noise.unit) if noise is not None else (0.0, 0, 1.0)
        for name, bad in (("noise_intensity", -1.0), ("noise_intensity", math.nan), ("noise_seed", -1),
                          ("noise_unit", 0.0), ("noise_unit", -math.inf)):
            settings = dict(zip(("noise_intensity", "noise_seed", "noise_unit"), start), **{name: bad})
            with pytest.raises(ValueError) as refusal:
                Element(scene).set_noise(check_noise_settings(**{key.split("_")[1]: value
                                                                  for key, value in settings.items()}))
            found.append((f"{name}={bad!r}", {name: bad}, name, str(refusal.value)))
    return found


def library_reason(message: str) -> str:
    """The reason of a library's refusal without whom it names: "m: must be > 0, got -1.0" and "scene.toml: [delay]
    gain: a negative gain ..." both give what follows their last name."""
    if message.split(": ", 1)[0].endswith(".toml"):
        message = message.split(": ", 1)[1]
    return message.split(": ", 1)[1]


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    from prandtl_fmu.fmu.build import build_fmu

    folder = tmp_path_factory.mktemp("native_refusals")
    built = {}
    for kind, fmi in BUILDS:
        path = folder / f"{kind}.toml"
        path.write_text(scene_text(dict(SCENES[kind], name=kind)))
        # the C layer's checks do not depend on the steppers the FMU holds: the scene's alone (build --steppers;
        # the connector has none, its motion is given)
        steppers = None if kind == "connector" else [SOLVER["stepper"]]
        built[kind, fmi] = (build_fmu(path, folder / f"{kind}-{fmi}.fmu", runtime="native", fmi=fmi,
                                      steppers=steppers), path)
    return built


def test_the_table_covers_every_parameter_the_fmus_check():
    """Every parameter of both FMUs with a rule of the library is in the table (the step and the stepper are the
    FMU's own settings, their words the slave's: tests/fmu/native/test_against_library.py), and every row is refused by the library."""
    for kind, tables in SCENES.items():
        path_scene = rules.parse_scene(scene_text(dict(tables, name=kind)), f"{kind}.toml")
        named = {name for _, _, name, _ in table(path_scene)}
        parameters = {row.name for row in variables(path_scene) if row.causality == "parameter"}
        assert parameters - named == {"step", "stepper", "scene_load"} & parameters, (kind, parameters - named)


def _message(instance, name, reason):
    """The FMU's message that names the parameter and gives the library's reason, or None."""
    for _, message in instance.messages:
        if f"parameter {name}" in message and reason in message:
            return message
    return None


@pytest.mark.parametrize("kind, fmi", BUILDS)
def test_the_native_fmu_refuses_what_the_library_refuses_with_its_reasons(fmus, kind, fmi):
    path, scene_path = fmus[kind, fmi]
    scene = load_scene(scene_path, check_stepper=False)
    fixed = {row.name for row in variables(scene) if row.variability == "fixed"}
    disagreements = []
    for label, values, name, reason in table(scene):
        at_start = NativeInstance(str(path), name="refused", start=values)
        said = _message(at_start, name, reason)
        if at_start.refused != ERROR or said is None or "initialization refused: " not in said:
            disagreements.append((label, "initialization", reason, at_start.refused, at_start.messages[-2:]))
        at_start.fmu.freeInstance()
        if fixed & set(values):  # fixed: refused as such after initialization (tests/memory/test_native.py)
            continue
        stepping = NativeInstance(str(path), name="stepping")
        assert stepping.refused is None, stepping.messages
        for key, value in values.items():
            stepping.set(key, value)
        status = stepping.do_step(0.01) if kind == "connector" else stepping.step(0.01, 0.1)
        said = _message(stepping, name, reason)
        if status != DISCARD or said is None:
            disagreements.append((label, "step", reason, status, stepping.messages[-2:]))
        stepping.close()
    assert disagreements == [], "\n".join(map(repr, disagreements))


@pytest.mark.parametrize("kind", ["element", "connector"])
def test_a_refused_value_set_right_again_is_taken(fmus, kind):
    """The instance a step refused is usable once the value is set right (the scene's), as the library's is."""
    path, scene_path = fmus[kind, 2]
    scene = load_scene(scene_path, check_stepper=False)
    name = "k0"
    good = rules.coefficients_of(scene)[name]
    instance = NativeInstance(str(path))
    instance.set(name, -1.0)
    first = instance.do_step(0.01) if kind == "connector" else instance.step(0.01, 0.1)
    instance.set(name, good)
    second = instance.do_step(0.01) if kind == "connector" else instance.step(0.01, 0.1)
    assert (first, second) == (DISCARD, OK), instance.messages[-2:]
    instance.close()
