"""What the switch to ``prandtl_fmu.libm`` costs the kernels (issue 33): the same runs with the kernels calling
the platform's libm (before) and ``prandtl_fmu.libm`` (after), in one process.

Before: a second copy of the package, imported under a private name with its on-disk cache off, in which every
module that calls ``libm.<f>`` is given a stand-in module whose functions are numba's ``math.*``/``np.*`` (what the
kernels called before the switch: ``math.cos``, ``math.sin`` and ``math.cos`` of one argument for ``sincos``,
``abs`` of a complex for ``hypot``, ``x / 2.0 ** -n`` for ``scalbn``, ``x ** y`` for ``pow`` and ``pow3``, ...). After: the
installed package. The kernels differ in nothing else.

Problems (``CASES``):

* ``force_at``: a harmonic load's F(t) = offset + A cos(omega t) at 200,000 times in [0, 1e3] (a compiled loop
  over the library's ``loads.force_at``), ns per call;
* whole runs of ``simulate`` (ms per run, so ns per step = run / steps): exact on an oscillator with Coulomb
  friction and three branches under a harmonic load (sin, cos, exp, log2, acos, hypot in its phases), exact with
  series dashpots (``exact_series``: sincos, exp), implicit with Stribeck friction and series dashpots (exp,
  expm1, log1p, log), verlet on a continuum spectrum with k(s) a power law (pow).

Each case runs once in each version before the timing (compilation), then ``--repeat`` times alternately; the
figure is the median. No reference solution: the outputs of the two versions are compared instead (the largest
difference of x relative to max |x|, printed), which must be a few ulps per operation, growing over a run.

    python benchmarks/libm_kernels.py [--repeat 7] [--out out/libm_kernels.csv]

prints a markdown table (the one in docs/libm.md) and writes the CSV.
"""
import argparse
import importlib.util
import math
import os
import platform
import sys
import time
import types

import numpy as np
from numba import njit

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
sys.path.insert(0, HERE)
from common import write_rows  # noqa: E402

import prandtl_fmu  # noqa: E402

PACKAGE = os.path.dirname(os.path.abspath(prandtl_fmu.__file__))
BEFORE_NAME = "_prandtl_fmu_platform_libm"


def platform_libm():
    """A module with libm's names whose functions call numba's math.* / np.* (the platform's libm)."""
    shim = types.ModuleType("platform_libm")
    shim.sin = njit(lambda x: math.sin(x))
    shim.cos = njit(lambda x: math.cos(x))
    shim.sincos = njit(lambda x: (math.sin(x), math.cos(x)))
    shim.exp = njit(lambda x: math.exp(x))
    shim.expm1 = njit(lambda x: math.expm1(x))
    shim.log = njit(lambda x: math.log(x))
    shim.log1p = njit(lambda x: math.log1p(x))
    shim.acos = njit(lambda x: math.acos(x))
    shim.cbrt = njit(lambda x: np.cbrt(x))
    shim.hypot = njit(lambda x, y: abs(complex(x, y)))
    shim.log2 = njit(lambda x: math.log2(x))
    shim.pow = njit(lambda x, y: x ** y)
    shim.pow3 = njit(lambda x, y0, y1, y2: (x ** y0, x ** y1, x ** y2))
    shim.scalbn = njit(lambda x, n: x / 2.0 ** -n)
    return shim


def import_before():
    """The package's second copy, its kernels on the platform's libm (never cached: the stand-in is not in the
    sources' digest)."""
    saved = os.environ.get("PRANDTL_FMU_JIT_CACHE")
    os.environ["PRANDTL_FMU_JIT_CACHE"] = "0"
    try:
        spec = importlib.util.spec_from_file_location(BEFORE_NAME, os.path.join(PACKAGE, "__init__.py"),
                                                      submodule_search_locations=[PACKAGE])
        package = importlib.util.module_from_spec(spec)
        sys.modules[BEFORE_NAME] = package
        spec.loader.exec_module(package)
        for name in ("loads", "steppers.exact", "steppers.exact_series", "kernels.series", "kernels.increment",
                     "kernels.friction", "kernels.stack", "driver", "scene"):
            importlib.import_module(f"{BEFORE_NAME}.{name}")
    finally:
        if saved is None:
            del os.environ["PRANDTL_FMU_JIT_CACHE"]
        else:
            os.environ["PRANDTL_FMU_JIT_CACHE"] = saved
    own_libm = sys.modules[f"{BEFORE_NAME}.libm"]
    shim = platform_libm()
    patched = []
    for name, module in list(sys.modules.items()):
        if name.startswith(BEFORE_NAME + ".") and getattr(module, "libm", None) is own_libm:
            module.libm = shim
            patched.append(name[len(BEFORE_NAME) + 1:])
    return package, sorted(patched)


SOLVER = '\n[solver]\nstepper = "{stepper}"\nstep = {step}\nstop_time = {stop}\noutput_interval = {interval}\n'
SCENES = {
    "exact, Coulomb friction, 3 branches, harmonic": ("""
name = "exact"
[mass]
m = 1.0
x0 = 0.05
[spring]
k0 = 0.2
[damper]
c = 0.01
[friction]
alpha = 0.1
[branches]
k = [0.5, 0.3, 0.2]
eta = [0.1, 0.3, 0.6]
[load]
kind = "harmonic"
amplitude = 0.8
omega = 0.7
""" + SOLVER.format(stepper="exact", step=0.1, stop=200.0, interval=0.1), 2000),
    "exact_series, series dashpots, harmonic": ("""
name = "exact-series"
[mass]
m = 1.0
x0 = 0.05
[spring]
k0 = 0.2
[friction]
alpha = 0.1
[branches]
k = [0.5, 2.0, 0.3]
eta = [0.1, 0.3, 0.05]
c = [0.4, 2.0, 9.0]
[load]
kind = "harmonic"
amplitude = 0.8
omega = 1.3
""" + SOLVER.format(stepper="exact", step=0.1, stop=50.0, interval=0.1), 500),
    "implicit, Stribeck friction, series dashpots": ("""
name = "stribeck"
[mass]
m = 1.0
[spring]
k0 = 0.2
[damper]
c = 0.01
[friction]
alpha = 0.3
alpha_kinetic = 0.2
stribeck_velocity = 0.1
belt_velocity = 0.05
[branches]
k = [0.5, 0.3, 0.2]
eta = [0.1, 0.3, 0.6]
c = [0.4, 2.0, 9.0]
[load]
kind = "harmonic"
amplitude = 0.8
omega = 0.7
""" + SOLVER.format(stepper="implicit", step=0.001, stop=100.0, interval=0.1), 100000),
    "verlet, continuum: Iwan's power-law density": ("""
name = "continuum"
[mass]
m = 1.0
x0 = 0.05
[spring]
k0 = 0.2
[branches]
continuum = true
density = { kind = "iwan", F_S = 1.0, K_T = 2.0, chi = -0.5, beta = 0.1 }
[load]
kind = "harmonic"
amplitude = 0.8
omega = 1.3
""" + SOLVER.format(stepper="verlet", step=0.001, stop=100.0, interval=0.1), 100000),
}


def force_loop(force_at):
    @njit
    def loop(load, times):
        total = 0.0
        for i in range(times.shape[0]):
            total += force_at(load, times[i])
        return total
    return loop


def median_time(run, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--count", type=int, default=200000)
    parser.add_argument("--out", default=os.path.join(HERE, "..", "out", "libm_kernels.csv"))
    args = parser.parse_args(argv)

    before, patched = import_before()
    print(f"before: {BEFORE_NAME} with numba's math.* in {', '.join(patched)}", file=sys.stderr)
    from prandtl_fmu import driver, loads, scene as scenes

    versions = {"before": (sys.modules[f"{BEFORE_NAME}.loads"], sys.modules[f"{BEFORE_NAME}.driver"],
                           sys.modules[f"{BEFORE_NAME}.scene"]),
                "after": (loads, driver, scenes)}
    rows = []

    times = np.random.default_rng(33).uniform(0.0, 1e3, args.count)
    loops = {}
    for label, (load_module, _, _) in versions.items():
        loops[label] = (force_loop(load_module.force_at), (load_module.HARMONIC, 0.1, 0.8, 0.7,
                                                           np.zeros(0), np.zeros(0)))
        loops[label][0](loops[label][1], times)  # compile
    medians = {label: [] for label in loops}
    sums = {label: loop(load, times) for label, (loop, load) in loops.items()}
    for _ in range(args.repeat):
        for label, (loop, load) in loops.items():
            start = time.perf_counter()
            loop(load, times)
            medians[label].append(time.perf_counter() - start)
    ns = {label: float(np.median(values)) / args.count * 1e9 for label, values in medians.items()}
    rows.append(dict(case="force_at, harmonic load (per call)", unit="ns", before=ns["before"], after=ns["after"],
                     ratio=ns["after"] / ns["before"],
                     difference=abs(sums["after"] - sums["before"]) / max(abs(sums["before"]), 1.0)))

    for case, (text, steps) in SCENES.items():
        runs, results = {}, {}
        for label, (_, driver_module, scene_module) in versions.items():
            scene = scene_module.parse_scene(text, f"{label}.toml")
            runs[label] = (lambda d=driver_module, s=scene: d.simulate(s, progress=False))
            results[label] = runs[label]()  # compile
        medians = {label: [] for label in runs}
        for _ in range(args.repeat):
            for label, run in runs.items():
                start = time.perf_counter()
                run()
                medians[label].append(time.perf_counter() - start)
        ms = {label: float(np.median(values)) * 1e3 for label, values in medians.items()}
        x_before, x_after = results["before"].x, results["after"].x
        rows.append(dict(case=f"{case} ({steps} steps per run)", unit="ms", before=ms["before"], after=ms["after"],
                         ratio=ms["after"] / ms["before"],
                         difference=float(np.max(np.abs(x_after - x_before)) / np.max(np.abs(x_before)))))
    write_rows(args.out, rows)
    print(f"\n{platform.machine()}, {platform.python_version()}, load {os.getloadavg()[0]:.1f}, "
          f"median of {args.repeat}\n")
    print("| kernel | platform libm | prandtl_fmu.libm | ratio | max \\|x_after - x_before\\| / max \\|x\\| |")
    print("|---|---:|---:|---:|---:|")
    for row in rows:
        print(f"| {row['case']} | {row['before']:.3g} {row['unit']} | {row['after']:.3g} {row['unit']} | "
              f"{row['ratio']:.2f} | {row['difference']:.1e} |")


if __name__ == "__main__":
    main()
