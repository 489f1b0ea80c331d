"""Masing models given by their backbone ([masing]): the element's loops against the Masing rules.

    python examples/masing_figures.py [--out docs/masing/loops.png]

Each of the three backbones of docs/masing.md is read as a scene ([masing] kind = ...) and driven, as the
connector, by x(t) = x_max exp(-t / 4) sin(2 pi t) with a small offset, sampled 200 times a cycle over eight
cycles (decaying amplitude: nested loops, each reversal below the last). Top: the loops of the element (count =
10 branches for the smooth backbones, so that the interpolation shows; the bilinear is exact with one) over the
extended Masing rules written out below (reversal stack, return-point memory) on the exact backbone. Bottom: the
force error |F_N - F| along the same history for count = 25, 50, 100, 200, against the bound (D + 1) e_max
(D the reversals on the stack, e_max the interpolation error of the backbone), which falls like 1 / count^2.
"""
import argparse
import math
import os
import sys

import numpy as np

from prandtl_fmu import parse_scene
from prandtl_fmu.connector import displacement_response
from prandtl_fmu.masing import Bilinear, Hyperbolic, RambergOsgood, interpolation_error

CASES = [
    ("bilinear", {"kind": "bilinear", "k": 100.0, "f_y": 1.0, "alpha": 0.1}, Bilinear(100.0, 1.0, 0.1), 0.05),
    ("hyperbolic", {"kind": "hyperbolic", "k": 1000.0, "f_u": 10.0}, Hyperbolic(1000.0, 10.0), 0.1),
    ("Ramberg-Osgood", {"kind": "ramberg_osgood", "k": 1000.0, "f_y": 10.0, "a": 0.5, "r": 5.0},
     RambergOsgood(1000.0, 10.0, 0.5, 5.0), 0.1),
]


def scene(table):
    keys = "\n".join(f"{key} = {value!r}" if not isinstance(value, str) else f'{key} = "{value}"'
                     for key, value in table.items())
    return parse_scene(f"[masing]\n{keys}\n[fmu]\ncausality = \"displacement\"\n"
                       "[solver]\nstep = 0.01\nstop_time = 1.0\noutput_interval = 0.01\n")


def masing_rules(backbone, xs):
    """Forces and stack depths of the extended Masing rules along xs (see tests/models/test_masing.py)."""
    stack, x, force, direction = [], 0.0, 0.0, 0.0
    forces, depths = np.empty(len(xs)), np.empty(len(xs), dtype=int)
    for j, target in enumerate(xs):
        step = math.copysign(1.0, target - x) if target != x else 0.0
        if step:
            if direction and step != direction:
                stack.append((x, force))
            direction = step
            while stack:
                end = stack[-2][0] if len(stack) >= 2 else -stack[0][0]
                if (target - end) * step < 0:
                    break
                del stack[-2 if len(stack) >= 2 else -1:]
            x = target
            force = stack[-1][1] + 2.0 * float(backbone.force((x - stack[-1][0]) / 2.0)) if stack \
                else float(backbone.force(x))
        forces[j], depths[j] = force, len(stack)
    return forces, depths


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join("docs", "masing", "loops.png"))
    args = parser.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.linspace(0.0, 8.0, 1601)[1:]
    fig, axes = plt.subplots(2, 3, figsize=(13, 7.5))
    for column, (title, table, backbone, x_max) in enumerate(CASES):
        xs = x_max * (np.exp(-t / 4.0) * np.sin(2 * np.pi * t) + 0.05 * np.sin(0.7 * np.pi * t))
        expected, depths = masing_rules(backbone, xs)
        top, bottom = axes[0, column], axes[1, column]
        top.plot(xs, expected, color="0.6", lw=3, label="Masing rules, exact backbone")
        if isinstance(backbone, Bilinear):
            top.plot(xs, displacement_response(scene(table), xs), "C3", lw=1, label="element: 1 branch + k0")
            error = np.abs(displacement_response(scene(table), xs) - expected)
            bottom.semilogy(t, np.maximum(error, 1e-17), "C0", lw=0.8, label="|F_N - F| (0: below 1e-17)")
            print(f"{title}: max |F_N - F| = {error.max():.3g} N")
        else:
            coarse = scene({**table, "x_max": x_max, "count": 10})
            top.plot(xs, displacement_response(coarse, xs), "C3", lw=1, label="element: count = 10")
            for shade, count in enumerate((25, 50, 100, 200)):
                element = scene({**table, "x_max": x_max, "count": count})
                error = np.abs(displacement_response(element, xs) - expected)
                points = np.concatenate([[0.0], element.branches.yield_displacement])
                e_max = interpolation_error(backbone, points)
                line, = bottom.semilogy(t, np.maximum(error, 1e-17), lw=0.8, color=f"C{shade}",
                                        label=f"count = {count}")
                bottom.semilogy(t, (depths + 1) * e_max, lw=0.8, ls="--", color=line.get_color())
                print(f"{title}: count = {count}: e_max = {e_max:.3g} N, max |F_N - F| = {error.max():.3g} N, "
                      f"max (D + 1) e_max = {((depths + 1) * e_max).max():.3g} N")
        top.set(title=title, xlabel="x (m)", ylabel="F (N)")
        top.legend(fontsize=8)
        bottom.set(xlabel="t (s)", ylabel="|F_N - F| (N); dashed: (D + 1) e_max")
        bottom.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
