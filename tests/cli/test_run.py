"""The CLI contract: the CSV that ``run`` writes, its options, the plot."""
import csv
import io
import subprocess
import sys

import numpy as np
import pytest

from prandtl_fmu import load_scene, simulate
from prandtl_fmu.cli import main

from tests.conftest import ROOT, SCENES, base_tables


def read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def test_run_writes_the_contract_csv(write_scene, tmp_path):
    scene_path = write_scene(base_tables())
    out = tmp_path / "out.csv"
    assert main(["run", str(scene_path), "--out", str(out), "--stop-time", "2.05", "--stepper", "implicit"]) == 0
    header, rows = read_csv(out)
    assert header == ["time", "x", "v", "reaction"]
    times = [float(r[0]) for r in rows]
    assert times[0] == 0.0 and times[-1] == 2.05 and len(rows) == 22  # 0, 0.1, ..., 2.0, 2.05
    expected = simulate(load_scene(scene_path).with_solver(stop_time=2.05, stepper="implicit"))
    for row, x, v, r in zip(rows, expected.x, expected.v, expected.reaction):
        assert row[1:] == [repr(float(x)), repr(float(v)), repr(float(r))]  # full precision: repr
    # the reaction column is k0 x + k3 x^3 + c v + sum k_i u_i
    assert float(rows[0][3]) == 0.05 * 0.5 + -0.1 * 0.3


def test_states_columns_and_overrides(write_scene, tmp_path):
    scene_path = write_scene(base_tables())
    out = tmp_path / "out.csv"
    assert main(["run", str(scene_path), "--out", str(out), "--states", "--step", "0.002",
                 "--output-interval", "0.01", "--stop-time", "1"]) == 0
    header, rows = read_csv(out)
    assert header == ["time", "x", "v", "reaction", "u[1]", "u[2]", "u[3]"]
    assert len(rows) == 101
    u = np.array([[float(v) for v in row[4:]] for row in rows])
    assert np.all(np.abs(u) <= [0.1, 0.3, 0.6])
    np.testing.assert_array_equal(u[0], [0.05, -0.1, 0.0])


def test_stdout_and_plot(write_scene, tmp_path):
    scene_path = write_scene(base_tables())
    png = tmp_path / "loop.png"
    run = subprocess.run([sys.executable, "-m", "prandtl_fmu", "run", str(scene_path), "--stop-time", "1",
                          "--plot", str(png)], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    rows = list(csv.reader(io.StringIO(run.stdout)))
    assert rows[0] == ["time", "x", "v", "reaction"] and len(rows) == 12
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    assert run.stderr == ""  # no progress bar outside a terminal


def test_default_scene_runs_from_the_cli(tmp_path):
    out = tmp_path / "paper.csv"
    assert main(["run", str(SCENES / "paper-section-8.toml"), "--stop-time", "20", "--out", str(out)]) == 0
    header, rows = read_csv(out)
    assert len(rows) == 201
    reaction = np.array([float(r[3]) for r in rows])
    # the reaction never exceeds the strength sum alpha_i = sum k_i eta_i (k0 = 0, no dashpot)
    strength = load_scene(SCENES / "paper-section-8.toml").branches.strength
    assert np.all(np.abs(reaction) <= strength * (1 + 1e-12))
    assert np.abs(reaction).max() > 0.9 * strength


def test_the_continuum_runs_from_the_command_line_and_refuses_states_in_one_line(write_scene, tmp_path):
    scene_path = write_scene(base_tables(cubic=None, branches={"continuum": True, "k_total": 1.0,
                                                               "eta_range": [0.1, 1.1]}))
    out = tmp_path / "out.csv"
    assert main(["run", str(scene_path), "--out", str(out), "--stop-time", "3", "--energy"]) == 0
    header, rows = read_csv(out)
    assert header[:4] == ["time", "x", "v", "reaction"] and len(rows) == 31
    expected = simulate(load_scene(scene_path).with_solver(stop_time=3.0))
    assert [float(r[1]) for r in rows] == list(expected.x)
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "run", str(scene_path), "--states"],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.count("\n") == 1 and "continuum has no list of elongations" in done.stderr


def test_version_scenes_and_a_packaged_scene_named_without_a_path(tmp_path, capsys):
    import prandtl_fmu

    try:
        main(["--version"])
    except SystemExit as exit_:
        assert exit_.code == 0
    assert capsys.readouterr().out.strip() == f"prandtl-fmu {prandtl_fmu.__version__}"
    assert main(["scenes"]) == 0
    names = capsys.readouterr().out.split()
    assert "paper-section-8" in names and "hard/step-load" in names
    assert len(names) == len(list(SCENES.rglob("*.toml")))
    # a packaged scene by name, run from a folder where no such file exists: the same numbers as its file
    out = tmp_path / "named.csv"
    assert main(["run", "hard/single-branch", "--stop-time", "0.5", "--out", str(out)]) == 0
    by_file = simulate(load_scene(SCENES / "hard" / "single-branch.toml").with_solver(stop_time=0.5))
    _, rows = read_csv(out)
    assert [float(r[1]) for r in rows] == by_file.x.tolist()


def test_a_name_that_is_neither_a_file_nor_a_packaged_scene_is_one_line(capsys):
    """A misspelt name gets the closest packaged names (a name given without its folder too), not the whole
    list; a name close to nothing gets where the list is."""
    from prandtl_fmu.catalog import packaged_scenes

    for given, closest in (("paper-section-9", "paper-section-8"), ("paper-sectoin-8", "paper-section-8"),
                           ("step-lod", "hard/step-load"), ("networks/chain-masless", "networks/chain-massless")):
        assert main(["run", given]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and given in err and f"did you mean {closest}" in err, err
        assert sum(name in err.split() for name in packaged_scenes()) <= 3, err
    assert main(["run", "qqqqqq"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "did you mean" not in err and "prandtl-fmu scenes" in err


def test_a_bare_command_prints_the_usage_and_the_commands(capsys):
    assert main([]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    for command in ("run", "build", "fit", "sweep", "scenes", "bench"):
        assert command in captured.err
    assert captured.err.startswith("usage: prandtl-fmu")


def test_build_help_names_both_fmi_versions(capsys):
    try:
        main(["--help"])
    except SystemExit as exit_:
        assert exit_.code == 0
    assert "FMI 2.0 or 3.0" in capsys.readouterr().out


def test_a_step_the_output_interval_is_no_multiple_of_suggests_the_option(tmp_path, capsys):
    out = tmp_path / "never.csv"
    for step, how, suggestion in (("0.5", "is longer than", "--output-interval 0.5"),
                                  ("0.03", "does not divide", "--output-interval 0.12")):
        assert main(["run", "paper-section-8", "--step", step, "--stop-time", "1", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"--step {step} {how}" in err and suggestion in err, err
        assert not out.exists()
    # with the suggested option the run goes
    assert main(["run", "paper-section-8", "--step", "0.5", "--output-interval", "0.5", "--stop-time", "1",
                 "--out", str(out)]) == 0
    _, rows = read_csv(out)
    assert [float(r[0]) for r in rows] == [0.0, 0.5, 1.0]


def test_help_version_and_scenes_load_neither_numpy_nor_numba():
    """Printing a help text compiles nothing: a fresh interpreter answers --help, --version, scenes and a bare
    command without importing numba or numpy (the cost a user pays before anything runs)."""
    for argv in (["--help"], ["--version"], ["scenes"], [], ["build", "--help"]):
        code = ("import sys\nfrom prandtl_fmu.cli import main\ntry:\n    main(%r)\nexcept SystemExit:\n    pass\n"
                "print(sorted(m for m in ('numba', 'numpy') if m in sys.modules))" % (argv,))
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
        assert done.stdout.strip().splitlines()[-1] == "[]", (argv, done.stdout[-500:], done.stderr[-500:])


def test_build_writes_an_fmu_and_prints_its_path(tmp_path, capsys):
    from fmpy import read_model_description

    out = tmp_path / "element.fmu"
    assert main(["build", "hard/single-branch", "-o", str(out)]) == 0
    assert capsys.readouterr().out.strip() == str(out)
    assert read_model_description(str(out)).modelName == load_scene(SCENES / "hard" / "single-branch.toml").name
    assert main(["build", "hard/single-branch", "-o", str(tmp_path / "no" / "x.fmu")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    script = subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "-o", str(tmp_path / "default.fmu")],
                            capture_output=True, text=True, cwd=tmp_path)
    assert script.returncode == 0, script.stderr
    assert read_model_description(str(tmp_path / "default.fmu")).modelName == "paper-section-8"


def test_an_extra_that_is_not_installed_is_one_line_before_any_work(write_scene, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as in a core install: no [plot] extra
    out = tmp_path / "out.csv"
    assert main(["run", str(write_scene(base_tables())), "--out", str(out), "--plot", str(tmp_path / "p.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "matplotlib" in err and "prandtl_fmu[plot]" in err
    assert not out.exists()
    assert main(["bench", "--quick", "--out", str(tmp_path / "bench")]) == 2
    assert "matplotlib" in capsys.readouterr().err and not (tmp_path / "bench").exists()


def test_fmpy_example_script_runs_the_fmu_as_the_library(tmp_path):
    """The README's main job: examples/run_fmu.py drives the FMU by F alone (scene_load set false: a fresh FMU
    would add its scene's load to F) and gives the library's numbers."""
    import importlib.util

    from prandtl_fmu import Element, load_scene
    from prandtl_fmu.fmu.build import build_fmu

    spec = importlib.util.spec_from_file_location("run_fmu", ROOT / "examples" / "run_fmu.py")
    run_fmu = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(run_fmu)
    scene = ROOT / "scenes" / "paper-section-8.toml"
    fmu = build_fmu(scene, tmp_path / "element.fmu")
    result = run_fmu.run(str(fmu), stop_time=30.0)
    assert len(result) == 301  # the DefaultExperiment's step: the scene's output_interval 0.1
    element = Element(load_scene(scene))
    for k in range(300):
        element.advance(0.1, 0.45 * np.cos(0.5 * k * 0.1))
    assert result["x"][-1] == pytest.approx(element.x, abs=1e-12)


def test_the_example_script_without_fmpy_names_the_extra(tmp_path):
    """examples/run_fmu.py where FMPy is not installed: one line naming the extra, exit 2."""
    hide = ("import importlib.util, runpy, sys\n"
            "found = importlib.util.find_spec\n"
            "importlib.util.find_spec = lambda name, *rest: None if name == 'fmpy' else found(name, *rest)\n"
            "sys.argv = ['run_fmu.py', 'element.fmu']\n"
            "runpy.run_path(%r, run_name='__main__')\n" % str(ROOT / "examples" / "run_fmu.py"))
    done = subprocess.run([sys.executable, "-c", hide], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 2
    assert done.stderr == "error: examples/run_fmu.py needs fmpy: pip install 'prandtl_fmu[fmpy]'\n"
