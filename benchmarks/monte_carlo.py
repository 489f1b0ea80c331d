"""Monte Carlo throughput: white-noise paths per second per core, in one process and on a LocalCluster.

Problem: the linear oscillator under white noise of ``examples/monte_carlo_oscillator_scene.toml``
(m = 1, k = 1, c = 0.5, sigma = 0.5, stepper ``implicit``, h = 0.01 s, output every 0.05 s, the Brownian
tree's unit ``noise_unit`` = 1.28 s = 128 h: one normal a step), run for
T = 10 s and T = 100 s (1000 and 10,000 steps a path), keeping ``final_x, final_v, late_mean_square_x,
late_mean_square_v`` (the summaries of a Monte Carlo of stationary laws). The reference solution is not the
point here: the laws' checks are tests/analysis/test_monte_carlo.py and docs/sweep/monte_carlo_laws.md.

Measured in one run of this script, warm (every kernel compiled, in this process and in every worker):

* ``one process``: ``runs.run_batch`` of ``--paths`` seeds in this process, the work of one sweep task: each
  path's scene checked (the seed set in the document), run (a noisy path goes alone through
  ``driver.simulate``, a row after every step: ``summary._noisy_run``) and reduced; paths per second and
  microseconds per step of a path;
* ``white noise, noise_unit = 1 s``: the same with the default unit, where h / T0 = 0.01 is not a power of
  two and a step's time needs up to 52 - 7 bridge draws (``prandtl_fmu/noise.py``);
* ``deterministic``: the same scene with ``[load] kind = "random"`` (band-limited, 64 cosines, seeded the
  same way) or a harmonic load (the same run ``--paths`` times) instead of the white noise, which the batch
  kernel (``kernels/batch.py``) runs many paths per compiled call: what the noise and its path-by-path route
  cost;
* ``LocalCluster, W workers``: ``prandtl_fmu.sweep.sweep`` of the same seeds on a warm cluster of W = 1, 2
  single-threaded workers (the cluster started before the clock; the Parquet store and the report written;
  the better of two sweeps), paths per second and per core (divided by W);
* the load average before and after (the machine is shared: a load above the core count slows every line).

    python benchmarks/monte_carlo.py [--paths 2000] [--out docs/bench/monte_carlo.md]
"""
import argparse
import os
import platform
import sys
import tempfile
import time
import tomllib

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from prandtl_fmu.sweep import sweep  # noqa: E402
from prandtl_fmu.sweep import plan as sweep_plan  # noqa: E402
from prandtl_fmu.sweep.runs import run_batch  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SCENE = os.path.join(ROOT, "examples", "monte_carlo_oscillator_scene.toml")
SUMMARY = ["final_x", "final_v", "late_mean_square_x", "late_mean_square_v"]
RANDOM = {"kind": "random", "seed": 0, "rms": 0.5, "band": [0.1, 5.0], "components": 64}
HARMONIC = {"kind": "harmonic", "amplitude": 0.5, "omega": 1.0}


def document(stop_time, load=None):
    with open(SCENE, "rb") as fh:
        doc = tomllib.load(fh)
    doc["solver"]["stop_time"] = float(stop_time)
    if load is not None:
        doc["load"] = dict(load)
    return doc


def spec(paths):
    return {"seeds": {"count": paths}, "keep": {"summary": SUMMARY}}


def in_process(doc, paths, repeats=3):
    """Best of ``repeats`` wall times of one task's batch of ``paths`` runs in this process: the seeds of the
    scene's seeded load, or (a harmonic load) the same run ``paths`` times."""
    if doc["load"]["kind"] == "harmonic":
        keys, summary = ["load.amplitude"], SUMMARY
        values = [(run, {"load.amplitude": doc["load"]["amplitude"]}) for run in range(paths)]
    else:
        the_plan = sweep_plan(doc, spec(paths))
        keys, values, summary = the_plan.spec.keys, the_plan.spec.values(0, paths), the_plan.summary
    run_batch(doc, "bench", keys, values[:2], summary, False)  # warm: compiled
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        rows = run_batch(doc, "bench", keys, values, summary, False)
        best = min(best, time.perf_counter() - start)
        assert all(error == "" for error in rows["error"]), rows["error"][:3]
    return best


def on_cluster(doc, paths, workers):
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster) as client, tempfile.TemporaryDirectory() as folder:
        # warm: every worker compiles, this process imports what the store and the report need
        sweep(doc, spec(4 * workers), client=client, out=os.path.join(folder, "warm"), progress=False)
        wall = float("inf")
        for repeat in range(2):  # the better of two: the machine is shared
            start = time.perf_counter()
            frame = sweep(doc, spec(paths), client=client, out=os.path.join(folder, f"out{repeat}"), progress=False)
            wall = min(wall, time.perf_counter() - start)
            assert len(frame) == paths and (frame["error"] == "").all()
    return wall


def derived(rows):
    """From the in-process lines at both lengths: the cost of a step and of a path's fixed part (scene check,
    simulate's setup, the reduction), per load; the cluster's efficiency against one process."""
    per_path = {(where, load, steps): wall / paths for where, load, steps, paths, wall, _ in rows}
    lines = ["One process, from the two path lengths (cost of a path = fixed + steps x step):", "",
             "| load | us per step | fixed cost per path (ms) |", "|---|---|---|"]
    for load in dict.fromkeys(load for where, load, *_ in rows if where.startswith("one process")):
        short, long = per_path[("one process (1 core)", load, 1000)], per_path[("one process (1 core)", load, 10000)]
        step = (long - short) / 9000
        lines.append(f"| {load} | {1e6 * step:.3f} | {1e3 * (short - 1000 * step):.3f} |")
    lines += ["", "The cluster against one process (paths/s per core over one process's paths/s):", ""]
    for where, load, steps, paths, wall, cores in rows:
        if where.startswith("LocalCluster"):
            alone = per_path[("one process (1 core)", load, steps)]
            lines.append(f"* {where}, {steps} steps a path: {alone * paths / (wall * cores):.2f}")
    return lines


def load_average():
    return "{:.2f} {:.2f} {:.2f}".format(*os.getloadavg())


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--paths", type=int, default=2000)
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "bench", "monte_carlo.md"))
    args = parser.parse_args(argv)
    before = load_average()
    rows = []
    for stop_time in (10.0, 100.0):
        steps = round(stop_time / 0.01)
        paths = args.paths if stop_time <= 10 else max(50, args.paths // 4)
        noisy = document(stop_time)
        wall = in_process(noisy, paths)
        rows.append(("one process (1 core)", "white noise", steps, paths, wall, 1))
        wall = in_process(document(stop_time, dict(noisy["load"], noise_unit=1.0)), paths)
        rows.append(("one process (1 core)", "white noise, noise_unit = 1 s", steps, paths, wall, 1))
        for name, load in (("band-limited (random, 64 cosines)", RANDOM), ("harmonic", HARMONIC)):
            wall = in_process(document(stop_time, load), paths)
            rows.append(("one process (1 core)", f"deterministic: {name}", steps, paths, wall, 1))
        for workers in (1, 2):
            wall = on_cluster(noisy, paths, workers)
            rows.append((f"LocalCluster, {workers} worker{'s' if workers > 1 else ''}", "white noise", steps, paths,
                         wall, workers))
        print(f"T = {stop_time:g} s done ({load_average()})", file=sys.stderr)
    after = load_average()
    lines = ["# Monte Carlo throughput", "",
             "Generated by `python benchmarks/monte_carlo.py` (its docstring says what each line measures): the "
             "white-noise linear oscillator of `examples/monte_carlo_oscillator_scene.toml` (stepper implicit, "
             "h = 0.01 s), 4 summaries kept per path.", "",
             f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}; load average (1, 5, 15 min) {before} before, {after} after.", "",
             "| where | load | steps a path | paths | wall (s) | paths/s | paths/s per core | us per step |",
             "|---|---|---|---|---|---|---|---|"]
    for where, load, steps, paths, wall, cores in rows:
        lines.append(f"| {where} | {load} | {steps} | {paths} | {wall:.2f} | {paths / wall:.0f} | "
                     f"{paths / wall / cores:.0f} | {1e6 * wall * cores / (paths * steps):.2f} |")
    lines += ["", *derived(rows)]
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"written: {args.out}")


if __name__ == "__main__":
    main()
