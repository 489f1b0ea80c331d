"""A mass on the ground through the Prandtl connector FMU, in a master: convergence to the library's solution.

    python examples/cosim/connector/run_connector.py [--out DIR] [--stop-time T] [--master M] [--plot FILE.png]

The system: a point mass (``PointMass.fmu``, this folder) under F(t) = 0.45 cos(0.5 t), tied to the ground
by the connector FMU of ``bushing.toml`` (spring, dashpot, five Prandtl branches): the connector takes the
mass's x and v (relative to the ground: the mass's own) and returns the force that acts against it. Exactly
the element with its mass of ``bushing-with-mass.toml``, which the library solves with the event-driven
``exact`` stepper (error: rounding): the reference.

Coupled through the OSP system structure (a ``VariableGroupConnection`` of the two LinearMechanicalPorts,
force <-> v, plus x), with libcosim's fixed-step algorithm at communication steps H = 0.1 ... 0.00625 s, then
with its ECCO algorithm (adaptive step, power bond force * v). Prints the error max |x - x_ref| on the 0.1 s
grid and the measured order at each H, and the ECCO run's error and step count; writes DIR/convergence.csv.
libcosim counts time in integer nanoseconds.

``--master ecos`` runs the same system from SystemStructure.ssd in ecos (ecospy), ``--master omsimulator``
in OMSimulator's binary (``--omsimulator PATH``; the SSD packed into connector.ssp), ``--master cofmupy`` in
cofmupy (Jacobi and Gauss-Seidel; from cofmupy's own environment): DIR/convergence-M.csv. See the README's
table of masters for what each needs.
"""
import argparse
import csv
import math
import os
import shutil
import sys
from pathlib import Path

import numpy as np


HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
sys.path.insert(0, str(ROOT))
from prandtl_fmu.cli import require_extras  # noqa: E402  (the checkout's package first)

NANOSECONDS = 1_000_000_000
STEPS = (0.1, 0.05, 0.025, 0.0125, 0.00625)

STRUCTURE = """<?xml version="1.0" encoding="UTF-8"?>
<!-- A point mass on the ground through the Prandtl connector (run_connector.py writes this file). -->
<OspSystemStructure xmlns="http://opensimulationplatform.com/MSMI/OSPSystemStructure" version="0.1">
    <StartTime>0.0</StartTime>
    <BaseStepSize>{step!r}</BaseStepSize>
    <Algorithm>{algorithm}</Algorithm>
    <Simulators>
        <Simulator name="mass" source="PointMass.fmu">
            <InitialValues>
                <InitialValue variable="m"><Real value="1.0"/></InitialValue>
                <InitialValue variable="amplitude"><Real value="0.45"/></InitialValue>
                <InitialValue variable="omega"><Real value="0.5"/></InitialValue>
            </InitialValues>
        </Simulator>
        <Simulator name="bushing" source="bushing.fmu"/>
    </Simulators>
    <Connections>
{connections}
    </Connections>{ecco}
</OspSystemStructure>
"""

PORTS = """        <VariableGroupConnection>
            <VariableGroup simulator="mass" name="mechanical_port"/>
            <VariableGroup simulator="bushing" name="mechanical_port"/>
        </VariableGroupConnection>
        <VariableConnection>
            <Variable simulator="mass" name="x"/>
            <Variable simulator="bushing" name="x"/>
        </VariableConnection>"""

# ECCO: the power bond force * v, declared on the two connections that carry it (libcosim's quarter-truck form)
BONDS = """        <VariableConnection powerBond="bushing_mass">
            <Variable simulator="bushing" name="v" causality="input"/>
            <Variable simulator="mass" name="v" causality="output"/>
        </VariableConnection>
        <VariableConnection powerBond="bushing_mass">
            <Variable simulator="mass" name="force" causality="input"/>
            <Variable simulator="bushing" name="force" causality="output"/>
        </VariableConnection>
        <VariableConnection>
            <Variable simulator="mass" name="x"/>
            <Variable simulator="bushing" name="x"/>
        </VariableConnection>"""

ECCO = """
    <EccoConfiguration>
        <SafetyFactor>0.8</SafetyFactor>
        <StepSize>0.01</StepSize>
        <MinimumStepSize>0.0001</MinimumStepSize>
        <MaximumStepSize>0.1</MaximumStepSize>
        <MinimumChangeRate>0.2</MinimumChangeRate>
        <MaximumChangeRate>1.5</MaximumChangeRate>
        <ProportionalGain>0.2</ProportionalGain>
        <IntegralGain>0.15</IntegralGain>
        <RelativeTolerance>{tolerance!r}</RelativeTolerance>
        <AbsoluteTolerance>{tolerance!r}</AbsoluteTolerance>
    </EccoConfiguration>"""


def build(folder):
    """Build both FMUs and their OSP descriptions into ``folder``."""
    from pythonfmu import FmuBuilder

    from prandtl_fmu.fmu.build import build_fmu
    from prandtl_fmu.fmu.python.loader import install as install_loader

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    build_fmu(HERE / "bushing.toml", folder / "bushing.fmu", osp=True)  # + bushing_OspModelDescription.xml
    source = HERE / "prandtl_example_mass.py"
    try:
        FmuBuilder.build_FMU(source, dest=folder / "PointMass.fmu")
        install_loader(folder / "PointMass.fmu")  # our patched PythonFMU loader (prandtl_fmu/fmu/python/loader)
    finally:  # let the FMU import its own copy when loaded in this process
        sys.modules.pop(source.stem, None)
        if str(source.parent) in sys.path:
            sys.path.remove(str(source.parent))
    for name in ("PointMass_OspModelDescription.xml", "SystemStructure.ssd"):
        shutil.copyfile(HERE / name, folder / name)
    return folder


def write_structure(folder, step, ecco_tolerance=None):
    """OspSystemStructure.xml for a fixed step, or for ECCO (initial step ``step``) with a tolerance."""
    if ecco_tolerance is None:
        text = STRUCTURE.format(step=step, algorithm="fixedStep", connections=PORTS, ecco="")
        path = Path(folder) / "OspSystemStructure.xml"
    else:
        text = STRUCTURE.format(step=step, algorithm="ecco", connections=BONDS,
                                ecco=ECCO.format(tolerance=ecco_tolerance))
        path = Path(folder) / "OspSystemStructure-ecco.xml"
    path.write_text(text, encoding="utf-8")
    return path


def run(structure, stop_time, ssp_step=None):
    """Run the system to ``stop_time``; return the arrays time, x, v, force after every step.

    ``structure`` is an OspSystemStructure.xml, or with ``ssp_step`` (s) the folder of SystemStructure.ssd."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    if ssp_step is None:
        execution = CosimExecution.from_osp_config_file(str(structure))
    else:
        execution = CosimExecution.from_ssp_file(str(structure), step_size=round(ssp_step * NANOSECONDS))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    mass = execution.slave_index_from_instance_name("mass")  # indices are not in declaration order
    bushing = execution.slave_index_from_instance_name("bushing")

    def reference(slave, name):
        for variable in execution.slave_variables(slave):
            if variable.name.decode() == name:
                return variable.reference
        raise KeyError(name)

    mass_outputs = [reference(mass, "x"), reference(mass, "v")]
    force = [reference(bushing, "force")]
    columns = {name: [] for name in ("time", "x", "v", "force")}
    end = round(stop_time * NANOSECONDS)
    while True:
        now = execution.status().current_time
        if now >= end:
            break
        execution.step(1)
        x, v = observer.last_real_values(mass, mass_outputs)
        columns["time"].append(execution.status().current_time / NANOSECONDS)
        columns["x"].append(x)
        columns["v"].append(v)
        columns["force"].append(observer.last_real_values(bushing, force)[0])
    return {name: np.array(values) for name, values in columns.items()}


def run_ecos(folder, step, stop_time):
    """The same system in ecos (ecospy, in this process) from the SSP folder (SystemStructure.ssd and the FMUs):
    the arrays time, x, v, force after every step of size ``step`` (s). ecos 0.7.2 reads SSP, not
    OspSystemStructure.xml; its fixed-step master couples like libcosim's."""
    from ecospy import EcosSimulation

    simulation = EcosSimulation(step, ssp_path=str(folder))
    columns = {name: [] for name in ("time", "x", "v", "force")}
    try:
        simulation.init(parameter_set="initialValues")
        for _ in range(round(stop_time / step)):
            simulation.step(1)
            columns["time"].append(simulation.get_time())
            columns["x"].append(simulation.get_real("mass::x"))
            columns["v"].append(simulation.get_real("mass::v"))
            columns["force"].append(simulation.get_real("bushing::force"))
        simulation.terminate()
    finally:
        simulation.free()
    return {name: np.array(values) for name, values in columns.items()}


def run_cofmupy(folder, step, stop_time, cosim_method="jacobi"):
    """The same system in cofmupy 1.0.0 (in this process): the arrays time, x, v, force after every step of size
    ``step`` (s). cofmupy pins fmpy 0.3.20 and pythonfmu 0.6.3: run it from its own virtual environment with
    pythonfmu 0.7.0, numpy and numba added, and ``pip install --no-deps prandtl_fmu`` (README, Other masters).
    Its configuration is a dict (or JSON file) of FMUs, initial values and connections; ``cosim_method``
    "jacobi" (every FMU steps on the previous step's outputs, as libcosim's fixed step) or "gauss_seidel" (its
    docstring says "gauss-seidel", which it refuses)."""
    from cofmupy import Coordinator

    def port(element, variable, unit):
        return {"type": "fmu", "id": element, "variable": variable, "unit": unit}

    config = {
        "fmus": [{"id": "mass", "path": str(Path(folder).resolve() / "PointMass.fmu"),
                  "initialization": {"m": 1.0, "amplitude": 0.45, "omega": 0.5}},
                 {"id": "bushing", "path": str(Path(folder).resolve() / "bushing.fmu")}],
        "connections": [{"source": port("mass", "x", "m"), "target": [port("bushing", "x", "m")]},
                        {"source": port("mass", "v", "m/s"), "target": [port("bushing", "v", "m/s")]},
                        {"source": port("bushing", "force", "N"), "target": [port("mass", "force", "N")]}],
        "cosim_method": cosim_method,
        "iterative": False,
    }
    coordinator = Coordinator()
    coordinator.start(config)
    for _ in range(round(stop_time / step)):
        coordinator.do_step(step)
    results = coordinator.get_results()
    # cofmupy labels the outputs after a step with the step's start time: here, its end (as the others)
    return {"time": np.array(results["time"]) + step, "x": np.array(results[("mass", "x")]),
            "v": np.array(results[("mass", "v")]), "force": np.array(results[("bushing", "force")])}


def make_ssp(folder, step=None):
    """``folder``/connector.ssp: SystemStructure.ssd and the two FMUs in one SSP archive (the FMUs under
    resources/), as OMSimulator reads a system; ``step`` (s) replaces the communication step of the SSD's
    OMSimulator annotation (which its --stepSize option does not override)."""
    import re
    import zipfile

    folder = Path(folder)
    ssd = (folder / "SystemStructure.ssd").read_text(encoding="utf-8")
    if step is not None:
        ssd = re.sub(r'(<oms:FixedStepMaster [^>]*stepSize=")[^"]*"', rf'\g<1>{step!r}"', ssd)
    for name in ("PointMass.fmu", "bushing.fmu"):
        ssd = ssd.replace(f'source="{name}"', f'source="resources/{name}"')
    path = folder / "connector.ssp"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("SystemStructure.ssd", ssd)
        for name in ("PointMass.fmu", "bushing.fmu"):
            archive.write(folder / name, f"resources/{name}")
    return path


def run_omsimulator(folder, step, stop_time, omsimulator="OMSimulator", options=()):
    """The same system in OMSimulator's binary (``omsimulator``: its path) from connector.ssp (:func:`make_ssp`):
    the arrays time, x, v, force at every step of size ``step`` (s), from its result CSV (12 significant digits).
    ``options``: more command-line options for the binary (e.g. ``["--inputExtrapolation=true"]``).

    A PythonFMU FMU in a host that is not a Python process needs the host's libpython preloaded and the
    environment's packages on PYTHONPATH (the README's recipe): set here from this interpreter."""
    import subprocess
    import sysconfig

    folder = Path(folder).resolve()
    ssp = make_ssp(folder, step)
    result = folder / f"omsimulator-{step!r}.csv"
    libpython = Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("LDLIBRARY")
    paths = [p for p in sys.path if p.endswith("-packages")] + [str(ROOT)]
    env = dict(os.environ, LD_PRELOAD=str(libpython), PYTHONPATH=os.pathsep.join(paths))
    command = [omsimulator, str(ssp), f"--stopTime={stop_time!r}", f"--stepSize={step!r}", "--mode=cs",
               f"--resultFile={result}", f"--tempDir={folder}", *options]
    done = subprocess.run(command, cwd=folder, env=env, capture_output=True, text=True, timeout=3600)
    if done.returncode != 0 or not result.exists():
        raise RuntimeError(f"OMSimulator failed (exit {done.returncode}): {done.stdout[-2000:]}{done.stderr[-2000:]}")
    with open(result, newline="") as fh:
        rows = list(csv.reader(fh))
    header = [name.strip().strip('"') for name in rows[0]]
    table = np.array([[float(value) for value in row] for row in rows[1:]])

    def column(suffix):
        return table[:, header.index(f"prandtl_connector_example.mass_on_bushing.{suffix}")]

    # the initial state is the first row; OMSimulator writes two rows at each communication point (before and
    # after its outputs are updated): keep the last of each time
    last = np.append(table[1:, 0] != table[:-1, 0], True)
    keep = last & (table[:, 0] > 0)
    return {"time": table[keep, 0], "x": column("mass.x")[keep], "v": column("mass.v")[keep],
            "force": column("bushing.force")[keep]}


def reference_x(times):
    """x of the element with its mass (bushing-with-mass.toml, exact stepper) at the given times."""
    from prandtl_fmu import Element, load_scene

    element = Element(load_scene(HERE / "bushing-with-mass.toml"))
    values, now = [], 0.0
    for t in times:
        element.advance(t - now, 0.0, scene_load=True)
        now = t
        values.append(element.x)
    return np.array(values)


def convergence(folder, stop_time=40.0, steps=STEPS, ecco_tolerances=(1e-4, 1e-6)):
    """Rows (algorithm, H or tolerance, steps taken, max error of x, order) of the study in libcosim."""
    rows = fixed_step_rows("fixedStep", lambda step: run(write_structure(folder, step), stop_time), stop_time,
                           steps)
    for tolerance in ecco_tolerances:
        result = run(write_structure(folder, 0.01, ecco_tolerance=tolerance), stop_time)
        error = float(np.abs(result["x"] - reference_x(result["time"])).max())
        rows.append(("ecco", tolerance, len(result["time"]), error, float("nan")))
    return rows


def fixed_step_rows(label, run_at, stop_time, steps=STEPS):
    """Rows (label, H, steps taken, max error of x on the 0.1 s grid, order) of ``run_at(H)`` (arrays time at
    the end of each step, x, ...) for each H of ``steps``."""
    grid = np.round(np.arange(1, round(stop_time / 0.1) + 1) * 0.1, 10)
    exact = reference_x(grid)
    rows, previous = [], None
    for step in steps:
        result = run_at(step)
        index = np.searchsorted(np.round(result["time"], 9), grid)
        error = float(np.abs(result["x"][index] - exact).max())
        order = math.log2(previous / error) if previous else float("nan")
        rows.append((label, step, len(result["time"]), error, order))
        previous = error
    return rows


def master_rows(master, folder, stop_time, omsimulator="OMSimulator", omsimulator_options=()):
    """The convergence rows of one master: libcosim (fixed step and ECCO), ecos (fixed step), OMSimulator (its
    binary ``omsimulator``, with the options ``omsimulator_options``), cofmupy (Jacobi and Gauss-Seidel)."""
    if master == "libcosim":
        return convergence(folder, stop_time)
    if master == "ecos":
        return fixed_step_rows("ecos", lambda step: run_ecos(folder, step, stop_time), stop_time)
    if master == "omsimulator":
        return fixed_step_rows("omsimulator", lambda step: run_omsimulator(folder, step, stop_time, omsimulator,
                                                                           omsimulator_options), stop_time)
    return [row for method in ("jacobi", "gauss_seidel")
            for row in fixed_step_rows(f"cofmupy-{method}", lambda step: run_cofmupy(folder, step, stop_time, method),
                                       stop_time)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "out" / "connector"))
    parser.add_argument("--stop-time", type=float, default=40.0)
    parser.add_argument("--master", choices=("libcosim", "ecos", "omsimulator", "cofmupy"), default="libcosim",
                        help="the master to run (ecos: the [ecos] extra; omsimulator: its binary, see --omsimulator; "
                             "cofmupy: its own environment; see the README)")
    parser.add_argument("--omsimulator", default="OMSimulator", help="path of the OMSimulator binary")
    parser.add_argument("--input-extrapolation", action="store_true",
                        help="--master omsimulator: run it with --inputExtrapolation=true (this example's PythonFMU "
                             "FMUs take no derivatives: it changes nothing; benchmarks/omsimulator_extrapolation.py "
                             "runs the native FMUs)")
    parser.add_argument("--plot", help="PNG of the force-displacement loop, co-simulated against the reference")
    args = parser.parse_args()
    masters = {"libcosim": (["libcosimpy"], "cosim"), "ecos": (["ecospy"], "ecos")}
    require_extras(({f"--master {args.master}": masters[args.master]} if args.master in masters else {})
                   | ({"--plot": (["matplotlib"], "plot")} if args.plot else {}))
    if args.input_extrapolation and args.master != "omsimulator":
        parser.error("--input-extrapolation: an option of --master omsimulator")
    folder = build(args.out)
    options = ["--inputExtrapolation=true"] if args.input_extrapolation else []
    rows = master_rows(args.master, folder, args.stop_time, args.omsimulator, options)
    path = os.path.join(args.out, "convergence.csv" if args.master == "libcosim" else f"convergence-{args.master}.csv")
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["algorithm", "step_or_tolerance", "steps", "max_error_x", "order"])
        writer.writerows(rows)
    print(f"{'algorithm':20} {'H / tol':>9} {'steps':>7} {'max |x - x_ref|':>16} {'order':>6}")
    for algorithm, setting, count, error, order in rows:
        print(f"{algorithm:20} {setting:9.3g} {count:7d} {error:16.3e} {order:6.2f}")
    print(path)
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        result = run(write_structure(folder, 0.0125), args.stop_time)
        fig, ax = plt.subplots(figsize=(6, 4.5), layout="constrained")
        ax.plot(result["x"], result["force"], lw=0.8, label="libcosim, H = 0.0125 s")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("connector force (N)")
        ax.set_title("Mass on the ground through the Prandtl connector")
        ax.legend()
        fig.savefig(args.plot, dpi=120)
        print(args.plot)


if __name__ == "__main__":
    main()
