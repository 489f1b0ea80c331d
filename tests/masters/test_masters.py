"""The FMU in real co-simulation masters: libcosim (libcosimpy), ecos, OMSimulator, against FMPy."""
import importlib.util
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

from tests.conftest import ROOT
from tests.fmu_tools import held_input

# the masters (libcosim, ecos, fmusim, OMSimulator) running the FMUs: run by .ci/run after the quick suite
pytestmark = pytest.mark.slow

spec = importlib.util.spec_from_file_location("run_cosim", ROOT / "examples" / "cosim" / "run_cosim.py")
run_cosim = importlib.util.module_from_spec(spec)
spec.loader.exec_module(run_cosim)


def test_libcosim_run_of_the_shipped_example_agrees_with_fmpy(tmp_path):
    structure = run_cosim.build(tmp_path)
    stop = 10.0
    cosim = {name: np.array(values) for name, values in run_cosim.run(structure, stop).items()}
    dt = 0.01
    assert len(cosim["time"]) == 1000 and cosim["time"][-1] == stop
    # libcosim hands the element, for the step from t_k, the source's output at t_k.
    np.testing.assert_allclose(cosim["F"], 0.45 * np.cos(0.5 * cosim["time"]), rtol=0, atol=1e-15)
    times = np.round(np.arange(0, stop + dt / 2, dt), 12)
    forces = np.concatenate([[0.45], cosim["F"]])  # F(0) = 0.45: the source's initial output
    result = simulate_fmu(str(tmp_path / "PrandtlElement.fmu"), stop_time=stop, output_interval=dt,
                          input=held_input(times, forces), start_values={"stepper": "implicit", "scene_load": False},
                          output=["x", "v", "reaction"])
    for name in ("x", "v", "reaction"):
        np.testing.assert_allclose(cosim[name], result[name][1:], rtol=0, atol=1e-12)
    assert np.abs(cosim["x"]).max() > 0.5  # the branches yielded: x reaches the plastic range


def test_libcosim_runs_the_native_element_as_the_pythonfmu_one_bit_for_bit(tmp_path):
    """The native FMU (no Python in its binary, no recipe) in libcosim: the same run, to the bit."""
    if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler: a native FMU cannot be built here")
    stop = 10.0
    runs = {runtime: run_cosim.run(run_cosim.build(tmp_path / runtime, runtime=runtime), stop)
            for runtime in ("python", "native")}
    for name in ("x", "v", "reaction"):
        assert runs["native"][name] == runs["python"][name]
    assert np.abs(np.array(runs["native"]["x"])).max() > 0.5


def test_the_example_force_source_gives_f0_of_the_amplitude_set_during_initialization(tmp_path):
    """A master that reads F during initialization (OMSimulator, ecos: to start a massless element from the
    equilibrium with F(0)) must get F(0) of the amplitude it set, not of the default."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    from pythonfmu import FmuBuilder

    from prandtl_fmu.fmu.python.loader import install as install_loader

    FmuBuilder.build_FMU(ROOT / "examples" / "cosim" / "prandtl_example_harmonic_force.py",
                         dest=tmp_path / "HarmonicForce.fmu")
    install_loader(tmp_path / "HarmonicForce.fmu")
    fmu = str(tmp_path / "HarmonicForce.fmu")
    md = read_model_description(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="source")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr["amplitude"], vr["offset"]], [2.0, 0.25])
    assert slave.getReal([vr["F"]]) == [2.25]  # read before leaving initialization
    slave.exitInitializationMode()
    slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=1.0)
    assert slave.getReal([vr["F"]])[0] == 0.25 + 2.0 * np.cos(0.5)
    slave.terminate()
    slave.freeInstance()


spec = importlib.util.spec_from_file_location("run_connector",
                                              ROOT / "examples" / "cosim" / "connector" / "run_connector.py")
run_connector = importlib.util.module_from_spec(spec)
spec.loader.exec_module(run_connector)


def test_a_mass_on_the_ground_through_the_connector_converges_in_libcosim_to_the_library(tmp_path):
    """Connected by their OSP mechanical ports (VariableGroupConnection): first order in the communication step
    towards the element with its mass solved exactly; ECCO's adaptive run converges with its tolerance."""
    folder = run_connector.build(tmp_path)
    rows = run_connector.convergence(folder, stop_time=12.0, steps=(0.04, 0.02, 0.01), ecco_tolerances=(1e-4, 1e-6))
    fixed = [row for row in rows if row[0] == "fixedStep"]
    errors = [row[3] for row in fixed]
    orders = [row[4] for row in fixed[1:]]
    assert all(0.8 < order < 1.5 for order in orders), rows
    assert errors[-1] < 0.3 * errors[0]  # H / 4: the error falls about fourfold
    ecco = [row for row in rows if row[0] == "ecco"]
    assert ecco[1][3] < ecco[0][3] and ecco[1][2] > ecco[0][2], rows  # tighter: more steps, smaller error


def test_every_ssd_component_says_it_is_an_fmu():
    """SSP 1.0 lets a component's ``type`` default to an FMU, but OMSimulator 3's Python ``SSP()`` loads only
    components that say ``type="application/x-fmu-sharedlibrary"`` (without it: KeyError CRef['mass'])."""
    import xml.etree.ElementTree as ET

    ns = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription"}
    root = ET.parse(run_connector.HERE / "SystemStructure.ssd").getroot()
    components = root.findall(".//ssd:Component", ns)
    assert len(components) == 2
    for component in components:
        assert component.get("type") == "application/x-fmu-sharedlibrary", component.get("name")


def test_the_ssp_system_description_runs_the_same_system_as_the_osp_structure(tmp_path):
    """SystemStructure.ssd (written for SSP masters such as OMSimulator) read by libcosim's SSP loader gives the
    very run of the OspSystemStructure."""
    folder = run_connector.build(tmp_path)
    osp = run_connector.run(run_connector.write_structure(folder, 0.02), 6.0)
    ssp = run_connector.run(folder, 6.0, ssp_step=0.02)
    assert len(osp["time"]) == len(ssp["time"]) == 300
    for column in ("x", "v", "force"):
        np.testing.assert_array_equal(osp[column], ssp[column])
    assert np.abs(osp["force"]).max() > 0.1


def test_ecos_runs_the_connector_system_as_libcosim(tmp_path):
    """The same SystemStructure.ssd in ecos (ecospy 0.7.2, in-process): its fixed-step master gives libcosim's
    run to rounding, so the same first-order convergence to the library. The connector's force (a direct
    feedthrough of x, v) shows in ecos after the step's new inputs reached it; libcosim's observer shows it one
    step later (the lag the README's master table names)."""
    try:
        import ecospy  # noqa: F401  (loads Debian's libtbb12)
    except (ImportError, OSError) as exc:
        pytest.skip(f"ecospy cannot load ({exc}): pip install 'prandtl_fmu[ecos]' and apt install libtbb12")
    folder = run_connector.build(tmp_path)
    libcosim = run_connector.run(run_connector.write_structure(folder, 0.02), 6.0)
    ecos = run_connector.run_ecos(folder, 0.02, 6.0)
    assert len(ecos["time"]) == len(libcosim["time"]) == 300
    np.testing.assert_allclose(ecos["time"], libcosim["time"], rtol=0, atol=1e-12)
    for column in ("x", "v"):
        np.testing.assert_allclose(ecos[column], libcosim[column], rtol=0, atol=1e-11)
    np.testing.assert_allclose(ecos["force"][:-1], libcosim["force"][1:], rtol=0, atol=1e-11)
    assert np.abs(ecos["force"]).max() > 0.1


def test_libcosim_and_ecos_run_the_native_connector_as_the_pythonfmu_one(tmp_path):
    """The connector system with the bushing built --runtime native (no Python in its binary, no recipe):
    libcosim's and ecos' runs are those of the PythonFMU bushing, to the bit."""
    if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler: a native FMU cannot be built here")
    from prandtl_fmu.fmu.build import build_fmu

    folders = {runtime: run_connector.build(tmp_path / runtime) for runtime in ("python", "native")}
    build_fmu(run_connector.HERE / "bushing.toml", folders["native"] / "bushing.fmu", runtime="native")
    masters = {"libcosim": lambda folder: run_connector.run(run_connector.write_structure(folder, 0.02), 6.0)}
    try:
        import ecospy  # noqa: F401  (loads Debian's libtbb12)
        masters["ecos"] = lambda folder: run_connector.run_ecos(folder, 0.02, 6.0)
    except (ImportError, OSError):
        pass  # libcosim alone (test_ecos_runs_the_connector_system_as_libcosim says why ecos is absent)
    for master, run in masters.items():
        python, native = run(folders["python"]), run(folders["native"])
        for column in ("x", "v", "force"):
            np.testing.assert_array_equal(np.asarray(native[column]), np.asarray(python[column]), err_msg=master)
        assert np.abs(np.asarray(native["force"])).max() > 0.1


ALONE = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription name="prandtl_native_alone" version="1.0"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
  <ssd:System name="alone">
    <ssd:Elements>
      <ssd:Component name="element" type="application/x-fmu-sharedlibrary" source="element.fmu">
        <ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>
          <ssv:ParameterSet version="1.0" name="initialValues"><ssv:Parameters>
            <ssv:Parameter name="scene_load"><ssv:Boolean value="true"/></ssv:Parameter>
            <ssv:Parameter name="stepper"><ssv:String value="{stepper}"/></ssv:Parameter>
          </ssv:Parameters></ssv:ParameterSet>
        </ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>
      </ssd:Component>
    </ssd:Elements>
  </ssd:System>
</ssd:SystemStructureDescription>
"""


@pytest.mark.parametrize("stepper", ["exact", "implicit"])
def test_ecos_own_binary_runs_the_native_fmu_with_no_python(tmp_path, stepper):
    """ecos' command-line binary (C++: no Python in the process, no LD_PRELOAD, no PYTHONPATH, no recipe) runs the
    native FMU of the paper's scene (100 branches on the memory stack; exact unfolds them) from an SSD that sets
    scene_load and the stepper: its CSV (6 decimals) is the library's run of the scene."""
    if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler: a native FMU cannot be built here")
    try:
        import ecospy
    except (ImportError, OSError) as exc:
        pytest.skip(f"ecospy cannot load ({exc}): pip install 'prandtl_fmu[ecos]' and apt install libtbb12")
    import subprocess

    from prandtl_fmu import load_scene, simulate
    from prandtl_fmu.fmu.build import build_fmu

    shipped = Path(ecospy.__file__).parent / "binaries" / "ecos"
    if not shipped.exists():
        pytest.skip(f"ecospy {ecospy.__file__} ships no ecos binary for this platform")
    binary = tmp_path / "ecos"  # the wheel loses the run bit of its binaries
    shutil.copyfile(shipped, binary)
    binary.chmod(0o755)
    system = tmp_path / "system"
    system.mkdir()
    build_fmu(ROOT / "scenes" / "paper-section-8.toml", system / "element.fmu", runtime="native")
    (system / "SystemStructure.ssd").write_text(ALONE.format(stepper=stepper))
    step, stop = 0.05, 20.0
    done = subprocess.run([str(binary), "simulate", "--path", str(system), "--stepSize", str(step), "--stopTime",
                           str(stop), "--parameterSet", "initialValues"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120, env={"PATH": "/usr/bin:/bin"})
    assert done.returncode == 0, done.stdout + done.stderr
    lines = (tmp_path / "system.csv").read_text().splitlines()
    header = [name.strip() for name in lines[0].split(",")]
    rows = [line.split(",") for line in lines[1:]]
    column = {name: np.array([float(row[j]) for row in rows]) for j, name in enumerate(header)
              if name.endswith("[REAL]") or name == "time"}
    scene = load_scene(ROOT / "scenes" / "paper-section-8.toml")
    library = simulate(scene.with_solver(stop_time=stop, output_interval=step), stepper=stepper)
    assert len(rows) == len(library.time) - 1  # ecos writes the rows from t = 0 to stop - step
    np.testing.assert_allclose(column["time"], library.time[:-1], rtol=0, atol=1e-9)
    for name in ("x", "v", "reaction"):  # %f: 6 decimals
        np.testing.assert_allclose(column[f"element::{name}[REAL]"], getattr(library, name)[:-1], rtol=0, atol=6e-7)
    assert np.abs(library.x).max() > 1.0


def fmusim_binary():
    """Reference-FMUs' fmusim, the C program (FMUSIM=path or fmusim on PATH; CI has none, README), or skip."""
    import subprocess

    binary = shutil.which(os.environ.get("FMUSIM", "fmusim"))
    if binary is None:
        pytest.skip("no fmusim binary (set FMUSIM=path; README: the C fmusim of Reference-FMUs)")
    usage = subprocess.run([binary, "--help"], capture_output=True, text=True, timeout=60).stdout
    if "--interface-type" not in usage or "--start-value" not in usage:
        pytest.skip(f"{binary} is not the C fmusim of Reference-FMUs (another command line)")
    if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler: a native FMU cannot be built here")
    return binary


@pytest.mark.parametrize("fmi", [2, 3])
def test_fmusim_runs_the_native_fmu_as_the_library(tmp_path, fmi):
    """fmusim, a host with no Python, runs the native FMU of the paper's scene (exact: the stack unfolded) with
    scene_load from its command line: its CSV (16 digits) is simulate's run."""
    import subprocess

    binary = fmusim_binary()
    from prandtl_fmu import load_scene, simulate
    from prandtl_fmu.fmu.build import build_fmu

    scene_path = ROOT / "scenes" / "paper-section-8.toml"
    fmu = build_fmu(scene_path, tmp_path / "element.fmu", runtime="native", fmi=fmi)
    out = tmp_path / "out.csv"
    done = subprocess.run([binary, "--interface-type", "cs", "--stop-time", "20", "--output-interval", "0.05",
                           "--start-value", "scene_load", "true", "--start-value", "stepper", "exact",
                           "--output-variable", "x", "--output-variable", "v", "--output-variable", "reaction",
                           "--output-file", str(out), str(fmu)], capture_output=True, text=True, timeout=300,
                          env={"PATH": "/usr/bin:/bin"})
    assert done.returncode == 0, done.stdout + done.stderr
    result = np.genfromtxt(out, delimiter=",", names=True)
    library = simulate(load_scene(scene_path).with_solver(stop_time=20.0, output_interval=0.05), stepper="exact")
    assert len(result) == len(library.time)
    for name in ("x", "v", "reaction"):  # %.16g
        np.testing.assert_allclose(result[name], getattr(library, name), rtol=1e-15, atol=1e-15)
    assert np.abs(library.x).max() > 1.0


@pytest.mark.parametrize("fmi", [2, 3])
def test_fmusim_runs_the_native_connector_as_fmpy(tmp_path, fmi):
    """The native bushing in fmusim, its motion x(t), v(t) from an input file on the output grid: the force of
    FMPy's run of the same FMU with the same input, to fmusim's 16 digits."""
    import subprocess

    from fmpy import simulate_fmu

    from prandtl_fmu.fmu.build import build_fmu

    binary = fmusim_binary()
    fmu = build_fmu(run_connector.HERE / "bushing.toml", tmp_path / "bushing.fmu", runtime="native", fmi=fmi)
    signal = np.zeros(101, dtype=[("time", float), ("x", float), ("v", float)])
    signal["time"] = np.round(np.arange(101) * 0.05, 10)
    signal["x"], signal["v"] = 0.3 * np.sin(1.3 * signal["time"]), 0.39 * np.cos(1.3 * signal["time"])
    rows = ['"time","x","v"'] + [",".join(repr(float(value)) for value in row) for row in signal]
    (tmp_path / "in.csv").write_text("\n".join(rows) + "\n")
    done = subprocess.run([binary, "--interface-type", "cs", "--stop-time", "5", "--output-interval", "0.05",
                           "--input-file", str(tmp_path / "in.csv"), "--output-variable", "force",
                           "--output-file", str(tmp_path / "out.csv"), str(fmu)], capture_output=True, text=True,
                          timeout=300, env={"PATH": "/usr/bin:/bin"})
    assert done.returncode == 0, done.stdout + done.stderr
    result = np.genfromtxt(tmp_path / "out.csv", delimiter=",", names=True)
    fmpy = simulate_fmu(str(fmu), stop_time=5.0, output_interval=0.05, input=signal, output=["force"])
    assert len(result) == len(fmpy) == 101
    np.testing.assert_allclose(result["force"], fmpy["force"], rtol=1e-15, atol=1e-15)
    assert np.ptp(fmpy["force"]) > 0.3


def gauss_seidel(folder, step, stop_time):
    """An independent Gauss-Seidel master over FMPy: the mass steps with the force of the previous step, then
    the connector with the mass's new x, v; returns the arrays time, x, v, force after every step."""
    from fmpy import extract, instantiate_fmu, read_model_description

    units = {}
    for name in ("mass", "bushing"):
        path = str(Path(folder) / ("PointMass.fmu" if name == "mass" else "bushing.fmu"))
        description = read_model_description(path)
        fmu = instantiate_fmu(extract(path), description, fmi_type="CoSimulation")
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        units[name] = (fmu, {v.name: v.valueReference for v in description.modelVariables})
    (mass, m), (bushing, b) = units["mass"], units["bushing"]
    columns = {name: [] for name in ("time", "x", "v", "force")}
    force = 0.0
    try:
        for k in range(round(stop_time / step)):
            mass.setReal([m["force"]], [force])
            mass.doStep(k * step, step)
            x, v = mass.getReal([m["x"], m["v"]])
            bushing.setReal([b["x"], b["v"]], [x, v])
            bushing.doStep(k * step, step)
            force = bushing.getReal([b["force"]])[0]
            for name, value in zip(columns, ((k + 1) * step, x, v, force)):
                columns[name].append(value)
    finally:
        for fmu, _ in units.values():
            fmu.terminate()
            fmu.freeInstance()
    return {name: np.array(values) for name, values in columns.items()}


@pytest.mark.parametrize("runtime", ["python", "native"])
def test_omsimulator_runs_the_connector_system_as_a_gauss_seidel_master(tmp_path, runtime):
    """The SSD packed into an SSP archive in OMSimulator's binary (when one is installed: OMSIMULATOR=path or
    OMSimulator on PATH; CI has none, it takes ~15 min to build): with the mass's outputs declared free of
    direct feedthrough it steps the mass, then the connector on the mass's new x, v: a Gauss-Seidel master,
    equal to an FMPy loop doing that to the 12 digits of its CSV. With the native bushing, no recipe for it."""
    binary = shutil.which(os.environ.get("OMSIMULATOR", "OMSimulator"))
    if binary is None:
        pytest.skip("no OMSimulator binary (set OMSIMULATOR=path; README: building it from source)")
    folder = run_connector.build(tmp_path)
    if runtime == "native":
        from prandtl_fmu.fmu.build import build_fmu

        build_fmu(run_connector.HERE / "bushing.toml", folder / "bushing.fmu", runtime="native")
    oms = run_connector.run_omsimulator(folder, 0.05, 8.0, binary)
    expected = gauss_seidel(folder, 0.05, 8.0)
    assert len(oms["time"]) == len(expected["time"]) == 160
    np.testing.assert_allclose(oms["time"], expected["time"], rtol=0, atol=1e-9)
    for column in ("x", "v", "force"):
        np.testing.assert_allclose(oms[column], expected[column], rtol=1e-10, atol=1e-11)
    assert np.abs(oms["force"]).max() > 0.1


@pytest.mark.parametrize("script", ["examples/cosim/run_cosim.py", "examples/cosim/connector/run_connector.py"])
def test_an_example_without_the_plot_extra_says_so_in_one_line(tmp_path, script):
    """--plot on a machine without matplotlib ended with a traceback after the whole run (issue 23, item 15)."""
    import subprocess
    import sys

    hide = ("import runpy, sys; sys.modules['matplotlib'] = None; sys.argv = sys.argv[1:]; "
            "runpy.run_path(sys.argv[0], run_name='__main__')")
    done = subprocess.run([sys.executable, "-c", hide, str(ROOT / script), "--plot", str(tmp_path / "p.png"),
                           "--out", str(tmp_path / "out")], capture_output=True, text=True, timeout=300)
    assert done.returncode == 2
    assert done.stderr.strip() == "error: --plot needs matplotlib: pip install 'prandtl_fmu[plot]'"
    assert not (tmp_path / "out").exists()
