"""Nonlinear modes by the extended periodic motion concept (EPMC, Krack 2015): the backbone of a jointed structure.

The free system with a negative viscous term that makes its motion periodic,

    M x'' + (C - xi M) x' + K x + g(x) = 0,

is solved by harmonic balance (``harmonic_balance.py``: H harmonics, the same AFT and Jacobian) for omega and
xi at each amplitude A of the first harmonic of x at the node: the phase is fixed by b_1 = 0 and the amplitude
by a_1 = A there, so x_node's first harmonic is A cos(omega t). The mode's frequency is omega / (2 pi) (Hz) and
its damping ratio xi / (2 omega): the viscous damping xi M that the motion needs to be undamped is the mode's
own damping. With one harmonic, a mass m on an element whose describing function is K(A), D(A) has
m omega^2 = K(A) and damping ratio D(A) / (2 pi K(A) A^2) (c / (2 m omega) more with a dashpot c).

The family starts from the linear mode with every branch sticking (the massless nodes condensed), at the first of
STARTS (shares of the lowest amplitude) where Newton from it converges with its shape (the MAC below), and is
stepped in ln A to each amplitude in turn, each step from the last solution scaled by the ratio of the amplitudes,
halved where Newton does not converge within NEWTON_ITERATIONS or does not land next to it (at most MAX_HALVINGS
times in a row; doubled after each success; at most MAX_MODE_STEPS solves between two amplitudes). Next to it
means the mass-weighted MAC of the first harmonics of the two points at least CONTINUES (another mode's shape is
M-orthogonal to it), their frequencies within STEP_FREQUENCY relative and their damping ratios within
STEP_DAMPING. Where a family turns back in the node's amplitude (its motion moving to another node as it grows, or
a fold of the backbone) no step past the turn lands next to it, and the backbone is refused there, saying how far
it was followed. Stepping A alone, Newton went on along another mode's family past such a turn (the packaged
two-mass joint's first mode at node a, past 0.853 m), and, with the shape's MAC alone, one long step past a fold
landed on the family's way back, whose shape is alike: the value at an amplitude depended on the amplitudes listed
(three masses and three branches, 0.2918 or 0.2981 Hz at 0.05 m).

:func:`synthesis`: the forced response near the mode's resonance from the backbone alone (single nonlinear
mode synthesis).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import DEFAULT_TOLERANCE, FrequencyError, check_tolerance, positive_values
from .harmonic_balance import NEWTON_ITERATIONS, harmonic_steps, HarmonicBalance, periodic_system, solve_linear
from .series import check_named, joined

MAX_HALVINGS = 30  # of a step in a row, where Newton does not converge or finds another motion
MAX_MODE_STEPS = 4000  # Newton solves from one amplitude to the next
STARTS = (1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)  # the first amplitude's tries: these shares of the lowest
CONTINUES = 0.9  # the mass-weighted MAC of the first harmonics of two neighbouring points of one family, at least
STEP_FREQUENCY = 0.05  # ... their frequencies' relative change, at most
STEP_DAMPING = 0.02  # ... their damping ratios' change, at most


@dataclass(frozen=True, eq=False)
class Backbone:
    """The nonlinear mode ``mode`` at each amplitude: arrays of shape (amplitudes,), in the order given.

    ``amplitude`` (m) of the first harmonic of x at ``node``, ``frequency`` (Hz), ``damping_ratio``;
    ``harmonics`` H; ``change`` the relative change at the last increase of H (None when H was given);
    ``shape`` the mode's first harmonic at every node per unit amplitude (complex, (amplitudes, n))."""

    amplitude: np.ndarray
    frequency: np.ndarray
    damping_ratio: np.ndarray
    mode: int
    node: str
    harmonics: Optional[int]  # None: a network with sliders, by shooting on its exact motion (nothing truncated)
    change: Optional[float]
    shape: np.ndarray  # (amplitudes, n) complex: the first harmonic a_1 - i b_1 of every node over the amplitude
    mass: np.ndarray  # (n,) the nodes' masses
    nodes: tuple

    def columns(self) -> dict:
        return {"amplitude": self.amplitude, "frequency": self.frequency, "damping_ratio": self.damping_ratio}


def nonlinear_mode(scene, mode: int, amplitudes, *, harmonics: Optional[int] = None, node: Optional[str] = None,
                   tolerance: float = DEFAULT_TOLERANCE, samples: Optional[int] = None,
                   load_node: Optional[str] = None) -> Backbone:
    """The backbone of nonlinear mode ``mode`` (1: the lowest) of ``scene`` at ``amplitudes`` (m, of x at
    ``node``; default the first node with a mass) (see the module); ``samples``: N of the AFT (default
    ``harmonic_balance.sample_count``); ``load_node``: a node the synthesis will load (kept in the mode's shape
    where a massless node would be joined away). FrequencyError names the culprit."""
    amplitudes = positive_values(amplitudes, "amplitudes")
    tolerance = check_tolerance(tolerance)
    if getattr(scene, "friction", None) is not None:
        if _friction_taylor(scene):  # a belt, a Stribeck drop, a history or a delay: the element's Taylor orbit
            return _slider_mode(scene, mode, amplitudes, node, tolerance, load_node)
        scene = _friction_network(scene, tolerance)
    check_named(scene, node, load_node)
    scene = joined(scene, keep=(node, load_node))  # a Jenkins element written with its massless node: a branch
    if any(e.kind == "slider" for e in getattr(getattr(scene, "network", None), "elements", ())):
        return _slider_mode(scene, mode, amplitudes, node, tolerance, load_node)
    system = periodic_system(scene, tolerance=tolerance)
    where = system.node_index(node)
    if harmonics is not None:
        values, shape = _backbone(system, mode, amplitudes, where, harmonics, samples)
        change = None
    else:
        previous, change = None, math.inf
        steps = harmonic_steps(system.n)
        for H in steps:
            values, shape = _backbone(system, mode, amplitudes, where, H, samples)
            if previous is not None:
                change = float(np.max(np.abs(values - previous) / np.maximum(np.abs(values), 1e-300)))
                if change <= tolerance:
                    harmonics = H
                    break
            previous = values
        else:
            raise FrequencyError(f"{system.source}: the mode's frequency and damping still changed by {change:.3g} "
                                 f"relative from H = {steps[-2]} to {steps[-1]} harmonics: give "
                                 "--harmonics, or a larger --tolerance")
    return Backbone(amplitudes, values[:, 0] / (2.0 * math.pi), values[:, 1] / (2.0 * values[:, 0]), mode,
                    system.nodes[where], harmonics, change, shape, system.mass.copy(), system.nodes)


def _friction_taylor(scene) -> bool:
    """Whether the modes of an element with ``[friction]`` are solved for on its own Taylor orbit
    (``slider_modes.FreeElement``): a moving belt, a Stribeck drop, a history or a delay beside the friction (the
    network of one node, ``_friction_network``, takes a spring, a cubic spring, a dashpot, branches and Coulomb
    friction on a fixed ground)."""
    friction = scene.friction
    return scene.mass is not None and (friction.belt_velocity != 0.0 or friction.alpha_kinetic != friction.alpha
                                       or scene.history is not None or scene.delay is not None)


def _friction_network(scene, tolerance: float):
    """An element with ``[friction]`` on its mass as the network of one node ``mass`` (its spring, dashpot,
    branches and a slider of the friction's alpha to the ground), whose modes ``slider_modes.py`` takes;
    FrequencyError for what it does not take."""
    from ..network.model import Element, Network, NetworkScene
    from .harmonic_balance import ELEMENT_NODE, spectrum_branches

    friction = scene.friction
    if scene.mass is None:
        raise FrequencyError(f"{scene.source}: the nonlinear modes need [mass]")
    # (a Stribeck drop, a history or a delay: _friction_taylor; [dahl] with [friction] the scene refuses)
    elements = [Element("slider", "friction", (0, -1), float(friction.alpha))]
    if scene.spring is not None and scene.spring.k0 > 0:
        elements.append(Element("spring", "k0", (0, -1), float(scene.spring.k0)))
    if scene.has_dashpot:
        elements.append(Element("dashpot", "c", (0, -1), float(scene.damper.c)))
    if scene.cubic is not None and scene.cubic.k3 > 0:
        elements.append(Element("cubic", "k3", (0, -1), float(scene.cubic.k3)))
    if scene.branches is not None:
        if scene.branches.continuum:
            k, eta = spectrum_branches(scene.branches, tolerance, scene.source)
        else:
            k, eta = scene.branches.stiffness, scene.branches.yield_displacement
        # their series dashpots too (they were left out: the mode of the branches without them, silently)
        c = np.zeros(len(k)) if scene.branches.damping is None else np.asarray(scene.branches.damping, float)
        elements += [Element("branch", f"branch_{i + 1}", (0, -1), float(k_i), float(eta_i), float(c_i))
                     for i, (k_i, eta_i, c_i) in enumerate(zip(np.asarray(k).tolist(), np.asarray(eta).tolist(),
                                                                c.tolist()))]
    network = Network((ELEMENT_NODE,), np.array([float(scene.mass.m)]), np.zeros(1), np.zeros(1), tuple(elements), 0)
    return NetworkScene(scene.name, network, scene.load, scene.solver, scene.source)


def _slider_mode(scene, mode: int, amplitudes: np.ndarray, node: Optional[str], tolerance: float,
                 load_node: Optional[str] = None) -> Backbone:
    """A network with rigid sliders: EPMC by shooting on its exact motion (``slider_modes.py``): no harmonics
    are truncated (``harmonics`` None), ``change`` that of the samples' last doubling; where the backbone turns
    back in amplitude, a listed amplitude has a row for each of its points there."""
    from ..network.model import NetworkScene
    from .harmonic_balance import ELEMENT_NODE
    from .shooting import ShootingSystem, prepared_network
    from .slider_modes import slider_backbone

    extra = {}  # massless nodes named or loaded: their x as weights over the nodes
    pulls = None  # the massless node named, with a slider or branch on it: weights over those levers' tensions
    if isinstance(scene, NetworkScene):
        # massless nodes condensed (series.condensed); the node named and the node loaded kept as weights
        scene, observed = prepared_network(scene, node, load_node, "the nonlinear modes", observe=True)
        nodes, mass = tuple(scene.network.nodes), np.array(scene.network.mass, float)
        for name, (weights, _, tensions) in observed.views.items():
            extra[name] = np.array([weights.get(other, 0.0) for other in nodes])
            if tensions:
                pulls = dict(tensions)
        if load_node is not None and load_node not in nodes:  # its force passes on as its weights: x_p's
            extra[load_node] = np.array([observed.load.get(other, 0.0) for other in nodes])
    else:  # an element with friction on its Taylor orbit (_friction_taylor)
        nodes, mass = (ELEMENT_NODE,), np.array([float(scene.mass.m)])
        if load_node is not None and load_node != ELEMENT_NODE:
            raise FrequencyError(f"--load-node: {load_node!r} is not a node of {scene.source} ({ELEMENT_NODE})")
    if node in extra:
        probe, name = extra[node], node
    else:
        where = ShootingSystem(scene.name, scene.source, nodes, mass).node_index(node)
        probe, name = np.eye(len(nodes))[where], nodes[where]
    values, shape, rows, change, at_node = slider_backbone(scene, mode, amplitudes, probe, name, tolerance, pulls)
    # the massless nodes' columns: their weighted means of the shape (massless: no share of the modal mass); the
    # node named with a lever's tension in its motion: its first harmonic per unit amplitude, from the equations
    shape = np.hstack([shape] + [at_node[:, None] if other == node and pulls else
                                 (shape @ weights)[:, None] for other, weights in extra.items()])
    return Backbone(rows, values[:, 0] / (2.0 * math.pi), values[:, 1] / (2.0 * values[:, 0]), mode, name, None,
                    change, shape, np.concatenate((mass, np.zeros(len(extra)))), nodes + tuple(extra))


def synthesis(backbone: Backbone, force_amplitude: float, load_node: Optional[str] = None) -> tuple:
    """The forced response under F0 cos(Omega t) on ``load_node`` (default: the backbone's node) synthesised from
    the one nonlinear mode (single nonlinear mode synthesis): at each amplitude a of the backbone, with omega(a),
    zeta(a) and the shape psi(a) (per unit amplitude), the modal equation

        (omega^2 - Omega^2 + 2 i zeta omega Omega) m_psi a = conj(psi_L) F0,    m_psi = sum_i m_i |psi_i|^2,

    gives |.| = F0 |psi_L| / (m_psi a), a quadratic in Omega^2: up to two Omega per amplitude, below and above
    the backbone. Where the mode dominates the response (near its resonance, modes well apart) it is the
    forced response; with one harmonic and a conservative nonlinearity plus viscous damping it is exactly the
    harmonic balance's. Returns ``(frequency (Hz), amplitude (m))`` along the curve: up the lower side, down
    the upper side (amplitudes where the force cannot reach are left out)."""
    force_amplitude = float(positive_values([force_amplitude], "force amplitude")[0])
    where = backbone.nodes.index(load_node) if load_node is not None else backbone.nodes.index(backbone.node)
    if np.unique(backbone.amplitude).size < backbone.amplitude.size:
        raise FrequencyError(f"the backbone of mode {backbone.mode} has several points at one amplitude at node "
                             f"{backbone.node} (it turns back in amplitude there): single nonlinear mode synthesis "
                             "needs one per amplitude; take it at another --node, or compute the forced response")
    a = backbone.amplitude
    order = np.argsort(a)
    a = a[order]
    omega = 2.0 * math.pi * backbone.frequency[order]
    zeta = backbone.damping_ratio[order]
    shape = backbone.shape[order]
    modal_mass = np.sum(backbone.mass[None, :] * np.abs(shape) ** 2, axis=1)
    right = (force_amplitude * np.abs(shape[:, where]) / (modal_mass * a)) ** 2
    # Omega^4 + (4 zeta^2 - 2) omega^2 Omega^2 + omega^4 - right = 0
    b = (4.0 * zeta**2 - 2.0) * omega**2
    disc = b * b - 4.0 * (omega**4 - right)
    with np.errstate(invalid="ignore"):
        root = np.sqrt(disc)
        low = np.sqrt((-b - root) / 2.0)
        high = np.sqrt((-b + root) / 2.0)
    low_ok, high_ok = np.isfinite(low) & (disc >= 0), np.isfinite(high) & (disc >= 0)
    frequency = np.concatenate((low[low_ok], high[high_ok][::-1])) / (2.0 * math.pi)
    amplitude = np.concatenate((a[low_ok], a[high_ok][::-1]))
    return frequency, amplitude


def linear_mode(system, mode: int) -> tuple:
    """(omega (rad/s), shape (n,)) of the linear mode ``mode`` with every branch sticking, the massless nodes
    condensed."""
    stuck = system.stiffness.copy()
    for (p, r), k in zip(system.branch_ends.tolist(), system.branch_k.tolist()):
        stuck[p, p] += k
        if r >= 0:
            stuck[r, r] += k
            stuck[p, r] -= k
            stuck[r, p] -= k
    massive = system.massive
    massless = [i for i in range(system.n) if i not in massive]
    if mode > len(massive):
        raise FrequencyError(f"--mode: {system.source} has {len(massive)} node(s) with a mass, so "
                             f"{len(massive)} mode(s); got {mode}")
    K = stuck[np.ix_(massive, massive)]
    coupling = stuck[np.ix_(massless, massive)]
    if massless:
        condensed = np.linalg.solve(stuck[np.ix_(massless, massless)], coupling)
        K = K - stuck[np.ix_(massive, massless)] @ condensed
    scale = 1.0 / np.sqrt(system.mass[massive])
    values, vectors = np.linalg.eigh(scale[:, None] * K * scale[None, :])
    if values[mode - 1] <= 0:
        raise FrequencyError(f"{system.source}: mode {mode} has no stiffness with every branch sticking (a rigid-body "
                             "mode): nothing holds it")
    shape = np.zeros(system.n)
    shape[massive] = vectors[:, mode - 1] * scale
    if massless:
        shape[massless] = -condensed @ shape[massive]
    return math.sqrt(values[mode - 1]), shape


def _backbone(system, mode: int, amplitudes: np.ndarray, where: int, harmonics: int, samples) -> np.ndarray:
    """((amplitudes, 2): omega and xi at each amplitude, (amplitudes, n): the first harmonic of every node per
    unit amplitude), in the order given."""
    balance = HarmonicBalance(system, harmonics, 1.0, samples)
    L = balance.L
    free = list(balance.free)
    fixed = [free.index(where * L + 1), free.index(where * L + 2)]
    keep = np.array([i for i in range(len(free)) if i not in fixed], dtype=np.int64)
    omega0, shape = linear_mode(system, mode)
    if abs(shape[where]) < 1e-9 * np.max(np.abs(shape)):
        raise FrequencyError(f"--node: mode {mode} does not move node {system.nodes[where]}: its amplitude cannot "
                             "set the mode's (choose another --node)")
    C = np.diag(system.mass)
    xi0 = float(shape @ system.damping @ shape / (shape @ C @ shape))
    order = np.argsort(amplitudes)
    out = np.empty((amplitudes.size, 2))
    shapes = np.empty((amplitudes.size, system.n), dtype=complex)
    state = None
    last = None
    for index in order.tolist():
        A = float(amplitudes[index])
        if state is None:  # from the linear mode, at the smallest of STARTS where Newton converges with its shape
            q = np.zeros(len(free))
            for i in range(system.n):
                if i * L + 1 in free:
                    q[free.index(i * L + 1)] = shape[i] / shape[where] * A
            for share in STARTS:
                state, last = _newton(balance, q * share, omega0, xi0, fixed, keep, share * A), share * A
                if state is not None and _alike(balance, system, q, state[0]):
                    break
            else:
                raise FrequencyError(f"{system.source}: the nonlinear mode {mode} did not converge with the linear "
                                     f"mode's shape at any amplitude from {STARTS[0] * A!r} to {float(A)!r} m (H = "
                                     f"{harmonics})")
        state, reached, left = _stepped(balance, system, state, last, A, fixed, keep)
        if state is None:
            found = ("finds only another motion (its shape's MAC against the family's last point below "
                     f"{CONTINUES}) or does not converge" if left else
                     f"does not converge within {NEWTON_ITERATIONS} iterations")
            raise FrequencyError(
                f"{system.source}: mode {mode} does not reach A = {float(A)!r} m at node {system.nodes[where]} "
                f"(H = {harmonics}): its family was followed to {reached:.6g} m there, and past it Newton {found}, "
                f"the step halved {MAX_HALVINGS} times: the family turns back in that node's amplitude (while "
                "another node's grows) or ends there: choose amplitudes below it, or another --node")
        last = A
        out[index] = state[1], state[2]
        full = balance.full(state[0]).reshape(system.n, L)
        shapes[index] = (full[:, 1] - 1j * full[:, 2]) / A
    return out, shapes


def _shape(balance, system, q) -> np.ndarray:
    """The first harmonic of every node (complex), of the balance's unknowns ``q``."""
    full = balance.full(q).reshape(system.n, balance.L)
    return full[:, 1] - 1j * full[:, 2]


def _alike(balance, system, first, second) -> bool:
    """Whether the first harmonics of unknowns ``first`` and ``second`` have a mass-weighted MAC of at least
    CONTINUES (another mode's shape is M-orthogonal: near 0)."""
    first, second = _shape(balance, system, first), _shape(balance, system, second)
    weights = np.asarray(system.mass, dtype=float)
    inner = abs(np.sum(weights * np.conj(first) * second)) ** 2
    size = float(np.sum(weights * np.abs(first) ** 2) * np.sum(weights * np.abs(second) ** 2))
    return size > 0.0 and inner >= CONTINUES * size


def _continues(balance, system, before, after, A_before, A_after) -> bool:
    """Whether ``after`` (at A_after) is the neighbour of ``before`` (at A_before) on its family: the
    mass-weighted MAC of their first harmonics at least CONTINUES (another mode's shape is M-orthogonal to it:
    near 0), their frequencies within STEP_FREQUENCY relative and their damping ratios within STEP_DAMPING (a
    step that changes more is halved: so a family that passes an amplitude twice, up to a turn and back, is
    not entered on its way back by one long step past the turn, whose shape can be alike)."""
    (_, omega, xi), (_, omega_after, xi_after) = before, after
    return _alike(balance, system, before[0], after[0]) and abs(omega_after / omega - 1.0) <= STEP_FREQUENCY and \
        abs(xi_after / (2.0 * omega_after) - xi / (2.0 * omega)) <= STEP_DAMPING


def _stepped(balance, system, state, A_from, A_to, fixed, keep) -> tuple:
    """From the solution at A_from to A_to in steps of ln A, each point on the family of the last
    (:func:`_continues`): halved where Newton does not converge or lands on another motion (at most MAX_HALVINGS
    times in a row), doubled after each success, at most MAX_MODE_STEPS Newton solves. ``(state or None,
    the amplitude reached, whether the last failures found another motion)``."""
    q, omega, xi = state
    current = A_from
    step = math.log(A_to / A_from)
    halvings = left = 0
    for _ in range(MAX_MODE_STEPS):
        if current == A_to:
            return (q, omega, xi), current, False
        remaining = math.log(A_to / current)
        target = A_to if abs(step) >= abs(remaining) else current * math.exp(step)
        trial = _newton(balance, q * (target / current), omega, xi, fixed, keep, target)
        if trial is not None and _continues(balance, system, (q, omega, xi), trial, current, target):
            q, omega, xi = trial
            current = target
            halvings, left = 0, 0
            step = math.copysign(min(2.0 * abs(step), abs(math.log(A_to / A_from))), remaining)
            continue
        left += trial is not None
        halvings += 1
        if halvings > MAX_HALVINGS:
            return None, current, left > 0
        step *= 0.5
    return None, current, False


def _newton(balance, q, omega, xi, fixed, keep, A):
    """(q, omega, xi) of the mode at amplitude A by Newton from the guess, or None."""
    q = np.array(q, dtype=float)
    q[fixed[0]], q[fixed[1]] = A, 0.0
    for _ in range(NEWTON_ITERATIONS):
        residual, jacobian, by_omega, by_xi = balance.evaluate(q, omega, xi, forced=False)
        matrix = np.hstack((jacobian[:, keep], by_omega[:, None], by_xi[:, None]))
        step = solve_linear(matrix, -residual)
        if step is None:
            return None
        q[keep] += step[:-2]
        omega += step[-2]
        xi += step[-1]
        if not omega > 0:
            return None
        small = np.max(np.abs(step[:-2]), initial=0.0) <= 1e-10 * np.max(np.abs(q)) and abs(step[-2]) <= 1e-10 * omega and \
            abs(step[-1]) <= 1e-10 * max(abs(xi), 1e-6 * omega)
        if small:
            return q, omega, xi
    return None
