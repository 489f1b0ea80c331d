"""Friction on the mass beside ``[delay]`` (refused before): shooting on the Taylor orbit with the delay's force
on the periodic orbit as unknowns, its odd harmonics (``frequency/shooting.py``, ``ElementShooting``). Checked
against the linear closed form where the friction vanishes, against the time sweep where it sticks and slides,
and the harmonics of the delay's force as they converge."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main

from tests.analysis.test_describe_cli import read_csv, write
from tests.analysis.test_harmonic_balance import element

DELAYED = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.05}, "friction": {"alpha": 0.1},
           "delay": {"gain": -0.2, "tau": 0.5}}


SLOW = pytest.mark.slow  # the quick suite keeps one case of each (its time on a cold cache: README)


@pytest.mark.parametrize("acts_on, gain, stuck", [("x", -0.2, 0.0), pytest.param("v", 0.1, 0.0, marks=SLOW),
                                                  pytest.param("x", 0.2, 0.5, marks=SLOW)])
def test_friction_beside_a_delay_is_the_linear_closed_form_where_the_friction_vanishes(acts_on, gain, stuck):
    """With a friction of 1e-9 N against a force of 1 N every point of the curve is the linear oscillator's with
    the delay's transfer function, X = F / (k - m w^2 + i c w + g e^(-i w tau) (1 on x, i w on v)), to 1e-7 in
    amplitude and phase; also beside a branch whose range (100 m) the motion never reaches (``stuck``: its k adds
    to k), which made the slide's end overshoot by 1e-12 of its range times the delay's fastest harmonic (a
    review's find: the error doubled with the delay's harmonics and the tolerance was never met)."""
    from prandtl_fmu.frequency.curve import harmonic_response

    tau = 0.5
    tables = dict(DELAYED, friction={"alpha": 1e-9}, delay={"gain": gain, "tau": tau, "acts_on": acts_on})
    if stuck:
        tables["branches"] = {"k": [stuck], "alpha": [100.0 * stuck]}
    curve = harmonic_response(element(tables), 1.0, [0.05, 0.4], tolerance=1e-9)
    assert curve.method == "shooting" and curve.orbit == "Taylor series" and len(curve.frequency) > 10
    omega = 2.0 * math.pi * curve.frequency
    y = np.ones_like(omega) if acts_on == "x" else 1j * omega
    X = 1.0 / (1.0 + stuck - omega**2 + 0.05j * omega + gain * y * np.exp(-1j * omega * tau))
    assert np.allclose(curve.amplitude, np.abs(X), rtol=1e-7, atol=0)
    assert np.allclose(curve.phase, np.angle(X), rtol=0, atol=1e-7)


@SLOW
def test_friction_beside_a_delay_is_the_time_sweep_s_curve(tmp_path):
    """Where the mass sticks for part of each period (0.1 Hz) and where it slides through (0.3 Hz), from the
    command line: the curve's ends are the time sweep's first harmonic (implicit, to 1e-4) within 2e-4 in
    amplitude and phase; every point is stable (the sweep settles there too)."""
    table = ends_are_the_time_sweep_s(tmp_path, DELAYED, "0.3", "0.1,0.3", "1e-4", 2e-4)
    assert set(table["stable"]) == {"true"} and all(0.0 < float(m) < 1.0 for m in table["multiplier"])


def ends_are_the_time_sweep_s(tmp_path, tables, force, frequencies, sweep_tolerance, within) -> dict:
    """The curve of ``tables`` from the command line (tolerance 1e-5) against the time sweep's (`--method time`
    at ``sweep_tolerance``) at both ends: amplitude within ``within`` relative, phase within ``within`` rad.
    Returns the curve's table."""
    scene = write(tmp_path, tables)
    curve, sweep = tmp_path / "curve.csv", tmp_path / "sweep.csv"
    assert main(["describe", scene, "--force-amplitude", force, "--frequencies", frequencies, "--tolerance", "1e-5",
                 "--out", str(curve)]) == 0
    assert main(["describe", scene, "--force-amplitude", force, "--frequencies", frequencies, "--method", "time",
                 "--tolerance", sweep_tolerance, "--out", str(sweep)]) == 0
    table, reference = read_csv(curve), read_csv(sweep)
    for row in (0, -1):
        f = float(table["frequency"][row])
        at = [i for i, g in enumerate(reference["frequency"]) if abs(float(g) - f) <= 1e-12 * f][0]
        A, B = float(table["amplitude"][row]), float(reference["amplitude"][at])
        assert abs(A - B) <= within * B, (f, A, B)
        assert abs(float(table["phase"][row]) - float(reference["phase"][at])) <= within, f
    return table


def rightmost_root(gain, tau, acts_on) -> complex:
    """The root of l^2 + 0.05 l + 1 + g (1 on x, l on v) e^(-l tau) = 0 by Newton from the undelayed one (m = k
    = 1, c = 0.05): the rightmost, for the delays here."""
    root = -0.025 + 1j * math.sqrt(1.0 - 0.025**2)
    for _ in range(50):
        y, dy = (1.0, 0.0) if acts_on == "x" else (root, 1.0)
        root -= (root**2 + 0.05 * root + 1.0 + gain * y * np.exp(-root * tau)) / \
            (2.0 * root + 0.05 + gain * (dy - tau * y) * np.exp(-root * tau))
    assert abs(root**2 + 0.05 * root + 1.0 + gain * (1.0 if acts_on == "x" else root) * np.exp(-root * tau)) < 1e-12
    return root


@pytest.mark.parametrize("gain, acts_on", [(-0.2, "x"), pytest.param(0.2, "x", marks=SLOW),
                                           pytest.param(0.1, "v", marks=SLOW), pytest.param(-0.1, "v", marks=SLOW)])
def test_the_multipliers_beside_a_delay_are_the_delay_equation_s_where_the_friction_vanishes(gain, acts_on):
    """With a friction of 1e-9 N the perturbations obey the linear delay equation m x'' + c x' + k x + g y(t -
    tau) = 0, whose largest Floquet multiplier over a period T is exp(Re(lambda) T), lambda its rightmost root
    of m l^2 + c l + k + g (1, or l) e^(-l tau) = 0 (Newton from the undelayed root): at every point of the
    curve to 1e-3, stable where Re(lambda) < 0 and unstable where the delay makes it > 0 (g > 0 on x, g < 0 on v:
    a negative damping near the resonance)."""
    from prandtl_fmu.frequency.curve import harmonic_response

    tau = 0.5
    scene = element(dict(DELAYED, friction={"alpha": 1e-9}, delay={"gain": gain, "tau": tau, "acts_on": acts_on}))
    curve = harmonic_response(scene, 1.0, [0.05, 0.4])
    root = rightmost_root(gain, tau, acts_on)
    expected = np.exp(root.real / curve.frequency)
    assert np.allclose(curve.multiplier, expected, rtol=1e-3, atol=0)
    assert set(curve.stable.tolist()) == {root.real < 0}


def test_a_delay_of_many_periods_beside_the_friction_has_the_delay_equation_s_multipliers():
    """tau = 30 s (3 to 4 periods, a buffer of 2000 values and more: Arnoldi's iteration on the period map, not
    a run per value) with a friction of 1e-9 N: the largest multiplier is exp(Re(lambda) T), lambda the rightmost
    root found from a grid (``test_harmonic_balance_memory.rightmost_root``: Re = +0.0094, a second pair at
    +0.0090), to 1e-3 at every point, and every point unstable."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from tests.analysis.test_harmonic_balance_memory import rightmost_root

    scene = element(dict(DELAYED, friction={"alpha": 1e-9}, delay={"gain": 0.2, "tau": 30.0}))
    curve = harmonic_response(scene, 1.0, [0.1, 0.14])
    assert curve.method == "shooting" and len(curve.frequency) > 5
    root = rightmost_root(0.2, 30.0)
    assert root.real > 0.0
    assert np.allclose(curve.multiplier, np.exp(root.real / curve.frequency), rtol=1e-3, atol=0)
    assert not np.any(curve.stable)


def test_a_point_the_delay_makes_unstable_is_not_where_the_time_sweep_goes(tmp_path):
    """A delay on x of gain +0.2 beside the friction: at 0.0898 Hz the symmetric orbit has a real multiplier
    1.19 (unstable), and the time sweep, from rest, settles on another motion (its first harmonic 0.6 % away,
    many times its error column); at 0.0988 Hz it is stable (0.25) and the sweep's, within that column."""
    scene = write(tmp_path, dict(DELAYED, delay={"gain": 0.2, "tau": 0.5}))
    curve, sweep = tmp_path / "curve.csv", tmp_path / "sweep.csv"
    assert main(["describe", scene, "--force-amplitude", "0.3", "--frequencies", "0.0898,0.0988", "--out",
                 str(curve)]) == 0
    assert main(["describe", scene, "--force-amplitude", "0.3", "--frequencies", "0.0898,0.0988", "--method", "time",
                 "--out", str(sweep)]) == 0
    table, reference = read_csv(curve), read_csv(sweep)
    assert table["stable"][0] == "false" and table["stable"][-1] == "true"
    assert 1.1 < float(table["multiplier"][0]) < 1.3 and float(table["multiplier"][-1]) < 0.5
    for row, stable in ((0, False), (-1, True)):
        f = float(table["frequency"][row])
        at = [i for i, g in enumerate(reference["frequency"]) if abs(float(g) - f) <= 1e-12 * f][0]
        A, B, error = float(table["amplitude"][row]), float(reference["amplitude"][at]), float(reference["error"][at])
        assert (abs(A - B) <= max(error, 1e-3) * B) if stable else (abs(A - B) > 2.0 * error * B), (f, A, B, error)


def test_the_delay_s_force_is_the_orbit_s_and_its_harmonics_converge():
    """At a point where the mass sticks: the unknowns of the delay's force are the odd harmonics of -g x(t - tau)
    of the orbit they drive (the residual's last block is their difference, 0 at the solution); with 7, 15, 31
    and 63 of them (and 64 to 512 samples) the first harmonic of x converges, each change at most half the one
    before."""
    from prandtl_fmu.frequency.shooting import ElementShooting, prepared

    scene = prepared(element(DELAYED))
    omega = 2.0 * math.pi * 0.1
    amplitudes, s, coarse = [], None, None
    for harmonics, steps in ((7, 64), (15, 128), (31, 256), (63, 512)):
        shooting = ElementShooting(scene, 0.3, None, steps, 7, 1.0, delay_harmonics=harmonics)
        assert shooting.dimension == 2 + harmonics + 1
        s = shooting.solve_at(omega) if s is None else shooting._newton(omega, coarse.padded(s, shooting))
        _, xs = shooting.run(s, omega)
        half = np.concatenate(([s[0]], xs[:-1, 0]))
        period = np.concatenate((half, -half))
        t = np.arange(steps) * 2.0 * math.pi / omega / steps
        p = np.arange(1, harmonics + 1, 2)
        # -g x(t - tau), its harmonics written out (a rectangle rule over the samples: x periodic, C^1)
        delayed = np.interp((t - 0.5) % (2.0 * math.pi / omega), np.append(t, 2.0 * math.pi / omega),
                            np.append(period, period[0]))
        a = 2.0 / steps * np.array([np.sum(0.2 * delayed * np.cos(q * omega * t)) for q in p])
        b = 2.0 / steps * np.array([np.sum(0.2 * delayed * np.sin(q * omega * t)) for q in p])
        unknowns = s[2:] * 0.2
        assert np.max(np.abs(unknowns[0::2] - a)) <= 0.02 * np.max(np.abs(a))  # the interpolation's error
        assert np.max(np.abs(unknowns[1::2] - b)) <= 0.02 * np.max(np.abs(a))
        assert np.max(np.abs(shooting.residual(s, omega))) <= 1e-9 * shooting.size(s, omega)
        amplitudes.append(shooting.amplitude_at(s, omega))
        coarse = shooting
    changes = np.abs(np.diff(amplitudes))
    assert np.all(changes[1:] <= 0.5 * changes[:-1]), amplitudes


@SLOW
def test_a_delay_too_short_for_the_stability_s_grid_leaves_it_unknown_and_says_so(tmp_path, capsys):
    """tau = 1e-6 s at 0.1 Hz: the semi-discretised delay would need 1e7 steps a period (its grid at most tau):
    past its bound (shooting.DELAY_MAX_STEPS) the stability is not computed, quickly: every `stable` empty, and
    one warning line says so, and the plot draws it dotted ("stability not computed"); the curve itself is the
    delay's."""
    import importlib.util
    import time

    out, plot = tmp_path / "curve.csv", tmp_path / "curve.png"
    arguments = ["describe", write(tmp_path, dict(DELAYED, delay={"gain": 0.2, "tau": 1e-6})), "--force-amplitude",
                 "0.3", "--frequencies", "0.1,0.2", "--out", str(out)]
    if importlib.util.find_spec("matplotlib") is not None:
        arguments += ["--plot", str(plot)]
    start = time.perf_counter()
    assert main(arguments) == 0
    assert time.perf_counter() - start < 120.0
    assert "--plot" not in arguments or plot.read_bytes()[:4] == b"\x89PNG"
    table = read_csv(out)
    assert set(table["stable"]) == {""} and set(table["multiplier"]) == {""}
    warnings = [line for line in capsys.readouterr().err.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1 and "not computed" in warnings[0]


def test_a_mass_held_at_rest_by_its_friction_beside_a_delay_is_stable(tmp_path):
    """The delay-oscillator scene's element (its linear part unstable: s^2 + 0.1 s + 4 + e^(-0.6 s) has the
    root 0.157 + 2.08 i) under F0 = 0.02 N, below its friction's 0.05 N: the mass stays at rest at every
    frequency, and rest is stable (a perturbation within the friction's margin is held: the multipliers 1, the
    stuck positions, and 0). The delay's finite differences were scaled by the orbit's size, 0 there: a
    perturbation of 1e-306 m, the multipliers rounding over it (6e281, every point but the first unstable)."""
    out = tmp_path / "curve.csv"
    scene = write(tmp_path, {"mass": {"m": 1.0}, "spring": {"k0": 4.0}, "damper": {"c": 0.1},
                             "branches": {"k": [1.0, 0.5], "eta": [0.2, 0.6]}, "friction": {"alpha": 0.05},
                             "delay": {"gain": 1.0, "tau": 0.6}})
    assert main(["describe", scene, "--force-amplitude", "0.02", "--frequencies", "0.05,0.6", "--out",
                 str(out)]) == 0
    table = read_csv(out)
    assert len(table["frequency"]) >= 3 and {float(a) for a in table["amplitude"]} == {0.0}
    assert set(table["stable"]) == {"true"}
    assert np.array(table["multiplier"], dtype=float) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.slow
def test_the_delay_oscillator_s_curve_turns_back_at_each_slip_onset_and_goes_on():
    """scenes/delay-oscillator at F0 = 0.1 N: the curve meets the first branch's slip onset (its range eta = 0.2
    m: a centred branch slides once max |x| passes it) twice, at 0.3705 Hz going up and at 0.3854 Hz coming
    down, and turns back there on a corner (by 131 degrees: the far side's tangent points where no curve is; the
    corner's search takes its way on against it, ``continuation._around_corner``); the points past the finer
    curve's corner are left out (``shooting._solved_again``). The whole curve is drawn, 0.05 to 0.6 Hz, with a
    fold at each onset whose first harmonic is eta to its higher harmonics (1e-3), and a fold between them
    where a multiplier crosses 1."""
    from prandtl_fmu.frequency import read_scene
    from prandtl_fmu.frequency.curve import harmonic_response

    scene, _ = read_scene("delay-oscillator")
    curve = harmonic_response(scene, 0.1, [0.05, 0.6])
    assert curve.frequency[0] == pytest.approx(0.05) and curve.frequency[-1] == pytest.approx(0.6)
    folds = curve.folds
    onsets = [index for index in folds if abs(curve.amplitude[index] - 0.2) <= 2e-4]
    assert len(onsets) == 2, (curve.frequency[folds], curve.amplitude[folds])
    assert sorted(round(float(curve.frequency[index]), 4) for index in onsets) == [0.3705, 0.3854]
    # past each onset the branch slides: the curve reaches far above eta between them
    between = slice(min(onsets), max(onsets))
    assert np.max(curve.amplitude[between]) > 1.5 * 0.2


@pytest.mark.slow
@pytest.mark.parametrize("force, first, second", [(0.2, (0.09, 0.092), (0.088, 0.09)),
                                                  (0.3, (0.105, 0.107), (0.099, 0.101))])
def test_a_fold_that_a_finer_resolution_moves_is_found_on_the_normal_through_it(force, first, second):
    """scenes/delay-oscillator at F0 = 0.2 N: a fold pair near 0.09 Hz (the mass starts to slide on its
    friction). Doubling the delay's harmonics and the samples moves the first fold down by about 4e-4 of its
    frequency, so the fold point and the one after it exist at no frequency of theirs on the finer curve; on
    the normal through each (``continuation.across``) they are found, which a cap of a tenth of the tolerance
    refused (the whole curve with it). At 0.3 N the fold near 0.1063 Hz moves past the fold point and a point
    3e-6 of it away, too close together for the normal's guard: the finer curve is followed from the point
    before them to the one after (``continuation.bridge``). The curve reaches 0.6 Hz; between the two folds a
    point is unstable."""
    from prandtl_fmu.frequency import read_scene
    from prandtl_fmu.frequency.curve import harmonic_response

    scene, _ = read_scene("delay-oscillator")
    curve = harmonic_response(scene, force, [0.05, 0.6])
    assert curve.frequency[-1] == pytest.approx(0.6)
    low = [index for index in curve.folds if curve.frequency[index] < 0.11]
    assert len(low) == 2, curve.frequency[curve.folds]
    assert first[0] < curve.frequency[low[0]] < first[1] and second[0] < curve.frequency[low[1]] < second[1]
    assert not np.all(curve.stable[low[0]:low[1] + 1])


@pytest.mark.slow
def test_the_delay_oscillator_s_curve_turns_back_where_the_mass_starts_to_stick():
    """scenes/delay-oscillator at F0 = 0.5 N: near 0.1189 Hz the mass, sliding through each reversal until
    then, starts to stick there; the curve turns back on a corner by about 153 degrees, so sharp that every
    guess of the corner's search along the tangent lands on the way back, and the way on is found by Newton with
    that point deflated (``continuation._deflated``; refused before). Past the corner the curve goes back down
    to a second fold near 0.1100 Hz (the middle part, unstable), then up again, where the mass sticks for part
    of each period (stable, most of it): three symmetric periodic states between the folds. The whole curve is
    drawn to 0.6 Hz."""
    from prandtl_fmu.frequency import read_scene
    from prandtl_fmu.frequency.curve import harmonic_response

    scene, _ = read_scene("delay-oscillator")
    curve = harmonic_response(scene, 0.5, [0.05, 0.6])
    assert curve.frequency[-1] == pytest.approx(0.6)
    f = curve.frequency
    corner = [index for index in curve.folds if 0.1185 < f[index] < 0.1190]
    back = [index for index in curve.folds if 0.1098 < f[index] < 0.1101]
    assert len(corner) == 1 and len(back) == 1 and corner[0] < back[0], f[curve.folds]
    middle = slice(corner[0] + 1, back[0])
    assert np.all(np.diff(f[corner[0]:back[0] + 1]) < 0) and not np.any(curve.stable[middle])
    # at 0.115 Hz, three states: the sliding one below the corner, the middle one, the sticking one (stable)
    first = corner[0]
    while f[first - 1] < f[first]:
        first -= 1
    last = back[0]
    while f[last + 1] > f[last]:
        last += 1
    pieces = (slice(first, corner[0] + 1), slice(back[0], corner[0] - 1, -1), slice(back[0], last + 1))
    assert all(f[piece][0] < 0.115 < f[piece][-1] for piece in pieces)
    sliding, unstable, sticking = (np.interp(0.115, f[piece], curve.amplitude[piece]) for piece in pieces)
    assert unstable < sliding < sticking
    # mostly stable there (from about 0.1116 to 0.1131 Hz a real multiplier up to 1.036 passes 1: integrated,
    # the motion leaves for an unsymmetric periodic state off the curve)
    assert np.count_nonzero(curve.stable[back[0]:last + 1]) >= 0.75 * (last + 1 - back[0])


@pytest.mark.slow
def test_the_delay_oscillator_s_corner_at_0_15_n_is_passed_by_a_longer_deflated_search():
    """scenes/delay-oscillator at F0 = 0.15 N: at the first branch's slip onset near 0.3593 Hz the deflated
    search on the sphere needs 37 iterations (a review's find: refused there with 24); the curve goes on to
    0.6 Hz with a fold at the onset."""
    from prandtl_fmu.frequency import read_scene
    from prandtl_fmu.frequency.curve import harmonic_response

    scene, _ = read_scene("delay-oscillator")
    curve = harmonic_response(scene, 0.15, [0.05, 0.6])
    assert curve.frequency[-1] == pytest.approx(0.6)
    assert any(0.3590 < curve.frequency[index] < 0.3596 for index in curve.folds), curve.frequency[curve.folds]


@pytest.mark.slow
def test_a_bridge_whose_step_was_halved_grows_it_back_and_arrives():
    """scenes/delay-oscillator at F0 = 0.3 N listed from 0.05 to 1 Hz (the points fall elsewhere than from 0.05
    to 0.6): the finer resolution moves the fold near 0.1063 Hz past two points, and the bridge over them meets
    a kink that halves its step to a 128th of its chord; the step never grew back, 64 steps went half way, and
    the curve was refused there. Now it reaches 1 Hz, with the fold moved to about 0.10626 Hz."""
    from prandtl_fmu.frequency import read_scene
    from prandtl_fmu.frequency.curve import harmonic_response

    scene, _ = read_scene("delay-oscillator")
    curve = harmonic_response(scene, 0.3, [0.05, 1.0])
    assert curve.frequency[-1] == pytest.approx(1.0)
    assert any(0.1060 < curve.frequency[index] < 0.1064 for index in curve.folds), curve.frequency[curve.folds]
