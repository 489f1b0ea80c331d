"""The strong order of the noisy steppers, measured on one path refined (the numbers of docs/white-noise.md).

Problem: the element of tests/noise/test_schemes.py (7 branches, m = 0.8, x0 = 0.01, v0 = -0.2, harmonic load
0.6 cos(1.3 t) + 0.05 plus a white noise of sigma = 0.7 N sqrt(s), noise_unit = 2^-3 s) with the effects
named on the command line, run to 4 s with h = 2^-3 .. 2^-9 s and a reference at 2^-12 s, all on the same
path per seed (the tree's points are shared by every h). The strong error is the mean over ``--seeds`` seeds
of max_t |x_h(t) - x_ref(t)| on a 2^-3 s grid; the order is the least-squares slope of log(error) on log(h).

    python benchmarks/noise_order.py [--seeds 8] [--out out/noise_order.csv]
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
from common import write_rows  # noqa: E402
from prandtl_fmu import simulate  # noqa: E402
from tests.noise.test_schemes import scene_of, tables_with_branches  # noqa: E402

ROOT = os.path.join(os.path.dirname(__file__), "..")
CASES = (("implicit", ("spring", "damper")), ("projected", ("spring", "damper")),
         ("implicit", ("friction", "spring")), ("projected", ("friction", "series", "damper")))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "noise_order.csv"))
    args = parser.parse_args()
    levels, reference = list(range(3, 10)), 12
    rows = []
    for stepper, effects in CASES:
        errors = np.zeros(len(levels))
        for seed in range(1, args.seeds + 1):
            runs = {}
            for level in levels + [reference]:
                tables = tables_with_branches(stepper, effects)
                tables["load"].update(noise_seed=seed, noise_unit=2.0 ** -3)
                tables["solver"].update(step=2.0 ** -level, stop_time=4.0, output_interval=2.0 ** -3)
                runs[level] = simulate(scene_of(tables)).x
            errors += [np.max(np.abs(runs[level] - runs[reference])) for level in levels]
        errors /= args.seeds
        slope = np.polyfit(np.log(2.0 ** -np.array(levels)), np.log(errors), 1)[0]
        rows.append({"stepper": stepper, "effects": "+".join(effects), "order": round(slope, 3),
                     **{f"error_h=2^-{level}": f"{error:.3e}" for level, error in zip(levels, errors)}})
        print(f"{stepper:9s} {'+'.join(effects):28s} order {slope:.3f}   error at 2^-9 s: {errors[-1]:.2e} m")
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
