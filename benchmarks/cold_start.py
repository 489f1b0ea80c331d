"""What a newcomer waits for: each command in a fresh process with an empty numba cache (cold), then again with
the cache it filled (warm), and which kernels compiled for how long.

    python benchmarks/cold_start.py [--repeat 1] [--out docs/bench/cold_start.csv] [--only run-paper,...]

Cases (``prandtl-fmu`` through ``python -m prandtl_fmu``, so that the process is the command itself):

* ``help``: ``--help``; ``version``: ``--version``; ``scenes``: the packaged scenes;
* ``run-paper``: ``run paper-section-8`` to a CSV (100 branches, T = 500 s, ``projected``);
* ``run-network``: ``run networks/two-masses-slider`` (``implicit``, the active-set step);
* ``run-noise``: ``run white-noise``; ``run-memory``: ``run delay-oscillator``;
* ``build-native-2``, ``build-native-3``: ``build paper-section-8 --runtime native --fmi 2|3``;
  ``build-native-one``: the same, FMI 2.0, with only the scene's stepper (``--steppers projected``).

Each row: the case, cold or warm, the wall and CPU seconds of the whole process (user + system of the process
and its children: the native build's compiler and linker), and, for the cold runs, the kernels numba compiled
(its event API, ``numba:compile``: each dispatcher's inclusive compile time; a kernel compiled inside another's
compilation is counted in both, so the first rows are the ones to read). One CSV row per case and state, and
``cold_start_kernels.csv``: every compiled kernel of every cold run with its seconds.

The cold runs are cold for numba only: Python's bytecode cache and the operating system's file cache are warm
(a first install pays those too, about a second). zig's own cache (the native build's linker) is left as it is:
.ci/run warms it once, as a machine does on its first native build.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import write_rows  # noqa: E402

CASES = {
    "help": ["--help"],
    "version": ["--version"],
    "scenes": ["scenes"],
    "run-paper": ["run", "paper-section-8", "--out", "{out}/paper.csv"],
    "run-network": ["run", "networks/two-masses-slider", "--out", "{out}/network.csv"],
    "run-noise": ["run", "white-noise", "--out", "{out}/noise.csv"],
    "run-memory": ["run", "delay-oscillator", "--out", "{out}/memory.csv"],
    "build-native-2": ["build", "paper-section-8", "--runtime", "native", "--fmi", "2", "-o", "{out}/p2.fmu"],
    "build-native-3": ["build", "paper-section-8", "--runtime", "native", "--fmi", "3", "-o", "{out}/p3.fmu"],
    "build-native-one": ["build", "paper-section-8", "--runtime", "native", "--steppers", "projected", "-o",
                         "{out}/p1.fmu"],
}

# Run in the child: record every numba compilation (dispatcher, seconds), then the command line as the program.
CHILD = r"""
import atexit, json, sys, time
record = []
try:
    from numba.core import event

    class Compiles(event.Listener):
        def __init__(self):
            self.started = {}

        def on_start(self, ev):
            self.started[id(ev.data["dispatcher"])] = time.perf_counter()

        def on_end(self, ev):
            dispatcher = ev.data["dispatcher"]
            start = self.started.pop(id(dispatcher), None)
            if start is not None:
                function = dispatcher.py_func
                record.append((f"{function.__module__}.{function.__qualname__}", time.perf_counter() - start))

    event.register("numba:compile", Compiles())
except ImportError:
    pass


RECORD = sys.argv[1]


def dump():
    with open(RECORD, "w") as fh:
        json.dump(record, fh)


atexit.register(dump)
sys.argv = ["prandtl-fmu"] + sys.argv[2:]
from prandtl_fmu.cli import main
code = main(sys.argv[1:])
dump()
sys.stdout.flush()
raise SystemExit(code)
"""

# The same without the listener: whether numba is imported at all is part of what a help text costs.
CHILD_PLAIN = r"""
import sys
sys.argv = ["prandtl-fmu"] + sys.argv[2:]
from prandtl_fmu.cli import main
raise SystemExit(main(sys.argv[1:]))
"""


def run_case(argv, cache: str, out: str, listen: bool):
    """(wall s, cpu s, [(kernel, s)], exit status) of one fresh process."""
    record = os.path.join(out, "compiles.json")
    if os.path.exists(record):
        os.unlink(record)
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    command = [sys.executable, "-c", CHILD if listen else CHILD_PLAIN, record] + [a.format(out=out) for a in argv]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, env=env, cwd=out, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    compiles = []
    if os.path.exists(record):
        with open(record) as fh:
            compiles = [tuple(item) for item in json.load(fh)]
    if done.returncode not in (0,):
        raise SystemExit(f"{argv}: exit {done.returncode}: {done.stderr.strip()[-500:]}")
    return wall, cpu, compiles


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1, help="cold and warm runs of each case (medians)")
    parser.add_argument("--out", default="out/bench/cold_start.csv", help="the CSV (and *_kernels.csv beside it)")
    parser.add_argument("--only", help="comma-separated cases (default: all): " + ", ".join(CASES))
    args = parser.parse_args()
    cases = args.only.split(",") if args.only else list(CASES)
    unknown = [name for name in cases if name not in CASES]
    if unknown:
        parser.error(f"unknown case {unknown[0]!r}: one of {', '.join(CASES)}")
    rows, kernels = [], []
    for name in cases:
        listen = not name.startswith(("help", "version", "scenes"))
        colds, warms = [], []
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory(prefix="cold-start-") as folder:
                cache = os.path.join(folder, "cache")
                colds.append(run_case(CASES[name], cache, folder, listen))
                warms.append(run_case(CASES[name], cache, folder, listen))
        for state, runs in (("cold", colds), ("warm", warms)):
            walls = sorted(r[0] for r in runs)
            cpus = sorted(r[1] for r in runs)
            compiles = runs[0][2]
            rows.append(dict(case=name, cache=state, wall=round(walls[len(walls) // 2], 3),
                             cpu=round(cpus[len(cpus) // 2], 3), kernels_compiled=len(compiles),
                             slowest=";".join(f"{k}={s:.2f}" for k, s in sorted(compiles, key=lambda c: -c[1])[:3])))
            if state == "cold":
                kernels += [dict(case=name, kernel=k, seconds=round(s, 3)) for k, s in compiles]
        print(f"{name}: cold {rows[-2]['wall']:.2f} s wall, {rows[-2]['cpu']:.2f} s CPU "
              f"({rows[-2]['kernels_compiled']} kernels); warm {rows[-1]['wall']:.2f} s wall, {rows[-1]['cpu']:.2f} "
              "s CPU", file=sys.stderr)
    write_rows(args.out, rows)
    if kernels:
        write_rows(os.path.splitext(args.out)[0] + "_kernels.csv", kernels)


if __name__ == "__main__":
    main()
