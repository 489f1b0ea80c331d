"""Monte Carlo sweeps (issue 34): the [seeds] range, the intervals and the chi-square test against closed forms
(coverage over many repetitions, exact binomial sums, scipy's own test), the laws normalised by quadrature
against their closed forms, a sweep whose output has a known law, and (slow) the linear oscillator under white
noise: its x(T) histogram over 400 seeds against sigma^2 / (2ck)."""
import math
import subprocess
import sys
import tomllib

import numpy as np
import pytest

from tests.conftest import base_tables, scene_text

scipy_stats = pytest.importorskip("scipy.stats")
pd = pytest.importorskip("pandas")

from prandtl_fmu.cli import main  # noqa: E402
from prandtl_fmu.sweep import SweepError, plan  # noqa: E402
from prandtl_fmu.sweep.report import tables  # noqa: E402
from prandtl_fmu.sweep.runs import run_batch  # noqa: E402
from prandtl_fmu.sweep.spec import parse_spec  # noqa: E402
from prandtl_fmu.sweep.statistics import (Density, chi_square_test, coulomb_dashpot_v, cubic_oscillator_x,  # noqa: E402
                                          histogram, mean_interval, normal, std_interval, wilson_interval)

Z95 = 1.959963984540054
RANDOM = {"kind": "random", "seed": 0, "rms": 0.5, "band": [0.5, 2.0], "components": 1}
WHITE = {"kind": "white_noise", "intensity": 0.5, "seed": 0}


def _binomial_band(p, repetitions, sd=4.0):
    """The coverage of `repetitions` independent intervals of level p lies within sd standard deviations."""
    return sd * math.sqrt(p * (1 - p) / repetitions)


# ------------------------------------------------------------------ the intervals

@pytest.mark.slow
def test_student_and_chi_square_intervals_cover_the_true_mean_and_std_at_their_rate():
    rng = np.random.default_rng(34)
    repetitions, n, mean, std = 4000, 8, 1.5, 0.3  # small n: a normal quantile instead of t would undercover
    samples = rng.normal(mean, std, size=(repetitions, n))
    for confidence in (0.9, 0.95):
        means = np.array([mean_interval(sample, confidence) for sample in samples])
        stds = np.array([std_interval(sample, confidence) for sample in samples])
        covered_mean = np.mean((means[:, 1] <= mean) & (mean <= means[:, 2]))
        covered_std = np.mean((stds[:, 1] <= std) & (std <= stds[:, 2]))
        band = _binomial_band(confidence, repetitions)
        assert abs(covered_mean - confidence) < band, covered_mean
        assert abs(covered_std - confidence) < band, covered_std
        # equal tails: the true value is above and below the interval equally often
        above, below = np.mean(means[:, 2] < mean), np.mean(means[:, 1] > mean)
        assert abs(above - below) < _binomial_band((1 - confidence) / 2, repetitions) * 2
    # the normal's 95 % quantile (1.96) instead of Student's (2.36 at 7 dof) would cover 0.91 only
    naive = np.mean(np.abs(samples.mean(axis=1) - mean) <= Z95 * samples.std(axis=1, ddof=1) / math.sqrt(n))
    assert naive < 0.93


def test_the_intervals_are_their_formulas():
    sample = np.array([0.3, -1.2, 0.8, 2.1, 0.0, 1.1])
    n, m, s = 6, sample.mean(), sample.std(ddof=1)
    _, low, high = mean_interval(sample, 0.95)
    assert high - m == pytest.approx(2.570581835636314 * s / math.sqrt(n), rel=1e-12)  # t_{0.975, 5}
    assert m - low == pytest.approx(high - m, rel=1e-12)
    _, low, high = std_interval(sample, 0.95)
    assert low == pytest.approx(s * math.sqrt(5 / 12.832501994030027), rel=1e-12)  # chi2_{0.975, 5}
    assert high == pytest.approx(s * math.sqrt(5 / 0.8312116134866628), rel=1e-12)  # chi2_{0.025, 5}
    assert all(math.isnan(value) for value in std_interval([1.0], 0.95))


def test_wilson_bounds_solve_the_score_equation_and_cover_the_binomial_at_their_rate():
    n = 40
    k = np.arange(n + 1)
    low, high = wilson_interval(k, n, 0.95)
    # the bounds are the p where the score statistic |k/n - p| / sqrt(p(1-p)/n) equals z
    for bound in (low[1:-1], high[1:-1]):
        score = np.abs(k[1:-1] / n - bound) / np.sqrt(bound * (1 - bound) / n)
        np.testing.assert_allclose(score, Z95, rtol=1e-10)
    assert low[0] == 0 and high[-1] == 1
    assert high[0] == pytest.approx(Z95**2 / (n + Z95**2), rel=1e-12)
    # exact coverage: sum of the binomial probabilities of the k whose interval holds p
    coverage = []
    for p in np.linspace(0.02, 0.98, 97):
        inside = (low <= p) & (p <= high)
        coverage.append(scipy_stats.binom.pmf(k[inside], n, p).sum())
    coverage = np.array(coverage)
    assert abs(coverage.mean() - 0.95) < 0.01   # Wilson: close to nominal on average
    assert coverage.min() > 0.83                 # and never far below (the Wald interval drops under 0.6 here)
    wald = []
    for p in (0.02, 0.05):
        phat = k / n
        half = Z95 * np.sqrt(phat * (1 - phat) / n)
        wald.append(scipy_stats.binom.pmf(k[(phat - half <= p) & (p <= phat + half)], n, p).sum())
    assert min(wald) < 0.6


def test_a_histogram_counts_every_value_and_its_bars_are_wilsons():
    values = np.random.default_rng(3).normal(size=500)
    hist = histogram(values, confidence=0.9)
    assert hist.counts.size == math.ceil(2 * 500 ** (1 / 3)) and hist.counts.sum() == 500
    assert hist.edges[0] == values.min() and hist.edges[-1] == values.max()
    low, high = wilson_interval(hist.counts, 500, 0.9)
    np.testing.assert_array_equal(hist.density_low, low / np.diff(hist.edges))
    assert np.sum(hist.density * np.diff(hist.edges)) == pytest.approx(1.0)
    assert np.all((hist.fraction_low <= hist.fraction) & (hist.fraction <= hist.fraction_high))


# ------------------------------------------------------------------ the chi-square test and the laws

def test_the_chi_square_test_is_scipys_when_no_cell_is_merged():
    values = np.random.default_rng(5).normal(0.2, 1.1, size=2000)
    law = normal(0.0, 1.0)
    edges = np.linspace(-2, 2, 9)
    fit = chi_square_test(values, edges, law)
    observed = np.histogram(values, np.concatenate(([-np.inf], edges, [np.inf])))[0]
    expected = 2000 * np.diff(np.concatenate(([0], scipy_stats.norm.cdf(edges), [1])))
    assert expected.min() > 5 and fit.cells == 10 and fit.dof == 9
    reference = scipy_stats.chisquare(observed, expected)
    assert fit.chi2 == pytest.approx(reference.statistic, rel=1e-12)
    assert fit.p_value == pytest.approx(reference.pvalue, rel=1e-9) and fit.p_value < 1e-6  # the wrong law


def test_cells_expecting_fewer_than_5_are_merged_with_their_neighbours():
    law = Density("uniform", lambda y: np.zeros_like(y), mode=0.5, cdf=lambda y: np.clip(y, 0, 1), support=(0, 1))
    values = np.array([0.05, 0.15, 0.5, 0.55, 0.6, 0.95] * 5)  # 30 values
    fit = chi_square_test(values, np.array([0.1, 0.2, 0.8, 0.9]), law)
    # cells (-inf, .1) .1 / [.1, .2) .1 / [.2, .8) .6 / [.8, .9) .1 / [.9, inf) .1, expected 3, 3, 18, 3, 3:
    # merged from the left into [0, .2) (6 expected, 10 seen), [.2, .8) (18, 15) and [.8, 1] (6, 5)
    assert fit.cells == 3 and fit.dof == 2
    assert fit.chi2 == pytest.approx((10 - 6) ** 2 / 6 + (15 - 18) ** 2 / 18 + (5 - 6) ** 2 / 6, rel=1e-12)
    np.testing.assert_allclose(fit.expected, [0.1, 0.6, 0.1], rtol=1e-12)
    # what is left at the end short of 5 joins the last cell: expected 3, 3, 15, 6, 3 -> 6, 15, 6 + 3
    fit = chi_square_test(values, np.array([0.1, 0.2, 0.7, 0.9]), law)
    assert fit.cells == 3 and fit.chi2 == pytest.approx(16 / 6 + 0 + 16 / 9, rel=1e-12)


@pytest.mark.slow
def test_p_values_are_uniform_under_the_law_and_tiny_under_another():
    rng = np.random.default_rng(8)
    law = coulomb_dashpot_v(sigma=1.0, m=1.0, c=0.5, alpha=0.3)
    # draw from the law by inverting its CDF (quadrature) on a fine grid
    grid = np.linspace(-8, 8, 4001)
    cdf = np.cumsum(law.probabilities(grid))[:-1]
    p_values, p_wrong = [], []
    wrong = coulomb_dashpot_v(sigma=1.0, m=1.0, c=0.5, alpha=0.6)
    for _ in range(200):
        values = np.interp(rng.uniform(size=400), cdf, grid)
        edges = histogram(values).edges
        p_values.append(chi_square_test(values, edges, law).p_value)
        p_wrong.append(chi_square_test(values, edges, wrong).p_value)
    assert scipy_stats.kstest(p_values, "uniform").pvalue > 1e-3
    assert np.median(p_wrong) < 1e-3


def test_laws_normalised_by_quadrature_equal_their_closed_forms():
    edges = np.linspace(-1.5, 1.5, 13)
    # no cubic: the Gibbs law is the Gaussian sigma^2 / (2ck)
    gibbs = cubic_oscillator_x(sigma=0.6, c=0.4, k=1.5, k3=0.0)
    gaussian = np.diff(np.concatenate(([0], scipy_stats.norm.cdf(edges, 0, 0.6 / math.sqrt(2 * 0.4 * 1.5)), [1])))
    np.testing.assert_allclose(gibbs.probabilities(edges), gaussian, atol=1e-12)
    # a pure quartic: p(0) = a^(1/4) / (2 Gamma(5/4)), a = (2c/sigma^2) k3/4
    quartic = cubic_oscillator_x(sigma=0.6, c=0.4, k=0.0, k3=3.0)
    a = 2 * 0.4 / 0.36 * 3.0 / 4
    assert quartic.pdf([0.0])[0] == pytest.approx(a ** 0.25 / (2 * math.gamma(1.25)), rel=1e-9)
    # Coulomb friction without a dashpot: a Laplace law of rate 2 m alpha / sigma^2
    laplace = coulomb_dashpot_v(sigma=0.8, m=2.0, c=0.0, alpha=0.1)
    rate = 2 * 2.0 * 0.1 / 0.64
    cdf = np.where(edges < 0, 0.5 * np.exp(rate * edges), 1 - 0.5 * np.exp(-rate * edges))
    np.testing.assert_allclose(laplace.probabilities(edges), np.diff(np.concatenate(([0], cdf, [1]))), atol=1e-11)
    # a narrow law is not lost in the tails' change of variable
    narrow = coulomb_dashpot_v(sigma=1e-3, m=1.0, c=1.0, alpha=0.0)
    assert narrow.pdf([0.0])[0] == pytest.approx(1 / (math.sqrt(2 * math.pi) * 1e-3 / math.sqrt(2)), rel=1e-9)


# ------------------------------------------------------------------ the sweep file

def _spec(text):
    return parse_spec(tomllib.loads(text), "mc.toml")


def test_seeds_are_the_innermost_range_and_each_grid_point_gets_them_all():
    spec = _spec('[grid]\n"spring.k0" = [1.0, 2.0]\n[seeds]\nkey = "load.seed"\nfirst = 10\ncount = 3\n')
    assert spec.runs == 6 and spec.keys == ["spring.k0", "load.seed"] and spec.group_size == 3
    values = spec.values(0, 6)
    assert [v["load.seed"] for _, v in values] == [10, 11, 12] * 2
    assert [v["spring.k0"] for _, v in values] == [1.0] * 3 + [2.0] * 3
    assert [spec.group(run) for run, _ in values] == [0, 0, 0, 1, 1, 1]
    assert spec.values(2, 5) == values[2:5]
    both = _spec('[random]\nsamples = 2\n"mass.m" = { distribution = "uniform", low = 1, high = 2 }\n'
                 '[seeds]\nkey = "load.noise_seed"\ncount = 4\n')
    masses = [v["mass.m"] for _, v in both.values(0, 8)]
    assert masses[:4] == [masses[0]] * 4 and masses[4:] == [masses[4]] * 4 and masses[0] != masses[4]
    assert both.group_keys == ["mass.m"]
    # the report's tables change no run: the digest that --resume compares ignores them
    assert _spec("[seeds]\ncount = 5\n[law]\noutput = \"final_x\"\ndensity = \"normal\"\nmean = 0\nstd = 1\n"
                 ).digest() == _spec("[seeds]\ncount = 5\n").digest() != _spec("[seeds]\ncount = 6\n").digest()


@pytest.mark.parametrize("text, message", [
    ("[seeds]\nfirst = 3", "[seeds] count: missing"),
    ("[seeds]\ncount = 0", "[seeds] count: must be >= 1"),
    ("[seeds]\ncount = 2\nfirst = -1", "[seeds] first: must be >= 0"),
    ("[seeds]\ncount = 2\nfirst = 9223372036854775807", "the last seed"),
    ("[seeds]\ncount = 2\nkey = \"spring.k0\"", "'spring.k0' is not a seed"),
    ("[seeds]\ncount = 2\nstep = 1", "[seeds] step: unknown key"),
    ('[grid]\n"load.seed" = [1, 2]\n[seeds]\ncount = 2\nkey = "load.seed"', "load.seed already varies in [grid]"),
    ("[seeds]\ncount = 2\n[statistics]\nconfidence = 1.0", "[statistics] confidence: must be in (0, 1)"),
    ("[seeds]\ncount = 2\n[statistics]\nbins = 0", "[statistics] bins: must be >= 1"),
    ("[seeds]\ncount = 2\n[statistics]\noutputs = [\"xmax\"]", "unknown quantity 'xmax'"),
    ('[seeds]\ncount = 2\n[keep]\nsummary = ["final_v"]\n[statistics]\noutputs = ["final_x"]',
     "'final_x' is not kept"),
    ('[seeds]\ncount = 2\n[law]\noutput = "final_x"', "[law] density: missing"),
    ('[seeds]\ncount = 2\n[law]\noutput = "final_x"\ndensity = "gauss"', "[law] density: must be one of"),
    ('[seeds]\ncount = 2\n[law]\noutput = "final_x"\ndensity = "normal"\nmedian = 1',
     "[law] median: unknown parameter of normal"),
    ('[seeds]\ncount = 2\n[law]\noutput = "final_x"\ndensity = "oscillator_x"\nc = "damper"',
     "[law] c: 'damper' is neither a number nor a scene key"),
    ('[seeds]\ncount = 2\n[[law]]\noutput = "final_x"\ndensity = "oscillator_x"\n'
     '[[law]]\noutput = "final_x"\ndensity = "normal"', "[[law]] 2 output: final_x has a law already"),
    ('[grid]\n"spring.k0" = [1.0]\n[statistics]\nbins = 4', "[statistics]: needs [seeds] or [random]"),
])
def test_a_bad_monte_carlo_table_is_one_line_naming_the_key(text, message):
    with pytest.raises(SweepError) as info:
        _spec(text)
    assert message in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("load, key", [
    (RANDOM, "load.seed"),
    (WHITE, "load.seed"),
    ({"kind": "harmonic", "amplitude": 0.1, "omega": 1.0, "noise_intensity": 0.2, "noise_seed": 4}, "load.noise_seed"),
])
def test_the_seed_key_defaults_to_the_scenes_seeded_load(write_scene, load, key):
    scene = write_scene(base_tables(branches=None, cubic=None, load=load,
                                    solver={"stepper": "implicit", "step": 0.01, "stop_time": 1.0,
                                            "output_interval": 0.1}))
    the_plan = plan(scene, {"seeds": {"count": 3}})
    assert the_plan.spec.seeds.key == key and the_plan.columns[:2] == ["run", key]
    assert the_plan.spec.statistics is not None  # a seed range gets its report


def test_a_scene_without_seeded_load_or_law_parameter_is_refused_before_any_run(write_scene):
    scene = write_scene(base_tables())
    with pytest.raises(SweepError, match=r"\[seeds\] key: .* has no seeded load .*: name the key$"):
        plan(scene, {"seeds": {"count": 3}})
    noisy = write_scene(base_tables(damper=None, load=WHITE, branches=None,
                                    solver={"stepper": "implicit", "step": 0.01, "stop_time": 1.0,
                                            "output_interval": 0.1}), "noisy.toml")
    with pytest.raises(SweepError, match=r"\[law\]: c is the scene's damper.c, which it does not have"):
        plan(noisy, {"seeds": {"count": 3}, "law": {"output": "final_x", "density": "oscillator_x"}})
    with pytest.raises(SweepError, match=r"\[law\]: oscillator_x: c must be > 0, got -1.0"):
        plan(noisy, {"seeds": {"count": 3}, "law": {"output": "final_x", "density": "oscillator_x", "c": -1.0}})
    with pytest.raises(SweepError, match="late_mean_x"):  # a quantity asked by name is kept without [keep]
        plan(noisy, {"seeds": {"count": 3}, "statistics": {"outputs": ["late_mean_x"]}, "keep": {"summary": ["final_x"]}})
    kept = plan(noisy, {"seeds": {"count": 3}, "statistics": {"outputs": ["late_mean_square_x"]}})
    assert "late_mean_square_x" in kept.summary and "final_x" in kept.summary


def test_bad_monte_carlo_input_to_the_command_is_one_line_and_exit_2(write_scene, tmp_path, capsys):
    scene = write_scene(base_tables())
    spec = tmp_path / "mc.toml"
    spec.write_text("[seeds]\ncount = 3\n")
    assert main(["sweep", str(scene), str(spec), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "has no seeded load" in error and "Traceback" not in error
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ a sweep whose output has a known law

@pytest.mark.slow
def test_one_cosine_of_random_phase_has_the_arcsine_law_over_the_seeds():
    """A massless spring under F = rms sqrt(2) cos(omega t + phi), phi uniform: x(T) = F(T) / k0 has the arcsine
    law on [-a, a], a = rms sqrt(2) / k0, whatever omega: P(x < y) = 1/2 + arcsin(y / a) / pi."""
    scene_tables = {"name": "arcsine", "spring": {"k0": 2.0}, "load": RANDOM,
                    "solver": {"stepper": "implicit", "step": 0.05, "stop_time": 0.5, "output_interval": 0.5}}
    document = tomllib.loads(scene_text(scene_tables))
    the_plan = plan(document, {"seeds": {"count": 600, "first": 100}, "keep": {"summary": ["final_x"]}})
    spec = the_plan.spec
    frame = pd.DataFrame(run_batch(document, "arcsine", spec.keys, spec.values(0, spec.runs), the_plan.summary, False))
    assert list(frame["load.seed"]) == list(range(100, 700)) and set(frame["error"]) == {""}
    a = 0.5 * math.sqrt(2) / 2.0
    x = frame["final_x"].to_numpy()
    assert np.all(np.abs(x) <= a * (1 + 1e-12))
    arcsine = Density("arcsine", lambda y: -0.5 * np.log1p(-(y / a) ** 2), support=(-a, a),
                      cdf=lambda y: 0.5 + np.arcsin(np.clip(y / a, -1, 1)) / math.pi)
    assert chi_square_test(x, histogram(x).edges, arcsine).p_value > 1e-3
    assert chi_square_test(x, histogram(x).edges, normal(0.0, a / math.sqrt(2))).p_value < 1e-6  # same variance
    # the report's tables: one group, the seeds' statistics, the mean's interval holding 0
    statistics, bins, _ = tables(frame, spec, document, the_plan.summary)
    [row] = statistics.to_dict("records")
    assert row["n"] == 600 and row["failed"] == 0 and row["mean_low"] < 0 < row["mean_high"]
    assert row["std_low"] < a / math.sqrt(2) < row["std_high"]
    assert bins["count"].sum() == 600


def test_the_report_counts_failed_runs_apart_and_has_one_row_per_group_and_output():
    spec = _spec('[grid]\n"damper.c" = [0.5, 1.0]\n[seeds]\nkey = "load.seed"\ncount = 50\n'
                 '[keep]\nsummary = ["final_x", "final_v"]\n'
                 '[law]\noutput = "final_x"\ndensity = "oscillator_x"\nsigma = 1.0\nk = 2.0\n')
    rng = np.random.default_rng(1)
    runs = spec.values(0, spec.runs)
    c = np.array([v["damper.c"] for _, v in runs])
    frame = pd.DataFrame({"run": np.arange(100), "damper.c": c, "load.seed": [v["load.seed"] for _, v in runs],
                          "final_x": rng.normal(0, 1 / np.sqrt(4 * c)), "final_v": rng.normal(size=100),
                          "error": [""] * 100, "warning": [""] * 100})
    frame.loc[[3, 60], "error"] = "failed"
    frame.loc[[3, 60], ["final_x", "final_v"]] = math.nan
    statistics, bins, figures = tables(frame, spec, {"damper": {"c": 0.1}}, ["final_x", "final_v"])
    assert list(statistics.columns[:3]) == ["group", "damper.c", "output"]
    assert list(statistics["damper.c"]) == [0.5, 0.5, 1.0, 1.0] and list(statistics["n"]) == [49, 49, 49, 49]
    assert list(statistics["failed"]) == [1] * 4
    # each group's law takes c from the group's own scene: sd 1 / sqrt(2 c k)
    assert statistics["law"][0].endswith("sd 0.7071") and statistics["law"][2].endswith("sd 0.5")
    assert statistics["law"][1] == "" and math.isnan(statistics["p_value"][1])
    assert len(figures) == 2 and set(bins["output"]) == {"final_x", "final_v"}


# ------------------------------------------------------------------ the linear oscillator under white noise

@pytest.mark.slow
def test_the_linear_oscillators_x_at_T_over_400_seeds_has_its_stationary_law(tmp_path):
    """m x'' + c x' + k x = sigma xi: x(T) ~ N(0, sigma^2 / (2ck)) once T >> 2m/c (here T = 10 relaxation
    times): the sweep command on a LocalCluster, its report's chi-square p-value, the mean's and the std's
    intervals; the same runs against a wider law are refused."""
    tables_ = {"name": "oscillator", "mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.5},
               "load": {"kind": "white_noise", "intensity": 0.5, "seed": 0},
               "solver": {"stepper": "implicit", "step": 0.01, "stop_time": 40.0, "output_interval": 0.1}}
    scene = tmp_path / "oscillator.toml"
    scene.write_text(scene_text(tables_))
    spec = tmp_path / "mc.toml"
    spec.write_text('[seeds]\ncount = 400\n[keep]\nsummary = ["final_x", "final_v", "late_mean_square_x"]\n'
                    '[law]\noutput = "final_x"\ndensity = "oscillator_x"\n')
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "sweep", str(scene), str(spec), "--workers", "1",
                           "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == [str(out), str(out / "_report" / "report.md")]
    statistics = pd.read_csv(out / "_report" / "statistics.csv").set_index("output")
    sd = 0.5 / math.sqrt(2 * 0.5 * 1.0)
    x = statistics.loc["final_x"]
    assert x["n"] == 400 and x["p_value"] > 1e-3, x
    assert x["mean_low"] < 0 < x["mean_high"] and x["std_low"] < sd < x["std_high"]
    # the time average over the second half: sigma^2/(2ck) within 10 % (backward Euler damps by about h k / c)
    assert abs(statistics.loc["late_mean_square_x", "mean"] / sd**2 - 1) < 0.1
    assert (out / "_report" / "law-final_x-0.png").stat().st_size > 10_000
    frame = pd.read_parquet(out)
    assert sorted(frame["load.seed"]) == list(range(400))
    # the test can fail: a sd 20 % larger is outside the std's interval, a law 50 % wider fails the chi-square
    assert x["std_high"] < 1.2 * sd
    wider = plan(str(scene), {"seeds": {"count": 400}, "keep": {"summary": ["final_x"]},
                              "law": {"output": "final_x", "density": "oscillator_x", "sigma": 0.75}})
    too_wide, _, _ = tables(frame, wider.spec, wider.document, ["final_x"])
    assert too_wide["p_value"][0] < 1e-4


@pytest.mark.slow
def test_a_white_noise_run_is_summarized_from_simulates_own_rows_bit_for_bit():
    """The batch kernel packs loads without noise: a noisy run goes through simulate, every step a row when a
    peak is asked for; its numbers are simulate's (the scene's grid, and every step for the peaks)."""
    from prandtl_fmu import parse_scene
    from prandtl_fmu.driver import simulate
    from prandtl_fmu.summary import late_average, summarize

    scene = parse_scene(scene_text(base_tables(branches=None, load=dict(WHITE, noise_unit=0.64),
                                               solver={"stepper": "implicit", "step": 0.01, "stop_time": 5.0,
                                                       "output_interval": 0.05})))
    result = simulate(scene, energy=True)
    fine = simulate(scene.with_solver(output_interval=0.01))
    quantities = ["final_x", "final_v", "work", "dissipated", "late_mean_square_v"]
    for peaks in ([], ["max_abs_x", "max_abs_v"]):
        values = summarize(scene, quantities=quantities + peaks, history=True)
        assert values["final_x"] == result.x[-1] and values["final_v"] == result.v[-1]
        assert values["work"] == result.energy["work"][-1]
        assert values["dissipated"] == result.energy["dissipated_sliders"][-1] + result.energy["dissipated_damper"][-1]
        assert values["late_mean_square_v"] == late_average(result.time, result.v**2)
        assert np.array_equal(values["x"], result.x) and np.array_equal(values["time"], result.time)
    assert values["max_abs_x"] == np.abs(fine.x).max() and values["max_abs_v"] == np.abs(fine.v).max()
    assert values["max_abs_v"] > np.abs(result.v).max()  # every step, not the rows
    # the late average is the trapezoidal rule from T/2 (a row here) to T
    half = result.time >= 2.5
    assert values["late_mean_square_v"] == pytest.approx(np.trapezoid(result.v[half] ** 2, result.time[half]) / 2.5,
                                                         rel=1e-13)


def test_a_law_that_fails_at_one_grid_point_is_refused_before_any_run(write_scene):
    scene = write_scene(base_tables(branches=None, cubic=None, load=WHITE,
                                    solver={"stepper": "implicit", "step": 0.01, "stop_time": 1.0,
                                            "output_interval": 0.1}))
    with pytest.raises(SweepError) as info:
        plan(scene, {"grid": {"damper.c": [0.5, 0.0]}, "seeds": {"count": 3},
                     "law": {"output": "final_x", "density": "oscillator_x"}})
    assert str(info.value).endswith("[law] (damper.c = 0.0): oscillator_x: c must be > 0, got 0.0")


@pytest.mark.parametrize("time", [np.linspace(0, 10, 101), np.array([0, 0.3, 1.0, 4.9, 5.2, 7.0, 10.0]),
                                  np.array([0, 3.0, 7.5]), np.array([0.0, 10.0])])
def test_the_late_average_is_the_trapezoid_from_half_the_run_with_its_cut_interpolated(time):
    from prandtl_fmu.summary import late_average

    y = np.random.default_rng(time.size).normal(size=time.size)
    half = time[-1] / 2
    after = time > half
    expected = np.trapezoid(np.concatenate(([np.interp(half, time, y)], y[after])),
                            np.concatenate(([half], time[after]))) / half
    assert late_average(time, y) == pytest.approx(expected, rel=1e-12, abs=1e-15)
    assert late_average(time, np.full(time.size, 3.0)) == pytest.approx(3.0, rel=1e-14)
