"""What one doStep of the native FMU costs on top of the library's step, against Reference-FMUs' Dahlquist (issue 46).

Problem: the paper's section 8 scene (n = 100 branches on the memory stack, h = 1e-3 s, 'projected'), force held at
0.3 N (scene_load false), in the plain C host of tests/c_host/fmi2_host.c, which never loads Python; x is read after
every doStep (one fmi2GetReal). Five runs, interleaved, ``--repeat`` times each, the median reported:

* ``one_step_us``: a doStep of one internal step (H = h), x read, with the FMU as built for users (linked by zig
  where it is installed): what a master that steps at h pays;
* ``library_step_us``: a doStep of 1000 internal steps (H = 1000 h), x read, divided by 1000: the library's own
  step (the kernel's loop), every per-call cost spread over 1000 steps;
* ``cc_one_step_us``: ``one_step_us`` with the FMU's C compiled by this machine's C compiler (-O2), as Dahlquist;
* ``kernel_step_us``: the same build with ``-DPRANDTL_BENCH_KERNEL_ONLY``: a doStep that is the kernel's advance of
  one step and nothing else (element.h), what the library's ``Element.advance`` pays for its compiled part
  (the call into the kernels, the loop's entry, the step);
* ``dahlquist_us``: a doStep of Reference-FMUs' Dahlquist FMU (x' = -k x: one forward Euler step of its fixed
  solver step, H = 0.1 s; a shorter H takes no step at all), x read, in the same host: the FMI plumbing of a
  model whose step costs nothing.

``core_us``, the median over the repeats of ``cc_one_step_us - kernel_step_us``, is what the C layer adds to a
step (the call's checks, the clock, the checkpoint that a refused step rolls back to, the check that no output is
shown NaN or inf, the getReal); ``core_over_dahlquist`` the median of its ratio to Dahlquist's whole doStep in the
same repeat (the target of issue 46: at most 1.2). ``added_over_dahlquist``, the same of ``(one_step_us -
library_step_us) / dahlquist_us``, also counts the kernel's per-call cost, which the library's own advance pays
too.

Dahlquist is built here from a checkout of https://github.com/modelica/Reference-FMUs (``--reference-fmus DIR``;
its sources are not part of this project): ``DIR/Dahlquist``, ``DIR/include``, ``DIR/src``. The native FMUs are
built from the working tree (``--fmu`` takes the users' build already made, e.g. an older one for a before/after
comparison; the two C-compiler builds are always made now).

    python benchmarks/dostep_cost.py --reference-fmus /tmp/Reference-FMUs [--fmu p.fmu] [--repeat 9]
        [--count 200000] [--out out/dostep_cost.csv]
"""
import argparse
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))
from common import write_rows  # noqa: E402
from native_host import Extracted, compile_host, run_host  # noqa: E402

SCENE = ROOT / "scenes" / "paper-section-8.toml"
DAHLQUIST_GUID = "{221063D2-EF4A-45FE-B954-B5BFEEA9A59B}"  # Dahlquist/config.h's INSTANTIATION_TOKEN
DAHLQUIST_X = 1  # Dahlquist/FMI2.xml: x's value reference
DAHLQUIST_STEP = 0.1  # Dahlquist/config.h's FIXED_SOLVER_STEP: one step per doStep


def build_dahlquist(reference: Path, folder: Path) -> Path:
    """Dahlquist's FMI 2.0 binary (Reference-FMUs' CMake build of one model: fmi2Functions.c, model.c,
    cosimulation.c in one unit, DISABLE_PREFIX), with the same optimisation as the native FMU (-O2)."""
    compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    unit = folder / "all2.c"
    unit.write_text('#define FMI_VERSION 2\n#include "fmi2Functions.c"\n#include "model.c"\n#include "cosimulation.c"\n')
    out = folder / "Dahlquist.so"
    subprocess.run([compiler, "-O2", "-shared", "-fPIC", "-std=c99", "-D_POSIX_C_SOURCE=200809L", "-DDISABLE_PREFIX",
                    f"-I{reference / 'Dahlquist'}", f"-I{reference / 'include'}", f"-I{reference / 'src'}", str(unit),
                    "-o", str(out), "-lm"], check=True)
    return out


def build(out: Path, cflags: str = "") -> Path:
    """The paper scene's native FMU at ``out``: as users get it, or with ``cflags`` compiled by this machine's C
    compiler ($PRANDTL_NATIVE_CFLAGS, platforms.toolchain)."""
    from prandtl_fmu.fmu.build import build_fmu

    saved = os.environ.pop("PRANDTL_NATIVE_CFLAGS", None)
    if cflags:
        os.environ["PRANDTL_NATIVE_CFLAGS"] = cflags
    try:
        return build_fmu(SCENE, out, runtime="native")
    finally:
        os.environ.pop("PRANDTL_NATIVE_CFLAGS", None)
        if saved is not None:
            os.environ["PRANDTL_NATIVE_CFLAGS"] = saved


class Dahlquist:
    """The host's view of the Dahlquist binary (run_host's Extracted)."""

    def __init__(self, library: Path):
        self.library, self.resources, self.guid = library, library.parent.as_uri(), DAHLQUIST_GUID
        self.vr = {"x": DAHLQUIST_X}


def seconds(host, fmu, start, h, count) -> float:
    """One host run: ``start`` commands, then ``count`` doSteps of ``h`` each followed by a getReal of x."""
    code, _, _, _, out = run_host(host, fmu, ["setup", "enter", *start, "exit", f"timeit:0:{h!r}:{count}:x", "term",
                                              "free"], env={"PATH": os.environ.get("PATH", "/usr/bin:/bin")})
    if code != 0:
        raise SystemExit(out[-2000:])
    return float(next(line.split()[1] for line in out.splitlines() if line.startswith("TIME ")))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reference-fmus", type=Path, required=True, help="a checkout of modelica/Reference-FMUs")
    parser.add_argument("--fmu", type=Path, help="the native FMU of the paper scene (default: built now)")
    parser.add_argument("--repeat", type=int, default=9)
    parser.add_argument("--count", type=int, default=200000, help="doSteps of one internal step per run")
    parser.add_argument("--out", default=str(ROOT / "out" / "dostep_cost.csv"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        fmus = {"one_step_us": args.fmu or build(scratch / "paper.fmu"),
                "cc_one_step_us": build(scratch / "cc.fmu", "-O2"),
                "kernel_step_us": build(scratch / "kernel.fmu", "-O2 -DPRANDTL_BENCH_KERNEL_ONLY")}
        extracted = {name: Extracted(fmu, scratch / name) for name, fmu in fmus.items()}
        dahlquist = Dahlquist(build_dahlquist(args.reference_fmus, scratch))
        host = compile_host(scratch)
        start = ["setb:scene_load:0", "setr:F:0.3"]  # F alone, the scene's stepper
        h, coarse = 1e-3, args.count // 1000
        samples = {name: [] for name in ("one_step_us", "library_step_us", "cc_one_step_us", "kernel_step_us",
                                         "dahlquist_us")}
        for _ in range(args.repeat):  # interleaved: the machine's load falls on all of them alike
            for name, fmu in extracted.items():
                samples[name].append(seconds(host, fmu, start, h, args.count) / args.count * 1e6)
            samples["library_step_us"].append(seconds(host, extracted["one_step_us"], start, 1000 * h, coarse)
                                              / (coarse * 1000) * 1e6)
            samples["dahlquist_us"].append(seconds(host, dahlquist, [], DAHLQUIST_STEP, args.count) / args.count
                                           * 1e6)
    row = {name: float(np.median(values)) for name, values in samples.items()}
    core = np.subtract(samples["cc_one_step_us"], samples["kernel_step_us"])  # paired within a repeat
    row["core_us"] = float(np.median(core))
    row["core_over_dahlquist"] = float(np.median(core / np.array(samples["dahlquist_us"])))
    row["added_over_dahlquist"] = float(np.median(np.subtract(samples["one_step_us"], samples["library_step_us"])
                                                  / np.array(samples["dahlquist_us"])))
    row.update(fmu=str(args.fmu or "built now"), repeat=args.repeat, count=args.count, machine=platform.machine(),
               spread_core_us=float(np.ptp(np.subtract(samples["cc_one_step_us"], samples["kernel_step_us"]))),
               spread_dahlquist_us=float(np.ptp(samples["dahlquist_us"])))
    for name, value in row.items():
        print(f"{name}: {value:.4g}" if isinstance(value, float) else f"{name}: {value}")
    write_rows(args.out, [row])


if __name__ == "__main__":
    main()
