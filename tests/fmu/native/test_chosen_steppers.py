"""A native FMU built with only some steppers (``--steppers``): it compiles those alone; a bad choice stops the build
in one line (exit 2, no FMU); a network's FMU refuses the stepper it does not hold. The element's FMUs built so
(tests/fmu/native/test_against_library.py's ``held``) are the library bit for bit with each stepper they hold, name
them in their model description and page, and refuse the others with a logged reason (the tests there)."""
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from prandtl_fmu import load_scene, simulate

from tests.conftest import SCENES, base_tables, scene_text
from tests.networks.scenes import SCENES as NETWORK_SCENES

pytest.importorskip("fmpy")
if shutil.which(os.environ.get("CC", "cc")) is None and shutil.which("gcc") is None:
    pytest.skip("no C compiler: a native FMU cannot be built here", allow_module_level=True)

SOLVER = {"stepper": "implicit", "step": 0.01, "stop_time": 10.0, "output_interval": 0.1}
# friction on the mass and series dashpots: exact applies too, so leaving it out is the option's doing
SCENE = base_tables(cubic=None, solver=SOLVER, friction={"alpha": 0.3},
                    branches={"k": [0.5, 0.3, 0.2], "eta": [0.1, 0.3, 0.6], "c": [0.4, 2.0, 9.0]},
                    load={"kind": "harmonic", "amplitude": 0.8, "omega": 1.3})
NETWORKS = SCENES / "networks"
# every node massive, all plasticity in branches: both network steppers apply; its own is projected
TWO_NODES = NETWORK_SCENES["branches"]


def test_only_the_steppers_asked_for_are_compiled(tmp_path, monkeypatch):
    from prandtl_fmu.fmu.native import build

    monkeypatch.setattr(build, "element_objects", lambda scene, scene_bytes, steppers, folders:
                        (_ for _ in ()).throw(RuntimeError(f"compiles {','.join(steppers)}")))
    path = tmp_path / "scene.toml"
    path.write_text(scene_text(SCENE))
    with pytest.raises(RuntimeError, match="compiles projected,implicit$"):
        build.build_native_fmu(path, tmp_path / "out.fmu", steppers=["implicit", "projected"])
    with pytest.raises(RuntimeError, match="compiles projected,implicit,symplectic,verlet,exact$"):
        build.build_native_fmu(path, tmp_path / "out.fmu")
    assert not (tmp_path / "out.fmu").exists()


CONNECTOR = base_tables(mass=None, cubic=None, load=None, solver=SOLVER)  # the massless element between two bodies


@pytest.mark.parametrize("tables, arguments, culprit", [
    (SCENE, ["--steppers", "projected"], "PythonFMU runtime compiles a stepper"),
    (SCENE, ["--runtime", "native", "--steppers", "projected"], "must hold the scene's own stepper 'implicit'"),
    (SCENE, ["--runtime", "native", "--steppers", "implicit,rk4"], "'rk4' is not a stepper"),
    (SCENE, ["--runtime", "native", "--steppers", "implicit,"], "an empty name"),
    (CONNECTOR, ["--runtime", "native", "--steppers", "implicit", "--causality", "displacement"],
     "the connector has no stepper"),
    (TWO_NODES, ["--runtime", "native", "--steppers", "implicit"], "must hold the scene's own stepper 'projected'"),
    (TWO_NODES, ["--runtime", "native", "--steppers", "projected,exact"],
     "'exact' is not a stepper this scene's native FMU can hold (those that apply: implicit, projected)"),
    ("chain-dynamic", ["--runtime", "native", "--steppers", "implicit,projected"],
     "'projected' is not a stepper this scene's native FMU can hold (those that apply: implicit)"),
], ids=["python-runtime", "without-the-scene-s", "unknown", "empty-name", "connector", "network-without-the-scene-s",
        "network-exact", "network-not-applying"])
def test_a_bad_choice_of_steppers_is_refused_in_one_line(tmp_path, tables, arguments, culprit):
    path = tmp_path / "scene.toml"
    if tables == "chain-dynamic":  # a network shipped in the package
        path = NETWORKS / f"{tables}.toml"
    else:
        path.write_text(tables if isinstance(tables, str) else scene_text(tables))
    out = tmp_path / "out.fmu"
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "build", str(path), "-o", str(out), *arguments],
                          capture_output=True, text=True)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert culprit in done.stderr and not out.exists()


def test_a_stepper_that_does_not_apply_cannot_be_held(tmp_path):
    """A cubic spring: exact does not apply, so no FMU can hold it."""
    path = tmp_path / "scene.toml"
    path.write_text(scene_text(base_tables(solver=SOLVER)))
    out = tmp_path / "out.fmu"
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "build", str(path), "-o", str(out), "--runtime",
                           "native", "--steppers", "implicit,exact"], capture_output=True, text=True)
    assert done.returncode == 2 and "'exact' is not a stepper this scene's native FMU can hold (those that apply: " \
        "projected, implicit, symplectic, verlet)" in done.stderr, done.stderr
    assert not out.exists()


@pytest.mark.slow  # a network's native build, for this test alone
def test_a_network_fmu_holds_the_stepper_asked_for_and_refuses_the_other(tmp_path):
    from fmpy import read_model_description, simulate_fmu
    from fmpy.fmi1 import FMICallException

    from prandtl_fmu.fmu.build import build_fmu

    scene_path = tmp_path / "two_nodes.toml"
    scene_path.write_text(TWO_NODES)
    fmu = build_fmu(scene_path, tmp_path / "two_nodes.fmu", runtime="native", steppers=["projected"])
    stepper = next(v for v in read_model_description(str(fmu)).modelVariables if v.name == "stepper")
    assert stepper.description.startswith("time stepper: projected (the steppers this FMU holds")
    scene = load_scene(scene_path)
    library = simulate(scene, energy=True)
    result = simulate_fmu(str(fmu), stop_time=scene.solver.stop_time, output_interval=scene.solver.output_interval,
                          start_values={"scene_load": True}, output=["reaction"])
    np.testing.assert_array_equal(result["reaction"], library.columns()["reaction"])
    with pytest.raises(FMICallException):  # implicit applies to this network, but the FMU does not hold it
        simulate_fmu(str(fmu), stop_time=1.0, start_values={"stepper": "implicit"})
