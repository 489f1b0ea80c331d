"""What the FMU costs on top of the library, per communication step.

Problem: the paper's section 8 scene (n = 100, h = 1e-3), force held at
0.3 N. For each stepper, the same sequence of communication steps is run

* by the library: ``Element.advance(H, F)``;
* by the FMU, built by build_fmu.py and driven by FMPy's FMU2Slave
  (``setReal(F)`` + ``doStep``), which adds ctypes, PythonFMU's C++ and the
  slave's checks;

with H = 1000 h (the target: the FMU within 1.2x of the library) and H = h
(one internal step: the fixed overhead per doStep). The native FMU of the same
scene (``--runtime native``: the library's kernels and a C FMI layer) is run
the same way in FMPy (``native_us``) and, with one internal step per doStep,
in the C host of tests/c_host, which never loads Python (``native_c_host_us``:
doStep alone, and ``native_c_host_read_all_us``: doStep and one getReal of
every output), against the library's compiled step and the PythonFMU FMU.
``native_first_step_ms``: instantiate .. the first doStep in the C host,
including the process's start. Repeats are interleaved
and the median per communication step is reported, with the ratio measured in
the same run. With H = h the FMU also reads every output after each step
(one getReal of all of them, as a master's observer does): ``read_all_us`` is
what that read adds to a step, each output computed once per step however
many are read. ``read_x_warm_us`` and ``read_all_warm_us`` time one getReal
of x alone and of every output when they are already computed: the hosts'
own cost per call and per variable.

    python benchmarks/fmu_overhead.py [--repeat 7] [--out out/fmu_overhead.csv]
"""
import argparse
import os
import platform
import sys
import tempfile
import time

from pathlib import Path

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, ROOT)
from common import write_rows  # noqa: E402
sys.path.insert(0, os.path.join(ROOT, "tests"))

from prandtl_fmu import Element, load_scene  # noqa: E402
from prandtl_fmu.fmu.build import build_fmu  # noqa: E402
from fmu_tools import Slave  # noqa: E402
from native_host import Extracted, compile_host, run_host  # noqa: E402

SCENE = os.path.join(ROOT, "scenes", "paper-section-8.toml")


def library_run(stepper, size, count):
    element = Element(load_scene(SCENE), stepper=stepper)
    element.advance(size, 0.3)  # compile
    start = time.perf_counter()
    for _ in range(count):
        element.advance(size, 0.3)
    return (time.perf_counter() - start) / count


def fmu_run(slave, size, count, read=()):
    """Seconds per communication step: setReal(F), doStep and, with ``read``, one getReal of those value
    references."""
    fmu, vr = slave.fmu, [slave.vr["F"]]
    t = slave.time
    start = time.perf_counter()
    for _ in range(count):
        fmu.setReal(vr, [0.3])
        fmu.doStep(t, size)
        if read:
            fmu.getReal(read)
        t += size
    slave.time = t
    return (time.perf_counter() - start) / count


def c_host_run(host, extracted, stepper, h, count, repeat):
    """(s per doStep, s per doStep + getReal of every output, ms from the host's start to its first doStep's
    end): the native FMU in the C host, which never loads Python."""
    outputs_vr = [str(extracted.vr[name]) for name in extracted.outputs]
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin")}
    bare, reading, first = [], [], []
    for _ in range(repeat):
        started = time.perf_counter()
        code, _, _, _, out = run_host(host, extracted, ["setup", "enter", "setb:scene_load:0", "exit", f"step:0:{h!r}",
                                                        "free"], env=env)
        first.append((time.perf_counter() - started) * 1e3)
        commands = ["setup", "enter", "setb:scene_load:0", "exit", f"timeit:0:{h!r}:{count * 10}",
                    f"timeit:0:{h!r}:{count * 10}:" + ":".join(outputs_vr), "free"]
        code, _, _, _, out = run_host(host, extracted, commands, env=env)
        times = [float(line.split()[1]) for line in out.splitlines() if line.startswith("TIME ")]
        bare.append(times[0] / (count * 10))
        reading.append(times[1] / (count * 10))
    return np.median(bare), np.median(reading), np.median(first)


def warm_read(slave, refs, count=20000):
    """Seconds per getReal of ``refs`` with the outputs already computed (no step in between)."""
    fmu = slave.fmu
    fmu.getReal(refs)
    start = time.perf_counter()
    for _ in range(count):
        fmu.getReal(refs)
    return (time.perf_counter() - start) / count


def outputs(slave):
    """The value references of every output of the FMU."""
    return [v.valueReference for v in slave.md.modelVariables if v.causality == "output"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "fmu_overhead.csv"))
    args = parser.parse_args()
    h = load_scene(SCENE).solver.step
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        fmu = build_fmu(SCENE, os.path.join(folder, "element.fmu"))
        started = time.perf_counter()
        native = build_fmu(SCENE, os.path.join(folder, "native.fmu"), runtime="native")
        print(f"native FMU built in {time.perf_counter() - started:.1f} s")
        extracted = Extracted(native, Path(folder) / "native")
        host = compile_host(Path(folder))
        print(f"machine: {platform.machine()}, python {platform.python_version()}, n = 100, h = {h}")
        for stepper in ("projected", "implicit"):
            slave = Slave(fmu, start_values={"stepper": stepper})
            slave.step(h, 0.3)  # compile inside the FMU
            native_slave = Slave(native, start_values={"stepper": stepper})
            for internal, count in ((1000, 200), (1, 5000)):
                size = internal * h
                lib, ours, reading, natives = [], [], [], []
                for _ in range(args.repeat):
                    lib.append(library_run(stepper, size, count))
                    ours.append(fmu_run(slave, size, count))
                    natives.append(fmu_run(native_slave, size, count))
                    if internal == 1:
                        reading.append(fmu_run(slave, size, count, read=outputs(slave)))
                lib_s, fmu_s = np.median(lib), np.median(ours)
                read_s = np.median(reading) - fmu_s if reading else float("nan")
                warm = [(warm_read(slave, [slave.vr["x"]]), warm_read(slave, outputs(slave))) for _ in range(3)] \
                    if reading else [(float("nan"), float("nan"))]
                warm_x, warm_all = np.median([w[0] for w in warm]), np.median([w[1] for w in warm])
                native_s = np.median(natives)
                if internal > 1:  # the library's compiled step alone: a long advance, per internal step
                    compiled_step = lib_s / internal
                host_s, host_read_s, first_ms = (c_host_run(host, extracted, stepper, h, count, args.repeat)
                                                 if internal == 1 else (float("nan"),) * 3)
                rows.append({"stepper": stepper, "internal_steps": internal,
                             "native_us": f"{native_s * 1e6:.2f}", "native_c_host_us": f"{host_s * 1e6:.3f}",
                             "native_c_host_read_all_us": f"{host_read_s * 1e6:.3f}",
                             "native_first_step_ms": f"{first_ms:.2f}",
                             "compiled_step_us": f"{compiled_step * 1e6:.3f}",
                             "library_us": f"{lib_s * 1e6:.2f}", "fmu_us": f"{fmu_s * 1e6:.2f}",
                             "overhead_us": f"{(fmu_s - lib_s) * 1e6:.2f}", "ratio": f"{fmu_s / lib_s:.3f}",
                             "outputs": len(outputs(slave)), "read_all_us": f"{read_s * 1e6:.2f}",
                             "read_x_warm_us": f"{warm_x * 1e6:.2f}", "read_all_warm_us": f"{warm_all * 1e6:.2f}"})
                print(f"{stepper:9s} H = {internal:4d} h: library {lib_s * 1e6:9.2f} us, FMU {fmu_s * 1e6:9.2f} us"
                      f"  (x{fmu_s / lib_s:.3f}, +{(fmu_s - lib_s) * 1e6:.1f} us per doStep)"
                      + (f"; reading all {len(outputs(slave))} outputs +{read_s * 1e6:.1f} us (already computed: x "
                         f"{warm_x * 1e6:.1f} us, all {warm_all * 1e6:.1f} us)" if reading else ""))
                print(f"{'':9s}   native FMU: FMPy {native_s * 1e6:9.2f} us (PythonFMU / native: "
                      f"x{fmu_s / native_s:.1f})" + (f"; C host {host_s * 1e6:.3f} us per doStep (x{host_s / lib_s:.2f}"
                      f" the library's Element.advance, x{host_s / compiled_step:.2f} its compiled step "
                      f"{compiled_step * 1e6:.3f} us), {host_read_s * 1e6:.3f} us reading every output; "
                      f"instantiate .. first doStep {first_ms:.1f} ms with the process" if internal == 1 else ""))
            slave.close()
            native_slave.close()
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
