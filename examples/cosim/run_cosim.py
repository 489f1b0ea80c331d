"""Run the Prandtl element FMU in libcosim (Open Simulation Platform), driven by a force FMU.

    python examples/cosim/run_cosim.py [--scene SCENE.toml] [--out DIR] [--stop-time T] [--plot FILE.png]

Builds ``PrandtlElement.fmu`` (from the scene, default: the paper's section 8
scene) and ``HarmonicForce.fmu`` into DIR (default: out/cosim), copies
``OspSystemStructure.xml`` there (force.F -> element.F, communication step
0.01 s, stepper "implicit"), runs it with libcosimpy and writes
``DIR/cosim.csv`` (time, F, x, v, reaction) and, with --plot, the loop.
libcosim counts time in integer nanoseconds.
"""
import argparse
import csv
import os
import shutil
import sys
from pathlib import Path


HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(ROOT))
from prandtl_fmu.cli import require_extras  # noqa: E402  (the checkout's package first)

NANOSECONDS = 1_000_000_000


def build(folder, scene=ROOT / "scenes" / "paper-section-8.toml", runtime="python"):
    """Build both FMUs and the system structure into ``folder``; return the structure's path. ``runtime``: the
    element's ("native": no Python in its binary, README "Which FMU to build")."""
    from pythonfmu import FmuBuilder

    from prandtl_fmu.fmu.build import build_fmu
    from prandtl_fmu.fmu.python.loader import install as install_loader

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    build_fmu(scene, folder / "PrandtlElement.fmu", runtime=runtime)
    source = HERE / "prandtl_example_harmonic_force.py"
    try:
        FmuBuilder.build_FMU(source, dest=folder / "HarmonicForce.fmu")
        install_loader(folder / "HarmonicForce.fmu")  # our patched PythonFMU loader (prandtl_fmu/fmu/python/loader)
    finally:  # let the FMU import its own copy when loaded in this process
        sys.modules.pop(source.stem, None)
        if str(source.parent) in sys.path:
            sys.path.remove(str(source.parent))
    structure = folder / "OspSystemStructure.xml"
    shutil.copyfile(HERE / "OspSystemStructure.xml", structure)
    return structure


def run(structure, stop_time):
    """Run the system until ``stop_time`` (s); return the columns time, F, x, v, reaction.

    Row k holds the values after step k (time k dt); F is the force the
    source output at that time, which libcosim hands to the element for the
    next step.
    """
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_osp_config_file(str(structure))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    element = execution.slave_index_from_instance_name("element")
    force = execution.slave_index_from_instance_name("force")

    def reference(slave, name):
        for variable in execution.slave_variables(slave):
            if variable.name.decode() == name:
                return variable.reference
        raise KeyError(name)

    outputs = [reference(element, name) for name in ("x", "v", "reaction")]
    force_output = reference(force, "F")
    step = 10_000_000  # 0.01 s, the BaseStepSize of OspSystemStructure.xml
    columns = {name: [] for name in ("time", "F", "x", "v", "reaction")}
    steps = round(stop_time * NANOSECONDS / step)
    for k in range(1, steps + 1):
        execution.step(1)
        x, v, reaction = observer.last_real_values(element, outputs)
        columns["time"].append(k * step / NANOSECONDS)
        columns["F"].append(observer.last_real_values(force, [force_output])[0])
        for name, value in zip(("x", "v", "reaction"), (x, v, reaction)):
            columns[name].append(value)
    return columns


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=str(ROOT / "scenes" / "paper-section-8.toml"))
    parser.add_argument("--out", default=str(ROOT / "out" / "cosim"))
    parser.add_argument("--stop-time", type=float, default=100.0)
    parser.add_argument("--plot")
    parser.add_argument("--runtime", choices=("python", "native"), default="python",
                        help="the element FMU's runtime (native: no Python in its binary)")
    args = parser.parse_args()
    require_extras({"the co-simulation": (["libcosimpy"], "cosim")}
                   | ({"--plot": (["matplotlib"], "plot")} if args.plot else {}))
    structure = build(args.out, args.scene, runtime=args.runtime)
    columns = run(structure, args.stop_time)
    path = os.path.join(args.out, "cosim.csv")
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(columns)
        writer.writerows(zip(*columns.values()))
    print(path)
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4.5), layout="constrained")
        ax.plot(columns["x"], columns["reaction"], lw=0.8)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("reaction (N)")
        ax.set_title("Prandtl element in libcosim, driven by HarmonicForce")
        fig.savefig(args.plot, dpi=120)
        print(args.plot)


if __name__ == "__main__":
    main()
