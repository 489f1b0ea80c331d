"""Nonlinear modes (EPMC) of a network with rigid sliders, by shooting on its motion (``network_orbit.py``).

The free network with the extended periodic motion concept's negative viscous term,

    M x'' + (C - xi M) x' + K x + (branches) + (sliders) = 0,

is periodic for the mode's own xi. Harmonic balance cannot sample a rigid slider (its force while it sticks is
set by the other forces, not by the motion: ``shooting.py`` says why), so the periodic state is solved for as
in the forced response of such a network: the fixed point of the exact motion over half a period (every force
is odd, so x(t + T/2) = -x(t)). The unknowns are s = (x, v / omega_ref, u of the branches) at t = 0, omega and
xi; the equations

    -Phi(s; omega, xi) - s = 0,     a_1 = A,     b_1 = 0,

a_1, b_1 the first harmonic of x at the node (x_node = A cos(omega t) + higher harmonics: the amplitude sets
the mode's size, b_1 = 0 its phase, which the free motion leaves open). A massless node named with a slider or
branch on it (a lever of ``series.condensed``) moves with its springs' weighted mean less the lever's tension
k u; on a rigid slider it stands still while the slider sticks, where the family starts, so there the phase (and
the start's amplitude) are those of the node with a mass that moves most, the anchor, and the named node's
amplitude is |a_1 - i b_1|. The motion is the exact one between
events whatever xi (the damping matrix C - xi M only changes the linear flow; which sliders hold is decided on
the forces, as for c >= 0). The mode's frequency is omega / (2 pi), its damping ratio xi / (2 omega).

Newton's method on (s, omega, xi), its Jacobian by forward differences (N + 2 runs of half a period), each
step halved while the residual grows (at most HALVINGS times), at most NEWTON_ITERATIONS steps.

**The backbone through its folds.** Where a slider starts to slip, the mode's family need not be a graph of
the node's amplitude (measured on two masses and a joint, docs/frequency.md: every amplitude measure tried, the
node's a_1, the mass-weighted first harmonic, the energy, turns back near slip onset; the node's a_1 can even stay
bounded while the other mass's amplitude grows without bound). So the family is followed without an amplitude
condition: pseudo-arclength continuation of the half-period map's fixed point with the phase condition b_1 = 0
at the node, in (s, omega, xi), from the linear mode with every slider and branch sticking at half the amplitude
where the first would slip (there the orbit is that mode's exactly), or, where the stuck sliders leave no mode,
from the lowest amplitude with the sliders free and xi from the energy that each dissipates per cycle, until the
largest node's first harmonic is FAMILY_BEYOND times the largest listed amplitude. At each listed amplitude, every
point of the family where the node's a_1 is that amplitude (Newton from the curve's points on either side): one
row each, in their order along the family, so a fold gives a listed amplitude several rows; an amplitude the
family never reaches at the node is refused with the largest it reaches. Where the family is left, the node's
a_1 may still be moving (on two masses and a joint it tends to a limit from below while the other mass's
amplitude grows without bound, so an amplitude just below the limit has one more point far out): an amplitude
within the node's move over the last doubling of the largest amplitude from where it was left is refused, not
answered without that point (the move is assumed to shrink as the amplitude doubles, as it does there).

**On a moving belt** (an element whose friction acts on the slip v - V) no half-period symmetry holds: the map
is the whole period's, x(T) = x(0), the Prandtl branches' rows the forced response's convention
(``ElementShooting._centred``), a_1 and b_1 over the whole period. While A omega < |V| the mass slides one way
and the mode is the linear one about the drag's offset (its damping c less the Stribeck drop's slope there, which
can make it negative: steady sliding excites itself); where it first reaches the belt's speed the family has a
kink that the arc-length corrector does not pass (Newton cycled between the two sides' Jacobians), and is
passed at a fixed amplitude just above (:func:`_past_kink`). Where the damping ratio is 0 the orbit is the
scene's own stick-slip limit cycle (the tests: its period and amplitude from an independent integration).

The amplitude condition uses the trapezoid rule on M samples per period (x is C^1: an error like 1 / M^2): the
backbone is followed at M = FIRST_STEPS, then its rows solved again with M doubled until the frequency and the
damping ratio change by at most half the tolerance (relative; past MAX_STEPS refused with the change).
"""
from __future__ import annotations

import math

import numpy as np

from . import FrequencyError
from .harmonic_balance import solve_linear
from .shooting import FIRST_STEPS, MAX_STEPS, PERTURBATION, ElementShooting, NetworkShooting, StepFailed, \
    prepared_network

NEWTON_ITERATIONS = 40
HALVINGS = 8
CONVERGED = 1e-11  # a Newton step below this (relative to the orbit, or to omega) has converged


class _Free:
    """The free system (no force) with damping C - xi M: :meth:`equations` of (s, omega, xi) at amplitude A, and
    Newton's method on them; a shooting's ``run`` and ``coefficients``, and ``damping`` that the equations set.
    ``anchor``: where the node named stands still along the mode's start (a massless node on a rigid slider),
    the node with a mass whose phase the equations fix instead (:func:`_anchored`); ``at_anchor``: the amplitude
    condition on the anchor's a_1 (the start) rather than on the node's |a_1|."""

    anchor = None
    at_anchor = False

    def equations(self, z: np.ndarray, A: float) -> np.ndarray:
        """The N + 2 residuals at z = (s, omega, xi) (m): the half-period map's, then a_1 - A and b_1."""
        residual, X, node = _family_equations(self, z)
        if self.anchor is None:
            return np.concatenate((residual[:-1], [node.real - A], residual[-1:]))
        # anchored (the node stands still while its slider sticks): the phase is the anchor's, so the node's
        # amplitude is |a_1 - i b_1|; at the start (``at_anchor``) the amplitude is the anchor's
        measure = X[self.anchor].real if self.at_anchor else abs(node)
        return np.concatenate((residual[:-1], [measure - A], residual[-1:]))

    def jacobian_of(self, z: np.ndarray, A: float, residual: np.ndarray) -> np.ndarray:
        """d equations / dz by forward differences (PERTURBATION of the orbit's size, of omega for omega and xi)."""
        N = self.dimension
        size = max(float(np.max(np.abs(z[:N]))), A)
        steps = np.concatenate((np.full(N, PERTURBATION * size), [PERTURBATION * z[N]] * 2))
        jacobian = np.empty((N + 2, N + 2))
        for k in range(N + 2):
            moved = z.copy()
            moved[k] += steps[k]
            jacobian[:, k] = (self.equations(moved, A) - residual) / steps[k]
        return jacobian

    def solve(self, z: np.ndarray, A: float):
        """Newton from ``z`` at amplitude A (see the module): the solution, or None."""
        N = self.dimension
        z = np.array(z, dtype=float)
        try:
            residual = self.equations(z, A)
            for _ in range(NEWTON_ITERATIONS):
                size = max(float(np.max(np.abs(z[:N]))), A)
                step = solve_linear(self.jacobian_of(z, A, residual), -residual)
                if step is None:
                    return None
                for _ in range(HALVINGS + 1):
                    trial = z + step
                    try:
                        new = self.equations(trial, A)
                    except StepFailed:
                        new = None
                    if new is not None and np.max(np.abs(new)) <= np.max(np.abs(residual)):
                        break
                    step = 0.5 * step
                if new is None:
                    return None
                z, residual = trial, new
                if np.max(np.abs(step[:N])) <= CONVERGED * size and abs(step[N]) <= CONVERGED * z[N] and \
                        abs(step[N + 1]) <= CONVERGED * z[N]:
                    return z
        except StepFailed:
            return None
        return None


class FreeShooting(_Free, NetworkShooting):
    """The free network with sliders (``network_orbit.py``)."""

    def __init__(self, scene, steps: int, reference: float, probe: np.ndarray, name: str, pulls=None):
        super().__init__(scene, 0.0, None, steps, 7, reference)
        self.viscous = self.damping.copy()
        self.probe = np.asarray(probe, dtype=float)  # the node's x as weights over the nodes (see _free_systems)
        self.name = name
        # a massless node named with a slider or branch on it (series.Observed): its x takes weights of those
        # levers' tensions k u too, {lever: weight}, here over the branches in the order of s
        self.pulls = np.zeros(self.branches)
        for lever, weight in (pulls or {}).items():
            if lever not in self.branch_names:  # a lever with a dashpot: its u relaxes, no state of the mode's start
                raise FrequencyError(f"--node: {name} is massless, on the lever {lever} with a dashpot: the nonlinear "
                                     "modes do not take its motion (the forced response does): name a node with a "
                                     "mass")
            self.pulls[self.branch_names.index(lever)] = weight
        n = self.system.n
        self.state_probe = np.zeros(self.dimension)  # the node's x(0) from s, to first order
        self.state_probe[:n] = self.probe
        self.state_probe[2 * n:2 * n + self.branches] = self.pulls * self.bk
        self.linear_probe = self.probe + (self.pulls * self.bk) @ self.brows  # ... along a mode with all stuck


class FreeElement(_Free, ElementShooting):
    """The free element with friction on its mass whose orbit is ``element_orbit.py``'s Taylor series (a Stribeck
    drop, a history, a delay: the delay's harmonics are unknowns of s, as in the forced response), presented as
    a network of one node: its spring and stuck branches (the linear start's stiffness), the friction a slider
    to the ground; ``damping`` (1, 1) is the Taylor orbit's c, which the equations set to c - xi m."""

    def __init__(self, scene, steps: int, reference: float):
        super().__init__(scene, 0.0, None, steps, 7, reference)
        if not self.smooth:
            raise ValueError("FreeElement: an element whose orbit is the Taylor series (shooting.smooth)")
        self.probe = self.linear_probe = np.ones(1)
        self.pulls = np.zeros(0)
        self.state_probe = np.eye(self.dimension)[0]
        self.name = self.system.nodes[0]
        self.stiffness_matrix = np.array([[self.parameters[1]]])
        self.viscous = np.array([[self.parameters[2]]])
        self.rows = np.ones((1, 1))
        self.alpha = np.array([float(scene.friction.alpha)])
        self.bk = np.array(self.parameters[7], float)
        self.brows = np.ones((self.bk.size, 1))
        if not self.symmetric:  # on a belt the friction slips at small amplitudes: no slider holds the mass
            self.rows = np.zeros((0, 1))

    def belt_start(self, omega: float) -> tuple:
        """On a belt, what the linear start (:func:`_linear_start`) takes from the friction: (the mean friction
        force's static deflection x_0 (m), the friction's linear damping d (N s/m), the amplitude where the mass
        first reaches the belt's speed, |V| / omega). At a slip V - v of the belt's sign the friction is
        f(|V - v|) = alpha_k + (alpha - alpha_k) exp(-|V - v| / v_s) along V: about v = 0, f(|V|) and the
        damping d = f'(|V|) (negative on a Stribeck drop: the drop feeds the motion); x_0 = sign(V) f(|V|) / k
        over the static stiffness k (the spring's, a history's and a delay's on x)."""
        m, k0, c, k3, alpha, alpha_k, vs = self.parameters[:7]
        V = self.belt
        drop = alpha - alpha_k if vs > 0.0 else 0.0
        force = alpha_k + drop * math.exp(-abs(V) / vs) if vs > 0.0 else alpha
        slope = -drop / vs * math.exp(-abs(V) / vs) if vs > 0.0 else 0.0
        static = self.static_stiffness
        offset = math.copysign(force, V) / static if static > 0.0 else 0.0
        return offset, slope, abs(V) / omega

    @property
    def damping(self) -> np.ndarray:
        return np.array([[self.parameters[2]]])

    @damping.setter
    def damping(self, value) -> None:
        self.parameters = (self.parameters[0], self.parameters[1], float(np.asarray(value)[0, 0]),
                           *self.parameters[3:])


def _free_systems(scene, probe: np.ndarray, name: str, pulls=None):
    """``(scene, make(steps, reference))``: the free system of ``scene`` at M = steps: the element with friction
    on its Taylor orbit (:class:`FreeElement`), else the network (massless nodes condensed: FreeShooting, the
    amplitude that of x = probe . x over its nodes: a node's own, or a massless node's weighted mean, plus
    ``pulls`` {lever: weight} of the levers' tensions where a slider or branch is on it)."""
    from ..network.model import NetworkScene
    from .shooting import prepared

    if isinstance(scene, NetworkScene):
        scene = prepared_network(scene)
        return scene, lambda steps, reference: FreeShooting(scene, steps, reference, probe, name, pulls)
    scene = prepared(scene)
    return scene, lambda steps, reference: FreeElement(scene, steps, reference)


def slider_backbone(scene, mode: int, amplitudes: np.ndarray, probe: np.ndarray, name: str,
                    tolerance: float, pulls=None) -> tuple:
    """The backbone at ``amplitudes`` (see the module): (rows, 2): omega and xi of every point of the backbone at
    each amplitude (the amplitudes in the order given; where the backbone turns back in amplitude, each of its
    points at that amplitude, in their order along it), (rows, n) complex: the first harmonic of every node per
    unit amplitude, (rows,) the amplitudes, the last relative change of M's doubling, (rows,) complex: the node's
    first harmonic per unit amplitude (1, but where its phase is the anchor's: see :class:`_Free`).

    The family is followed without an amplitude condition (:func:`_follow_family`: the node's a_1 need not grow
    along it; on two masses and a joint it saturates at 4 (alpha + k eta) / (pi |k_a - m_a omega_b^2|) while
    the other mass's amplitude grows without bound), then each listed amplitude is solved for at every crossing
    of the node's a_1; an amplitude that the family's a_1 at the node never reaches is refused, with the largest
    it reaches."""
    scene, make = _free_systems(scene, probe, name, pulls)
    free = make(FIRST_STEPS, 1.0)
    low, high = float(np.min(amplitudes)), float(np.max(amplitudes))
    omega0, shape, xi0, onset = _linear_start(free, mode, low)
    anchor = free.anchor
    if anchor is not None:  # the node named stands still at the start: the family starts at the anchor's amplitude
        make = _anchored(make, anchor)
    free = make(FIRST_STEPS, omega0)
    A0 = min(low, 0.5 * onset) if anchor is None else 0.5 * onset
    free.at_anchor = anchor is not None
    z = free.solve(_guess(free, shape, omega0, xi0, A0), A0)
    free.at_anchor = False
    if z is None and math.isinf(onset):  # started with the sliders slipping (stuck, they hold the mode still)
        raise FrequencyError(f"{scene.source}: the nonlinear mode {mode} was not found at A = {A0!r} m, the "
                             "smallest amplitude listed, with its sliders slipping: stuck they hold it still, and "
                             "below the amplitude where the springs overcome them at the turning points (alpha / k "
                             "for a mass on a spring k and a slider alpha to the ground) there is no periodic "
                             "motion: list larger amplitudes")
    if z is None:
        raise FrequencyError(f"{scene.source}: the nonlinear mode {mode} was not found at A = {A0!r} m from its "
                             "linear mode (every slider and branch sticking)")
    points, measures, largest = _follow_family(free, z, high)
    # where the family was left, the node's a_1 may still be moving (towards a limit, while the other nodes'
    # amplitude grows): as much again as over the last doubling of the largest amplitude is its reach beyond
    half = int(np.searchsorted(largest, 0.5 * largest[-1])) if np.all(np.diff(largest[-8:]) > 0) else 0
    reach = float(np.max(np.abs(measures[half:] - measures[-1])))
    rows, states = [], []
    for index, A in enumerate(amplitudes.tolist()):
        if abs(A - measures[-1]) <= reach:
            raise FrequencyError(
                f"{scene.source}: mode {mode} at A = {A!r} m at node {free.name}: where the family "
                f"was followed to (other nodes' amplitude {largest[-1]:.6g} m) node {free.name}'s "
                f"first harmonic is {measures[-1]:.6g} m and still moving by {reach:.3g} m, so the family may pass "
                "that amplitude again further out: choose an amplitude farther from it, or another --node")
        found = _family_crossings(free, points, measures, A)
        if not found:
            top = int(np.argmax(measures))
            raise FrequencyError(
                f"{scene.source}: mode {mode} does not reach A = {A!r} m at node {free.name}: along "
                f"the family its first harmonic there is at most {measures[top]:.6g} m (at "
                f"{points[top][free.dimension] / (2 * math.pi):.6g} Hz) while the other nodes' amplitude grows "
                "(choose another --node)")
        for state in found:
            rows.append(index)
            states.append(state)
    change = math.inf
    while True:
        if free.M * 2 > MAX_STEPS:
            raise FrequencyError(f"{scene.source}: the mode's frequency and damping still changed by {change:.3g} "
                                 f"relative from {free.M // 2} to {free.M} samples per period (tolerance "
                                 f"{tolerance:g}): give a larger --tolerance")
        finer = make(2 * free.M, omega0)
        refined = []
        for index, z in zip(rows, states):
            solved = finer.solve(z, float(amplitudes[index]))
            if solved is None:
                raise FrequencyError(f"{scene.source}: the nonlinear mode {mode} at A = {float(amplitudes[index])!r} "
                                     f"m did not converge at {finer.M} samples per period")
            refined.append(solved)
        change = max(_change(a, b, free.dimension) for a, b in zip(states, refined))
        free, states = finer, refined
        if change <= 0.5 * tolerance:
            break
    N, n = free.dimension, free.system.n
    values = np.empty((len(rows), 2))
    shapes = np.empty((len(rows), n), dtype=complex)
    nodes = np.empty(len(rows), dtype=complex)  # the node's first harmonic per unit amplitude (1 unless anchored)
    for row, (index, z) in enumerate(zip(rows, states)):
        values[row] = z[N], z[N + 1]
        free.damping = free.viscous - z[N + 1] * np.diag(free.system.mass)
        harmonics = free.coefficients(z[:N], z[N])
        shapes[row] = (harmonics[:, 1] - 1j * harmonics[:, 2]) / float(amplitudes[index])
        nodes[row] = _family_equations(free, z)[2] / float(amplitudes[index])
    return values, shapes, amplitudes[np.array(rows, dtype=np.int64)], change, nodes


def _anchored(make, anchor: int):
    """``make`` whose free systems fix the phase at node ``anchor`` (see :class:`_Free`)."""
    def anchored(steps, reference):
        free = make(steps, reference)
        free.anchor = anchor
        free.state_probe = np.eye(free.dimension)[anchor]
        return free
    return anchored


FAMILY_STEP = 0.02       # the arc-length step's bound (unknowns scaled by the orbit's size and by omega)
FAMILY_MIN_STEP = 1e-6
FAMILY_KINK_STEP = 1e-4  # below this step a converged corrector past a kink is taken (see _follow_family)
FAMILY_KINK_REACH = 4.0
FAMILY_KINK_ITERATIONS = 30
KINK_AMPLITUDE_STEPS = (1e-4, 1e-3, 1e-2)  # relative steps of the node's amplitude past a kink (_past_kink)
FAMILY_POINTS = 20000
FAMILY_BEYOND = 20.0     # follow until the largest node's a_1 is this many times the largest listed amplitude


def _family_equations(free, z):
    """The half-period map's residual and the phase condition b_1 = 0 at the node (no amplitude condition), the
    first harmonic of every node, and the node's (a massless node's: its weights over the nodes and over the
    levers' tensions, ``free.pulls``)."""
    N = free.dimension
    s, omega, xi = z[:N], float(z[N]), float(z[N + 1])
    if not omega > 0:
        raise StepFailed(f"{free.system.source}: the mode's frequency left the positive axis")
    free.damping = free.viscous - xi * np.diag(free.system.mass)
    if not getattr(free, "symmetric", True):  # on a belt: the whole period, x(T) = x(0) (and the branches' rows)
        end, xs = free.run(s, omega, 2)
        residual = end - s
        whole = np.vstack((s[None, :free.system.n], xs[:-1]))
        free._centred(s, residual, np.concatenate(([s[0]], xs[:, 0])))
        X = np.exp(-2j * math.pi * np.arange(free.M) / free.M) @ whole * 2.0 / free.M
        node = complex(free.probe @ X)
        return np.concatenate((residual, [-node.imag])), X, node
    n, pulled = free.system.n, np.any(free.pulls)
    end, xs = free.run(s, omega, with_u=True) if pulled else free.run(s, omega)
    half = np.vstack((s[None, :n], xs[:-1, :n]))
    turns = np.exp(-2j * math.pi * np.arange(free.M) / free.M)
    X = turns @ np.vstack((half, -half)) * 2.0 / free.M
    node = complex(free.probe @ X)
    if pulled:  # the levers' tensions k u over the period (the second half the first's negative)
        nb = free.branches
        start = np.clip(np.asarray(s[2 * n:2 * n + nb], dtype=float), -free.eta, free.eta)
        tension = np.vstack((start[None, :], xs[:-1, n:n + nb])) * free.bk
        node += complex(free.pulls @ (turns @ np.vstack((tension, -tension)) * 2.0 / free.M))
    phase = node if free.anchor is None else complex(X[free.anchor])
    return np.concatenate((-end - s, [-phase.imag])), X, node


def _family_jacobian(free, z, residual, scale):
    N = free.dimension
    J = np.empty((N + 1, N + 2))
    for k in range(N + 2):
        moved = z.copy()
        moved[k] += PERTURBATION * scale[k]
        J[:, k] = (_family_equations(free, moved)[0] - residual) / PERTURBATION
    return J  # d residual / d (z / scale)


def _follow_family(free, z, high):
    """Pseudo-arclength continuation of the family through z in (s, omega, xi) with the phase condition only:
    the points and the node's |a_1| at each, until the largest node's |a_1| passes FAMILY_BEYOND x high (the
    node's own may turn back, so passing high is not the end), or FAMILY_POINTS points. Unknowns scaled by the
    orbit's size (so the steps grow with the amplitude) and by omega; the tangent's sign kept by the secant where
    a kink (a slip starting or stopping) flips the null vector; past a kink that no step passes, see
    :func:`_past_kink`."""
    N = free.dimension

    def scale_of(z):
        return np.concatenate((np.full(N, max(float(np.max(np.abs(z[:N]))), 1e-12)), [z[N], z[N]]))

    def tangent(z, scale, previous):
        residual = _family_equations(free, z)[0]
        _, _, vt = np.linalg.svd(_family_jacobian(free, z, residual, scale))
        t = vt[-1]
        return t if previous is None or t @ previous >= 0 else -t

    scale = scale_of(z)
    t = tangent(z, scale, None)
    n = free.system.n
    _, first, node = _family_equations(free, z)
    if getattr(free, "symmetric", True):
        if (free.state_probe @ t[:N]) * (free.state_probe @ z[:N]) < 0:  # the amplitude's way up
            t = -t
    else:  # on a belt x(0) carries the drag's offset: the way up is where the node's |a_1| grows
        if abs(_family_equations(free, z + FAMILY_STEP * 1e-3 * t * scale)[2]) < abs(node):
            t = -t
    points, measures, largest = [z.copy()], [abs(node)], [max(float(np.max(np.abs(first))), abs(node))]
    step = FAMILY_STEP
    while len(points) < FAMILY_POINTS:
        y = z / scale
        while True:
            predicted = y + step * t
            w = predicted.copy()
            ok = False
            # below FAMILY_KINK_STEP, Newton's step is halved while the residual grows (at most HALVINGS times),
            # for up to FAMILY_KINK_ITERATIONS: at a kink (on a belt where the mass first reaches the belt's
            # speed) plain Newton cycled between the Jacobians of its two sides, a step of 2e-5 each way
            kink = step <= FAMILY_KINK_STEP
            try:
                residual = _family_equations(free, w * scale)[0]
                for _ in range(FAMILY_KINK_ITERATIONS if kink else 12):
                    J = _family_jacobian(free, w * scale, residual, scale)
                    size = np.max(np.abs(residual))
                    delta = solve_linear(np.vstack((J, t)), -np.concatenate((residual, [t @ (w - predicted)])))
                    if delta is None:
                        break
                    for _ in range(HALVINGS + 1 if kink else 1):
                        trial = w + delta
                        new_residual = _family_equations(free, trial * scale)[0]
                        if np.max(np.abs(new_residual)) <= size:
                            break
                        delta = 0.5 * delta
                    w, residual = trial, new_residual
                    if np.max(np.abs(delta)) < 1e-11:
                        drift = np.linalg.norm(w - predicted)
                        # near the prediction; or, past a kink whose turn does not shrink with the step (on a belt
                        # a branch's onset of sliding, where its row leaves the centred convention), ahead of
                        # the last point and within FAMILY_KINK_REACH steps of it, once the step is that small
                        ok = drift < 0.5 * step or (step <= FAMILY_KINK_STEP and (w - y) @ t > 0.0 and
                                                    np.linalg.norm(w - y) <= FAMILY_KINK_REACH * step)
                        break
            except StepFailed:
                ok = False
            if ok:
                break
            step *= 0.5
            if step < FAMILY_MIN_STEP:
                w = _past_kink(free, z, measures[-1], scale)
                if w is not None:
                    break
                raise FrequencyError(f"{free.system.source}: the nonlinear mode's family could not be followed past "
                                     f"{points[-1][N] / (2 * math.pi):.6g} Hz (node amplitude {measures[-1]:.6g} m)")
        new = w * scale
        secant = w - y
        scale = scale_of(new)
        t_new = tangent(new, scale, None)
        if t_new @ secant < 0:
            t_new = -t_new
        z, t = new, t_new
        _, X, node = _family_equations(free, z)
        points.append(z.copy())
        measures.append(abs(node))
        largest.append(max(float(np.max(np.abs(X))), abs(node)))
        step = min(FAMILY_STEP, 1.5 * step)
        if largest[-1] > FAMILY_BEYOND * high:
            break
    return points, np.array(measures), np.array(largest)


def _past_kink(free, z, measure: float, scale):
    """The family's next point (scaled) past a kink where the arc-length corrector fails at every step (on a belt,
    where the mass first reaches the belt's speed: Newton on the hyperplane stalled at a residual of 1.5e-7 while
    Newton at a fixed amplitude, its step halved while the residual grows, goes through): :meth:`_Free.solve` at
    the node's amplitude KINK_AMPLITUDE_STEPS larger, the first whose solution is within FAMILY_KINK_REACH
    FAMILY_STEPs (the way on is the amplitude's: there the tangent turned by more than a right angle, xi's share
    from -0.25 to +0.97); or None (the family turns back in the node's amplitude there)."""
    y = z / scale
    for share in KINK_AMPLITUDE_STEPS:
        solved = free.solve(z, measure * (1.0 + share))
        if solved is None:
            continue
        w = solved / scale
        if np.linalg.norm(w - y) <= FAMILY_KINK_REACH * FAMILY_STEP:
            return w
    return None


def _family_crossings(free, points, measures, A: float) -> list:
    """Every point of the family where the node's |a_1| is A: Newton at A from the interpolation between the
    curve's points that bracket it (in their order along the family); solutions met twice kept once."""
    out = []
    for i in range(len(points) - 1):
        m0, m1 = measures[i], measures[i + 1]
        if i == 0 and abs(m0 - A) <= 1e-9 * A:  # the start (its A to rounding)
            m0 = A
        if (m0 - A) * (m1 - A) <= 0 and m0 != m1:
            guess = points[i] + (A - m0) / (m1 - m0) * (points[i + 1] - points[i])
            if getattr(free, "symmetric", True) and free.state_probe @ guess[:free.dimension] < 0:
                guess = guess.copy()
                guess[:free.dimension] = -guess[:free.dimension]
            solved = free.solve(guess, A)
            if solved is None:
                raise FrequencyError(f"{free.system.source}: the nonlinear mode at A = {A!r} m was not found between "
                                     "the points of its family on either side")
            if not any(np.max(np.abs(solved - o) / np.maximum(np.abs(o), 1e-9)) < 1e-6 for o in out):
                out.append(solved)
    return out


def _change(a: np.ndarray, b: np.ndarray, N: int) -> float:
    """The relative change of the frequency and of the damping ratio (against 1e-6 at least) between two
    solutions."""
    frequency = abs(b[N] - a[N]) / abs(b[N])
    ratio_a, ratio_b = a[N + 1] / (2 * a[N]), b[N + 1] / (2 * b[N])
    return max(frequency, abs(ratio_b - ratio_a) / max(abs(ratio_b), 1e-6))


def _guess(free, shape, omega, xi, A) -> np.ndarray:
    """(s, omega, xi) of the linear mode ``shape`` at amplitude A: x = A shape at t = 0, at rest, every branch's
    spring stretched by its ends."""
    x = A * shape
    offset = free.belt_start(omega)[0] if hasattr(free, "belt_start") and not free.symmetric else 0.0
    s = np.concatenate((x + offset, np.zeros(free.system.n), np.clip(free.brows @ x, -free.eta, free.eta)))
    # the states after them (series dashpots' u, a history's z) start at 0
    return np.concatenate((s, np.zeros(free.dimension - s.size), [omega, xi]))


def _linear_start(free, mode: int, A: float) -> tuple:
    """(omega, shape with probe . shape = 1, xi, onset) of linear mode ``mode`` (1: the lowest) with every branch
    and slider sticking, ``onset`` the amplitude where a slider's force (G^T lambda = (K - omega^2 M) x) reaches
    its alpha or a branch's spring its eta; where the stuck sliders leave fewer modes, with the sliders free, xi
    from the energy each dissipates over a cycle of amplitude A (4 alpha |d . shape| A against
    pi xi omega A^2 shape' M shape), onset infinite (they slip at every amplitude)."""
    source = free.system.source
    stuck = free.stiffness_matrix + (free.brows.T * free.bk) @ free.brows
    mass = np.diag(free.system.mass)
    start = None
    for held in (True, False):
        rows = free.rows if held else free.rows[:0]
        basis = _null_space(rows, free.system.n)
        if basis.shape[1] < mode:
            continue
        omega, shape = _mode(basis.T @ stuck @ basis, basis.T @ mass @ basis, mode)
        if omega is None:
            continue
        shape = basis @ shape
        if abs(free.linear_probe @ shape) < 1e-9 * np.max(np.abs(shape)):
            if not (held and np.any(free.pulls)):
                raise FrequencyError(f"--node: mode {mode} does not move node {free.name}: its "
                                     "amplitude cannot set the mode's (choose another --node)")
            # a massless node on a rigid slider stands still while it sticks: the mode starts at the amplitude
            # of the node with a mass that moves most (the anchor: its phase set, see _Free)
            free.anchor = int(np.argmax(np.abs(shape) * np.sqrt(free.system.mass)))
            free.state_probe = np.eye(free.dimension)[free.anchor]
            shape = shape / shape[free.anchor]
        else:
            shape = shape / (free.linear_probe @ shape)
        modal = float(shape @ mass @ shape)
        xi = float(shape @ free.viscous @ shape) / modal
        onset = math.inf
        if held:
            if rows.shape[0]:
                force = np.linalg.lstsq(rows.T, (stuck - omega * omega * mass) @ shape, rcond=None)[0]
                onset = min(onset, float(np.min(free.alpha / np.maximum(np.abs(force), 1e-300))))
            if free.brows.shape[0]:
                onset = min(onset, float(np.min(free.eta / np.maximum(np.abs(free.brows @ shape), 1e-300))))
            if hasattr(free, "belt_start") and not free.symmetric:  # slipping on its belt until |v| = |V|
                _, slope, reach = free.belt_start(omega)
                xi += slope / modal
                onset = min(onset, reach)
        else:
            xi += float(np.sum(4.0 * free.alpha * np.abs(free.rows @ shape))) / (math.pi * omega * A * modal)
        start = (omega, shape, xi, onset)
        break
    if start is None:
        raise FrequencyError(f"--mode: {source} has fewer than {mode} mode(s) with a stiffness (every branch "
                             f"sticking); got {mode}")
    return start


def _null_space(rows: np.ndarray, n: int) -> np.ndarray:
    """An orthonormal basis (n, n - rank) of the motions that keep every row's relative displacement 0."""
    if rows.shape[0] == 0:
        return np.eye(n)
    _, singular, vt = np.linalg.svd(rows)
    rank = int(np.sum(singular > 1e-12 * singular[0]))
    return vt[rank:].T


def _mode(K: np.ndarray, M: np.ndarray, mode: int) -> tuple:
    """(omega, shape) of the generalized eigenproblem K phi = omega^2 M phi, ``mode`` from the lowest; (None,
    None) if it has no stiffness."""
    lower = np.linalg.cholesky(M)
    inverse = np.linalg.inv(lower)
    values, vectors = np.linalg.eigh(inverse @ K @ inverse.T)
    if values[mode - 1] <= 0:
        return None, None
    return math.sqrt(values[mode - 1]), inverse.T @ vectors[:, mode - 1]
