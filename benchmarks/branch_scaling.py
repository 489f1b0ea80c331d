"""Nanoseconds per time step against the number of branches, O(n) play kernel and memory stack side by side.

Problem: the paper's section 8 spectrum (k_i = 1/n, eta_i = 0.1 + i/n, F = 0.45 cos(0.5 t), m = 1),
h = 1e-3, output every 10 s, for n = 10, 100, ..., 10^5 and the continuum (infinitely many branches,
the stack with integrals), for every stepper that takes the stack (projected, implicit, symplectic,
verlet). The cost per step is the marginal one: the difference between runs of 2e5 and 2e4 steps
divided by the difference in steps, so the setup (sorting the branches, prefix sums: O(n log n), once)
is reported apart, in ms. Compiled code is warmed up first; the median of interleaved repeats is
reported. Writes out/branch_scaling.csv and out/branch_scaling.png.

    python benchmarks/branch_scaling.py [--repeat 3] [--out out]
"""
import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, ROOT)
from common import write_rows  # noqa: E402
from prandtl_fmu import simulate  # noqa: E402
from prandtl_fmu.bench.paper import paper_scene  # noqa: E402

STEPS = 200_000
SHORT = 20_000
STEPPERS = ("projected", "implicit", "symplectic", "verlet")


def timed(scene, stepper, kernel, repeat):
    """(ns per step, setup ms): medians over ``repeat`` interleaved pairs of a long and a short run."""
    simulate(scene.with_solver(stop_time=10.0), stepper, branch_kernel=kernel)  # compile, warm up
    long_runs, short_runs = [], []
    for _ in range(repeat):
        for stop, samples in ((STEPS * 1e-3, long_runs), (SHORT * 1e-3, short_runs)):
            start = time.perf_counter()
            simulate(scene.with_solver(stop_time=stop), stepper, branch_kernel=kernel)
            samples.append(time.perf_counter() - start)
    t_long, t_short = float(np.median(long_runs)), float(np.median(short_runs))
    per_step = (t_long - t_short) / (STEPS - SHORT)
    return per_step * 1e9, max(t_short - per_step * SHORT, 0.0) * 1e3


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", default=os.path.join(ROOT, "out"))
    args = parser.parse_args()
    runs = [(s, "play") for s in STEPPERS] + [(s, "stack") for s in STEPPERS]
    rows = []
    for n in (10, 100, 1_000, 10_000, 100_000, None):
        scene = paper_scene(n, STEPS * 1e-3).with_solver(output_interval=10.0)
        for stepper, kernel in runs:
            if n is None and (kernel == "play" or stepper == "implicit"):
                continue  # the continuum: the stack only, and not implicit (its force is not piecewise linear)
            if kernel == "play" and n is not None and n * STEPS > 2e9:
                continue  # the O(n) kernel at n = 10^5: minutes; its line is straight anyway
            ns, setup = timed(scene, stepper, kernel, args.repeat)
            rows.append({"stepper": stepper, "kernel": kernel, "n": "continuum" if n is None else n,
                         "ns_per_step": f"{ns:.1f}", "setup_ms": f"{setup:.2f}"})
            print(rows[-1], flush=True)
    write_rows(os.path.join(args.out, "branch_scaling.csv"), rows)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5), layout="constrained")
    for index, (stepper, kernel) in enumerate(runs):
        chosen = [r for r in rows if r["stepper"] == stepper and r["kernel"] == kernel and r["n"] != "continuum"]
        ax.loglog([r["n"] for r in chosen], [float(r["ns_per_step"]) for r in chosen],
                  "o-" if kernel == "stack" else "s--", color=f"C{index % 4}", label=f"{stepper} ({kernel})")
        for r in rows:
            if r["stepper"] == stepper and r["kernel"] == kernel and r["n"] == "continuum":
                ax.plot([3e5], [float(r["ns_per_step"])], "*", ms=10, color=f"C{index % 4}")
    ax.axvline(3e5, color="0.6", lw=0.6)
    ax.text(3e5, ax.get_ylim()[1], " continuum (*)", fontsize=8, va="top", rotation=90)
    ax.set(xlabel="number of branches n", ylabel="ns per step", title="Cost per step against n")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.savefig(os.path.join(args.out, "branch_scaling.png"), dpi=120)
    print(f"written: {args.out}/branch_scaling.png")


if __name__ == "__main__":
    main()
