"""Drive a Prandtl element FMU with FMPy under a harmonic force and plot its hysteresis loop.

    python examples/run_fmu.py ELEMENT.fmu [--amplitude 0.45] [--omega 0.5] [--offset 0]
                               [--stop-time T] [--interval DT] [--stepper NAME]
                               [--scene-load] [--out run.csv] [--plot loop.png]

The force F(t) = offset + amplitude cos(omega t) is sampled at every
communication point and held over the step (FMPy sets inputs at the start of
each step). With --scene-load there is no input: the FMU's parameter
scene_load applies its scene's [load] at every internal step, and the run
reproduces the library's run of the scene. Stop time and communication step default to the FMU's
DefaultExperiment (the scene's [solver] stop_time and output_interval).
"""
import argparse
import importlib.util
import sys

import numpy as np


def _require(module: str, extra: str, what: str) -> None:
    """One line naming the extra that brings ``module``, exit status 2, before any work."""
    if importlib.util.find_spec(module) is None:
        print(f"error: {what} needs {module}: pip install 'prandtl_fmu[{extra}]'", file=sys.stderr)
        raise SystemExit(2)


def run(fmu, amplitude=0.45, omega=0.5, offset=0.0, stop_time=None, interval=None, stepper=None,
        scene_load=False):
    """Simulate and return FMPy's structured array with time, x, v, reaction."""
    from fmpy import read_model_description, simulate_fmu

    experiment = read_model_description(fmu).defaultExperiment
    stop_time = float(stop_time or experiment.stopTime)
    interval = float(interval or experiment.stepSize)
    count = int(round(stop_time / interval))
    times = np.arange(count + 1) * interval
    signal = np.zeros(count + 1, dtype=[("time", float), ("F", float)])
    signal["time"], signal["F"] = times, offset + amplitude * np.cos(omega * times)
    start_values = {"stepper": stepper} if stepper else {}
    # said either way: a fresh FMU adds its scene's [load] to F (scene_load starts true where the scene names one)
    start_values["scene_load"] = bool(scene_load)
    return simulate_fmu(fmu, stop_time=stop_time, output_interval=interval, input=None if scene_load else signal,
                        start_values=start_values, output=["x", "v", "reaction"])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fmu")
    parser.add_argument("--amplitude", type=float, default=0.45)
    parser.add_argument("--omega", type=float, default=0.5)
    parser.add_argument("--offset", type=float, default=0.0)
    parser.add_argument("--stop-time", type=float)
    parser.add_argument("--interval", type=float)
    parser.add_argument("--stepper")
    parser.add_argument("--scene-load", action="store_true",
                        help="no input: the scene's own [load] at every internal step (reproduces the library)")
    parser.add_argument("--out", help="CSV file: time,x,v,reaction")
    parser.add_argument("--plot", help="PNG file: the hysteresis loop and x(t)")
    args = parser.parse_args()
    _require("fmpy", "fmpy", "examples/run_fmu.py")
    if args.plot:
        _require("matplotlib", "plot", "--plot")
    result = run(args.fmu, args.amplitude, args.omega, args.offset, args.stop_time, args.interval, args.stepper,
                 args.scene_load)
    print(f"{args.fmu}: {len(result)} communication points, x(T) = {float(result['x'][-1])!r}, "
          f"reaction(T) = {float(result['reaction'][-1])!r}")
    if args.out:
        with open(args.out, "w") as fh:
            fh.write("time,x,v,reaction\n")
            for row in result:
                fh.write(",".join(repr(float(value)) for value in row) + "\n")
        print(args.out)
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, (loop, history) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
        loop.plot(result["x"], result["reaction"], lw=0.8)
        loop.set(xlabel="x (m)", ylabel="reaction (N)", title="hysteresis loop (FMU driven by FMPy)")
        history.plot(result["time"], result["x"], lw=0.8)
        history.set(xlabel="t (s)", ylabel="x (m)", title="displacement")
        for ax in (loop, history):
            ax.grid(alpha=0.3)
        fig.savefig(args.plot, dpi=120)
        print(args.plot)


if __name__ == "__main__":
    main()
