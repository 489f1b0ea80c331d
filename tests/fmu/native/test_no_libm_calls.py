"""The compiled kernels call no libm function (issue 33, "one number everywhere"): the native kernels' objects,
built as ``prandtl_fmu.fmu.native`` builds them, declare no transcendental function and need none from the link.

glibc's, Windows' and musl's cos, sin, exp, log, pow, hypot, cbrt, ... differ in their last bits; the kernels call
``prandtl_fmu.libm`` instead, so that the library in process and every FMU binary compute the same bits. What is
left for the link is exact in every conforming C library (sqrt, floor, ceil, fmod, nextafter, frexp, ldexp: IEEE
754 fixes their results), the C runtime's memcpy and memset, numba's runtime (NRT_*, numba_* helpers) and the
CPython API of numba's error path (the native build stubs it).

The ground truth is the objects themselves: a kernel's LLVM IR may name an intrinsic (llvm.cos, llvm.pow, ...)
that the code generator lowers into a libm call (and merges sin and cos of one argument into ``sincos``), so the
test reads both the IR's declarations, intrinsics included (what every target's object would need), and the
undefined symbols of the x86_64 objects (``nm -u``). The scenes cover every effect, load, stepper, the memory
stack and the continuum, the noisy variants, the connector and the networks (element, connector).
"""
import pathlib
import re
import shutil
import subprocess

import pytest

from prandtl_fmu.scene import parse_scene

from tests.conftest import SCENES as SCENE_FOLDER, base_tables, scene_text

# each scene compiles its native kernels: 3 to 65 s, about 9 minutes in all on 2 shared cores
pytestmark = pytest.mark.slow

# exact in every conforming C library (IEEE 754 fixes the result), or not arithmetic at all
EXACT_C = {"sqrt", "fabs", "copysign", "floor", "ceil", "trunc", "round", "rint", "nearbyint", "fmod", "fmin", "fmax",
           "nextafter", "frexp", "ldexp", "scalbn", "memcpy", "memmove", "memset", "memcmp"}
# numba's helpers: nextafter, frexp and ldexp (exact), the error path, the GIL, the runtime's allocations
NUMBA_HELPERS = {"numba_nextafter", "numba_frexp", "numba_ldexp", "numba_do_raise", "numba_gil_ensure",
                 "numba_gil_release", "numba_unpickle", "numba_runtime_build_excinfo_struct"}
RUNTIME_PREFIXES = ("NRT_", "Py", "_Py")
# LLVM intrinsics the code generator lowers into a libm call (or that fuse a product into a sum)
LIBM_INTRINSIC = re.compile(r"llvm\.(sin|cos|tan|sincos|asin|acos|atan|atan2|sinh|cosh|tanh|exp|exp2|exp10|log|log2"
                            r"|log10|pow|powi|fma|fmuladd)\.")

SOLVER = {"stepper": "implicit", "step": 0.01, "stop_time": 10.0, "output_interval": 0.1}
ELEMENTS = {
    # mass, spring, cubic spring, dashpot, three branches, a harmonic load
    "smooth": scene_text(base_tables(solver=SOLVER)),
    # Stribeck friction on a belt, series dashpots (kernels/series.py), a table load
    "friction": scene_text(base_tables(
        cubic=None, solver=SOLVER,
        friction={"alpha": 0.3, "alpha_kinetic": 0.2, "stribeck_velocity": 0.1, "belt_velocity": 0.05},
        branches={"k": [0.5, 0.3, 0.2], "eta": [0.1, 0.3, 0.6], "c": [0.4, 2.0, 9.0]},
        load={"kind": "table", "time": [0.0, 3.0, 6.0, 10.0], "force": [0.0, 0.6, -0.5, 0.2]})),
    # exact with Coulomb friction and series dashpots (steppers/exact_series.py)
    "coulomb": scene_text(base_tables(
        cubic=None, solver=dict(SOLVER, stepper="exact"), friction={"alpha": 0.1},
        branches={"k": [0.5, 2.0, 0.3], "eta": [0.1, 0.3, 0.05], "c": [0.4, 2.0, 9.0]})),
    # exact on plain branches with Coulomb friction (steppers/exact.py; force_at compiles every kind of load)
    "exact": scene_text(base_tables(cubic=None, solver=dict(SOLVER, stepper="exact"), friction={"alpha": 0.1})),
    # massless, with and without a dashpot
    "massless": scene_text(base_tables(mass=None, cubic=None, solver=SOLVER)),
    "rigid": scene_text(base_tables(mass=None, damper=None, solver=SOLVER)),
    # the paper's 100 branches on the memory stack (and unfolded for exact), a continuum with a power law
    "paper": (SCENE_FOLDER / "paper-section-8.toml").read_text(),
    "continuum": scene_text(base_tables(
        cubic=None, damper=None, solver=dict(SOLVER, stepper="verlet"),
        branches={"continuum": True, "k_total": 1.0, "eta_range": [0.0, 1.0]})),
    # a white noise on the load (every scene also compiles the noisy variants of the steppers that take one)
    "noise": (SCENE_FOLDER / "white-noise.toml").read_text(),
}
CONNECTORS = {  # the connector: massless, motion in
    "connector": scene_text(base_tables(mass=None, solver=SOLVER)),
    "stack-connector": scene_text(base_tables(mass=None, cubic=None, solver=SOLVER,
                                              branches={"count": 100, "k_total": 1.0, "eta_range": [0.1, 1.1]})),
}
NETWORK_SOLVER = '\n[solver]\nstepper = "implicit"\nstep = 0.001\nstop_time = 1.0\noutput_interval = 0.01\n'
NETWORKS = {
    "chain": (SCENE_FOLDER / "networks" / "chain-dynamic.toml").read_text(),
    "massless-chain": (SCENE_FOLDER / "networks" / "chain-massless.toml").read_text(),
    # a Prandtl branch with a series dashpot and u0, sliders, a dashpot, a cubic spring
    "joint": """
name = "joint"

[network]
nodes = ["a", "b", "c"]
mass = [1.0, 2.0, 0.5]
load_node = "a"

[[network.spring]]
between = ["a", "ground"]
k = 100.0

[[network.slider]]
between = ["a", "b"]
alpha = 2.0

[[network.branch]]
between = ["a", "b"]
k = 50.0
eta = 0.02
u0 = 0.005
c = 5.0

[[network.slider]]
between = ["c", "b"]
alpha = 0.3

[[network.dashpot]]
between = ["b", "ground"]
c = 0.5

[[network.cubic]]
between = ["a", "ground"]
k3 = 10000.0

[load]
kind = "harmonic"
amplitude = 10.0
omega = 5.0
""" + NETWORK_SOLVER,
}


def element_kernels(text, causality):
    from prandtl_fmu.fmu.native import kernels

    scene = parse_scene(text + (f'\n[fmu]\ncausality = "{causality}"\n' if causality != "force" else ""), "s.toml")
    steppers = [] if scene.causality == "displacement" else kernels.applicable(scene)
    return kernels.compile_kernels(scene, steppers)


def network_kernels(text, causality):
    from prandtl_fmu.fmu.native import network_kernels
    from prandtl_fmu.fmu.native.network_build import steppers_of

    if causality == "displacement":  # the load node's motion is imposed: it is massless
        text = text.replace("mass = [1.0,", "mass = [0.0,") + f'\n[fmu]\ncausality = "{causality}"\n'
    scene = parse_scene(text, "s.toml")
    connector = scene.causality == "displacement"
    if connector:
        scene = scene.with_solver(stepper="implicit")
    return network_kernels.compile_network(scene, steppers_of(scene, connector), connector)


def allowed(symbol):
    return symbol in EXACT_C or symbol in NUMBA_HELPERS or symbol.startswith(RUNTIME_PREFIXES)


def libm_calls(compiled, folder):
    """``{symbol: [C functions that need it]}`` for every symbol of the kernels that is not allowed: the IR's
    declarations (intrinsics that lower to libm included) and the undefined symbols of the objects emitted for
    this machine as the native build emits them (position-independent, LLVM at -O3)."""
    import llvmlite.binding as llvm

    machine = llvm.Target.from_default_triple().create_target_machine(reloc="pic", codemodel="default", opt=3)
    nm = shutil.which("nm")
    found = {}
    for c_name, function in compiled:
        module = llvm.parse_assembly(str(function._library._final_module))
        for declared in module.functions:
            name = declared.name
            if declared.is_declaration and (LIBM_INTRINSIC.match(name) or not (name.startswith("llvm.")
                                                                               or allowed(name))):
                found.setdefault(name, []).append(c_name)
        if nm is None:
            continue
        path = pathlib.Path(folder) / f"{c_name}.o"
        path.write_bytes(machine.emit_object(module))
        listing = subprocess.run([nm, "-u", str(path)], capture_output=True, text=True, check=True).stdout
        for symbol in (line.split()[-1] for line in listing.splitlines() if line.strip()):
            if not allowed(symbol):
                found.setdefault(symbol, []).append(c_name)
    return found


@pytest.mark.parametrize("name,causality", [(name, "force") for name in ELEMENTS]
                         + [(name, "displacement") for name in CONNECTORS])
def test_element_kernels_call_no_libm(name, causality, tmp_path):
    compiled = element_kernels({**ELEMENTS, **CONNECTORS}[name], causality)
    assert compiled
    assert libm_calls(compiled, tmp_path) == {}


@pytest.mark.parametrize("name,causality", [(name, "force") for name in NETWORKS] + [("joint", "displacement")])
def test_network_kernels_call_no_libm(name, causality, tmp_path):
    compiled = network_kernels(NETWORKS[name], causality)
    assert compiled
    assert libm_calls(compiled, tmp_path) == {}


def test_the_check_sees_libm(tmp_path):
    """The check itself: a cfunc calling math.cos, math.pow and complex abs is caught (cos, pow, hypot), in the
    IR and in the object."""
    import math

    from numba import cfunc, types

    @cfunc(types.float64(types.float64, types.float64), error_model="numpy")
    def calls_libm(x, y):
        return math.cos(x) + math.pow(x, y) + abs(complex(x, y))

    found = libm_calls([("calls_libm", calls_libm)], tmp_path)
    assert {"llvm.cos.f64", "llvm.pow.f64", "hypot"} <= set(found)
