"""What the native network FMU costs per doStep, against the library's compiled step.

Problem: the dynamic chain of ``prandtl-fmu bench --networks`` (n nodes of 1 kg, k = 1000 N/m between
neighbours and to the wall, alpha = 1 N per node, a dashpot 0.01 N s/m), under a force held at 0.6 n alpha
on its last node, h = 5e-4 s. For each n:

* the library: ``NetworkElement.advance(1000 h, F)``, per internal step (the compiled loop; Python once per
  advance);
* the native FMU (``--runtime native``, FMI 2.0) in the C host of tests/c_host, which never loads Python: one
  internal step per doStep (``doStep`` alone, and ``doStep`` + one getReal of every output).

Ratios are measured in the same run; medians of ``--repeat`` interleaved repeats.

    python benchmarks/network_fmu_overhead.py [--sizes 10,100,1000] [--repeat 5] [--out docs/bench/network_fmu_overhead.csv]
"""
import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, ROOT)
from common import write_rows  # noqa: E402
sys.path.insert(0, os.path.join(ROOT, "tests"))

from native_host import Extracted, compile_host, run_host  # noqa: E402
from prandtl_fmu.network import NetworkElement  # noqa: E402

H = 5e-4


def scene_text(n: int) -> str:
    return f"""name = "chain{n}"
[chain]
n = {n}
m = 1.0
c = 0.01
k = 1000.0
alpha = 1.0
k_wall = 1000.0
[solver]
stepper = "implicit"
step = {H!r}
stop_time = 1.0
output_interval = {H!r}
"""


def library_step(scene, force: float, count: int) -> float:
    element = NetworkElement(scene)
    element.advance(1000 * H, force)  # compiled and warm
    started = time.perf_counter()
    for _ in range(count):
        element.advance(1000 * H, force)
    return (time.perf_counter() - started) / (1000 * count)


def host_step(host, extracted, force: float, count: int) -> tuple:
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin")}
    outputs = [str(extracted.vr[name]) for name in extracted.outputs]
    commands = ["setup", "enter", f"setb:{extracted.vr['scene_load']}:0", "exit", f"setr:{extracted.vr['F']}:{force!r}",
                f"steps:0:{H!r}:1000",
                f"timeit:{1000 * H!r}:{H!r}:{count}", f"timeit:{1000 * H + count * H!r}:{H!r}:{count}:"
                + ":".join(outputs), "free"]
    code, _, _, _, out = run_host(host, extracted, commands, env=env)
    times = [float(line.split()[1]) for line in out.splitlines() if line.startswith("TIME ")]
    if code != 0 or len(times) != 2:
        raise RuntimeError(f"the C host failed ({code}): {out[-400:]}")
    return times[0] / count, times[1] / count


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", default="10,100,1000")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--out", default="docs/bench/network_fmu_overhead.csv")
    args = parser.parse_args()
    from prandtl_fmu.fmu.native.build import build_native_network_fmu
    from prandtl_fmu.scene import parse_scene

    rows = []
    with tempfile.TemporaryDirectory(prefix="network_fmu_bench_") as scratch:
        scratch = Path(scratch)
        host = compile_host(scratch)
        for n in map(int, args.sizes.split(",")):
            path = scratch / f"chain{n}.toml"
            path.write_text(scene_text(n))
            scene = parse_scene(path.read_text(), source=str(path))
            started = time.perf_counter()
            fmu = build_native_network_fmu(path, scratch / f"chain{n}.fmu")
            built = time.perf_counter() - started
            extracted = Extracted(fmu, scratch / f"chain{n}")
            force = 0.6 * n
            count = max(200, 200000 // n)
            library, bare, reading = [], [], []
            for _ in range(args.repeat):
                library.append(library_step(scene, force, max(2, count // 1000)))
                step, read = host_step(host, extracted, force, count)
                bare.append(step)
                reading.append(read)
            lib, c_host, c_read = np.median(library), np.median(bare), np.median(reading)
            rows.append({"n": n, "build_s": f"{built:.1f}", "library_step_us": f"{lib * 1e6:.3f}",
                         "c_host_dostep_us": f"{c_host * 1e6:.3f}", "c_host_dostep_read_all_us": f"{c_read * 1e6:.3f}",
                         "ratio_dostep_to_library": f"{c_host / lib:.2f}",
                         "outputs": len(extracted.outputs)})
            print(rows[-1], flush=True)
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
