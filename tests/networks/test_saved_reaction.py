"""A network's saved state is checked, not trusted, where it holds an output derived from the rest (issue 59,
item 6): the reaction. A forged one (12345 N, shown as it was while x, v and u said otherwise) is refused; every
state the network itself saves is taken, after steps, at the start, after a change of its coefficients. The
native FMU's check is the same compiled kernel (tests/networks/test_native.py, FORGERIES)."""
import copy

import pytest

from prandtl_fmu.network import NetworkElement
from prandtl_fmu.scene import parse_scene
from tests.networks.scenes import SCENES


def stepped(name, steps=((0.3, 1.0), (0.2, -0.5))):
    element = NetworkElement(parse_scene(SCENES[name], f"{name}.toml"))
    for duration, force in steps:
        element.advance(duration, force)
    return element


@pytest.mark.parametrize("name", ["joint", "chain3", "massless"])
def test_a_forged_reaction_is_refused_and_changes_nothing(name):
    element = stepped(name)
    good = element.get_state()
    before = (element.x.tolist(), element.v.tolist(), element.reaction)
    forged = copy.deepcopy(good)
    forged["reaction"] = 12345.0
    with pytest.raises(ValueError, match=r"state's reaction \(12345.0 N\) is not the one its x, v and u give"):
        element.set_state(forged)
    assert (element.x.tolist(), element.v.tolist(), element.reaction) == before
    element.set_state(good)
    assert element.reaction == before[2]


@pytest.mark.parametrize("name", ["joint", "chain3", "massless"])
def test_every_state_the_network_saves_is_taken_back(name):
    element = NetworkElement(parse_scene(SCENES[name], f"{name}.toml"))
    saves = [element.get_state()]  # at the start (its reaction from the instant's equilibrium)
    for duration, force in ((0.3, 1.0), (0.2, -0.5), (0.05, 2.0)):
        element.advance(duration, force)
        saves.append(element.get_state())
    spring = next(key for key in element.scene.network.parameters() if key.startswith("k_spring"))
    element.set_parameters(**{spring: 3.0 * element.scene.network.parameters()[spring]})
    saves.append(element.get_state())  # the reaction under the new coefficients
    for state in saves:
        element.set_state(state)
        assert element.get_state()["reaction"] == state["reaction"]


def test_the_reaction_after_a_change_of_a_spring_is_the_state_s_under_it():
    # the one-mass element's rule: the reaction of the state as it stands under the coefficients now
    from prandtl_fmu.network import kernels

    element = stepped("chain3")
    kind, ends = element.model[1], element.model[2]
    e = next(j for j in range(len(kind)) if kind[j] == kernels.SPRING and ends[j, 1] == kernels.GROUND)
    spring = f"k_{element.scene.network.elements[e].name}"
    before, k = element.reaction, element.scene.network.parameters()[spring]
    element.set_parameters(**{spring: 2.0 * k})
    assert element.reaction == pytest.approx(before + k * element.x[ends[e, 0]], rel=1e-12)
