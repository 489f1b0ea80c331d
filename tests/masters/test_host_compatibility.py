"""Host compatibility of the native FMUs (issue 33): what OMSimulator, ecos, libcosim, fmusim and FMPy need.

FMI 3.0 offers scalars by default (the element's and the connector's branch elongations u_1 .. u_n), which every
master reads, one value per value reference; ``arrays`` adds the array u for masters that handle arrays. Both
descriptions validate (FMPy, the FMU Manipulation Toolbox), share the FMI 2.0 variables' names, value references
and dependencies, and the scalars read after random steps, in FMPy and in the sanitized C host, are the library's
elongations to the bit. ``--arrays`` where it means nothing is refused in one line.

Building the six FMUs takes a minute: the module is under ``slow`` but for the refusals, which build nothing
(tests/fmu/native/test_against_library.py has the quick checks of the scalar default)."""
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest

from prandtl_fmu import load_scene
from prandtl_fmu.connector import Connector
from prandtl_fmu.element import Element

from tests.conftest import base_tables, scene_text
from tests.paths import ROOT

pytest.importorskip("fmpy")
if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)

SOLVER = {"stepper": "implicit", "step": 0.01, "stop_time": 10.0, "output_interval": 0.1}
SCENES = {
    # friction on the mass, series dashpots: three branches
    "element": base_tables(cubic=None, solver=SOLVER,
                           friction={"alpha": 0.3, "alpha_kinetic": 0.2, "stribeck_velocity": 0.1},
                           branches={"k": [0.5, 0.3, 0.2], "eta": [0.1, 0.3, 0.6], "c": [0.4, 2.0, 9.0]}),
    # the connector: spring, dashpot, four branches
    "connector": base_tables(mass=None, cubic=None, solver=SOLVER, fmu={"causality": "displacement"},
                             branches={"k": [1.0, 0.6, 2.0, 0.4], "eta": [0.1, 0.3, 0.05, 0.2]}),
}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """{(scene, kind): FMU path}, kind "2" (FMI 2.0), "3" (FMI 3.0, scalars) or "3a" (FMI 3.0 with arrays)."""
    from prandtl_fmu.fmu.build import build_fmu

    folder = tmp_path_factory.mktemp("hosts")
    fmus = {}
    for name, tables in SCENES.items():
        path = folder / f"{name}.toml"
        path.write_text(scene_text(tables))
        fmus[name, "scene"] = path
        for kind, fmi, arrays in (("2", 2, False), ("3", 3, False), ("3a", 3, True)):
            fmus[name, kind] = build_fmu(path, folder / f"{name}-{kind}.fmu", runtime="native", fmi=fmi,
                                         arrays=arrays)
    return fmus


def _root(fmu):
    with zipfile.ZipFile(fmu) as archive:
        return ET.fromstring(archive.read("modelDescription.xml"))


def _variables(root) -> dict:
    """name -> (element, type): FMI 2.0's ScalarVariable (type: its child's tag) or FMI 3.0's typed element."""
    if root.get("fmiVersion") == "2.0":
        return {v.get("name"): (v, v[0].tag) for v in root.iter("ScalarVariable")}
    return {v.get("name"): (v, v.tag) for v in root.find("ModelVariables")}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SCENES))
def test_fmi3_offers_the_elongations_as_scalars_and_the_array_only_as_an_option(built, name):
    """By default no FMI 3.0 variable is an array (OMSimulator and ecos read one as a scalar): u_1 .. u_n are
    Float64 outputs with no direct dependency, n the FMI 2.0 local Int32 constant; every FMI 2.0 variable is there
    with its type and its dependencies, in its order after time, under its FMI 3.0 value reference: its 1-based
    position in ModelVariables (issue 44.1). With arrays: the array u sized by n, which is then a structural
    parameter (UInt64, start n >= 1), besides the same scalars."""
    n = load_scene(built[name, "scene"]).branches.n
    two = _variables(_root(built[name, "2"]))
    for kind in ("3", "3a"):
        root = _root(built[name, kind])
        three = _variables(root)
        assert not [v for v, _ in three.values() if v.find("Dimension") is not None] if kind == "3" else \
            [v.get("name") for v, _ in three.values() if v.find("Dimension") is not None] == ["u"]
        types = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}
        position = {name: str(at) for at, name in enumerate(three, start=1)}
        assert [v.get("valueReference") for v, _ in three.values()] == list(position.values())
        assert list(three)[1:len(two) + 1] == list(two)  # time, then the FMI 2.0 variables in their order
        for variable, (element, tag) in two.items():
            if variable == "n" and kind == "3a":
                assert three["n"][1] == "UInt64" and three["n"][0].get("valueReference") == position["n"]
                assert three["n"][0].get("causality") == "structuralParameter" and three["n"][0].get("start") == str(n)
                continue
            assert three[variable][1] == types[tag], variable
            assert three[variable][0].get("valueReference") == position[variable], variable
            assert three[variable][0].get("causality") == element.get("causality"), variable
        if kind == "3":
            assert three["n"][1] == "Int32" and three["n"][0].get("causality") == "local"
            assert three["n"][0].get("start") == str(n)
        scalars = [f"u_{i}" for i in range(1, n + 1)]
        assert [name for name in three if name.startswith("u_")] == scalars
        for scalar in scalars:
            assert three[scalar][1] == "Float64" and three[scalar][0].get("causality") == "output"
        # every output has its dependencies, the FMI 2.0 ones translated to value references
        by_vr = {v.get("valueReference"): name for name, (v, _) in three.items()}
        outputs = [name for name, (v, _) in three.items() if v.get("causality") == "output"]
        structure = root.find("ModelStructure")
        for tag in ("Output", "InitialUnknown"):
            listed = [by_vr[unknown.get("valueReference")] for unknown in structure.findall(tag)]
            assert listed == outputs, tag
        dependencies = {by_vr[u.get("valueReference")]: sorted(by_vr[d] for d in u.get("dependencies").split())
                        for u in structure.findall("Output")}
        two_root = _root(built[name, "2"])
        index = {str(i): v.get("name") for i, v in enumerate(two_root.iter("ScalarVariable"), start=1)}
        for unknown in two_root.find("ModelStructure/Outputs"):
            assert dependencies[index[unknown.get("index")]] == sorted(
                index[i] for i in unknown.get("dependencies", "").split())
        assert all(dependencies[scalar] == [] for scalar in scalars)
        categories = [c.get("description", "") for c in root.find("LogCategories")]
        assert not any("fmi2" in text for text in categories)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SCENES))
def test_fmpy_s_validator_finds_nothing(built, name):
    from fmpy.validation import validate_fmu

    for kind in ("2", "3", "3a"):
        assert validate_fmu(str(built[name, kind])) == [], kind


@pytest.mark.slow
def test_the_toolbox_checker_finds_nothing_in_the_scalar_and_array_descriptions(built):
    """fmutool -check (the FMI schemas and the semantic rules: causality, variability, initial, start, model
    structure) on the FMI 3.0 element and connector, scalars and arrays."""
    pytest.importorskip("fmu_manipulation_toolbox", reason="pip install 'prandtl_fmu[test]'")
    for name in SCENES:
        for kind in ("3", "3a"):
            done = subprocess.run([sys.executable, "-m", "fmu_manipulation_toolbox", "-input",
                                   str(built[name, kind]), "-check"], capture_output=True, text=True, timeout=300)
            report = done.stdout + done.stderr
            assert done.returncode == 0, report
            assert "This FMU seems to be compliant with FMI-3.0." in report, (name, kind, report)
            assert "No semantic error against the FMI-3 standard." in report, (name, kind, report)
            assert not [line for line in report.splitlines() if "ERROR" in line or "WARNING" in line], report


class Slave3:
    """An FMI 3.0 native FMU in FMPy's FMU3Slave, initialized; value references by name."""

    def __init__(self, fmu, start=None):
        from fmpy import extract, read_model_description
        from fmpy.fmi3 import FMU3Slave

        description = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in description.modelVariables}
        self.messages = []
        self.slave = FMU3Slave(guid=description.instantiationToken, unzipDirectory=extract(str(fmu)),
                               modelIdentifier=description.coSimulation.modelIdentifier)
        self.slave.instantiate(loggingOn=False, logMessage=lambda env, status, category, message:
                               self.messages.append(message.decode()))
        self.slave.enterInitializationMode()
        if "scene_load" in self.vr:  # F alone, as the library's element is driven (it starts true with a load)
            self.slave.setBoolean([self.vr["scene_load"]], [False])
        for variable, value in (start or {}).items():
            self.slave.setFloat64([self.vr[variable]], [value])
        self.slave.exitInitializationMode()

    def get(self, *names):
        """One fmi3GetFloat64 call, one value per value reference (as OMSimulator and ecos call it)."""
        return self.slave.getFloat64([self.vr[name] for name in names], nValues=len(names))

    def close(self):
        self.slave.terminate()
        self.slave.freeInstance()


@pytest.mark.slow
def test_the_element_s_scalars_are_the_library_s_elongations_after_every_step(built):
    """Random forces and step sizes; after each step one call reads x, v, reaction and every u_i, one value per
    reference (the call OMSimulator and ecos make): the library's Element to the bit. The arrays' FMU gives the
    same u as its array and its scalars; a read of the array as a scalar (one value) is refused with the reason."""
    from fmpy.fmi1 import FMICallException

    scene = load_scene(built["element", "scene"])
    n = scene.branches.n
    names = ["x", "v", "reaction"] + [f"u_{i}" for i in range(1, n + 1)]
    scalars, arrays = Slave3(built["element", "3"]), Slave3(built["element", "3a"])
    element = Element(scene)
    rng = np.random.default_rng(33)
    t = 0.0
    try:
        for _ in range(40):
            size, force = float(rng.choice([0.013, 0.05, 0.1])), float(rng.uniform(-1.2, 1.2))
            for slave in (scalars, arrays):
                slave.slave.setFloat64([slave.vr["F"]], [force])
                slave.slave.doStep(t, size)
            element.time = t
            element.advance(size, force)
            t += size
            expected = [element.x, element.v, element.reaction] + element.elongations().tolist()
            assert scalars.get(*names) == expected
            assert scalars.get(*reversed(names)) == expected[::-1]  # any order, each computed from the state
            assert arrays.get(*names) == expected
            assert arrays.slave.getFloat64([arrays.vr["u"]], nValues=n) == expected[3:]
        assert np.ptp(element.elongations()) > 0  # the branches moved apart: a test that can fail
        assert "u" not in scalars.vr
        with pytest.raises(FMICallException):
            arrays.slave.getFloat64([arrays.vr["u"]], nValues=1)
        assert any("u alone has 3" in message for message in arrays.messages), arrays.messages
        with pytest.raises(FMICallException):  # an output is not set
            scalars.slave.setFloat64([scalars.vr["u_1"]], [0.0])
    finally:
        scalars.close()
        arrays.close()


@pytest.mark.slow
def test_the_connector_s_scalars_are_the_library_s_elongations(built):
    """The connector driven by random motions: force and every u_i as the library's Connector after each doStep
    (the committed motion; the elongations move at doStep only)."""
    scene = load_scene(built["connector", "scene"])
    n = scene.branches.n
    slave = Slave3(built["connector", "3"])
    connector = Connector(scene)
    rng = np.random.default_rng(5)
    t = 0.0
    try:
        for _ in range(40):
            x, v, size = float(rng.uniform(-0.5, 0.5)), float(rng.uniform(-1, 1)), float(rng.choice([0.01, 0.05]))
            slave.slave.setFloat64([slave.vr["x"], slave.vr["v"]], [x, v])
            slave.slave.doStep(t, size)
            connector.move_to(x, v, t)  # as the PythonFMU connector commits a sample: at the step's start
            t += size
            got = slave.get(*[f"u_{i}" for i in range(1, n + 1)])
            assert got == connector.elongations().tolist()
        assert np.ptp(connector.elongations()) > 0
    finally:
        slave.close()


@pytest.mark.slow
def test_the_scalars_in_the_sanitized_c_host(tmp_path_factory):
    """The FMI 3.0 element built with AddressSanitizer and UBSan in the C host (no Python): every u_i read after
    steps is the library's; a reference past u_n is refused; no leak (the elongations of a call are freed)."""
    from tests.native_host import built_native, compile_trust_host, run_trust

    folder = tmp_path_factory.mktemp("hosts_c")
    host = compile_trust_host(folder, 3)
    fmu = built_native("hosts_element", SCENES["element"], 3, folder / "fmu")
    scene = parse_scene_of("element")
    n = scene.branches.n
    element = Element(scene)
    commands, expected, t = ["setup:0", "enter", "setb:scene_load:0", "exit"], [], 0.0  # F alone, as the element
    for force, size in ((0.9, 0.1), (-1.1, 0.05), (0.4, 0.13), (1.3, 0.1)):
        commands += [f"setr:F:{force!r}", f"step:{t!r}:{size!r}"] + [f"getr:u_{i}" for i in range(1, n + 1)]
        element.time = t
        element.advance(size, force)
        t += size
        expected += element.elongations().tolist()
    past = fmu.vr[f"u_{n}"] + 1
    assert past not in fmu.vr.values()
    run = run_trust(host, fmu, commands + [f"getr:{past}", "term", "free"])
    assert run.code == 0 and run.ended, run.out[-3000:]
    assert [value for _, value in run.values] == expected
    assert run.status(f"getr:{past}") != 0 and run.said("no Float64 variable"), run.logs


def parse_scene_of(name):
    from prandtl_fmu import parse_scene

    return parse_scene(scene_text(SCENES[name]), f"{name}.toml")


def test_build_fmu_refuses_arrays_where_they_mean_nothing_before_building(tmp_path):
    from prandtl_fmu.fmu.build import build_fmu

    path = tmp_path / "s.toml"
    path.write_text(scene_text(SCENES["element"]))
    bare = tmp_path / "bare.toml"
    bare.write_text(scene_text(base_tables(branches=None, solver=SOLVER)))
    for scene, settings, words in ((path, {"runtime": "native", "fmi": 2}, "FMI 3.0 option of the native runtime"),
                                   (path, {}, "FMI 3.0 option of the native runtime"),
                                   (bare, {"runtime": "native", "fmi": 3}, "no branch elongations")):
        with pytest.raises(ValueError, match=words):
            build_fmu(scene, tmp_path / "x.fmu", arrays=True, **settings)
        assert not (tmp_path / "x.fmu").exists()


@pytest.mark.slow
def test_arrays_where_they_mean_nothing_are_refused_in_one_line(tmp_path):
    """--arrays with FMI 2.0, with the PythonFMU runtime, or on a scene without branch elongations: one line on
    stderr, exit 2, nothing written."""
    path = tmp_path / "s.toml"
    path.write_text(scene_text(SCENES["element"]))
    bare = tmp_path / "bare.toml"
    bare.write_text(scene_text(base_tables(branches=None, solver=SOLVER)))
    for scene, extra in ((path, ["--runtime", "native", "--fmi", "2"]), (path, []), (bare, ["--runtime", "native",
                                                                                           "--fmi", "3"])):
        out = tmp_path / "x.fmu"
        done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "build", str(scene), "-o", str(out), "--arrays",
                               *extra], capture_output=True, text=True, timeout=300)
        assert done.returncode == 2, (extra, done.stderr)
        assert len(done.stderr.strip().splitlines()) == 1 and "arrays" in done.stderr, done.stderr
        assert "Traceback" not in done.stderr and not out.exists()


@pytest.mark.slow
def test_ecos_own_binary_reads_every_scalar_of_the_fmi3_fmu(built, tmp_path):
    """ecos' command-line binary (fmi4c, C++: no Python) ran the FMI 3.0 native FMU with its array u and got
    nothing or garbage; with the scalars (the default) its CSV has x, v, reaction and u_1 .. u_n of the library's
    run of the scene (scene_load, implicit; 6 decimals)."""
    try:
        import ecospy
    except (ImportError, OSError) as exc:
        pytest.skip(f"ecospy cannot load ({exc}): pip install 'prandtl_fmu[ecos]' and apt install libtbb12")
    from prandtl_fmu import simulate

    from tests.masters.test_masters import ALONE

    shipped = Path(ecospy.__file__).parent / "binaries" / "ecos"
    if not shipped.exists():
        pytest.skip(f"ecospy {ecospy.__file__} ships no ecos binary for this platform")
    binary = tmp_path / "ecos"  # the wheel loses the run bit of its binaries
    shutil.copyfile(shipped, binary)
    binary.chmod(0o755)
    system = tmp_path / "system"
    system.mkdir()
    shutil.copyfile(built["element", "3"], system / "element.fmu")
    (system / "SystemStructure.ssd").write_text(ALONE.format(stepper="implicit"))
    step, stop = 0.05, 8.0
    done = subprocess.run([str(binary), "simulate", "--path", str(system), "--stepSize", str(step), "--stopTime",
                           str(stop), "--parameterSet", "initialValues"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120, env={"PATH": "/usr/bin:/bin"})
    assert done.returncode == 0, done.stdout + done.stderr
    lines = (tmp_path / "system.csv").read_text().splitlines()
    header = [name.strip() for name in lines[0].split(",")]
    rows = [line.split(",") for line in lines[1:]]
    assert all(len(row) == len(rows[0]) for row in rows)
    column = {name: np.array([float(row[j]) for row in rows]) for j, name in enumerate(header)
              if name.endswith("[REAL]") or name == "time"}
    scene = load_scene(built["element", "scene"])
    library = simulate(scene.with_solver(stop_time=stop, output_interval=step), stepper="implicit", states=True)
    count = len(rows)  # ecos writes the rows from t = 0 to stop, or to stop - step (its clock's rounding)
    assert count in (len(library.time), len(library.time) - 1)
    np.testing.assert_allclose(column["time"], library.time[:count], rtol=0, atol=1e-9)
    for name in ("x", "v", "reaction"):
        np.testing.assert_allclose(column[f"element::{name}[REAL]"], getattr(library, name)[:count], rtol=0,
                                   atol=6e-7)
    for i in range(scene.branches.n):
        np.testing.assert_allclose(column[f"element::u_{i + 1}[REAL]"], library.u[:count, i], rtol=0, atol=6e-7)
    assert np.ptp(library.u[:, 0]) > 0.05


@pytest.mark.slow
def test_the_native_package_is_the_native_fmu_s_own(built):
    """Every entry readable by all (0644, the binary 0755); the page describes the native FMU and lists every
    variable of its own description (u_i in FMI 3.0), nothing of PythonFMU's needs; no PythonFMU licence (its
    loader is not in the native binary)."""
    for name in SCENES:
        for kind in ("2", "3", "3a"):
            with zipfile.ZipFile(built[name, kind]) as archive:
                modes = {info.filename: info.external_attr >> 16 & 0o777 for info in archive.infolist()}
                page = archive.read("documentation/index.html").decode("utf-8")
                root = ET.fromstring(archive.read("modelDescription.xml"))
            assert not [entry for entry in modes if entry.startswith("documentation/licenses/")], modes
            assert all(mode == (0o755 if entry.startswith("binaries/") else 0o644) for entry, mode in modes.items()), \
                modes
            assert "<b>native</b>" in page and "PYTHONHOME" not in page and "pythonfmu" not in page.lower()
            assert all(f"<td>{name}</td>" in page for name in _variables(root)), kind
            version = "fmi3" if kind != "2" else "fmi2"
            assert f"{version}Discard" in page and ("fmi2" not in page if version == "fmi3" else True)


@pytest.mark.slow
def test_the_cli_s_arrays_reach_the_network_fmu(tmp_path):
    """``--runtime native --fmi 3 --arrays`` on a network scene: the nodes' x and v as arrays sized by the
    structural parameter n_nodes, besides the scalars x_<node>, v_<node>, equal after steps; FMPy's validator
    finds nothing."""
    from fmpy.validation import validate_fmu

    scene = ROOT / "prandtl_fmu" / "scenes" / "networks" / "two-masses-slider.toml"
    out = tmp_path / "two.fmu"
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "build", str(scene), "-o", str(out), "--runtime",
                           "native", "--fmi", "3", "--arrays"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert validate_fmu(str(out)) == []
    variables = _variables(_root(out))
    assert variables["n_nodes"][1] == "UInt64" and variables["n_nodes"][0].get("start") == "2"
    assert [name for name, (v, _) in variables.items() if v.find("Dimension") is not None] == ["x", "v"]
    slave = Slave3(out)
    try:
        for j in range(20):
            slave.slave.setFloat64([slave.vr["F"]], [3.0 * np.sin(0.7 * j)])
            slave.slave.doStep(0.05 * j, 0.05)
            for quantity in ("x", "v"):
                assert slave.slave.getFloat64([slave.vr[quantity]], nValues=2) == slave.get(f"{quantity}_a",
                                                                                            f"{quantity}_b")
        assert slave.get("x_a") != slave.get("x_b")
    finally:
        slave.close()
