"""The belt tensioner as a connector FMU coupled to a belt-span FMU built from a network scene (issue 35).

    python examples/cosim/tensioner/run_tensioner.py [--out DIR] [--plot FILE.png]

The system: the tensioner's arm (inertia 2e-3 kg m^2) held by the belt span's elasticity and damping and driven
by the span tension's fluctuation at 40 Hz: ``belt-span.toml``, a network scene, built as the element FMU
(input F: an external torque on the arm; outputs x_arm, v_arm). The tensioner, ``tensioner.toml``, is the
connector FMU of its torsion spring and Dahl friction (docs/memory.md): inputs the arm's angle and velocity,
output its torque. A Gauss-Seidel master over FMPy (this script) steps the span with F = -torque of the last
step, then hands the span's new x_arm, v_arm to the tensioner; ``--master libcosim`` runs the same system from
``SystemStructure.ssd`` (SSP 1.0: the torque reaches the span through a linear transformation of factor -1). Together they are the element of
``tensioner-with-belt.toml``, which the library steps implicitly at h = 1e-7 s: the reference. Prints the
error max |x - x_ref| on the 1e-4 s grid at communication steps H = 4e-4 ... 5e-5 s and the measured order
(about 1: the torque is held over each step); writes DIR/convergence.csv; --plot draws the arm's torque
against its angle.
"""
import argparse
import csv
import shutil
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
sys.path.insert(0, str(ROOT))
from prandtl_fmu.cli import require_extras  # noqa: E402  (the checkout's package first)

STEPS = (4e-4, 2e-4, 1e-4, 5e-5)
GRID = 1e-4  # the grid the errors are taken on


def build(folder):
    """Build both FMUs (PythonFMU) into ``folder``."""
    from prandtl_fmu.fmu.build import build_fmu

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    build_fmu(HERE / "belt-span.toml", folder / "belt-span.fmu")
    build_fmu(HERE / "tensioner.toml", folder / "tensioner.fmu")
    shutil.copyfile(HERE / "SystemStructure.ssd", folder / "SystemStructure.ssd")
    return folder


def gauss_seidel(folder, step, stop_time):
    """The coupled run: the arrays time, x (the arm's angle), v, torque after every communication step."""
    from fmpy import extract, instantiate_fmu, read_model_description

    units = {}
    for name in ("belt-span", "tensioner"):
        path = str(Path(folder) / f"{name}.fmu")
        description = read_model_description(path)
        fmu = instantiate_fmu(extract(path), description, fmi_type="CoSimulation")
        vr = {v.name: v.valueReference for v in description.modelVariables}
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        if name == "belt-span":
            fmu.setBoolean([vr["scene_load"]], [True])
        fmu.exitInitializationMode()
        units[name] = (fmu, vr)
    (span, s), (tensioner, t) = units["belt-span"], units["tensioner"]
    columns = {name: [] for name in ("time", "x", "v", "torque")}
    torque = tensioner.getReal([t["force"]])[0]
    try:
        for k in range(round(stop_time / step)):
            span.setReal([s["F"]], [-torque])
            span.doStep(k * step, step)
            x, v = span.getReal([s["x_arm"], s["v_arm"]])
            tensioner.setReal([t["x"], t["v"]], [x, v])
            tensioner.doStep(k * step, step)
            torque = tensioner.getReal([t["force"]])[0]
            for name, value in zip(columns, ((k + 1) * step, x, v, torque)):
                columns[name].append(value)
    finally:
        for fmu, _ in units.values():
            fmu.terminate()
            fmu.freeInstance()
    return {name: np.array(values) for name, values in columns.items()}


def run_libcosim(folder, step, stop_time):
    """The same system from SystemStructure.ssd in libcosim (its fixed-step algorithm: both FMUs step at once,
    then the outputs are exchanged; the torque reaches the span through the SSD's linear transformation of
    factor -1). libcosim counts time in integer nanoseconds."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_ssp_file(str(folder), step_size=round(step * 1_000_000_000))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    span = execution.slave_index_from_instance_name("span")
    tensioner = execution.slave_index_from_instance_name("tensioner")

    def reference(slave, name):
        return next(v.reference for v in execution.slave_variables(slave) if v.name.decode() == name)

    arm = [reference(span, "x_arm"), reference(span, "v_arm")]
    force = [reference(tensioner, "force")]
    columns = {name: [] for name in ("time", "x", "v", "torque")}
    for k in range(round(stop_time / step)):
        execution.step(1)
        x, v = observer.last_real_values(span, arm)
        for name, value in zip(columns, ((k + 1) * step, x, v, observer.last_real_values(tensioner, force)[0])):
            columns[name].append(value)
    return {name: np.array(values) for name, values in columns.items()}


MASTERS = {"gauss-seidel": gauss_seidel, "libcosim": run_libcosim}


def reference(stop_time):
    """The library's element of tensioner-with-belt.toml: (times, x) on the GRID."""
    from prandtl_fmu import load_scene, simulate

    scene = load_scene(HERE / "tensioner-with-belt.toml").with_solver(stop_time=stop_time)
    result = simulate(scene).columns()
    return result["time"], result["x"]


def convergence(folder, stop_time=0.1, steps=STEPS, master="gauss-seidel"):
    """Rows (H, error, order) of the coupled runs (``master``: a key of MASTERS) against the reference."""
    times, x_ref = reference(stop_time)
    rows, last = [], None
    for step in steps:
        run = MASTERS[master](folder, step, stop_time)
        every = round(GRID / step) if step < GRID else 1
        on_grid = run["x"][every - 1::every] if step <= GRID else np.interp(times[1:], run["time"], run["x"])
        error = float(np.max(np.abs(on_grid[:len(times) - 1] - x_ref[1:len(on_grid) + 1])))
        order = float(np.log2(last / error)) if last else float("nan")
        rows.append((step, error, order))
        last = error
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/tensioner")
    parser.add_argument("--stop-time", type=float, default=0.1)
    parser.add_argument("--master", choices=sorted(MASTERS), default="gauss-seidel",
                        help="this script's Gauss-Seidel loop over FMPy, or libcosim on SystemStructure.ssd")
    parser.add_argument("--plot", help="a PNG of the arm's torque against its angle (needs the plot extra)")
    args = parser.parse_args()
    if args.plot:
        require_extras({"--plot": (("matplotlib",), "plot")})
    folder = build(args.out)
    rows = convergence(folder, args.stop_time, master=args.master)
    with open(Path(folder) / "convergence.csv", "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["communication_step", "max_error_x", "order"])
        writer.writerows(rows)
    for step, error, order in rows:
        print(f"H = {step:.1e} s: max |x - x_ref| = {error:.3e} rad   order {order:.2f}")
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        run = gauss_seidel(folder, STEPS[-1], args.stop_time)
        late = run["time"] > args.stop_time / 2
        fig, ax = plt.subplots(figsize=(6, 4.5))
        ax.plot(run["x"][late], run["torque"][late], lw=1.0)
        ax.set_xlabel("arm angle (rad)")
        ax.set_ylabel("tensioner torque (N m)")
        ax.set_title("The tensioner connector FMU in the belt-span co-simulation")
        fig.tight_layout()
        fig.savefig(args.plot, dpi=110)
        print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
