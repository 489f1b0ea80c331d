"""Time to first result: what a new process pays before its first number.

Each case runs in fresh processes (the median of ``--repeat`` runs, wall
time of the whole process, measured here in one run so the ratios compare
like with like):

* ``import numba``: ``python -c "import numba"``;
* ``numba floor``: one trivial cached numba function called once: what any
  program that uses numba's cache pays before its first compiled call (numba
  then loads its typing and lowering registries), the floor of the two
  cases below;
* ``cli``: ``prandtl-fmu run`` on a tiny scene (10 steps, 2 branches) writing
  a CSV, the way a user's first command runs (it ends without the interpreter's
  teardown once its output is closed); ``cli, interpreter teardown``: the same
  run through ``main(argv)``, which returns and lets the interpreter tear numba
  down: what that teardown costs;
* ``fmu``: a fresh process that loads the FMU of the same scene with FMPy and
  calls instantiate ... first ``doStep`` (reported: the time from
  instantiate to the end of the first doStep, and the whole process);

each with a *warm* cache (the compiled kernels are in the user's numba cache
folder: every run after the first) and a *cold* one (an empty cache folder:
the first run after an install or an edit of the library, which compiles and
fills the cache). numba's first compiled call imports scipy.linalg when scipy
is installed (to find BLAS, which no kernel here uses): the ``no scipy`` rows
hide scipy from the process, as in a core install (``pip install prandtl_fmu``
without extras).

    python benchmarks/startup.py [--repeat 5] [--out docs/bench/startup.csv]
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, ROOT)
from common import write_rows  # noqa: E402

TINY_SCENE = """\
name = "tiny"
[mass]
m = 1.0
[spring]
k0 = 1.0
[branches]
k = [0.5, 0.5]
eta = [0.1, 0.3]
[load]
kind = "harmonic"
amplitude = 0.4
omega = 1.0
[solver]
stepper = "projected"
step = 0.01
stop_time = 0.1
output_interval = 0.01
"""

HIDE_SCIPY = "import sys; sys.modules['scipy'] = None\n"

TRIVIAL = "from numba import njit\n\n\n@njit(cache=True)\ndef twice(x):\n    return 2.0 * x\n"

# as the console script runs it: main() reads the process's arguments
CLI = "sys.argv = ['prandtl-fmu', 'run', {scene!r}, '--out', {out!r}]\nfrom prandtl_fmu.cli import main\nsys.exit(main())\n"
CLI_TEARDOWN = "from prandtl_fmu.cli import main\nsys.exit(main(['run', {scene!r}, '--out', {out!r}]))\n"

FMU = textwrap.dedent("""\
    import os, time
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    description = read_model_description({fmu!r})
    folder = extract({fmu!r})
    slave = FMU2Slave(guid=description.guid, unzipDirectory=folder,
                      modelIdentifier=description.coSimulation.modelIdentifier, instanceName="tiny")
    start = time.perf_counter()
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    print("FIRST", time.perf_counter() - start, flush=True)
    slave.terminate()
    slave.freeInstance()
""")


def timed(code, cache_dir):
    """Wall time of a fresh ``python -c code``, and the 'FIRST' time it prints (or None)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"benchmark process failed ({done.returncode}): {done.stderr.strip()[-500:]}")
    first = [float(line.split()[1]) for line in done.stdout.splitlines() if line.startswith("FIRST ")]
    return wall, (first[0] if first else None)


def measure_all(cases, repeat):
    """Median wall time (and first-result time) of each (label, code, warm) case over ``repeat`` fresh
    processes, the cases interleaved round-robin so that a slow spell of the machine hits them all alike."""
    walls = {case: [] for case in cases}
    firsts = {case: [] for case in cases}
    with tempfile.TemporaryDirectory(prefix="prandtl_startup_cache_") as shared:
        for label, code, warm in cases:
            if warm:
                timed(code, shared)  # fills the cache
        for _ in range(repeat):
            for case in cases:
                label, code, warm = case
                if warm:
                    wall, first = timed(code, shared)
                else:
                    with tempfile.TemporaryDirectory(prefix="prandtl_startup_cold_") as empty:
                        wall, first = timed(code, empty)
                walls[case].append(wall)
                firsts[case].append(first)
    return {case: (statistics.median(walls[case]),
                   statistics.median(firsts[case]) if firsts[case][0] is not None else None) for case in cases}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "bench", "startup.csv"))
    args = parser.parse_args(argv)

    from prandtl_fmu.fmu.build import build_fmu

    with tempfile.TemporaryDirectory(prefix="prandtl_startup_") as work:
        scene = os.path.join(work, "tiny.toml")
        with open(scene, "w") as fh:
            fh.write(TINY_SCENE)
        fmu = str(build_fmu(scene, os.path.join(work, "tiny.fmu")))
        with open(os.path.join(work, "trivial_kernel.py"), "w") as fh:
            fh.write(TRIVIAL)
        floor = f"import sys; sys.path.insert(0, {work!r})\nimport trivial_kernel\ntrivial_kernel.twice(1.0)\n"
        cases = [("import numba", "import numba\n"), ("numba floor", floor), ("numba floor, no scipy", HIDE_SCIPY + floor)]
        cli = CLI.format(scene=scene, out=os.path.join(work, "tiny.csv"))
        fmu_code = FMU.format(fmu=fmu)
        for label, code in (("cli", "import sys\n" + cli), ("fmu", fmu_code)):
            cases.append((label, code))
            cases.append((label + ", no scipy", HIDE_SCIPY + ("" if label == "fmu" else "import sys\n") + code))
        teardown = "import sys\n" + CLI_TEARDOWN.format(scene=scene, out=os.path.join(work, "tiny.csv"))
        cases.insert(4, ("cli, interpreter teardown", teardown))
        warm_only = ("import numba", "numba floor", "cli, interpreter teardown")
        runs = [(label, code, warm) for label, code in cases
                for warm in ((True,) if label.startswith(warm_only) else (True, False))]
        measured = measure_all(runs, args.repeat)
        rows = []
        for label, code, warm in runs:
            wall, first = measured[(label, code, warm)]
            rows.append({"case": label, "cache": "warm" if warm else "cold", "process_s": round(wall, 3),
                         "instantiate_to_first_step_s": "" if first is None else round(first, 3)})
            print(f"{label:22s} {rows[-1]['cache']:5s} process {wall:6.3f} s"
                  + ("" if first is None else f"   instantiate..first doStep {first:6.3f} s"), flush=True)
    floor = rows[0]["process_s"]
    for row in rows:
        row["x_import_numba"] = round(row["process_s"] / floor, 2)
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
