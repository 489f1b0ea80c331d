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
outside the allow-list, for every object the run's native builds kept in the object cache.
"""
import shutil
import subprocess

import pytest

from tests.conftest import SCENES

# one native build of the paper's scene (every stepper; from the object cache when the quick suite built it) and the
# objects of every native build of the run
pytestmark = pytest.mark.slow


def calls_libm():
    """A C function that calls math.cos, math.pow and the absolute value of a complex (hypot)."""
    import math

    from numba import cfunc, types

    @cfunc(types.float64(types.float64, types.float64), error_model="numpy")
    def calls_libm(x, y):
        return math.cos(x) + math.pow(x, y) + abs(complex(x, y))

    return calls_libm


def undefined_symbols(path) -> list:
    """``nm -u`` of the object at ``path``: the symbols it needs from the link."""
    listing = subprocess.run([shutil.which("nm"), "-u", str(path)], capture_output=True, text=True, check=True).stdout
    return [line.split()[-1] for line in listing.splitlines() if line.strip()]


@pytest.mark.parametrize("target", ["x86_64-linux", "aarch64-linux", "x86_64-windows", "aarch64-darwin"])
def test_a_native_build_refuses_a_kernel_that_calls_libm(tmp_path, target):
    """The IR of a cfunc calling cos, pow and a complex's abs declares ``llvm.cos``, ``llvm.pow`` and ``hypot``:
    the build names the C function and the three, for every target, and emits no object."""
    from prandtl_fmu.fmu.native.assemble import NativeBuildError
    from prandtl_fmu.fmu.native.platforms import TARGETS, emit_objects

    with pytest.raises(NativeBuildError) as refused:
        emit_objects([("prandtl_calls_libm", calls_libm())], tmp_path, TARGETS[target])
    message = str(refused.value)
    assert "the native kernel prandtl_calls_libm calls " in message and "\n" not in message
    assert all(name in message for name in ("llvm.cos.f64", "llvm.pow.f64", "hypot")), message
    assert list(tmp_path.iterdir()) == []


def test_the_objects_of_every_native_build_need_no_libm(tmp_path):
    """The paper's scene built natively (every stepper that applies), then every object in the object cache: the
    run's native builds, each checked on its IR when emitted (those of the quick suite too, when it ran first on
    this cache), for every target ``nm`` reads (ELF: both Linux targets; COFF: Windows; not Mach-O). No undefined
    symbol is outside the allow-list but numba's mangled names of compiled functions (``_ZN...``: resolved among
    the build's objects; COFF lists their COMDAT copies as undefined). ``nm`` itself sees libm in the object of a
    cfunc that calls it (emitted here as the build emits, unchecked)."""
    if shutil.which("nm") is None:
        pytest.skip("no nm (Debian: apt-get install binutils): the objects cannot be read")
    import llvmlite.binding as llvm

    from prandtl_fmu.fmu.build import build_fmu
    from prandtl_fmu.fmu.native import object_cache
    from prandtl_fmu.fmu.native.platforms import host_target, may_link, portable_ir, prepare, target_machine

    def outside(symbols):
        return {symbol for symbol in symbols if not (may_link(symbol) or symbol.startswith("_ZN"))}

    machine = target_machine(host_target())
    module = prepare(llvm.parse_assembly(portable_ir(str(calls_libm()._library._final_module))), machine)
    unchecked = tmp_path / "calls_libm.o"
    unchecked.write_bytes(machine.emit_object(module))
    assert {"cos", "pow", "hypot"} <= outside(undefined_symbols(unchecked))

    scene = tmp_path / "paper.toml"
    scene.write_text((SCENES / "paper-section-8.toml").read_text())
    build_fmu(scene, tmp_path / "paper.fmu", runtime="native")
    root = object_cache._root()
    assert root is not None, "the suite runs with a cache folder: the build kept its objects"
    found, read = {}, {}
    for objects in sorted(root.glob("[!.]*/*/")):  # <digest>/<triple>/
        try:
            needed = {path.name: undefined_symbols(path) for path in objects.glob("*.o")}
        except subprocess.CalledProcessError:  # a format this nm does not read (Mach-O)
            continue
        read[objects.name] = read.get(objects.name, 0) + 1
        for name, symbols in needed.items():
            for symbol in outside(symbols):
                found.setdefault(symbol, []).append(f"{objects.parent.name[:12]}/{objects.name}/{name}")
    assert read.get(host_target().triple), f"no object of this machine's kept in {root}"
    assert found == {}
