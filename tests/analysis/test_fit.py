"""Identification: a measured loop becomes a scene (prandtl-fmu fit)."""
import subprocess
import sys

import numpy as np
import pytest

from prandtl_fmu import load_scene, parse_scene
from prandtl_fmu.connector import displacement_response
from prandtl_fmu.identify import FitError, fit

from tests.conftest import scene_text

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


@pytest.mark.parametrize("seed", range(6))
def test_a_noise_free_loop_of_a_discrete_element_is_recovered_with_its_true_branches_off_the_grid(seed):
    """Issue 23, item 14: with the ranges fixed on its grid the fit kept 14 branches for a 5-branch element
    whose ranges are not on the grid, with a force error of 3e-4 of the range. The ranges are now moved (variable
    projection from the NNLS solution): the true number of branches, the force to 1e-8 of its range, the ranges
    and stiffnesses to 1e-6."""
    rng = np.random.default_rng(100 + seed)
    n = 5
    k = rng.uniform(0.3, 1.5, n)
    eta = np.sort(rng.uniform(0.03, 0.6, n))
    t, x = history(rng)
    force = displacement_response(connector(k, eta, 0.2), x)
    result = fit(x, force, time=t)
    assert len(result.k) == n, (result.eta, eta)
    assert result.relative_max <= 1e-8
    np.testing.assert_allclose(result.eta, eta, rtol=1e-6)
    np.testing.assert_allclose(result.k, k, rtol=1e-6)
    assert abs(result.k0 - 0.2) <= 1e-6


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


@pytest.mark.slow
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


@pytest.mark.slow
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


@pytest.mark.slow
@pytest.mark.parametrize("options", [[], ["--continuum", "iwan"]])
def test_the_example_goes_from_a_csv_to_a_scene_an_fmu_and_a_plot(tmp_path, options):
    from tests.conftest import ROOT

    run = subprocess.run([sys.executable, str(ROOT / "examples" / "fit_loop.py"), "--out", str(tmp_path), *options],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    for name in ("measured.csv", "fitted.toml", "fitted.fmu", "fit.png"):
        assert (tmp_path / name).stat().st_size > 0
    relative_rms = float(run.stderr.split("residual RMS")[1].split("(")[1].split("%")[0])
    assert 0.8 < relative_rms < 1.2  # the stand-in's 1 % noise, not more


# ------------------------------------------------ the continuous families (--continuum MODEL)

def continuum_connector(branches, k0):
    tables = {"spring": {"k0": float(k0)}, "branches": branches, "fmu": {"causality": "displacement"},
              "solver": SOLVER}
    return parse_scene(scene_text(tables))


@pytest.mark.parametrize("seed", range(3))
def test_an_iwan_fit_recovers_segalmans_four_parameters(seed):
    rng = np.random.default_rng(100 + seed)
    truth = {"kind": "iwan", "F_S": float(rng.uniform(0.5, 3.0)), "K_T": float(rng.uniform(5.0, 50.0)),
             "chi": float(rng.uniform(-0.9, -0.1)), "beta": float(rng.choice([0.0, rng.uniform(0.1, 2.0)]))}
    k0 = float(rng.uniform(0.1, 2.0))
    scene = continuum_connector({"continuum": True, "density": truth}, k0)
    phi_max = scene.branches.eta[-1]
    t, x = history(rng)
    x = 1.2 * phi_max * x / np.abs(x).max()  # micro-slip and a little macro-slip
    force = displacement_response(scene, x)
    result = fit_continuum_checked(x, force, "iwan")
    assert result.residual_max <= 1e-8 * np.ptp(force)
    fitted = result.density["density"]
    for key in ("F_S", "K_T", "chi", "beta"):
        assert fitted[key] == pytest.approx(truth[key], rel=1e-6, abs=1e-6), key
    assert result.k0 == pytest.approx(k0, rel=1e-6)
    assert not result.notes


def fit_continuum_checked(x, force, model, **options):
    """fit_continuum, and the scene it writes reproduces the fitted force (the contract's keys, reparsed)."""
    from prandtl_fmu.identify import fit_continuum

    result = fit_continuum(x, force, model, **options)
    scene = parse_scene(result.scene_text("fit"))
    assert scene.branches.continuum
    np.testing.assert_allclose(displacement_response(scene, x), result.fitted, rtol=0, atol=1e-9 * np.ptp(force))
    residual = force - result.fitted
    assert result.residual_rms == pytest.approx(np.sqrt(np.mean(residual ** 2)), rel=1e-12, abs=1e-300)
    assert result.residual_max == pytest.approx(np.abs(residual).max(), rel=1e-12, abs=1e-300)
    return result


def test_a_linear_continuum_fit_recovers_the_papers_spectrum():
    rng = np.random.default_rng(7)
    scene = continuum_connector({"continuum": True, "k_total": 1.7, "eta_range": [0.05, 0.6]}, 0.4)
    t, x = history(rng)
    force = displacement_response(scene, x)
    result = fit_continuum_checked(x, force, "linear")
    assert result.residual_max <= 1e-8 * np.ptp(force)
    assert result.density["k_total"] == pytest.approx(1.7, rel=1e-6)
    np.testing.assert_allclose(result.density["eta_range"], [0.05, 0.6], rtol=1e-6)
    assert result.k0 == pytest.approx(0.4, rel=1e-6)


def test_a_piecewise_fit_on_a_grid_holding_the_true_nodes_recovers_the_density():
    rng = np.random.default_rng(8)
    nodes = np.geomspace(0.02, 1.0, 12)
    truth = rng.uniform(0.2, 2.0, 11) * (rng.uniform(size=11) > 0.3)  # total stiffness per segment, some empty
    truth[0] = truth[-1] = 1.0
    density = {"kind": "piecewise", "k": (11 * truth).tolist(), "eta": nodes.tolist()}
    scene = continuum_connector({"continuum": True, "density": density}, 0.3)
    t, x = history(rng)
    force = displacement_response(scene, x)
    grid = np.unique(np.concatenate([nodes, np.geomspace(0.01, 2.0, 15)]))
    result = fit_continuum_checked(x, force, "piecewise", etas=grid)
    assert result.residual_max <= 1e-8 * np.ptp(force)
    fitted = result.density["density"]
    fitted_nodes = np.array(fitted["eta"])
    stiffness = np.array(fitted["k"]) / len(fitted["k"])  # total stiffness per fitted segment
    # the true segment j spreads over the grid's segments inside it, in proportion to their width
    for j in range(11):
        inside = (fitted_nodes[:-1] >= nodes[j] * (1 - 1e-12)) & (fitted_nodes[1:] <= nodes[j + 1] * (1 + 1e-12))
        assert np.sum(stiffness[inside]) == pytest.approx(truth[j], rel=1e-6, abs=1e-9), j
    assert result.k0 == pytest.approx(0.3, rel=1e-6)


def test_a_loop_without_macro_slip_says_what_it_cannot_determine():
    """Below phi_max the force is (k0 + K_T) x - R x^(chi+2) / ((chi+1)(chi+2)) on the virgin curve: F_S, beta
    and the split of k0 and K_T are not in the data. The fit is exact, and says so."""
    rng = np.random.default_rng(4)
    scene = continuum_connector({"continuum": True, "density": {"kind": "iwan", "F_S": 1.0, "K_T": 30.0,
                                                                "chi": -0.6, "beta": 0.2}}, 1.0)
    t, x = history(rng, count=800)
    x = 0.7 * scene.branches.eta[-1] * x / np.abs(x).max()
    force = displacement_response(scene, x)
    result = fit_continuum_checked(x, force, "iwan")
    assert result.residual_max <= 1e-8 * np.ptp(force)
    assert result.density["density"]["chi"] == pytest.approx(-0.6, rel=1e-6)  # chi is in the data
    assert result.k0 + result.density["density"]["K_T"] == pytest.approx(31.0, rel=1e-6)
    assert len(result.notes) == 1 and "never reaches macro-slip" in result.report()


def test_an_iwan_fit_with_one_percent_noise_has_the_noise_as_residual():
    rng = np.random.default_rng(21)
    truth = {"kind": "iwan", "F_S": 1.0, "K_T": 20.0, "chi": -0.4, "beta": 0.5}
    scene = continuum_connector({"continuum": True, "density": truth}, 0.5)
    t, x = history(rng)
    x = 0.1 * x / np.abs(x).max()
    clean = displacement_response(scene, x)
    noise = 0.01 * np.ptp(clean) * rng.standard_normal(len(clean))
    result = fit_continuum_checked(x, clean + noise, "iwan")
    level = np.sqrt(np.mean(noise ** 2))
    assert 0.95 * level < result.residual_rms < 1.02 * level
    assert np.sqrt(np.mean((result.fitted - clean) ** 2)) < 0.2 * level


@pytest.mark.parametrize("model", ["piecewise", "iwan", "linear"])
def test_a_bouc_wen_loop_fitted_by_each_continuum_reports_its_residual_honestly(model):
    t, x, force = bouc_wen_loop()
    result = fit_continuum_checked(x, force, model, time=t)
    limit = {"piecewise": 0.02, "iwan": 0.05, "linear": 0.1}[model]
    assert result.relative_rms < limit, result.report()
    assert f"{100 * result.relative_rms:.3g} %" in result.report()


@pytest.mark.slow
def test_the_command_fits_an_iwan_continuum_and_builds_its_fmu(tmp_path):
    from fmpy import simulate_fmu

    rng = np.random.default_rng(4)
    scene = continuum_connector({"continuum": True, "density": {"kind": "iwan", "F_S": 1.0, "K_T": 30.0,
                                                                "chi": -0.6, "beta": 0.2}}, 1.0)
    t, x = history(rng, count=800)
    phi_max = scene.branches.eta[-1]
    x = 1.3 * phi_max * x / np.abs(x).max()
    force = displacement_response(scene, x)
    data = tmp_path / "loop.csv"
    np.savetxt(data, np.column_stack([t, x, force]), delimiter=",", header="t,x,force", comments="")
    run = _cli(data, "--time", "t", "--continuum", "iwan", "--out", tmp_path / "fit.toml", "--fmu",
               tmp_path / "fit.fmu")
    assert run.returncode == 0, run.stderr
    assert "Iwan F_S = 1 N" in run.stderr and "residual RMS" in run.stderr
    fitted_scene = load_scene(tmp_path / "fit.toml")
    assert fitted_scene.branches.continuum and "Segalman" in fitted_scene.branches.description
    signal = np.zeros(len(t), dtype=[("time", float), ("x", float), ("v", float)])
    signal["time"], signal["x"] = t, x
    out = simulate_fmu(str(tmp_path / "fit.fmu"), stop_time=t[-1], output_interval=t[1] - t[0], input=signal,
                       output=["force"])
    rows = min(len(out) - 1, len(t) - 1)
    np.testing.assert_allclose(out["force"][1:rows + 1], force[:rows], rtol=0, atol=1e-7 * np.ptp(force))


@pytest.mark.parametrize("options, culprit", [
    (["--continuum", "spline"], "invalid choice: 'spline'"),
    (["--continuum", "iwan", "--branches", "5"], "not allowed with argument"),
])
def test_bad_continuum_options_are_one_line_and_exit_2(tmp_path, options, culprit):
    data = tmp_path / "loop.csv"
    data.write_text("x,force\n" + "".join(f"{np.sin(i / 3)},{np.sin(i / 3)}\n" for i in range(30)))
    run = _cli(data, *options)
    assert run.returncode == 2 and culprit in run.stderr and len(run.stderr.strip().splitlines()) == 1, run.stderr
