"""The scene contract: every key read as written, every rule refused with one line."""
import subprocess
import sys

import numpy as np
import pytest

from prandtl_fmu import SceneError, load_scene
from prandtl_fmu.cli import main
from prandtl_fmu.loads import ConstantLoad, HarmonicLoad, TableLoad

from tests.conftest import ROOT, SCENES, base_tables, scene_text


def test_paper_scene_is_sampled_as_eq_7_19():
    scene = load_scene(SCENES / "paper-section-8.toml")
    n = 100
    assert scene.branches.n == n
    np.testing.assert_allclose(scene.branches.stiffness, np.full(n, 1.0 / n), rtol=0, atol=0)
    np.testing.assert_allclose(scene.branches.yield_displacement, 0.1 + np.arange(1, n + 1) / n, rtol=1e-15)
    assert scene.mass.m == 1.0 and scene.spring.k0 == 0.0
    assert scene.load == HarmonicLoad(amplitude=0.45, omega=0.5, offset=0.0)
    assert (scene.solver.stepper, scene.solver.step, scene.solver.stop_time) == ("projected", 1e-3, 500.0)
    assert scene.effects == ["mass", "spring", "branches"]


def test_every_key_is_read(write_scene):
    tables = base_tables()
    tables["branches"] = {"k": [2.0, 4.0], "alpha": [1.0, 0.4], "u0": [0.25, -0.1]}
    tables["mass"] = {"m": 2.5, "x0": 0.3, "v0": -0.2}
    scene = load_scene(write_scene(tables))
    assert (scene.mass.m, scene.mass.x0, scene.mass.v0) == (2.5, 0.3, -0.2)
    assert (scene.spring.k0, scene.cubic.k3, scene.damper.c) == (0.2, 0.05, 0.01)
    np.testing.assert_array_equal(scene.branches.yield_displacement, [0.5, 0.1])
    np.testing.assert_array_equal(scene.branches.threshold, [1.0, 0.4])
    np.testing.assert_array_equal(scene.branches.u0, [0.25, -0.1])


def test_defaults_and_absent_tables(write_scene):
    tables = base_tables(spring=None, cubic=None, damper=None, load=None)
    tables["mass"] = {"m": 1}  # an integer is a number too
    tables["branches"] = {"k": [1.0], "eta": [0.5]}
    tables["solver"] = {"step": 0.01, "stop_time": 1, "output_interval": 0.1}
    scene = load_scene(write_scene(tables))
    assert scene.effects == ["mass", "branches"]
    assert (scene.mass.x0, scene.mass.v0) == (0.0, 0.0)
    np.testing.assert_array_equal(scene.branches.u0, [0.0])
    assert scene.load == ConstantLoad(0.0)
    assert scene.solver.stepper == "projected"


def test_load_kinds(write_scene):
    tables = base_tables(load={"kind": "constant", "value": 0.7})
    assert load_scene(write_scene(tables)).load == ConstantLoad(0.7)
    tables = base_tables(load={"kind": "table", "time": [0.0, 1.0, 1.0, 2.0], "force": [0.0, 1.0, 2.0, 0.0]})
    load = load_scene(write_scene(tables)).load
    assert isinstance(load, TableLoad)
    from prandtl_fmu.loads import force_at

    compiled = load.compile()
    assert force_at(compiled, 0.5) == 0.5
    assert force_at(compiled, 1.0) == 2.0  # right-continuous at a jump
    assert force_at(compiled, 1.5) == 1.0
    assert force_at(compiled, 7.0) == 0.0  # held after the end


# Each case: a change to the base scene, the key the message must name, and a word of the rule.
BAD = {
    "unknown top key": (lambda t: t.update(foo=1), "foo", "unknown key"),
    "unknown key in table": (lambda t: t["spring"].update(k=1.0), "[spring] k", "unknown key"),
    "missing m": (lambda t: t["mass"].pop("m"), "[mass] m", "missing"),
    "m zero": (lambda t: t["mass"].update(m=0.0), "[mass] m", "> 0"),
    "m negative": (lambda t: t["mass"].update(m=-1.0), "[mass] m", "> 0"),
    "negative k0": (lambda t: t["spring"].update(k0=-1.0), "[spring] k0", ">= 0"),
    "negative k3": (lambda t: t["cubic"].update(k3=-1.0), "[cubic] k3", ">= 0"),
    "negative c": (lambda t: t["damper"].update(c=-0.1), "[damper] c", ">= 0"),
    "missing k0": (lambda t: t["spring"].pop("k0"), "[spring] k0", "missing"),
    "string number": (lambda t: t["spring"].update(k0="1.0"), "[spring] k0", "must be a number"),
    "boolean number": (lambda t: t["damper"].update(c=True), "[damper] c", "must be a number"),
    "nan": (lambda t: t["mass"].update(x0=float("nan")), "[mass] x0", "finite"),
    "inf": (lambda t: t["load"].update(amplitude=float("inf")), "[load] amplitude", "finite"),
    "nan in list": (lambda t: t["branches"].update(k=[0.5, float("nan"), 0.2]), "[branches] k[2]", "finite"),
    "branch k zero": (lambda t: t["branches"].update(k=[0.5, 0.0, 0.2]), "[branches] k[2]", "> 0"),
    "negative eta": (lambda t: t["branches"].update(eta=[0.1, -0.3, 0.6]), "[branches] eta[2]", ">= 0"),
    "lengths differ": (lambda t: t["branches"].update(eta=[0.1, 0.3]), "[branches] eta", "must have 3 values"),
    "u0 length": (lambda t: t["branches"].update(u0=[0.0]), "[branches] u0", "must have 3 values"),
    "u0 beyond eta": (lambda t: t["branches"].update(u0=[0.2, 0.0, 0.0]), "[branches] u0[1]", "<= eta"),
    "eta and alpha": (lambda t: t["branches"].update(alpha=[1.0, 1.0, 1.0]), "[branches] alpha", "not both"),
    "neither eta nor alpha": (lambda t: t["branches"].pop("eta"), "[branches] eta", "missing"),
    "empty list": (lambda t: t["branches"].update(k=[], eta=[], u0=[]), "[branches] k", "empty"),
    "list not list": (lambda t: t["branches"].update(k=1.0), "[branches] k", "list"),
    "count zero": (lambda t: t.update(branches={"count": 0, "k_total": 1.0, "eta_range": [0.1, 1.1]}),
                   "[branches] count", ">= 1"),
    "count float": (lambda t: t.update(branches={"count": 2.5, "k_total": 1.0, "eta_range": [0.1, 1.1]}),
                    "[branches] count", "integer"),
    "eta_range length": (lambda t: t.update(branches={"count": 4, "k_total": 1.0, "eta_range": [0.1]}),
                         "[branches] eta_range", "two numbers"),
    "mixed branch forms": (lambda t: t["branches"].update(count=3), "[branches]", "unknown key"),
    "table not table": (lambda t: t.update(spring=3.0), "[spring]", "must be a table"),
    "load kind": (lambda t: t["load"].update(kind="sine"), "[load] kind", "one of"),
    "load key of other kind": (lambda t: t["load"].update(value=1.0), "[load] value", "unknown key"),
    "load missing omega": (lambda t: t["load"].pop("omega"), "[load] omega", "missing"),
    "table lengths": (lambda t: t.update(load={"kind": "table", "time": [0.0, 1.0], "force": [1.0]}),
                      "[load] force", "must have 2 values"),
    "table decreasing": (lambda t: t.update(load={"kind": "table", "time": [0.0, 2.0, 1.0], "force": [1.0, 2.0, 3.0]}),
                         "[load] time[3]", "non-decreasing"),
    "missing solver": (lambda t: t.pop("solver"), "[solver]", "missing"),
    "missing step": (lambda t: t["solver"].pop("step"), "[solver] step", "missing"),
    "step zero": (lambda t: t["solver"].update(step=0.0), "[solver] step", "> 0"),
    "stop_time negative": (lambda t: t["solver"].update(stop_time=-1.0), "[solver] stop_time", "> 0"),
    "output not multiple": (lambda t: t["solver"].update(output_interval=0.0015), "[solver] output_interval",
                            "whole multiple"),
    "output below step": (lambda t: t["solver"].update(output_interval=0.0005), "[solver] output_interval",
                          "whole multiple"),
    "unknown stepper": (lambda t: t["solver"].update(stepper="rk4"), "[solver] stepper", "one of"),
    "massless projected without dashpot": (lambda t: (t.pop("mass"), t.pop("damper")), "[solver] stepper",
                                           "needs [mass] or a [damper] with c > 0"),
    "name not string": (lambda t: t.update(name=3), "name", "string"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_scene_is_refused_with_one_line(case, write_scene, capsys):
    change, key, rule = BAD[case]
    tables = base_tables()
    tables["branches"] = dict(tables["branches"])
    change(tables)
    path = write_scene(tables)
    with pytest.raises(SceneError):
        load_scene(path)
    status = main(["run", str(path)])
    captured = capsys.readouterr()
    assert status == 2
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, lines
    assert str(path) in lines[0] and key in lines[0] and rule in lines[0], lines[0]


def test_not_toml_and_missing_file(tmp_path, capsys):
    path = tmp_path / "broken.toml"
    path.write_text("[mass\nm = 1")
    assert main(["run", str(path)]) == 2
    assert "not valid TOML" in capsys.readouterr().err
    assert main(["run", str(tmp_path / "nope.toml")]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_scene_is_data_not_code(tmp_path):
    # A string where a number belongs is refused, never evaluated.
    marker = tmp_path / "evaluated"
    tables = base_tables()
    tables["spring"] = {"k0": f"__import__('pathlib').Path({str(marker)!r}).touch() or 1.0"}
    path = tmp_path / "evil.toml"
    path.write_text(scene_text(tables))
    with pytest.raises(SceneError, match="must be a number"):
        load_scene(path)
    assert not marker.exists()


def test_cli_exit_status_and_no_traceback(write_scene):
    tables = base_tables()
    tables["spring"] = {"k0": -1.0}
    path = write_scene(tables)
    run = subprocess.run([sys.executable, "-m", "prandtl_fmu", "run", str(path)],
                         capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 2
    assert run.stderr.count("\n") == 1 and "Traceback" not in run.stderr
    assert "[spring] k0" in run.stderr


@pytest.mark.parametrize("option, value, key", [
    ("--step", "0.0015", "--output-interval"),
    ("--step", "-1", "step"),
    ("--stop-time", "0", "stop_time"),
    ("--output-interval", "nan", "output_interval"),
])
def test_bad_cli_override_is_refused(option, value, key, write_scene, capsys):
    path = write_scene(base_tables())
    assert main(["run", str(path), option, value]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0] and str(path) in err[0]
