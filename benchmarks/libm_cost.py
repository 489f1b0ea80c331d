"""What the portable elementary functions cost: ns per call of each of ``prandtl_fmu.libm`` beside numba's own
(``np.cos``, ``np.exp``, ... compiled to calls of the platform's libm, glibc here).

Problem: a compiled loop sums f(x_i) over ``--count`` arguments drawn once (fixed seed) from the range a kernel
meets: cos and sin of omega t over [0, 1e3] (Cody-Waite) and [1e6, 1e9] (Payne-Hanek above 2^20 pi/2 = 1.6e6),
exp and the other ones over the ranges in ``CASES``. Each loop is compiled before it is timed; the figure is
the median of ``--repeat`` runs divided by the count, loop and load included, ours and numba's run in turn
in every repeat so that both see the same load of a shared machine (an empty loop over the same array is
timed too, for scale). No reference solution: ``tests/steppers/test_libm.py`` checks the values; the two sums
are printed side by side as a sanity check (they agree to the functions' last bits).

    python benchmarks/libm_cost.py [--count 200000] [--repeat 21] [--out out/libm_cost.csv]

prints a markdown table (the one in docs/libm.md) and writes the CSV.
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
from prandtl_fmu import libm  # noqa: E402

ROOT = os.path.join(os.path.dirname(__file__), "..")


def _unary_loop(function):
    @njit
    def loop(xs, ys):
        total = 0.0
        for i in range(xs.shape[0]):
            total += function(xs[i])
        return total
    return loop


def _binary_loop(function):
    @njit
    def loop(xs, ys):
        total = 0.0
        for i in range(xs.shape[0]):
            total += function(xs[i], ys[i])
        return total
    return loop


def _sincos_loop(function):
    @njit
    def loop(xs, ys):
        total = 0.0
        for i in range(xs.shape[0]):
            s, c = function(xs[i])
            total += s + c
        return total
    return loop


@njit
def _np_sincos(x):
    return np.sin(x), np.cos(x)


@njit
def _empty(xs, ys):
    total = 0.0
    for i in range(xs.shape[0]):
        total += xs[i]
    return total


def _uniform(low, high):
    return lambda rng, n: rng.uniform(low, high, n)


def _log_uniform(low, high):
    return lambda rng, n: np.exp(rng.uniform(np.log(low), np.log(high), n))


# (name, arguments' range, ours, numba's, loop maker, draw of x, draw of y)
CASES = [
    ("cos", "[0, 1e3]", libm.cos, np.cos, _unary_loop, _uniform(0.0, 1e3), None),
    ("cos", "[1e6, 1e9]", libm.cos, np.cos, _unary_loop, _log_uniform(1e6, 1e9), None),
    ("sin", "[0, 1e3]", libm.sin, np.sin, _unary_loop, _uniform(0.0, 1e3), None),
    ("sincos", "[0, 1e3]", libm.sincos, _np_sincos, _sincos_loop, _uniform(0.0, 1e3), None),
    ("exp", "[-20, 20]", libm.exp, np.exp, _unary_loop, _uniform(-20.0, 20.0), None),
    ("expm1", "[-1, 1]", libm.expm1, np.expm1, _unary_loop, _uniform(-1.0, 1.0), None),
    ("log", "[1e-3, 1e3]", libm.log, np.log, _unary_loop, _log_uniform(1e-3, 1e3), None),
    ("log1p", "[-0.5, 2]", libm.log1p, np.log1p, _unary_loop, _uniform(-0.5, 2.0), None),
    ("acos", "[-1, 1]", libm.acos, np.arccos, _unary_loop, _uniform(-1.0, 1.0), None),
    ("cbrt", "[-1e3, 1e3]", libm.cbrt, np.cbrt, _unary_loop, _uniform(-1e3, 1e3), None),
    ("hypot", "[1e-3, 1e3]^2", libm.hypot, np.hypot, _binary_loop, _log_uniform(1e-3, 1e3),
     _log_uniform(1e-3, 1e3)),
    ("log2", "[1e-3, 1e3]", libm.log2, np.log2, _unary_loop, _log_uniform(1e-3, 1e3), None),
    ("pow", "[1e-3, 1e3] x [-3, 3]", libm.pow, np.power, _binary_loop, _log_uniform(1e-3, 1e3),
     _uniform(-3.0, 3.0)),
]


def _seconds(loop, xs, ys):
    start = time.perf_counter()
    loop(xs, ys)
    return time.perf_counter() - start


def _median_ns(loops, xs, ys, repeat):
    """Median ns per element of each loop, the loops run in turn in every repeat (on a shared machine they see
    the same load), and each loop's sum."""
    values = [loop(xs, ys) for loop in loops]  # compiles
    times = np.array([[_seconds(loop, xs, ys) for loop in loops] for _ in range(repeat)])
    return np.median(times, axis=0) / xs.shape[0] * 1e9, values


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--count", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=21)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "libm_cost.csv"))
    args = parser.parse_args()

    rng = np.random.default_rng(33)
    rows = []
    empty_ns = None
    for name, domain, ours, theirs, make_loop, draw_x, draw_y in CASES:
        xs = draw_x(rng, args.count)
        ys = draw_y(rng, args.count) if draw_y is not None else xs
        if empty_ns is None:
            (empty_ns,), _ = _median_ns([_empty], xs, ys, args.repeat)
        (ours_ns, libm_ns), (ours_sum, libm_sum) = _median_ns([make_loop(ours), make_loop(theirs)], xs, ys,
                                                              args.repeat)
        rows.append(dict(function=name, arguments=domain, libm_ns=round(ours_ns, 2), platform_ns=round(libm_ns, 2),
                         ratio=round(ours_ns / libm_ns, 2), sum_libm=repr(ours_sum), sum_platform=repr(libm_sum)))

    print(f"{platform.machine()} {platform.processor() or ''} {platform.system()} {platform.release()}, "
          f"numba's libm calls: {platform.libc_ver()}; {args.count} arguments, median of {args.repeat} runs; "
          f"an empty loop over the same array: {empty_ns:.2f} ns per element")
    print()
    print("| function | arguments | prandtl_fmu.libm (ns) | numba np.* = libm (ns) | ratio |")
    print("|---|---|---:|---:|---:|")
    for row in rows:
        print(f"| {row['function']} | {row['arguments']} | {row['libm_ns']:.1f} | {row['platform_ns']:.1f} | "
              f"{row['ratio']:.2f} |")
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
