"""Nonlinear modes (EPMC) of a network with rigid sliders, by shooting on its exact motion
(``frequency/slider_modes.py``): a node on a spring and a slider is a closed form at every amplitude, two masses
that a slider locks together are one linear mode, the command line writes the contract's columns, and a backbone
that turns back in amplitude is refused in one line where it does."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main
from prandtl_fmu.frequency import FrequencyError

from tests.analysis.test_describe_cli import read_csv
from tests.analysis.test_harmonic_balance_network_friction import ONE_NODE, TWO_MASSES, network


def slipping_mode(A, a, omega0):
    """The EPMC orbit of a mass on a spring k and a slider alpha to the ground (a = alpha / k, omega0^2 = k / m)
    through the peak A > a: while it slides down, x'' - xi x' + omega0^2 x = omega0^2 a, from rest at A to rest
    at -A in half a period pi / omega_d, omega_d^2 = omega0^2 - xi^2 / 4:
    x = a + (A - a) e^(xi t / 2) (cos omega_d t - xi / (2 omega_d) sin omega_d t), so e^(xi pi / (2 omega_d)) =
    (A + a) / (A - a). With r = ln((A + a) / (A - a)): omega_d = omega0 / sqrt(1 + r^2 / pi^2), damping ratio
    xi / (2 omega_d) = r / pi. Returns (omega_d, damping ratio, the first harmonic's amplitude of that orbit
    by a quadrature of 2^16 points)."""
    r = math.log((A + a) / (A - a))
    omega_d = omega0 / math.sqrt(1 + r * r / math.pi**2)
    xi = 2 * r * omega_d / math.pi
    t = np.arange(2**15) * (math.pi / omega_d) / 2**15
    half = a + (A - a) * np.exp(xi * t / 2) * (np.cos(omega_d * t) - xi / (2 * omega_d) * np.sin(omega_d * t))
    x = np.concatenate((half, -half))
    first = x @ np.exp(-1j * omega_d * np.concatenate((t, t + math.pi / omega_d))) * 2 / x.size
    return omega_d, r / math.pi, abs(first)


@pytest.mark.slow
def test_a_node_on_a_spring_and_a_slider_is_its_closed_form_mode(tmp_path):
    """ONE_NODE (m = 1, k = 1, alpha = 0.1): at every amplitude the frequency and the damping ratio of the
    exact orbit (the function above), to 1e-6."""
    from prandtl_fmu.frequency.modes import nonlinear_mode

    scene = network(tmp_path, ONE_NODE)
    closed = [slipping_mode(A, 0.1, 1.0) for A in (0.15, 0.3, 1.0, 5.0)]
    backbone = nonlinear_mode(scene, 1, [c[2] for c in closed], tolerance=1e-7)
    assert backbone.harmonics is None and backbone.node == "a"
    for (omega_d, ratio, _), frequency, damping in zip(closed, backbone.frequency, backbone.damping_ratio):
        assert frequency == pytest.approx(omega_d / (2 * math.pi), rel=1e-6)
        assert damping == pytest.approx(ratio, rel=1e-6)


@pytest.mark.slow
def test_two_masses_a_slider_locks_together_are_one_linear_mode_until_it_slips(tmp_path):
    """scenes/networks/two-masses-slider.toml: while the slider holds (its force (k_total / m_total - k_a / m_a)
    m_a A below alpha = 2 N, A < 0.03 m) the masses are one: omega^2 = (100 + 400) / 3, damping ratio
    (0.5 / 3) / (2 omega), to 1e-9; past it the joint's friction damps the mode more (the command line)."""
    from prandtl_fmu.frequency.modes import nonlinear_mode
    from prandtl_fmu.scene import load_scene
    from prandtl_fmu.catalog import scene_path

    scene = load_scene(str(scene_path(TWO_MASSES)))
    omega = math.sqrt(500 / 3)
    backbone = nonlinear_mode(scene, 1, [0.001, 0.01, 0.025])
    assert backbone.frequency == pytest.approx(np.full(3, omega / (2 * math.pi)), rel=1e-9)
    assert backbone.damping_ratio == pytest.approx(np.full(3, 0.5 / 3 / (2 * omega)), rel=1e-9)
    out = tmp_path / "mode.csv"
    assert main(["describe", TWO_MASSES, "--mode", "1", "--amplitudes", "0.01,0.04", "--out", str(out)]) == 0
    table = read_csv(out)
    assert list(table)[:3] == ["amplitude", "frequency", "damping_ratio"]
    ratio = [float(value) for value in table["damping_ratio"]]
    assert ratio[0] == pytest.approx(0.5 / 3 / (2 * omega), rel=1e-9) and ratio[1] > 3 * ratio[0]


@pytest.mark.slow
def test_the_two_masses_backbone_is_the_family_from_the_locked_mode(tmp_path, capsys):
    """The two masses' mode 1, followed from the locked linear mode without an amplitude condition: past slip
    onset it becomes mass b's own oscillation (omega_b = sqrt(k_b / m_b)), mass a driven by the joint's bounded
    force, so node a's first harmonic turns back and then tends to 4 (alpha + k eta) / (pi |k_a - m_a
    omega_b^2|) = 0.0382 m. At node a, 0.04 m is several points of the family, one row each, between the two
    masses' own frequencies and more damped than the locked mode (the joint dissipates); an amplitude above what
    node a reaches is refused in one line that says the most it reaches (above the limit, below the amplitude
    asked), exit 2, nothing written. At node b the backbone tends to b's own frequency and a's amplitude to the
    limit above."""
    import re

    from prandtl_fmu.frequency.modes import nonlinear_mode
    from prandtl_fmu.scene import load_scene
    from prandtl_fmu.catalog import scene_path

    scene = load_scene(str(scene_path(TWO_MASSES)))
    omega_a, omega_b, locked = math.sqrt(100.0), math.sqrt(400.0 / 2.0), math.sqrt(500.0 / 3.0)
    limit = 4 * (2.0 + 50.0 * 0.02) / (math.pi * abs(100.0 - 1.0 * omega_b**2))
    at_a = nonlinear_mode(scene, 1, [0.01, 0.04], node="a")
    assert at_a.amplitude[0] == 0.01 and np.all(at_a.amplitude[1:] == 0.04) and at_a.amplitude.size >= 3
    omega = 2 * math.pi * at_a.frequency[1:]
    assert np.all((omega_a < omega) & (omega < omega_b)) and np.min(np.abs(np.diff(omega))) > 1e-3 * omega_b
    assert np.all(at_a.damping_ratio[1:] > 0.5 / 3 / (2 * locked))

    out = tmp_path / "mode.csv"
    assert main(["describe", TWO_MASSES, "--mode", "1", "--amplitudes", "0.01,0.05", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "A = 0.05 m" in err and "does not reach" in err, err
    most = float(re.search(r"at most (\S+) m", err).group(1))
    assert limit < most < 0.05 and not out.exists()

    # just below the limit the family passes again far out, beyond where it is followed: refused, not answered
    # without that point
    with pytest.raises(FrequencyError, match="may pass that amplitude again further out"):
        nonlinear_mode(scene, 1, [0.99 * limit], node="a")

    at_b = nonlinear_mode(scene, 1, [0.01, 0.03, 0.05, 0.2, 0.5], node="b")
    assert at_b.amplitude.size == 5
    assert at_b.frequency[-1] == pytest.approx(omega_b / (2 * math.pi), rel=1e-3)
    assert abs(at_b.shape[-1, 0]) * 0.5 == pytest.approx(limit, rel=0.03)
