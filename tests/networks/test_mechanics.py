"""Networks of nodes (issue 32): the checks the issue asks for, each against mechanics written here.

References are independent of the library's kernels: closed forms (the massless chain, Masing's rule), a
backward Euler written in this file that solves each step by enumerating the sliders' states (stick, slip
forwards, slip backwards) and keeping the one whose forces and velocities are consistent, and the one-mass
element of the library (a different code path: prandtl_fmu.driver).
"""
import itertools
import math
import re
import subprocess
import sys

import numpy as np
import pytest

from prandtl_fmu.stepping import ElementError
from prandtl_fmu.driver import simulate as simulate_element
from prandtl_fmu.network import NetworkConnector, NetworkElement, NetworkScene, simulate, simulate_chunks
from prandtl_fmu.scene import SceneError, parse_scene


# ------------------------------------------------------------------ scenes as TOML text

def toml_value(value):
    if isinstance(value, str):
        return '"' + value + '"'
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return str(int(value))
    return repr(float(value))


def table(header, values):
    return "\n".join([f"[{header}]"] + [f"{k} = {toml_value(v)}" for k, v in values.items()]) + "\n"


def network_text(nodes, mass, elements, load, solver, x0=None, v0=None, load_node=None):
    """A [network] scene: ``elements`` is a list of (kind, {between, k, ...})."""
    head = {"nodes": list(nodes), "mass": list(mass)}
    if x0 is not None:
        head["x0"] = list(x0)
    if v0 is not None:
        head["v0"] = list(v0)
    if load_node is not None:
        head["load_node"] = load_node
    text = table("network", head)
    for kind, values in elements:
        text += table(f"[network.{kind}]", values)
    return text + table("load", load) + table("solver", solver)


def solver(step, stop_time, output_interval=None, stepper="implicit"):
    return {"stepper": stepper, "step": step, "stop_time": stop_time,
            "output_interval": step if output_interval is None else output_interval}


def chain_text(n, m, k, alpha, load, solver_values, k_wall=None, c=None):
    chain = {"n": n, "m": m, "k": k, "alpha": alpha}
    if k_wall is not None:
        chain["k_wall"] = k_wall
    if c is not None:
        chain["c"] = c
    return table("chain", chain) + table("load", load) + table("solver", solver_values)


def ramp(points, duration_per_unit=1.0):
    """A table load through the forces ``points`` at times spaced by |dF| * duration_per_unit (so the force
    changes at the same rate everywhere)."""
    times = [0.0]
    for a, b in zip(points[:-1], points[1:]):
        times.append(times[-1] + abs(b - a) * duration_per_unit)
    return {"kind": "table", "time": times, "force": list(points)}


# ------------------------------------------------------------------ 1. the massless chain, closed forms

def virgin_end(force, k, alpha):
    """x_end(F) of a massless chain of uniform k and alpha pulled from rest: the last p = floor(F / alpha)
    nodes slide, the spring behind the q-th of them from the end carries F - q alpha."""
    p = np.floor(np.asarray(force) / alpha)
    return (p * force - alpha * p * (p + 1) / 2) / k


def massless_chain(n, k, alpha, force_max, k_wall, steps_per_second=512):
    """Load from 0 to force_max over 1 s, down to -force_max over 2 s; output at every step (h = 1/512 s: the
    table's corners fall on the step grid exactly)."""
    load = {"kind": "table", "time": [0.0, 1.0, 3.0], "force": [0.0, force_max, -force_max]}
    text = chain_text(n, 0.0, k, alpha, load, solver(1.0 / steps_per_second, 3.0), k_wall=k_wall)
    return parse_scene(text)


@pytest.mark.parametrize("case, wall", [pytest.param("n6", True, marks=pytest.mark.slow),  # (56 s cold: slow)
                                        ("n6", False), ("random", True), ("random", False)])
def test_massless_chain_virgin_curve_and_masing(case, wall):
    if case == "n6":
        n, k, alpha = 6, 2.0, 0.5
    else:
        rng = np.random.default_rng(20261124 + wall)
        n, k, alpha = int(rng.integers(3, 12)), float(rng.uniform(0.5, 5.0)), float(rng.uniform(0.1, 2.0))
    # with the wall spring (k_wall = k) the formula holds for p <= n: F < (n + 1) alpha; free: p < n
    force_max = (n + 0.7) * alpha if wall else (n - 0.3) * alpha
    result = simulate(massless_chain(n, k, alpha, force_max, k if wall else None))
    F, x_end = result.F, result.x[:, -1]
    peak = int(np.argmax(F))
    assert F[peak] == pytest.approx(force_max, rel=1e-12)
    loading = slice(0, peak + 1)
    scale = virgin_end(force_max, k, alpha)
    np.testing.assert_allclose(x_end[loading], virgin_end(F[loading], k, alpha), rtol=0, atol=1e-12 * scale)
    # the curve is not trivially zero: the end moved by the closed form's amount at the peak
    assert x_end[peak] == pytest.approx(scale, rel=1e-12) and scale > 0
    unloading = slice(peak, None)
    masing = x_end[peak] - 2 * virgin_end((force_max - F[unloading]) / 2, k, alpha)
    assert F[-1] == pytest.approx(-force_max, rel=1e-12)
    np.testing.assert_allclose(x_end[unloading], masing, rtol=0, atol=1e-12 * scale)
    # nothing with a mass: the ground holds the whole load at every instant
    np.testing.assert_allclose(result.reaction, F, rtol=0, atol=1e-12 * force_max)
    # the node next to the fixed end (n1) stays put while F < n alpha (only p < n nodes slide)
    if not wall:
        assert np.all(result.x[:, 0] == 0.0)


def test_massless_chain_beyond_total_friction_has_no_equilibrium():
    n, k, alpha = 6, 2.0, 0.5
    scene = massless_chain(n, k, alpha, (n + 0.5) * alpha, None)
    with pytest.raises(ElementError, match="no equilibrium") as info:
        simulate(scene)
    message = str(info.value)
    assert "\n" not in message
    # the step refused is the first whose load exceeds the total friction n alpha (F rises by
    # (n + 0.5) alpha / 512 per step)
    refused_force = float(re.search(r"F = ([-+0-9.e]+) N", message).group(1))
    assert n * alpha < refused_force <= n * alpha + (n + 0.5) * alpha / 512 * (1 + 1e-12)
    # the refusal comes where F first exceeds n alpha, not earlier: just below it the run goes through
    below = massless_chain(n, k, alpha, (n - 0.01) * alpha, None)
    assert np.isfinite(simulate(below).x).all()


@pytest.mark.parametrize("wall", [True, False])
def test_massless_chain_driven_by_its_end_motion(wall):
    """The connector imposes x_end; the force it reports is the closed form's inverse: x_end = x_virgin(F)
    while x_end rises, Masing's branch on the way back; a free chain pulled beyond the point where all its
    nodes slide holds exactly the total friction n alpha."""
    n, k, alpha = 6, 2.0, 0.5
    scene = parse_scene(chain_text(n, 0.0, k, alpha, {"kind": "constant", "value": 0.0}, solver(0.01, 1.0),
                                   k_wall=k if wall else None))
    connector = NetworkConnector(scene)
    assert connector.force == 0.0
    force_max = (n - 0.3) * alpha
    x_max = float(virgin_end(force_max, k, alpha))
    path = list(np.linspace(0.0, x_max, 41)[1:]) + list(np.linspace(x_max, -x_max, 81)[1:])
    forces = []
    for j, x in enumerate(path):
        connector.move_to(float(x), 0.0, 0.05 * (j + 1))
        assert connector.x[-1] == pytest.approx(x, abs=1e-14 * x_max)
        forces.append(connector.force)
    forces = np.array(forces)
    rising = slice(0, 40)
    np.testing.assert_allclose(virgin_end(forces[rising], k, alpha), path[:40], rtol=0, atol=1e-12 * x_max)
    assert forces[39] == pytest.approx(force_max, rel=1e-12)
    falling = np.array(path[40:])
    masing = x_max - 2 * virgin_end((force_max - forces[40:]) / 2, k, alpha)
    np.testing.assert_allclose(masing, falling, rtol=0, atol=1e-12 * x_max)
    if not wall:
        # beyond the last node's start the whole chain slides: the force is the total friction, exactly
        connector.move_to(-3 * x_max, 0.0, 100.0)
        assert connector.force == pytest.approx(-n * alpha, rel=1e-12)


# ------------------------------------------------------------------ 2. an independent backward Euler

class BruteForceEuler:
    """Backward Euler for nodes with masses m (0: a massless node, in equilibrium), springs (linear), dashpots
    and sliders, the load F on one node:

        m (w - v) / h = F(t + h) e_L - K (x + h w) - C w - sum_s g_s f_s,   f_s in alpha_s Sign(g_s . w),

    with w the new velocities, g_s the incidence row of slider s (e_i - e_j, or e_i to the ground). Each step
    tries the sliders' states (stuck: g_s . w = 0 and f_s unknown; slipping: f_s = +-alpha_s) and keeps the
    one that is consistent (|f_s| <= alpha_s, sign(g_s . w) = the slip's sign): the KKT point of a strictly
    convex problem, hence the step. The previous step's states are tried first (the answer is unique)."""

    def __init__(self, mass, springs, sliders, load_node, force, dashpots=(), cubics=()):
        self.m = np.asarray(mass, float)
        n = self.n = len(mass)
        self.K = np.zeros((n, n))
        for i, j, k in springs:
            g = self.row(i, j)
            self.K += k * np.outer(g, g)
        self.C = np.zeros((n, n))  # dashpots: force c (w_i - w_j) at the new velocities
        for i, j, c in dashpots:
            g = self.row(i, j)
            self.C += c * np.outer(g, g)
        # cubic springs: force k3 (g . x1)^3, solved by Newton's iteration to its last bit
        self.cubics = [(self.row(i, j), k3) for i, j, k3 in cubics]
        self.G = np.array([self.row(i, j) for i, j, _ in sliders]).reshape(len(sliders), n)
        self.alpha = np.array([a for _, _, a in sliders], float)
        self.load_node = load_node
        self.force = force
        self.states = (0,) * len(sliders)

    def row(self, i, j):
        g = np.zeros(self.n)
        g[i] += 1.0
        if j is not None:
            g[j] -= 1.0
        return g

    def solve(self, states, A, b, x, h):
        stuck = [s for s, state in enumerate(states) if state == 0]
        rhs = b - sum((state * self.alpha[s] * self.G[s] for s, state in enumerate(states) if state), np.zeros(self.n))
        size = self.n + len(stuck)
        system = np.zeros((size, size))
        system[:self.n, :self.n] = A
        for c, s in enumerate(stuck):
            system[:self.n, self.n + c] = self.G[s]
            system[self.n + c, :self.n] = self.G[s]
        solution = np.linalg.solve(system, np.concatenate([rhs, np.zeros(len(stuck))]))
        for _ in range(100 if self.cubics else 0):  # Newton on the same KKT system with the cubic forces
            w = solution[:self.n]
            residual = system @ solution - np.concatenate([rhs, np.zeros(len(stuck))])
            jacobian = system.copy()
            for g, k3 in self.cubics:
                y = g @ (x + h * w)
                residual[:self.n] += k3 * y ** 3 * g
                jacobian[:self.n, :self.n] += 3.0 * k3 * y * y * h * np.outer(g, g)
            change = np.linalg.solve(jacobian, -residual)
            solution = solution + change
            if np.all(np.abs(change[:self.n]) <= 1e-16 * (np.abs(solution[:self.n]) + 1e-300)):
                break
        w = solution[:self.n]
        scale = np.abs(b).max() + self.alpha.max() + 1e-300
        for c, s in enumerate(stuck):
            if abs(solution[self.n + c]) > self.alpha[s] + 1e-10 * scale:
                return None
        rate_scale = 1e-10 * (np.abs(w).max() + 1e-300)
        for s, state in enumerate(states):
            if state and state * (self.G[s] @ w) < -rate_scale:
                return None
        return w

    def step(self, t, h, x, v):
        A = np.diag(self.m / h) + h * self.K + self.C
        b = self.m * v / h - self.K @ x
        b[self.load_node] += self.force(t + h)
        candidates = itertools.chain([self.states], itertools.product((0, 1, -1), repeat=len(self.alpha)))
        for states in candidates:
            w = self.solve(states, A, b, x, h)
            if w is not None:
                self.states = states
                return x + h * w, w
        raise AssertionError(f"no consistent slider state at t = {t + h}")

    def run(self, x0, v0, h, steps):
        x, v = np.array(x0, float), np.array(v0, float)
        xs, vs = [x], [v]
        for p in range(steps):
            x, v = self.step(p * h, h, x, v)
            xs.append(x)
            vs.append(v)
        return np.array(xs), np.array(vs)


HARMONIC = {"kind": "harmonic", "amplitude": 1.0, "omega": 1.3, "offset": 0.2}


def harmonic(t):
    return HARMONIC["offset"] + HARMONIC["amplitude"] * math.cos(HARMONIC["omega"] * t)


def two_masses(h, stop=5.0, output=None):
    """Masses a, b joined by a slider, each on a spring to the ground, the load on b."""
    text = network_text(
        ["a", "b"], [1.0, 0.5],
        [("spring", {"between": ["a", "ground"], "k": 4.0}), ("spring", {"between": ["b", "ground"], "k": 2.0}),
         ("slider", {"between": ["a", "b"], "alpha": 0.6})],
        HARMONIC, solver(h, stop, output), x0=[0.1, -0.2], v0=[0.5, -0.2])
    reference = BruteForceEuler([1.0, 0.5], [(0, None, 4.0), (1, None, 2.0)], [(0, 1, 0.6)], 1, harmonic)
    return parse_scene(text), reference


def test_two_masses_and_a_slider_against_brute_force_backward_euler():
    h, stop = 0.005, 5.0
    scene, reference = two_masses(h, stop)
    result = simulate(scene)
    x, v = reference.run([0.1, -0.2], [0.5, -0.2], h, round(stop / h))
    # the slider both sticks and slips in this run (else the test would not test the slider)
    stuck = np.abs(v[:, 0] - v[:, 1]) <= 1e-12 * np.abs(v).max()
    assert np.sum(stuck) > 10 and np.sum(~stuck) > 10
    scale = np.abs(x).max()
    np.testing.assert_allclose(result.x, x, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(result.v, v, rtol=0, atol=1e-11 * np.abs(v).max())


def test_two_masses_order_one_in_h():
    stop, output = 4.0, 0.05
    fine = simulate(two_masses(0.05 / 2 ** 12, stop, output)[0]).x
    steps = [0.05 / 2 ** j for j in range(2, 7)]
    errors = [np.abs(simulate(two_masses(h, stop, output)[0]).x - fine).max() for h in steps]
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert 0.85 < slope < 1.15, (errors, slope)
    assert np.all((ratios > 1.5) & (ratios < 2.6)), ratios


@pytest.mark.parametrize("damped", [False, True])
def test_chain_with_masses_against_brute_force_backward_euler(damped):
    n, h, stop = 4, 0.005, 6.0
    m, k, alpha, k_wall = [1.0, 0.7, 1.2, 0.9], [3.0, 2.0, 4.0], [0.2, 0.3, 0.25, 0.4], 2.0
    c = [0.3, 0.1, 0.2, 0.05] if damped else None
    load = {"kind": "harmonic", "amplitude": 1.0, "omega": 1.1, "offset": 0.0}
    result = simulate(parse_scene(chain_text(n, m, k, alpha, load, solver(h, stop), k_wall=k_wall, c=c)))
    springs = [(0, None, k_wall)] + [(i, i + 1, k[i]) for i in range(n - 1)]
    sliders = [(i, None, alpha[i]) for i in range(n)]
    dashpots = [(i, None, c[i]) for i in range(n)] if damped else ()
    reference = BruteForceEuler(m, springs, sliders, n - 1, lambda t: math.cos(1.1 * t), dashpots)
    x, v = reference.run(np.zeros(n), np.zeros(n), h, round(stop / h))
    # every node both sticks and slips (the solve of the reference leaves 1e-30 where a node is held)
    for i in range(n):
        held = np.abs(v[:, i]) < 1e-12 * np.abs(v).max()
        assert np.sum(held) > 10 and np.sum(~held) > 10
    np.testing.assert_allclose(result.x, x, rtol=0, atol=1e-12 * np.abs(x).max())
    np.testing.assert_allclose(result.v, v, rtol=0, atol=1e-11 * np.abs(v).max())


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5])
def test_random_network_against_brute_force_backward_euler(seed):
    """Four nodes, one massless (held by its own spring), sliders forming a tree through the ground (no loop
    of sliders: the rule of check_topology), springs and a dashpot at random, the load on a random node."""
    rng = np.random.default_rng(seed)
    nodes = ["p", "q", "r", "s"]
    n = len(nodes)
    mass = rng.uniform(0.5, 2.0, n)
    mass[rng.integers(n)] = 0.0

    def name(j):
        return "ground" if j is None else nodes[j]

    springs = [(j, None, float(rng.uniform(1.0, 4.0))) for j in range(n)]
    for _ in range(2):
        i, j = rng.choice(n, 2, replace=False)
        springs.append((int(i), int(j), float(rng.uniform(0.5, 3.0))))
    order = rng.permutation(n)
    sliders = []
    for position, j in enumerate(order):  # each node on a slider to the ground or to a node before it
        other = None if position == 0 or rng.random() < 0.4 else int(order[rng.integers(position)])
        sliders.append((int(j), other, float(rng.uniform(0.1, 0.6))))
    i, j = rng.choice(n, 2, replace=False)
    dashpots = [(int(i), int(j), float(rng.uniform(0.05, 0.5)))]
    load_node = int(rng.integers(n))
    amplitude, omega = float(rng.uniform(1.0, 3.0)), float(rng.uniform(0.5, 2.0))
    elements = ([("spring", {"between": [name(i), name(j)], "k": k}) for i, j, k in springs]
                + [("slider", {"between": [name(i), name(j)], "alpha": a}) for i, j, a in sliders]
                + [("dashpot", {"between": [name(i), name(j)], "c": c}) for i, j, c in dashpots])
    v0 = rng.uniform(-0.5, 0.5, n) * (mass > 0)
    h, stop = 0.004, 6.0
    text = network_text(nodes, mass, elements, {"kind": "harmonic", "amplitude": amplitude, "omega": omega,
                                               "offset": 0.0}, solver(h, stop), v0=v0, load_node=nodes[load_node])
    result = simulate(parse_scene(text))
    reference = BruteForceEuler(mass, springs, sliders, load_node, lambda t: amplitude * math.cos(omega * t),
                                dashpots)
    # from the library's first row (the massless node's initial equilibrium is checked below)
    x, v = reference.run(result.x[0], result.v[0], h, round(stop / h))
    massless = int(np.flatnonzero(mass == 0)[0])
    np.testing.assert_allclose(result.x, x, rtol=0, atol=1e-11 * np.abs(x).max())
    np.testing.assert_allclose(result.v[1:], v[1:], rtol=0, atol=1e-10 * np.abs(v).max())
    assert np.abs(x[:, massless]).max() > 0.01  # the massless node moves
    # its initial position balances the forces on it at F(0), its sliders holding at most their alpha (a
    # dashpot on it holds it at its x0 at the instant t = 0: not this check's case)
    if any(massless in (i, j) for i, j, _ in dashpots):
        assert np.all(result.x[0] == 0.0)
        return
    stuck = [s for s in sliders if massless in (s[0], s[1])]
    force = sum(-k * (result.x[0, i] - (0.0 if j is None else result.x[0, j])) * (1 if i == massless else -1)
                for i, j, k in springs if massless in (i, j)) + (amplitude if load_node == massless else 0.0)
    assert abs(force) <= sum(a for _, _, a in stuck) * (1 + 1e-12) + 1e-12


def test_cubic_springs_and_sliders_against_brute_force_backward_euler():
    """Three masses, cubic springs between them and to the ground, sliders: Newton inside the active set."""
    nodes, mass = ["a", "b", "c"], [1.0, 0.6, 0.8]
    springs = [(0, None, 1.0), (0, 1, 2.0), (2, None, 0.5)]
    cubics = [(0, 1, 3.0), (1, None, 2.0), (1, 2, 1.5)]
    sliders = [(0, None, 0.5), (1, 2, 1.0), (2, None, 0.8)]
    elements = ([("spring", {"between": [nodes[i], "ground" if j is None else nodes[j]], "k": k})
                 for i, j, k in springs]
                + [("cubic", {"between": [nodes[i], "ground" if j is None else nodes[j]], "k3": k3})
                   for i, j, k3 in cubics]
                + [("slider", {"between": [nodes[i], "ground" if j is None else nodes[j]], "alpha": a})
                   for i, j, a in sliders])
    h, stop = 0.004, 6.0
    load = {"kind": "harmonic", "amplitude": 2.5, "omega": 1.4, "offset": 0.0}
    result = simulate(parse_scene(network_text(nodes, mass, elements, load, solver(h, stop), v0=[0.0, 0.8, -0.5],
                                               load_node="b")))
    reference = BruteForceEuler(mass, springs, sliders, 1, lambda t: 2.5 * math.cos(1.4 * t), cubics=cubics)
    x, v = reference.run(np.zeros(3), [0.0, 0.8, -0.5], h, round(stop / h))
    assert np.abs(x[:, 0] - x[:, 1]).max() > 0.3  # the cubic terms matter (3 y^3 against 2 y)
    for i, j, _ in sliders:  # each slider both sticks and slips
        rate = v[:, i] - (0.0 if j is None else v[:, j])
        stuck = np.abs(rate) <= 1e-12 * np.abs(v).max()
        assert np.sum(stuck) > 20 and np.sum(~stuck) > 20
    np.testing.assert_allclose(result.x, x, rtol=0, atol=1e-12 * np.abs(x).max())
    np.testing.assert_allclose(result.v, v, rtol=0, atol=1e-10 * np.abs(v).max())


# ------------------------------------------------------------------ 3. one node is the element

BRANCHES = {"k": [0.5, 0.3, 0.2], "eta": [0.1, 0.3, 0.6], "u0": [0.05, -0.1, 0.0]}
ELEMENT_LOAD = {"kind": "harmonic", "amplitude": 0.8, "omega": 0.7, "offset": 0.1}
ONE_NODE_CASES = {
    # name: (element tables, whether a mass, extra network elements)
    "branches": {"mass": True, "spring": 0.2},
    "series_dashpots": {"mass": True, "spring": 0.2, "c": [0.4, 1.5, 3.0]},
    "slider": {"mass": True, "spring": 0.2, "friction": 0.5},
    "cubic": {"mass": True, "spring": 0.2, "cubic": 0.3},
    "damper": {"mass": True, "spring": 0.2, "damper": 0.05},
    "massless": {"mass": False, "spring": 0.2},
    "massless_dashpot": {"mass": False, "spring": 0.2, "damper": 0.5},
    "massless_series": {"mass": False, "spring": 0.0, "c": [0.4, 1.5, 3.0], "cubic": 0.3},
}


def one_node_scenes(case, stepper, h=2e-3, stop=12.0, output=0.02, load=None, parse=parse_scene):
    spec = ONE_NODE_CASES[case]
    load = ELEMENT_LOAD if load is None else load
    element = ""
    elements = [("spring", {"between": ["a", "ground"], "k": spec["spring"]})]
    if spec["mass"]:
        element += table("mass", {"m": 1.3, "x0": 0.05, "v0": 0.2})
    element += table("spring", {"k0": spec["spring"]})
    branches = dict(BRANCHES)
    if "c" in spec:
        branches["c"] = spec["c"]
    element += table("branches", branches)
    for i in range(3):
        values = {"between": ["ground", "a"], "k": BRANCHES["k"][i], "eta": BRANCHES["eta"][i],
                  "u0": BRANCHES["u0"][i]}  # from the ground to a: u follows x_a, as the element's u_i
        if "c" in spec:
            values["c"] = spec["c"][i]
        elements.append(("branch", values))
    if "cubic" in spec:
        element += table("cubic", {"k3": spec["cubic"]})
        elements.append(("cubic", {"between": ["a", "ground"], "k3": spec["cubic"]}))
    if "damper" in spec:
        element += table("damper", {"c": spec["damper"]})
        elements.append(("dashpot", {"between": ["a", "ground"], "c": spec["damper"]}))
    if "friction" in spec:
        # alpha_kinetic = alpha (its default): Coulomb's law, the network's slider
        element += table("friction", {"alpha": spec["friction"], "alpha_kinetic": spec["friction"]})
        elements.append(("slider", {"between": ["a", "ground"], "alpha": spec["friction"]}))
    settings = solver(h, stop, output, stepper)
    element += table("load", load) + table("solver", settings)
    network = network_text(["a"], [1.3 if spec["mass"] else 0.0], elements, load, settings,
                           x0=[0.05] if spec["mass"] else None, v0=[0.2] if spec["mass"] else None)
    return parse(element), parse(network)


ONE_NODE_RUNS = [(case, "implicit") for case in ONE_NODE_CASES] + [
    (case, "projected") for case, spec in ONE_NODE_CASES.items() if spec["mass"] and "friction" not in spec]


@pytest.mark.parametrize("case,stepper", ONE_NODE_RUNS)
def test_one_node_network_is_the_element(case, stepper):
    element_scene, network_scene = one_node_scenes(case, stepper)
    assert isinstance(network_scene, NetworkScene) and not isinstance(element_scene, NetworkScene)
    element = simulate_element(element_scene, stepper)
    network = simulate(network_scene, stepper)
    np.testing.assert_array_equal(network.time, element.time)
    x_scale = np.abs(element.x).max()
    assert x_scale > 0.1  # a run that moves
    np.testing.assert_allclose(network.x[:, 0], element.x, rtol=0, atol=1e-12 * x_scale)
    # v from the first step on (the initial row of a massless node with a dashpot is
    # test_massless_dashpot_node_velocity_at_time_zero's)
    # A massless node's v is d/h: with a cubic spring both solve a cubic equation by Newton to the rounding of
    # the position x + d (the network's test: 64 eps |x|), which d/h amplifies by |x| / |d|: 1e-11 there.
    massless_cubic = not ONE_NODE_CASES[case]["mass"] and "cubic" in ONE_NODE_CASES[case]
    np.testing.assert_allclose(network.v[1:, 0], element.v[1:], rtol=0,
                               atol=(1e-11 if massless_cubic else 1e-12) * (np.abs(element.v).max() + x_scale))
    if case != "slider":
        # With a slider the reaction differs where the mass sticks: the element reports the static friction
        # (F minus the other forces), the network the implicit step's friction force. x and v only there.
        np.testing.assert_allclose(network.reaction, element.reaction, rtol=0,
                                   atol=1e-12 * np.abs(element.reaction).max())
    else:
        assert np.any(element.v == 0) and np.any(element.v != 0)  # the mass both sticks and slides


NOISY_LOAD = dict(ELEMENT_LOAD, noise_intensity=0.6, noise_seed=11, noise_unit=2e-3)
# (a massless node needs a dashpot of its own under a white noise: the refusal's test below)
NOISY_RUNS = [(case, stepper) for case, stepper in ONE_NODE_RUNS if case not in ("massless", "massless_series")]


@pytest.mark.slow  # compiles the noisy forms of the element's and the network's kernels
@pytest.mark.parametrize("case,stepper", NOISY_RUNS)
def test_one_node_network_under_white_noise_is_the_element(case, stepper):
    """The same Brownian path (a function of the seed and the time alone) drives the element and the
    one-node network: the same x(t), each with its own scheme's rounding."""
    element_scene, network_scene = one_node_scenes(case, stepper, load=NOISY_LOAD)
    element = simulate_element(element_scene, stepper)
    network = simulate(network_scene, stepper)
    quiet = simulate(one_node_scenes(case, stepper)[1], stepper)
    x_scale = np.abs(element.x).max()
    assert np.abs(network.x[:, 0] - quiet.x[:, 0]).max() > 0.05 * x_scale  # the noise moves it
    np.testing.assert_allclose(network.x[:, 0], element.x, rtol=0, atol=1e-12 * x_scale)
    np.testing.assert_allclose(network.v[1:, 0], element.v[1:], rtol=0,
                               atol=1e-12 * (np.abs(element.v).max() + x_scale))


@pytest.mark.parametrize("case", ["massless", "massless_series"])
def test_white_noise_on_a_massless_node_without_dashpot_is_refused(case):
    """As the element refuses it (its series dashpots do not hold the node: a branch's force is at most k eta)."""
    element, network = one_node_scenes(case, "implicit", load=NOISY_LOAD, parse=lambda text: text)
    with pytest.raises(SceneError, match="white noise on a massless element without a dashpot"):
        parse_scene(element)
    with pytest.raises(SceneError, match="white noise on the massless node a with no dashpot"):
        parse_scene(network)


@pytest.mark.slow  # compiles the noisy forms of the network's kernels
def test_white_noise_network_does_not_depend_on_chunks_or_fmu_steps():
    """The path is a function of (seed, t): a run cut into chunks, a coarser output grid, and a NetworkElement
    advanced by uneven communication steps (whole numbers of steps) give the batch run's numbers bit for bit."""
    h = 2e-3
    _, scene = one_node_scenes("slider", "implicit", h=h, stop=3.0, output=10 * h, load=NOISY_LOAD)
    whole = simulate(scene)
    np.testing.assert_array_equal(np.concatenate([chunk.table for chunk in simulate_chunks(scene)]), whole.table)
    _, coarse = one_node_scenes("slider", "implicit", h=h, stop=3.0, output=50 * h, load=NOISY_LOAD)
    np.testing.assert_array_equal(simulate(coarse).table, whole.table[::5])
    element = NetworkElement(scene)
    rng = np.random.default_rng(3)
    for row in range(1, len(whole.time)):
        steps = 0
        while steps < 10:  # 10 steps per row, advanced in random pieces
            piece = int(min(10 - steps, rng.integers(1, 8)))
            element.advance(piece * h, 0.0, scene_load=True)
            steps += piece
        np.testing.assert_array_equal(element.x, whole.x[row])
        np.testing.assert_array_equal(element.v, whole.v[row])


@pytest.mark.slow  # about 10 s: long runs for the statistics
@pytest.mark.parametrize("stepper,stop", [("projected", 20000.0), ("implicit", 8000.0)])
def test_white_noise_network_reaches_the_gibbs_law(stepper, stop):
    """Two masses, a spring to the ground, a spring between them, a cubic spring and a dashpot from the loaded
    node to the ground, white noise sigma on that node: the noise and the damping act on the same node, so
    the stationary law is Gibbs's, exp(-E / T) with T = sigma^2 / (2 c) (fluctuation-dissipation; unique: the
    chain is controllable from the loaded node): <m v^2> = T at each node, and the positions' moments are
    integrals of exp(-V / T) (quadrature here). The schemes' bias is O(h): the estimate is extrapolated from
    h and h / 2 on the same Brownian path (2 m(h/2) - m(h), Richardson), and must agree with the law within 4
    standard errors (batch means over 40 batches of the extrapolated series)."""
    ma, mb, k1, k2, k3, c, sigma = 1.0, 0.5, 1.0, 2.0, 0.5, 0.8, 1.0
    temperature = sigma ** 2 / (2 * c)
    elements = [("spring", {"between": ["a", "ground"], "k": k1}), ("spring", {"between": ["a", "b"], "k": k2}),
                ("cubic", {"between": ["b", "ground"], "k3": k3}), ("dashpot", {"between": ["b", "ground"], "c": c})]
    load = {"kind": "white_noise", "intensity": sigma, "seed": 5, "noise_unit": 0.01}

    def moments(h):
        run = simulate(parse_scene(network_text(["a", "b"], [ma, mb], elements, load, solver(h, stop, 0.1, stepper))))
        late = slice(len(run.time) // 20, None)  # 5 % burn-in
        x, v = run.x[late], run.v[late]
        return np.stack([ma * v[:, 0] ** 2, mb * v[:, 1] ** 2, x[:, 0] ** 2, (x[:, 1] - x[:, 0]) ** 2])

    extrapolated = 2 * moments(0.005) - moments(0.01)
    batches = extrapolated[:, :extrapolated.shape[1] // 40 * 40].reshape(4, 40, -1).mean(axis=2)
    mean, error = batches.mean(axis=1), batches.std(axis=1, ddof=1) / np.sqrt(40)
    grid = np.linspace(-6.0, 6.0, 1201)
    xa, xb = np.meshgrid(grid, grid, indexing="ij")
    weight = np.exp(-(0.5 * k1 * xa ** 2 + 0.5 * k2 * (xb - xa) ** 2 + 0.25 * k3 * xb ** 4) / temperature)
    weight /= weight.sum()
    law = np.array([temperature, temperature, np.sum(weight * xa ** 2), np.sum(weight * (xb - xa) ** 2)])
    assert np.all(error < 0.03 * law)  # the statistics resolve a bias of a few per cent
    assert np.all(np.abs(mean - law) < 4 * error), (mean, law, error)


@pytest.mark.parametrize("case", ["massless", "massless_dashpot"])
def test_massless_network_passes_its_load_to_the_ground(case):
    """A massless network holds the whole load at every instant, t = 0 included: the reaction is F."""
    network = simulate(one_node_scenes(case, "implicit")[1])
    np.testing.assert_allclose(network.reaction, network.F, rtol=0, atol=1e-12 * np.abs(network.F).max())


def test_massless_dashpot_node_velocity_at_time_zero():
    """A massless node has no velocity of its own (docs/networks.md, Limits): its v is the rate of the step that
    ended at the row's time, d/h, and 0 in the initial row. The one-mass element reports the rate
    c v(0) = F(0) - (springs' and branches' forces) there instead; from the first step on the two agree (the
    one-node tests), and the network's reaction at t = 0 already holds the dashpot's force c v(0+)."""
    element_scene, network_scene = one_node_scenes("massless_dashpot", "implicit")
    c = ONE_NODE_CASES["massless_dashpot"]["damper"]
    F0 = ELEMENT_LOAD["offset"] + ELEMENT_LOAD["amplitude"]
    held_by_branches = sum(k * u for k, u in zip(BRANCHES["k"], BRANCHES["u0"]))  # x(0) = 0: no spring force
    rate = (F0 - held_by_branches) / c
    element = simulate_element(element_scene, "implicit")
    assert element.v[0] == pytest.approx(rate, rel=1e-12)
    network = simulate(network_scene)
    assert network.x[0, 0] == 0.0
    assert float(network.v[0, 0]) == 0.0  # the documented rule, not the element's rate
    # the reaction at t = 0 is F(0): the springs' and branches' forces plus the dashpot's c v(0+)
    assert float(network.reaction[0]) == pytest.approx(held_by_branches + c * rate, rel=1e-12)
    # and the first step's rate is the element's
    assert float(network.v[1, 0]) == pytest.approx(float(element.v[1]), rel=1e-12)


def test_cubic_spring_step_solves_backward_euler():
    """Mass, spring and cubic spring to the ground: each implicit step is backward Euler,
    m (v1 - v0) / h = F(t1) - k x1 - k3 x1^3 with x1 = x0 + h v1, to the rounding of its terms."""
    m, k, k3, h = 1.3, 0.2, 0.3, 2e-3
    elements = [("spring", {"between": ["a", "ground"], "k": k}), ("cubic", {"between": ["a", "ground"], "k3": k3})]
    result = simulate(parse_scene(network_text(["a"], [m], elements, ELEMENT_LOAD, solver(h, 12.0), x0=[0.05],
                                               v0=[0.2])))
    x, v, t = result.x[:, 0], result.v[:, 0], result.time
    F = ELEMENT_LOAD["offset"] + ELEMENT_LOAD["amplitude"] * np.cos(ELEMENT_LOAD["omega"] * t[1:])
    inertia = m * (v[1:] - v[:-1]) / h
    spring = k * x[1:] + k3 * x[1:] ** 3
    residual = inertia - (F - spring)
    # the rounding of the terms: m v / h (about 1e3 N here) times a few eps
    terms = m * (np.abs(v[1:]) + np.abs(v[:-1])) / h + np.abs(F) + np.abs(spring)
    assert np.abs(x).max() > 1.0  # the cubic spring matters
    bad = np.abs(residual) > 1e-13 * terms
    worst = int(np.argmax(np.abs(residual) / terms))
    assert not bad.any(), (f"{bad.sum()} of {bad.size} steps off backward Euler; worst: the step to t = "
                           f"{float(t[worst + 1])!r}, x = {float(x[worst + 1])!r}, v = {float(v[worst + 1])!r}: "
                           "residual "
                           f"{float(residual[worst])!r} N against terms of {float(terms[worst])!r} N")
    np.testing.assert_allclose(x[1:] - x[:-1], h * v[1:], rtol=0, atol=1e-15 * np.abs(x).max())


# ------------------------------------------------------------------ 4. energy

def energy_scene(h, stop=6.0, output=None, slider=True, stepper="implicit"):
    """Three masses: springs, a cubic spring, a dashpot, a branch with a series dashpot, sliders."""
    elements = [
        ("spring", {"between": ["a", "ground"], "k": 3.0}),
        ("spring", {"between": ["a", "b"], "k": 2.0}),
        ("cubic", {"between": ["b", "c"], "k3": 1.5}),
        ("spring", {"between": ["b", "c"], "k": 1.0}),
        ("dashpot", {"between": ["c", "ground"], "c": 0.2, "name": "damp_c"}),
        ("branch", {"between": ["b", "ground"], "k": 1.5, "eta": 0.05, "c": 2.0, "name": "br_b"}),
        ("branch", {"between": ["c", "a"], "k": 0.8, "eta": 0.1, "name": "br_ca"}),
    ]
    if slider:
        elements += [("slider", {"between": ["a", "b"], "alpha": 0.2, "name": "slip_ab"}),
                     ("slider", {"between": ["c", "ground"], "alpha": 0.15, "name": "slip_c"})]
    load = {"kind": "harmonic", "amplitude": 1.5, "omega": 1.7, "offset": 0.0}
    return parse_scene(network_text(["a", "b", "c"], [1.0, 0.6, 0.8], elements, load,
                                    solver(h, stop, output, stepper), v0=[0.0, 0.3, -0.2]))


@pytest.mark.parametrize("stepper", ["implicit", "projected"])
def test_energy_account_dissipation_and_the_sign_of_the_residual(stepper):
    h = 2e-3
    sliders = stepper == "implicit"  # projected: all plasticity in branches
    scene = energy_scene(h, slider=sliders, stepper=stepper)
    result = simulate(scene, states=True, energy=True)
    cols = result.columns()
    dissipations = [name for name in result.names if name.startswith("dissipated_")
                    and name not in ("dissipated_sliders", "dissipated_damper")]
    expected = {"dissipated_dashpot_damp_c", "dissipated_branch_br_b", "dissipated_branch_br_ca"}
    if sliders:
        expected |= {"dissipated_slider_slip_ab", "dissipated_slider_slip_c"}
    assert set(dissipations) == expected
    for name in dissipations + ["dissipated_sliders", "dissipated_damper"]:
        assert np.all(np.diff(cols[name]) >= 0), name
        assert cols[name][-1] > 0, name  # every element dissipated something in this run
    total = sum(cols[name] for name in dissipations)
    np.testing.assert_allclose(total, cols["dissipated_sliders"] + cols["dissipated_damper"], rtol=1e-12,
                               atol=1e-14)
    work = cols["work"]
    scale = np.abs(work).max()
    assert scale > 0.1
    if stepper == "implicit":
        # implicit Euler only dissipates: the residual (numerical dissipation) is never negative
        assert np.all(cols["energy_residual"] >= -1e-12 * scale)
        assert cols["energy_residual"][-1] > 0


def test_energy_dissipation_is_the_physics_of_each_element():
    """With a row every step: a slider dissipates alpha |slip| per step, a dashpot c (delta)^2 / h, and the load
    does F(t + h) times the step of its node (the implicit step's work)."""
    h = 2e-3
    result = simulate(energy_scene(h, stop=3.0), energy=True)
    x, cols = result.x, result.columns()
    a, b, c = x[:, 0], x[:, 1], x[:, 2]
    slip_ab = 0.2 * np.cumsum(np.abs(np.diff(a - b)))
    slip_c = 0.15 * np.cumsum(np.abs(np.diff(c)))
    dashpot = 0.2 * np.cumsum(np.diff(c) ** 2 / h)
    work = np.cumsum(result.F[1:] * np.diff(c))
    for name, expected in [("dissipated_slider_slip_ab", slip_ab), ("dissipated_slider_slip_c", slip_c),
                           ("dissipated_dashpot_damp_c", dashpot), ("work", work)]:
        got = cols[name][1:]
        np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max(), err_msg=name)


def test_energy_residual_goes_to_zero_like_h():
    """A smooth dynamic scene (no slider, branches elastic: eta large) so that the scheme's own dissipation
    is O(h) over a fixed time."""
    residuals = []
    steps = [4e-3, 2e-3, 1e-3, 5e-4]
    for h in steps:
        text = network_text(
            ["a", "b"], [1.0, 0.5],
            [("spring", {"between": ["a", "ground"], "k": 3.0}), ("spring", {"between": ["a", "b"], "k": 2.0}),
             ("dashpot", {"between": ["b", "ground"], "c": 0.1}),
             ("branch", {"between": ["b", "ground"], "k": 1.0, "eta": 100.0, "c": 3.0})],
            {"kind": "harmonic", "amplitude": 1.0, "omega": 1.3, "offset": 0.0}, solver(h, 4.0, 0.1),
            v0=[0.5, 0.0])
        cols = simulate(parse_scene(text), energy=True).columns()
        residuals.append(cols["energy_residual"][-1])
        assert np.all(cols["energy_residual"] >= -1e-12 * np.abs(cols["work"]).max())
    ratios = np.array(residuals[:-1]) / np.array(residuals[1:])
    assert residuals[-1] > 0
    np.testing.assert_allclose(ratios, 2.0, rtol=0.1)


# ------------------------------------------------------------------ 5. rate independence

def test_massless_network_is_rate_independent():
    """Same load path twice as fast with the same number of steps per unit of force: x(F) the same."""
    elements = [
        ("spring", {"between": ["a", "ground"], "k": 2.0}),
        ("branch", {"between": ["a", "b"], "k": 1.0, "eta": 0.3}),
        ("cubic", {"between": ["a", "b"], "k3": 0.5}),
        ("slider", {"between": ["b", "ground"], "alpha": 0.4}),
        ("branch", {"between": ["b", "ground"], "k": 0.7, "eta": 0.5}),
        ("spring", {"between": ["c", "b"], "k": 1.5}),
        ("slider", {"between": ["c", "ground"], "alpha": 0.2}),
    ]
    points = [0.0, 1.5, -1.0, 2.0, 0.3]
    runs = []
    for rate in (1.0, 2.0):
        load = ramp(points, 1.0 / rate)
        h = 0.005 / rate
        text = network_text(["a", "b", "c"], [0.0, 0.0, 0.0], elements, load, solver(h, load["time"][-1]))
        runs.append(simulate(parse_scene(text)))
    slow, fast = runs
    assert slow.x.shape == fast.x.shape
    np.testing.assert_allclose(fast.F, slow.F, rtol=0, atol=1e-13)
    scale = np.abs(slow.x).max()
    assert scale > 0.5
    np.testing.assert_allclose(fast.x, slow.x, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(fast.reaction, slow.reaction, rtol=0, atol=1e-13 * np.abs(slow.reaction).max())


# ------------------------------------------------------------------ 6. refusals

SIMPLE_LOAD = {"kind": "constant", "value": 1.0}
SIMPLE_SOLVER = solver(0.01, 1.0, 0.1)


def refused(text, *culprits):
    with pytest.raises(SceneError) as info:
        parse_scene(text)
    message = str(info.value)
    assert "\n" not in message and message.strip()
    for culprit in culprits:
        assert culprit in message, (culprit, message)
    return message


def test_refuses_a_node_with_no_path_to_the_load_or_ground():
    text = network_text(["a", "lost", "other"], [1.0, 1.0, 1.0],
                        [("spring", {"between": ["a", "ground"], "k": 1.0}),
                         ("spring", {"between": ["lost", "other"], "k": 1.0})],
                        SIMPLE_LOAD, SIMPLE_SOLVER, load_node="a")
    refused(text, "lost")


def test_refuses_a_massless_node_held_by_sliders_alone():
    text = network_text(["a", "floater"], [1.0, 0.0],
                        [("spring", {"between": ["a", "ground"], "k": 1.0}),
                         ("slider", {"between": ["floater", "ground"], "alpha": 1.0}),
                         ("slider", {"between": ["floater", "a"], "alpha": 1.0})],
                        SIMPLE_LOAD, SIMPLE_SOLVER, load_node="a")
    refused(text, "floater", "slider")


def test_refuses_an_element_between_a_node_and_itself():
    text = network_text(["a", "b"], [1.0, 1.0],
                        [("spring", {"between": ["a", "ground"], "k": 1.0}),
                         ("spring", {"between": ["b", "a"], "k": 1.0}),
                         ("dashpot", {"between": ["b", "b"], "c": 1.0})],
                        SIMPLE_LOAD, SIMPLE_SOLVER)
    refused(text, "'b'", "itself")


def test_refuses_ground_as_a_node_name():
    text = network_text(["a", "ground"], [1.0, 1.0], [("spring", {"between": ["a", "ground"], "k": 1.0})],
                        SIMPLE_LOAD, SIMPLE_SOLVER)
    refused(text, "ground", "reserved")


@pytest.mark.parametrize("where", ["top", "network", "element", "chain"])
def test_refuses_an_unknown_key(where):
    if where == "chain":
        text = table("chain", {"n": 3, "m": 1.0, "k": 1.0, "alpha": 0.1, "stiffness": 2.0}) + table(
            "solver", SIMPLE_SOLVER)
        refused(text, "stiffness")
        return
    text = network_text(["a"], [1.0], [("spring", {"between": ["a", "ground"], "k": 1.0, **(
        {"stiffnes": 2.0} if where == "element" else {})})], SIMPLE_LOAD, SIMPLE_SOLVER)
    if where == "network":
        text = text.replace("[network]\n", "[network]\nmasses = [1.0]\n")
        refused(text, "masses")
    elif where == "top":
        refused("colour = 3\n" + text, "colour")
    else:
        refused(text, "stiffnes")


def test_refuses_network_with_an_element_table():
    text = network_text(["a"], [1.0], [("spring", {"between": ["a", "ground"], "k": 1.0})], SIMPLE_LOAD,
                        SIMPLE_SOLVER) + table("mass", {"m": 1.0})
    refused(text, "[mass]")
    text = table("chain", {"n": 3, "m": 1.0, "k": 1.0, "alpha": 0.1}) + table("solver", SIMPLE_SOLVER)
    text += table("network", {"nodes": ["a"], "mass": [1.0]})
    refused(text, "[chain]", "[network]")


@pytest.mark.parametrize("stepper,case,culprit", [
    ("exact", "plain", "exact"),
    ("symplectic", "plain", "symplectic"),
    ("projected", "slider", "(slider_1)"),
    ("projected", "massless", "b is massless"),
])
def test_refuses_a_stepper_that_does_not_apply(stepper, case, culprit):
    elements = [("spring", {"between": ["a", "ground"], "k": 1.0}), ("spring", {"between": ["a", "b"], "k": 1.0})]
    if case == "slider":
        elements.append(("slider", {"between": ["b", "ground"], "alpha": 0.5}))
    mass = [1.0, 0.0 if case == "massless" else 1.0]
    text = network_text(["a", "b"], mass, elements, SIMPLE_LOAD, solver(0.01, 1.0, 0.1, stepper))
    message = refused(text, culprit, "stepper")
    assert "'implicit'" in message
    # the same network with the implicit stepper is accepted and runs; asked for the stepper that does not
    # apply, the run and the stepped object refuse (ValueError) with the same reason
    good = parse_scene(text.replace(f'stepper = "{stepper}"', 'stepper = "implicit"'))
    assert np.isfinite(simulate(good).x).all()
    with pytest.raises(ValueError, match=re.escape(culprit)):
        simulate(good, stepper)
    with pytest.raises(ValueError, match=re.escape(culprit)):
        NetworkElement(good, stepper)


# ------------------------------------------------------------------ 7. the CSV contract, parameter names

def test_columns_and_parameter_names_of_a_chain():
    scene = parse_scene(chain_text(4, [1.0, 0.0, 2.0, 0.5], [1.0, 2.0, 3.0], [0.1, 0.2, 0.3, 0.4],
                                   SIMPLE_LOAD, SIMPLE_SOLVER, k_wall=5.0, c=[0.5, 0.6, 0.7, 0.8]))
    nodes = [f"n{i}" for i in range(1, 5)]
    assert list(scene.network.nodes) == nodes
    result = simulate(scene)
    expected = ["time"] + [f"{axis}_{node}" for node in nodes for axis in ("x", "v")] + ["F", "reaction"]
    assert result.names == expected
    assert result.table.shape == (11, len(expected))
    assert list(result.columns()) == expected
    np.testing.assert_array_equal(result.x, result.table[:, [1, 3, 5, 7]])
    np.testing.assert_array_equal(result.v, result.table[:, [2, 4, 6, 8]])
    np.testing.assert_array_equal(result.F, 1.0)
    parameters = scene.network.parameters()
    expected_parameters = {"m_n1": 1.0, "m_n2": 0.0, "m_n3": 2.0, "m_n4": 0.5, "k_wall": 5.0,
                           "k_spring_1": 1.0, "k_spring_2": 2.0, "k_spring_3": 3.0,
                           "alpha_n1": 0.1, "alpha_n2": 0.2, "alpha_n3": 0.3, "alpha_n4": 0.4,
                           "c_n1": 0.5, "c_n2": 0.6, "c_n3": 0.7, "c_n4": 0.8}
    assert parameters == expected_parameters


def test_chain_is_its_network():
    """[chain] is the shorthand of a [network]: springs k_i between n<i> and n<i+1>, each node on a slider
    alpha_i and a dashpot c_i to the support, k_wall from n1 to the ground, the load on the last node."""
    m, k, alpha, c = [1.0, 0.0, 2.0, 0.5], [1.0, 2.0, 3.0], [0.1, 0.2, 0.3, 0.4], [0.5, 0.6, 0.7, 0.8]
    load = {"kind": "harmonic", "amplitude": 1.5, "omega": 2.0, "offset": 0.0}
    settings = solver(0.005, 5.0, 0.05)
    chain = simulate(parse_scene(chain_text(4, m, k, alpha, load, settings, k_wall=5.0, c=c)))
    nodes = ["n1", "n2", "n3", "n4"]
    elements = [("spring", {"between": ["n1", "ground"], "k": 5.0})]
    elements += [("spring", {"between": [nodes[i], nodes[i + 1]], "k": k[i]}) for i in range(3)]
    elements += [("slider", {"between": [nodes[i], "ground"], "alpha": alpha[i]}) for i in range(4)]
    elements += [("dashpot", {"between": [nodes[i], "ground"], "c": c[i]}) for i in range(4)]
    network = simulate(parse_scene(network_text(nodes, m, elements, load, settings)))
    assert network.names == chain.names
    assert np.abs(chain.x[:, -1]).max() > 0.1
    np.testing.assert_allclose(chain.table, network.table, rtol=0, atol=1e-13 * np.abs(chain.table).max())


def test_columns_with_states_and_energy_and_the_reaction():
    scene = energy_scene(0.01, stop=0.5, output=0.1)
    result = simulate(scene, states=True, energy=True)
    base = ["time", "x_a", "v_a", "x_b", "v_b", "x_c", "v_c", "F", "reaction"]
    energy = ["kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
              "energy_residual"]
    # the elements' own columns come by kind (spring, dashpot, slider, branch, cubic), in the scene's order
    per_element = ["dissipated_dashpot_damp_c", "dissipated_slider_slip_ab", "dissipated_slider_slip_c",
                   "dissipated_branch_br_b", "dissipated_branch_br_ca"]
    assert result.names == base + ["u_br_b", "u_br_ca"] + energy + per_element
    assert np.all(np.abs(result.column("u_br_b")) <= 0.05) and np.all(np.abs(result.column("u_br_ca")) <= 0.1)
    # an element without a name is <kind>_<its number among its kind>
    assert scene.network.parameters() == {
        "m_a": 1.0, "m_b": 0.6, "m_c": 0.8, "k_spring_1": 3.0, "k_spring_2": 2.0, "k_spring_3": 1.0,
        "c_damp_c": 0.2, "alpha_slip_ab": 0.2, "alpha_slip_c": 0.15, "k_br_b": 1.5, "eta_br_b": 0.05,
        "c_br_b": 2.0, "k_br_ca": 0.8, "eta_br_ca": 0.1, "c_br_ca": 0.0, "k3_cubic_1": 1.5}
    # the reaction of a network without sliders to the ground, from the state: the spring on a, the branch on
    # b, the dashpot on b at the step's velocity
    text = network_text(["a", "b"], [1.0, 0.5],
                        [("spring", {"between": ["a", "ground"], "k": 3.0}),
                         ("spring", {"between": ["a", "b"], "k": 2.0}),
                         ("dashpot", {"between": ["b", "ground"], "c": 0.4}),
                         ("branch", {"between": ["ground", "b"], "k": 1.0, "eta": 0.2, "u0": 0.1})],
                        HARMONIC, solver(0.01, 3.0, 0.01), v0=[0.5, 0.0])
    run = simulate(parse_scene(text), states=True)
    u = run.column("u_branch_1")
    # between = [ground, b]: u counts from the ground to b (x_b - x_ground), as written: u0 = 0.1 is u(0)
    assert u[0] == 0.1
    expected = 3.0 * run.x[:, 0] + 0.4 * run.v[:, 1] + 1.0 * u
    np.testing.assert_allclose(run.reaction, expected, rtol=0, atol=1e-13 * np.abs(expected).max())


@pytest.mark.parametrize("between", [("ground", "b"), ("b", "ground"), ("a", "b"), ("b", "a")])
def test_an_elongation_counts_from_the_first_end_to_the_second(between):
    """``between = [i, j]`` goes from i to j (issue 44.8: the finite-element convention): a branch's elongation
    is x_j - x_i, its u0 is u(0) as written, and a stretched branch (u0 > 0) pulls its ends together. An elastic
    branch (eta large) keeps u - u0 = (x_j - x_i) - (x_j(0) - x_i(0)) at every row, in every orientation."""
    text = network_text(["a", "b"], [1.0, 0.5],
                        [("spring", {"between": ["ground", "a"], "k": 3.0}),
                         ("spring", {"between": ["ground", "b"], "k": 1.0}),
                         ("branch", {"between": list(between), "k": 2.0, "eta": 10.0, "u0": 0.1})],
                        {"kind": "constant", "value": 0.0}, solver(0.01, 1.0, 0.01))
    run = simulate(parse_scene(text), states=True)
    position = {"ground": np.zeros(len(run.time)), "a": run.x[:, 0], "b": run.x[:, 1]}
    elongation = position[between[1]] - position[between[0]]
    u = run.column("u_branch_1")
    assert u[0] == 0.1
    np.testing.assert_allclose(u - 0.1, elongation - elongation[0], rtol=0, atol=1e-14)
    # the tension k u0 > 0 pulls the second end back towards the first: its first move is -x for j to the
    # right of i, so the elongation shrinks
    assert elongation[5] < elongation[0]


# ------------------------------------------------------------------ 8. output grid, chunks

def test_output_interval_and_chunks_do_not_change_the_numbers():
    h = 0.002
    every = simulate(energy_scene(h, stop=4.0, output=h))
    tenth = simulate(energy_scene(h, stop=4.0, output=10 * h))
    np.testing.assert_array_equal(every.table[::10], tenth.table)
    scene = energy_scene(h, stop=4.0, output=h)
    whole = simulate(scene, states=True, energy=True)
    chunks = list(simulate_chunks(scene, states=True, energy=True))
    assert len(chunks) >= 2
    np.testing.assert_array_equal(np.concatenate([c.table for c in chunks]), whole.table)
    # a stop time off the grid: the last row is the state at stop_time, the others unchanged
    odd = simulate(energy_scene(h, stop=4.0 - h, output=10 * h))
    np.testing.assert_array_equal(odd.table[:-1], tenth.table[:-1])
    assert odd.time[-1] == pytest.approx(4.0 - h)
    np.testing.assert_array_equal(odd.x[-1], every.x[-2])


# ------------------------------------------------------------------ 9. the stepped object

def stepped_scene(h=0.002, stop=2.0, value=0.7):
    elements = [
        ("spring", {"between": ["a", "ground"], "k": 3.0}),
        ("spring", {"between": ["a", "b"], "k": 2.0}),
        ("slider", {"between": ["b", "ground"], "alpha": 0.3}),
        ("branch", {"between": ["a", "b"], "k": 1.0, "eta": 0.1, "c": 2.0}),
        ("dashpot", {"between": ["b", "ground"], "c": 0.1}),
    ]
    return parse_scene(network_text(["a", "b"], [1.0, 0.5], elements, {"kind": "constant", "value": value},
                                    solver(h, stop, 10 * h), v0=[0.3, 0.0]))


@pytest.mark.parametrize("scene_load", [True, False])
def test_network_element_advances_as_simulate(scene_load):
    h = 0.002
    scene = stepped_scene(h)
    rows = simulate(scene)
    element = NetworkElement(scene)
    xs, vs = [element.x.copy()], [element.v.copy()]
    for _ in range(rows.table.shape[0] - 1):
        if scene_load:
            element.advance(10 * h, 0.0, scene_load=True)
        else:
            element.advance(10 * h, 0.7)
        xs.append(element.x.copy())
        vs.append(element.v.copy())
    assert element.time == pytest.approx(rows.time[-1])
    np.testing.assert_allclose(np.array(xs), rows.x, rtol=0, atol=1e-14 * np.abs(rows.x).max())
    np.testing.assert_allclose(np.array(vs), rows.v, rtol=0, atol=1e-14 * np.abs(rows.v).max())
    assert element.reaction == pytest.approx(rows.reaction[-1], rel=1e-12)


def test_network_element_state_round_trip_and_forged_states():
    h = 0.002
    scene = stepped_scene(h)
    first = NetworkElement(scene)
    for _ in range(30):
        first.advance(10 * h, 0.7)
    state = first.get_state()
    later = []
    for _ in range(30):
        first.advance(10 * h, 0.7)
        later.append(np.concatenate([first.x, first.v, first.u]))
    second = NetworkElement(scene)
    second.set_state(state)
    assert second.time == pytest.approx(state["time"])
    for expected in later:
        second.advance(10 * h, 0.7)
        np.testing.assert_array_equal(np.concatenate([second.x, second.v, second.u]), expected)
    assert second.energy() == first.energy()

    # forged states are refused whole, and the element is left as it was
    before = second.get_state()
    branch = [e.kind for e in scene.network.elements].index("branch")
    eta = scene.network.elements[branch].eta
    forgeries = {
        "x too short": dict(state, x=state["x"][:1]),
        "v NaN": dict(state, v=[float("nan"), 0.0]),
        "u beyond eta": dict(state, u=[1.5 * eta if e == branch else 0.0 for e in range(len(state["u"]))]),
        "u of a spring": dict(state, u=[0.01] + state["u"][1:]),
        "no x": {key: value for key, value in state.items() if key != "x"},
    }
    for what, forged in forgeries.items():
        with pytest.raises(ValueError) as info:
            second.set_state(forged)
        assert "\n" not in str(info.value), what
        after = second.get_state()
        assert after == before, what
    # and it continues as before
    second.advance(10 * h, 0.7)
    first_again = NetworkElement(scene)
    first_again.set_state(before)
    first_again.advance(10 * h, 0.7)
    np.testing.assert_array_equal(second.x, first_again.x)


# ------------------------------------------------------------------ 6 bis. the CLI

def test_cli_runs_a_network_and_refuses_with_one_line(tmp_path):
    path = tmp_path / "chain.toml"
    path.write_text(chain_text(3, 1.0, 2.0, 0.1, SIMPLE_LOAD, solver(0.01, 0.5, 0.1), k_wall=1.0))
    out = tmp_path / "out.csv"
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "run", str(path), "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    lines = out.read_text().splitlines()
    assert lines[0] == "time,x_n1,v_n1,x_n2,v_n2,x_n3,v_n3,F,reaction"
    table_read = np.loadtxt(out, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(table_read, simulate(parse_scene(path.read_text())).table)

    bad = tmp_path / "bad.toml"
    bad.write_text(network_text(["a", "a_b"], [1.0, 0.0],
                                [("spring", {"between": ["a", "ground"], "k": 1.0}),
                                 ("slider", {"between": ["a_b", "ground"], "alpha": 1.0}),
                                 ("slider", {"between": ["a_b", "a"], "alpha": 1.0})],
                                SIMPLE_LOAD, SIMPLE_SOLVER, load_node="a"))
    beyond = tmp_path / "beyond.toml"
    beyond.write_text(chain_text(3, 0.0, 2.0, 0.1, ramp([0.0, 0.5]), solver(0.01, 0.5, 0.1)))
    projected = tmp_path / "projected.toml"
    projected.write_text(network_text(["a"], [1.0], [("slider", {"between": ["a", "ground"], "alpha": 0.5}),
                                                   ("spring", {"between": ["a", "ground"], "k": 1.0})],
                                      SIMPLE_LOAD, solver(0.01, 1.0, 0.1, "projected")))
    for path, culprit in [(bad, "a_b"), (beyond, "no equilibrium"), (projected, "slider_1")]:
        done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "run", str(path), "--out",
                               str(tmp_path / "x.csv")], capture_output=True, text=True, timeout=300)
        assert done.returncode == 2, done.stderr
        assert len(done.stderr.strip().splitlines()) == 1, done.stderr
        assert "Traceback" not in done.stderr and culprit in done.stderr


def test_the_network_s_kernels_are_compiled_once_not_once_more_per_constant_argument():
    """The implicit step of a network is handed "no node imposed" and its counters and flags as int64 and bool,
    not as constants, for each of which numba compiled the step again (a literal is a signature of its own: the
    active-set step twice, 38 s of a cold suite). The cache of this run holds no kernel signature with a
    literal (tests/compiled_copies.py), after the kernels ran: a network's steps, its initial state (two masses
    and a slider, which the active-set method solves) and a massless chain (its own programme). ``solve_step``
    is inlined into its callers (no cache entry of its own): the methods it chooses between are checked."""
    from tests.compiled_copies import literal_signatures

    assert np.isfinite(simulate(two_masses(0.01, stop=0.5)[0]).x).all()
    assert np.isfinite(simulate(massless_chain(3, 1.0, 0.5, 1.0, 1.0, steps_per_second=64)).x).all()
    assert literal_signatures("kernels.active_set_step", "chain.chain_step", "kernels.run_implicit") == []
