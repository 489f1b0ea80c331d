"""What an effect with memory costs per time step, against the 7-branch element without it (issue 35's goal: a
delay buffer and an exponential history each under 20 % of the element's step).

Problem: a mass, a spring, a dashpot and n = 7 branches under a harmonic force, h = 1e-3, run for ``--steps``
steps with ``implicit`` and ``projected``, alone and with [delay] (tau = 0.1234 s: interpolated, not a multiple
of h), [history] (one term, three terms), [dahl], and all three. Timing: every configuration ``--repeat``
times, interleaved, after a warm-up that compiles it; the median, with its ratio to the base measured in the
same run.

    python benchmarks/memory_cost.py [--steps 200000] [--repeat 7] [--out out/memory_cost.csv]
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

ROOT = os.path.join(os.path.dirname(__file__), "..")
BASE = """
[mass]
m = 1.0
[spring]
k0 = 1.0
[damper]
c = 0.05
[branches]
k = [1.0, 0.8, 0.6, 0.5, 0.4, 0.3, 0.2]
eta = [0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5]
[load]
kind = "harmonic"
amplitude = 1.5
omega = 1.1
"""
EFFECTS = {
    "base (7 branches)": "",
    "+ delay": "[delay]\ngain = 0.3\ntau = 0.1234\n",
    "+ history, 1 term": "[history]\nweight = [0.2]\nrate = [1.5]\n",
    "+ history, 3 terms": "[history]\nweight = [0.2, 0.1, 0.05]\nrate = [1.5, 0.3, 7.0]\n",
    "+ dahl": "[dahl]\nsigma = 20.0\nforce = 0.3\n",
    "+ all three": "[delay]\ngain = 0.3\ntau = 0.1234\n[history]\nweight = [0.2]\nrate = [1.5]\n"
                   "[dahl]\nsigma = 20.0\nforce = 0.3\n",
}


def scene(extra, stepper, steps):
    return parse_scene(BASE + extra + f'[solver]\nstepper = "{stepper}"\nstep = 1e-3\nstop_time = {steps * 1e-3!r}\n'
                       "output_interval = 1.0\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "memory_cost.csv"))
    args = parser.parse_args()
    rows = []
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    for stepper in ("implicit", "projected"):
        scenes = {name: scene(extra, stepper, args.steps) for name, extra in EFFECTS.items()}
        for name, extra in EFFECTS.items():  # compile
            simulate(scene(extra, stepper, 1000))
        times = {name: [] for name in scenes}
        for _ in range(args.repeat):
            for name, s in scenes.items():
                start = time.perf_counter()
                simulate(s)
                times[name].append(time.perf_counter() - start)
        reference = np.median(times["base (7 branches)"])
        print(f"\nstepper {stepper}: {args.steps} steps")
        for name, samples in times.items():
            median = np.median(samples)
            ns = median / args.steps * 1e9
            rows.append({"stepper": stepper, "scene": name, "ns_per_step": f"{ns:.1f}",
                         "ratio_to_base": f"{median / reference:.3f}"})
            print(f"  {name:22s} {ns:8.1f} ns/step   x{median / reference:.3f}")
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
