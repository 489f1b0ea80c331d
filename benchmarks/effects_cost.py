"""What an effect costs per time step, and what an absent one costs (nothing).

Problem: the paper's section 8 scene (n = 100 branches, h = 1e-3), run for
``--steps`` steps with each stepper, alone and with a dashpot and/or a cubic
spring added, both with zero coefficients and with real ones, and with friction
on the mass or series dashpots in the branches. A table with a
zero coefficient is simulated (it is present). An absent table is not compiled
at all, but for the springs and the dashpot, which the library gives its loops as
zero coefficients (compiled.py): for them the base scene runs the code of the
zero rows.

Timing: every configuration is run ``--repeat`` times, interleaved, after a
warm-up that compiles it; the median is reported, with its ratio to the base
scene measured in the same run.

    python benchmarks/effects_cost.py [--steps 200000] [--repeat 7] [--out out/effects_cost.csv]
"""
import argparse
import os
import platform
import sys
import time
from dataclasses import replace

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from common import write_rows  # noqa: E402
from prandtl_fmu import parse_scene, simulate  # noqa: E402
from prandtl_fmu.effects import CubicSpring, Damper, Friction  # noqa: E402

ROOT = os.path.join(os.path.dirname(__file__), "..")


def variants(scene):
    return {
        "base (no dashpot, no cubic)": scene,
        "+ dashpot c = 0": replace(scene, damper=Damper(0.0)),
        "+ cubic k3 = 0": replace(scene, cubic=CubicSpring(0.0)),
        "+ dashpot c = 0.05": replace(scene, damper=Damper(0.05)),
        "+ cubic k3 = 0.05": replace(scene, cubic=CubicSpring(0.05)),
        "+ both": replace(scene, damper=Damper(0.05), cubic=CubicSpring(0.05)),
        # issue 25's effects, present: Coulomb friction on the mass, and series dashpots (the O(n) kernel)
        "+ friction alpha = 0.01": replace(scene, friction=Friction(0.01, 0.01, None, 0.0)),
        "+ series dashpots c = 1e3": replace(scene, branches=replace(
            scene.branches, damping=np.full(scene.branches.n, 1e3))),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "effects_cost.csv"))
    args = parser.parse_args()
    path = os.path.join(ROOT, "scenes", "paper-section-8.toml")
    rows = []
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    for count, stepper in [(n, s) for n in (3, 100) for s in ("projected", "implicit")]:
        with open(path) as fh:
            base = parse_scene(fh.read().replace("count = 100", f"count = {count}"), path)
        h = base.solver.step
        base = base.with_solver(stop_time=args.steps * h, output_interval=1000 * h)
        scenes = variants(base)
        for scene in scenes.values():  # compile
            simulate(scene.with_solver(stop_time=10 * h, output_interval=h), stepper)
        times = {name: [] for name in scenes}
        for _ in range(args.repeat):
            for name, scene in scenes.items():
                start = time.perf_counter()
                simulate(scene, stepper)
                times[name].append(time.perf_counter() - start)
        reference = np.median(times["base (no dashpot, no cubic)"])
        print(f"\nstepper {stepper}: {args.steps} steps, n = {base.branches.n}")
        for name, samples in times.items():
            median = np.median(samples)
            ns = median / args.steps * 1e9
            rows.append({"stepper": stepper, "n": count, "scene": name, "ns_per_step": f"{ns:.1f}",
                         "ratio_to_base": f"{median / reference:.3f}"})
            print(f"  {name:30s} {ns:8.1f} ns/step   x{median / reference:.3f}")
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
