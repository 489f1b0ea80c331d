"""The native FMU on random scenes (issue 24's evidence): every effect, branch kernel and load, the element and the
connector, bit for bit the library (a file of its own: the suite's workers take a file each)."""
import os
import shutil

import numpy as np
import pytest

from prandtl_fmu import load_scene, parse_scene
from prandtl_fmu.element import Element

from tests.conftest import ROOT, base_tables, scene_text
from tests.fmu.native.test_against_library import ENERGIES, SOLVER, same, step_both, steppers_of

# random scenes, a native FMU built for each (minutes): run by .ci/run after the quick suite
pytestmark = pytest.mark.slow

pytest.importorskip("fmpy")
if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)


def random_tables(seed, connector=False):
    """A random scene (independent of the fixed ones above): a random subset of the effects (a mass or none, the
    springs, a dashpot, friction on the mass with or without Stribeck and a belt), branches on any kernel (a few
    with or without series dashpots, 70 on the memory stack, the continuum, an Iwan spectrum), any load; the
    connector's when ``connector``. Redrawn while the scene format refuses the combination (bounded: fails
    loudly)."""
    rng = np.random.default_rng(seed)
    for _ in range(200):
        n = int(rng.integers(1, 6))
        kinds = {
            "play": {"k": rng.uniform(0.2, 1.5, n).tolist(), "eta": rng.uniform(0.02, 0.5, n).tolist()},
            "series": {"k": rng.uniform(0.2, 1.5, n).tolist(), "eta": rng.uniform(0.02, 0.5, n).tolist(),
                       "c": rng.uniform(0.3, 5.0, n).tolist()},
            "stack": {"count": 70, "k_total": float(rng.uniform(0.5, 2.0)),
                      "eta_range": sorted(rng.uniform(0.0, 0.8, 2).tolist())},
            "continuum": {"continuum": True, "k_total": float(rng.uniform(0.5, 2.0)),
                          "eta_range": sorted(rng.uniform(0.0, 0.8, 2).tolist())},
            "iwan": {"count": 80, "density": {"kind": "iwan", "F_S": float(rng.uniform(0.2, 1.0)), "K_T": 2.0,
                                              "chi": -0.5, "beta": 0.1}},
        }
        massive = not connector and rng.uniform() < 0.75
        loads = [{"kind": "harmonic", "amplitude": float(rng.uniform(0.3, 1.2)), "omega": float(rng.uniform(0.3, 2))},
                 {"kind": "table", "time": [0.0, 2.0, 5.0, 10.0], "force": rng.uniform(-1, 1, 4).tolist()},
                 {"kind": "constant", "value": float(rng.uniform(-0.8, 0.8))}]
        stribeck = rng.uniform() < 0.5
        kind = str(rng.choice(list(kinds)))
        tables = base_tables(
            mass={"m": float(rng.uniform(0.5, 2.0)), "x0": float(rng.uniform(-0.05, 0.05)), "v0": 0.0}
            if massive else None,
            spring={"k0": float(rng.uniform(0.1, 1.0))} if rng.uniform() < 0.7 else None,
            cubic={"k3": float(rng.uniform(0.01, 0.2))} if rng.uniform() < 0.4 else None,
            damper={"c": float(rng.uniform(0.3, 1.0))} if rng.uniform() < 0.6 else None,
            branches=kinds[kind],
            friction=({"alpha": float(rng.uniform(0.05, 0.3))} | (
                {"alpha_kinetic": 0.03, "stribeck_velocity": 0.1, "belt_velocity": 0.02} if stribeck else {}))
            if massive and rng.uniform() < 0.4 else None,
            load=loads[int(rng.integers(0, 3))],
            solver=dict(SOLVER, stepper="verlet") if kind == "continuum" else SOLVER,  # implicit: not the continuum
            fmu={"causality": "displacement"} if connector else None)
        try:
            parse_scene(scene_text(tables), "random.toml")
        except ValueError:
            continue
        return tables
    raise AssertionError(f"no scene the format accepts in 200 draws of seed {seed}")


@pytest.mark.parametrize("seed", [7, 1, 4, 32, 2])  # together: every effect, kernel and load (drawn here)
def test_a_random_scene_s_native_fmu_is_the_library_bit_for_bit(tmp_path, seed):
    """Every stepper that applies, random communication steps and forces, the dashpot set to 0 and back (the
    functions without c and with it): every output equals Element's to the bit."""
    from prandtl_fmu.fmu.build import build_fmu

    from tests.fmu_tools import Slave

    path = tmp_path / "random.toml"
    path.write_text(scene_text(random_tables(seed)))
    fmu = build_fmu(path, tmp_path / "random.fmu", runtime="native")
    scene = load_scene(path)
    rng = np.random.default_rng(seed)
    for stepper in steppers_of(scene):
        slave = Slave(fmu, start_values={"stepper": stepper})
        element = Element(scene, stepper=stepper)
        names = ["x", "v", "reaction", "stiffness"] + [n for n in ENERGIES if n in slave.vr]
        try:
            for j in range(30):
                if j in (10, 20) and "c" in slave.vr and scene.mass is not None:
                    c = 0.0 if j == 10 else 0.4
                    slave.set("c", c)
                    element.set_coefficients(c=c)
                step_both(slave, element, rng, names, stepper)
        finally:
            slave.close()


@pytest.mark.parametrize("seed", [12, 1])  # series dashpots (massless, a cubic spring); the stack
def test_a_random_connector_s_native_fmu_is_the_pythonfmu_one_bit_for_bit(tmp_path, seed):
    """A random connector scene: random motions read before and after each step, every output to the bit."""
    from prandtl_fmu.fmu.build import build_fmu

    from tests.fmu_tools import Slave

    path = tmp_path / "random.toml"
    path.write_text(scene_text(random_tables(seed, connector=True)))
    python, native = (Slave(build_fmu(path, tmp_path / f"{runtime}.fmu", runtime=runtime)) for runtime in
                      ("python", "native"))
    names = [v.name for v in python.md.modelVariables if v.causality == "output"]
    rng = np.random.default_rng(seed)
    try:
        for j in range(60):
            x, v = float(rng.uniform(-0.6, 0.6)), float(rng.uniform(-1, 1))
            for slave in (python, native):
                slave.set("x", x)
                slave.set("v", v)
            assert same(native.get(*names), python.get(*names)), j
            size = float(rng.choice([0.01, 0.05, 0.1]))
            python.step(size)
            native.step(size)
            assert same(native.get(*names), python.get(*names)), j
    finally:
        python.close()
        native.close()


def test_building_both_runtimes_in_one_process_leaves_no_cache_entry_a_later_process_cannot_load(tmp_path):
    """The PythonFMU FMU and the native FMU of a connector built in one process, then the PythonFMU one stepped
    there: a kernel of the FMU's library copy compiled once that copy had left sys.modules was cached under the
    module "<dynamic>", and the next process's getReal failed ("No module named '<dynamic>'"). In a fresh cache:
    no such entry, and a second process reads the outputs."""
    import subprocess
    import sys

    script = tmp_path / "both.py"
    script.write_text(f"""
import pathlib, sys
sys.path.insert(0, {str(ROOT)!r})
from tests.fmu.native.test_random_scenes import test_a_random_connector_s_native_fmu_is_the_pythonfmu_one_bit_for_bit as run
from tests.fmu_tools import Slave
folder = pathlib.Path({str(tmp_path)!r})
if sys.argv[1] == "build":
    run(folder, 12)  # builds python.fmu and native.fmu there, steps both
slave = Slave(folder / "python.fmu")
slave.set("x", 0.1)
slave.set("v", 0.2)
slave.step(0.05)
print(slave.get("force", "stiffness", "stored_energy", "dissipated_sliders"))
slave.close()
""")
    environment = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    runs = [subprocess.run([sys.executable, str(script), stage], capture_output=True, text=True, timeout=600,
                           env=environment) for stage in ("build", "load")]
    for run in runs:
        assert run.returncode == 0, run.stderr[-2000:]
    assert runs[0].stdout == runs[1].stdout
    poisoned = [entry.name for entry in (tmp_path / "cache").rglob("*.nbc") if b"<dynamic>" in entry.read_bytes()]
    assert not poisoned, poisoned
