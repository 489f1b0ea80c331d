"""The native FMU on every platform: the build time per platform, the FMU's size, the doStep cost of each binary.

Problem: the paper's section 8 scene (n = 100 on the memory stack, h = 1e-3, every native stepper), built once
for every platform FMI 2.0 names (linux64, win64, darwin64: a universal dylib) and once for every platform FMI 3.0
names (``--platforms all``). Reported:

* ``build``: the seconds of each binary (its objects emitted by llvmlite for the target, the C layer compiled and
  linked: ``platforms.build_binaries``), and the whole build's (the PythonFMU build whose model description it
  takes and numba's compile of the kernels, done once for all platforms, included); warm numba and zig caches;
* ``size``: each binary's bytes and the FMU's;
* ``step``: one doStep of one internal step under F = 0.3 N (scene_load false: F alone, as the library's step is
  timed) and one getReal of every output, in the C host of
  tests/c_host/cross_host.c (built for each platform: gcc, mingw-w64, aarch64-linux-gnu-gcc), against the library's
  compiled step alone (``Element.advance`` of 1000 steps, per step), timed just before each run of the host: the
  ratio is the median of the runs' ratios (the machine is shared: its load drifts between runs). The win64 binary runs
  under wine and the aarch64 one under qemu-user: their figures are **emulated** (qemu translates every
  instruction; wine runs x86-64 code natively but its own loader and C library), quoted as the ratio only.
  Medians of ``--repeat`` runs.

    python benchmarks/platforms_cost.py [--repeat 5] [--out out/platforms_cost.csv]

The Debian packages it needs (gcc-mingw-w64-x86-64, gcc-aarch64-linux-gnu, qemu-user, wine64) and zig (ziglang)
are those of tests/fmu/native/test_platforms.py; a platform whose runner is missing is left out and said so.
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from common import write_rows  # noqa: E402

from prandtl_fmu import Element, load_scene  # noqa: E402
from prandtl_fmu.fmu.build import build_fmu  # noqa: E402
from prandtl_fmu.fmu.native import platforms  # noqa: E402

SCENE = ROOT / "scenes" / "paper-section-8.toml"
HOST = ROOT / "tests" / "c_host" / "cross_host.c"
HEADERS = {2: ROOT / "prandtl_fmu" / "fmu" / "python" / "loader" / "src" / "fmi",
           3: ROOT / "prandtl_fmu" / "fmu" / "native" / "fmi3"}
WINE = "/usr/lib/wine/wine64"
STEPPERS = ("projected", "implicit")


def timed_build(fmi, folder):
    """(FMU path, whole seconds, {platform: seconds of its binary})."""
    seconds = {}
    build_binaries = platforms.build_binaries

    def recording(*args, **kwargs):
        binaries, spent = build_binaries(*args, **kwargs)
        seconds.update(spent)
        return binaries, spent

    platforms.build_binaries = recording
    try:
        started = time.perf_counter()
        fmu = build_fmu(SCENE, Path(folder) / f"paper-fmi{fmi}.fmu", runtime="native", fmi=fmi, platforms="all")
        return fmu, time.perf_counter() - started, seconds
    finally:
        platforms.build_binaries = build_binaries


def library_step(stepper, h, count=100, repeat=1):
    """Seconds of one internal step of the library's compiled kernel (a 1000-step advance, per step)."""
    element = Element(load_scene(SCENE), stepper=stepper)
    element.advance(1000 * h, 0.3)
    runs = []
    for _ in range(repeat):
        started = time.perf_counter()
        for _ in range(count):
            element.advance(1000 * h, 0.3)
        runs.append((time.perf_counter() - started) / (count * 1000))
    return float(np.median(runs))


def runner(platform_name, folder):
    """(argv prefix that runs a host built for the platform, the host's compiler, label) or None."""
    if platform_name in ("linux64", "x86_64-linux") and platforms.host_target().name == "x86_64-linux":
        return [], shutil.which("gcc") or shutil.which("cc"), "native"
    if platform_name in ("win64", "x86_64-windows") and platforms.mingw() and os.path.exists(WINE):
        prefix = Path(folder) / "wineprefix"
        os.environ.update(WINEDEBUG="-all", WINEPREFIX=str(prefix))
        return [WINE], platforms.mingw()[0], "emulated: wine"
    if platform_name == "aarch64-linux" and shutil.which("qemu-aarch64") and shutil.which("aarch64-linux-gnu-gcc"):
        return [shutil.which("qemu-aarch64"), "-L", "/usr/aarch64-linux-gnu"], shutil.which(
            "aarch64-linux-gnu-gcc"), "emulated: qemu-user"
    return None


def host_step(fmu, fmi, platform_name, folder, stepper, h, count, repeat):
    """(seconds per doStep + getReal of every output of one platform's binary in its C host, the median of the
    ratios to the library's step timed just before each run: the machine's load drifts), or (None, why)."""
    found = runner(platform_name, folder)
    if found is None:
        return None, None, "no runner here"
    prefix, compiler, label = found
    root = ET.fromstring(zipfile.ZipFile(fmu).read("modelDescription.xml"))
    variables = list(root.iter("ScalarVariable")) if fmi == 2 else list(root.find("ModelVariables"))
    vr = {v.get("name"): v.get("valueReference") for v in variables}
    outputs = [v.get("valueReference") for v in variables if v.get("causality") == "output"]
    token = root.get("guid") if fmi == 2 else root.get("instantiationToken")
    with zipfile.ZipFile(fmu) as archive:
        (entry,) = [name for name in archive.namelist() if name.startswith(f"binaries/{platform_name}/")]
        library = Path(folder) / f"{platform_name}-{Path(entry).name}"
        library.write_bytes(archive.read(entry))
    host = Path(folder) / f"host-{platform_name}-{fmi}{'.exe' if 'mingw' in compiler else ''}"
    if not host.exists():
        extra = [] if "mingw" in compiler else ["-D_POSIX_C_SOURCE=200809L"]
        subprocess.run([compiler, "-std=c99", "-O2", *extra, f"-DFMI_VERSION={fmi}", f"-I{HEADERS[fmi]}", str(HOST),
                        "-o", str(host), *([] if "mingw" in compiler else ["-ldl"])], check=True)
    runs, ratios = [], []
    for _ in range(repeat):
        reference = library_step(stepper, h)
        done = subprocess.run([*prefix, str(host), str(library), token, "file:///unused", vr["stepper"], stepper,
                               vr["F"], ",".join(outputs), f"noload:{vr['scene_load']}", f"time:{count}:{h!r}:0.3"],
                              capture_output=True,
                              text=True, check=True)
        runs.append(float(done.stdout.split()[-1]) / count)
        ratios.append(runs[-1] / reference)
    return float(np.median(runs)), float(np.median(ratios)), label


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--count", type=int, default=100000, help="doSteps per timed run (native; emulated: 1/5)")
    parser.add_argument("--out", default=str(ROOT / "out" / "platforms_cost.csv"))
    args = parser.parse_args()
    h = load_scene(SCENE).solver.step
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        built = {fmi: timed_build(fmi, folder) for fmi in (2, 3)}
        for fmi, (fmu, whole, seconds) in built.items():
            rows.append({"what": "fmu", "fmi": fmi, "platform": "all", "seconds": round(whole, 2),
                         "bytes": fmu.stat().st_size, "stepper": "", "us_per_step": "", "ratio_to_library": "",
                         "run": ""})
            with zipfile.ZipFile(fmu) as archive:
                sizes = {name.split("/")[1]: archive.getinfo(name).file_size for name in archive.namelist()
                         if name.startswith("binaries/")}
            for name, spent in seconds.items():
                rows.append({"what": "binary", "fmi": fmi, "platform": name, "seconds": round(spent, 2),
                             "bytes": sizes[name], "stepper": "", "us_per_step": "", "ratio_to_library": "",
                             "run": ""})
        library = {stepper: library_step(stepper, h, count=200, repeat=args.repeat) for stepper in STEPPERS}
        for stepper in STEPPERS:
            rows.append({"what": "library step", "fmi": "", "platform": "", "seconds": "", "bytes": "",
                         "stepper": stepper, "us_per_step": round(library[stepper] * 1e6, 4), "ratio_to_library": 1,
                         "run": "native"})
        for fmi, platform_name in ((2, "linux64"), (3, "x86_64-linux"), (2, "win64"), (3, "aarch64-linux")):
            fmu = built[fmi][0]
            for stepper in STEPPERS:
                emulated = platform_name in ("win64", "aarch64-linux")
                step, ratio, label = host_step(fmu, fmi, platform_name, folder, stepper, h,
                                               args.count // 5 if emulated else args.count, args.repeat)
                rows.append({"what": "doStep", "fmi": fmi, "platform": platform_name, "seconds": "", "bytes": "",
                             "stepper": stepper,
                             "us_per_step": "" if step is None or emulated else round(step * 1e6, 4),
                             "ratio_to_library": "" if step is None else round(ratio, 2),
                             "run": label})
    for row in rows:
        print(row)
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
