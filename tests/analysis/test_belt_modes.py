"""Nonlinear modes of a mass with friction on a moving belt (``slider_modes.FreeElement`` on the whole period,
``_follow_family`` past the kink where the mass first reaches the belt's speed): the linear mode while the mass
slides one way, the mode's orbit against an independent integration, and the stick-slip limit cycle that a
Stribeck drop excites at the zero of the mode's damping."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main

from tests.analysis.test_belt_shooting import belt_reference
from tests.analysis.test_describe_cli import read_csv, write
from tests.analysis.test_harmonic_balance import element

# m, k0, c, alpha, alpha_k, v_s, V: steady sliding is unstable (c < (alpha - alpha_k) / v_s exp(-V / v_s))
STRIBECK = (1.0, 1.0, 0.01, 0.3, 0.2, 0.1, 0.1)


def stribeck_scene():
    m, k0, c, alpha, alpha_k, vs, V = STRIBECK
    return {"mass": {"m": m}, "spring": {"k0": k0}, "damper": {"c": c},
            "friction": {"alpha": alpha, "alpha_kinetic": alpha_k, "stribeck_velocity": vs, "belt_velocity": V}}


@pytest.mark.parametrize("belt", [0.2, pytest.param(-0.2, marks=pytest.mark.slow)])
def test_a_mode_on_a_belt_while_the_mass_slides_one_way_is_the_linear_mode(belt):
    """Coulomb friction on a belt at V, a spring, a dashpot and a branch: while A omega < |V| (and the branch
    sticks) the friction is a constant force, so the mode is the linear one about the drag's offset at every
    such amplitude: frequency sqrt((k0 + k) / m), damping ratio c / (2 m omega)."""
    from prandtl_fmu.frequency.modes import nonlinear_mode

    scene = element({"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.1},
                     "friction": {"alpha": 0.3, "belt_velocity": belt}, "branches": {"k": [0.5], "alpha": [0.05]}})
    omega = math.sqrt(1.5)
    backbone = nonlinear_mode(scene, 1, [0.02, 0.05, 0.09])  # below eta = 0.1 and |V| / omega = 0.163
    assert backbone.frequency == pytest.approx(np.full(3, omega / (2 * math.pi)), rel=1e-9)
    assert backbone.damping_ratio == pytest.approx(np.full(3, 0.1 / (2 * omega)), rel=1e-8)


def _run(damping, x, v, span, samples):
    """The free motion m x'' + damping x' + k0 x + friction on the belt (``belt_reference``: independent of the
    library) from (x, v) over ``span`` s: x at ``samples`` equal steps (the start's included), and (x, v) at the
    end."""
    m, k0, _, alpha, alpha_k, vs, V = STRIBECK
    t, u, xs = 0.0, np.zeros(0), []
    for _ in range(samples):
        xs.append(x)
        x, v, u = belt_reference(m, k0, damping, 0.0, alpha, alpha_k, vs, V, np.zeros(0), np.zeros(0), 0.0, 1.0,
                                 x, v, u, t + span / samples, t=t, max_step=0.05)
        t += span / samples
    return np.array(xs), (x, v)


def _first_harmonic(xs) -> float:
    return float(abs(2.0 * np.fft.rfft(xs)[1] / xs.size))


@pytest.mark.slow
def test_the_zero_of_a_belt_mode_s_damping_is_the_stick_slip_limit_cycle():
    """A Stribeck drop on a belt makes steady sliding unstable (negative damping c - (alpha - alpha_k) / v_s
    exp(-V / v_s)): the mass settles onto a stick-slip limit cycle. Where the mode's damping ratio is 0, its
    orbit is a periodic motion of the scene itself: integrated independently from the belt's speed, the cycle's
    period (between its crossings of its mid-level upwards) is the mode's 1 / f at the cycle's first harmonic,
    where the damping ratio vanishes. Below, the ratio tends to the linearised sliding's (c - d) / (2 m omega);
    above, it is positive (the cycle attracts)."""
    from prandtl_fmu.frequency.modes import nonlinear_mode

    m, k0, c, alpha, alpha_k, vs, V = STRIBECK
    _, (x, v) = _run(c, 0.25, V, 400.0, 40)  # 55 periods of about 7.3 s
    xs, _ = _run(c, x, v, 22.0, 4400)  # three periods at 200 samples each
    mid = 0.5 * (xs.min() + xs.max())
    up = np.flatnonzero((xs[:-1] < mid) & (xs[1:] >= mid))
    times = 0.005 * (up + (mid - xs[up]) / (xs[up + 1] - xs[up]))
    periods = np.diff(times)
    assert periods.size >= 2 and np.ptp(periods) <= 1e-6 * periods[0]  # settled
    period = float(periods[0])
    cycle, (x1, v1) = _run(c, x, v, period, 512)
    assert abs(x1 - x) <= 1e-5 * np.ptp(cycle)  # periodic over that period
    amplitude = _first_harmonic(cycle)
    backbone = nonlinear_mode(element(stribeck_scene()), 1, [0.02, amplitude, 0.3])
    assert backbone.frequency[1] == pytest.approx(1.0 / period, rel=1e-4)
    assert abs(backbone.damping_ratio[1]) <= 1e-4  # the zero (the ratio changes by 3 per metre of amplitude)
    d = (alpha - alpha_k) / vs * math.exp(-V / vs)
    assert backbone.damping_ratio[0] == pytest.approx((c - d) / (2 * m * math.sqrt(k0 / m)), rel=2e-2)
    assert backbone.damping_ratio[2] > 0.02


def test_a_belt_mode_from_the_command_line(tmp_path):
    """`describe --mode 1` on a belt (refused before: no mode symmetric over half a period): the columns of the
    contract, the damping ratio negative while the drop feeds the sliding, positive past the limit cycle."""
    out = tmp_path / "mode.csv"
    assert main(["describe", write(tmp_path, stribeck_scene()), "--mode", "1", "--amplitudes", "0.05,0.3",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    assert list(table)[:3] == ["amplitude", "frequency", "damping_ratio"]
    ratio = [float(value) for value in table["damping_ratio"]]
    assert ratio[0] < 0 < ratio[1]
