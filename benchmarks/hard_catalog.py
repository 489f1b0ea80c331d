"""Run the catalog of hard scenes (scenes/hard) with every stepper that applies and report.

For each scene and stepper: steps, wall time, the largest |u_i| / eta_i, the
energy balance residual relative to the work done (positive: dissipated by
the scheme, negative: created), and what was said (stability warning,
error). Writes out/hard_catalog.csv and prints a Markdown table.

    python benchmarks/hard_catalog.py [--out out/hard_catalog.csv]
"""
import argparse
import os
import sys
import time
import warnings

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, ROOT)
from common import write_rows  # noqa: E402

from prandtl_fmu import STEPPERS, load_scene, simulate  # noqa: E402
from prandtl_fmu.stepping import ElementError  # noqa: E402
from prandtl_fmu.stability import StabilityWarning  # noqa: E402
from prandtl_fmu.steppers import get_stepper  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "hard_catalog.csv"))
    args = parser.parse_args()
    folder = os.path.join(ROOT, "scenes", "hard")
    rows = []
    for file in sorted(os.listdir(folder)):
        scene = load_scene(os.path.join(folder, file))
        for stepper in STEPPERS:
            try:
                get_stepper(stepper).loop_for(scene)
            except ValueError:
                continue
            states = scene.branches.n <= 1000
            energy = True
            try:  # compile
                simulate(scene.with_solver(stop_time=scene.solver.step * 10, output_interval=scene.solver.step),
                         stepper, energy=energy, states=states)
            except ElementError:
                pass
            said = ""
            start = time.perf_counter()
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", StabilityWarning)
                try:
                    result = simulate(scene, stepper, energy=energy, states=states)
                except ElementError as exc:
                    result, said = None, "error: " + str(exc).split(": ", 1)[1].split(":")[0]
            seconds = time.perf_counter() - start
            if caught:
                said = "warning: beyond the stability limit"
            row = {"scene": file[:-5], "stepper": stepper,
                   "steps": round(scene.solver.stop_time / scene.solver.step), "seconds": f"{seconds:.2f}"}
            if result is not None:
                if result.energy is not None:
                    work = max(np.abs(result.energy["work"]).max(), 1e-300)
                    residual = f'{result.energy["energy_residual"][-1] / work:+.2e}'
                else:
                    residual = "no account"
                ratio = (np.abs(result.u) / np.maximum(scene.branches.yield_displacement, 1e-300)).max() \
                    if result.u is not None else float("nan")
                finite = all(np.all(np.isfinite(c)) for c in result.columns().values())
                row.update(finite=finite, max_u_over_eta=f"{ratio:.3g}", residual_over_work=residual)
            else:
                row.update(finite="", max_u_over_eta="", residual_over_work="")
            row["said"] = said
            rows.append(row)
            print(row, flush=True)
    fields = ["scene", "stepper", "steps", "seconds", "finite", "max_u_over_eta", "residual_over_work", "said"]
    write_rows(args.out, rows, fields)
    print("\n| " + " | ".join(fields) + " |\n|" + "---|" * len(fields))
    for row in rows:
        print("| " + " | ".join(str(row[f]) for f in fields) + " |")


if __name__ == "__main__":
    main()
