"""The light install: a wheel of the project in a fresh virtual environment, with the core dependencies and
fmpy only (no scipy, no matplotlib), builds an FMU of a packaged scene and runs it, and the library agrees."""
import os
import subprocess
import sys
import textwrap

import pytest

from tests.conftest import ROOT

CHECK = textwrap.dedent("""\
    import importlib.util, os, sys
    extras = [m for m in ("scipy", "matplotlib", "pytest", "hypothesis", "libcosimpy") if importlib.util.find_spec(m)]
    assert extras == [], f"not a core install: {extras}"
    import prandtl_fmu
    assert "site-packages" in prandtl_fmu.__file__, prandtl_fmu.__file__  # the installed wheel, not the checkout
    from fmpy import simulate_fmu
    from prandtl_fmu import Element, load_scene
    result = simulate_fmu(sys.argv[1], stop_time=3.0, output_interval=0.5, start_values={"F": 0.3, "scene_load": False})
    element = Element(load_scene("paper-section-8"))
    for _ in range(6):
        element.advance(0.5, 0.3)
    print(repr(float(result["x"][-1])), repr(element.x), flush=True)
""")


def _run(command, **kwargs):
    done = subprocess.run(command, capture_output=True, text=True, timeout=900, **kwargs)
    assert done.returncode == 0, f"{' '.join(map(str, command))}\n{done.stdout[-2000:]}\n{done.stderr[-3000:]}"
    return done


@pytest.mark.slow
def test_a_wheel_in_a_fresh_venv_with_core_dependencies_and_fmpy_builds_and_runs_an_fmu(tmp_path):
    _run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", str(ROOT), "-w", str(tmp_path / "dist")])
    wheel, = (tmp_path / "dist").glob("prandtl_fmu-*.whl")
    _run([sys.executable, "-m", "venv", str(tmp_path / "venv")])
    bin_ = tmp_path / "venv" / "bin"
    # no PYTHONPATH: a checkout on it holds the egg-info that `pip wheel` wrote, and pip would then take the
    # package for installed and skip it (no prandtl-fmu script in the venv)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    _run([str(bin_ / "python"), "-m", "pip", "install", "--quiet", f"{wheel}", "fmpy"], env=env)
    work = tmp_path / "work"  # not the checkout: nothing of it on the path
    work.mkdir()
    version = _run([str(bin_ / "prandtl-fmu"), "--version"], cwd=work, env=env).stdout
    assert version.startswith("prandtl-fmu ")
    built = _run([str(bin_ / "prandtl-fmu"), "build", "paper-section-8", "-o", "element.fmu"], cwd=work, env=env)
    assert built.stdout.strip() == "element.fmu"
    fmu_x, library_x = map(float, _run([str(bin_ / "python"), "-c", CHECK, "element.fmu"], cwd=work,
                                       env=env).stdout.split())
    assert fmu_x == library_x != 0.0
    # an extra that is missing is one line, exit 2, and nothing written
    plot = subprocess.run([str(bin_ / "prandtl-fmu"), "run", "paper-section-8", "--stop-time", "1", "--out",
                           "run.csv", "--plot", "run.png"], capture_output=True, text=True, cwd=work, env=env)
    assert plot.returncode == 2 and plot.stderr.count("\n") == 1 and "prandtl_fmu[plot]" in plot.stderr
    assert not (work / "run.csv").exists()
