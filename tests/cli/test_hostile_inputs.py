"""A corpus of hostile inputs for the CLI and build_fmu.py: each exits 0 or 2, never prints a traceback,
prints at most one line on stderr and leaves no partial file (issue: "Trust every number and every exit")."""
import os
import subprocess
import sys

import numpy as np
import pytest

from prandtl_fmu.cli import main

from tests.conftest import ROOT, base_tables, scene_text


def run_cli(argv, capsys):
    """main() in-process: returns (status, stderr lines, stdout). An exception escaping is a traceback."""
    status = main([str(a) for a in argv])
    captured = capsys.readouterr()
    lines = [line for line in captured.err.splitlines() if line.strip()]
    return status, lines, captured.out


def check(status, lines, folder=None):
    assert status in (0, 2), lines
    assert len(lines) <= 1, lines
    assert not any("Traceback" in line for line in lines)
    if folder is not None:  # no partial or temporary file left behind
        assert not [p.name for p in folder.iterdir() if p.name.startswith(".prandtl-") or p.suffix == ".part"]


SOLVER = {"stepper": "implicit", "step": 1e-2, "stop_time": 2.0, "output_interval": 0.5}
HOSTILE_SCENES = {
    "massless quasi-static on the stack": (base_tables(mass=None, damper=None, cubic=None, solver=SOLVER, branches={
        "count": 100, "k_total": 1.0, "eta_range": [0.1, 1.1]}), 0, None),
    "massless with c = 0 and projected": (base_tables(mass=None, damper={"c": 0.0}, solver={**SOLVER,
                                          "stepper": "projected"}), 2, "c > 0"),
    "stability overflow": (base_tables(mass={"m": 1.0}, damper={"c": 2.0}, spring={"k0": 1.0000000001}, cubic=None,
                                       branches=None, solver={"stepper": "projected", "step": 3.0,
                                                              "stop_time": 3000.0, "output_interval": 3.0}), None, None),
    "m = 1e308": (base_tables(mass={"m": 1e308}), 2, "[mass] m: |1e+308| is outside [1e-50, 1e+50]"),
    "F = 1e307 implicit": (base_tables(load={"kind": "constant", "value": 1e307}, solver=SOLVER), None, None),
    "F = 1.7e308 implicit": (base_tables(load={"kind": "constant", "value": 1.7e308}, solver=SOLVER), None, None),
    "count = 10**12": (base_tables(branches={"count": 10**12, "k_total": 1.0, "eta_range": [0.1, 1.1]}), 2,
                       "memory"),
    "u0 beyond eta": (base_tables(branches={"k": [1.0], "eta": [0.5], "u0": [0.7]}), 2, "eta = 0.5, got 0.7"),
    "huge integer": (base_tables(spring={"k0": 10**400}), 2, "k0"),
    "alpha / k overflows": (base_tables(branches={"k": [1e-300], "alpha": [1e300]}), 2, "alpha"),
    "collapse of the massless element": (base_tables(mass=None, damper=None, spring=None, cubic=None, solver=SOLVER,
                                                     load={"kind": "constant", "value": 100.0}), 2, "collapse"),
}


@pytest.mark.parametrize("case", list(HOSTILE_SCENES))
def test_hostile_scenes(case, write_scene, tmp_path, capsys):
    tables, expected, words = HOSTILE_SCENES[case]
    out = tmp_path / "out.csv"
    status, lines, _ = run_cli(["run", write_scene(tables), "--out", out], capsys)
    check(status, lines, tmp_path)
    if expected is not None:
        assert status == expected, lines
    if words:
        assert words in lines[0]
    assert "np.float64" not in " ".join(lines)
    assert out.exists() == (status == 0)


@pytest.mark.parametrize("options, words", [
    (["--out", "/nonexistent-folder/x.csv"], "does not exist"),
    (["--out", "{tmp}"], "is a directory"),
    (["--plot", "/nonexistent-folder/p.png"], "does not exist"),
    (["--step", "1e-300"], "too small"),
    (["--step", "nan"], "finite"),
    (["--stop-time", "1e12", "--out", "{tmp}/big.csv"], "disk"),
    (["--output-interval", "0.0015"], "whole multiple"),
])
def test_hostile_options(options, words, write_scene, tmp_path, capsys):
    scene = write_scene(base_tables(cubic=None))
    options = [o.replace("{tmp}", str(tmp_path)) for o in options]
    status, lines, out = run_cli(["run", scene] + options, capsys)
    check(status, lines, tmp_path)
    assert status == 2 and words in lines[0], lines
    assert out == ""  # nothing ran


def test_stepper_option_rescues_a_massless_scene(write_scene, capsys):
    """The scene's default stepper (projected) does not apply to it; --stepper implicit must."""
    tables = base_tables(mass=None, damper=None, solver={"step": 1e-2, "stop_time": 1.0, "output_interval": 0.5})
    status, lines, out = run_cli(["run", write_scene(tables), "--stepper", "implicit"], capsys)
    assert status == 0 and lines == [] and out.count("\n") == 4


def test_a_full_disk_leaves_no_file(write_scene, capsys):
    """/dev/full: every write fails with ENOSPC. A device is written directly (never replaced)."""
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    status, lines, _ = run_cli(["run", write_scene(base_tables()), "--out", "/dev/full"], capsys)
    check(status, lines)
    assert status == 2 and "cannot write /dev/full" in lines[0]
    assert os.path.exists("/dev/full") and not os.path.isfile("/dev/full")


@pytest.mark.parametrize("option", ["--out", "--plot"])
def test_a_full_disk_under_describe_is_said_as_such(write_scene, tmp_path, capsys, option):
    """describe's CSV or figure on /dev/full: "cannot write", exit 2 (it said "internal error (OSError ...);
    please report it", a review's find)."""
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    other = ["--out", str(tmp_path / "curve.csv")] if option == "--plot" else []
    status, lines, _ = run_cli(["describe", "networks/two-mass-joint", "--force-amplitude", "0.1", "--frequencies",
                                "0.1,0.2", "--harmonics", "1", "--tolerance", "0.1", option, "/dev/full"] + other,
                               capsys)
    check(status, lines)
    assert status == 2 and "cannot write" in lines[0] and "/dev/full" in lines[0] and "internal" not in lines[0]


def test_an_existing_output_is_untouched_by_a_failed_run(write_scene, tmp_path, capsys):
    out = tmp_path / "out.csv"
    out.write_text("precious\n")
    tables = base_tables(mass=None, damper=None, spring=None, cubic=None, solver=SOLVER,
                         load={"kind": "table", "time": [0.0, 1.0, 1.0], "force": [0.0, 0.0, 100.0]})
    status, lines, _ = run_cli(["run", write_scene(tables), "--out", out], capsys)
    check(status, lines, tmp_path)
    assert status == 2 and "collapse" in lines[0]
    assert out.read_text() == "precious\n"


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_output_streams_in_bounded_memory(write_scene, tmp_path, capsys, monkeypatch):
    """10 000 rows x 204 columns (16 MB as doubles, 40 MB as text) go to the file a chunk at a time: with chunks
    of 10 000 values (2 000 000 in use) the peak is about 1 MB, a chunk's doubles and text, not the table's
    (measured: the peak grows with the chunk, 90 bytes per value). A first short run loads the compiled kernels
    outside the measurement."""
    import tracemalloc

    from prandtl_fmu import driver

    monkeypatch.setattr(driver, "_CHUNK_VALUES", 10_000)
    tables = base_tables(cubic=None, branches={"count": 200, "k_total": 1.0, "eta_range": [0.1, 1.1]},
                         solver={"stepper": "projected", "step": 1e-3, "stop_time": 10.0, "output_interval": 1e-3})
    scene = write_scene(tables)
    out = tmp_path / "out.csv"
    assert run_cli(["run", scene, "--states", "--out", out, "--stop-time", "0.01"], capsys)[0] == 0
    tracemalloc.start()
    status, lines, _ = run_cli(["run", scene, "--states", "--out", out], capsys)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    check(status, lines, tmp_path)
    assert status == 0
    table = 10_001 * 204 * 8
    assert peak < table / 8, peak  # chunks of doubles (and their text), never the whole table
    with open(out) as fh:
        assert sum(1 for _ in fh) == 10_002


def test_head_closing_the_pipe_is_silent():
    scene = os.path.join(ROOT, "scenes", "paper-section-8.toml")
    shell = f"{sys.executable} -m prandtl_fmu run {scene} --stop-time 100 | head -1"
    run = subprocess.run(["bash", "-c", shell], capture_output=True, text=True, cwd=ROOT)
    assert run.stdout == "time,x,v,reaction\n"
    assert run.stderr == ""


@pytest.mark.parametrize("seed", range(40))
def test_fuzzed_scenes(seed, tmp_path, capsys):
    """Random mutations of a valid scene (values replaced by hostile ones, keys dropped or renamed, bytes
    cut): 0 or 2, one line at most, never a traceback. The solver stays short so that every case ends."""
    rng = np.random.default_rng(seed)
    tables = base_tables(solver={"stepper": str(rng.choice(["projected", "implicit", "symplectic", "verlet"])),
                                 "step": 1e-2, "stop_time": 1.0, "output_interval": 0.5})
    hostile = [float("nan"), float("inf"), -1.0, 0.0, 1e308, -1e308, 5e-324, "text", True, [], [1.0, "x"], 10**30]
    for _ in range(int(rng.integers(1, 4))):
        table = str(rng.choice([t for t in tables if t not in ("name", "solver")]))
        if rng.random() < 0.2:
            del tables[table]
            continue
        keys = list(tables[table])
        if not keys:
            continue
        key = str(rng.choice(keys))
        choice = rng.random()
        if choice < 0.6:
            tables[table][key] = hostile[int(rng.integers(len(hostile)))]
        elif choice < 0.8:
            tables[table][key + "_typo"] = tables[table].pop(key)
        else:
            del tables[table][key]
    text = scene_text(tables)
    if rng.random() < 0.3:  # cut the file somewhere
        text = text[:int(rng.integers(len(text)))]
    scene = tmp_path / "fuzz.toml"
    scene.write_text(text)
    status, lines, _ = run_cli(["run", scene, "--out", tmp_path / "out.csv"], capsys)
    check(status, lines, tmp_path)


@pytest.mark.parametrize("name", ["../escaped", "", "/abs/path", "con:\x00"])
def test_build_fmu_with_hostile_names(name, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text(base_tables(name=name)))
    run = subprocess.run([sys.executable, os.path.join(ROOT, "build_fmu.py"), str(scene)], capture_output=True,
                         text=True, cwd=tmp_path)
    lines = [line for line in run.stderr.splitlines() if line.strip()]
    assert run.returncode in (0, 2) and len(lines) <= 1 and "Traceback" not in run.stderr, run.stderr
    if run.returncode == 0:
        built = [p for p in tmp_path.iterdir() if p.suffix == ".fmu"]
        assert len(built) == 1 and built[0].parent == tmp_path


@pytest.mark.parametrize("argv, words", [(["{tmp}/missing.toml"], "cannot read"),
                                         (["{scene}", "-o", "{tmp}"], "is a directory"),
                                         (["{scene}", "-o", "{tmp}/no/such/x.fmu"], "does not exist")])
def test_build_fmu_refuses_in_one_line(argv, words, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text(base_tables()))
    argv = [a.replace("{tmp}", str(tmp_path)).replace("{scene}", str(scene)) for a in argv]
    run = subprocess.run([sys.executable, os.path.join(ROOT, "build_fmu.py")] + argv, capture_output=True,
                         text=True, cwd=tmp_path)
    assert run.returncode == 2 and words in run.stderr and len(run.stderr.splitlines()) == 1, run.stderr


# ------------------------------------------------------------------ issue 23, item 13: what still got through


def _loop_csv(path, rows=400, bom=False):
    """A force-displacement loop of a two-branch connector, as a spreadsheet might save it."""
    from prandtl_fmu import parse_scene
    from prandtl_fmu.connector import displacement_response

    t = np.linspace(0.0, 20.0, rows)
    x = (0.1 + 0.03 * t) * np.sin(0.9 * t)
    scene = parse_scene(scene_text({"spring": {"k0": 0.2}, "branches": {"k": [1.0, 0.5], "eta": [0.1, 0.4]},
                                    "fmu": {"causality": "displacement"},
                                    "solver": {"step": 0.01, "stop_time": 1.0, "output_interval": 0.01}}))
    force = displacement_response(scene, x)
    text = "t,x,force\n" + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in zip(t.tolist(), x.tolist(), force.tolist()))
    path.write_bytes(("\ufeff" if bom else "").encode() + text.encode())
    return path


@pytest.mark.parametrize("command", ["run", "fit"])
def test_an_unknown_image_format_is_one_line_before_any_work(write_scene, tmp_path, capsys, command):
    pytest.importorskip("matplotlib")
    pytest.importorskip("scipy")
    source = write_scene(base_tables()) if command == "run" else _loop_csv(tmp_path / "loop.csv")
    status, lines, _ = run_cli([command, source, "--plot", tmp_path / "x.xyz", "--out", tmp_path / "out"], capsys)
    check(status, lines, tmp_path)
    assert status == 2 and "unknown image format 'xyz'" in lines[0] and ".png" in lines[0], lines
    assert not (tmp_path / "out").exists() and not (tmp_path / "x.xyz").exists()


@pytest.mark.parametrize("option", ["--out", "--fmu"])
def test_a_file_name_longer_than_the_folder_allows_is_one_line(tmp_path, capsys, option):
    pytest.importorskip("scipy")
    data = _loop_csv(tmp_path / "loop.csv")
    status, lines, _ = run_cli(["fit", data, option, tmp_path / ("f" * 300 + ".toml")], capsys)
    check(status, lines, tmp_path)
    assert status == 2 and "longer than" in lines[0], lines


def test_a_reader_that_closed_the_pipe_gets_no_traceback(tmp_path):
    """`prandtl-fmu scenes | head -1`: the reader is gone before the program writes (a pipe whose reading end is
    closed): exit 0, nothing on stderr."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "scenes"], stdout=write_end,
                              stderr=subprocess.PIPE, text=True, timeout=120)
    finally:
        os.close(write_end)
    assert done.returncode == 0 and done.stderr == "", done.stderr


def test_a_sweep_grid_too_large_for_memory_is_one_line(write_scene, tmp_path, capsys):
    pytest.importorskip("distributed")
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('[grid]\n"spring.k0" = { from = 0.1, to = 1.0, count = 1000000000000 }\n')
    status, lines, _ = run_cli(["sweep", write_scene(base_tables()), sweep, "--out", tmp_path / "out"], capsys)
    check(status, lines, tmp_path)
    assert status == 2 and "memory" in lines[0] and "spring.k0" in lines[0], lines
    assert not (tmp_path / "out").exists()


def test_a_fit_basis_too_large_for_memory_is_one_line_before_any_work(tmp_path, capsys):
    pytest.importorskip("scipy")
    status, lines, _ = run_cli(["fit", _loop_csv(tmp_path / "loop.csv"), "--branches", 10**9], capsys)
    check(status, lines, tmp_path)
    assert status == 2 and "memory" in lines[0] and "--branches" in lines[0], lines


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_reading_a_large_csv_takes_the_memory_of_its_numbers_only(tmp_path):
    """fit's reader peaked at 31 times the file (a list of every row's strings); the named columns alone, as
    doubles, are 16 bytes a row here."""
    import tracemalloc

    from prandtl_fmu.identify import read_columns

    rows = 200_000
    data = tmp_path / "big.csv"
    with open(data, "w") as fh:
        fh.write("t,x,force,a,b\n")
        for i in range(rows):
            fh.write(f"{i * 0.001!r},{float(np.sin(i * 0.01))!r},{float(np.cos(i * 0.01))!r},123456.789,987654.321\n")
    tracemalloc.start()
    try:
        columns = read_columns(str(data), None, "x", "force", None)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert columns["x"].shape == (rows,) and columns["x"][1] == np.sin(0.01)
    assert peak < 64 * rows, f"{peak / rows:.0f} bytes a row"


def test_a_csv_with_a_byte_order_mark_is_read(tmp_path):
    from prandtl_fmu.identify import read_columns

    plain = read_columns(str(_loop_csv(tmp_path / "plain.csv")), "t", "x", "force", None)
    marked = read_columns(str(_loop_csv(tmp_path / "marked.csv", bom=True)), "t", "x", "force", None)
    for role in ("time", "x", "force"):
        assert np.array_equal(plain[role], marked[role])


def test_a_plot_to_a_full_device_fails_in_one_line(write_scene, capsys):
    pytest.importorskip("matplotlib")
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    status, lines, _ = run_cli(["run", write_scene(base_tables()), "--plot", "/dev/full"], capsys)
    check(status, lines)
    assert status == 2 and "/dev/full" in lines[0], lines


def test_the_branch_memory_check_bounds_the_real_peak():
    """The scene's check of [branches] count uses BYTES_PER_BRANCH: the measured peak of a run, an Element and
    its saved state stays below it (2.5e7 branches passed the old figure, 96, and then failed)."""
    import tracemalloc

    from prandtl_fmu import Element, parse_scene, simulate
    from prandtl_fmu.scene import BYTES_PER_BRANCH

    def tables(count):
        return base_tables(cubic=None, branches={"count": count, "k_total": 1.0, "eta_range": [0.1, 1.1]},
                           solver={"stepper": "projected", "step": 1e-2, "stop_time": 0.05, "output_interval": 0.05})

    n = 200_000
    warm = parse_scene(scene_text(tables(100)), "warm.toml")  # compiled before the measure
    simulate(warm)
    Element(warm).advance(0.05, 0.3)
    text = scene_text(tables(n))
    tracemalloc.start()
    try:
        scene = parse_scene(text, "many.toml")
        simulate(scene)
        element = Element(scene)
        element.advance(0.05, 0.3)
        element.get_state()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < BYTES_PER_BRANCH * n, f"{peak / n:.0f} bytes a branch"


def test_an_overflow_of_a_massless_element_with_a_spring_is_not_called_a_collapse(write_scene, capsys):
    tables = base_tables(mass=None, damper=None, cubic=None, load={"kind": "constant", "value": 1e308},
                         solver={"stepper": "implicit", "step": 1e-2, "stop_time": 1.0, "output_interval": 0.5})
    status, lines, _ = run_cli(["run", write_scene(tables)], capsys)
    check(status, lines)
    assert status == 2 and "collapse" not in lines[0] and "hardening" not in lines[0], lines


def test_a_duration_of_more_than_2_to_the_53_steps_is_refused_in_words():
    from prandtl_fmu import Element, parse_scene

    element = Element(parse_scene(scene_text(base_tables()), "scene.toml"))
    with pytest.raises(ValueError, match="2\\^53"):
        element.advance(1e300, 0.5)
    assert element.time == 0.0 and element.x == 0.0


@pytest.mark.parametrize("command", ["run", "fit", "describe"])
def test_two_outputs_in_one_file_or_an_output_over_the_input_are_one_line(write_scene, tmp_path, capsys, command):
    """--out and --plot naming one file left only the plot (exit 0, the CSV lost), and --out naming the scene
    (or the fit's data) wrote over it: both refused in one line before any work, the input untouched (a
    review's find)."""
    pytest.importorskip("matplotlib")
    pytest.importorskip("scipy")
    source = _loop_csv(tmp_path / "loop.csv") if command == "fit" else write_scene(base_tables())
    before = open(source, "rb").read()
    extra = ["--force-amplitude", "0.5", "--frequencies", "0.1,0.2"] if command == "describe" else []
    same = tmp_path / "same.png"
    status, lines, _ = run_cli([command, source, "--out", same, "--plot", same] + extra, capsys)
    check(status, lines, tmp_path)
    assert status == 2 and "--plot" in lines[0] and "the same file as --out" in lines[0], lines
    assert not same.exists()
    status, lines, _ = run_cli([command, source, "--out", source] + extra, capsys)
    check(status, lines, tmp_path)
    assert status == 2 and "it would be written over" in lines[0], lines
    assert open(source, "rb").read() == before


@pytest.mark.parametrize("command", ["run", "describe"])
def test_an_output_over_a_packaged_scene_named_by_its_name_is_one_line(tmp_path, capsys, command):
    """A packaged scene named by its name (``masing-bilinear``) is read from the package: --out naming that file
    wrote the CSV over it (a review's find, where the package is writable); refused, the scene untouched."""
    from prandtl_fmu.catalog import scene_path

    packaged = scene_path("masing-bilinear")
    before = open(packaged, "rb").read()
    extra = ["--force-amplitude", "0.5", "--frequencies", "0.1,0.2"] if command == "describe" else []
    status, lines, _ = run_cli([command, "masing-bilinear", "--out", packaged] + extra, capsys)
    check(status, lines, tmp_path)
    assert status == 2 and "it would be written over" in lines[0], lines
    assert open(packaged, "rb").read() == before
