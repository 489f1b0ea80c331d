"""Spectra beyond the paper's family: Segalman's four-parameter Iwan model and piecewise densities.

Closed forms (virgin curve, Masing branches, dissipation per cycle, secant stiffness), measured slopes, and
the continuum against its sampled branches run by independent code.
"""
import numpy as np
import pytest

from prandtl_fmu import parse_scene, simulate
from prandtl_fmu.connector import displacement_response
from prandtl_fmu.effects import ContinuousBranches, iwan_parameters
from prandtl_fmu.kernels import stack
from prandtl_fmu.scene import SceneError

from tests.conftest import scene_text

SOLVER = {"step": 0.01, "stop_time": 1.0, "output_interval": 0.01}
IWAN = {"kind": "iwan", "F_S": 2.0, "K_T": 50.0, "chi": -0.5, "beta": 0.4}


def connector(branches, k0=None):
    tables = {"branches": branches, "fmu": {"causality": "displacement"}, "solver": SOLVER}
    if k0 is not None:
        tables = {"spring": {"k0": k0}, **tables}
    return parse_scene(scene_text(tables))


def iwan_virgin(u, F_S, K_T, chi, beta):
    """Segalman's virgin curve: K_T u - R u^(chi+2) / ((chi+1)(chi+2)) below phi_max, F_S beyond."""
    p = iwan_parameters(F_S, K_T, chi, beta)
    u = np.abs(u)
    below = K_T * u - p["R"] * u ** (chi + 2) / ((chi + 1) * (chi + 2))
    return np.where(u < p["phi_max"], below, F_S)


def independent_play(k, eta, xs):
    """sum_i k_i play_{eta_i}[x] along xs from a virgin state: the play update written out in numpy."""
    u = np.zeros_like(eta)
    forces = np.empty(len(xs))
    previous = 0.0
    for j, x in enumerate(xs):
        u = np.clip(u + (x - previous), -eta, eta)
        previous = x
        forces[j] = k @ u
    return forces


@pytest.mark.parametrize("chi, beta", [(-0.8, 0.0), (-0.5, 0.4), (-0.2, 2.0), (0.5, 1.0)])
def test_the_iwan_virgin_curve_and_masing_branches_are_segalmans(chi, beta):
    density = {**IWAN, "chi": chi, "beta": beta}
    p = iwan_parameters(2.0, 50.0, chi, beta)
    scene = connector({"continuum": True, "density": density})
    assert scene.branches.stiffness_sum == pytest.approx(50.0, rel=1e-13)
    assert scene.branches.strength == pytest.approx(2.0, rel=1e-13)
    top = 1.5 * p["phi_max"]
    up = np.linspace(0.0, top, 3001)
    down = np.linspace(top, -0.6 * p["phi_max"], 4001)
    forces = displacement_response(scene, np.concatenate([up, down]))
    virgin = iwan_virgin(up, 2.0, 50.0, chi, beta)
    np.testing.assert_allclose(forces[:len(up)], virgin, rtol=0, atol=1e-12 * 2.0)
    # the macro-slip plateau is F_S: past phi_max every slider slides (the Dirac included)
    assert forces[len(up) - 1] == pytest.approx(2.0, rel=1e-13)
    masing = virgin[-1] - 2 * iwan_virgin((top - down) / 2, 2.0, 50.0, chi, beta)
    np.testing.assert_allclose(forces[len(up):], masing, rtol=0, atol=1e-12 * 2.0)


@pytest.mark.parametrize("chi", [-0.8, -0.5, -0.2])
def test_small_amplitude_dissipation_grows_like_a_to_the_chi_plus_3(chi):
    """Segalman: below phi_max the energy a cycle of amplitude A dissipates is 4 R A^(chi+3) / ((chi+2)(chi+3)).
    Measured from the loop area (trapezoid on a fine cycle), independently of the energy account."""
    density = {**IWAN, "chi": chi}
    p = iwan_parameters(2.0, 50.0, chi, IWAN["beta"])
    scene = connector({"continuum": True, "density": density})
    amplitudes = p["phi_max"] * np.geomspace(1e-3, 0.3, 7)
    areas, accounted = [], []
    for amplitude in amplitudes:
        phase = np.linspace(0.0, 2 * np.pi, 40_001)
        x = np.concatenate([np.linspace(0.0, amplitude, 1001)[:-1], amplitude * np.cos(phase)])
        forces, dissipated = displacement_response(scene, x, energy=True)
        cycle = slice(1000, None)
        areas.append(-np.sum(0.5 * (forces[cycle][1:] + forces[cycle][:-1]) * np.diff(x[cycle])))
        accounted.append(dissipated)
    areas = np.abs(areas)
    closed = 4 * p["R"] * amplitudes ** (chi + 3) / ((chi + 2) * (chi + 3))
    slope = np.polyfit(np.log(amplitudes), np.log(areas), 1)[0]
    assert abs(slope - (chi + 3)) < 0.02, slope
    np.testing.assert_allclose(areas, closed, rtol=2e-4)  # the trapezoid's own error
    # the sliders' account: the virgin quarter dissipates too; over the cycle alone it is the closed form
    first_quarter = [displacement_response(scene, np.linspace(0.0, a, 1001), energy=True)[1] for a in amplitudes]
    np.testing.assert_allclose(np.array(accounted) - first_quarter, closed, rtol=1e-9)


@pytest.mark.parametrize("chi", [-0.7, -0.3])
def test_the_secant_stiffness_falls_as_segalmans_closed_form(chi):
    """K_T - F(u) / u = R u^(chi+1) / ((chi+1)(chi+2)) on the virgin curve: slope chi + 1 in log-log."""
    p = iwan_parameters(2.0, 50.0, chi, 0.4)
    scene = connector({"continuum": True, "density": {**IWAN, "chi": chi}})
    u = p["phi_max"] * np.geomspace(1e-3, 0.5, 30)
    forces = displacement_response(scene, u)
    loss = 50.0 - forces / u
    slope = np.polyfit(np.log(u), np.log(loss), 1)[0]
    assert abs(slope - (chi + 1)) < 0.02, slope
    np.testing.assert_allclose(loss, p["R"] * u ** (chi + 1) / ((chi + 1) * (chi + 2)), rtol=1e-6)


def random_piecewise(rng):
    """A random piecewise spectrum: 2-6 segments, random densities (some zero), eta with flat parts. Segments
    are no narrower than a third of the mean (the sampling's rate is asymptotic: a cell must resolve them)."""
    count = int(rng.integers(2, 7))
    s = np.concatenate([[0.0], np.cumsum(rng.uniform(0.5, 1.5, count))])
    s /= s[-1]
    rises = rng.uniform(0.0, 0.4, count) * (rng.uniform(size=count) > 0.25)  # some flat: Diracs
    eta = rng.uniform(0.0, 0.1) + np.concatenate([[0.0], np.cumsum(rises)])
    k = rng.uniform(0.2, 3.0, count) * (rng.uniform(size=count) > 0.2)
    k[int(rng.integers(count))] = 1.0
    return {"kind": "piecewise", "s": s.tolist(), "k": k.tolist(), "eta": eta.tolist()}


def random_history(rng, extent, count=4000):
    steps = rng.normal(0.0, 1.0, count)
    x = np.cumsum(steps)
    return extent * x / np.abs(x).max()


@pytest.mark.parametrize("seed", range(4))
def test_a_piecewise_continuum_is_the_limit_of_its_samples_run_by_independent_code(seed):
    """Random piecewise spectra (with Diracs and empty segments) under a random history: the continuum's
    force against n branches of the scene's sampling (k_i = cell integral, eta_i = cell mean), run by the
    play update written out in numpy; the error falls like 1/n^2."""
    rng = np.random.default_rng(seed)
    density = random_piecewise(rng)
    scene = connector({"continuum": True, "density": density})
    xs = random_history(rng, 1.2 * density["eta"][-1] + 0.05)
    exact = displacement_response(scene, xs)
    ns, errors = [25, 50, 100, 200, 400], []
    for n in ns:
        sampled = connector({"count": n, "density": density}).branches
        np.testing.assert_allclose(sampled.stiffness.sum(), scene.branches.stiffness_sum, rtol=1e-12)
        np.testing.assert_allclose(sampled.strength, scene.branches.strength, rtol=1e-12)
        errors.append(np.abs(independent_play(sampled.stiffness, sampled.yield_displacement, xs) - exact).max())
    slope = -np.polyfit(np.log(ns), np.log(errors), 1)[0]
    assert 1.6 < slope < 2.4, errors  # a max over a random history: the local rate scatters by +-0.3 (30 seeds)
    assert errors[-1] < 5e-5 * np.abs(exact).max()


@pytest.mark.parametrize("rule, order", [("right", 1.0), ("mean", 1.5)])
def test_the_iwan_continuum_is_the_limit_of_its_samples(rule, order):
    """Segalman's spectrum (singular at 0, a Dirac at phi_max) sampled by n branches: the force converges at
    the sampling's order, on a random history that reaches macro-slip: 1/n for right end points, n^-(chi+2)
    for cell means (the first cell's stiffness ~ n^-(chi+1) is off by ~ 1/n in eta; 2 elsewhere)."""
    rng = np.random.default_rng(11)
    p = iwan_parameters(**{key: IWAN[key] for key in ("F_S", "K_T", "chi", "beta")})
    scene = connector({"continuum": True, "density": IWAN})
    xs = random_history(rng, 1.3 * p["phi_max"])
    exact = displacement_response(scene, xs)
    ns, errors = [50, 100, 200, 400, 800], []
    for n in ns:
        sampled = connector({"count": n, "density": IWAN, "sampling": rule}).branches
        errors.append(np.abs(independent_play(sampled.stiffness, sampled.yield_displacement, xs) - exact).max())
    slope = -np.polyfit(np.log(ns), np.log(errors), 1)[0]
    assert order - 0.2 < slope < order + 0.35, errors


def test_the_papers_continuum_written_as_a_piecewise_density_is_the_same_element():
    linear = connector({"continuum": True, "k_total": 1.0, "eta_range": [0.1, 1.1]})
    split = connector({"continuum": True, "density": {"kind": "piecewise", "s": [0.0, 0.3, 1.0], "k": [1.0, 1.0],
                                                      "eta": [0.1, 0.4, 1.1]}})
    xs = random_history(np.random.default_rng(3), 1.3)
    np.testing.assert_allclose(displacement_response(split, xs), displacement_response(linear, xs), atol=1e-13)


def test_a_dirac_slides_whole_and_its_memory_survives_many_reversals():
    """A spectrum that is one flat segment (all branches at one eta) is a single Prandtl branch; a decaying
    oscillation with thousands of turning points keeps the memory bounded and the force of 400 sampled
    branches (run by independent code) to 1e-6."""
    dirac = connector({"continuum": True, "density": {"kind": "piecewise", "k": [3.0], "eta": [0.2, 0.2]}})
    xs = random_history(np.random.default_rng(5), 0.7)
    np.testing.assert_allclose(displacement_response(dirac, xs),
                               independent_play(np.array([3.0]), np.array([0.2]), xs), atol=1e-13)
    params = ContinuousBranches.iwan(**{key: IWAN[key] for key in ("F_S", "K_T", "chi", "beta")}).params
    state = stack.fresh_state(params, 0.0)
    turns = stack.CONTINUUM_PIECES + 512  # past the bound on the pieces: 512 reversals merge pieces
    xs = np.concatenate([[0.0], 0.05 * (-1.0) ** np.arange(turns) / (1 + 0.01 * np.arange(turns))])
    from tests.models.test_continuum import drive

    forces = drive(params, state, xs, None)
    assert int(state[stack.COUNT]) <= stack.CONTINUUM_PIECES
    sampled = connector({"count": 4000, "density": IWAN}).branches
    reference = independent_play(sampled.stiffness, sampled.yield_displacement, xs)
    assert np.abs(forces - reference).max() < 1e-6 * IWAN["F_S"] * 10


def test_a_forced_iwan_element_keeps_its_energy_balance_and_agrees_with_fine_sampling():
    tables = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "branches": {"continuum": True, "density": IWAN},
              "load": {"kind": "harmonic", "amplitude": 3.0, "omega": 2.0},
              "solver": {"stepper": "verlet", "step": 1e-3, "stop_time": 20.0, "output_interval": 0.1}}
    continuum = simulate(parse_scene(scene_text(tables)), energy=True)
    energy = continuum.energy
    assert energy["dissipated_sliders"][-1] > 1.0
    assert np.abs(energy["energy_residual"]).max() < 1e-5 * energy["dissipated_sliders"][-1]
    sampled = simulate(parse_scene(scene_text({**tables, "branches": {"count": 3000, "density": IWAN}})))
    assert np.abs(continuum.x - sampled.x).max() < 1e-5 * np.abs(continuum.x).max()


@pytest.mark.parametrize("branches, culprit", [
    ({"continuum": True, "density": {**IWAN, "chi": -1.0}}, r"\[branches.density\] chi: must be > -1"),
    ({"continuum": True, "density": {**IWAN, "F_S": 0.0}}, r"\[branches.density\] F_S: must be > 0"),
    ({"continuum": True, "density": {**IWAN, "beta": -0.1}}, r"\[branches.density\] beta: must be >= 0"),
    ({"continuum": True, "density": {"kind": "iwan", "F_S": 1.0, "K_T": 1.0, "chi": 0.0}},
     r"\[branches.density\] beta: missing"),
    ({"continuum": True, "density": {**IWAN, "phi_max": 1.0}}, r"\[branches.density\] phi_max: unknown key"),
    ({"continuum": True, "density": {"kind": "spline"}}, r"\[branches.density\] kind: must be one of"),
    ({"continuum": True, "density": 3.0}, r"\[branches.density\]: must be a table"),
    ({"continuum": True, "density": {"kind": "piecewise", "k": [1.0, 2.0], "eta": [0.0, 0.3, 0.2]}},
     r"\[branches.density\] eta\[3\]: eta\(s\) must be non-decreasing"),
    ({"continuum": True, "density": {"kind": "piecewise", "k": [1.0, 2.0], "eta": [0.0, 0.3]}},
     r"\[branches.density\] eta: must have 3 values"),
    ({"continuum": True, "density": {"kind": "piecewise", "s": [0.0, 0.6, 0.5, 1.0], "k": [1.0, 1.0, 1.0],
                                     "eta": [0.0, 0.1, 0.2, 0.3]}}, r"\[branches.density\] s\[3\]: .*rise"),
    ({"continuum": True, "density": {"kind": "piecewise", "s": [0.1, 1.0], "k": [1.0], "eta": [0.0, 0.3]}},
     r"\[branches.density\] s: the segment ends must run from 0 to 1"),
    ({"continuum": True, "density": {"kind": "piecewise", "k": [0.0, 0.0], "eta": [0.0, 0.1, 0.2]}},
     r"\[branches.density\] k: at least one segment"),
    ({"continuum": True, "density": {"kind": "piecewise", "k": [-1.0], "eta": [0.0, 0.1]}},
     r"\[branches.density\] k\[1\]: must be >= 0"),
    ({"continuum": True, "density": IWAN, "k_total": 1.0}, r"\[branches\] k_total: unknown key"),
    ({"density": IWAN}, r"\[branches\] density: give count = n"),
    ({"count": 10, "density": IWAN, "u0": [0.0] * 10}, r"\[branches\] u0: unknown key"),
    ({"count": 10, "density": IWAN, "sampling": "left"}, r"\[branches\] sampling: must be one of"),
])
def test_density_errors_name_the_key(branches, culprit):
    with pytest.raises(SceneError, match=culprit):
        connector(branches)


def test_the_scene_keys_of_the_densities_build_the_documented_spectra():
    iwan = connector({"continuum": True, "density": IWAN}).branches
    p = iwan_parameters(2.0, 50.0, -0.5, 0.4)
    # the Dirac holds S = beta / (1 + beta) of K_T at phi_max; the power law the rest
    K, M, E = stack.spectrum_integrals(iwan.params, [0.0, 1.0 / 1.4, 1.0])
    np.testing.assert_allclose(K, [50.0 / 1.4, p["S"]], rtol=1e-13)
    np.testing.assert_allclose(M[1], p["S"] * p["phi_max"], rtol=1e-13)
    piecewise = connector({"continuum": True, "density": {"kind": "piecewise", "k": [2.0, 0.0, 4.0],
                                                          "eta": [0.0, 0.3, 0.3, 0.6]}}).branches
    np.testing.assert_allclose(piecewise.s, [0.0, 1 / 3, 2 / 3, 1.0])  # s defaults to equal segments
    assert piecewise.stiffness_sum == pytest.approx(2.0)
    assert piecewise.strength == pytest.approx((2.0 * 0.15 + 4.0 * 0.45) / 3)
    sampled = connector({"count": 6, "density": {"kind": "piecewise", "k": [2.0, 0.0, 4.0],
                                                 "eta": [0.0, 0.3, 0.3, 0.6]}}).branches
    assert sampled.n == 4  # the empty segment holds no branch
    np.testing.assert_allclose(sampled.yield_displacement, [0.075, 0.225, 0.375, 0.525])
    dirac = connector({"count": 5, "density": {"kind": "piecewise", "s": [0.0, 0.5, 1.0], "k": [2.0, 4.0],
                                               "eta": [0.0, 0.3, 0.3]}}).branches
    # cells [0, .2), [.2, .4), [.4, .5) (cut at the segment end), then the Dirac as one branch
    np.testing.assert_allclose(dirac.stiffness, [0.4, 0.4, 0.2, 2.0])
    np.testing.assert_allclose(dirac.yield_displacement, [0.06, 0.18, 0.27, 0.3])
