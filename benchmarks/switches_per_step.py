"""How often a slider switches inside a communication step on the paper's scene, and what it costs a master that
extrapolates the element's outputs with their derivatives (issue 61, item 5).

The paper's scene (100 branches, eta from 0.1 to 1.1, F = 0.45 cos(0.5 t)) run by the exact stepper over two periods
of its steady cycle (t from 8 pi to 16 pi), sampled every millisecond. A switch is an instant where the tangent
stiffness for the motion ahead (the output ``stiffness``) changes: a branch starts or stops sliding, or the motion
reverses. For each communication step H it counts the steps that hold a switch, and compares, separately for the
steps with and without one, the local error of the second-order extrapolation a master makes from the outputs'
derivatives at the step's start (the FMU's ``fmi2GetRealOutputDerivatives``: x with v and a, v with a and a';
a' = (F' - R') / m with F' the force's own rate):

    x(tc + H) ~ x + v H + a H^2 / 2,    v(tc + H) ~ v + a H + a' H^2 / 2

Without a switch the local error of v is O(H^3); a switch inside the step makes a' jump (by the switching branch's
stiffness times v / m), and the error is O(H^2) there. Printed: a Markdown table (docs/connector.md).

    python benchmarks/switches_per_step.py
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from prandtl_fmu import load_scene  # noqa: E402
from prandtl_fmu.element import Element  # noqa: E402

SAMPLE = 1e-3  # s
STEPS = (0.5, 0.2, 0.1, 0.05, 0.02, 0.01)  # s: each a multiple of SAMPLE
AMPLITUDE, OMEGA = 0.45, 0.5  # the paper's force


def trajectory():
    """Samples every SAMPLE s over two periods of the steady cycle: t, x, v, a, a', stiffness."""
    element = Element(load_scene(str(ROOT / "scenes" / "paper-section-8.toml")), stepper="exact")
    period = 2 * math.pi / OMEGA
    element.advance(2 * period, 0.0, scene_load=True)
    count = round(2 * period / SAMPLE)
    rows = np.empty((count + 1, 6))
    for j in range(count + 1):
        if j:
            element.advance(SAMPLE, 0.0, scene_load=True)
        t = element.time
        force, rate = AMPLITUDE * math.cos(OMEGA * t), -AMPLITUDE * OMEGA * math.sin(OMEGA * t)
        found = element.output_derivatives(force)
        rows[j] = (t, element.x, element.v, found[("v", 1)], found[("v", 2)] + rate / element.scene.mass.m,
                   element.stiffness())
    return rows


def measure(rows) -> list:
    """Per H: (H, steps, steps with a switch, max local error of x and of v in steps without and with one)."""
    t, x, v, a, jerk, stiffness = rows.T
    switched = np.concatenate([[False], stiffness[1:] != stiffness[:-1]])  # a switch in (t_j-1, t_j]
    found = []
    for H in STEPS:
        every = round(H / SAMPLE)
        starts = np.arange(0, len(t) - every, every)
        ends = starts + every
        crossing = np.array([switched[s + 1:e + 1].any() for s, e in zip(starts, ends)])
        error_x = np.abs(x[starts] + v[starts] * H + a[starts] * H ** 2 / 2 - x[ends])
        error_v = np.abs(v[starts] + a[starts] * H + jerk[starts] * H ** 2 / 2 - v[ends])
        found.append((H, len(starts), int(crossing.sum()), error_x[~crossing].max(initial=0.0),
                      error_x[crossing].max(initial=0.0), error_v[~crossing].max(initial=0.0),
                      error_v[crossing].max(initial=0.0)))
    return found


def table(found) -> str:
    lines = ["| H (s) | steps | with a switch | x error, no switch | x error, switch | v error, no switch | "
             "v error, switch |", "|---|---|---|---|---|---|---|"]
    for H, steps, crossing, x_smooth, x_switch, v_smooth, v_switch in found:
        lines.append(f"| {H:g} | {steps} | {crossing} ({100 * crossing / steps:.0f} %) | {x_smooth:.2e} | "
                     f"{x_switch:.2e} | {v_smooth:.2e} | {v_switch:.2e} |")
    orders = []
    for column in range(3, 7):
        values = np.array([row[column] for row in found])
        usable = values > 0
        orders.append(np.polyfit(np.log(np.array(STEPS)[usable]), np.log(values[usable]), 1)[0])
    lines.append("| fitted order (local) | | | " + " | ".join(f"{order:.2f}" for order in orders) + " |")
    return "\n".join(lines)


def main() -> None:
    rows = trajectory()
    t, stiffness = rows[:, 0], rows[:, 5]
    switches = int(np.count_nonzero(stiffness[1:] != stiffness[:-1]))
    print(f"{switches} switches over {t[-1] - t[0]:.2f} s ({switches / (t[-1] - t[0]):.1f} per second, sampled every "
          f"{SAMPLE:g} s)\n")
    print(table(measure(rows)))


if __name__ == "__main__":
    main()
