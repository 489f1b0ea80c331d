"""The FMU's binary in a native host (tests/c_host/fmi2_host.c), as OMSimulator's or ecos' binary runs it
(issue 23, items 1, 2 and 5): never a NULL log category, refusals logged with logging off, FMI 2.0's call
order enforced, and the library's numbers."""
import numpy as np
import pytest

from prandtl_fmu import parse_scene
from prandtl_fmu.element import Element

from tests.conftest import base_tables, scene_text
from tests.native_host import Extracted, compile_host, run_host

OK, DISCARD, ERROR = 0, 2, 3
DECLARED = {"logStatusWarning", "logStatusDiscard", "logStatusError", "logStatusFatal", "logAll"}
TABLES = base_tables(solver={"stepper": "implicit", "step": 1e-3, "stop_time": 1.0, "output_interval": 0.1})
# friction on the mass (Stribeck) and series dashpots (issue 25)
FRICTION_TABLES = base_tables(
    cubic=None, friction={"alpha": 0.3, "alpha_kinetic": 0.2, "stribeck_velocity": 0.1},
    branches={"k": [0.5, 0.3, 0.2], "eta": [0.1, 0.3, 0.6], "c": [0.4, 2.0, 9.0]},
    solver={"stepper": "implicit", "step": 1e-3, "stop_time": 1.0, "output_interval": 0.1})


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    return compile_host(tmp_path_factory.mktemp("c_host"))


def _built(folder, tables):
    from prandtl_fmu.fmu.build import build_fmu

    scene = folder / "element.toml"
    scene.write_text(scene_text(tables))
    return Extracted(build_fmu(scene, folder / "element.fmu"), folder / "element")


@pytest.fixture(scope="module")
def element(tmp_path_factory):
    return _built(tmp_path_factory.mktemp("native_host"), TABLES)


@pytest.fixture(scope="module")
def friction_element(tmp_path_factory):
    return _built(tmp_path_factory.mktemp("native_host_friction"), FRICTION_TABLES)


def categories_declared(logs):
    return all(category in DECLARED for _, category, _ in logs)


@pytest.mark.parametrize("logging", [False, True])
def test_a_refused_start_value_is_logged_with_a_category_whatever_loggingOn_says(host, element, logging):
    """m = -1: fmi2ExitInitializationMode fails with fmi2Error, the reason reaches the logger with logging off
    too, under a declared category (a NULL one aborted OMSimulator: this host aborts likewise), and the instance
    stays usable: m set right, initialization succeeds and a step is taken."""
    code, calls, logs, values, out = run_host(host, element, [
        "setup", "enter", "setr:m:-1", "exit", "setr:m:2", "exit", "step:0:0.1", "getr:x", "term", "free"],
        logging=logging)
    assert code == 0, out
    assert calls["exit"] == [str(ERROR), str(OK)], out
    assert calls["step:0:0.1"] == [str(OK)] and calls["term"] == [str(OK)], out
    refusals = [entry for entry in logs if entry[0] == ERROR]
    assert refusals and "parameter m" in refusals[0][2] and refusals[0][1] == "logStatusError", logs
    assert categories_declared(logs), logs
    assert len(values) == 1 and np.isfinite(values[0][1])


def test_a_refused_input_is_logged_as_a_discard_with_logging_off(host, element):
    code, calls, logs, _, out = run_host(host, element, [
        "setup", "enter", "exit", "setr:F:inf", "step:0:0.1", "setr:F:1", "step:0:0.1", "free"])
    assert code == 0, out
    assert calls["step:0:0.1"] == [str(DISCARD), str(OK)], out
    assert [entry for entry in logs if entry[0] == DISCARD and "F = inf" in entry[2]], logs
    assert categories_declared(logs), logs


def test_a_failed_instantiation_is_logged_with_a_category(host, element, tmp_path):
    """The slave cannot be made (a numba that cannot be imported, as in a host Python without it): fmi2Instantiate
    returns NULL, the reason is logged with logging off, and the host lives on."""
    import shutil

    broken = tmp_path / "broken"
    shutil.copytree(element.library.parent.parent.parent, broken)
    (broken / "resources" / "numba.py").write_text("raise ImportError('no numba in this host')\n")
    fmu = Extracted.__new__(Extracted)
    fmu.__dict__.update(element.__dict__, library=broken / element.library.relative_to(
        element.library.parent.parent.parent), resources=(broken / "resources").as_uri())
    code, calls, logs, _, out = run_host(host, fmu, ["setup"])
    assert code == 0, out  # no abort
    assert calls["instantiate"] == ["null"], out
    assert logs and "numba" in " ".join(message for _, _, message in logs), out
    assert categories_declared(logs), logs


def test_the_fmi2_call_sequence_is_enforced(host, element):
    """doStep before and during initialization, doStep, setReal and terminate after fmi2Terminate are refused
    (fmi2Error, logged with logging off); getReal after fmi2Terminate is allowed (FMI 2.0, as the Reference-FMUs:
    the master reads the final values then); fmi2Reset starts the sequence again."""
    code, calls, logs, values, out = run_host(host, element, [
        "step:0:0.1", "setup", "enter", "step:0:0.1", "exit", "step:0:0.1", "term", "term", "step:0:0.1",
        "setr:F:1", "getr:x", "reset", "setup", "enter", "exit", "step:0:0.1", "free"])
    assert code == 0, out
    assert calls["step:0:0.1"] == [str(ERROR), str(ERROR), str(OK), str(ERROR), str(OK)], out
    assert calls["term"] == [str(OK), str(ERROR)], out
    assert calls["setr:F:1"] == [str(ERROR)] and calls["getr:x"] == [str(OK)], out
    assert calls["reset"] == [str(OK)] and calls["exit"] == [str(OK), str(OK)], out
    refused = [message for status, _, message in logs if status == ERROR]
    assert len(refused) == 5 and all("FMI 2.0 co-simulation call sequence" in text for text in refused), logs
    assert "fmi2DoStep refused: not allowed before fmi2EnterInitializationMode" in refused[0]
    assert categories_declared(logs), logs
    assert len(values) == 1


@pytest.mark.parametrize("which", ["element", "friction_element"])
def test_the_binary_in_a_native_host_gives_the_library_numbers(host, which, request):
    """Steps of random sizes under random forces, read after each: bit for bit Element.advance (also with
    friction on the mass, which sticks and slips here, and series dashpots)."""
    element = request.getfixturevalue(which)
    rng = np.random.default_rng(5)
    sizes = [float(size) for size in rng.choice([0.013, 0.05, 0.1, 0.0371], 12)]
    forces = [float(force) for force in rng.uniform(-1, 1, 12)]
    commands, t = ["setup", "enter", "setb:scene_load:0", "exit"], 0.0  # F alone, as the element is driven
    tables = FRICTION_TABLES if which == "friction_element" else TABLES
    reference = Element(parse_scene(scene_text(tables), "element.toml"))
    expected = []
    for size, force in zip(sizes, forces):
        commands += [f"setr:F:{force!r}", f"step:{t!r}:{size!r}", "getr:x", "getr:v", "getr:reaction"]
        reference.time = t
        reference.advance(size, force)
        expected += [reference.x, reference.v, reference.reaction]
        t += size
    code, calls, logs, values, out = run_host(host, element, commands + ["term", "free"])
    assert code == 0, out
    assert [value for _, value in values] == expected



@pytest.mark.parametrize("logging", [False, True])
def test_a_friction_parameter_out_of_its_rule_is_refused_and_logged(host, friction_element, logging):
    """alpha_kinetic > alpha: initialization fails with fmi2Error and the reason names both, logged with logging
    off too; set right, the instance initializes and steps."""
    code, calls, logs, values, out = run_host(host, friction_element, [
        "setup", "enter", "setr:alpha_kinetic:0.5", "exit", "setr:alpha_kinetic:0.25", "exit", "step:0:0.1",
        "getr:x", "term", "free"], logging=logging)
    assert code == 0, out
    assert calls["exit"] == [str(ERROR), str(OK)], out
    refusals = [entry for entry in logs if entry[0] == ERROR]
    assert refusals and "alpha_kinetic" in refusals[0][2] and "alpha" in refusals[0][2], logs
    assert categories_declared(logs), logs
    assert len(values) == 1 and np.isfinite(values[0][1])
