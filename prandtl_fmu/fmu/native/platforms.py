"""The native FMU's platforms: which binaries an FMU holds, the objects for each target, the linkers.

One FMU holds a binary per platform, each linked from the same kernels (numba's LLVM IR, emitted by llvmlite
for the target's triple) and the same C FMI layer:

=================  ==============  =================================  ===============================
FMI 3.0 name       FMI 2.0 name    LLVM triple                        linker
=================  ==============  =================================  ===============================
x86_64-linux       linux64         x86_64-unknown-linux-gnu           zig cc, glibc 2.17
aarch64-linux      (none)          aarch64-unknown-linux-gnu          zig cc, glibc 2.17
x86_64-windows     win64           x86_64-w64-windows-gnu             mingw-w64 gcc, -static-libgcc
x86_64-darwin      darwin64 [1]    x86_64-apple-macosx10.13.0         zig cc, macOS 10.13
aarch64-darwin     darwin64 [1]    arm64-apple-macosx11.0.0           zig cc, macOS 11.0
=================  ==============  =================================  ===============================

[1] FMI 2.0's darwin64 is one universal (fat) dylib holding both slices, written here (:func:`universal`).

Each version takes the other's name for the same target (win64 = x86_64-windows; darwin64 under FMI 3.0 is both
darwin targets; x86_64-darwin or aarch64-darwin under FMI 2.0 is darwin64); FMI 2.0 has no name for aarch64 Linux,
which it refuses. ``all``: every target the version can name; none given: the machine's own platform.

The IR is numba's for this machine; :func:`prepare` makes it a target's: the triple and data layout from the
target machine, NRT_decref's x86-only ``llvm.x86.atomic.sub.cc`` as a portable ``atomicrmw``, numba's common
NumbaEnv globals internal (nothing outside reads them), every other definition hidden (a binary exports the FMI
functions only, on Windows too). The C layer names the kernels through ``KERNEL("symbol")``
(:data:`KERNEL_MACRO`), which adds Mach-O's '_' (``__USER_LABEL_PREFIX__``), and is compiled with
``-ffp-contract=off``: no fused multiply-add on aarch64, the same number on every platform. For the same reason a
module that declares a libm function (or an intrinsic that becomes one) is refused before its object is emitted
(:func:`platform_dependent_calls`): the kernels call ``prandtl_fmu.libm``, whose bits are the same everywhere.
"""
from __future__ import annotations

import importlib.util
import os
import platform as host_platform
import re
import shutil
import struct
import subprocess
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path


class PlatformError(ValueError):
    """A platform cannot be built (one line: the name or the missing toolchain, and what to install)."""


@dataclass(frozen=True)
class Target:
    """One binary's target: ``name`` (FMI 3.0's platform name), ``triple`` (LLVM's), ``zig`` (zig cc's -target,
    the libc floor in it), ``suffix`` (the shared library's), ``arch`` (Mach-O's CPU type for a fat dylib)."""
    name: str
    triple: str
    zig: str
    suffix: str
    arch: int = 0


TARGETS = {target.name: target for target in (
    Target("x86_64-linux", "x86_64-unknown-linux-gnu", "x86_64-linux-gnu.2.17", "so"),
    Target("aarch64-linux", "aarch64-unknown-linux-gnu", "aarch64-linux-gnu.2.17", "so"),
    Target("x86_64-windows", "x86_64-w64-windows-gnu", "x86_64-windows-gnu", "dll"),
    Target("x86_64-darwin", "x86_64-apple-macosx10.13.0", "x86_64-macos.10.13", "dylib", 0x01000007),
    Target("aarch64-darwin", "arm64-apple-macosx11.0.0", "aarch64-macos.11.0", "dylib", 0x0100000C),
)}
# FMI 2.0's folders and the targets each holds (darwin64: one universal dylib of both)
FMI2_FOLDERS = {"linux64": ("x86_64-linux",), "win64": ("x86_64-windows",),
                "darwin64": ("x86_64-darwin", "aarch64-darwin")}
GLIBC_FLOOR = (2, 17)
KERNEL_MACRO = [  # scene.h's: a kernel's symbol as the C compiler names it (Mach-O: "_" + symbol)
    "#define PRANDTL_STRING_(text) #text",
    "#define PRANDTL_STRING(text) PRANDTL_STRING_(text)",
    "#define KERNEL(symbol) __asm__(PRANDTL_STRING(__USER_LABEL_PREFIX__) symbol)",
]
ZIG_PACKAGE = "pip install ziglang (or pip install 'prandtl_fmu[native]')"
MINGW_PACKAGE = "Debian/Ubuntu: apt-get install gcc-mingw-w64-x86-64"


@dataclass(frozen=True)
class Folder:
    """One ``binaries/<name>/`` folder of the FMU and the targets its binary holds (two: a universal dylib)."""
    name: str
    targets: tuple

    @property
    def suffix(self) -> str:
        return self.targets[0].suffix


def host_target() -> Target:
    machine = host_platform.machine().lower()
    arch = {"amd64": "x86_64", "x86_64": "x86_64", "arm64": "aarch64", "aarch64": "aarch64"}.get(machine, machine)
    system = {"linux": "linux", "win32": "windows", "darwin": "darwin"}.get(sys.platform, sys.platform)
    name = f"{arch}-{system}"
    if name not in TARGETS:
        raise PlatformError(f"this machine ({machine}, {sys.platform}) is no platform of the native runtime: build "
                            f"with --platforms (one of {', '.join(TARGETS)})")
    return TARGETS[name]


def resolve(names, fmi: int) -> list:
    """The FMU's binary folders for ``names`` (a comma-separated string or a list of platform names of either FMI
    version, or ``all``; None: this machine's platform), in the order given, each once."""
    if names is None or names == "" or names == []:
        wanted = [host_target().name]
    else:
        wanted = [name.strip() for name in (names.split(",") if isinstance(names, str) else names)]
        if any(not name for name in wanted):
            raise PlatformError(f"--platforms {','.join(wanted)}: an empty name")
    folders = []
    for name in wanted:
        for folder in _folders_of(name, fmi):
            if folder not in folders:
                folders.append(folder)
    return folders


def _folders_of(name: str, fmi: int) -> list:
    known = sorted(set(TARGETS) | set(FMI2_FOLDERS))
    if name == "all":
        return [_folder(name, fmi) for name in (FMI2_FOLDERS if fmi == 2 else TARGETS)]
    if name not in known:
        raise PlatformError(f"--platforms: unknown platform {name!r}: one of {', '.join(known)} or all")
    if fmi == 2:
        if name in FMI2_FOLDERS:
            return [_folder(name, 2)]
        folder = next((folder for folder, targets in FMI2_FOLDERS.items() if name in targets), None)
        if folder is None:
            raise PlatformError(f"--platforms {name}: FMI 2.0 has no platform name for it (its binaries are "
                                f"{', '.join(FMI2_FOLDERS)}): build with --fmi 3")
        return [_folder(folder, 2)]
    return [_folder(target, 3) for target in (FMI2_FOLDERS.get(name) or (name,))]


def _folder(name: str, fmi: int) -> Folder:
    return Folder(name, tuple(TARGETS[target] for target in (FMI2_FOLDERS[name] if fmi == 2 else (name,))))


# ------------------------------------------------------------------ toolchains

def zig() -> list:
    """zig cc's command (the ziglang package in this Python, else zig on PATH), or [] without one."""
    if importlib.util.find_spec("ziglang") is not None:
        return [sys.executable, "-m", "ziglang"]
    found = shutil.which("zig")
    return [found] if found else []


def mingw() -> list:
    found = shutil.which("x86_64-w64-mingw32-gcc")
    return [found] if found else []


def host_compiler() -> list:
    found = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if found is None:
        raise PlatformError("a native FMU needs a C compiler and linker (cc or gcc, or set CC): install one "
                            "(Debian/Ubuntu: apt-get install gcc; macOS: xcode-select --install)")
    return [found]


@dataclass(frozen=True)
class Toolchain:
    """How a target is linked: ``kind`` "zig", "mingw" or "cc" (this machine's compiler: its own platform only,
    with $PRANDTL_NATIVE_CFLAGS, e.g. the tests' sanitizers), ``command`` the compiler's argv prefix."""
    kind: str
    command: tuple


def toolchain(target: Target, default: bool) -> Toolchain:
    """The toolchain of ``target``; ``default``: the build named no platform (this machine's). One line naming
    the package to install where it is missing.

    The default build is linked by zig (glibc 2.17, as every Linux binary) where zig is installed, else by this
    machine's C compiler with a warning (the binary then needs this machine's glibc or newer); a build with
    $PRANDTL_NATIVE_CFLAGS set (the tests' sanitizers, whose runtime is this machine's) always by the latter."""
    if default and os.environ.get("PRANDTL_NATIVE_CFLAGS", "").strip():
        return Toolchain("cc", tuple(host_compiler()))
    if target.name.endswith("-windows"):
        found = mingw()
        if found:
            return Toolchain("mingw", tuple(found))
        if not default:
            raise PlatformError(f"--platforms {target.name}: the Windows binary needs mingw-w64's gcc "
                                f"(x86_64-w64-mingw32-gcc): {MINGW_PACKAGE}")
        return Toolchain("cc", tuple(host_compiler()))
    found = zig()
    if found:
        return Toolchain("zig", tuple(found) + ("cc", "-target", target.zig))
    if default:
        warnings.warn("zig is not installed: the native FMU's binary is linked by this machine's C compiler and "
                      "needs this machine's glibc or newer (zig links against glibc 2.17: " + ZIG_PACKAGE + ")",
                      stacklevel=3)
        return Toolchain("cc", tuple(host_compiler()))
    raise PlatformError(f"--platforms {target.name}: the {target.name} binary is linked by zig: {ZIG_PACKAGE}")


def toolchains(folders, default: bool) -> dict:
    """Every target's toolchain, before anything is compiled (a missing one stops the build first)."""
    return {target.name: toolchain(target, default) for folder in folders for target in folder.targets}


# ------------------------------------------------------------------ objects

def target_machine(target: Target):
    import llvmlite.binding as llvm

    if not getattr(target_machine, "initialized", False):
        llvm.initialize_all_targets()
        llvm.initialize_all_asmprinters()
        target_machine.initialized = True
    return llvm.Target.from_triple(target.triple).create_target_machine(reloc="pic", codemodel="default", opt=3)


_X86_ATOMIC_SUB = re.compile(r"(%[\w.]+) = (?:tail )?call i8 @llvm\.x86\.atomic\.sub\.cc\.i64\(ptr (?:nonnull )?"
                             r"(%[\w.]+), i64 (\d+), i32 4\)")


def portable_ir(text: str) -> str:
    """numba's IR without what only x86 takes: NRT_decref's ``llvm.x86.atomic.sub.cc.i64(p, n, 4)`` (subtract,
    then "the result is zero") as ``atomicrmw sub`` and a compare."""
    count = iter(range(1 << 30))

    def replace(match):
        result, pointer, amount = match.groups()
        name = f"%prandtl.decref.{next(count)}"  # a fresh name (numbered values cannot take a suffix)
        return (f"{name}.old = atomicrmw sub ptr {pointer}, i64 {amount} seq_cst\n"
                f"  {name}.zero = icmp eq i64 {name}.old, {amount}\n"
                f"  {result} = zext i1 {name}.zero to i8")

    text = _X86_ATOMIC_SUB.sub(replace, text)
    return re.sub(r"^declare [^\n]*@llvm\.x86\.atomic\.sub\.cc\.i64\([^\n]*\n", "", text, flags=re.M)


def prepare(module, machine, exported=("fmi2", "fmi3")):
    """``module`` made the target's: its triple and data layout, numba's NumbaEnv globals internal, every
    definition but the FMI functions hidden."""
    module.triple = machine.triple
    module.data_layout = str(machine.target_data)
    for value, variable in [(f, False) for f in module.functions] + [(g, True) for g in module.global_variables]:
        if value.is_declaration or value.name.startswith(exported):
            continue
        if variable and value.linkage.name == "common":
            value.linkage = "internal"
        if value.linkage.name not in ("internal", "private"):
            value.visibility = "hidden"
    return module


# "One number everywhere": glibc's, Windows' and musl's cos, exp, pow, ... differ in their last bits, so the kernels
# call prandtl_fmu.libm and what a module may leave to the link is exact in every conforming C library (IEEE 754
# fixes these results) or no arithmetic at all (bcmp, bzero and memset_pattern16: LLVM's forms of memcmp and
# memset), numba's runtime and helpers, and the CPython API of numba's error path (assemble.stubs provides both)
EXACT_C = frozenset({"sqrt", "fabs", "copysign", "floor", "ceil", "trunc", "round", "rint", "nearbyint", "fmod",
                     "fmin", "fmax", "nextafter", "frexp", "ldexp", "scalbn", "memcpy", "memmove", "memset", "memcmp",
                     "bcmp", "bzero", "memset_pattern16"})
NUMBA_HELPERS = frozenset({"numba_nextafter", "numba_frexp", "numba_ldexp", "numba_do_raise", "numba_gil_ensure",
                           "numba_gil_release", "numba_unpickle", "numba_runtime_build_excinfo_struct"})
RUNTIME_PREFIXES = ("NRT_", "Py", "_Py")
# LLVM intrinsics that the code generator lowers into a libm call (sin and cos of one argument into sincos), or
# that fuse a product into a sum; their constrained (strict floating-point) forms too
LIBM_INTRINSIC = re.compile(r"llvm\.(experimental\.constrained\.)?(sin|cos|tan|sincos|sincospi|asin|acos|atan|atan2"
                            r"|sinh|cosh|tanh|exp|exp2|exp10|log|log2|log10|pow|powi|fma|fmuladd)\.")


# LLVM's fast-math flags on a floating-point instruction: each lets the code generator change the result's bits, and
# each target does it its own way (``contract`` lets an fmul and an fadd fuse into one rounding: an fmadd on aarch64,
# two roundings on x86-64 without FMA; ``reassoc``, ``afn``, ``arcp``: another order, an approximate function, x * 1/y;
# ``nnan``, ``ninf``, ``nsz``: NaN, inf and -0 assumed away). The kernels are IEEE arithmetic (``_jit.kernel``: no
# fastmath), so none is allowed
FAST_MATH = re.compile(r"=\s*(?:(?:tail|musttail|notail)\s+)?(fadd|fsub|fmul|fdiv|frem|fneg|fcmp|fptrunc|fpext|call"
                       r"|phi|select)((?:\s+(?:nnan|ninf|nsz|arcp|contract|afn|reassoc|fast)\b)+)")


def fast_math(module) -> list:
    """The floating-point instructions of ``module`` (llvmlite's) that carry fast-math flags (:data:`FAST_MATH`),
    as ``"fmul contract"``, each kind once, sorted."""
    return sorted({f"{opcode} {' '.join(flags.split())}" for opcode, flags in FAST_MATH.findall(str(module))})


def may_link(symbol: str) -> bool:
    """Whether a kernel's object may need ``symbol`` from the link (see :data:`EXACT_C`)."""
    return symbol in EXACT_C or symbol in NUMBA_HELPERS or symbol.startswith(RUNTIME_PREFIXES)


def platform_dependent_calls(module) -> list:
    """The functions ``module`` (llvmlite's) declares and uses that may not give the same bits on every platform
    (a libm function, an intrinsic that becomes one or a fused multiply-add in the object) or that the native
    binaries do not provide: anything :func:`may_link` does not allow. A declaration nothing uses emits no symbol
    and is left alone: one whose name the module's text holds exactly once, in its declaration (a name LLVM
    prints with escapes is found 0 times and counts as used: a false alarm at worst, never a miss)."""
    text = str(module)
    declared = [f.name for f in module.functions
                if f.is_declaration and (LIBM_INTRINSIC.match(f.name)
                                         or not (f.name.startswith("llvm.") or may_link(f.name)))]
    return sorted(name for name in declared if len(re.findall(rf"@\"?{re.escape(name)}(?![\w.$-])", text)) != 1)


def emit_objects(compiled, folder, target: Target) -> tuple:
    """One object file per C function for ``target`` (position-independent, for a shared library) into
    ``folder``. Returns their paths and the symbols the modules declare without defining (what the link must
    provide: numba's error path, the exact functions of :data:`EXACT_C`). A module that calls a function whose
    result differs between platforms (:func:`platform_dependent_calls`) is refused: NativeBuildError names it."""
    import llvmlite.binding as llvm

    from .assemble import NativeBuildError

    machine = target_machine(target)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths, external = [], set()
    for c_name, function in compiled:
        module = prepare(llvm.parse_assembly(portable_ir(str(function._library._final_module))), machine)
        module.verify()
        calls = platform_dependent_calls(module)
        if calls:
            raise NativeBuildError(f"the native kernel {c_name} calls {', '.join(calls)}: not the same bits on "
                                   "every platform, or not in the native binary (a defect of prandtl_fmu, whose "
                                   "kernels call prandtl_fmu.libm: please report it)")
        flagged = fast_math(module)
        if flagged:
            raise NativeBuildError(f"the native kernel {c_name} has fast-math arithmetic ({', '.join(flagged)}): "
                                   "not the same bits on every platform (a defect of prandtl_fmu, whose kernels "
                                   "are IEEE arithmetic: please report it)")
        external.update(f.name for f in module.functions if f.is_declaration and not f.name.startswith("llvm."))
        external.update(g.name for g in module.global_variables if g.is_declaration)
        path = folder / f"{c_name}.o"
        path.write_bytes(machine.emit_object(module))
        paths.append(path)
    return paths, external


# ------------------------------------------------------------------ linking

FLAGS = ["-O2", "-std=c99", "-D_POSIX_C_SOURCE=200809L", "-fvisibility=hidden", "-ffp-contract=off"]


def link(target: Target, chain: Toolchain, sources, objects, includes, defines, out: Path, fmi: int) -> Path:
    """The shared library of ``target`` at ``out``: ``sources`` (C) compiled and linked with ``objects``;
    ``includes`` folders, ``defines`` NAME=VALUE. NativeBuildError's message on a failure."""
    command = [*chain.command, *FLAGS, *(f"-D{define}" for define in defines), *(f"-I{path}" for path in includes)]
    if chain.kind == "cc":
        command += os.environ.get("PRANDTL_NATIVE_CFLAGS", "").split()  # e.g. a sanitizer, for the tests
    else:
        command.append("-s")  # no debug sections in a shipped binary
    command += ["-shared", *map(str, sources), *map(str, objects), "-o", str(out)]
    if target.suffix == "so":  # the FMI functions only: the kernels' symbols stay inside
        exports = out.with_suffix(".map")
        exports.write_text(f"{{ global: fmi{fmi}*; local: *; }};\n")
        command = command[:len(chain.command)] + ["-fPIC"] + command[len(chain.command):]
        command += ["-lm", "-Wl,--no-undefined", f"-Wl,--version-script={exports}"]
    elif target.suffix == "dll":
        command += ["-static-libgcc", "-Wl,--no-undefined"]  # imports KERNEL32 and msvcrt only
    else:  # Mach-O: hidden visibility keeps the kernels inside; libSystem holds libm
        command = command[:len(chain.command)] + ["-fPIC"] + command[len(chain.command):]
        command += [f"-Wl,-install_name,@rpath/{out.name}"]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        errors = [line for line in done.stderr.splitlines() if "error" in line] or done.stderr.splitlines()[-1:]
        raise PlatformError(f"linking the native FMU's {target.name} binary failed: "
                            f"{errors[0].strip() if errors else done.returncode}")
    return out


def universal(slices) -> bytes:
    """A fat Mach-O of the thin dylibs ``slices`` [(cpu type, bytes)], as lipo writes it: the big-endian header
    (0xcafebabe, count), one (cputype, cpusubtype, offset, size, align) per slice, each slice at a 2^14 boundary."""
    align = 14
    header = struct.pack(">II", 0xCAFEBABE, len(slices))
    offset = 1 << align
    table, body = b"", b""
    for cpu, data in slices:
        subtype = struct.unpack("<I", data[8:12])[0]  # the thin Mach-O's own (little-endian header)
        table += struct.pack(">iiIII", cpu, subtype, offset + len(body), len(data), align)
        body += data + b"\0" * (-len(data) % (1 << align))
    return (header + table).ljust(offset, b"\0") + body


def build_binaries(folders, chains, kernels, scratch, stubs, sources, includes, defines, fmi: int,
                   identifier: str) -> tuple:
    """Every folder's binary: ``{folder name: bytes}`` and the seconds each took (its objects, from the cache or
    emitted, and linking). ``kernels``: the build's ``object_cache.KernelObjects``; ``stubs(external)``: the C
    text of what the kernels' modules declare (``build._stubs``); ``identifier``: the model identifier, the
    binary's own name (a DLL's export name, a dylib's install name)."""
    import time

    from ...compiling import stage

    binaries, seconds, emitted = {}, {}, {}
    for folder in folders:
        started = time.perf_counter()
        slices = []
        for target in folder.targets:
            where = Path(scratch) / target.name
            stage(f"native build: the objects for {target.name}" + (" (from the cache)" if kernels.cached else ""))
            objects, external = emitted[target] = kernels.objects(where, target)
            (where / "stubs.c").write_text(stubs(external))
            stage(f"native build: linking {target.name}")
            out = link(target, chains[target.name], [*sources, where / "stubs.c"], objects, includes, defines,
                       where / f"{identifier}.{target.suffix}", fmi)
            slices.append((target.arch, out.read_bytes()))
        binaries[folder.name] = slices[0][1] if len(slices) == 1 else universal(slices)
        seconds[folder.name] = time.perf_counter() - started
    kernels.keep(emitted)
    return binaries, seconds
