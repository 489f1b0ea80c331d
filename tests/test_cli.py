"""The CLI contract: the CSV that ``run`` writes, its options, the plot."""
import csv
import io
import subprocess
import sys

import numpy as np

from prandtl_fmu import load_scene, simulate
from prandtl_fmu.cli import main

from .conftest import ROOT, SCENES, base_tables


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
