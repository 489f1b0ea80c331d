"""What a white noise costs a step of the element: the noisy step against the same deterministic step.

Problem: the paper's section 8 scene with 7 branches (count = 7; m = 1, k_i = 1/7, F = 0.45 cos(0.5 t)),
h = 1e-3 s, stepped by ``implicit`` (backward Euler-Maruyama) and ``projected`` (Euler-Maruyama): without
noise, then with ``noise_intensity = 0.1`` (issue 34's goal: the noisy step under 2x the deterministic one)
for two Brownian tree units: ``noise_unit = 1e-3`` s (= h: every step time is a point of the tree, one normal
per step) and the default ``noise_unit = 1`` s (h = 1e-3 units: each step time carries about 40 fraction
bits, and the levels below the step's are drawn at every step). Also ``noise_intensity = 0`` written out
(no noise at all: the scene has no noise, the deterministic code runs). No reference solution (the tests
check the values: tests/noise/test_schemes.py); ns per step from the wall time of ``--repeat`` runs of ``--steps``
steps (one output row per 1000 steps) after a warm-up that compiles every loop: the fastest run (the least
disturbed by the other processes of a shared machine; the ratios are taken on it) and the median.

    python benchmarks/noise_step.py [--steps 1000000] [--repeat 7] [--out out/noise_step.csv]
"""
import argparse
import os
import platform
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from common import write_rows  # noqa: E402
from prandtl_fmu import parse_scene, simulate  # noqa: E402
from prandtl_fmu.scene import scene_path  # noqa: E402

ROOT = os.path.join(os.path.dirname(__file__), "..")
CASES = (("deterministic", ""),
         ("noise_intensity = 0", "noise_intensity = 0.0\nnoise_seed = 1\n"),
         ("noise, noise_unit = h = 1e-3 s", "noise_intensity = 0.1\nnoise_seed = 1\nnoise_unit = 1e-3\n"),
         ("noise, noise_unit = 1 s (default)", "noise_intensity = 0.1\nnoise_seed = 1\n"))


def scene_with(noise_keys: str):
    path = scene_path("paper-section-8")
    with open(path) as fh:
        text = fh.read().replace("count = 100", "count = 7").replace("offset = 0.0\n", "offset = 0.0\n" + noise_keys)
    return parse_scene(text, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "noise_step.csv"))
    args = parser.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}, "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    rows = []
    for stepper in ("implicit", "projected"):
        base = None
        for label, keys in CASES:
            scene = scene_with(keys)
            h = scene.solver.step
            simulate(scene.with_solver(stop_time=10 * h, output_interval=h), stepper)  # compile
            run = scene.with_solver(stop_time=args.steps * h, output_interval=1000 * h)
            times = []
            for _ in range(args.repeat):
                start = time.perf_counter()
                simulate(run, stepper)
                times.append(time.perf_counter() - start)
            ns = min(times) / args.steps * 1e9
            median = float(np.median(times)) / args.steps * 1e9
            base = base or ns
            rows.append({"stepper": stepper, "case": label, "ns_per_step": round(ns, 1),
                         "median_ns_per_step": round(median, 1), "ratio_to_deterministic": round(ns / base, 2),
                         "load_average": round(os.getloadavg()[0], 1)})
            print(f"{stepper:9s} {label:36s} {ns:8.1f} ns/step (median {median:7.1f})  {ns / base:5.2f}x")
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
