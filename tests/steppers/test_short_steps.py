"""A duration shorter than rounding of the internal step changes nothing but the time (issue 44, item 2).

OMSimulator's clock (2000 x 0.1 s) ends 7.1e-12 s short of 200 s and then steps that remainder: a step of
7e-12 s taken under a white noise drew a Brownian increment that moved v by about sigma sqrt(7e-12) = 1e-6.
``split_duration`` drops a remainder below 1e-9 h after the whole steps, and a duration that is itself below
1e-9 h is no step at all; the stepped objects (Element, NetworkElement, NetworkConnector) then change nothing,
and the steps after it are those of a run without it, to the bit (the clock stays on its grid).
"""
import numpy as np
import pytest

from prandtl_fmu import Element, load_scene, parse_scene, simulate
from prandtl_fmu.network import NetworkConnector, NetworkElement
from prandtl_fmu.stepping import split_duration

from tests.conftest import SCENES, base_tables, scene_text

SHORT = 7e-12  # what OMSimulator stepped at the end of the white-noise scene's 200 s


@pytest.mark.parametrize("duration,h,expected", [
    (7e-12, 0.01, (0, 0.0)),  # below 1e-9 h itself: no step
    (0.0, 0.01, (0, 0.0)),
    (0.05 + 5e-12, 0.01, (5, 0.0)),  # within 1e-9 h of whole steps (as before)
    (0.05 - 5e-12, 0.01, (5, 0.0)),
])
def test_split_duration_drops_what_is_rounding(duration, h, expected):
    assert split_duration(duration, h) == expected
    assert split_duration(duration, h, 200.0) == expected  # (OMSimulator's clock ends at 200 s)


@pytest.mark.parametrize("h", [1e3, 1e20, 1e300])
def test_a_step_longer_than_the_interval_is_cut_to_it(h):
    # a clock's rounding is a fraction of its time: 1 s of a clock at 1..5 s is no rounding, whatever h is
    for end in (1.0, 5.0):
        assert split_duration(1.0, h, end) == (0, 1.0)
    assert split_duration(1e-8, h, 1.0) == (0, 1e-8)
    assert split_duration(1e-10, h, 1e2) == (0, 0.0)  # below 1e-9 of the clock and of h: rounding


def test_an_element_with_a_step_longer_than_its_advances_takes_them_as_steps():
    # Element(scene, step=1e20) advanced by 1 s five times stayed at x = 0 (each advance was 'rounding');
    # each is one step of 1 s: the element with step = 1 to the bit
    scene = load_scene(SCENES / "masing-bilinear.toml")
    long, exact = Element(scene, step=1e20), Element(scene, step=1.0)
    for _ in range(5):
        for element in (long, exact):
            element.advance(1.0, 5.0)
        assert (long.x, long.v, long.time, long.reaction) == (exact.x, exact.v, exact.time, exact.reaction)
    assert long.x != 0.0 and long.time == 5.0
    long.time = 5.0 + 1e-12  # a master's clock's rounding is still the same instant
    assert long.time == 5.0


def test_a_network_with_a_step_longer_than_its_advances_takes_them_as_steps():
    scene = parse_scene(network_text(False), "net.toml")
    long, exact = NetworkElement(scene, step=1e300), NetworkElement(scene, step=0.25)
    for _ in range(4):
        for network in (long, exact):
            network.advance(0.25, 3.0)
        assert network_state(long) == network_state(exact)
    assert long.x[0] != 0.0 and long.time == 1.0


def test_split_duration_keeps_a_remainder_above_rounding():
    h = 0.01
    assert split_duration(2e-11, h) == (0, 2e-11)  # 2e-9 h: a (short) step
    whole, rest = split_duration(0.053, h)
    assert whole == 5 and rest == pytest.approx(0.003, abs=1e-15)
    whole, rest = split_duration(0.05 + 3e-11, h)  # 3e-9 h after the whole steps: kept
    assert whole == 5 and rest == pytest.approx(3e-11, rel=1e-4)


def element_state(element):
    return (element.x, element.v, element.time, element.reaction, tuple(element.energy().values()),
            tuple(element.elongations()))


def test_element_under_white_noise_ignores_a_step_below_rounding():
    scene = load_scene(SCENES / "white-noise.toml")
    assert scene.load.noise is not None and SHORT < 1e-9 * scene.solver.step
    element, twin = Element(scene), Element(scene)
    for stepped in (element, twin):
        stepped.advance(1.0, 0.0, scene_load=True)
    before = element_state(element)
    element.advance(SHORT, 0.0, scene_load=True)
    assert element_state(element) == before  # x, v, the outputs and the clock: nothing moved
    element.time = 1.0 + SHORT  # the master's next communication point: the same instant of the grid
    for _ in range(3):
        element.advance(0.1, 0.0, scene_load=True)
        twin.advance(0.1, 0.0, scene_load=True)
        assert element_state(element) == element_state(twin)
    # a step of 2e-9 h is a step: its Brownian increment moves v (what the rule must not swallow)
    longer = Element(scene)
    longer.advance(1.0, 0.0, scene_load=True)
    longer.advance(2e-9 * scene.solver.step, 0.0, scene_load=True)
    assert longer.v != before[1]


def test_element_run_ends_as_the_library_whatever_the_short_last_step():
    """The OMSimulator case: 20 steps of 0.1 s, then the 7e-12 s remainder: the state is simulate's at 2 s."""
    scene = load_scene(SCENES / "white-noise.toml").with_solver(stop_time=2.0)
    library = simulate(scene, energy=True)  # the account, as the element keeps it: one compiled loop
    element = Element(scene)
    for j in range(20):
        element.time = 0.1 * j  # a master's clock (adds up to 1.9999999999999996)
        element.advance(0.1, 0.0, scene_load=True)
    element.advance(SHORT, 0.0, scene_load=True)
    assert (element.x, element.v) == (library.x[-1], library.v[-1])


def network_text(massless_load_node: bool) -> str:
    text = (SCENES / "networks" / "two-masses-slider.toml").read_text()
    if massless_load_node:  # a connector imposes the motion of a massless load node (and takes no force)
        return text.replace("mass = [1.0, 2.0]", "mass = [0.0, 2.0]")
    return text.replace('amplitude = 10.0', 'amplitude = 10.0\nnoise_intensity = 0.5\nnoise_seed = 3\n'
                        'noise_unit = 0.001')


def network_state(network):
    return (tuple(network.x), tuple(network.v), tuple(network.u), network.time, network.reaction,
            tuple(network.energy().values()))


def test_network_ignores_a_step_below_rounding():
    scene = parse_scene(network_text(False), "net.toml")
    assert scene.load.noise is not None
    network, twin = NetworkElement(scene), NetworkElement(scene)
    for stepped in (network, twin):
        stepped.advance(0.5, 0.0, scene_load=True)
    before = network_state(network)
    network.advance(SHORT * 0.1, 0.0, scene_load=True)  # h = 1e-3: 1e-9 h = 1e-12
    assert network_state(network) == before
    for _ in range(3):
        network.advance(0.05, 0.0, scene_load=True)
        twin.advance(0.05, 0.0, scene_load=True)
        assert network_state(network) == network_state(twin)


def test_network_connector_sample_within_rounding_is_at_its_instant():
    """A sample a rounding after the last one is a sample at that instant (the instant's move): the node is
    where the master put it, and every output equals those of a sample at the same time."""
    scene = parse_scene(network_text(True), "net.toml")
    late, same = NetworkConnector(scene), NetworkConnector(scene)
    for connector in (late, same):
        connector.move_to(0.01, 0.2, 0.05)
    late.move_to(0.012, 0.2, 0.05 + SHORT * 0.1)
    same.move_to(0.012, 0.2, 0.05)
    load_node = scene.network.load_node
    assert late.x[load_node] == 0.012
    assert (late.force, *network_state(late)[:3]) == (same.force, *network_state(same)[:3])
    for connector in (late, same):
        connector.move_to(0.02, 0.1, 0.1)
    assert (late.force, *network_state(late)[:3]) == (same.force, *network_state(same)[:3])


def test_a_run_shorter_than_rounding_is_still_one_short_step():
    """The output grid of a batch run keeps its rows t = 0 and t = stop_time whatever the stop time."""
    scene = parse_scene(scene_text(base_tables(solver={"stepper": "implicit", "step": 0.01, "stop_time": 5e-12,
                                                       "output_interval": 0.01})), "short.toml")
    result = simulate(scene)
    assert list(result.time) == [0.0, 5e-12]
    assert np.isfinite(result.x).all() and result.v[-1] != result.v[0]
