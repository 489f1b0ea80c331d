"""What the command line leaves on disk when it is stopped, and with which mode (issue 23, items 8 and 9).

The program is run as a user runs it (a child process, ``python -m prandtl_fmu``) and stopped by a signal:
SIGTERM and SIGHUP leave no hidden ``.prandtl-*.part`` file and print one line, as SIGINT did; a Ctrl-C while
the modules load is one line and exit 130, not an import's traceback. Every output follows the umask, as any
tool's does (mkstemp's 0600 made an FMU unreadable to a master running as another user)."""
import os
import signal
import stat
import subprocess
import sys
import time

import pytest

from tests.conftest import ROOT, base_tables, scene_text

# a run of minutes whose CSV (5e6 rows, about 0.5 GB) fits any disk: the run refuses a CSV larger than the free disk,
# and one row per step (5e8 rows, 48 GB) failed these tests on a disk with less free
LONG = base_tables(solver={"stepper": "projected", "step": 1e-4, "stop_time": 5e4, "output_interval": 1e-2})


def _start(args, folder):
    return subprocess.Popen([sys.executable, "-m", "prandtl_fmu", *map(str, args)], cwd=folder,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _partial_files(folder):
    return [p.name for p in folder.iterdir() if p.name.startswith(".prandtl-") or p.suffix == ".part"]


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_a_signal_during_a_run_leaves_no_partial_file_and_one_line(tmp_path, signum):
    scene = tmp_path / "long.toml"
    scene.write_text(scene_text(LONG))
    out = tmp_path / "long.csv"
    run = _start(["run", scene, "--out", out], tmp_path)
    deadline = time.monotonic() + 240
    while not _partial_files(tmp_path) and time.monotonic() < deadline and run.poll() is None:
        time.sleep(0.05)
    assert _partial_files(tmp_path), "the run never started writing"
    time.sleep(0.3)  # rows are being written
    run.send_signal(signum)
    _, err = run.communicate(timeout=60)
    lines = [line for line in err.splitlines() if line.strip()]
    assert run.returncode == 128 + signum, err
    assert len(lines) == 1 and lines[0].startswith("error: ") and "no output written" in lines[0], err
    assert _partial_files(tmp_path) == [] and not out.exists()


def _wait_until_the_command_catches_signals(run, timeout=60.0):
    """Until the process catches SIGTERM (the command line's first lines install its handlers; the interpreter's
    own start-up, the site module included, is before them and not the package's to answer): Linux's
    /proc/PID/status SigCgt mask. Elsewhere, a second (the interpreter's start on a quiet machine)."""
    status = f"/proc/{run.pid}/status"
    if not os.path.exists(status):
        time.sleep(1.0)
        return
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and run.poll() is None:
        try:
            with open(status) as file:
                caught = next(int(line.split()[1], 16) for line in file if line.startswith("SigCgt:"))
        except (OSError, StopIteration):
            caught = 0
        if caught >> (signal.SIGTERM - 1) & 1:
            return
        time.sleep(0.002)
    raise AssertionError("the command never caught SIGTERM")


@pytest.mark.parametrize("delay", [0.0, 0.15, 0.4])
def test_ctrl_c_while_the_modules_load_is_one_line_and_exit_130(tmp_path, delay):
    """Ctrl-C ``delay`` seconds after the command line's handlers are in place, while numpy and numba load."""
    scene = tmp_path / "long.toml"
    scene.write_text(scene_text(LONG))
    run = _start(["run", scene, "--out", tmp_path / "long.csv"], tmp_path)
    _wait_until_the_command_catches_signals(run)
    time.sleep(delay)
    run.send_signal(signal.SIGINT)
    _, err = run.communicate(timeout=60)
    lines = [line for line in err.splitlines() if line.strip()]
    assert run.returncode == 130, err
    # the one line of an interrupt while loading, or (the modules loaded within the delay: a warm cache on a
    # quick machine) of an interrupted run
    assert lines in (["error: interrupted"], ["error: interrupted; no output written"]), err
    assert _partial_files(tmp_path) == []


def _mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_every_output_follows_the_umask_and_an_existing_file_keeps_its_mode(tmp_path, umask):
    """CSV, figure, FMU and the OSP sidecar: 0666 less the umask (what open() gives), never mkstemp's 0600; a file
    that is replaced keeps its mode."""
    pytest.importorskip("matplotlib")
    scene = tmp_path / "small.toml"
    scene.write_text(scene_text(base_tables(name="small", solver={"stepper": "implicit", "step": 1e-2,
                                                                  "stop_time": 1.0, "output_interval": 0.5})))
    expected = 0o666 & ~umask
    kept = tmp_path / "kept.csv"
    kept.write_text("old\n")
    os.chmod(kept, 0o640)
    code = (f"import os, sys; os.umask({umask}); from prandtl_fmu.cli import main; "
            "status = [main(args) for args in ("
            "['run', sys.argv[1], '--out', 'run.csv', '--plot', 'run.png'], "
            "['run', sys.argv[1], '--out', 'kept.csv'], "
            "['build', sys.argv[1], '-o', 'small.fmu', '--osp'])]; sys.exit(max(status))")
    done = subprocess.run([sys.executable, "-c", code, str(scene)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert done.returncode == 0, done.stderr
    for name in ("run.csv", "run.png", "small.fmu", "small_OspModelDescription.xml"):
        assert _mode(tmp_path / name) == expected, (name, oct(_mode(tmp_path / name)))
    assert _mode(kept) == 0o640 and kept.read_text().startswith("time,")
