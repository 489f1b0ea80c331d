"""An input given with its derivatives (``Element.advance(..., force_derivatives=(F', F''))``, ``loads.polynomial``):
the force over an advance is the Taylor polynomial of the sample, evaluated wherever the stepper evaluates its
force. What an FMU master's sampled force then costs against the continuous force, measured in the sample spacing:
held, first order; with F', second; with F' and F'', third."""
import dataclasses
import math

import numpy as np
import pytest

from prandtl_fmu import load_scene
from prandtl_fmu.element import Element
from prandtl_fmu.loads import TableLoad

from tests.conftest import SCENES

PAPER = SCENES / "paper-section-8.toml"
AMPLITUDE, OMEGA = 0.45, 0.5  # the paper's F(t) = 0.45 cos(0.5 t)
STOP = 12.0


def _sampled_run(scene, spacing, orders):
    """The paper's element over [0, STOP] driven by F sampled every ``spacing`` s with its first ``orders``
    derivatives (0: held); its x at the end."""
    element = Element(scene, stepper="projected", step=1e-3)
    steps = int(round(STOP / spacing))
    for j in range(steps):
        t = j * spacing
        force = AMPLITUDE * math.cos(OMEGA * t)
        rate = -AMPLITUDE * OMEGA * math.sin(OMEGA * t) if orders >= 1 else 0.0
        curvature = -AMPLITUDE * OMEGA ** 2 * math.cos(OMEGA * t) if orders >= 2 else 0.0
        element.time = t
        element.advance(spacing, force, force_derivatives=(rate, curvature))
    return element.x


def _continuous_run(scene):
    element = Element(scene, stepper="projected", step=1e-3)
    element.advance(STOP, 0.0, scene_load=True)
    return element.x


@pytest.mark.slow
def test_the_error_of_a_sampled_force_falls_with_the_order_of_its_polynomial():
    """The paper's element under its force sampled at 0.4, 0.2, 0.1, 0.05 s against the continuous force (the same
    internal steps): the error in x at t = 12 s falls at order ~1 held, >= 1.8 with F', >= 2.7 with F' and F''."""
    scene = load_scene(PAPER)
    reference = _continuous_run(scene)
    spacings = np.array([0.4, 0.2, 0.1, 0.05])
    for orders, least, most in ((0, 0.8, 1.3), (1, 1.8, 2.4), (2, 2.7, 3.5)):
        errors = np.array([abs(_sampled_run(scene, spacing, orders) - reference) for spacing in spacings])
        slope = np.polyfit(np.log(spacings), np.log(errors), 1)[0]
        assert least <= slope <= most, (orders, errors, slope)


def test_a_linear_force_is_the_line_a_table_draws():
    """F' alone over one advance is the line through (t0, F) and (t0 + H, F + F' H): the paper's element under it
    equals simulate under that table to rounding (the table interpolates in its own arithmetic)."""
    scene = load_scene(PAPER)
    force, rate, span = 0.3, -0.2, 2.0
    element = Element(scene, stepper="projected", step=1e-3)
    element.advance(span, force, force_derivatives=(rate, 0.0))
    line = TableLoad(np.array([0.0, span]), np.array([force, force + rate * span]))
    table = Element(dataclasses.replace(scene, load=line), stepper="projected", step=1e-3)
    table.advance(span, 0.0, scene_load=True)
    assert element.x == pytest.approx(table.x, rel=1e-12, abs=1e-15)
    assert element.v == pytest.approx(table.v, rel=1e-12, abs=1e-15)
    assert abs(element.x) > 1e-3


def test_zero_derivatives_are_the_held_force_bit_for_bit_and_bad_ones_are_refused():
    """(0, 0) is the held force, the same compiled load; a non-finite derivative, derivatives with scene_load and
    with 'exact' (its closed forms know the scene's load kinds) are refused naming the culprit, the element
    unchanged."""
    scene = load_scene(PAPER)
    held, given = Element(scene, stepper="projected", step=1e-3), Element(scene, stepper="projected", step=1e-3)
    held.advance(0.5, 0.3)
    given.advance(0.5, 0.3, force_derivatives=(0.0, 0.0))
    assert (held.x, held.v, held.reaction) == (given.x, given.v, given.reaction)
    before = (given.x, given.v, given.time)
    with pytest.raises(ValueError, match="order 2 must be finite"):
        given.advance(0.5, 0.3, force_derivatives=(0.1, math.nan))
    with pytest.raises(ValueError, match="scene_load"):
        given.advance(0.5, 0.3, scene_load=True, force_derivatives=(0.1, 0.0))
    exact = Element(scene, stepper="exact", step=1e-3)
    with pytest.raises(ValueError, match="stepper 'exact'"):
        exact.advance(0.5, 0.3, force_derivatives=(0.1, 0.0))
    assert (given.x, given.v, given.time) == before
