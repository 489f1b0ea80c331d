"""Nanoseconds per move of the branch kernels against n: the O(n) play kernel and the memory stack.

Problem: n branches sampled from the paper's spectrum (k_i = 1/n, eta_i = 0.1 + i/n),
x(t) = 0.9 cos(0.5 t) sampled every 1e-3 s over 200 s (2e5 moves), repeated,
median of interleaved repeats. This measures the kernels alone (the
steppers add their own arithmetic and the load).

    python benchmarks/stack_cost.py [--repeat 5] [--out out/stack_cost.csv]
"""
import argparse
import os
import sys
import time

import numpy as np
from numba import njit

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, ROOT)
from common import write_rows  # noqa: E402
from prandtl_fmu.kernels import play, stack  # noqa: E402


@njit
def drive_play(k, eta, u, xs):
    total = 0.0
    for p in range(1, xs.shape[0]):
        total += play.shift(k, eta, u, xs[p] - xs[p - 1])
    return total


@njit
def drive_stack(params, state, xs):
    total = 0.0
    for p in range(1, xs.shape[0]):
        total += stack.move(params, state, xs[p] - xs[p - 1], None)
    return total


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "stack_cost.csv"))
    args = parser.parse_args()
    xs = 0.9 * np.cos(0.5 * np.arange(200_001) * 1e-3)
    rows = []
    for n in (10, 100, 1_000, 10_000, 100_000):
        eta = 0.1 + np.arange(1, n + 1) / n
        k = np.full(n, 1.0 / n)
        params, _ = stack.prepare(k, eta, np.zeros(n))
        state = stack.fresh_state(params, xs[0])
        u = np.zeros(n)
        drive_play(k, eta, u, xs[:10])
        drive_stack(params, state, xs[:10])
        timings = {"play": [], "stack": []}
        for _ in range(args.repeat):
            start = time.perf_counter()
            drive_play(k, eta, u, xs)
            timings["play"].append(time.perf_counter() - start)
            start = time.perf_counter()
            drive_stack(params, state, xs)
            timings["stack"].append(time.perf_counter() - start)
        row = {"n": n}
        for name, values in timings.items():
            row[f"{name}_ns_per_move"] = f"{np.median(values) / (len(xs) - 1) * 1e9:.1f}"
        rows.append(row)
        print(row, flush=True)
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
