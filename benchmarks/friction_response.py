"""Friction on the mass: the curve by shooting (``frequency/shooting.py``) against the time-integration sweep.

Problem: the friction damper of docs/frequency.md with Coulomb friction on the mass instead of a branch (m = 1
kg, k0 = 1 N/m, c = 0.02 N s/m, alpha = 0.1 N) under F0 = 0.3 N cos(2 pi f t), f from 0.05 to 0.3 Hz (through
its resonance at 0.16 Hz; below about 0.1 Hz the mass sticks for part of each period).

Measured, in one run of this script:

* ``curve``: :func:`harmonic_response` (shooting, the exact stepper), warm, with and without the stability of
  every point: its points and its time;
* ``sweep``: :func:`frequency_response` (``--method time``, the exact stepper) at 20 frequencies up and down at
  the default tolerance 1e-3, warm: its time;
* ``difference``: the sweep at 1e-5 at every sixth point of the curve against the curve (amplitude relative,
  phase in rad);
* ``one harmonic``: the describing function's balance (K = k0, D = 4 alpha A + pi c omega A^2) against the
  curve: the largest relative error of the amplitude and where.

    python benchmarks/friction_response.py [--out docs/bench/friction_response.csv]
"""
import argparse
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from common import write_rows  # noqa: E402
from prandtl_fmu.frequency import parse_scene  # noqa: E402
from prandtl_fmu.frequency.curve import harmonic_response  # noqa: E402
from prandtl_fmu.frequency.response import frequency_response  # noqa: E402

SCENE = """
name = "friction-damper-coulomb"
[mass]
m = 1.0
[spring]
k0 = 1.0
[damper]
c = 0.02
[friction]
alpha = 0.1
"""
FORCE = 0.3
LOW, HIGH = 0.05, 0.3


def one_harmonic(omega: float, m=1.0, k=1.0, c=0.02, alpha=0.1, F0=FORCE) -> float:
    """|X| of (k - m w^2) X + i (c w X + 4 alpha / pi) = F0 in magnitude: 0 where friction holds the mass."""
    a = (k - m * omega**2) ** 2 + (c * omega) ** 2
    b = 2 * c * omega * 4 * alpha / math.pi
    d = (4 * alpha / math.pi) ** 2 - F0**2
    disc = b * b - 4 * a * d
    return max((-b + math.sqrt(disc)) / (2 * a), 0.0) if disc >= 0 else 0.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join("docs", "bench", "friction_response.csv"))
    args = parser.parse_args()
    scene = parse_scene(SCENE, "friction-damper-coulomb")[0]
    rows = []
    harmonic_response(scene, FORCE, [LOW, HIGH])  # compiles
    for stability in (False, True):
        started = time.perf_counter()
        curve = harmonic_response(scene, FORCE, [LOW, HIGH], stability=stability)
        elapsed = time.perf_counter() - started
        rows.append({"measure": f"curve {'with' if stability else 'without'} stability", "value": elapsed,
                     "unit": "s", "note": f"{curve.frequency.size} points"})
        print(rows[-1])
    frequencies = np.linspace(LOW, HIGH, 20)
    frequency_response(scene, FORCE, frequencies[:2], sweep="up")  # compiles
    started = time.perf_counter()
    frequency_response(scene, FORCE, frequencies, sweep="both")
    rows.append({"measure": "sweep 20 frequencies up and down", "value": time.perf_counter() - started, "unit": "s",
                 "note": "exact stepper, tolerance 1e-3"})
    print(rows[-1])
    picks = np.arange(0, curve.frequency.size, 6)
    reference = frequency_response(scene, FORCE, curve.frequency[picks], sweep="up", tolerance=1e-5)
    rows.append({"measure": "difference of the amplitude", "value": float(np.max(np.abs(
        reference.amplitude / curve.amplitude[picks] - 1))), "unit": "relative",
        "note": f"the sweep at 1e-5 at {picks.size} points of the curve"})
    rows.append({"measure": "difference of the phase", "value": float(np.max(np.abs(
        reference.phase - curve.phase[picks]))), "unit": "rad", "note": f"{picks.size} points"})
    single = np.array([one_harmonic(2 * math.pi * f) for f in curve.frequency])
    error = np.abs(single / curve.amplitude - 1)
    worst = int(np.argmax(error))
    rows.append({"measure": "one harmonic's error", "value": float(error[worst]), "unit": "relative",
                 "note": f"at {curve.frequency[worst]:.4f} Hz; median {float(np.median(error)):.3g}"})
    for row in rows[-3:]:
        print(row)
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
