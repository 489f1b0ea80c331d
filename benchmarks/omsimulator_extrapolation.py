"""OMSimulator's --inputExtrapolation on the connector example, every FMU native: the error of the mass's x against
the exact solution at communication steps H, with and without the option, and the orders.

    python benchmarks/omsimulator_extrapolation.py --omsimulator PATH [--out DIR] [--stop-time T] [--calls]
                                                   [--plot FILE.png]

The system is docs/connector.md's example (m x'' = A cos(omega t) - force(x, v), the bushing of
examples/cosim/connector/bushing.toml) as three FMUs in one SSP: the mass, a native element FMU of a point mass
(m = 1, `verlet`, h = 1e-4 s, its input F); the bushing, the native connector FMU; and the load, a small FMU that
forms F = A cos(omega t) - force (benchmarks/omsimulator_load.c, built here with gcc: OMSimulator connects an
output to an input and cannot add or change a sign). All three can get and set their state, which OMSimulator's
fixed-step master ("oms-ma") needs to use --inputExtrapolation at all.

What the option does there (OMSimulator's SystemWC.cpp at acb56d9d): each communication step is taken twice. The
first pass steps every FMU on the inputs of the step's start; OMSimulator reads the inputs that result at its end,
sets every FMU back to its state at the start, sets on every FMU that declares canInterpolateInputs the slope of each
input between the two (order 1), and steps again. After a step it also passes each output's derivative of the
source FMU's maxOutputDerivativeOrder to the input it feeds, as that order alone (the mass's x gives the bushing
x'' = a, its v gives v'' = a'; the connector declares no output derivatives, so the load's input and the mass's F
get none from there). With an FMU that cannot get and set its state in the system, OMSimulator takes one pass and
only the output derivatives remain: the third case, the load declaring canGetAndSetFMUstate="false".

Prints the markdown table of docs/masters/omsimulator.md (error = max |x - x_ref| over the instants 0, 0.1, ...,
T s, x_ref the exact stepper's single element of bushing-with-mass.toml) and writes DIR/omsimulator-extrapolation.csv.
``--calls`` also runs a short case (H = 0.1 s, 1 s) under gdb and prints every fmi2SetRealInputDerivatives and
fmi2GetRealOutputDerivatives call OMSimulator makes (which FMU, value reference, order, value). ``--plot``: the
errors against H on log-log axes.
"""
import argparse
import csv
import math
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "cosim" / "connector"
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(EXAMPLE))

STEPS = (0.1, 0.05, 0.025, 0.0125, 0.00625)
COMPARED_EVERY = 0.1  # s: the instants every H of STEPS reaches
SYSTEM = "prandtl_connector_native.mass_on_bushing"

MASS = """name = "point-mass"

[mass]
m = 1.0

[solver]
stepper = "verlet"
step = 1e-4
stop_time = 40.0
output_interval = 0.01
"""

LOAD_DESCRIPTION = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="harmonic_load" guid="{{5e2c4a56-9b0e-4d8b-9a3e-6f1b1c0d2e71}}"
    description="F = amplitude cos(omega t) - force (benchmarks/omsimulator_load.c)" variableNamingConvention="flat"
    numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="harmonic_load" canHandleVariableCommunicationStepSize="true"
      canGetAndSetFMUstate="{state}" canSerializeFMUstate="false" canInterpolateInputs="false"
      canNotUseMemoryManagementFunctions="true"/>
  <UnitDefinitions>
    <Unit name="N"><BaseUnit kg="1" m="1" s="-2"/></Unit>
    <Unit name="rad/s"><BaseUnit rad="1" s="-1"/></Unit>
  </UnitDefinitions>
  <ModelVariables>
    <ScalarVariable name="force" valueReference="0" causality="input" variability="continuous"
        description="force of the connector against the motion"><Real start="0" unit="N"/></ScalarVariable>
    <ScalarVariable name="F" valueReference="1" causality="output" variability="continuous" initial="calculated"
        description="amplitude cos(omega t) - force"><Real unit="N"/></ScalarVariable>
    <ScalarVariable name="amplitude" valueReference="2" causality="parameter" variability="fixed" initial="exact">
      <Real start="0.45" unit="N"/></ScalarVariable>
    <ScalarVariable name="omega" valueReference="3" causality="parameter" variability="fixed" initial="exact">
      <Real start="0.5" unit="rad/s"/></ScalarVariable>
  </ModelVariables>
  <ModelStructure>
    <Outputs><Unknown index="2" dependencies="1"/></Outputs>
    <InitialUnknowns><Unknown index="2" dependencies="1 3 4"/></InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""

SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription name="prandtl_connector_native" version="1.0"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:oms="https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd">
  <ssd:System name="mass_on_bushing">
    <ssd:Elements>
      <ssd:Component name="mass" type="application/x-fmu-sharedlibrary" source="resources/mass.fmu">
        <ssd:Connectors>
          <ssd:Connector name="F" kind="input"><ssc:Real unit="N"/></ssd:Connector>
          <ssd:Connector name="x" kind="output"><ssc:Real unit="m"/></ssd:Connector>
          <ssd:Connector name="v" kind="output"><ssc:Real unit="m/s"/></ssd:Connector>
        </ssd:Connectors>
      </ssd:Component>
      <ssd:Component name="bushing" type="application/x-fmu-sharedlibrary" source="resources/bushing.fmu">
        <ssd:Connectors>
          <ssd:Connector name="x" kind="input"><ssc:Real unit="m"/></ssd:Connector>
          <ssd:Connector name="v" kind="input"><ssc:Real unit="m/s"/></ssd:Connector>
          <ssd:Connector name="force" kind="output"><ssc:Real unit="N"/></ssd:Connector>
        </ssd:Connectors>
      </ssd:Component>
      <ssd:Component name="load" type="application/x-fmu-sharedlibrary" source="resources/load.fmu">
        <ssd:Connectors>
          <ssd:Connector name="force" kind="input"><ssc:Real unit="N"/></ssd:Connector>
          <ssd:Connector name="F" kind="output"><ssc:Real unit="N"/></ssd:Connector>
        </ssd:Connectors>
      </ssd:Component>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="mass" startConnector="x" endElement="bushing" endConnector="x"/>
      <ssd:Connection startElement="mass" startConnector="v" endElement="bushing" endConnector="v"/>
      <ssd:Connection startElement="bushing" startConnector="force" endElement="load" endConnector="force"/>
      <ssd:Connection startElement="load" startConnector="F" endElement="mass" endConnector="F"/>
    </ssd:Connections>
    <ssd:Annotations>
      <ssc:Annotation type="org.openmodelica">
        <oms:Annotations>
          <oms:SimulationInformation>
            <oms:FixedStepMaster description="oms-ma" stepSize="{step!r}" relativeTolerance="0.0001"/>
          </oms:SimulationInformation>
        </oms:Annotations>
      </ssc:Annotation>
    </ssd:Annotations>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0.0" stopTime="{stop_time!r}"/>
</ssd:SystemStructureDescription>
"""


def build(folder: Path) -> Path:
    """The FMUs in ``folder``: mass.fmu and bushing.fmu (native, build_fmu), load.fmu (gcc) and load-stateless.fmu,
    the same but declaring canGetAndSetFMUstate="false" (with it in the system OMSimulator takes one pass)."""
    from prandtl_fmu.fmu.build import build_fmu

    folder.mkdir(parents=True, exist_ok=True)
    (folder / "point-mass.toml").write_text(MASS)
    build_fmu(folder / "point-mass.toml", folder / "mass.fmu", runtime="native")
    build_fmu(EXAMPLE / "bushing.toml", folder / "bushing.fmu", runtime="native")
    headers = ROOT / "prandtl_fmu" / "fmu" / "python" / "loader" / "src" / "fmi"
    library = folder / "harmonic_load.so"
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-std=c99", f"-I{headers}",
                    str(ROOT / "benchmarks" / "omsimulator_load.c"), "-o", str(library), "-lm"], check=True)
    for name, state in (("load.fmu", "true"), ("load-stateless.fmu", "false")):
        with zipfile.ZipFile(folder / name, "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("modelDescription.xml", LOAD_DESCRIPTION.format(state=state))
            archive.write(library, "binaries/linux64/harmonic_load.so")
    return folder


# the runs compared: (--inputExtrapolation, the load's FMU)
CASES = {"held": (False, "load.fmu"), "extrapolated": (True, "load.fmu"), "one pass": (True, "load-stateless.fmu")}


def run(folder: Path, step: float, stop_time: float, omsimulator: str, case: str, wrapper=()) -> dict:
    """Run the system in OMSimulator at communication step ``step`` as ``case`` says (a key of CASES); the arrays
    time, x (the last row OMSimulator writes at each communication point), or with ``wrapper`` (a command the run
    goes through, e.g. gdb) its output."""
    extrapolate, load = CASES[case]
    name = f"H{step!r}-{case.replace(' ', '-')}"
    ssp = folder / f"{name}.ssp"
    with zipfile.ZipFile(ssp, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("SystemStructure.ssd", SSD.format(step=step, stop_time=stop_time))
        for fmu, source in (("mass", "mass.fmu"), ("bushing", "bushing.fmu"), ("load", load)):
            archive.write(folder / source, f"resources/{fmu}.fmu")
    result = folder / f"{name}.csv"
    command = [*wrapper, omsimulator, str(ssp), "--mode=cs", f"--stopTime={stop_time!r}",
               f"--resultFile={result}", f"--tempDir={folder / 'temp'}"]
    if extrapolate:
        command.append("--inputExtrapolation=true")
    done = subprocess.run(command, cwd=folder, capture_output=True, text=True, timeout=3600)
    if wrapper:
        return {"output": done.stdout + done.stderr}
    if done.returncode != 0 or not result.exists() or "error:" in done.stdout:
        raise RuntimeError(f"OMSimulator failed (exit {done.returncode}): {done.stdout[-2000:]}{done.stderr[-2000:]}")
    with open(result, newline="") as fh:
        rows = list(csv.reader(fh))
    header = [column.strip().strip('"') for column in rows[0]]
    table = np.array([[float(value) for value in row] for row in rows[1:]])
    last = np.append(table[1:, 0] != table[:-1, 0], True)
    return {"time": table[last, 0], "x": table[last, header.index(f"{SYSTEM}.mass.x")]}


def errors(folder: Path, stop_time: float, omsimulator: str) -> dict:
    """{case: [max |x - x_ref| at each of STEPS]} for every case of CASES."""
    from run_connector import reference_x

    grid = np.round(np.arange(0, round(stop_time / COMPARED_EVERY) + 1) * COMPARED_EVERY, 10)
    exact = reference_x(grid)
    found = {}
    for case in CASES:
        found[case] = []
        for step in STEPS:
            result = run(folder, step, stop_time, omsimulator, case)
            index = np.searchsorted(np.round(result["time"], 9), grid)
            found[case].append(float(np.abs(result["x"][index] - exact).max()))
    return found


def orders(values) -> list:
    """The order between each pair of successive STEPS (halved)."""
    return [math.log2(coarse / fine) for coarse, fine in zip(values[:-1], values[1:])]


def fitted_order(values) -> float:
    """The slope of log(error) against log(H), least squares over STEPS."""
    return float(np.polyfit(np.log(STEPS), np.log(values), 1)[0])


GDB_CALLS = """set pagination off
set breakpoint pending on
break fmi2SetRealInputDerivatives
commands
silent
printf "set  %p vr %u order %d value % .6e\\n", $rdi, *(unsigned int*)$rsi, *(int*)$rcx, *(double*)$r8
continue
end
break fmi2GetRealOutputDerivatives
commands
silent
printf "get  %p vr %u order %d\\n", $rdi, *(unsigned int*)$rsi, *(int*)$rcx
continue
end
run
"""


def calls(folder: Path, omsimulator: str) -> str:
    """The derivative calls of a 1 s run at H = 0.1 s with --inputExtrapolation, as gdb prints them (x86-64: the
    arguments in rdi, rsi, rdx, rcx, r8 at the function's entry)."""
    script = folder / "calls.gdb"
    script.write_text(GDB_CALLS)
    output = run(folder, 0.1, 1.0, omsimulator, "extrapolated", wrapper=("gdb", "-q", "-batch", "-x", str(script), "--args"))
    return "\n".join(line for line in output["output"].splitlines() if line.startswith(("set ", "get ")))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--omsimulator", required=True, help="path of the OMSimulator binary")
    parser.add_argument("--out", default=str(ROOT / "out" / "omsimulator-extrapolation"))
    parser.add_argument("--stop-time", type=float, default=20.0)
    parser.add_argument("--calls", action="store_true", help="also list the derivative calls of a short run (gdb)")
    parser.add_argument("--plot", help="PNG of the errors against H")
    args = parser.parse_args()
    if shutil.which(args.omsimulator) is None:
        parser.error(f"--omsimulator: {args.omsimulator} is not an executable")
    folder = build(Path(args.out).resolve())
    if args.calls:
        print(calls(folder, args.omsimulator))
    found = errors(folder, args.stop_time, args.omsimulator)
    with open(folder / "omsimulator-extrapolation.csv", "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["H"] + [f"max_error_x_{case.replace(' ', '_')}" for case in CASES])
        writer.writerows(zip(STEPS, *found.values()))
    print("| H (s) | without (m) | order | with `--inputExtrapolation` (m) | order | with it, one pass (m) | order |")
    print("|---|---|---|---|---|---|---|")
    for i, step in enumerate(STEPS):
        cells = [f"{step:g}"]
        for values in found.values():
            cells += [f"{values[i]:.2e}", f"{orders(values)[i - 1]:.2f}" if i else ""]
        print("| " + " | ".join(cells) + " |")
    print("| fitted order | " + " | ".join(f" | {fitted_order(values):.2f}" for values in found.values()) + " |")
    if args.plot:
        plot(found, args.plot)


def plot(found: dict, path: str) -> None:
    """The errors of every case against H, log-log, into the PNG ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = {"held": "without", "extrapolated": "--inputExtrapolation", "one pass": "--inputExtrapolation, one pass"}
    fig, ax = plt.subplots(figsize=(6, 4.5), layout="constrained")
    for case, values in found.items():
        ax.loglog(STEPS, values, "o-" if case != "one pass" else "x--", label=f"{labels[case]} "
                  f"(order {fitted_order(values):.2f})")
    ax.set_xlabel("communication step H (s)")
    ax.set_ylabel("max |x - x_ref| (m)")
    ax.set_title("Connector example in OMSimulator, native FMUs")
    ax.legend()
    fig.savefig(path, dpi=120)
    print(path)

if __name__ == "__main__":
    main()
