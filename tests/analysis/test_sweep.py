"""Sweeps on dask.distributed (issue 14): the random load, the per-run summaries, the sweep file, and sweeps
that equal the same runs done one by one, bit for bit, however they are run (a LocalCluster, a scheduler and
workers in separate processes, a worker killed in the middle, an interrupted sweep resumed)."""
import math
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from prandtl_fmu import parse_scene
from prandtl_fmu.driver import simulate
from prandtl_fmu.loads import force_at, uniform_stream
from prandtl_fmu.scene import SceneError
from prandtl_fmu.summary import summarize

from tests.conftest import base_tables, scene_text
from tests.paths import ROOT

distributed = pytest.importorskip("distributed")
pd = pytest.importorskip("pandas")
pytest.importorskip("pyarrow")

from prandtl_fmu.sweep import SweepError, plan, read_sweep, sweep  # noqa: E402
from prandtl_fmu.sweep.spec import parse_spec  # noqa: E402

RANDOM = {"kind": "random", "seed": 11, "rms": 0.4, "band": [0.2, 3.0], "components": 64}


# ------------------------------------------------------------------ the random load

def test_the_uniform_stream_is_numpys_own_generator_of_the_same_seed():
    """Independent path: numpy's Generator.random draws (next_uint64 >> 11) * 2^-53 from the same PCG64."""
    for seed in (0, 1, 12345, 2**62):
        assert np.array_equal(uniform_stream(seed, 1000), np.random.Generator(np.random.PCG64(seed)).random(1000))


def test_a_random_load_is_its_formula_and_a_function_of_its_seed_alone():
    scene = parse_scene(scene_text(base_tables(load=RANDOM)))
    load = scene.load
    omega, phase = load.frequencies_and_phases()
    cells = np.floor((omega - 0.2) / (2.8 / 64)).astype(int)
    assert np.array_equal(cells, np.arange(64))  # one frequency in each cell of the band
    assert np.all((phase >= 0) & (phase < 2 * math.pi))
    compiled = load.compile()
    times = np.linspace(0, 100, 777)
    formula = 0.4 * math.sqrt(2 / 64) * np.cos(np.outer(times, omega) + phase).sum(axis=1)
    kernel = np.array([force_at(compiled, t) for t in times])
    np.testing.assert_allclose(kernel, formula, rtol=0, atol=1e-13)
    again = parse_scene(scene_text(base_tables(load=dict(RANDOM))))
    assert np.array_equal([force_at(again.load.compile(), t) for t in times], kernel)
    other = parse_scene(scene_text(base_tables(load=dict(RANDOM, seed=12))))
    assert not np.allclose([force_at(other.load.compile(), t) for t in times], kernel)


def test_a_random_load_has_its_rms_and_its_offset():
    scene = parse_scene(scene_text(base_tables(load=dict(RANDOM, components=400, offset=0.25))))
    values = np.array([force_at(scene.load.compile(), t) for t in np.arange(0, 20000, 0.37)])
    assert abs(values.mean() - 0.25) < 0.02
    assert abs(values.std() / 0.4 - 1) < 0.03


@pytest.mark.parametrize("load, message", [
    (dict(RANDOM, band=[3.0, 1.0]), "[load] band: must be [omega_min, omega_max]"),
    (dict(RANDOM, band=[1.0]), "[load] band: must be [omega_min, omega_max]"),
    (dict(RANDOM, seed=-1), "[load] seed: must be >= 0"),
    (dict(RANDOM, seed=1.5), "[load] seed: must be an integer"),
    (dict(RANDOM, rms=-1.0), "[load] rms: must be >= 0.0"),
    (dict(RANDOM, components=0), "[load] components: must be >= 1"),
    (dict(RANDOM, amplitude=1.0), "[load] amplitude: unknown key"),
])
def test_a_bad_random_load_is_one_line_naming_the_key(load, message):
    with pytest.raises(SceneError) as info:
        parse_scene(scene_text(base_tables(load=load)), "s.toml")
    assert message in str(info.value) and "\n" not in str(info.value)


def test_exact_refuses_a_random_load_in_one_line_and_the_others_run_it():
    tables = base_tables(load=RANDOM, cubic=None)
    tables["solver"] = dict(tables["solver"], stepper="exact")
    with pytest.raises(SceneError, match="a random load is a sum of many harmonics"):
        parse_scene(scene_text(tables), "s.toml")
    scene = parse_scene(scene_text(base_tables(load=RANDOM)))
    for stepper in ("projected", "implicit", "symplectic", "verlet"):
        result = simulate(scene, stepper, energy=True)
        assert np.all(np.isfinite(result.x))


# ------------------------------------------------------------------ the summaries of one run

def _fine_scene(stepper="verlet", **changes):
    """A scene whose output rows are its steps: simulate's rows see every step, as summarize does."""
    tables = base_tables(**changes)
    tables["solver"] = {"stepper": stepper, "step": 0.01, "stop_time": 30.05, "output_interval": 0.01}
    return tables


# symplectic and verlet slow: a summary loop each to compile (6 to 8 s cold), the same reduction as the others'
@pytest.mark.parametrize("stepper", ["projected", "implicit", pytest.param("symplectic", marks=pytest.mark.slow),
                                     pytest.param("verlet", marks=pytest.mark.slow)])
def test_the_summaries_are_simulates_rows_reduced_bit_for_bit(stepper):
    scene = parse_scene(scene_text(_fine_scene(stepper)))
    result = simulate(scene, energy=True)
    summary = summarize(scene, history=True)
    e = result.energy
    expected = {
        "max_abs_x": np.abs(result.x).max(), "max_abs_v": np.abs(result.v).max(),
        "max_abs_reaction": np.abs(result.reaction).max(), "final_x": result.x[-1], "final_v": result.v[-1],
        "final_reaction": result.reaction[-1], "work": e["work"][-1],
        "dissipated_sliders": e["dissipated_sliders"][-1], "dissipated_damper": e["dissipated_damper"][-1],
        "dissipated": e["dissipated_sliders"][-1] + e["dissipated_damper"][-1],
    }
    for name, value in expected.items():
        assert summary[name] == value, name
    # loop_area: the dissipation over the last period (a whole number of steps: 2 pi / 0.7 s)
    start = int(round((30.05 - 2 * math.pi / 0.7) / 0.01))
    dissipated = e["dissipated_sliders"] + e["dissipated_damper"]
    assert summary["loop_area"] == dissipated[-1] - dissipated[start]
    for name in ("time", "x", "v", "reaction"):
        assert np.array_equal(summary[name], getattr(result, name))


def test_the_summaries_do_not_depend_on_the_output_grid_and_the_history_is_simulates():
    tables = _fine_scene()
    coarse = dict(tables, solver=dict(tables["solver"], output_interval=0.5))  # 30.05 s: a last short row
    fine_summary = summarize(parse_scene(scene_text(tables)))
    coarse_scene = parse_scene(scene_text(coarse))
    coarse_summary = summarize(coarse_scene, history=True)
    result = simulate(coarse_scene)
    for name, value in fine_summary.items():
        assert coarse_summary[name] == value, name
    assert np.abs(result.x).max() < coarse_summary["max_abs_x"]  # the rows alone miss the peak
    for name in ("time", "x", "v", "reaction"):
        assert np.array_equal(coarse_summary[name], getattr(result, name))


def test_a_summary_that_does_not_apply_is_refused_in_one_line():
    scene = parse_scene(scene_text(base_tables(load={"kind": "constant", "value": 0.3})), "s.toml")
    with pytest.raises(ValueError, match="loop_area needs a harmonic load"):
        summarize(scene, quantities=["loop_area"])
    with pytest.raises(ValueError, match="unknown summary 'peak'"):
        summarize(scene, quantities=["peak"])
    assert "loop_area" not in summarize(scene)


# ------------------------------------------------------------------ the sweep file

def _spec(text):
    import tomllib

    return parse_spec(tomllib.loads(text), "sweep.toml")


@pytest.mark.parametrize("text, message", [
    ('[grid]\n"spring.k0" = []', '[grid] spring.k0: must not be empty'),
    ('[grid]\n"spring" = [1.0]', "not a scene key"),
    ('[grid]\n"fmu.causality" = ["force"]', "[fmu] is not a table a sweep can vary"),
    ('[grid]\n"spring.k0" = { from = 0, to = 1 }', "range: count missing"),
    ('[grid]\n"spring.k0" = { from = 0, to = 1, count = 3, spacing = "log" }', "a log range needs from > 0"),
    ('[grid]\n"load.seed" = [1.5]', "load.seed takes whole numbers"),
    ('[random]\nsamples = 3\n"mass.m" = { distribution = "gauss" }', "distribution must be one of"),
    ('[random]\nsamples = 3\n"mass.m" = { distribution = "uniform", low = 1 }', "uniform: high missing"),
    ('[random]\nsamples = 3\n"mass.m" = { distribution = "uniform", low = 2, high = 1 }', "needs low < high"),
    ('[random]\nsamples = 3\n"load.seed" = { distribution = "uniform", low = 0, high = 9 }', "takes whole numbers"),
    ('[random]\n"mass.m" = { distribution = "uniform", low = 1, high = 2 }', "[random] samples: missing"),
    ('[random]\nsamples = 2', "[random]: names no key to draw"),
    ('[keep]\nsummary = ["max_abs_x"]', "the sweep varies nothing"),
    ('[grid]\n"spring.k0" = [1.0]\n[keep]\nsummary = ["area"]', "unknown quantity 'area'"),
    ('[grid]\n"spring.k0" = [1.0]\n[keep]\nsummary = []', "[keep]: keeps nothing"),
    ('[grid]\n"spring.k0" = [1.0]\n[tasks]\nruns_per_task = 0', "[tasks] runs_per_task: must be >= 1"),
    ('[grid]\n"spring.k0" = [1.0]\n[plot]\nx = 1', "plot: unknown table"),
])
def test_a_bad_sweep_file_is_one_line_naming_the_key(text, message):
    with pytest.raises(SweepError) as info:
        _spec(text)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_runs_combine_grid_points_and_samples_and_do_not_depend_on_the_split():
    spec = _spec('[grid]\n"spring.k0" = [0.0, 0.5]\n"load.omega" = { from = 0.1, to = 1000, count = 3, '
                 'spacing = "log" }\n[random]\nsamples = 4\nseed = 9\n'
                 '"mass.m" = { distribution = "normal", mean = 1.0, std = 0.1 }\n'
                 '"load.seed" = { distribution = "integers", low = 5, high = 7 }\n'
                 '"solver.stepper" = { distribution = "choice", values = ["verlet", "symplectic"] }')
    assert spec.runs == 24 and spec.keys == ["spring.k0", "load.omega", "mass.m", "load.seed", "solver.stepper"]
    runs = spec.values(0, 24)
    assert [r for r, _ in runs] == list(range(24))
    assert [v["spring.k0"] for _, v in runs] == [0.0] * 12 + [0.5] * 12  # the first key varies slowest
    np.testing.assert_allclose([v["load.omega"] for _, v in runs[:12:4]], [0.1, 10.0, 1000.0], rtol=1e-12)
    samples = [v["mass.m"] for _, v in runs[:4]]
    assert all(v["mass.m"] == samples[r % 4] for r, v in runs)  # sample r % samples at every grid point
    assert all(isinstance(v["load.seed"], int) and 5 <= v["load.seed"] <= 7 for _, v in runs)
    assert {v["solver.stepper"] for _, v in runs} <= {"verlet", "symplectic"}
    pieces = spec.values(0, 7) + spec.values(7, 13) + spec.values(13, 24)
    assert pieces == runs
    # the normal draws are the inverse CDF of the documented uniform stream
    from statistics import NormalDist

    u = uniform_stream(9, 4 * 3).reshape(4, 3)[:, 0] + 0.5 / 2**53
    assert samples == [NormalDist(1.0, 0.1).inv_cdf(p) for p in u]


def test_a_key_the_scene_cannot_take_is_refused_before_any_run(write_scene, tmp_path):
    scene = write_scene(base_tables(load={"kind": "constant", "value": 0.3}))
    spec = tmp_path / "sweep.toml"
    spec.write_text('[grid]\n"load.amplitude" = [0.1, 0.2]\n')
    with pytest.raises(SweepError, match=r"\[load\] amplitude: unknown key"):
        plan(scene, spec)
    spec.write_text('[grid]\n"branches.k[4]" = [0.1]\n')
    with pytest.raises(SweepError, match=r"branches.k\[4\]: the scene's \[branches\] k has 3 values"):
        plan(scene, spec)
    spec.write_text('[grid]\n"spring.k0" = [0.1]\n[keep]\nsummary = ["loop_area"]\n')
    with pytest.raises(SweepError, match="loop_area needs a harmonic load"):
        plan(scene, spec)


def test_a_sweep_varies_the_keys_of_a_density_table():
    """branches.density.chi: a key of an inline table; each run is the scene with it set (its own rules)."""
    from prandtl_fmu.sweep.runs import run_batch
    from prandtl_fmu.sweep.spec import apply

    tables = base_tables(mass={"m": 1.0}, cubic=None, damper=None,
                         branches={"continuum": True, "density": {"kind": "iwan", "F_S": 1.0, "K_T": 5.0,
                                                                  "chi": -0.5, "beta": 0.2}},
                         solver={"stepper": "verlet", "step": 1e-3, "stop_time": 5.0, "output_interval": 0.5})
    import tomllib

    document = tomllib.loads(scene_text(tables))
    spec = _spec('[grid]\n"branches.density.chi" = [-0.8, -0.3]\n"branches.density.F_S" = [1.0, 2.0]\n'
                 '[keep]\nsummary = ["max_abs_x", "dissipated_sliders"]')
    runs = spec.values(0, spec.runs)
    table = run_batch(document, "iwan.toml", spec.keys, runs, spec.summary, False)
    assert table["error"] == [""] * 4
    for (run, values), peak, dissipated in zip(runs, table["max_abs_x"], table["dissipated_sliders"]):
        alone = summarize(parse_scene(scene_text({**tables, "branches": {"continuum": True, "density": {
            "kind": "iwan", "F_S": values["branches.density.F_S"], "K_T": 5.0,
            "chi": values["branches.density.chi"], "beta": 0.2}}})), None, ["max_abs_x", "dissipated_sliders"])
        assert (peak, dissipated) == (alone["max_abs_x"], alone["dissipated_sliders"])
    bad = run_batch(document, "iwan.toml", spec.keys, [(0, {"branches.density.chi": -1.5,
                                                             "branches.density.F_S": 1.0})], spec.summary, False)
    assert "[branches.density] chi: must be > -1" in bad["error"][0]
    with pytest.raises(SweepError, match="the scene's branches.k is not a table"):
        apply({"branches": {"k": [1.0]}}, {"branches.k.x": 1.0})


# ------------------------------------------------------------------ sweeps

SWEEP = """
[grid]
"spring.k0" = [0.0, 0.3]
"load.amplitude" = { from = 0.4, to = 0.8, count = 5 }
[random]
samples = 5
seed = 2
"mass.m" = { distribution = "uniform", low = 0.8, high = 1.2 }
[keep]
history = true
"""


@pytest.fixture(scope="module")
def cluster():
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as local:
        with Client(local) as client:
            # both workers known to the client before a test asks (under load the client's view of the
            # scheduler lagged: one worker, so the first task did not run alone)
            client.wait_for_workers(2)
            yield local, client


@pytest.fixture
def sweep_files(tmp_path):
    tables = _fine_scene()
    tables["solver"]["stop_time"] = 10.05
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text(tables))
    spec = tmp_path / "sweep.toml"
    spec.write_text(SWEEP)
    return scene, spec, tables


def _one_by_one(tables, frame):
    """Each run of ``frame`` done alone with simulate, compared bit for bit."""
    for row in frame.to_dict("records"):
        run = {key: dict(value) if isinstance(value, dict) else value for key, value in tables.items()}
        run["spring"] = {"k0": row["spring.k0"]}
        run["load"] = dict(run["load"], amplitude=row["load.amplitude"])
        run["mass"] = dict(run["mass"], m=row["mass.m"])
        result = simulate(parse_scene(scene_text(run)), energy=True)
        e = result.energy
        assert row["error"] == ""
        assert row["final_x"] == result.x[-1] and row["final_v"] == result.v[-1]
        assert row["max_abs_x"] == np.abs(result.x).max()
        assert row["max_abs_reaction"] == np.abs(result.reaction).max()
        assert row["dissipated"] == e["dissipated_sliders"][-1] + e["dissipated_damper"][-1]
        assert np.array_equal(row["x"], result.x) and np.array_equal(row["reaction"], result.reaction)


def test_a_50_run_sweep_on_2_workers_equals_the_runs_one_by_one_bit_for_bit(cluster, sweep_files, tmp_path):
    scene, spec, tables = sweep_files
    frame = sweep(scene, spec, cluster[1], out=tmp_path / "out")
    assert len(frame) == 50 and list(frame["run"]) == list(range(50))
    assert frame.columns[:4].tolist() == ["run", "spring.k0", "load.amplitude", "mass.m"]
    assert len(list((tmp_path / "out").glob("runs-*.parquet"))) > 2  # several tasks, each many runs
    _one_by_one(tables, frame)
    again = sweep(scene, spec, cluster[1], out=tmp_path / "again")
    pd.testing.assert_frame_equal(again, frame)
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "out").sort_values("run").reset_index(drop=True),
                                  frame)


def test_local_workers_take_the_first_task_alone_then_the_others(cluster, sweep_files):
    """Workers on this machine share its numba cache: the first task runs alone (its worker compiles the
    kernels), the others start once it is done and load them, instead of both workers compiling the same kernels
    at once. Workers elsewhere get every task at once."""
    from distributed import get_task_stream

    from prandtl_fmu.sweep import _workers_share_this_machine

    scene, spec, _ = sweep_files
    with get_task_stream(client=cluster[1]) as stream:
        frame = sweep(scene, spec, cluster[1])
    assert len(frame) == 50
    computed = {}
    for record in stream.data:
        key = str(record["key"])
        if "prandtl-sweep-" in key:
            for part in record["startstops"]:
                if part["action"] == "compute":
                    computed[int(key.rpartition("-")[2])] = (part["start"], part["stop"])
    assert len(computed) > 2 and 0 in computed, computed
    assert all(start >= computed[0][1] for first, (start, _) in computed.items() if first != 0), computed

    class Scheduler:
        def __init__(self, *addresses):
            self.addresses = addresses

        def scheduler_info(self):
            return {"workers": {address: {} for address in self.addresses}}

    assert _workers_share_this_machine(cluster[1])
    assert _workers_share_this_machine(Scheduler("tcp://127.0.0.1:4001", "tcp://localhost:4002"))
    assert not _workers_share_this_machine(Scheduler("tcp://127.0.0.1:4001"))  # one worker: nothing to share
    assert not _workers_share_this_machine(Scheduler("tcp://127.0.0.1:4001", "tcp://10.0.0.7:4002"))


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_a_scheduler_and_workers_in_separate_processes_give_the_same_file(cluster, sweep_files, tmp_path):
    scene, spec, _ = sweep_files
    reference = sweep(scene, spec, cluster[1])
    address = f"tcp://127.0.0.1:{_free_port()}"
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    processes = [subprocess.Popen([*dask, "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1],
                                   "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        for _ in range(2):
            processes.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address,
                                               "--nthreads", "1", "--no-dashboard"],
                                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        out = tmp_path / "remote"
        done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "sweep", str(scene), str(spec), "--scheduler",
                               address, "--out", str(out)], capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        assert done.stdout.strip() == str(out)
        pd.testing.assert_frame_equal(read_sweep(out), reference)
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            process.wait(timeout=30)


def test_a_killed_worker_loses_no_finished_row_and_the_sweep_completes(sweep_files, tmp_path):
    from distributed import Client, LocalCluster

    scene, spec, tables = sweep_files
    spec.write_text(SWEEP.replace("history = true", "history = false") + "[tasks]\nruns_per_task = 1\n")
    out = tmp_path / "out"
    killed = {}

    def kill_a_worker_once_runs_are_written(client):
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and len(list(out.glob("runs-*.parquet"))) < 5:
            time.sleep(0.05)
        killed["written"] = len(list(out.glob("runs-*.parquet")))
        pids = client.run(os.getpid)
        victim = sorted(pids.values())[0]
        os.kill(victim, signal.SIGKILL)
        killed["pid"] = victim

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as local:
        with Client(local) as client:
            killer = threading.Thread(target=kill_a_worker_once_runs_are_written, args=(client,))
            killer.start()
            frame = sweep(scene, spec, client, out=out)
            killer.join()
    assert killed.get("pid") and 5 <= killed["written"] < 50, killed  # killed in the middle of the sweep
    assert list(frame["run"]) == list(range(50)) and (frame["error"] == "").all()
    reference = sweep(scene, spec, client=None, workers=1)
    pd.testing.assert_frame_equal(frame, reference)


def test_an_interrupted_sweep_resumes_running_only_its_unfinished_tasks(cluster, sweep_files, tmp_path):
    scene, spec, _ = sweep_files
    out = tmp_path / "out"
    whole = sweep(scene, spec, cluster[1], out=out)
    parts = sorted(out.glob("runs-*.parquet"))
    lost = parts[1::3]
    for path in lost:
        path.unlink()
    kept = {path: path.stat().st_mtime_ns for path in parts if path not in lost}
    with pytest.raises(SweepError, match="holds a sweep already: --resume"):
        sweep(scene, spec, cluster[1], out=out)
    resumed = sweep(scene, spec, cluster[1], out=out, resume=True)
    pd.testing.assert_frame_equal(resumed, whole)
    assert all(path.stat().st_mtime_ns == mtime for path, mtime in kept.items())  # finished tasks not rerun
    assert all(path.exists() for path in lost)
    spec.write_text(SWEEP.replace("seed = 2", "seed = 3"))
    with pytest.raises(SweepError, match="holds another sweep"):
        sweep(scene, spec, cluster[1], out=out, resume=True)


def test_runs_that_fail_keep_their_reason_and_the_command_line_says_so(cluster, write_scene, tmp_path):
    tables = _fine_scene()
    tables["solver"]["stop_time"] = 2.0
    scene = write_scene(tables)
    spec = tmp_path / "sweep.toml"
    spec.write_text('[grid]\n"mass.m" = [1.0, -1.0, 2.0]\n"damper.c" = [0.0]\n')
    frame = sweep(scene, spec, cluster[1])
    assert list(frame["error"] != "") == [False, True, False]
    assert "[mass] m: must be > 0, got -1.0" in frame["error"][1] and math.isnan(frame["final_x"][1])
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "sweep", str(scene), str(spec), "--workers", "1",
                           "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 1
    assert done.stderr.splitlines()[-1].startswith("error: 1 of 3 runs failed (column 'error'); first, run 1:")
    pd.testing.assert_frame_equal(read_sweep(out), frame)


@pytest.mark.parametrize("args, message", [
    (["missing.toml"], "missing.toml: no such scene file"),
    (["SCENE", "--workers", "0"], "--workers must be >= 1"),
    (["SCENE", "--out", "OUT"], "holds a sweep already"),
])
def test_bad_input_to_the_sweep_command_is_one_line_and_exit_2(write_scene, tmp_path, args, message):
    scene = write_scene(base_tables())
    spec = tmp_path / "sweep.toml"
    spec.write_text('[grid]\n"spring.k0" = [0.1]\n')
    out = tmp_path / "out"
    out.mkdir()
    (out / "_sweep.json").write_text("{}")
    args = [str(scene) if a == "SCENE" else str(out) if a == "OUT" else a for a in args]
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "sweep", args[0], str(spec), *args[1:]],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and message in done.stderr, done.stderr


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_the_amplitude_example_draws_its_heat_map(tmp_path):
    out = tmp_path / "map.png"
    done = subprocess.run([sys.executable, str(ROOT / "examples" / "sweep_amplitude.py"), "--quick", "--workers", "2",
                           "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert out.stat().st_size > 10_000
    table = pd.read_csv(tmp_path / "map.csv", index_col=0)
    assert table.shape == (3, 4) and np.all(table.values >= 0)
    assert np.all(np.diff(table.values, axis=1) >= 0)  # at k0 = 0..1, a larger amplitude dissipates more
