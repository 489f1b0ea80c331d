"""Nanoseconds per time step against the number of branches, O(n) play kernel and memory stack side by side.

Problem: the paper's section 8 spectrum (k_i = 1/n, eta_i = 0.1 + i/n, F = 0.45 cos(0.5 t), m = 1),
h = 1e-3, T = 200 s (2e5 steps), output every 10 s, for n = 10, 100, ..., 10^5 and every stepper
that takes the stack (projected, symplectic, verlet) plus implicit (O(n) only). Compiled code is warmed
up first; the median of interleaved repeats is reported. Writes out/branch_scaling.csv and
out/branch_scaling.png.

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
from prandtl_fmu.bench import paper_scene  # noqa: E402

STEPS = 200_000


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", default=os.path.join(ROOT, "out"))
    args = parser.parse_args()
    runs = [(s, "play") for s in ("projected", "symplectic", "verlet", "implicit")] + \
           [(s, "stack") for s in ("projected", "symplectic", "verlet")]
    rows = []
    for n in (10, 100, 1_000, 10_000, 100_000):
        scene = paper_scene(n, STEPS * 1e-3).with_solver(output_interval=10.0)
        for stepper, kernel in runs:
            if kernel == "play" and n * STEPS > 2e9:
                continue  # the O(n) kernel at n = 10^5: minutes; its line is straight anyway
            simulate(scene.with_solver(stop_time=10.0), stepper, branch_kernel=kernel)
            samples = []
            for _ in range(args.repeat):
                start = time.perf_counter()
                simulate(scene, stepper, branch_kernel=kernel)
                samples.append(time.perf_counter() - start)
            ns = float(np.median(samples)) / STEPS * 1e9
            rows.append({"stepper": stepper, "kernel": kernel, "n": n, "ns_per_step": f"{ns:.1f}"})
            print(rows[-1], flush=True)
    write_rows(os.path.join(args.out, "branch_scaling.csv"), rows)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5), layout="constrained")
    for index, (stepper, kernel) in enumerate(runs):
        chosen = [r for r in rows if r["stepper"] == stepper and r["kernel"] == kernel]
        ax.loglog([r["n"] for r in chosen], [float(r["ns_per_step"]) for r in chosen],
                  "o-" if kernel == "stack" else "s--", color=f"C{index % 4}", label=f"{stepper} ({kernel})")
    ax.set(xlabel="number of branches n", ylabel="ns per step", title="Cost per step against n")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.savefig(os.path.join(args.out, "branch_scaling.png"), dpi=120)
    print(f"written: {args.out}/branch_scaling.png")


if __name__ == "__main__":
    main()
