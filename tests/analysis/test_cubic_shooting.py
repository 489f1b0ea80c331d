"""Cubic springs beside rigid sliders in a network (``frequency/network_orbit.py``: the cubic springs' force by
its recurrence in each phase's Taylor series): the one-node network is the element's Taylor orbit
(``element_orbit.py``), two masses move as the implicit stepper runs the network, their curve folds, and the
nonlinear mode of a Duffing oscillator with a hair of friction is the conservative oscillator's exact
frequency."""
import dataclasses
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main

from tests.analysis.test_describe_cli import read_csv
from tests.analysis.test_harmonic_balance_network_friction import network, network_text
from tests.analysis.test_series import implicit_agrees

ONE_NODE = [("spring", ["a", "ground"], {"k": 1.0}), ("cubic", ["a", "ground"], {"k3": 0.5}),
            ("dashpot", ["a", "ground"], {"c": 0.02}), ("slider", ["a", "ground"], {"alpha": 0.05}),
            ("branch", ["a", "ground"], {"k": 0.7, "eta": 0.1})]
TWO_MASSES = [("spring", ["a", "ground"], {"k": 1.0}), ("cubic", ["a", "ground"], {"k3": 0.5}),
              ("dashpot", ["a", "ground"], {"c": 0.02}), ("spring", ["a", "b"], {"k": 0.8}),
              ("slider", ["a", "b"], {"alpha": 0.05}), ("dashpot", ["b", "ground"], {"c": 0.02})]


def test_a_node_with_a_cubic_spring_and_a_slider_is_the_element_s_taylor_orbit(tmp_path):
    """The network of one node (spring, cubic spring, dashpot, slider and branch to the ground) run by
    network shooting over two periods, from rest and from moving states, is the element's Taylor orbit to
    1e-11 of the motion at every sample (two codes: the network's phases with stuck sliders as constraints,
    the element's with its mass stuck)."""
    from prandtl_fmu.frequency import element_orbit
    from prandtl_fmu.frequency.shooting import NetworkShooting, prepared_network

    scene = prepared_network(network(tmp_path, network_text(["a"], [1.0], ONE_NODE, load_node="a")), None, "a")
    M = 128
    for F, omega in ((0.3, 1.0), (0.3, 2.5), (0.1, 0.6)):
        shooting = NetworkShooting(scene, F, None, M, 7, 1.0)
        assert shooting.smooth
        for start in ([0.0, 0.0, 0.0], [0.5, -0.3, 0.05], [1.5, 1.0, -0.1]):
            end, xs = shooting.run(np.array(start), omega, 4)
            state, u, out = np.array(start[:2]), np.array(start[2:]), np.empty(2 * M)
            status, _ = element_orbit.run(1.0, 1.0, 0.02, 0.5, 0.05, 0.05, 0.0, np.array([0.7]), np.array([0.1]),
                                          np.zeros(0), np.zeros(0), np.zeros(0), False, F, omega, state, u, np.zeros(0),
                                          2 * math.pi / omega / M, 2 * M, out, 0.0)
            size = max(1.0, float(np.max(np.abs(out))))
            assert status == element_orbit.OK and np.max(np.abs(out - xs[:, 0])) <= 1e-11 * size
            assert np.max(np.abs(end - np.r_[state, u])) <= 1e-11 * size


def test_two_masses_with_a_cubic_spring_and_a_slider_move_as_the_implicit_stepper_runs_them(tmp_path):
    """At a frequency of one stable state (below the first mode), shooting's first harmonic of both masses
    against the implicit stepper's steady state at h and h / 2: the stepper's error halves (order 1) and its
    Richardson extrapolation lands within 5 % of that error on shooting's."""
    from prandtl_fmu.frequency.shooting import NetworkShooting, prepared_network

    scene = network(tmp_path, network_text(["a", "b"], [1.0, 0.5], TWO_MASSES, load_node="a"))
    F, omega = 0.3, 2 * math.pi * 0.1
    shooting = NetworkShooting(prepared_network(scene, None, "a"), F, None, 1024, 7, omega)
    X = implicit_agrees(scene, shooting, F, omega, 40, ratio=0.15)
    assert np.min(np.abs(X)) > 0.1


def test_two_masses_with_a_cubic_spring_and_a_slider_fold_at_both_modes(tmp_path):
    """From the command line (refused before: a cubic spring beside sliders): the hardening spring bends both
    resonances to the right, each with two folds and its unstable part between them; the figure says how."""
    path, out, plot = tmp_path / "net.toml", tmp_path / "net.csv", tmp_path / "net.png"
    path.write_text(network_text(["a", "b"], [1.0, 0.5], TWO_MASSES, load_node="a"))
    assert main(["describe", str(path), "--force-amplitude", "0.3", "--frequencies", "0.08,0.5", "--out", str(out),
                 "--plot", str(plot)]) == 0
    table = read_csv(out)
    fold = np.flatnonzero(np.array(table["fold"]) == "true")
    stable = np.array(table["stable"]) == "true"
    assert len(fold) == 4
    for upper, lower in ((fold[0], fold[1]), (fold[2], fold[3])):  # each resonance: up to a fold, back, down
        assert float(table["frequency"][upper]) > float(table["frequency"][lower])
        assert not np.any(stable[upper + 1:lower])
    # (the first resonance's upper branch loses its stability a little before its fold: the next test)
    assert np.all(stable[:3]) and np.all(stable[fold[1] + 1:fold[2] - 3]) and np.all(stable[fold[3] + 1:])
    assert plot.read_bytes()[:4] == b"\x89PNG"


def test_the_network_s_unstable_points_leave_their_orbit_under_the_implicit_stepper(tmp_path):
    """The points of the first resonance's upper branch that shooting calls unstable, one before its fold
    among them, run by the implicit stepper (h = T / 4000, its own damping 1e-3 a period) from shooting's state:
    they leave (by more than 20 % of the motion within 60 periods), while a stable point of the same branch
    stays within 1 % (the stepper's own error)."""
    from prandtl_fmu.frequency.continuation import continue_curve
    from prandtl_fmu.frequency.shooting import NetworkShooting, prepared_network
    from prandtl_fmu.loads import HarmonicLoad
    from prandtl_fmu.network.driver import simulate
    from prandtl_fmu.scene_tables import Solver

    scene = network(tmp_path, network_text(["a", "b"], [1.0, 0.5], TWO_MASSES, load_node="a"))
    shooting = NetworkShooting(prepared_network(scene, None, "a"), 0.3, None, 256, 7, 1.0)
    points = continue_curve(shooting, 2 * math.pi * 0.12, 2 * math.pi * 0.16, 2)
    first_fold = next(i for i, p in enumerate(points) if p[2])
    largest = [float(np.max(np.abs(shooting.multipliers(s, w)))) for w, s, _ in points[:first_fold]]
    before = [i for i in range(first_fold) if largest[i] > 1.0]
    assert before, largest  # unstable before the fold
    checks = [(before[len(before) // 2], False), (first_fold + 2, False),
              (int(np.argmax(np.array(largest) < 0.95 * np.max(largest[:before[0]] + [0]))) if before[0] else 0,
               True)]
    for index, stable in checks:
        omega, s, _ = points[index]
        n = 2
        x0, v0 = s[:n], s[n:2 * n] * shooting.reference
        period = 2 * math.pi / omega
        written = dataclasses.replace(scene.network, x0=np.array(x0), v0=np.array(v0))
        run = dataclasses.replace(scene, network=written, load=HarmonicLoad(0.3, omega),
                                  solver=Solver("implicit", period / 4000, 60 * period, period / 4000))
        result = simulate(run, progress=False)
        x = np.stack([result.column(f"x_{name}") for name in "ab"], axis=1)
        orbit = np.stack([result.column(f"x_{name}")[:4001] for name in "ab"], axis=1)  # its first period
        size = float(np.max(np.abs(orbit)))
        drift = float(np.max(np.abs(x[-4001:] - orbit))) / size  # the last period against the first
        if stable:
            assert largest[index] < 1.0 and drift < 0.01, (index, largest[index], drift)
        else:
            assert drift > 0.2, (index, drift)


def _conservative_duffing(X, m=1.0, k=1.0, k3=0.5):
    """The free Duffing oscillator m x'' + k x + k3 x^3 = 0 of peak X: its frequency (Hz) from the period's
    integral T = 4 int_0^(pi/2) dtheta / g(theta), g = sqrt((k + k3 X^2 (1 + sin^2 theta) / 2) / m) (x = X sin
    theta), and the first harmonic of x, b_1 = (8 / T) int_0^(T/4) x sin(omega t) dt, along the same theta."""
    from scipy.integrate import quad, solve_ivp

    def g(theta):
        return math.sqrt((k + 0.5 * k3 * X * X * (1.0 + math.sin(theta) ** 2)) / m)

    period = 4.0 * quad(lambda theta: 1.0 / g(theta), 0.0, 0.5 * math.pi, epsabs=0, epsrel=1e-13)[0]
    omega = 2.0 * math.pi / period
    solution = solve_ivp(lambda theta, y: [1.0 / g(theta), X * math.sin(theta) * math.sin(omega * y[0]) / g(theta)],
                         (0.0, 0.5 * math.pi), [0.0, 0.0], rtol=1e-13, atol=1e-16, method="DOP853")
    return 1.0 / period, 8.0 / period * solution.y[1, -1]


@pytest.mark.parametrize("X", [0.5, 2.0])
def test_the_mode_of_a_duffing_oscillator_with_a_hair_of_friction_is_the_conservative_one(tmp_path, X):
    """EPMC by shooting (``slider_modes.py``) of a mass on a spring and a cubic spring with Coulomb friction of
    1e-4 N (refused before): at the first-harmonic amplitude of the free Duffing oscillator of peak X, the
    frequency of its exact period (an integral) to 1e-6 (Coulomb friction of a / A shifts it by about
    (2 a / A)^2 / (2 pi^2), 1e-9 here), and a damping ratio that is friction's, 2 a / (pi A) to 1 %."""
    from prandtl_fmu.frequency.modes import nonlinear_mode
    from tests.analysis.test_harmonic_balance import element

    frequency, b1 = _conservative_duffing(X)
    scene = element({"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "cubic": {"k3": 0.5}, "friction": {"alpha": 1e-4}})
    backbone = nonlinear_mode(scene, 1, [b1], tolerance=1e-8)
    assert backbone.frequency[0] == pytest.approx(frequency, rel=1e-6)
    assert frequency > 1.04 / (2 * math.pi)  # hardening: above the linear frequency by 4 % at least
    assert 0 < backbone.damping_ratio[0] < 1e-3


# ----------------------------------------------------------------- branches with series dashpots beside sliders

@pytest.mark.slow  # exact's series dashpots compile for it alone (the quick suite's cold budget, README)
def test_a_node_with_series_dashpot_branches_and_a_slider_is_the_element_s_exact_orbit(tmp_path):
    """Branches with series dashpots (their u relaxes, u' = e' - (k / c) u, while they stick: states of the
    network's phases now; refused before) beside a rigid slider, on one node: the element's exact stepper
    (``exact_series.py``: friction and series branches, closed form between events) to 1e-11 over two periods,
    from rest and from moving states."""
    from prandtl_fmu.frequency.shooting import ElementShooting, NetworkShooting, prepared, prepared_network
    from tests.analysis.test_harmonic_balance import element

    text = network_text(["a"], [1.0], [
        ("spring", ["a", "ground"], {"k": 1.0}), ("dashpot", ["a", "ground"], {"c": 0.02}),
        ("slider", ["a", "ground"], {"alpha": 0.1}), ("branch", ["a", "ground"], {"k": 0.7, "eta": 0.2, "c": 0.5}),
        ("branch", ["a", "ground"], {"k": 0.4, "eta": 0.1, "c": 0.8})], load_node="a")
    network_shooting = NetworkShooting(prepared_network(network(tmp_path, text), None, "a"), 0.3, None, 128, 7, 1.0)
    exact = ElementShooting(prepared(element({
        "mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.02}, "friction": {"alpha": 0.1},
        "branches": {"k": [0.7, 0.4], "eta": [0.2, 0.1], "c": [0.5, 0.8]}})), 0.3, None, 128, 7, 1.0)
    assert network_shooting.dimension == exact.dimension == 4
    for omega in (0.5, 1.0, 2.0):
        for start in ([0.0, 0.0, 0.0, 0.0], [0.5, -0.3, 0.05, -0.02], [1.5, 1.0, -0.2, 0.1]):
            end, xs = network_shooting.run(np.array(start), omega, 4)
            end_exact, xs_exact = exact.run(np.array(start), omega, 4)
            size = max(1.0, float(np.max(np.abs(xs_exact))))
            assert np.max(np.abs(xs[:, 0] - xs_exact[:, 0])) <= 1e-11 * size
            assert np.max(np.abs(end - end_exact)) <= 1e-11 * size


MAXWELL_JOINT = [("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.5}),
                 ("dashpot", ["a", "ground"], {"c": 0.02}), ("dashpot", ["b", "ground"], {"c": 0.02}),
                 ("branch", ["a", "b"], {"k": 0.8, "eta": 0.1, "c": 0.3}), ("slider", ["b", "ground"], {"alpha": 0.03})]


def test_two_masses_with_a_maxwell_branch_and_a_slider_move_as_the_implicit_stepper_runs_them(tmp_path):
    """Two masses joined by a branch with a series dashpot, one of them on a slider: shooting's first harmonic of
    both against the implicit stepper's steady state at h and h / 2 (order 1, Richardson within 5 % of its
    error), and the curve from the command line through the resonances."""
    from prandtl_fmu.frequency.shooting import NetworkShooting, prepared_network

    text = network_text(["a", "b"], [1.0, 0.5], MAXWELL_JOINT, load_node="a")
    scene = network(tmp_path, text)
    F, omega = 0.3, 2 * math.pi * 0.08  # below the resonances: the stepper's error is first order there
    shooting = NetworkShooting(prepared_network(scene, None, "a"), F, None, 1024, 7, omega)
    implicit_agrees(scene, shooting, F, omega, 60, ratio=0.15)
    path, out = tmp_path / "maxwell.toml", tmp_path / "maxwell.csv"
    path.write_text(text)
    assert main(["describe", str(path), "--force-amplitude", "1", "--frequencies", "0.05,0.4", "--out", str(out)]) == 0
    table = read_csv(out)
    assert len(table["frequency"]) > 10 and set(table["stable"]) == {"true"}
    assert "nan" not in " ".join(table["amplitude_b"]).lower()
