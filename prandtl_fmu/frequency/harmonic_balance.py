"""Harmonic balance: the periodic state of a scene with masses, solved for directly.

A scene (the element with ``[mass]``, or a network with masses) is one system of n nodes,

    M x'' + C x' + K x + g(x) = F(t),      F = F0 cos(omega t) on the load's node,

M = diag(m) (kg; a massless node has no inertia: an algebraic unknown), C and K (N s/m, N/m) assembled from the
dashpots and springs, g the restoring force of the nonlinear elements (cubic springs, Prandtl branches:
``aft.py``). The element is the network of one node ``mass`` with its k0, k3, c and branches to the ground.

Each node's motion is its mean and H harmonics, x_i(t) = a_0 + sum_h a_h cos(h omega t) + b_h sin(h omega t):
unknowns q (n L, L = 2 H + 1, node by node, in the order a_0, a_1, b_1, ..., a_H, b_H). The residual is

    R(q, omega) = (K (x) I + omega C (x) D + omega^2 M (x) D^2) q + G(q) - f,

D the derivative on one node's coefficients in units of omega ((a_h, b_h) -> h (b_h, -a_h)), G the harmonics
of g by alternating frequency-time: x sampled at N points per period (N = SAMPLES_PER_HARMONIC H rounded up
to a power of two, at least MIN_SAMPLES), the forces on the elements' steady cycle at the samples, the
harmonics by numpy's real FFT (``aft.py``: exact at the samples for the branches and springs; the FFT of the
samples is the trapezoid rule, the stated quadrature of a force whose cycle has kinks between samples: its
error falls like 1 / N^2, about 1e-5 of the first harmonic at N = 512 on a friction damper).

The Jacobian dR/dq is exact in structure: the linear part as written, dG/dq from each element's slope at each
sample through the same FFT, for a branch with the anchor of its stick (``aft.py``): exact for the sampled
map, so Newton's iteration converges in a few steps once the slip pattern is right. dR/d omega is exact.

The effects with memory of an element scene (``memory/``) act on its node:

* ``[delay]`` -gain y(t - tau), y = x or x': linear, so exact per harmonic: harmonic h of y delayed is that of
  y turned by -h omega tau, the operator exp(-omega tau D) on the coefficients (D as above), and y' = omega D x:
  the term gain exp(-omega tau D) (x) or gain exp(-omega tau D) omega D (x') of the linear part, with its
  exact d/d omega (-tau D times it, plus gain exp(-omega tau D) D on x');
* ``[history]`` -int_0^t sum_j w_j exp(-r_j (t - s)) y(s) ds: in the periodic steady state z_j' = -r_j z_j + y
  gives z_j = (r_j + omega D)^-1 y (harmonic h: Y_h / (r_j + i h omega), the mean Y_0 / r_j), the term
  sum_j w_j (r_j + omega D)^-1 (times omega D on x') with its exact d/d omega. A rate r_j = 0 (a plain
  integral) has no steady cycle fixed by the period (its constant is set by the whole past): refused;
* ``[dahl]`` F_d, dF_d/dx = sigma (1 - F_d / F_c sgn x')^exponent: a hysteretic force, in AFT beside the
  branches (``aft.dahl_cycle``): the law is rate independent and integrated exactly over each monotone move
  (``memory/dahl.py``), so along the samples taken linear between them it is exact at the samples, as a
  branch is; its steady cycle is the fixed point of the period map, found by Newton's method kept in a
  bracket (each iteration one period driven, at most aft.DAHL_PERIODS; exact in one step for exponent 1,
  where the map is affine); its Jacobian the exact tangent of that sampled map (the derivative of each move
  carried around the cycle, closed by periodicity). The error is the samples' (the turning points fall
  between them): like 1 / N^2.

A delay or a history on x holds the node's mean as a spring does (their mean stiffness gain, w_j / r_j).

Two effects take a stated quadrature instead: a spectrum of branches (the continuum) becomes branches at
quadrature nodes (:func:`spectrum_branches`), after which all of the above applies to them unchanged; branches
with series dashpots are driven by the compiled kernels over periods to their steady cycle, their Jacobian and
dG/d omega by finite differences (``driven.py``).

A node's mean is an unknown where springs or cubic springs hold the node to the ground; elsewhere it is 0
(branches carry no mean on their centred cycle, so no equation would set it). The equations of the other
coefficients are solved with Newton's method, at most NEWTON_ITERATIONS iterations; a point that does not
converge within them is refused (FrequencyError, saying where and how far it got).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import DEFAULT_TOLERANCE, FrequencyError

MIN_SAMPLES = 256
SAMPLES_PER_HARMONIC = 64
NEWTON_ITERATIONS = 40
HARMONIC_STEPS = (1, 3, 5, 7, 9, 11, 15, 21, 31, 45, 63)  # the numbers of harmonics the tolerance chooses among
# the tolerance climbs past H = 31 only while the balance has at most this many unknowns (n nodes times 2 H + 1):
# a dense Jacobian of 2000 factors in about 0.1 s, a curve takes about a thousand
DENSE_STEPS = 31
MOST_HARMONICS = 256  # of a balance (--harmonics)
MOST_CHOSEN_UNKNOWNS = 2000
NEWTON_HALVINGS = 10  # of a damped Newton step while the residual would grow (:meth:`HarmonicBalance._newton`)
# converged: the last Newton step moved q by at most this fraction of |q| (max norm), or R is at most this
# fraction of F0
STEP_TOLERANCE = 1e-10
RESIDUAL_TOLERANCE = 1e-11
ELEMENT_NODE = "mass"
# a spectrum of branches as branches (:func:`spectrum_branches`): the Gauss-Legendre points per panel, the most
# nodes per segment and the amplitudes its first harmonic is checked at
SPECTRUM_RULE = 8
SPECTRUM_MAX_NODES = 1024
SPECTRUM_AMPLITUDES = 25


class Nodes:
    """What a system of nodes says of them (its ``nodes`` names, ``mass`` array and ``source``): the periodic
    system here and the shooting's (``shooting.py``)."""

    @property
    def n(self) -> int:
        return len(self.nodes)

    @property
    def massive(self) -> list:
        """The indices of the nodes with a mass."""
        return [i for i in range(self.n) if self.mass[i] > 0]

    def node_index(self, name: Optional[str], default: Optional[int] = None) -> int:
        """The index of node ``name`` (None: ``default``, else the first node with a mass)."""
        if name is None:
            return self.massive[0] if default is None else default
        if name not in self.nodes:
            raise FrequencyError(f"--node: {name!r} is not a node of {self.source} ({', '.join(self.nodes)})")
        return self.nodes.index(name)


@dataclass(frozen=True, eq=False)
class PeriodicSystem(Nodes):
    """A scene as n nodes (see the module): ``nodes`` names, ``mass`` (n,), ``stiffness`` and ``damping``
    (n, n); the nonlinear elements as (count, 2) ``*_ends`` (-1: the ground), ``cubic_k3``, ``branch_k``,
    ``branch_eta``, each with the index of its pair of nodes in ``pairs``; ``load_node``; ``network``: the same
    system as a network (the time integration of the stability check runs it) and ``branch_index``: the index
    of each branch among the network's elements; ``held``: the nodes whose mean is an unknown; ``series``: the
    branches with series dashpots, one ``driven.SeriesBranches`` per pair of nodes; ``memory``: the effects with
    memory of an element scene (:class:`MemoryEffects`), else None."""

    name: str
    source: str
    nodes: tuple
    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    cubic_ends: np.ndarray
    cubic_k3: np.ndarray
    cubic_pair: np.ndarray
    branch_ends: np.ndarray
    branch_k: np.ndarray
    branch_eta: np.ndarray
    branch_pair: np.ndarray
    pairs: tuple
    load_node: int
    network: object
    branch_index: np.ndarray
    held: np.ndarray
    series: tuple = ()
    memory: Optional["MemoryEffects"] = None


@dataclass(frozen=True, eq=False)
class MemoryEffects:
    """The effects with memory of an element scene acting on node ``node`` (see the module): ``delay``,
    ``history``, ``dahl`` (the scene's ``memory.delay.Delay``, ``memory.history.History``, ``memory.dahl.Dahl``,
    or None); ``scene``: the element scene, whose time integration the stability check runs."""

    node: int
    delay: object
    history: object
    dahl: object
    scene: object

    def stiffness(self, omega: float, derivative: np.ndarray) -> tuple:
        """``(Z, dZ/d omega)`` (L, L): the delay's and the history's force on the node's coefficients at
        ``omega`` (rad/s) as a linear map of its x's (see the module); ``derivative``: D (L, L)."""
        L = derivative.shape[0]
        Z, by_omega = np.zeros((L, L)), np.zeros((L, L))
        D = derivative
        d = self.delay
        if d is not None:
            turn = np.eye(L)
            for h in range(1, (L - 1) // 2 + 1):
                c, s = math.cos(h * omega * d.tau), math.sin(h * omega * d.tau)
                turn[2 * h - 1:2 * h + 1, 2 * h - 1:2 * h + 1] = [[c, -s], [s, c]]
            turned = -d.tau * D @ turn
            if d.acts_on == "v":
                Z += d.gain * omega * turn @ D
                by_omega += d.gain * (omega * turned @ D + turn @ D)
            else:
                Z += d.gain * turn
                by_omega += d.gain * turned
        s = self.history
        if s is not None:
            for weight, rate in zip(s.weight, s.rate):
                inverse = np.linalg.inv(rate * np.eye(L) + omega * D)
                turned = -inverse @ D @ inverse
                if s.acts_on == "v":
                    Z += weight * omega * inverse @ D
                    by_omega += weight * (omega * turned @ D + inverse @ D)
                else:
                    Z += weight * inverse
                    by_omega += weight * turned
        return Z, by_omega


def periodic_system(scene, load_node: Optional[str] = None, tolerance: float = DEFAULT_TOLERANCE) -> PeriodicSystem:
    """The :class:`PeriodicSystem` of an element scene (with ``[mass]``) or a network scene; ``load_node``: the
    node the harmonic force acts on (default: the network's ``load_node``; the element's mass); ``tolerance``:
    of a spectrum of branches' quadrature (:func:`spectrum_branches`). FrequencyError for what harmonic balance
    does not take (and why)."""
    from ..network.model import NetworkScene

    network = scene.network if isinstance(scene, NetworkScene) else _element_network(scene, tolerance)
    memory = None
    if not isinstance(scene, NetworkScene) and any(e is not None for e in (scene.delay, scene.history, scene.dahl)):
        memory = MemoryEffects(0, scene.delay, scene.history, scene.dahl, scene)
    for element in network.elements:
        if element.kind == "slider":
            raise FrequencyError(f"{scene.source}: slider {element.name}: a slider's force is set-valued while it "
                                 "sticks, which harmonic balance cannot sample (docs/frequency.md): the forced "
                                 "response (--force-amplitude) is solved for by shooting on the network's motion; "
                                 "else model the joint as branches (k, eta: a slider behind a spring)")
    if not np.any(network.mass > 0):
        raise FrequencyError(f"{scene.source}: no node has a mass: the forced response needs one")
    n = network.n
    stiffness, damping = np.zeros((n, n)), np.zeros((n, n))
    cubic, branches, pairs, links, series = [], [], [], [], {}

    def pair_of(ends):
        key = (min(ends), max(ends)) if min(ends) >= 0 else (max(ends), -1)
        if key not in pairs:
            pairs.append(key)
        return pairs.index(key)

    for index, element in enumerate(network.elements):
        p, q = element.between
        if element.kind in ("spring", "dashpot"):
            target = stiffness if element.kind == "spring" else damping
            if element.kind == "spring":
                links.append((p, q))
            target[p, p] += element.value
            if q >= 0:
                target[q, q] += element.value
                target[p, q] -= element.value
                target[q, p] -= element.value
        elif element.kind == "cubic":
            cubic.append((p, q, element.value, pair_of((p, q))))
            links.append((p, q))
        elif element.c > 0:
            series.setdefault(pair_of((p, q)), []).append((element.value, element.eta, element.c, index))
        else:
            branches.append((p, q, element.value, element.eta, pair_of((p, q)), index))
    if memory is not None:
        on_x = [e for e in (memory.delay, memory.history) if e is not None and e.acts_on == "x"]
        if on_x:  # the mean's stiffness (gain, w_j / r_j), as a spring's
            links.append((memory.node, -1))
    node = network.load_node
    if load_node is not None:
        if load_node not in network.nodes:
            raise FrequencyError(f"--load-node: {load_node!r} is not a node of {scene.source} "
                                 f"({', '.join(network.nodes)})")
        node = network.nodes.index(load_node)
    network = dataclasses.replace(network, load_node=node)
    cubic_table = np.array([c[:3] for c in cubic], dtype=float).reshape(-1, 3)
    branch_table = np.array([b[:4] for b in branches], dtype=float).reshape(-1, 4)
    return PeriodicSystem(
        scene.name, scene.source, tuple(network.nodes), np.array(network.mass, dtype=float), stiffness, damping,
        cubic_table[:, :2].astype(np.int64).copy(), cubic_table[:, 2].copy(),
        np.array([c[3] for c in cubic], dtype=np.int64), branch_table[:, :2].astype(np.int64).copy(),
        branch_table[:, 2].copy(), branch_table[:, 3].copy(), np.array([b[4] for b in branches], dtype=np.int64),
        tuple(pairs), node, network, np.array([b[5] for b in branches], dtype=np.int64), _held_nodes(n, links),
        tuple(_series_branches(pairs[pair], pair, group) for pair, group in series.items()), memory)


def _series_branches(ends, pair, group):
    from .driven import SeriesBranches, series_model

    k, eta, c, index = (np.array(column) for column in zip(*group))
    return SeriesBranches(ends, pair, series_model(k, eta, c), index.astype(np.int64))


def _element_network(scene, tolerance: float = DEFAULT_TOLERANCE):
    """The element scene as a network of one node ``mass``, its effects to the ground (a spectrum of branches as
    the branches of :func:`spectrum_branches`); FrequencyError for the effects harmonic balance does not
    take."""
    from ..network.model import Element, Network

    if scene.mass is None:
        raise FrequencyError(f"{scene.source}: the frequency response and the nonlinear modes need [mass] (the "
                             "element alone has no resonance: describe it with --amplitudes)")
    if scene.friction is not None:
        raise FrequencyError(f"{scene.source}: [friction] (Coulomb friction of the mass: set-valued while it sticks) "
                             "is not taken by harmonic balance: use --method time")
    if scene.history is not None and 0.0 in scene.history.rate:
        raise FrequencyError(f"{scene.source}: [history] rate 0 (a plain integral of y) is not taken by harmonic "
                             "balance: its steady cycle is not fixed by the period (its constant depends on the "
                             "whole past): use --method time")
    elements = []
    if scene.spring is not None and scene.spring.k0 > 0:
        elements.append(Element("spring", "k0", (0, -1), float(scene.spring.k0)))
    if scene.cubic is not None:
        elements.append(Element("cubic", "k3", (0, -1), float(scene.cubic.k3)))
    if scene.has_dashpot:
        elements.append(Element("dashpot", "c", (0, -1), float(scene.damper.c)))
    if scene.branches is not None and scene.branches.continuum:
        k, eta = spectrum_branches(scene.branches, tolerance, scene.source)
        for i, (k_i, eta_i) in enumerate(zip(k.tolist(), eta.tolist())):
            elements.append(Element("branch", f"branch_{i + 1}", (0, -1), k_i, eta_i, 0.0, 0.0))
    elif scene.branches is not None:
        b = scene.branches
        cs = b.damping.tolist() if b.damping is not None else [0.0] * b.stiffness.shape[0]
        for i, (k, eta, c, u0) in enumerate(zip(b.stiffness.tolist(), b.yield_displacement.tolist(), cs,
                                                 b.u0.tolist())):
            elements.append(Element("branch", f"branch_{i + 1}", (0, -1), k, eta, c, u0))
    mass = scene.mass
    return Network((ELEMENT_NODE,), np.array([mass.m]), np.array([mass.x0]), np.array([mass.v0]),
                   tuple(elements), 0)


def spectrum_branches(branches, tolerance: float = DEFAULT_TOLERANCE, source: str = "scene") -> tuple:
    """``(k, eta)``: a spectrum of branches (``effects.ContinuousBranches``: k(s) = c_j eta(s)^p_j, eta linear on
    each segment [s_j, s_j+1]) as finitely many Prandtl branches, the nodes of a stated quadrature with their
    weights as stiffnesses. On each segment, composite Gauss-Legendre (SPECTRUM_RULE points on each of P equal
    panels of t in [0, 1]) under s = s_j + (s_j+1 - s_j) (1 - cos(pi t)) / 2 (which takes an end singularity of
    eta^p at eta = 0):

        k_i = w_i ds/dt(t_i) c_j eta(s_i)^p_j,      eta_i = eta(s_i);

    a flat segment (a Dirac) is one branch, c_j eta^p_j (s_j+1 - s_j). Unlike describe's integral
    (``closed_forms.spectrum_forms``) the nodes cannot be cut where eta(s) = A: A is an unknown of the balance.
    The count: P doubled from 1 until the first harmonic of the branches' force under
    x = A sin(theta) (their closed forms, ``closed_forms.branch_forms``: a_1 + i b_1 = K A + i D / (pi A))
    changes by at most ``tolerance`` of its size from one count to the next, at each of SPECTRUM_AMPLITUDES
    amplitudes from eta_max / 1000 to 4 eta_max (every regime: micro-slip, the slip of the spectrum's part,
    macro-slip); FrequencyError past SPECTRUM_MAX_NODES nodes per segment. (Panels rather than one rule of
    many points: the kink of each branch's forms at eta = A falls inside some panel wherever A is, and
    numpy's ``leggauss`` costs O(n^3) for n points.)"""
    from .closed_forms import branch_forms, gauss_legendre

    top = float(np.max(branches.eta))
    amplitudes = np.geomspace(1e-3, 4.0, SPECTRUM_AMPLITUDES) * (top if top > 0 else 1.0)

    x, w = gauss_legendre(SPECTRUM_RULE)

    def quadrature(panels):
        t = ((np.arange(panels)[:, None] + 0.5 * (x[None, :] + 1.0)) / panels).reshape(-1)
        weight = np.tile(w, panels) / panels
        k, eta = [], []
        for j in range(branches.coefficient.shape[0]):
            s0, s1 = float(branches.s[j]), float(branches.s[j + 1])
            e0, e1 = float(branches.eta[j]), float(branches.eta[j + 1])
            c, p = float(branches.coefficient[j]), float(branches.power[j])
            if c == 0.0 or s1 <= s0:
                continue
            if e1 == e0:
                k.append([c * e0**p * (s1 - s0)] if p != 0 else [c * (s1 - s0)])
                eta.append([e0])
                continue
            fraction = 0.5 - 0.5 * np.cos(math.pi * t)
            slope = 0.25 * math.pi * np.sin(math.pi * t)  # d fraction / dt times the weight's 1/2 (dt = dx / 2)
            eta_j = e0 + (e1 - e0) * fraction
            density = c * np.power(eta_j, p) if p != 0 else np.full_like(eta_j, c)
            k.append(weight * slope * (s1 - s0) * density)
            eta.append(eta_j)
        return np.concatenate(k), np.concatenate(eta)

    def first_harmonic(k, eta):
        K, D = branch_forms(k[:, None], eta[:, None], amplitudes[None, :])
        return K.sum(axis=0) * amplitudes + 1j * D.sum(axis=0) / (math.pi * amplitudes)

    panels = 1
    k, eta = quadrature(panels)
    previous = first_harmonic(k, eta)
    while True:
        panels *= 2
        k, eta = quadrature(panels)
        harmonic = first_harmonic(k, eta)
        change = float(np.max(np.abs(harmonic - previous) / np.abs(harmonic)))
        if change <= tolerance:
            return k, eta
        if panels * SPECTRUM_RULE >= SPECTRUM_MAX_NODES:
            raise FrequencyError(f"{source}: the spectrum of branches as {panels * SPECTRUM_RULE} branches per "
                                 f"segment still changed its first harmonic by {change:.3g} relative (tolerance "
                                 f"{tolerance:g}): give a larger --tolerance, or count = n sampled branches")
        previous = harmonic


def sample_count(harmonics: int) -> int:
    """N, the samples per period of H harmonics (see the module)."""
    return max(MIN_SAMPLES, 1 << int(math.ceil(math.log2(SAMPLES_PER_HARMONIC * harmonics))))


class HarmonicBalance:
    """The residual and Jacobian of ``system`` with ``harmonics`` H (see the module) under F0 cos(omega t) on
    the load's node, or (``base_amplitude`` Y0, ``force_amplitude`` None) the base's motion Y0 cos(omega t), in
    relative coordinates.

    ``free``: the indices of the unknowns (the means fixed at 0 left out); :meth:`evaluate` works on those."""

    def __init__(self, system: PeriodicSystem, harmonics: int, force_amplitude: Optional[float],
                 samples: Optional[int] = None, base_amplitude: Optional[float] = None):
        if isinstance(harmonics, bool) or not isinstance(harmonics, (int, np.integer)) or \
                not 1 <= harmonics <= MOST_HARMONICS:
            raise FrequencyError(f"--harmonics: must be a whole number in [1, {MOST_HARMONICS}], got {harmonics!r}")
        self.system = system
        self.H = H = int(harmonics)
        self.L = L = 2 * H + 1
        self.N = N = samples or sample_count(H)
        if isinstance(N, bool) or not isinstance(N, (int, np.integer)) or not 2 * H + 2 <= N <= 2**20:
            raise FrequencyError(f"samples: must be a whole number in [2 H + 2, 2^20] = [{2 * H + 2}, {2**20}], "
                                 f"got {samples!r}")
        theta = 2.0 * math.pi * np.arange(N) / N
        basis = np.empty((N, L))
        basis[:, 0] = 1.0
        derivative = np.zeros((L, L))
        for h in range(1, H + 1):
            basis[:, 2 * h - 1] = np.cos(h * theta)
            basis[:, 2 * h] = np.sin(h * theta)
            derivative[2 * h - 1, 2 * h] = h  # d/d theta of a cos + b sin: (h b) cos + (-h a) sin
            derivative[2 * h, 2 * h - 1] = -h
        self.basis = basis
        # the harmonics of samples as a matrix (the real FFT's, for the Jacobian's few columns: one product)
        self.projection = basis.T * np.where(np.arange(L) == 0, 1.0, 2.0)[:, None] / N
        self.derivative = derivative
        n = system.n
        identity = np.eye(L)
        self.linear_stiffness = np.kron(system.stiffness, identity)
        self.linear_damping = np.kron(system.damping, derivative)
        self.linear_inertia = np.kron(np.diag(system.mass), derivative @ derivative)
        self.mass_velocity = np.kron(np.diag(system.mass), derivative)
        # the force's cosine coefficients, times omega^power: F0 on the load's node (power 0), or m_j Y0 on
        # every node with a mass (power 2: base excitation)
        self.load = np.zeros(n * L)
        if base_amplitude is None:
            self.load[system.load_node * L + 1] = float(force_amplitude)
            self.power = 0
        else:
            self.load[np.arange(n) * L + 1] = system.mass * float(base_amplitude)
            self.power = 2
        self.force_amplitude = None if force_amplitude is None else float(force_amplitude)
        self.base_amplitude = None if base_amplitude is None else float(base_amplitude)
        self.fraction = 1.0  # of the force, while :meth:`solve_at` raises it in steps
        self.free = np.array([i * L + l for i in range(n) for l in range(L) if l > 0 or system.held[i]],
                             dtype=np.int64)
        self._forces = np.empty((n, N))
        self._tangent = np.empty((max(len(system.pairs), 1), N, L))
        self.elongations = np.zeros(system.branch_k.shape[0])
        self.series_u = [np.zeros(group.index.shape[0]) for group in system.series]
        self.by_omega = np.zeros(n * L)  # dG / d omega: the series dashpots' (``driven.py``), else 0
        self.dahl_force = 0.0  # F_d at sample 0 of its steady cycle (the state a time integration starts from)
        self._memory_omega, self._memory_terms = None, None

    # ------------------------------------------------------------- the harmonics and the samples

    def memory_terms(self, omega: float) -> tuple:
        """``(Z, dZ/d omega)`` (n L, n L): the delay's and the history's linear terms at ``omega`` (zero without
        them; see :meth:`MemoryEffects.stiffness`), cached for the last omega."""
        memory = self.system.memory
        if memory is None or (memory.delay is None and memory.history is None):
            return 0.0, 0.0
        if self._memory_omega != omega:
            Z, by_omega = memory.stiffness(omega, self.derivative)
            n, L = self.system.n, self.L
            at = slice(memory.node * L, (memory.node + 1) * L)
            self._memory_terms = (np.zeros((n * L, n * L)), np.zeros((n * L, n * L)))
            self._memory_terms[0][at, at] = Z
            self._memory_terms[1][at, at] = by_omega
            self._memory_omega = omega
        return self._memory_terms

    def harmonics_of(self, samples: np.ndarray) -> np.ndarray:
        """The coefficients (..., L) of real samples (..., N) over one period (numpy's real FFT)."""
        spectrum = np.fft.rfft(samples, axis=-1) / self.N
        out = np.empty(samples.shape[:-1] + (self.L,))
        out[..., 0] = spectrum[..., 0].real
        out[..., 1::2] = 2.0 * spectrum[..., 1:self.H + 1].real
        out[..., 2::2] = -2.0 * spectrum[..., 1:self.H + 1].imag
        return out

    def full(self, free_values: np.ndarray) -> np.ndarray:
        """All n L coefficients from the free ones (the fixed means 0)."""
        q = np.zeros(self.system.n * self.L)
        q[self.free] = free_values
        return q

    def amplitude_at(self, free_values: np.ndarray, omega: float, node: Optional[int] = None) -> float:
        """The first harmonic's amplitude (m) of x at ``node`` (default the load's; absolute under base
        excitation, as the curve's columns): what a refusal of the curve names."""
        full = self.full(free_values)
        at = (self.system.load_node if node is None else node) * self.L
        return float(math.hypot(full[at + 1] + (self.base_amplitude or 0.0), full[at + 2]))

    def samples(self, q: np.ndarray) -> np.ndarray:
        """x at the N samples of one period, (n, N), from all n L coefficients."""
        return q.reshape(self.system.n, self.L) @ self.basis.T

    # ------------------------------------------------------------- residual and Jacobian

    def nonlinear(self, q: np.ndarray, omega: Optional[float] = None) -> tuple:
        """(G (n L,), dG/dq (n L, n L)) at all coefficients q; ``omega`` (rad/s): the frequency, which the
        branches with series dashpots need (``driven.py``)."""
        from .aft import restoring_samples

        s = self.system
        n, L = s.n, self.L
        x = self.samples(q)
        restoring_samples(x, self.basis, s.cubic_ends, s.cubic_k3, s.cubic_pair, s.branch_ends, s.branch_k,
                          s.branch_eta, s.branch_pair, self._forces, self._tangent, self.elongations)
        G = self.harmonics_of(self._forces).reshape(n * L)
        jacobian = np.zeros((n * L, n * L))
        self.by_omega[:] = 0.0
        if s.memory is not None and s.memory.dahl is not None:
            self._dahl(s.memory, x, G, jacobian)
        if s.pairs:
            blocks = self.projection @ self._tangent  # (pairs, L, L)
            for group, u in zip(s.series, self.series_u):
                self._series(group, u, x, q, omega, G, blocks[group.pair])
            for (p, r), block in zip(s.pairs, blocks):
                jacobian[p * L:(p + 1) * L, p * L:(p + 1) * L] += block
                if r >= 0:
                    jacobian[r * L:(r + 1) * L, r * L:(r + 1) * L] += block
                    jacobian[p * L:(p + 1) * L, r * L:(r + 1) * L] -= block
                    jacobian[r * L:(r + 1) * L, p * L:(p + 1) * L] -= block
        return G, jacobian

    def _dahl(self, memory, x, G, jacobian) -> None:
        """Add Dahl's force on its steady cycle along the node's samples to G and its exact tangent to the
        Jacobian (``aft.dahl_cycle``)."""
        from .aft import DAHL_PERIODS, dahl_cycle

        dahl, L, node = memory.dahl, self.L, memory.node
        forces, tangent = np.empty(self.N), np.empty((self.N, L))
        periods = dahl_cycle(x[node], self.basis, float(dahl.sigma), float(dahl.force), float(dahl.exponent),
                             forces, tangent)
        if periods < 0:
            raise FrequencyError(f"{self.system.source}: [dahl] did not reach its periodic cycle within "
                                 f"{DAHL_PERIODS} periods")
        at = slice(node * L, (node + 1) * L)
        G[at] += self.harmonics_of(forces)
        jacobian[at, at] += self.projection @ tangent
        self.dahl_force = float(forces[0])

    def _series(self, group, u, x, q, omega, G, block) -> None:
        """Add the force of the Maxwell branches ``group`` to G, their finite-difference derivative with
        respect to the pair's elongation coefficients to ``block`` (L, L) and with respect to omega to
        ``self.by_omega`` (``driven.py``); ``u`` (in place): their state at sample 0 of the steady cycle, the
        warm start of the next call."""
        from .driven import FINITE_STEP, steady_cycle

        if omega is None or not omega > 0:
            raise FrequencyError(f"{self.system.source}: branches with series dashpots need the frequency")
        p, r = group.ends
        L, period = self.L, 2.0 * math.pi / omega
        elongation = x[p] - (x[r] if r >= 0 else 0.0)
        forces, _ = steady_cycle(group, elongation, period, u, self.system.source)
        harmonics = self.harmonics_of(forces)
        G[p * L:(p + 1) * L] += harmonics
        if r >= 0:
            G[r * L:(r + 1) * L] -= harmonics
        step = FINITE_STEP * max(float(np.max(np.abs(elongation))), float(np.max(group.eta)), 1e-300)
        for l in range(L):
            moved, _ = steady_cycle(group, elongation + step * self.basis[:, l], period, u.copy(),
                                    self.system.source)
            block[:, l] += (self.harmonics_of(moved) - harmonics) / step
        faster = omega * (1.0 + FINITE_STEP)
        moved, _ = steady_cycle(group, elongation, 2.0 * math.pi / faster, u.copy(), self.system.source)
        by_omega = (self.harmonics_of(moved) - harmonics) / (faster - omega)
        self.by_omega[p * L:(p + 1) * L] += by_omega
        if r >= 0:
            self.by_omega[r * L:(r + 1) * L] -= by_omega

    def force(self, omega: float) -> np.ndarray:
        """The harmonics (n L,) of the force at ``omega`` (rad/s)."""
        return self.load * (self.fraction * omega**self.power)

    def force_scale(self, omega: float) -> float:
        """The largest force amplitude at ``omega``: the scale of the residual's tolerance."""
        return float(np.max(np.abs(self.load))) * omega**self.power

    def evaluate(self, free_values: np.ndarray, omega: float, xi: float = 0.0, forced: bool = True) -> tuple:
        """``(R, dR/dq, dR/domega, dR/dxi)`` on the free unknowns at ``omega`` (rad/s); ``xi`` (1/s): the
        negative viscous term -xi M x' of a nonlinear mode (0: the forced response); ``forced``: with F0."""
        q = self.full(free_values)
        G, nonlinear = self.nonlinear(q, omega)
        velocity = self.linear_damping - xi * self.mass_velocity
        memory, memory_by_omega = self.memory_terms(omega)
        linear = self.linear_stiffness + omega * velocity + omega * omega * self.linear_inertia + memory
        residual = linear @ q + G - (self.force(omega) if forced else 0.0)
        jacobian = linear + nonlinear
        by_omega = (velocity + 2.0 * omega * self.linear_inertia + memory_by_omega) @ q + self.by_omega
        if forced and self.power:
            by_omega = by_omega - self.power * self.force(omega) / omega
        by_xi = -omega * (self.mass_velocity @ q)
        f = self.free
        return residual[f], jacobian[np.ix_(f, f)], by_omega[f], by_xi[f]

    def linear_guess(self, omega: float) -> np.ndarray:
        """The free unknowns of the response with every branch sticking and no cubic spring (a first guess)."""
        s = self.system
        stuck = s.stiffness.copy()
        ends = s.branch_ends.tolist() + [list(g.ends) for g in s.series for _ in g.index]
        stiffnesses = s.branch_k.tolist() + [k for g in s.series for k in g.model[4].tolist()]
        for (p, r), k in zip(ends, stiffnesses):
            stuck[p, p] += k
            if r >= 0:
                stuck[r, r] += k
                stuck[p, r] -= k
                stuck[r, p] -= k
        memory = s.memory
        if memory is not None and memory.dahl is not None:  # Dahl at a reversal: a spring sigma
            stuck[memory.node, memory.node] += memory.dahl.sigma
        matrix = np.kron(stuck, np.eye(self.L)) + omega * self.linear_damping + omega * omega * self.linear_inertia \
            + self.memory_terms(omega)[0]
        f = self.free
        try:
            return np.linalg.solve(matrix[np.ix_(f, f)], self.force(omega)[f])
        except np.linalg.LinAlgError:
            return np.linalg.lstsq(matrix[np.ix_(f, f)], self.force(omega)[f], rcond=None)[0]

    def solve_at(self, omega: float, guess: Optional[np.ndarray] = None, fewer: bool = True) -> np.ndarray:
        """The free unknowns at ``omega`` by Newton's method from ``guess`` (default :meth:`linear_guess`; then
        the force raised in steps if Newton does not converge at once; then, ``fewer``, from the state with
        fewer harmonics); FrequencyError past the bounds."""
        start = self.linear_guess(omega) if guess is None else guess
        solved = self._newton(omega, start)
        if solved is None:  # full Newton steps cycling between two slip patterns: halved while R grows
            solved = self._newton(omega, start, damped=True)
        if solved is not None:
            return solved
        q = 0.1 * start
        try:
            for fraction in np.linspace(0.1, 1.0, 10).tolist():
                self.fraction = fraction
                q = self._newton(omega, q)
                if q is None:
                    break
        finally:
            self.fraction = 1.0
        if q is None and fewer:
            q = self._from_fewer_harmonics(omega)
        if q is None:
            raise FrequencyError(f"{self.system.source}: harmonic balance did not converge at f = "
                                 f"{float(omega) / (2 * math.pi)!r} Hz within {NEWTON_ITERATIONS} Newton iterations "
                                 "(from the linear response, nor with the force raised in 10 steps"
                                 + (", nor from the state with fewer harmonics)" if fewer else ")"))
        return q

    def _from_fewer_harmonics(self, omega: float) -> Optional[np.ndarray]:
        """The free unknowns at ``omega`` from the state with fewer harmonics: solved with one harmonic, then
        with each number of HARMONIC_STEPS below H and H itself, each by Newton from the last lifted
        (full steps, then damped), or where that fails from its own linear response (:meth:`solve_at` without
        this ladder: the state of fewer harmonics can be on a branch that more do not have there, one
        harmonic's resonance reaching past the folds of three); None where the last is not found. From the linear
        response alone masing-bilinear at F0 = 3 N and 0.05 Hz is not found with 31 harmonics, from 21's it
        is; a Duffing oscillator with branches at 0.2279 Hz, past its folds, was refused with 21: one harmonic
        put it on its upper branch, which ends below with three. At most two solves a step."""
        ladder = [h for h in HARMONIC_STEPS if h < self.H]
        if not ladder:
            return None
        coarser = None
        q = None
        for h in ladder + [self.H]:
            balance = self if h == self.H else HarmonicBalance(self.system, h, self.force_amplitude, None,
                                                                 self.base_amplitude)
            if coarser is not None and q is not None:
                guess = lifted(coarser, balance, q)
                q = balance._newton(omega, guess)
                if q is None:
                    q = balance._newton(omega, guess, damped=True)
            if q is None and balance is not self:  # H's own linear response: what solve_at tried before
                try:
                    q = balance.solve_at(omega, fewer=False)
                except FrequencyError:
                    q = None
            coarser = balance
        return q

    def _newton(self, omega: float, q: np.ndarray, damped: bool = False) -> Optional[np.ndarray]:
        """Newton's method at ``omega`` from ``q``; ``damped``: a step after which max |R| would grow is halved (at
        most NEWTON_HALVINGS times). The sampled forces of branches are piecewise smooth: full steps can cycle
        between the Jacobians of two slip patterns (masing-bilinear, F0 = 2 N, H = 7 at 0.1 Hz: max |R| 2.161,
        2.162, 2.161, ... for 40 iterations), while damped steps can stall at a kink (a near-rigid branch), so
        :meth:`solve_at` tries the damped iteration only where the full one failed."""
        q = np.array(q, dtype=float)
        residual, jacobian, _, _ = self.evaluate(q, omega)
        for _ in range(NEWTON_ITERATIONS):
            step = solve_linear(jacobian, -residual)
            if step is None:
                return None
            size = np.max(np.abs(residual))
            if np.max(np.abs(step)) <= STEP_TOLERANCE * max(np.max(np.abs(q + step)), 1e-300) or \
                    size <= RESIDUAL_TOLERANCE * self.fraction * self.force_scale(omega):
                return q + step
            for _ in range(NEWTON_HALVINGS + 1 if damped else 1):
                moved = q + step
                residual, jacobian, _, _ = self.evaluate(moved, omega)
                if np.max(np.abs(residual)) <= size:
                    break
                step = 0.5 * step
            if not np.all(np.isfinite(residual)):
                return None
            q = moved
        return None


def harmonic_steps(nodes: int, lowest: int = 1) -> tuple:
    """The numbers of harmonics the tolerance climbs for a system of ``nodes`` nodes: HARMONIC_STEPS, those past
    DENSE_STEPS only while n (2 H + 1) <= MOST_CHOSEN_UNKNOWNS; from the last one below ``lowest`` (the first
    curve is only compared with, the curve chosen has at least ``lowest``), empty where none reaches ``lowest``."""
    steps = [H for H in HARMONIC_STEPS if H <= DENSE_STEPS or nodes * (2 * H + 1) <= MOST_CHOSEN_UNKNOWNS]
    first = next((i for i, H in enumerate(steps) if H >= lowest), None)
    return () if first is None else tuple(steps[max(first - 1, 0):])


def lifted(balance, finer, free_values) -> np.ndarray:
    """``balance``'s free unknowns as ``finer``'s (more harmonics): the same harmonics, the new ones 0."""
    n, L = balance.system.n, balance.L
    padded = np.zeros((n, finer.L))
    padded[:, :L] = balance.full(free_values).reshape(n, L)
    return padded.reshape(-1)[finer.free]


def solve_linear(matrix: np.ndarray, right: np.ndarray) -> Optional[np.ndarray]:
    """``matrix^-1 right``, or None where the matrix is singular or the result not finite."""
    try:
        out = np.linalg.solve(matrix, right)
    except np.linalg.LinAlgError:
        return None
    return out if np.all(np.isfinite(out)) else None


def _held_nodes(n: int, links: list) -> np.ndarray:
    """For each of ``n`` nodes, whether the ``links`` (p, q) (springs and cubic springs; q = -1 the ground)
    join it to the ground, through other nodes too: its mean is an unknown (see the module)."""
    parent = list(range(n + 1))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b in links:
        parent[find(a)] = find(n if b < 0 else b)
    return np.array([find(i) == find(n) for i in range(n)], dtype=bool)
