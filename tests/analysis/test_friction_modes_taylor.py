"""Nonlinear modes (EPMC) of friction on the mass beside a Stribeck drop, a history or a delay (refused before):
the free element with damping c - xi m on its Taylor orbit (``slider_modes.FreeElement``; a delay's harmonics
are unknowns of s, as in the forced response). Checked against closed forms where the friction vanishes (the
linear mode of the memory: frequency and damping from its transfer function) and, for Stribeck's drop, against
Coulomb friction at the kinetic level as the drop's velocity goes to 0 (the network of one node: other code)."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from prandtl_fmu.cli import main

from tests.analysis.test_describe_cli import read_csv, write
from tests.analysis.test_harmonic_balance import element

LINEAR = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.05}, "friction": {"alpha": 1e-9}}


def _linear_mode(memory):
    """(frequency in Hz, damping ratio) of m x'' + (c - xi m) x' + k x + memory = 0 periodic at omega: k - m w^2
    + Re(M(w)) = 0 and w (c - xi m) + Im(M(w)) = 0, M(w) the memory's transfer function."""
    omega = brentq(lambda w: 1.0 - w * w + memory(w).real, 0.1, 3.0)
    xi = 0.05 + memory(omega).imag / omega
    return omega / (2.0 * math.pi), xi / (2.0 * omega)


SLOW = pytest.mark.slow  # the quick suite keeps one case (its time on a cold cache: README)


@pytest.mark.parametrize("kind, acts_on", [("delay", "x"), pytest.param("delay", "v", marks=SLOW),
                                           pytest.param("history", "x", marks=SLOW),
                                           pytest.param("history", "v", marks=SLOW)])
def test_the_mode_beside_a_memory_is_its_closed_form_where_the_friction_vanishes(kind, acts_on):
    """A delay g y(t - tau) (transfer g e^(-i w tau) (1, or i w)) or a history sum_j w_j (1, or i w) / (r_j + i w),
    on x and on v, with a friction of 1e-9 N: at two amplitudes the mode's frequency and damping ratio are the
    linear closed form's to 1e-6 (a delay on x that damps, a history on x that excites: zeta < 0)."""
    from prandtl_fmu.frequency.modes import nonlinear_mode

    y = (lambda w: 1.0) if acts_on == "x" else (lambda w: 1j * w)
    if kind == "delay":
        gain, tau = (-0.2, 0.5) if acts_on == "x" else (0.1, 0.5)
        tables = dict(LINEAR, delay={"gain": gain, "tau": tau, "acts_on": acts_on})
        frequency, ratio = _linear_mode(lambda w: gain * y(w) * np.exp(-1j * w * tau))
    else:
        weights, rates = [0.3, 0.1], [0.5, 2.0]
        tables = dict(LINEAR, history={"weight": weights, "rate": rates, "acts_on": acts_on})
        frequency, ratio = _linear_mode(lambda w: sum(a * y(w) / (r + 1j * w) for a, r in zip(weights, rates)))
    backbone = nonlinear_mode(element(tables), 1, [0.5, 1.0])
    assert np.allclose(backbone.frequency, frequency, rtol=1e-6, atol=0)
    assert np.allclose(backbone.damping_ratio, ratio, rtol=1e-6, atol=0)


@SLOW
def test_the_mode_with_a_narrow_stribeck_drop_is_coulomb_s_at_the_kinetic_level(tmp_path):
    """Stribeck's drop from 0.1 N to 0.06 N over 1 mm/s, from the command line: the mass turns through the drop
    in a blink, so its mode is Coulomb friction's at 0.06 N (solved on the network of one node, exact between
    events) to 1e-3 in frequency and damping ratio, and far from Coulomb's at the static 0.1 N."""
    base = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}}
    tables = dict(base, friction={"alpha": 0.1, "alpha_kinetic": 0.06, "stribeck_velocity": 0.001})
    rows = {}
    for name, friction in (("stribeck", tables["friction"]), ("kinetic", {"alpha": 0.06}), ("static", {"alpha": 0.1})):
        out = tmp_path / f"{name}.csv"
        assert main(["describe", write(tmp_path, dict(base, friction=friction)), "--mode", "1", "--amplitudes",
                     "0.5,1,2", "--out", str(out)]) == 0
        table = read_csv(out)
        rows[name] = np.array([table["frequency"], table["damping_ratio"]], float)
    assert np.allclose(rows["stribeck"], rows["kinetic"], rtol=1e-3, atol=0)
    assert np.all(np.abs(rows["stribeck"][1] / rows["static"][1] - 1.0) > 0.3)
