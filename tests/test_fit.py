"""Identification: a measured loop becomes a scene (prandtl-fmu fit)."""
import subprocess
import sys

import numpy as np
import pytest

from prandtl_fmu import load_scene, parse_scene
from prandtl_fmu.connector import displacement_response
from prandtl_fmu.identify import FitError, fit

from .conftest import scene_text

SOLVER = {"step": 0.01, "stop_time": 1.0, "output_interval": 0.01}


def history(rng, count=2500):
    """A displacement history from x = 0 with a virgin branch, growing and shrinking cycles."""
    t = np.linspace(0.0, 40.0, count)
    x = (0.15 + 0.04 * t) * np.sin(0.8 * t) + 0.3 * np.sin(2.1 * t + rng.uniform(0, 1)) * np.sin(0.1 * t)
    return t, x


def connector(k, eta, k0):
    tables = {"spring": {"k0": float(k0)}, "branches": {"k": [float(v) for v in k], "eta": [float(v) for v in eta]},
              "fmu": {"causality": "displacement"}, "solver": SOLVER}
    return parse_scene(scene_text(tables))


@pytest.mark.parametrize("seed", range(6))
def test_a_fit_on_a_grid_holding_the_true_ranges_recovers_the_element(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 9))
    k = rng.uniform(0.1, 3.0, n)
    eta = np.sort(rng.choice(np.geomspace(0.02, 1.2, 60), n, replace=False))
    k0 = rng.uniform(0.05, 1.0)
    t, x = history(rng)
    force = displacement_response(connector(k, eta, k0), x)
    grid = np.unique(np.concatenate([np.geomspace(0.01, 2.0, 40), eta]))
    result = fit(x, force, etas=grid)
    assert result.residual_max <= 1e-8 * np.ptp(force)
    assert len(result.k) == n
    np.testing.assert_allclose(result.eta, eta, rtol=1e-12)
    np.testing.assert_allclose(result.k, k, rtol=1e-6)
    assert result.k0 == pytest.approx(k0, rel=1e-6)


def test_with_one_percent_noise_the_residual_is_the_noise():
    rng = np.random.default_rng(42)
    k, eta, k0 = rng.uniform(0.2, 2, 5), np.sort(rng.uniform(0.05, 0.9, 5)), 0.3
    t, x = history(rng)
    clean = displacement_response(connector(k, eta, k0), x)
    noise = 0.01 * np.ptp(clean) * rng.standard_normal(len(clean))
    result = fit(x, clean + noise)
    level = np.sqrt(np.mean(noise ** 2))
    assert 0.9 * level < result.residual_rms < 1.05 * level
    assert np.sqrt(np.mean((result.fitted - clean) ** 2)) < 0.35 * level  # closer to the truth than the data


def test_the_default_grid_fits_an_unseen_spectrum_closely():
    rng = np.random.default_rng(5)
    k, eta = rng.uniform(0.2, 2, 7), rng.uniform(0.03, 1.0, 7)
    t, x = history(rng)
    force = displacement_response(connector(k, eta, 0.2), x)
    result = fit(x, force)
    assert result.relative_rms < 2e-3 and result.relative_max < 2e-2


def bouc_wen_loop():
    """A loop of another model: Bouc-Wen, z' = A x' - beta |x'| |z|^(n-1) z - gamma x' |z|^n, F = a k x + (1-a) k z,
    integrated by scipy under x(t) = X sin(t) growing."""
    from scipy.integrate import solve_ivp

    t = np.linspace(0, 30, 3000)

    def motion(s):
        return (0.2 + 0.03 * s) * np.sin(s), 0.03 * np.sin(s) + (0.2 + 0.03 * s) * np.cos(s)

    def rate(s, z):
        _, xdot = motion(s)
        return [xdot - 0.5 * abs(xdot) * abs(z[0]) * z[0] - 0.5 * xdot * z[0] ** 2]

    z = solve_ivp(rate, (0, 30), [0.0], t_eval=t, rtol=1e-10, atol=1e-12).y[0]
    x, _ = motion(t)
    return t, x, 0.1 * x + 0.9 * z


def test_a_loop_of_another_model_is_fitted_honestly_and_the_fitted_scene_reproduces_the_fit(tmp_path):
    from fmpy import simulate_fmu

    from prandtl_fmu.fmu.build import build_fmu

    t, x, force = bouc_wen_loop()
    result = fit(x, force, time=t)
    residual = force - result.fitted
    assert result.residual_rms == pytest.approx(np.sqrt(np.mean(residual ** 2)))
    assert result.relative_rms < 0.02  # Bouc-Wen is smooth: many small branches approximate it
    scene_path = tmp_path / "bw.toml"
    scene_path.write_text(result.scene_text("bouc-wen-fit", t))
    scene = load_scene(scene_path)
    np.testing.assert_allclose(displacement_response(scene, x), result.fitted, rtol=0, atol=1e-9 * np.ptp(force))
    fmu = build_fmu(scene_path, tmp_path / "bw.fmu")
    signal = np.zeros(len(t), dtype=[("time", float), ("x", float), ("v", float)])
    signal["time"], signal["x"] = t, x
    interval = t[1] - t[0]
    run = simulate_fmu(str(fmu), stop_time=t[-1], output_interval=interval, input=signal, output=["force"])
    rows = min(len(run) - 1, len(t) - 1)
    # FMPy interpolates the input at its own communication points (k * interval, as t): row k + 1 shows sample k
    np.testing.assert_allclose(run["force"][1:rows + 1], result.fitted[:rows], rtol=0, atol=1e-9 * np.ptp(force))


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "prandtl_fmu", "fit", *map(str, args)], capture_output=True,
                          text=True, cwd=cwd)


def test_the_command_writes_a_scene_an_fmu_and_a_plot(tmp_path):
    rng = np.random.default_rng(9)
    t, x = history(rng, count=800)
    force = displacement_response(connector([1.0, 0.5], [0.1, 0.4], 0.2), x)
    data = tmp_path / "loop.csv"
    np.savetxt(data, np.column_stack([t, x, force]), delimiter=",", header="t,disp,F", comments="")
    run = _cli(data, "--time", "t", "--x", "disp", "--force", "F", "--out", tmp_path / "fit.toml",
               "--fmu", tmp_path / "fit.fmu", "--plot", tmp_path / "fit.png")
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == [str(tmp_path / name) for name in ("fit.toml", "fit.fmu", "fit.png")]
    assert "branches kept" in run.stderr and "residual RMS" in run.stderr
    scene = load_scene(tmp_path / "fit.toml")
    assert scene.causality == "displacement" and scene.mass is None
    fitted = displacement_response(scene, x)
    assert np.abs(fitted - force).max() < 5e-3 * np.ptp(force)


@pytest.mark.parametrize("rows, options, culprit", [
    ("t,x,force\n" + "".join(f"{i},{np.sin(i)},{i}\n" for i in range(20)).replace("3,", "nan,", 1),
     ["--time", "t"], "not a finite number"),
    ("t,x,force\n" + "".join(f"{i % 7},{np.sin(i)},{i}\n" for i in range(20)), ["--time", "t"], "not increasing"),
    ("t,x,force\n" + "".join(f"{i},1.0,{i}\n" for i in range(20)), [], "x is constant"),
    ("t,x,force\n" + "".join(f"{i},{i},{i}\n" for i in range(4)), [], "too few points"),
    ("t,x,F\n" + "".join(f"{i},{i},{i}\n" for i in range(20)), [], "no column 'force'"),
    ("t,x,force\n1,2,abc\n", [], "not a number"),
])
def test_bad_data_is_one_line_and_exit_2_with_nothing_written(tmp_path, rows, options, culprit):
    data = tmp_path / "bad.csv"
    data.write_text(rows)
    run = _cli(data, *options, "--out", tmp_path / "out.toml")
    assert run.returncode == 2
    assert len(run.stderr.strip().splitlines()) == 1 and culprit in run.stderr, run.stderr
    assert "Traceback" not in run.stderr and not (tmp_path / "out.toml").exists()


def test_the_library_refuses_bad_data_naming_it():
    with pytest.raises(FitError, match="x is constant"):
        fit(np.ones(20), np.arange(20.0))
    with pytest.raises(FitError, match="needs the velocity or the time"):
        fit(np.sin(np.arange(20.0)), np.arange(20.0), dashpot=True)


def test_the_example_goes_from_a_csv_to_a_scene_an_fmu_and_a_plot(tmp_path):
    from .conftest import ROOT

    run = subprocess.run([sys.executable, str(ROOT / "examples" / "fit_loop.py"), "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    for name in ("measured.csv", "fitted.toml", "fitted.fmu", "fit.png"):
        assert (tmp_path / name).stat().st_size > 0
    relative_rms = float(run.stderr.split("residual RMS")[1].split("(")[1].split("%")[0])
    assert 0.8 < relative_rms < 1.2  # the stand-in's 1 % noise, not more
