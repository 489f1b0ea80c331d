"""What the Brownian path costs: ns per increment stepping forward, and at random times.

Problem: ``prandtl_fmu.noise.increment(seed, a, b, cache)`` (W(b) - W(a) of the virtual Brownian tree) called
the way a stepper calls it, over [t_n, t_n + h] with one cache, for ``--steps`` steps from t = 0 and from
t = 1e6 units: with dyadic steps (h = 2^-10, 2^-20 units: the step times are points of the tree, about one
draw per step) and with h = 1e-3 (every step time has all its fraction bits: the levels below the step's
are drawn at each step). Random access: increments over [t, t + 1e-3] at uniform times in [0, 1e6], one
cache. For scale, the cost of one standard normal of the generator (a ziggurat on Philox4x32-10 blocks) and
of one Philox block alone. No reference solution: the tests (tests/noise/test_brownian_path.py) check the values;
this script counts the normals drawn (``cache[DRAWS]``) and times the loops (the median of ``--repeat``
runs, after a warm-up that compiles them). For the issue's goal (noise under 2x the deterministic step), the
same run times the deterministic step it is to be added to: the paper's section 8 scene with 7 branches,
``implicit`` and ``projected``, per step (``--no-reference`` skips it).

    python benchmarks/noise_cost.py [--steps 1000000] [--repeat 5] [--out out/noise_cost.csv]
"""
import argparse
import os
import platform
import sys
import time

import numpy as np
from numba import njit

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from common import write_rows  # noqa: E402
from prandtl_fmu import noise  # noqa: E402

ROOT = os.path.join(os.path.dirname(__file__), "..")


@njit
def step_forward(seed, t0, h, n, cache):
    total = 0.0
    a = t0
    for i in range(1, n + 1):
        b = t0 + i * h
        total += noise.increment(seed, a, b, cache)
        a = b
    return total


@njit
def random_access(seed, starts, h, cache):
    total = 0.0
    for i in range(starts.shape[0]):
        total += noise.increment(seed, starts[i], starts[i] + h, cache)
    return total


@njit
def normals(seed, n):
    total = 0.0
    for i in range(n):
        total += noise.normal(seed, 7, i)
    return total


@njit
def blocks(seed, n):
    total = 0.0
    for i in range(n):
        x0, _, _, _ = noise.philox4x32_10(np.uint64(i) & np.uint64(0xFFFFFFFF), np.uint64(i) >> np.uint64(32),
                                          np.uint64(7), np.uint64(0), np.uint64(seed), np.uint64(0))
        total += np.float64(x0)
    return total


def reference_steps(steps):
    """The deterministic step of the paper's section 8 scene with 7 branches, per stepper: [(name, run, steps)]."""
    from prandtl_fmu import parse_scene, simulate

    path = os.path.join(ROOT, "scenes", "paper-section-8.toml")
    with open(path) as fh:
        scene = parse_scene(fh.read().replace("count = 100", "count = 7"), path)
    h = scene.solver.step
    cases = []
    for stepper in ("implicit", "projected"):
        simulate(scene.with_solver(stop_time=10 * h, output_interval=h), stepper)  # compile
        run_scene = scene.with_solver(stop_time=steps * h, output_interval=1000 * h)
        cases.append((f"deterministic {stepper} step, 7 branches", lambda s=stepper: simulate(run_scene, s) and 0,
                      steps))
    return cases


def timed(run, repeat):
    """The median wall time of ``run()`` and what its last call returned (the draws)."""
    times, draws = [], 0
    for _ in range(repeat):
        start = time.perf_counter()
        draws = run()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), draws


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "noise_cost.csv"))
    parser.add_argument("--no-reference", action="store_true", help="do not time the deterministic step")
    args = parser.parse_args()
    n = args.steps
    seed = 20250101
    # warm-up: compile every loop
    step_forward(seed, 0.0, 1e-3, 10, noise.new_cache())
    random_access(seed, np.ones(2), 1e-3, noise.new_cache())
    normals(seed, 10)
    blocks(seed, 10)

    def forward(t0, h):
        def run():
            cache = noise.new_cache()
            step_forward(seed, t0, h, n, cache)
            return cache[noise.DRAWS]
        return run

    starts = np.random.default_rng(1).uniform(0.0, 1e6, n // 10)

    def scattered():
        cache = noise.new_cache()
        random_access(seed, starts, 1e-3, cache)
        return cache[noise.DRAWS]

    cases = [(f"forward h = {label} from t = {t0:g}", forward(t0, h), n)
             for t0 in (0.0, 1e6) for label, h in (("2^-10", 2.0 ** -10), ("2^-20", 2.0 ** -20), ("1e-3", 1e-3))]
    cases.append(("random access, h = 1e-3, t in [0, 1e6]", scattered, starts.size))
    cases.append(("one normal (Philox4x32-10 + ziggurat)", lambda: normals(seed, n) * 0 + n, n))
    cases.append(("one Philox4x32-10 block", lambda: blocks(seed, n) * 0, n))
    if not args.no_reference:
        cases += reference_steps(n // 5)
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}, "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    rows = []
    for name, run, count in cases:
        seconds, draws = timed(run, args.repeat)
        rows.append({"case": name, "calls": count, "ns_per_call": round(seconds / count * 1e9, 1),
                     "normals_per_call": round(draws / count, 3)})
        print(f"{name:45s} {rows[-1]['ns_per_call']:9.1f} ns   {rows[-1]['normals_per_call']:7.3f} normals")
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
