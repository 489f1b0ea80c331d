"""The FMU given hard scenes behaves as the library, refuses what the library refuses."""
import json

import numpy as np
import pytest

from prandtl_fmu import Element, load_scene
from prandtl_fmu.stepping import ENERGY_COLUMNS
from prandtl_fmu.fmu.build import build_fmu
from fmpy.fmi1 import FMICallException

from tests.conftest import SCENES
from tests.fmu_tools import Slave

# the hard scenes through the FMU: run by .ci/run after the quick suite
pytestmark = pytest.mark.slow

HARD = SCENES / "hard"


@pytest.fixture(scope="module")
def hard_fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("hard_fmus")
    names = ["stiff-branches", "overload", "massless-quasi-static", "massless-collapse", "large-forces",
             "many-branches", "long-horizon", "step-load"]
    return {name: build_fmu(HARD / f"{name}.toml", folder / f"{name}.fmu") for name in names}


def force_of(scene, t):
    from prandtl_fmu.loads import force_at

    return float(force_at(scene.load.compile(), t))


@pytest.mark.parametrize("name, comm_step, steps", [
    ("stiff-branches", 0.01, 300),
    ("overload", 0.05, 100),
    ("massless-quasi-static", 0.01, 400),
    ("large-forces", 0.1, 100),
    ("step-load", 0.037, 300),     # not a multiple of h: a shorter last internal step
    ("many-branches", 4.0, 2),      # 4000 internal steps per doStep, 10^5 branches
    ("long-horizon", 1000.0, 3),    # 10^6 internal steps per doStep
])
def test_fmu_runs_hard_scenes_as_the_library(hard_fmus, name, comm_step, steps):
    scene = load_scene(HARD / f"{name}.toml")
    first = force_of(scene, 0.0)
    slave = Slave(hard_fmus[name], start_values={"F": first})
    element = Element(scene)
    element.reset(first)
    try:
        outputs = ["x", "v", "reaction"] + [c for c in ENERGY_COLUMNS if c in slave.vr]
        scale = np.ones(len(outputs))
        for k in range(steps):
            force = force_of(scene, k * comm_step)
            slave.step(comm_step, force)
            element.advance(comm_step, force)
            energy = element.energy()
            expected = [element.x, element.v, element.reaction] + [
                energy[c] for c in ENERGY_COLUMNS if c in slave.vr]
            scale = np.maximum(scale, np.abs(expected))
            gap = np.abs(np.array(slave.get(*outputs)) - expected)
            assert np.all(gap <= 1e-12 * scale), dict(zip(outputs, gap / scale))
        assert np.all(np.isfinite(expected))
    finally:
        slave.close()


def test_fmu_refuses_plastic_collapse_and_keeps_its_state(hard_fmus):
    slave = Slave(hard_fmus["massless-collapse"])
    try:
        slave.step(0.5, 1.0)
        before = json.loads(bytes(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())))["element"]
        slave.set("F", 2.0)  # above the strength 1.7 N, no hardening spring
        with pytest.raises(FMICallException) as refused:
            slave.fmu.doStep(slave.time, 0.5)
        assert refused.value.status == 2
        message = " ".join(text for _, text in slave.messages)
        assert "plastic collapse" in message and "F = 2.0 N" in message and "1.7 N" in message
        after = json.loads(bytes(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())))["element"]
        assert after == before
        slave.step(0.5, 1.5)  # a load it can carry: on it goes
        assert slave.get("reaction") == pytest.approx(1.5, abs=1e-13)
    finally:
        slave.close()


def test_fmu_logs_a_warning_beyond_the_stability_limit(hard_fmus):
    slave = Slave(hard_fmus["stiff-branches"], start_values={"stepper": "projected"})
    try:
        warnings = [text for status, text in slave.messages if status == 1]
        assert any("stability limit" in text and "omega h" in text for text in warnings), slave.messages
        slave.messages.clear()
        slave.set("step", 1e-5)  # within the limit: no new warning
        slave.step(0.01, 0.0)
        assert not [text for status, text in slave.messages if status == 1]
    finally:
        slave.close()
