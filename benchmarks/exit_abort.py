"""Reproduce the known abort at interpreter exit after FMPy runs of the FMU (README, "an abort at
interpreter exit"; issue "Trust every number and every exit").

Builds the FMU of the paper's scene, then starts ``--processes`` Python processes at once, each running
``fmpy.simulate_fmu`` on it for 5 s of model time and exiting normally (no os._exit), and counts their
exit statuses. 134 is SIGABRT ("corrupted double-linked list" on stderr). The abort is timing dependent:
it shows more often under CPU load (run it beside the test suite), and not under gdb or with glibc's
malloc checking preloaded.

    python benchmarks/exit_abort.py [--processes 14] [--out out/exit_abort.csv]
"""
import argparse
import collections
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from common import write_rows  # noqa: E402
from prandtl_fmu.fmu.build import build_fmu  # noqa: E402

ROOT = os.path.join(os.path.dirname(__file__), "..")
SCRIPT = """
import sys
from fmpy import simulate_fmu
result = simulate_fmu(sys.argv[1], stop_time=5.0, output_interval=0.5)
print(result["x"][-1])
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--processes", type=int, default=14)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "exit_abort.csv"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        fmu = build_fmu(os.path.join(ROOT, "scenes", "paper-section-8.toml"), os.path.join(folder, "paper.fmu"))
        script = os.path.join(folder, "run.py")
        with open(script, "w") as fh:
            fh.write(SCRIPT)
        runs = [subprocess.Popen([sys.executable, script, str(fmu)], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True) for _ in range(args.processes)]
        outcomes = [(run.wait(), run.stderr.read().strip().splitlines()[-1:]) for run in runs]
    counts = collections.Counter(status for status, _ in outcomes)
    for status, count in sorted(counts.items()):
        last = next((line for s, line in outcomes if s == status and line), [""])
        print(f"exit {status}: {count} of {args.processes}  {last[0] if last else ''}")
    write_rows(args.out, [{"exit_status": status, "runs": count, "processes": args.processes}
                          for status, count in sorted(counts.items())])


if __name__ == "__main__":
    main()
