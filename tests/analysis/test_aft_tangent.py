"""The exact Jacobian of the alternating frequency-time forces (``aft.restoring_samples``, read through
``HarmonicBalance.nonlinear``) against central finite differences of the forces themselves, on random networks
and random periodic motions: the sampled map is piecewise linear in the coefficients for the branches (and
smooth for the cubic springs), so away from a sample that lands on a threshold the differences are its
derivative to rounding. Several branches per pair of nodes (slipping, and one too wide to slip), pairs to the
ground and between nodes, and a motion with minor loops (its third harmonic)."""
import numpy as np
import pytest

from prandtl_fmu.frequency import parse_scene
from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

from tests.analysis.test_harmonic_balance_network_friction import network_text


def random_network(rng):
    nodes = ["a", "b", "c"]
    elements = [("spring", [node, "ground"], {"k": 1.0}) for node in nodes]
    elements.append(("cubic", ["a", "b"], {"k3": float(rng.uniform(0.1, 1.0))}))
    for between in (["a", "ground"], ["a", "b"], ["b", "c"], ["c", "ground"]):
        for _ in range(int(rng.integers(2, 6))):
            elements.append(("branch", between, {"k": float(rng.uniform(0.1, 1.0)),
                                                 "eta": float(rng.uniform(0.01, 0.4))}))
        elements.append(("branch", between, {"k": 0.3, "eta": 50.0}))  # never slips
    text = network_text(nodes, [1.0, 1.0, 1.0], elements, load_node="a")
    return periodic_system(parse_scene(text, networks=True)[0])


@pytest.mark.parametrize("seed", range(4))
def test_the_forces_jacobian_is_their_finite_differences(seed):
    rng = np.random.default_rng(seed)
    system = random_network(rng)
    balance = HarmonicBalance(system, 5, 1.0)
    L = balance.L
    q = np.zeros(system.n * L)
    for node in range(system.n):  # a mean, a first harmonic of 0.5 m and smaller higher ones
        q[node * L] = rng.uniform(-0.1, 0.1)
        q[node * L + 1:node * L + 3] = rng.uniform(-0.5, 0.5, 2)
        q[node * L + 3:(node + 1) * L] = rng.uniform(-0.12, 0.12, L - 3)
    G, jacobian = balance.nonlinear(q, 1.0)
    G, jacobian = G.copy(), jacobian.copy()
    step = 1e-7
    finite = np.empty_like(jacobian)
    for column in range(q.size):
        moved = q.copy()
        moved[column] += step
        up = balance.nonlinear(moved, 1.0)[0].copy()
        moved[column] -= 2.0 * step
        down = balance.nonlinear(moved, 1.0)[0].copy()
        finite[:, column] = (up - down) / (2.0 * step)
    scale = np.max(np.abs(jacobian))
    assert scale > 0.1
    assert np.max(np.abs(finite - jacobian)) <= 1e-6 * scale, np.max(np.abs(finite - jacobian)) / scale
