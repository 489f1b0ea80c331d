"""Harmonic balance against the time-integration sweep: a whole curve through both folds, and the error against H.

Problem: two masses of 1 kg, each on a spring of 1 N/m and a dashpot of 0.02 N s/m to the ground, the first on a
cubic spring k3 = 0.5 N/m^3 too, joined by a joint of 20 Prandtl branches (k_i = 0.1 N/m, eta_i from 0.005 to
0.1 m: an Iwan joint of total stiffness 2 N/m); F0 cos(2 pi f t) on the first, f from 0.1 to 0.4 Hz. The cubic
spring bends the first resonance to the right: two folds, an unstable branch between them.

Measured, in one run of this script:

* ``curve``: :func:`harmonic_response` with H = 7 (512 samples per period) and 200 listed frequencies, warm
  (a first curve compiles), with and without the stability of every point: its points, its folds, its time;
* ``error_vs_H``: the first harmonic of x_a at four frequencies (two on the upper branch, one on the lower, one
  past the folds) for H = 1, 3, 5, 7, 11, 15, against H = 21;
* ``sweep``: the reference, the network run period by period with its own ``implicit`` stepper (backward
  Euler) at M steps per period from the previous frequency's state until the first harmonic changes by less
  than 1e-5 relative per period, at the same four frequencies (the upper branch swept up to them, the lower one
  down), with M = 2048 and 8192: its time per frequency, its difference from H = 21 (backward Euler is first
  order: the difference falls as 1 / M), and the time a 200-frequency sweep would take at that cost.

    python benchmarks/harmonic_balance.py [--out docs/bench/harmonic_balance.csv] [--no-sweep]
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
from prandtl_fmu.frequency.floquet import run_periods  # noqa: E402
from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system  # noqa: E402

FORCE = 0.2
LOW, HIGH = 0.1, 0.4


def scene_text(branches: int = 20) -> str:
    lines = ['name = "two-mass-iwan-joint"', "[network]", 'nodes = ["a", "b"]', "mass = [1.0, 1.0]",
             'load_node = "a"']
    for node in ("a", "b"):
        lines += ["[[network.spring]]", f'between = ["{node}", "ground"]', "k = 1.0",
                  "[[network.dashpot]]", f'between = ["{node}", "ground"]', "c = 0.02"]
    lines += ["[[network.cubic]]", 'between = ["a", "ground"]', "k3 = 0.5"]
    for eta in np.linspace(0.005, 0.1, branches).tolist():
        lines += ["[[network.branch]]", 'between = ["a", "b"]', f"k = {2.0 / branches!r}", f"eta = {eta!r}"]
    return "\n".join(lines) + "\n"


def first_harmonic(balance, q) -> complex:
    full = balance.full(q)
    return complex(full[1], -full[2])


def sweep_to(balance, omega_path, steps, tolerance=1e-5, max_periods=20000):
    """The network swept along ``omega_path`` (rad/s), each frequency settled from the last one's state (the
    first from rest): the first harmonic of x_a at the last frequency, and the time taken per frequency."""
    n = balance.system.n
    state = (np.zeros(n), np.zeros(n), np.zeros(len(balance.system.network.elements)))
    weights = np.exp(-1j * 2 * math.pi * np.arange(1, steps + 1) / steps) * 2 / steps
    started = time.perf_counter()
    X = None
    for omega in omega_path:
        previous = None
        for _ in range(max_periods):
            x, state = run_periods(balance, omega, state, 1, steps)
            X = complex(x[:, 0] @ weights)
            if previous is not None and abs(X - previous) <= tolerance * abs(X):
                break
            previous = X
    return X, (time.perf_counter() - started) / len(omega_path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join("docs", "bench", "harmonic_balance.csv"))
    parser.add_argument("--no-sweep", action="store_true", help="the harmonic balance only (the sweep takes minutes)")
    args = parser.parse_args()
    scene, _ = parse_scene(scene_text(), "two-mass-iwan-joint", networks=True)
    frequencies = np.linspace(LOW, HIGH, 200)
    rows = []
    harmonic_response(scene, FORCE, frequencies, harmonics=7)  # compiles
    for stability in (False, True):
        started = time.perf_counter()
        curve = harmonic_response(scene, FORCE, frequencies, harmonics=7, stability=stability)
        elapsed = time.perf_counter() - started
        rows.append({"measure": f"curve H=7 {'with' if stability else 'without'} stability", "value": elapsed,
                     "unit": "s", "note": f"{curve.frequency.size} points, folds at "
                     + " and ".join(f"{f:.5f}" for f in curve.frequency[curve.folds]) + " Hz"})
        print(rows[-1])
    folds = np.sort(curve.frequency[curve.folds])
    upper = curve.frequency[: curve.folds[0]]
    probes = [("upper", float(upper[len(upper) // 2])), ("upper", float(upper[int(len(upper) * 0.9)])),
              ("lower", float(0.5 * (folds[0] + folds[1]))), ("past", float(0.5 * (folds[1] + HIGH)))]
    system = periodic_system(scene)
    reference = {}
    for H in (21, 1, 3, 5, 7, 11, 15):
        balance = HarmonicBalance(system, H, FORCE)
        for branch, f in probes:
            points = harmonic_response(scene, FORCE, [LOW, f], harmonics=H, stability=False) if branch == "upper" \
                else harmonic_response(scene, FORCE, [LOW, HIGH], harmonics=H, stability=False)
            if branch == "upper":
                X = points.amplitude[-1]
            else:  # on the lower or past branch: the point of the curve after the last fold at f, by Newton
                start = int(np.max(points.folds)) if branch == "lower" else len(points.frequency) - 1
                later = np.flatnonzero(points.frequency[start:] >= f)
                index = start + int(later[0]) if later.size else len(points.frequency) - 1
                q = points.coefficients[index].reshape(-1)[balance.free]
                X = abs(first_harmonic(balance, balance.solve_at(2 * math.pi * f, q)))
            if H == 21:
                reference[f] = X
            else:
                rows.append({"measure": f"error H={H} at {f:.4f} Hz ({branch})", "value": abs(X - reference[f]) /
                             reference[f], "unit": "relative", "note": f"|X| = {X:.6g} m"})
                print(rows[-1])
    for steps in () if args.no_sweep else (2048, 8192):
        for branch, f in probes:
            omega = 2 * math.pi * f
            path = np.linspace(2 * math.pi * (LOW if branch == "upper" else HIGH), omega, 8)
            X, per_frequency = sweep_to(HarmonicBalance(system, 1, FORCE), path, steps)
            rows.append({"measure": f"sweep M={steps} at {f:.4f} Hz ({branch})", "value": per_frequency,
                         "unit": "s per frequency", "note": f"difference from H=21: "
                         f"{abs(abs(X) - reference[f]) / reference[f]:.3g}; 200 frequencies: "
                         f"{200 * per_frequency:.4g} s"})
            print(rows[-1])
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
