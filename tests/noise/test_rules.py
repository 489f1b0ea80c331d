"""The rules a white noise set on a stepped element (an FMU's noise_intensity, noise_seed, noise_unit) obeys:
every check is made against the noise in use, not the scene's own (issue 34; the adversarial review's cases)."""
import numpy as np
import pytest

from prandtl_fmu.element import Element
from prandtl_fmu.stepping import ElementError
from prandtl_fmu.loads import WhiteNoise, noise_problem
from prandtl_fmu.network import NetworkElement
from prandtl_fmu.scene import SceneError, parse_scene

NOISY = """
[mass]
m = 1.0
[spring]
k0 = 1.0
[damper]
c = 0.2
[load]
kind = "harmonic"
amplitude = 0.5
omega = 1.0
noise_intensity = 0.5
noise_seed = 3
noise_unit = 0.01
[solver]
stepper = "implicit"
step = 0.01
stop_time = 1.0
output_interval = 0.1
"""

MASSLESS = """
[spring]
k0 = 1.0
[damper]
c = 0.5
[load]
kind = "constant"
value = 0.1
[solver]
stepper = "implicit"
step = 0.01
stop_time = 1.0
output_interval = 0.1
"""

NETWORK = """
[network]
nodes = ["a", "b"]
mass = [1.0, 1.0]
[[network.spring]]
between = ["a", "ground"]
k = 1.0
[[network.spring]]
between = ["a", "b"]
k = 2.0
[load]
kind = "white_noise"
intensity = 0.3
seed = 4
noise_unit = 0.01
[solver]
stepper = "implicit"
step = 0.01
stop_time = 1.0
output_interval = 0.1
"""


def test_a_noise_turned_off_lets_a_stepper_without_noise_restore_and_change():
    element = Element(parse_scene(NOISY))
    element.set_noise(None)
    element.set_stepper("exact")
    element.advance(0.1, 0.0, scene_load=True)
    state = element.get_state()
    element.set_coefficients(k0=2.0)  # checked against no noise: 'exact' applies
    element.set_state(state)
    assert element.stepper == "exact" and element.noise is None


def test_a_state_whose_stepper_refuses_the_noise_in_use_is_refused():
    element = Element(parse_scene(NOISY))
    element.set_noise(None)
    element.set_stepper("exact")
    state = element.get_state()
    noisy = Element(parse_scene(NOISY))
    with pytest.raises(ValueError, match="'exact' has no exact solution under a white noise"):
        noisy.set_state(state)  # its noise stays on
    assert noisy.stepper == "implicit"
    noisy.set_state(state, noise=None)  # with the state's own settings (no noise) it applies
    assert noisy.stepper == "exact" and noisy.noise is None


def test_a_massless_element_refuses_losing_its_dashpot_under_a_noise_whatever_the_order():
    element = Element(parse_scene(MASSLESS))
    element.set_noise(WhiteNoise(1.0, 2, 0.01))
    with pytest.raises(ValueError, match="white noise on a massless element without a dashpot"):
        element.set_coefficients(c=0.0)
    element.set_noise(None)
    element.set_coefficients(c=0.0)  # no noise: the quasi-static element
    with pytest.raises(ValueError, match="white noise on a massless element without a dashpot"):
        element.set_noise(WhiteNoise(1.0, 2, 0.01))


def test_a_network_with_its_noise_off_takes_a_massless_load_node():
    scene = parse_scene(NETWORK)
    element = NetworkElement(scene)
    with pytest.raises(SceneError, match="white noise on the massless node b"):
        element.set_parameters(m_b=0.0)
    element.set_noise(None)
    element.set_parameters(m_b=0.0)
    fresh = NetworkElement(element.scene, noise=None)  # what an FMU's rebuild and restore do
    fresh.set_state(element.get_state())
    with pytest.raises(ValueError, match="white noise on the massless node b"):
        NetworkElement(element.scene)  # with the scene's noise


@pytest.mark.parametrize("unit,culprit", [(1e20, "too coarse for the step"), (1e-300, "too fine for the stop time")])
def test_a_noise_unit_the_tree_cannot_resolve_is_refused(unit, culprit):
    with pytest.raises(SceneError, match=culprit):
        parse_scene(NOISY.replace("noise_unit = 0.01", f"noise_unit = {unit}"))
    assert noise_problem(WhiteNoise(0.5, 3, unit), 0.01, 1.0)


def test_an_fmu_noise_unit_too_coarse_for_the_step_is_refused():
    """(A stepped element has no stop time: a unit too fine fails the step at the tree's end, below.)"""
    element = Element(parse_scene(NOISY))
    with pytest.raises(ValueError, match="too coarse for the step"):
        element.set_noise(WhiteNoise(0.5, 3, 1e20))
    with pytest.raises(ValueError, match="too coarse for the step"):
        element.set_step(1e-30)
    assert element.noise == WhiteNoise(0.5, 3, 0.01) and element.h == 0.01


def test_the_tree_s_horizon_fails_the_step_instead_of_freezing_the_path():
    """Past 2^52 units the path would be constant: the step is refused, never a silent zero."""
    element = Element(parse_scene(NOISY))
    element.set_noise(WhiteNoise(0.5, 3, 1e-13))  # 2^52 units = 450 s
    element.time = 460.0
    with pytest.raises(ElementError, match="the Brownian tree ends at 2\\^52 units"):
        element.advance(0.01, 0.0, scene_load=True)
    assert np.isfinite(element.x)
