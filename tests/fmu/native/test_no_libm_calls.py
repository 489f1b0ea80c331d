"""The native kernels call no libm function (issue 33, "one number everywhere"): every native build refuses a kernel
whose module declares one, and the objects it emits need nothing more than their IR declares.

glibc's, Windows' and musl's cos, sin, exp, log, pow, hypot, cbrt, ... differ in their last bits; the kernels call
``prandtl_fmu.libm`` instead, so that the library in process and every FMU binary compute the same bits. What is
left for the link is exact in every conforming C library (sqrt, floor, ceil, fmod, nextafter, frexp, ldexp: IEEE
754 fixes their results), the C runtime's memcpy and memset, numba's runtime (NRT_*, numba_* helpers) and the
CPython API of numba's error path (the native build stubs it): ``platforms.may_link``.

The check is the build's own (``platforms.emit_objects``: ``platform_dependent_calls`` of each C function's module,
for every target, before its object is emitted), so every native FMU the suite builds is checked: the fixed and the
random scenes (every effect, branch kernel, load and stepper), the memory stack, the continuum, white noise, the
connector and the networks. This file tests that check (a kernel calling libm is refused, for every target), and
that the IR is what matters: the objects the code generator emits from a checked IR (``nm -u``, the ground truth:
an intrinsic such as ``llvm.cos`` becomes a libm call there, sin and cos of one argument ``sincos``) need no symbol
outside the allow-list, for every object the builds of the native FMU's tests' scenes link (from the object cache
when those tests ran first), this machine's target.
"""
import itertools
import shutil
import subprocess

import pytest

from tests.conftest import scene_text


def calls_libm():
    """A C function that calls math.cos, math.pow and the absolute value of a complex (hypot)."""
    import math

    from numba import cfunc, types

    @cfunc(types.float64(types.float64, types.float64), error_model="numpy")
    def calls_libm(x, y):
        return math.cos(x) + math.pow(x, y) + abs(complex(x, y))

    return calls_libm


def test_the_check_counts_what_a_module_declares_and_uses():
    """On hand-written IR: a used libm function, intrinsic (plain or constrained) or unknown symbol is named; the
    exact C functions, numba's runtime, harmless intrinsics and declarations nothing uses are not."""
    import llvmlite.binding as llvm

    from prandtl_fmu.fmu.native.platforms import platform_dependent_calls

    module = llvm.parse_assembly("""
declare double @llvm.cos.f64(double)
declare double @llvm.experimental.constrained.exp.f64(double, metadata, metadata)
declare double @llvm.fmuladd.f64(double, double, double)
declare double @llvm.floor.f64(double)
declare void @llvm.memcpy.p0.p0.i64(ptr, ptr, i64, i1)
declare double @cbrt(double)
declare double @"odd name"(double)
declare double @log10(double)
declare double @sqrt(double)
declare ptr @NRT_MemInfo_alloc(i64)
define double @f(double %x, ptr %p, ptr %q) {
  %a = call double @llvm.cos.f64(double %x)
  %b = call double @llvm.experimental.constrained.exp.f64(double %a, metadata !"round.dynamic", metadata !"fpexcept.strict")
  %c = call double @llvm.fmuladd.f64(double %a, double %b, double %x)
  %d = call double @llvm.floor.f64(double %c)
  call void @llvm.memcpy.p0.p0.i64(ptr %p, ptr %q, i64 8, i1 false)
  %e = call double @cbrt(double %d)
  %f = call double @"odd name"(double %e)
  %g = call double @sqrt(double %f)
  %m = call ptr @NRT_MemInfo_alloc(i64 8)
  ret double %g
}
""")
    assert platform_dependent_calls(module) == ["cbrt", "llvm.cos.f64", "llvm.experimental.constrained.exp.f64",
                                                "llvm.fmuladd.f64", "odd name"]


@pytest.mark.parametrize("target", ["x86_64-linux", "aarch64-linux", "x86_64-windows", "x86_64-darwin",
                                    "aarch64-darwin"])
def test_a_native_build_refuses_a_kernel_that_calls_libm(tmp_path, target):
    """The IR of a cfunc calling cos, pow and a complex's abs declares ``llvm.cos``, ``llvm.pow`` and ``hypot``:
    the build names the C function and the three in one line, for every target, and emits no object."""
    from prandtl_fmu.fmu.native.assemble import NativeBuildError
    from prandtl_fmu.fmu.native.platforms import TARGETS, emit_objects

    with pytest.raises(NativeBuildError) as refused:
        emit_objects([("prandtl_calls_libm", calls_libm())], tmp_path, TARGETS[target])
    message = str(refused.value)
    assert "the native kernel prandtl_calls_libm calls " in message and "\n" not in message
    assert all(name in message for name in ("llvm.cos.f64", "llvm.pow.f64", "hypot")), message
    assert list(tmp_path.iterdir()) == []


def test_the_check_sees_fast_math_flags():
    """On written IR: a floating-point instruction with a fast-math flag (``contract``, which lets an fmul and an fadd
    fuse into aarch64's fmadd, ``fast``, ``reassoc``, ``afn``, ``nnan`` ... on arithmetic, a compare, a call or a
    phi) is named once per kind, as ``"fmul contract"``; the same instructions without flags, an integer's ``nsw`` and
    a flag's name in a global's text are not."""
    import llvmlite.binding as llvm

    from prandtl_fmu.fmu.native.platforms import fast_math

    ir = """
@note = private constant [13 x i8] c"fmul contract"
declare double @llvm.sqrt.f64(double)
define double @f(double %x, double %y, i64 %n, i1 %c) {
entry:
  %a = fmul contract double %x, %y
  %b = fadd contract double %a, %x
  %c2 = fmul contract double %b, %y
  %d = fdiv reassoc nsz double %c2, %x
  %e = tail call afn double @llvm.sqrt.f64(double %d)
  %f = fcmp fast olt double %e, %x
  %m = add nsw i64 %n, 1
  br i1 %c, label %left, label %right
left:
  br label %right
right:
  %p = phi nnan ninf double [ %e, %entry ], [ %x, %left ]
  %q = select i1 %f, double %p, double %y
  ret double %q
}
"""
    assert fast_math(llvm.parse_assembly(ir)) == ["call afn", "fadd contract", "fcmp fast", "fdiv reassoc nsz",
                                                  "fmul contract", "phi nnan ninf"]
    plain = ir
    for flags in ("contract ", "reassoc nsz ", "afn ", "fast ", "nnan ninf "):
        plain = plain.replace(f" {flags}double", " double").replace(f" {flags}olt", " olt")
    assert fast_math(llvm.parse_assembly(plain)) == []


@pytest.mark.parametrize("target", ["x86_64-linux", "aarch64-linux", "x86_64-windows"])
def test_a_native_build_refuses_fast_math(tmp_path, target):
    """A cfunc compiled with ``fastmath={'contract'}`` (x * y + x: an fmadd on aarch64, an fmul and an fadd on
    x86-64) is refused in one line naming the C function and its flagged instructions, and no object is emitted."""
    from numba import cfunc, types

    from prandtl_fmu.fmu.native.assemble import NativeBuildError
    from prandtl_fmu.fmu.native.platforms import TARGETS, emit_objects

    @cfunc(types.float64(types.float64, types.float64), fastmath={"contract"})
    def fused(x, y):
        return x * y + x

    with pytest.raises(NativeBuildError) as refused:
        emit_objects([("prandtl_fused", fused)], tmp_path, TARGETS[target])
    message = str(refused.value)
    assert message.startswith("the native kernel prandtl_fused has fast-math arithmetic (") and "\n" not in message
    assert "fmul contract" in message and "fadd contract" in message, message
    assert list(tmp_path.iterdir()) == []


def needed_symbols(path) -> set:
    """What the object at ``path`` needs from the link (``nm -u``): its undefined symbols, and its weak undefined
    ones but numba's mangled names of compiled functions (``_ZN...``: a COFF object refers to the copies other
    objects of the build define as weak externals)."""
    listing = subprocess.run([shutil.which("nm"), "-u", str(path)], capture_output=True, text=True, check=True).stdout
    needed = set()
    for kind, symbol in (line.split(maxsplit=1) for line in listing.splitlines() if line.strip()):
        if kind == "U" or not symbol.startswith("_ZN"):
            needed.add(symbol)
    return needed


@pytest.mark.slow  # builds: the scenes of the native FMU's tests, from the object cache when those tests ran first
def test_the_objects_of_native_builds_need_no_libm(tmp_path, monkeypatch):
    """The native FMUs of the element's scenes that tests/fmu/native/test_against_library.py builds (every effect on
    the mass and in the branches, the memory stack, the continuum, exact and exact_series, massless and rigid; every
    stepper that applies) and a network and a network connector of tests/networks/test_native.py, built as those
    tests build them (their objects are shared through the object cache): every object each build linked, for
    this machine's target (ELF or COFF: ``nm`` reads no Mach-O), needs only what :func:`may_link` allows. ``nm``
    itself sees libm in an object of a cfunc that calls it (emitted here as the build emits it, unchecked)."""
    if shutil.which("nm") is None:
        pytest.skip("no nm (Debian: apt-get install binutils): the objects cannot be read")
    import llvmlite.binding as llvm

    from prandtl_fmu.fmu.build import build_fmu
    from prandtl_fmu.fmu.native import object_cache
    from prandtl_fmu.fmu.native.build import build_native_network_fmu
    from prandtl_fmu.fmu.native.platforms import host_target, may_link, portable_ir, prepare, target_machine

    from tests.fmu.native.test_against_library import PAPER, SCENES
    from tests.networks.scenes import SCENES as NETWORKS

    if host_target().suffix == "dylib":
        pytest.skip("this machine's objects are Mach-O, which nm -u lists with a leading underscore")
    machine = target_machine(host_target())
    module = prepare(llvm.parse_assembly(portable_ir(str(calls_libm()._library._final_module))), machine)
    unchecked = tmp_path / "calls_libm.o"
    unchecked.write_bytes(machine.emit_object(module))
    assert {"cos", "pow", "hypot"} <= {symbol for symbol in needed_symbols(unchecked) if not may_link(symbol)}

    linked = tmp_path / "linked"  # a copy of every object a build hands to its link, whether cached or emitted
    handed, count = object_cache.KernelObjects.objects, itertools.count()

    def keep_a_copy(kernels, folder, target):
        paths, external = handed(kernels, folder, target)
        copies = linked / f"{next(count):02d}-{target.name}"
        copies.mkdir(parents=True)
        for path in paths:
            shutil.copyfile(path, copies / path.name)
        return paths, external

    monkeypatch.setattr(object_cache.KernelObjects, "objects", keep_a_copy)
    for name, tables in SCENES.items():
        path = tmp_path / f"{name}.toml"
        path.write_text(scene_text(tables) if tables else PAPER.read_text())
        build_fmu(path, tmp_path / f"{name}.fmu", runtime="native")
    for name, causality in (("joint", None), ("massless", "displacement")):
        path = tmp_path / f"network-{name}.toml"
        path.write_text(NETWORKS[name])
        build_native_network_fmu(path, tmp_path / f"network-{name}.fmu", fmi=2, causality=causality)
    builds = sorted(linked.iterdir())
    assert len(builds) == len(SCENES) + 2
    found = {}
    for build in builds:
        objects = sorted(build.glob("*.o"))
        assert objects, build.name
        for path in objects:
            for symbol in needed_symbols(path):
                if not may_link(symbol):
                    found.setdefault(symbol, []).append(f"{build.name}/{path.name}")
    assert found == {}
