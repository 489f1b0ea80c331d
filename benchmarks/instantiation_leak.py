"""What one FMU instantiation keeps in the host (README, "PythonFMU 0.7.0, worked around").

Builds the FMU of the paper's scene with each native loader (ours, ``prandtl_fmu/fmu/python/loader``, and
PythonFMU's stock one) and the connector example's point mass (a plain PythonFMU slave; ``run_connector.build``
gives it our loader), then, in a fresh process for each: 50 warm-up cycles of instantiate, initialize, one
doStep, terminate, free through FMPy, then ``--cycles`` more, and the growth of ``sys.getallocatedblocks()``
(Python's live memory blocks, after a garbage collection) per cycle. The processes end with ``os._exit``: the
stock loader's use-after-free at exit is not what is measured.

    python benchmarks/instantiation_leak.py [--cycles 200] [--out out/instantiation_leak.csv]
"""
import argparse
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from common import write_rows  # noqa: E402

ROOT = os.path.join(os.path.dirname(__file__), "..")
SCRIPT = """
import gc, os, sys
from fmpy import extract, instantiate_fmu, read_model_description
path, cycles = sys.argv[1], int(sys.argv[2])
description, folder = read_model_description(path), extract(path)
def cycle():
    fmu = instantiate_fmu(folder, description, fmi_type="CoSimulation")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 0.1)
    fmu.terminate()
    fmu.freeInstance()
for _ in range(50):
    cycle()
gc.collect()
before = sys.getallocatedblocks()
for _ in range(cycles):
    cycle()
gc.collect()
print((sys.getallocatedblocks() - before) / cycles, flush=True)
os._exit(0)
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=200)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "instantiation_leak.csv"))
    args = parser.parse_args()
    sys.path.insert(0, os.path.join(ROOT, "examples", "cosim", "connector"))
    import run_connector

    from prandtl_fmu.fmu.build import build_fmu

    rows = []
    with tempfile.TemporaryDirectory() as folder:
        scene = os.path.join(ROOT, "scenes", "paper-section-8.toml")
        element = build_fmu(scene, os.path.join(folder, "paper.fmu"))
        element_stock = build_fmu(scene, os.path.join(folder, "paper-stock.fmu"), loader="pythonfmu")
        mass = os.path.join(run_connector.build(folder), "PointMass.fmu")
        script = os.path.join(folder, "cycles.py")
        with open(script, "w") as fh:
            fh.write(SCRIPT)
        for label, fmu, loader in (("PrandtlElement", element, "prandtl"),
                                   ("PrandtlElement", element_stock, "pythonfmu"),
                                   ("PointMass (plain PythonFMU slave)", mass, "prandtl")):
            done = subprocess.run([sys.executable, script, str(fmu), str(args.cycles)], capture_output=True,
                                  text=True, timeout=1800)
            if done.returncode != 0:
                raise SystemExit(f"{label}: exit {done.returncode}: {done.stderr.strip()[-500:]}")
            blocks = float(done.stdout.split()[-1])
            rows.append({"fmu": label, "loader": loader, "cycles": args.cycles,
                         "blocks_per_instantiation": round(blocks, 2)})
            print(f"{label}, {loader} loader: {blocks:.2f} blocks per instantiation")
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
