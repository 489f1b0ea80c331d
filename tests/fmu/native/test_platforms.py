"""One native FMU, every platform (issue 33): ``--platforms`` names, the binaries' checks, the binaries run.

* The names: each FMI version's, the other's for the same target, ``all``; aarch64 Linux refused by FMI 2.0 in one
  line; a missing toolchain named with its package.
* The win64 binary in a C host built by mingw-w64, under wine; the aarch64-linux binary in a C host built by
  aarch64-linux-gnu-gcc, under qemu-user: every output after every step equals the library's to the bit, for every
  stepper (tests/c_host/cross_host.c); a network's (NetworkElement's) the same way.
* Every Linux binary (the default build's too) needs glibc 2.17 at most; the darwin binaries (a universal dylib for
  FMI 2.0's darwin64) export the FMI functions only and import libSystem only (read here from the Mach-O load
  commands: no Mac needed); the Windows binary exports the FMI functions only and imports KERNEL32 and msvcrt.
* FMPy's validate_fmu on the multi-platform FMUs.

The cross toolchains, wine and qemu are Debian packages (.ci/run installs them); where one is missing its test is
skipped and says which package."""
import os
import re
import shutil
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest

from prandtl_fmu.fmu.native import platforms
from prandtl_fmu.fmu.native.platforms import PlatformError, resolve

from tests.conftest import base_tables, scene_text
from tests.paths import ROOT, TESTS

HOST_SOURCE = TESTS / "c_host" / "cross_host.c"
FMI2_HEADERS = ROOT / "prandtl_fmu" / "fmu" / "python" / "loader" / "src" / "fmi"
FMI3_HEADERS = ROOT / "prandtl_fmu" / "fmu" / "native" / "fmi3"
WINE = "/usr/lib/wine/wine64"
ENERGIES = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
            "dissipated_friction", "energy_residual")
# every native stepper applies: Coulomb friction, series dashpots, three branches (exact included)
SCENE = base_tables(cubic=None, solver={"stepper": "exact", "step": 0.01, "stop_time": 10.0, "output_interval": 0.1},
                    friction={"alpha": 0.1},
                    branches={"k": [0.5, 2.0, 0.3], "eta": [0.1, 0.3, 0.05], "c": [0.4, 2.0, 9.0]},
                    load={"kind": "harmonic", "amplitude": 0.8, "omega": 1.3})


# what zig's Mach-O linker exports from every dylib it links (the image's own header and its handle): no
# -exported_symbols_list there; harmless under the two-level namespace (a symbol is looked up in its dylib)
ZIG_MACHO_SYMBOLS = {"__mh_dylib_header", "___dso_handle"}


def names(folders):
    return [folder.name for folder in folders]


# ------------------------------------------------------------------ the names (quick)

def test_each_version_names_its_platforms_and_takes_the_other_s_names():
    assert names(resolve("linux64,win64,darwin64", 2)) == ["linux64", "win64", "darwin64"]
    assert names(resolve("x86_64-windows,x86_64-linux", 2)) == ["win64", "linux64"]
    assert names(resolve("win64,x86_64-windows", 3)) == ["x86_64-windows"]
    assert names(resolve("all", 2)) == ["linux64", "win64", "darwin64"]
    assert names(resolve("all", 3)) == ["x86_64-linux", "aarch64-linux", "x86_64-windows", "x86_64-darwin",
                                        "aarch64-darwin"]
    # darwin64 is one universal dylib of both Mac targets; under FMI 3.0 the two targets' folders
    (darwin,) = resolve("darwin64", 2)
    assert [target.name for target in darwin.targets] == ["x86_64-darwin", "aarch64-darwin"]
    assert names(resolve("aarch64-darwin", 2)) == ["darwin64"]
    assert names(resolve("darwin64", 3)) == ["x86_64-darwin", "aarch64-darwin"]
    assert names(resolve(None, 3)) == [platforms.host_target().name]  # none given: this machine's


@pytest.mark.parametrize("given, words", [
    ("aarch64-linux", "--platforms aarch64-linux: FMI 2.0 has no platform name for it"),
    ("linux64,sparc-solaris", "--platforms: unknown platform 'sparc-solaris'"),
    ("linux64,,win64", "--platforms linux64,,win64: an empty name"),
])
def test_a_platform_fmi_2_cannot_name_or_an_unknown_one_is_refused_in_one_line(given, words):
    with pytest.raises(PlatformError) as refused:
        resolve(given, 2)
    assert str(refused.value).startswith(words) and "\n" not in str(refused.value)


def test_the_command_line_refuses_a_platform_before_anything_is_written(tmp_path, capsys):
    from prandtl_fmu.cli import main

    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text(SCENE))
    out = tmp_path / "out.fmu"
    code = main(["build", str(scene), "-o", str(out), "--runtime", "native", "--platforms", "linux64,aarch64-linux"])
    error = capsys.readouterr().err
    assert code == 2 and error.count("\n") == 1 and "FMI 2.0 has no platform name" in error, error
    assert not any(tmp_path.glob("out.fmu*"))
    code = main(["build", str(scene), "-o", str(out), "--platforms", "linux64"])  # the PythonFMU runtime
    assert code == 2 and "--platforms" in capsys.readouterr().err


def test_a_missing_toolchain_is_named_with_its_package(monkeypatch):
    monkeypatch.setattr(platforms, "zig", lambda: [])
    monkeypatch.setattr(platforms, "mingw", lambda: [])
    for given, package in (("aarch64-linux", "pip install ziglang"), ("x86_64-darwin", "pip install ziglang"),
                           ("x86_64-windows", "apt-get install gcc-mingw-w64-x86-64")):
        with pytest.raises(PlatformError) as refused:
            platforms.toolchains(resolve(given, 3), default=False)
        assert package in str(refused.value) and "\n" not in str(refused.value)


def test_the_default_build_without_zig_says_what_its_binary_needs(monkeypatch):
    monkeypatch.setattr(platforms, "zig", lambda: [])
    monkeypatch.delenv("PRANDTL_NATIVE_CFLAGS", raising=False)
    if platforms.host_target().name != "x86_64-linux":
        pytest.skip("the default build's fallback is checked on x86-64 Linux")
    with pytest.warns(UserWarning, match="needs this machine's glibc"):
        (chain,) = platforms.toolchains(resolve(None, 2), default=True).values()
    assert chain.kind == "cc"


def test_numba_s_x86_decrement_becomes_a_portable_atomic():
    text = ("declare i8 @llvm.x86.atomic.sub.cc.i64(ptr, i64, i32)\n"
            "define void @f(ptr %.1) {\n  %0 = tail call i8 @llvm.x86.atomic.sub.cc.i64(ptr nonnull %.1, i64 1, "
            "i32 4)\n  ret void\n}\n")
    portable = platforms.portable_ir(text)
    assert "llvm.x86" not in portable and "atomicrmw sub ptr %.1, i64 1 seq_cst" in portable
    assert "%0 = zext i1 %prandtl.decref.0.zero to i8" in portable


def test_a_universal_dylib_holds_each_slice_at_its_offset():
    thin = {cpu: struct.pack("<IIII", 0xFEEDFACF, cpu, 3, 6) + bytes([cpu & 0xFF]) * 100
            for cpu in (0x01000007, 0x0100000C)}
    fat = platforms.universal(list(thin.items()))
    assert fat_slices(fat) == thin


# ------------------------------------------------------------------ Mach-O, read statically

def fat_slices(data: bytes) -> dict:
    """{cpu type: thin Mach-O} of a fat file (or the one thin file)."""
    if struct.unpack(">I", data[:4])[0] != 0xCAFEBABE:
        return {struct.unpack("<I", data[4:8])[0]: data}
    count = struct.unpack(">I", data[4:8])[0]
    slices = {}
    for i in range(count):
        cpu, _, offset, size, _ = struct.unpack(">iiIII", data[8 + 20 * i:28 + 20 * i])
        slices[cpu & 0xFFFFFFFF] = data[offset:offset + size]
    return slices


def _uleb(data: bytes, at: int) -> tuple:
    value = shift = 0
    while True:
        byte = data[at]
        at += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return value, at


def macho_symbols(data: bytes) -> tuple:
    """(exported, imported symbols, dylibs loaded) of a thin 64-bit Mach-O: the export trie dyld reads
    (LC_DYLD_INFO's or LC_DYLD_EXPORTS_TRIE's), the undefined symbols of LC_SYMTAB (LC_DYSYMTAB's range),
    LC_LOAD_DYLIB's names."""
    magic, _, _, _, ncmds, _, _, _ = struct.unpack("<IiiIIIII", data[:32])
    assert magic == 0xFEEDFACF
    at, symtab, dysymtab, trie, dylibs = 32, None, None, None, []
    for _ in range(ncmds):
        command, size = struct.unpack("<II", data[at:at + 8])
        if command == 0x2:  # LC_SYMTAB
            symtab = struct.unpack("<IIII", data[at + 8:at + 24])
        elif command == 0xB:  # LC_DYSYMTAB
            dysymtab = struct.unpack("<18I", data[at + 8:at + 80])
        elif command in (0x22, 0x80000022):  # LC_DYLD_INFO(_ONLY): the export trie's offset and size
            trie = struct.unpack("<II", data[at + 40:at + 48])
        elif command == 0x80000033:  # LC_DYLD_EXPORTS_TRIE
            trie = struct.unpack("<II", data[at + 8:at + 16])
        elif command in (0xC, 0x80000018, 0x1F):  # LC_LOAD_DYLIB, LC_LOAD_WEAK_DYLIB, LC_REEXPORT_DYLIB
            offset = struct.unpack("<I", data[at + 8:at + 12])[0]
            dylibs.append(data[at + offset:at + size].split(b"\0")[0].decode())
        at += size
    symoff, _, stroff, _ = symtab

    def name(index):
        strx = struct.unpack("<I", data[symoff + 16 * index:symoff + 16 * index + 4])[0]
        return data[stroff + strx:].split(b"\0")[0].decode()

    iundef, nundef = dysymtab[4:6]
    nodes, exported = data[trie[0]:trie[0] + trie[1]], []

    def walk(node, prefix):
        terminal, at = _uleb(nodes, node)
        if terminal:
            exported.append(prefix)
        at += terminal
        count, at = nodes[at], at + 1
        for _ in range(count):
            end = nodes.index(b"\0", at)
            edge, at = nodes[at:end].decode(), end + 1
            child, at = _uleb(nodes, at)
            walk(child, prefix + edge)

    walk(0, "")
    return exported, [name(i) for i in range(iundef, iundef + nundef)], dylibs


# ------------------------------------------------------------------ the built FMUs (slow)

def _build(folder: Path, fmi: int, given):
    from prandtl_fmu.fmu.build import build_fmu

    scene = folder / "every_stepper.toml"
    scene.write_text(scene_text(SCENE))
    return build_fmu(scene, folder / f"every_stepper-{fmi}-{given or 'default'}.fmu", runtime="native", fmi=fmi,
                     platforms=given)


def _need_zig():
    if not platforms.zig():
        pytest.skip("zig is not installed (pip install ziglang, the test extra): the Linux and darwin binaries are "
                    "linked by zig")


def _need_mingw():
    if not platforms.mingw():
        pytest.skip("mingw-w64's gcc is not installed (apt-get install gcc-mingw-w64-x86-64)")


@pytest.fixture(scope="module")
def fmu2(tmp_path_factory):
    """The scene's FMI 2.0 FMU for every platform FMI 2.0 names (linux64, win64, darwin64)."""
    _need_zig()
    _need_mingw()
    return _build(tmp_path_factory.mktemp("fmi2"), 2, "all")


@pytest.fixture(scope="module")
def fmu3(tmp_path_factory):
    """The scene's FMI 3.0 FMU for every platform FMI 3.0 names."""
    _need_zig()
    _need_mingw()
    return _build(tmp_path_factory.mktemp("fmi3"), 3, "all")


def binary(fmu: Path, folder: str) -> bytes:
    with zipfile.ZipFile(fmu) as archive:
        (name,) = [name for name in archive.namelist() if name.startswith(f"binaries/{folder}/")]
        return archive.read(name)


@pytest.mark.slow
def test_one_fmu_holds_every_platform_s_binary(fmu2, fmu3):
    with zipfile.ZipFile(fmu2) as archive:
        held = sorted(name for name in archive.namelist() if name.startswith("binaries/"))
    identifier = ET.fromstring(zipfile.ZipFile(fmu2).read("modelDescription.xml")).find("CoSimulation").get(
        "modelIdentifier")
    assert held == [f"binaries/darwin64/{identifier}.dylib", f"binaries/linux64/{identifier}.so",
                    f"binaries/win64/{identifier}.dll"]
    with zipfile.ZipFile(fmu3) as archive:
        held = sorted(name.split("/")[1] for name in archive.namelist() if name.startswith("binaries/"))
    assert held == sorted(platforms.TARGETS)


def glibc_floor(library: bytes, tmp_path: Path) -> tuple:
    """The highest GLIBC_x.y symbol version an ELF binary needs (readelf's version needs)."""
    path = tmp_path / "library.so"
    path.write_bytes(library)
    shown = subprocess.run(["readelf", "-V", "-W", str(path)], capture_output=True, text=True, check=True).stdout
    versions = {tuple(int(part) for part in found.split(".")) for found in re.findall(r"GLIBC_(\d+(?:\.\d+)+)", shown)}
    assert versions, shown
    return max(versions)


@pytest.mark.slow
def test_every_linux_binary_needs_glibc_2_17_at_most(fmu2, fmu3, tmp_path_factory, tmp_path):
    if shutil.which("readelf") is None:
        pytest.skip("readelf is not installed (apt-get install binutils)")
    if platforms.host_target().name != "x86_64-linux":
        pytest.skip("the default build checked here is x86-64 Linux's")
    saved = os.environ.pop("PRANDTL_NATIVE_CFLAGS", None)
    try:
        default = _build(tmp_path_factory.mktemp("default"), 2, None)
    finally:
        if saved is not None:
            os.environ["PRANDTL_NATIVE_CFLAGS"] = saved
    found = {"default linux64": glibc_floor(binary(default, "linux64"), tmp_path),
             "linux64": glibc_floor(binary(fmu2, "linux64"), tmp_path),
             "x86_64-linux": glibc_floor(binary(fmu3, "x86_64-linux"), tmp_path),
             "aarch64-linux": glibc_floor(binary(fmu3, "aarch64-linux"), tmp_path)}
    print("highest GLIBC versions:", found)
    assert all(version <= platforms.GLIBC_FLOOR for version in found.values()), found


@pytest.mark.slow
def test_the_darwin_binaries_export_the_fmi_functions_and_import_libsystem_only(fmu2, fmu3):
    checked = {}
    for fmu, folder, fmi in ((fmu2, "darwin64", 2), (fmu3, "x86_64-darwin", 3), (fmu3, "aarch64-darwin", 3)):
        slices = fat_slices(binary(fmu, folder))
        expected = {0x01000007, 0x0100000C} if folder == "darwin64" else {platforms.TARGETS[folder].arch}
        assert set(slices) == expected, (folder, slices.keys())
        for cpu, thin in slices.items():
            exported, imported, dylibs = macho_symbols(thin)
            ours = [symbol for symbol in exported if symbol not in ZIG_MACHO_SYMBOLS]
            assert ours and all(symbol.startswith(f"_fmi{fmi}") for symbol in ours), (folder, exported)
            assert dylibs == ["/usr/lib/libSystem.B.dylib"], (folder, dylibs)
            checked[(folder, hex(cpu))] = sorted(symbol.lstrip("_") for symbol in imported)
    print("darwin imports:", checked)


@pytest.mark.slow
def test_the_windows_binary_exports_the_fmi_functions_and_imports_kernel32_and_msvcrt_only(fmu2, tmp_path):
    objdump = shutil.which("x86_64-w64-mingw32-objdump")
    if objdump is None:
        pytest.skip("x86_64-w64-mingw32-objdump is not installed (apt-get install binutils-mingw-w64-x86-64)")
    path = tmp_path / "library.dll"
    path.write_bytes(binary(fmu2, "win64"))
    shown = subprocess.run([objdump, "-p", str(path)], capture_output=True, text=True, check=True).stdout
    assert sorted(re.findall(r"DLL Name: (\S+)", shown)) == ["KERNEL32.dll", "msvcrt.dll"]
    exported = re.findall(r"^\s+\[\s*\d+\] (\w+)$", shown.split("[Ordinal/Name Pointer] Table")[1], re.M)
    assert exported and all(symbol.startswith("fmi2") for symbol in exported), exported


# the C library's functions whose last bits differ between glibc, msvcrt and libSystem
TRANSCENDENTAL = {"sin", "cos", "tan", "sincos", "__sincos_stret", "asin", "acos", "atan", "atan2", "sinh", "cosh",
                  "tanh", "asinh", "acosh", "atanh", "exp", "exp2", "exp10", "expm1", "log", "log2", "log10", "log1p",
                  "pow", "hypot", "cbrt", "erf", "erfc", "tgamma", "lgamma", "cabs", "csqrt", "cexp", "clog", "cpow"}


def imported_functions(library: bytes, folder: str, tmp_path: Path) -> set:
    """The C library functions a binary imports: ELF's undefined dynamic symbols (readelf), PE's import table
    (mingw's objdump), Mach-O's undefined symbols (every slice)."""
    path = tmp_path / f"library-{folder}"
    path.write_bytes(library)
    if folder in ("win64", "x86_64-windows"):
        shown = subprocess.run([platforms.mingw()[0].replace("gcc", "objdump"), "-p", str(path)], capture_output=True,
                               text=True, check=True).stdout
        return set(re.findall(r"^\t[0-9a-f]+\s+\d+\s+(\w+)$", shown, re.M))
    if "darwin" in folder:
        return {symbol[1:] for thin in fat_slices(library).values() for symbol in macho_symbols(thin)[1]}
    shown = subprocess.run(["readelf", "--dyn-syms", "-W", str(path)], capture_output=True, text=True,
                           check=True).stdout
    return {line.split()[7].split("@")[0] for line in shown.splitlines() if " UND " in line and len(line.split()) > 7}


@pytest.mark.slow
def test_no_binary_s_kernels_call_the_platform_s_libm(fmu2, fmu3, tmp_path):
    """One number everywhere: the kernels' elementary functions are prandtl_fmu.libm's, compiled into every binary,
    and the C layer computes none (its stability check is the library's kernel, stability.check): no binary imports
    a transcendental function of the C library."""
    if shutil.which("readelf") is None:
        pytest.skip("readelf is not installed (apt-get install binutils)")
    found, read = {}, {}
    for fmu, folders in ((fmu2, platforms.FMI2_FOLDERS), (fmu3, platforms.TARGETS)):
        for folder in folders:
            imported = imported_functions(binary(fmu, folder), folder, tmp_path)
            read[folder] = "malloc" in imported  # the reading sees the binary's imports (the C layer's malloc)
            found[folder] = sorted(imported & TRANSCENDENTAL)
    print("transcendental imports:", found)
    assert all(read.values()), read
    assert not any(found.values()), found


@pytest.mark.slow
def test_fmpy_validates_the_multi_platform_fmus(fmu2, fmu3):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu2)) == []
    assert validate_fmu(str(fmu3)) == []


# ------------------------------------------------------------------ the binaries run (wine, qemu)

class Description:
    """What the host needs of an FMU's model description: the token, the value references by name."""

    def __init__(self, fmu: Path, fmi: int):
        root = ET.fromstring(zipfile.ZipFile(fmu).read("modelDescription.xml"))
        self.token = root.get("guid") if fmi == 2 else root.get("instantiationToken")
        variables = list(root.iter("ScalarVariable")) if fmi == 2 else list(root.find("ModelVariables"))
        self.vr = {v.get("name"): int(v.get("valueReference")) for v in variables}
        self.identifier = root.find("CoSimulation").get("modelIdentifier")
        self.outputs = [v.get("name") for v in variables if v.get("causality") == "output"]


def compile_cross_host(compiler: str, fmi: int, out: Path) -> Path:
    headers = FMI2_HEADERS if fmi == 2 else FMI3_HEADERS
    extra = [] if "mingw" in compiler else ["-D_POSIX_C_SOURCE=200809L", "-ldl"]
    subprocess.run([compiler, "-std=c99", "-O1", "-Wall", "-Werror", f"-DFMI_VERSION={fmi}", f"-I{headers}",
                    str(HOST_SOURCE), "-o", str(out), *extra[:1], *extra[1:]], check=True, capture_output=True)
    return out


def bits(value: float) -> str:
    return struct.pack(">d", value).hex()


def expected(element, names):
    values = {"x": element.x, "v": element.v, "reaction": element.reaction, "stiffness": element.stiffness()}
    return [values[name] if name in values else element.energy_of(name) for name in names]


def compare_with_the_library(run, fmu: Path, fmi: int, label: str, network: bool = False):
    """Every stepper: 40 random communication steps (sizes not all multiples of the step, random forces) in the
    host ``run(argv, stdin) -> stdout`` and in the library's Element (a network's: NetworkElement); every output
    after every step, bit for bit."""
    from prandtl_fmu import load_scene
    from prandtl_fmu.element import Element
    from prandtl_fmu.fmu.native.kernels import applicable

    description = Description(fmu, fmi)
    if network:
        from prandtl_fmu.fmu.native.network_build import steppers_of
        from prandtl_fmu.network import NetworkElement

        from tests.networks.test_native import library_outputs

        scene = load_scene(fmu.parent / "network.toml")
        outputs = description.outputs
        steppers = steppers_of(scene, False)
        assert steppers
    else:
        scene = load_scene(fmu.parent / "every_stepper.toml")
        outputs = ["x", "v", "reaction", "stiffness"] + [name for name in ENERGIES if name in description.vr]
        steppers = applicable(scene)
        assert steppers == ["projected", "implicit", "symplectic", "verlet", "exact"]
    for stepper in steppers:
        rng = np.random.default_rng(11)
        steps = [(float(rng.choice([0.013, 0.05, 0.1, 0.0371])), float(rng.uniform(-1, 1))) for _ in range(40)]
        element = NetworkElement(scene, stepper=stepper) if network else Element(scene, stepper=stepper)
        want, time = [], 0.0
        for size, force in steps:
            element.time = time
            element.advance(size, force)
            time += size
            values = library_outputs(element, scene, outputs) if network else expected(element, outputs)
            want.append([bits(value) for value in values])
        argv = [description.token, "file:///unused", str(description.vr["stepper"]), stepper,
                str(description.vr["F"]), ",".join(str(description.vr[name]) for name in outputs),
                f"noload:{description.vr['scene_load']}"]  # F alone, as the library's element is driven
        stdout = run(argv, "".join(f"{bits(size)} {bits(force)}\n" for size, force in steps))
        got = [line.split()[1:] for line in stdout.splitlines() if line.startswith("OUT")]
        assert len(got) == len(steps), (label, stepper, stdout[-2000:])
        for k, (row, reference) in enumerate(zip(got, want)):
            assert row == reference, (label, stepper, k, dict(zip(outputs, zip(row, reference))))
        assert np.max(np.abs(element.x)) > 1e-3  # it moved


def _wine_env(prefix: Path) -> dict:
    return dict(os.environ, WINEDEBUG="-all", WINEPREFIX=str(prefix), WINEDLLOVERRIDES="mscoree,mshtml=")


@pytest.fixture(scope="module")
def wine_host(tmp_path_factory):
    """The FMI 2.0 host built by mingw-w64 and a wine of its own (its prefix in a temporary folder)."""
    _need_mingw()
    if not os.path.exists(WINE) and shutil.which("wine64") is None:
        pytest.skip("wine is not installed (apt-get install wine64)")
    folder = tmp_path_factory.mktemp("wine")
    host = compile_cross_host(platforms.mingw()[0], 2, folder / "cross_host.exe")
    return (WINE if os.path.exists(WINE) else shutil.which("wine64")), host, folder / "prefix"


@pytest.fixture(scope="module")
def qemu_host(tmp_path_factory):
    """The FMI 3.0 host built by aarch64-linux-gnu-gcc, run by qemu-aarch64 with Debian's aarch64 libraries."""
    compiler, qemu = shutil.which("aarch64-linux-gnu-gcc"), shutil.which("qemu-aarch64")
    if compiler is None:
        pytest.skip("aarch64-linux-gnu-gcc is not installed (apt-get install gcc-aarch64-linux-gnu)")
    if qemu is None:
        pytest.skip("qemu-aarch64 is not installed (apt-get install qemu-user)")
    if not os.path.exists("/usr/aarch64-linux-gnu/include/stdio.h"):
        # the compiler without its C library: --no-install-recommends leaves it out
        pytest.skip("the aarch64 C library's headers are not installed (apt-get install libc6-dev-arm64-cross)")
    folder = tmp_path_factory.mktemp("qemu")
    return qemu, compile_cross_host(compiler, 3, folder / "cross_host")


def run_in_wine(wine_host, library: Path, fmu_argv, stdin, timeout=600) -> str:
    wine, host, prefix = wine_host
    done = subprocess.run([wine, str(host), str(library), *fmu_argv], input=stdin, capture_output=True, text=True,
                          timeout=timeout, env=_wine_env(prefix))
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    return done.stdout


def run_in_qemu(qemu_host, library: Path, fmu_argv, stdin, timeout=600) -> str:
    qemu, host = qemu_host
    done = subprocess.run([qemu, "-L", "/usr/aarch64-linux-gnu", str(host), str(library), *fmu_argv], input=stdin,
                          capture_output=True, text=True, timeout=timeout)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    return done.stdout


def unpacked(fmu: Path, folder: str, where: Path) -> Path:
    where.mkdir(parents=True, exist_ok=True)
    description = Description(fmu, 2 if folder in platforms.FMI2_FOLDERS else 3)
    suffix = {"win64": "dll", "x86_64-windows": "dll"}.get(folder, "so")
    path = where / f"{description.identifier}.{suffix}"
    path.write_bytes(binary(fmu, folder))
    return path


@pytest.mark.slow
def test_the_win64_binary_under_wine_is_the_library_bit_for_bit(fmu2, wine_host, tmp_path):
    library = unpacked(fmu2, "win64", tmp_path)
    compare_with_the_library(lambda argv, stdin: run_in_wine(wine_host, library, argv, stdin), fmu2, 2, "win64")


@pytest.mark.slow
def test_the_aarch64_binary_under_qemu_is_the_library_bit_for_bit(fmu3, qemu_host, tmp_path):
    library = unpacked(fmu3, "aarch64-linux", tmp_path)
    compare_with_the_library(lambda argv, stdin: run_in_qemu(qemu_host, library, argv, stdin), fmu3, 3,
                             "aarch64-linux")


@pytest.fixture(scope="module")
def network_fmus(tmp_path_factory):
    """A network's element FMU (tests/networks/test_native.py's "joint": three masses, springs, a dashpot, a
    slider), FMI 2.0 for win64 and FMI 3.0 for aarch64-linux."""
    from prandtl_fmu.fmu.build import build_fmu

    from tests.networks.scenes import SCENES as NETWORKS

    _need_zig()
    _need_mingw()
    built = {}
    for fmi, given in ((2, "win64"), (3, "aarch64-linux")):
        folder = tmp_path_factory.mktemp(f"network{fmi}")
        (folder / "network.toml").write_text(NETWORKS["joint"])
        built[fmi] = build_fmu(folder / "network.toml", folder / "network.fmu", runtime="native", fmi=fmi,
                               platforms=given)
    return built


@pytest.mark.slow
def test_a_network_s_win64_and_aarch64_binaries_are_network_element_bit_for_bit(network_fmus, wine_host, qemu_host,
                                                                              tmp_path):
    """The network's own build (network_build.py) goes the same route: x_<node>, v_<node>, the reaction, the
    energies and dissipations, every u after every step equal NetworkElement's, for each of its steppers."""
    library = unpacked(network_fmus[2], "win64", tmp_path / "win64")
    compare_with_the_library(lambda argv, stdin: run_in_wine(wine_host, library, argv, stdin), network_fmus[2], 2,
                             "network win64", network=True)
    library = unpacked(network_fmus[3], "aarch64-linux", tmp_path / "aarch64")
    compare_with_the_library(lambda argv, stdin: run_in_qemu(qemu_host, library, argv, stdin), network_fmus[3], 3,
                             "network aarch64-linux", network=True)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(pytest.main([__file__, "-m", "slow or not slow", "-n", "0", "-q"]))
