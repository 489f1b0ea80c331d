"""Harmonic balance of the effects with memory (``prandtl_fmu/frequency/harmonic_balance.py``, ``aft.py``,
``floquet.py``): a delay and a history on a linear oscillator against its closed form and its characteristic
roots, Dahl's sampled cycle against an independent integration, stable points against the time sweep, unstable
points integrated, and the command line."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main

from tests.analysis.test_describe_cli import read_csv, write
from tests.analysis.test_harmonic_balance import element

OSCILLATOR = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.05}}
# each effect on the oscillator, with its term Z(w) of the dynamic stiffness k - m w^2 + i c w + Z(w)
LINEAR = {
    "delay on x": ({"delay": {"gain": 0.3, "tau": 0.7}}, lambda w: 0.3 * np.exp(-1j * w * 0.7)),
    "delay on v": ({"delay": {"gain": 0.3, "tau": 0.7, "acts_on": "v"}}, lambda w: 0.3j * w * np.exp(-1j * w * 0.7)),
    "history on x": ({"history": {"weight": [0.3, 0.2], "rate": [2.0, 0.5]}},
                     lambda w: 0.3 / (2.0 + 1j * w) + 0.2 / (0.5 + 1j * w)),
    "history on v": ({"history": {"weight": [0.3], "rate": [2.0], "acts_on": "v"}},
                     lambda w: 0.3j * w / (2.0 + 1j * w)),
}


@pytest.mark.parametrize("case", sorted(LINEAR))
def test_a_delay_and_a_history_on_a_linear_oscillator_are_its_closed_form(case):
    """m x'' + c x' + k x + [gain y(t - tau) or int sum w_j exp(-r_j (t - s)) y(s) ds] = F0 cos(w t): X = F0 /
    (k - m w^2 + i c w + Z(w)) at every point of the curve, with three harmonics (the higher ones 0)."""
    from prandtl_fmu.frequency.curve import harmonic_response

    tables, transfer = LINEAR[case]
    curve = harmonic_response(element({**OSCILLATOR, **tables}), 0.1, [0.05, 0.3], harmonics=3, stability=False)
    w = 2 * math.pi * curve.frequency
    expected = 0.1 / (1.0 - w**2 + 0.05j * w + transfer(w))
    assert curve.frequency.size > 5
    assert np.max(np.abs(curve.amplitude * np.exp(1j * curve.phase) - expected) / np.abs(expected)) <= 1e-10
    assert np.max(np.abs(curve.coefficients[:, 0, 3:])) <= 1e-12 * np.max(curve.amplitude)


@pytest.mark.parametrize("case", ["delay on x", "history on v"])
def test_a_one_harmonic_nonlinear_mode_with_memory_is_the_root_of_its_dynamic_stiffness(case):
    """EPMC of the linear oscillator with a delay or a history: k - m w^2 + Re Z(w) = 0 and the damping ratio
    (c w + Im Z(w)) / (2 m w^2), whatever the amplitude."""
    from prandtl_fmu.frequency.modes import nonlinear_mode

    tables, transfer = LINEAR[case]
    backbone = nonlinear_mode(element({**OSCILLATOR, **tables}), 1, [0.01, 1.0], harmonics=1)
    w = 2 * math.pi * backbone.frequency
    Z = transfer(w)
    assert np.max(np.abs(1.0 - w**2 + Z.real)) <= 1e-10
    assert backbone.damping_ratio == pytest.approx((0.05 * w + Z.imag) / (2 * w**2), rel=1e-9, abs=1e-12)


@pytest.mark.slow
def test_the_multipliers_of_a_linear_oscillator_with_memory_are_its_characteristic_roots():
    """A linear scene's Floquet multipliers are exp(s T), s the roots of its characteristic equation: with a
    delay of gain -1.5 (k + gain < 0: a real root of s^2 + c s + k + gain exp(-s tau)) and with a history of
    weight -3 (the roots of (s^2 + c s + k)(s + r) + w) the largest is far above 1 (unstable); with the delayed
    stiffness of gain 0.3 the motion's damping turns negative (c w < gain sin(w tau)): unstable too (its
    multiplier within 3e-3: the delay's buffer and backward Euler, extrapolated from 256 and 512 steps), while a
    history on x of weight 0.05 is stable."""
    from scipy.optimize import brentq

    from prandtl_fmu.frequency.floquet import is_stable, multipliers
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    omega = 2 * math.pi * 0.15
    period = 2 * math.pi / omega

    def largest(tables):
        balance = HarmonicBalance(periodic_system(element({**OSCILLATOR, **tables})), 3, 0.1)
        values = multipliers(balance, balance.solve_at(omega), omega)
        return float(np.max(np.abs(values))), is_stable(values)

    root = brentq(lambda s: s * s + 0.05 * s + 1.0 - 1.5 * math.exp(-0.7 * s), 0.0, 5.0)
    assert largest({"delay": {"gain": -1.5, "tau": 0.7}}) == (pytest.approx(math.exp(root * period), rel=1e-3),
                                                              False)
    roots = np.roots(np.polyadd(np.polymul([1.0, 0.05, 1.0], [1.0, 1.0]), [-3.0]))
    assert largest({"history": {"weight": [-3.0], "rate": [1.0]}}) == (
        pytest.approx(np.max(np.abs(np.exp(roots * period))), rel=2e-3), False)
    # the complex roots of s^2 + c s + k + 0.3 exp(-0.7 s) near i: Newton from i
    s = 1j
    for _ in range(50):
        s -= (s * s + 0.05 * s + 1 + 0.3 * np.exp(-0.7 * s)) / (2 * s + 0.05 - 0.21 * np.exp(-0.7 * s))
    assert s.real > 0
    assert largest({"delay": {"gain": 0.3, "tau": 0.7}}) == (pytest.approx(abs(np.exp(s * period)), rel=3e-3), False)
    roots = np.roots(np.polyadd(np.polymul([1.0, 0.05, 1.0], [1.0, 2.0]), [0.05]))
    assert largest({"history": {"weight": [0.05], "rate": [2.0]}}) == (
        pytest.approx(np.max(np.abs(np.exp(roots * period))), rel=2e-3), True)


def _dahl_along(path, sigma, level, exponent, periods=8):
    """Dahl's F along x = ``path(theta)`` by scipy's DOP853 on dF/dtheta = sigma (1 - F / F_c sgn x')^exponent x'
    over ``periods`` periods from F = 0: F at the last period's theta_j = 2 pi j / N as a function of N."""
    from scipy.integrate import solve_ivp

    def rate(theta, F):
        dx = (path(theta + 1e-7) - path(theta - 1e-7)) / 2e-7
        y = max(1.0 - F[0] / level * np.sign(dx), 0.0)
        return [sigma * y**exponent * dx]

    end = 2 * math.pi * periods
    solution = solve_ivp(rate, (0.0, end), [0.0], method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
    return lambda N: solution.sol(end - 2 * math.pi + 2 * math.pi * np.arange(N) / N)[0]


@pytest.mark.slow
@pytest.mark.parametrize("exponent", [1.0, 2.0, 0.5])
def test_dahl_s_sampled_cycle_is_its_integration_along_the_smooth_path(exponent):
    """aft.dahl_cycle against an independent integration of Dahl's law along x = A cos(theta + 0.3) + A / 4
    sin(2 theta) (turning points between samples): the error at the samples falls like 1 / N^2 (the turning
    points), and its exact tangent is the central difference of the cycle."""
    from prandtl_fmu.frequency.aft import dahl_cycle

    A, sigma, level = 0.01, 50.0, 0.4
    reference = _dahl_along(lambda t: A * np.cos(t + 0.3) + A / 4 * np.sin(2 * t), sigma, level, exponent)
    H = 2
    errors = []
    for N in (256, 1024):
        theta = 2 * math.pi * np.arange(N) / N
        basis = np.column_stack([np.ones(N)] + [f(h * theta) for h in range(1, H + 1) for f in (np.cos, np.sin)])
        c = np.array([0.0, A * math.cos(0.3), -A * math.sin(0.3), 0.0, A / 4])
        forces, tangent = np.empty(N), np.empty((N, 2 * H + 1))
        assert 0 < dahl_cycle(basis @ c, basis, sigma, level, exponent, forces, tangent)
        assert np.all(np.abs(forces) <= level)
        errors.append(np.max(np.abs(forces - reference(N))) / level)
        moved = np.empty((2, N))
        for l in range(2 * H + 1):
            for side, sign in enumerate((1, -1)):
                step = c.copy()
                step[l] += sign * 1e-7
                dahl_cycle(basis @ step, basis, sigma, level, exponent, moved[side], np.empty((N, 2 * H + 1)))
            assert np.max(np.abs((moved[0] - moved[1]) / 2e-7 - tangent[:, l])) <= 1e-6 * np.max(np.abs(tangent))
    assert errors[0] <= 1e-3 and errors[1] <= errors[0] / 10, errors


DAHL = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.02}, "dahl": {"sigma": 2.0, "force": 0.05}}
WITH_BRANCHES = {
    "dahl": DAHL,
    "delay and a branch": {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.02},
                           "branches": {"k": [1.0], "alpha": [0.1]}, "delay": {"gain": 0.05, "tau": 0.3}},
    "history and a branch": {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.05},
                             "branches": {"k": [1.0], "alpha": [0.1]},
                             "history": {"weight": [0.05], "rate": [2.0], "acts_on": "v"}},
}


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(WITH_BRANCHES))
def test_stable_points_with_memory_agree_with_the_time_sweep(case):
    """With H = 7 the curve's stable points agree with the time sweep (--method time: the implicit stepper with
    its memory, first order, refined to its tolerance 1e-3; 1e-4 takes it past 131072 steps a period) within
    twice that tolerance (the sweep's error estimate bounds its error by about the tolerance)."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.response import frequency_response

    scene = element(WITH_BRANCHES[case])
    curve = harmonic_response(scene, 0.1, [0.12, 0.25], harmonics=7)
    assert np.all(curve.stable)
    picks = [int(np.argmin(np.abs(curve.frequency - f))) for f in (0.14, 0.17, 0.21)]
    response = frequency_response(scene, 0.1, curve.frequency[picks], sweep="up", tolerance=1e-3)
    assert response.amplitude == pytest.approx(curve.amplitude[picks], rel=2e-3)
    assert response.phase == pytest.approx(curve.phase[picks], abs=2e-3)


@pytest.mark.slow
def test_a_point_marked_unstable_leaves_its_orbit_and_a_stable_one_keeps_it():
    """The orbit's state at t = 0 integrated period after period by the implicit stepper with its memory (the
    stability check's own runs, 2048 steps a period): a delay of gain -1.5 (multiplier about 12) leaves it
    within 10 periods; a delay of gain 0.05 on a mass with a branch keeps it."""
    from prandtl_fmu.frequency.floquet import _memory_period, multipliers
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    omega = 2 * math.pi * 0.15
    for tables, leaves in ((dict(OSCILLATOR, delay={"gain": -1.5, "tau": 0.7}), True),
                           (WITH_BRANCHES["delay and a branch"], False)):
        balance = HarmonicBalance(periodic_system(element(tables)), 7, 0.1)
        q = balance.solve_at(omega)
        assert (np.max(np.abs(multipliers(balance, q, omega))) > 1.01) == leaves
        run, state, _ = _memory_period(balance, q, omega, 2048)
        moved = state.copy()
        for _ in range(10):
            moved = run(moved)
        away = abs(moved[0] - state[0]) / np.max(np.abs(balance.full(q)))
        assert (away > 0.5) if leaves else (away < 2e-3), away


def test_the_command_line_runs_the_harmonic_balance_with_a_history(tmp_path):
    """describe SCENE --force-amplitude --frequencies on a scene with a [history]: the curve with its stability
    (every point computed is stable: c w exceeds the history's negative damping w_j w / (r_j^2 + w^2))."""
    out = tmp_path / "curve.csv"
    scene = write(tmp_path, {**OSCILLATOR, "damper": {"c": 0.2}, "history": {"weight": [0.3], "rate": [2.0]}})
    assert main(["describe", scene, "--force-amplitude", "0.1", "--frequencies", "0.1,0.2", "--harmonics", "1",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    assert list(table)[:4] == ["frequency", "amplitude", "phase", "stable"] and set(table["stable"]) == {"true"}
    w = 2 * math.pi * np.array(table["frequency"], dtype=float)
    expected = 0.1 / np.abs(1.0 - w**2 + 0.2j * w + 0.3 / (2.0 + 1j * w))
    assert np.array(table["amplitude"], dtype=float) == pytest.approx(expected, rel=1e-10)


@pytest.mark.slow
@pytest.mark.parametrize("tables", [{"delay": {"gain": 0.05, "tau": 0.3}}, {"dahl": DAHL["dahl"]}])
def test_the_command_line_runs_the_harmonic_balance_with_a_delay_or_dahl(tmp_path, tables):
    out = tmp_path / "curve.csv"
    scene = write(tmp_path, {**OSCILLATOR, **tables})
    assert main(["describe", scene, "--force-amplitude", "0.1", "--frequencies", "0.1,0.2", "--out", str(out)]) == 0
    table = read_csv(out)
    assert set(table["stable"]) <= {"true", "false"} and len(table["frequency"]) > 3


def test_a_history_of_rate_0_is_refused_in_one_line(tmp_path, capsys):
    out = tmp_path / "out.csv"
    scene = write(tmp_path, {**OSCILLATOR, "history": {"weight": [0.3, 0.1], "rate": [2.0, 0.0]}})
    assert main(["describe", scene, "--force-amplitude", "0.1", "--frequencies", "0.1,0.2", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "rate 0" in err and "--method time" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("acts_on", ["x", "v"])
def test_far_below_the_resonance_the_largest_multiplier_is_the_characteristic_root_s(acts_on):
    """Far below the resonance backward Euler shrinks the oscillator's multiplier by about exp(-(2 pi omega_n /
    omega)^2 / 2 M) a period (M steps): at omega_n / omega = 5.3 and 8, 256 steps shrink it by e^-2.2 and e^-4.9.
    The extrapolation in the multipliers' logarithm and the refinement while that shrinking is large give the
    value, not only the verdict: exp(Re(s) T), s the root of s^2 + c s + k + g s^j e^(-s tau) = 0 near i (a delay
    of gain 0.02 on x, j = 0, or on v, j = 1), to 2e-3 (it was 0.30 and 0.064 for 0.54 and 0.39 on x, 0.19 and
    0.031 for 0.33 and 0.19 on v)."""
    from prandtl_fmu.frequency.floquet import multipliers
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    on_v = acts_on == "v"
    balance = HarmonicBalance(periodic_system(element({**OSCILLATOR, "delay": {
        "gain": 0.02, "tau": 0.7, "acts_on": acts_on}})), 3, 0.1)
    s = 1j
    for _ in range(50):
        e = 0.02 * np.exp(-0.7 * s)
        s -= ((s * s + 0.05 * s + 1 + e * s) / (2 * s + 0.05 + e * (1 - 0.7 * s)) if on_v else
              (s * s + 0.05 * s + 1 + e) / (2 * s + 0.05 - 0.7 * e))
    for ratio in (5.3, 8.0):
        omega = 1.0 / ratio
        largest = float(np.max(np.abs(multipliers(balance, balance.solve_at(omega), omega))))
        assert largest == pytest.approx(math.exp(s.real * 2 * math.pi / omega), rel=2e-3)


def test_the_restarted_arnoldi_finds_the_largest_of_a_crowded_spectrum(monkeypatch):
    """floquet.arnoldi on a real matrix of 600 whose 200 largest eigenvalues crowd near 1 as a long delay's
    multipliers do (complex pairs (0.999 - 2e-4 j) exp(+-0.03 i j), j = 1 ... 100; the rest below 0.3) in a
    non-orthogonal basis: the 8 largest (j = 1 ... 4) are found to 1e-7, with more products than
    its basis holds (740: the Krylov-Schur restarts at work); with a bound of 40 products it gives None, no
    guess."""
    from prandtl_fmu.frequency import floquet

    rng = np.random.default_rng(3)
    n = 600
    blocks = np.zeros((n, n))
    for j in range(1, 101):
        radius, angle = 0.999 - 2e-4 * j, 0.03 * j
        i = 2 * (j - 1)
        blocks[i:i + 2, i:i + 2] = radius * np.array([[math.cos(angle), -math.sin(angle)],
                                                      [math.sin(angle), math.cos(angle)]])
    blocks[200:, 200:] = np.diag(rng.uniform(-0.3, 0.3, n - 200))
    basis = np.eye(n) + 0.3 * rng.standard_normal((n, n)) / math.sqrt(n)
    matrix = basis @ blocks @ np.linalg.inv(basis)
    products = []

    def product(w):
        products.append(1)
        return matrix @ w

    found = floquet.arnoldi(product, n, 8)
    exact = [(0.999 - 2e-4 * j) * np.exp(sign * 0.03j * j) for j in range(1, 5) for sign in (1, -1)]
    assert len(products) > 2 * floquet.KRYLOV_BASIS
    assert np.sort_complex(found) == pytest.approx(np.sort_complex(exact), abs=1e-7)
    monkeypatch.setattr(floquet, "KRYLOV_RUNS", 40)
    assert floquet.arnoldi(product, n, 8) is None


def rightmost_root(gain: float, tau: float) -> complex:
    """The rightmost root of l^2 + 0.05 l + 1 + g e^(-l tau) = 0 (the oscillator's perturbations under a delay
    on x), by Newton's method from every point of a grid over -0.3 <= Re l <= 0.3, 0 <= Im l <= 3: with a long
    delay the roots are many (about tau / 2 pi of them per unit of Im l), and the rightmost is not the one
    nearest the undelayed root."""
    re, im = np.meshgrid(np.linspace(-0.3, 0.3, 61), np.linspace(0.0, 3.0, 301))
    root = (re + 1j * im).ravel()
    with np.errstate(all="ignore"):
        for _ in range(100):
            root = root - (root**2 + 0.05 * root + 1.0 + gain * np.exp(-root * tau)) / (
                2.0 * root + 0.05 - gain * tau * np.exp(-root * tau))
        found = root[np.isfinite(root) & (np.abs(root**2 + 0.05 * root + 1.0 + gain * np.exp(-root * tau)) < 1e-10)]
    return complex(found[np.argmax(found.real)])


@pytest.mark.parametrize("gain", [pytest.param(0.05, marks=pytest.mark.slow), 0.2])
def test_a_long_delay_s_multipliers_are_the_delay_equation_s(tmp_path, gain):
    """A delay of 30 s (3 to 4 periods, a buffer of 1500 to 12 000 values at the steps the stability check
    takes, once one run a value): the largest multiplier, by Arnoldi's iteration on the period map, is the
    linear delay equation's exp(Re(lambda) T), lambda its rightmost root (:func:`rightmost_root`), to 5e-3 at
    every point of the curve, from the command line; every point stable where Re(lambda) < 0 (g = 0.05), none
    where the delay pumps energy in (g = 0.2: Re(lambda) = +0.0094, and a second pair at +0.0090)."""
    from prandtl_fmu.frequency.floquet import MAX_DELAY_STATES, STEPS

    assert 30.0 / (1.0 / (0.1 * 2 * STEPS)) < MAX_DELAY_STATES
    out = tmp_path / "curve.csv"
    scene = write(tmp_path, {**OSCILLATOR, "delay": {"gain": gain, "tau": 30.0}})
    assert main(["describe", scene, "--force-amplitude", "0.1", "--frequencies", "0.1,0.14", "--harmonics", "1",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    root = rightmost_root(gain, 30.0)
    frequency = np.array(table["frequency"], dtype=float)
    assert frequency.size > 3
    assert np.array(table["multiplier"], dtype=float) == pytest.approx(np.exp(root.real / frequency), rel=5e-3)
    assert set(table["stable"]) == {"true" if root.real < 0 else "false"}


@pytest.mark.slow
def test_a_one_harmonic_nonlinear_mode_on_dahl_is_its_describing_function():
    """m x'' + c x' + k0 x + F_d: with one harmonic the EPMC frequency is sqrt(K(A) / m) and the damping ratio
    D(A) / (2 pi K A^2) + c / (2 m omega), K and D describe's quadrature of Dahl's cycle (an independent
    computation: the element's drive kernel, cycles repeated until they settle)."""
    from prandtl_fmu.frequency.describing import describe_amplitudes
    from prandtl_fmu.frequency.modes import nonlinear_mode

    amplitudes = [0.002, 0.02, 0.2, 2.0]
    backbone = nonlinear_mode(element(DAHL), 1, amplitudes, harmonics=1, samples=4096)
    tables = {name: DAHL[name] for name in ("spring", "dahl")}
    described = describe_amplitudes(element(tables), amplitudes, tolerance=1e-7)
    K, D, A = np.asarray(described.stiffness), np.asarray(described.dissipation), np.asarray(amplitudes)
    omega = np.sqrt(K / 1.0)
    assert backbone.frequency == pytest.approx(omega / (2 * math.pi), rel=1e-5)
    assert backbone.damping_ratio == pytest.approx(D / (2 * math.pi * K * A * A) + 0.02 / (2 * omega), rel=1e-4)


def test_a_narrow_fold_pair_is_found_whatever_frequencies_are_listed():
    """A belt with a history at F0 = 0.5 N has two narrow loops between 0.07 and 0.12 Hz (folds 0.0902 and
    0.0895 Hz, 0.4 m; 0.10281 and 0.10279 Hz, 0.5 m). Asked for 0.07 and 0.12 Hz alone, the continuation's largest
    step was 0.75 of scaled arc length: it went from 0.07 to 0.103 Hz in one step, no fold, every point stable,
    while a listing of 41 frequencies found both loops. The curve must not depend on the listing: the same folds
    either way, and the points between each pair of folds (the middle branch) unstable, the others stable."""
    from prandtl_fmu.frequency.curve import harmonic_response

    scene = element({"mass": {"m": 1.0}, "spring": {"k0": 1.3}, "damper": {"c": 0.1},
                     "friction": {"alpha": 0.3, "belt_velocity": 0.2}, "branches": {"k": [0.5], "alpha": [0.05]},
                     "history": {"weight": [0.2], "rate": [0.5]}})
    curves = [harmonic_response(scene, 0.5, listing) for listing in ([0.07, 0.12], np.linspace(0.07, 0.12, 41))]
    for curve in curves:
        assert curve.folds.size == 4
        inside = np.zeros(curve.frequency.size, bool)
        for first, second in curve.folds.reshape(2, 2):
            inside[first + 1:second] = True
        assert np.all(~curve.stable[inside])
        outside = ~inside
        outside[curve.folds] = False  # a fold's multiplier is 1 to rounding
        assert np.all(curve.stable[outside])
    coarse, fine = curves
    assert coarse.frequency[coarse.folds] == pytest.approx(fine.frequency[fine.folds], rel=1e-9)
    assert coarse.amplitude[coarse.folds] == pytest.approx(fine.amplitude[fine.folds], rel=1e-7)
    assert 0.0895 < coarse.frequency[coarse.folds[1]] < coarse.frequency[coarse.folds[0]] < 0.0902


def test_dahl_s_friction_forced_beyond_den_hartog_s_bound_is_refused_before_the_curve_starts(tmp_path, capsys):
    """Dahl's force stays within its level on a periodic state, so Den Hartog's bound holds with it: the belt
    tensioner (2e-3 kg m^2 on 25 N m/rad, Dahl's level 1.5 N m, no dashpot) forced with 3 N m over its natural
    17.794 Hz, beyond 4 / pi 1.5 = 1.90986, has no periodic state there (it was refused at 17.794 Hz as a
    "branch point"): refused before it starts, in one line with the bound; 0.99 of the bound is not refused
    there."""
    from prandtl_fmu.frequency import read_scene
    from prandtl_fmu.frequency.unbounded import refuse_unbounded

    natural = math.sqrt(25.0 / 2e-3) / (2 * math.pi)
    bound = 4 / math.pi * 1.5
    scene, _ = read_scene("belt-tensioner")
    refuse_unbounded(scene, 0.99 * bound, None, 2 * math.pi * 5.0, 2 * math.pi * 40.0)  # no refusal
    out = tmp_path / "curve.csv"
    assert main(["describe", "belt-tensioner", "--force-amplitude", "3", "--frequencies", "5,40",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and not out.exists(), err
    assert f"no periodic state at f = {natural:.6g} Hz" in err and f"below {bound:.6g} " in err, err
