"""The periodic state of an element with friction on its mass (``[friction]``), by shooting on the exact
stepper (or, for a cubic spring or Stribeck's drop, on the Taylor series of ``element_orbit.py``), and of a
network with sliders (on ``network_orbit.py``): the whole curve, its folds and the stability of every point.

Why not harmonic balance: the friction's force while the mass sticks is set by the balance of the other forces,
not by the motion, so alternating frequency-time cannot sample it (a slider behind a spring, a Prandtl branch,
is sampled exactly). The dynamic Lagrangian of the contact was tried and measured (docs/frequency.md): its root
depends on its penalty at finite H and it stays 0.1 to 0.6 % off the time sweep at H = 63. The orbit itself has
no such limit: the ``exact`` stepper that ``--method time`` runs integrates it exactly (closed form between
events, stick and slip located to rounding), so the periodic state is found as the fixed point of the stepper's
map over one period, and its harmonics are those of the orbit (never truncated).

**Half a period, by symmetry.** Every force of such a scene is odd in (x, v, u) (springs, cubic springs, the
dashpot, the branches, friction on a fixed ground) and the force F0 cos(omega t) turns sign
over half a period, so the periodic state has x(t + T/2) = -x(t) (v and every u too). Shooting solves

    R(s, omega) = -Phi(s, omega) - s = 0,    s = (x, v / omega_ref, u_1 ... u_n) at t = 0,

Phi the stepper's map over T / 2 (M / 2 steps of h = T / M), omega_ref the geometric mean of the frequency
range (a fixed scale, so that s is in lengths). The symmetry fixes what a full period leaves free: a branch
that never slides keeps any offset over a full period (a neutral direction that would make R singular); over
half a period its u is carried by x and turned, so s is unique. It leaves out orbits that break the symmetry
(they bifurcate from the symmetric ones where a multiplier crosses +1: the stability column shows it).

The Jacobian dR/ds is by finite differences (each component of s perturbed by PERTURBATION of the orbit's
size, one half period each: 2 + n runs), dR/d omega likewise: the map is piecewise smooth (the events move with
s), so differences across an event are a secant of it, as Newton's method needs. The arc-length continuation
is ``continuation.py``'s, the unknowns s in place of the harmonics.

**Stability** of every point: the monodromy of the whole period is (dG/ds)^2, G = -Phi (the symmetry), so the
Floquet multipliers are the squares of the eigenvalues of dG/ds = dR/ds + I, from the same differences at the
point. A branch stuck all along gives the neutral multiplier 1, as ``floquet.py`` says. A scene of linear
springs, dashpots, branches, sliders and Coulomb friction on a fixed ground is monotone, so the energy of the
difference of two motions never grows and every multiplier has |mu| <= 1: no point is unstable, none folds
(docs/frequency.md; the tests check the contraction on the steppers themselves); there the multipliers are a
check on the code, and the rate at which a point attracts. A cubic spring or Stribeck's drop is not monotone:
their curves fold and have unstable parts, which the multipliers find.

**Accuracy.** The stepper is ``exact`` (closed form between events, stick and slip located to rounding): the
orbit is exact whatever the steps, and M samples per period only set the quadrature of the harmonics (the
trapezoid rule over x, which is C^1: an error like 1 / M^2). The continuation runs at FIRST_STEPS samples; then
M is doubled until the first harmonic of every point changes by at most half the tolerance (relative: the
error at M is about 4/3 of that change), past MAX_STEPS refused with the change reached. Scenes the exact
stepper does not take (a cubic spring, a Stribeck drop) run on ``element_orbit.py``: event by event as the
exact stepper, each smooth phase its Taylor series with the truncation at rounding (:func:`smooth`). Not on
``verlet``: its orbit's error comes in a staircase as the steps move across the stick and slip events
(measured: a change of 3e-4 from M to 2 M where the error was 1.2e-3), and at a reversal the discrete orbit
sticks for one step or not depending on M, which flips the multipliers' verdict from point to point (0.49
against 1.05 at neighbouring points of a Stribeck scene): no stated accuracy. The stepper's refusal of a
trial state (its event search past its bound, at a force within a hair of the friction's threshold) counts as
a corrector that did not converge. The
harmonics reported are those of the orbit's samples (the curve's ``harmonics``: how many are kept in
``coefficients``, 7 unless given; they do not limit the accuracy).

Base excitation (Y0 cos(omega t) of the ground): in relative coordinates z = x - y under m Y0 omega^2
cos(omega t), the friction on the relative velocity (the mass slides on the moving support); x = z + y
reported, as the harmonic balance does.

A ``[delay]`` beside the friction: its force on the periodic orbit, -g y(t - tau), is the orbit's own, odd
over half a period; its odd harmonics up to delay_harmonics are unknowns after the history's z_j, the Taylor
orbit runs under them (``element_orbit.run_forced``), and the residual asks them to be those of the orbit's
half period continued by the symmetry (:meth:`ElementShooting._delayed`). They are doubled with the samples
until the first harmonic settles (``shooting_response``). The stability of such a point is the delay
equation's, semi-discretised on the same Taylor orbit (:meth:`ElementShooting._delay_monodromy`).

**A moving belt** (``[friction] belt_velocity`` V != 0) is not odd: the friction acts on the slip v - V, so
the orbit has no half period's symmetry, and its mean is not zero (the belt drags the mass). Shooting then
solves R(s, omega) = Phi_T(s) - s over the whole period (M steps), the multipliers are the eigenvalues of
dPhi_T/ds, and the orbit is ``element_orbit.py``'s (the mass stuck to the belt moves with it, x a polynomial
in t, the branches it carries sliding at their levels ahead, a series branch and a history driven by it; a
slide ends where the slip does). Beside a spring, a dashpot, a cubic spring, branches (with series dashpots or
not), ``[history]``, ``[delay]`` (its mean and every harmonic as unknowns) and a Stribeck drop. A Prandtl
branch that never slides over the period keeps any preload (u - x is conserved: a family of periodic states, R
singular along it); its row of R is then replaced by a convention that picks the member whose elongation is
centred in its range, the one continuous with the branch sliding both ways (:meth:`ElementShooting._centred`),
and that member's neutral multiplier (1) is left out of its stability. Under base excitation the belt rides on
the support, as the friction does (its slip the relative velocity less V). The continuation's arc length is
scaled by the state less the drag's offset of x (:meth:`ElementShooting.size_of`). Refused with a belt, one
line each: nothing holding the mass's position (every translation of a periodic state is one too) and a family
beside a cubic spring (its amplitudes depend on the member: :meth:`ElementShooting.family`).

What is refused, one line each: a node other than the mass (``[dahl]`` with ``[friction]`` the scene refuses; ``[history]`` is taken: its states are
unknowns of ``element_orbit.py``, as are the u of branches behind series dashpots).
Nonlinear modes (EPMC) of such a scene are solved for by ``slider_modes.py`` on the network of one node
(``modes.py``).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import DEFAULT_TOLERANCE, FrequencyError
from .harmonic_balance import ELEMENT_NODE, Nodes, solve_linear

PERTURBATION = 1e-7
NEWTON_ITERATIONS = 40
STEP_TOLERANCE = 1e-11
# a start from rest: Newton, then periods of the motion from where it stands, at most START_ATTEMPTS times
# (8, 16, 32, ... periods: 2040 in all)
START_ATTEMPTS = 8
DEFAULT_HARMONICS = 7
MAX_STEPS = 2**16
# samples per period of the continuation (the orbit is exact: they set the quadrature only; each costs the exact
# stepper a matrix exponential)
FIRST_STEPS = 64
# the stability beside a delay: steps per period of its semi-discretisation, and how often they are doubled
DELAY_STEPS = 256
DELAY_REFINEMENTS = 3
DELAY_MAX_STEPS = 2**14
# from this many unknowns on, the continuation's corrector keeps the last point's Jacobian (see costly_jacobian)
CHORD_UNKNOWNS = 12


def takes(scene) -> bool:
    """Whether the forced response of ``scene`` is solved here: an element scene with ``[friction]``, or a
    network with sliders (the chain on a support among them)."""
    from ..network.model import NetworkScene

    if isinstance(scene, NetworkScene):
        return bool(scene.network.of_kind("slider"))
    return scene.friction is not None


class StepFailed(FrequencyError):
    """The stepper refused a state of the shooting (see :meth:`Shooting.evaluate`)."""


@dataclass(frozen=True, eq=False)
class ShootingSystem(Nodes):
    """The nodes of a scene, as ``harmonic_balance.PeriodicSystem`` names them to the curve and the continuation:
    ``nodes`` names, ``mass`` (n,) (0: massless), ``load_node`` the index of the node the force acts on."""

    name: str
    source: str
    nodes: tuple
    mass: np.ndarray
    load_node: int = 0


def prepared(scene, named=None, loaded=None, observe=False):
    """``scene`` as shooting runs it (a spectrum of branches as the harmonic balance's quadrature of branches; a
    network's massless nodes condensed, ``named`` (--node) and ``loaded`` (the node a force acts on) with them
    where ``observe``, which returns ``(scene, series.Observed or None)``); FrequencyError for what it does not
    take."""
    from ..effects import Branches
    from ..network.model import NetworkScene

    if isinstance(scene, NetworkScene):
        return prepared_network(scene, named, loaded, observe=observe)
    if observe:
        return prepared(scene, named, loaded), None
    from ..loads import HarmonicLoad
    from ..steppers import get_stepper
    from .harmonic_balance import spectrum_branches

    if scene.mass is None:
        raise FrequencyError(f"{scene.source}: the frequency response needs [mass] (the element alone has no "
                             "resonance: describe it with --amplitudes)")
    if scene.branches is not None and scene.branches.continuum:
        k, eta = spectrum_branches(scene.branches, DEFAULT_TOLERANCE, scene.source)
        scene = dataclasses.replace(scene, branches=Branches(k, eta, np.zeros(k.shape[0])))
    if smooth(scene):
        return scene
    try:
        get_stepper("exact").loop_for(dataclasses.replace(scene, load=HarmonicLoad(1.0, 1.0)))
    except ValueError as exc:
        raise FrequencyError(f"{scene.source}: [friction] on the mass is solved for by shooting on the exact "
                             f"stepper, which does not take this scene ({exc}): use --method time") from None
    return scene


def smooth(scene) -> bool:
    """Whether an element scene with friction is not the exact stepper's (a cubic spring, Stribeck's drop: not
    linear between events; ``[history]``: states of its own): its orbit is ``element_orbit.py``'s Taylor
    series."""
    return scene.cubic is not None or scene.friction.alpha_kinetic != scene.friction.alpha or \
        scene.history is not None or scene.delay is not None or scene.friction.belt_velocity != 0.0


def prepared_network(scene, named=None, loaded=None, purpose="the forced response", observe=False):
    """A network with sliders as :class:`NetworkShooting` runs it (``network_orbit.py``): its massless nodes
    condensed (``series.condensed``: springs and levers between the nodes with a mass; ``named`` and ``loaded``
    must have one, or, where ``observe``, be held by springs alone: then ``(scene, series.Observed)``), or
    FrequencyError (``purpose``: what it is for, as the refusals say)."""
    from .series import condensed

    network = scene.network
    source = scene.source
    for option, name in (("--node", named), ("--load-node", loaded)):
        if name is not None and name not in network.nodes:  # every node as written (some may be condensed)
            raise FrequencyError(f"{option}: {name!r} is not a node of {source} ({', '.join(network.nodes)})")
    return condensed(scene, named, loaded, purpose, observe)


class Shooting:
    """The periodic state at each omega (see the module): the unknowns s (x, v / omega_ref, u) at t = 0, the
    interface of ``HarmonicBalance`` that ``continuation.py`` uses (:meth:`evaluate`, :meth:`solve_at`,
    :meth:`_newton`, :meth:`force_scale`, :meth:`amplitude_at`). A subclass runs its stepper: :meth:`run`."""

    def __init__(self, system: ShootingSystem, force_amplitude: Optional[float], base_amplitude: Optional[float],
                 steps: int, harmonics: int, reference: float, stepper: str, dimension: int, stiffness: float):
        if steps % 2 or steps < 2 * harmonics + 2:
            raise ValueError(f"steps: an even number >= 2 H + 2, got {steps!r}")
        self.system = system
        self.force_amplitude = None if force_amplitude is None else float(force_amplitude)
        self.base_amplitude = None if base_amplitude is None else float(base_amplitude)
        self.M = int(steps)
        self.H = int(harmonics)
        self.L = 2 * self.H + 1
        self.reference = float(reference)
        self.stepper = stepper
        self.dimension = int(dimension)
        self.stiffness = float(stiffness)  # what holds the load's node when everything sticks: the motion's size
        self._loads = {}
        self.symmetric = True  # the half period's symmetry (see the module); a belt breaks it: the whole period

    # ------------------------------------------------------------- the stepper's map

    def amplitude_of_force(self, omega: float) -> float:
        """F0, or m Y0 omega^2 under base excitation (the relative coordinates' force on the node with a mass)."""
        if self.force_amplitude is not None:
            return self.force_amplitude
        return float(self.system.mass[self.system.load_node]) * self.base_amplitude * omega * omega

    def _load(self, omega: float):
        from ..loads import HarmonicLoad

        if omega not in self._loads:
            if len(self._loads) > 64:
                self._loads.clear()
            self._loads[omega] = HarmonicLoad(self.amplitude_of_force(omega), omega).compile()
        return self._loads[omega]

    def run(self, s: np.ndarray, omega: float, half_periods: int = 1) -> tuple:
        """``(state at the end, x at the step ends (M / 2 half_periods, n))``: ``half_periods`` half periods of the
        stepper from the unknowns ``s`` at t = 0 (the state at the end in the same unknowns, not turned)."""
        raise NotImplementedError

    def _refuse(self, omega: float, why: str):
        prefix = f"{self.system.source}: "
        why = why[len(prefix):] if why.startswith(prefix) else why
        raise StepFailed(f"{prefix}at f = {float(omega) / (2 * math.pi)!r} Hz: {why}")

    def _checked(self, end: np.ndarray, xs: np.ndarray, omega: float) -> tuple:
        if not (np.all(np.isfinite(end)) and np.all(np.isfinite(xs))):
            self._refuse(omega, "the motion is not finite (an overflow)")
        return end, xs

    def residual(self, s: np.ndarray, omega: float) -> np.ndarray:
        if self.symmetric:
            return -self.run(s, omega)[0] - s
        return self.run(s, omega, 2)[0] - s

    def size(self, s: np.ndarray, omega: float) -> float:
        """The orbit's size (m): its state's, or the force's static deflection, whichever is larger."""
        stiff = max(self.stiffness, float(self.system.mass[self.system.load_node]) * omega * omega, 1e-300)
        return max(float(np.max(np.abs(s))), self.amplitude_of_force(omega) / stiff)

    def jacobian(self, s: np.ndarray, omega: float, base: Optional[np.ndarray] = None) -> np.ndarray:
        """dR/ds by forward differences (see the module)."""
        if base is None:
            base = self.residual(s, omega)
        epsilon = PERTURBATION * self.size(s, omega)
        out = np.empty((self.dimension, self.dimension))
        for k in range(self.dimension):
            moved = s.copy()
            moved[k] += epsilon
            out[:, k] = (self.residual(moved, omega) - base) / epsilon
        return out

    def evaluate(self, s: np.ndarray, omega: float) -> tuple:
        """``(R, dR/ds, dR/d omega, None)`` at ``s`` and ``omega``; where the stepper refuses a trial state (the
        exact stepper's event search past its bound, at a force within a hair of the friction's threshold), all
        NaN: the continuation counts the trial as not converged and shortens its step."""
        s = np.asarray(s, dtype=float)
        try:
            residual = self.residual(s, omega)
            step = PERTURBATION * omega
            by_omega = (self.residual(s, omega + step) - residual) / step
            return residual, self.jacobian(s, omega, residual), by_omega, None
        except StepFailed:
            nan = np.full(self.dimension, np.nan)
            return nan, np.full((self.dimension, self.dimension), np.nan), nan, None

    @property
    def costly_jacobian(self) -> bool:
        """Whether the continuation's corrector keeps the Jacobian of the last point (the chord method): a
        Jacobian is a run of the motion per unknown, a chord iteration one run; measured, the chord's 10 to 20
        iterations a point cost more than Newton's 3 Jacobians below CHORD_UNKNOWNS unknowns (`prandtl-fmu
        describe networks/two-masses-slider --force-amplitude 3 --frequencies 0.3,4`, 5 unknowns: 5.8 s with
        the chord against 3.8 s); above, ``benchmarks/network_shooting.py``."""
        return self.dimension >= CHORD_UNKNOWNS

    def residual_at(self, s: np.ndarray, omega: float) -> np.ndarray:
        """R at ``s`` and ``omega``, all NaN where the stepper refuses the trial state (as :meth:`evaluate`)."""
        try:
            return self.residual(np.asarray(s, dtype=float), omega)
        except StepFailed:
            return np.full(self.dimension, np.nan)

    def force_scale(self, omega: float) -> float:
        """The residual's scale (m): the force's static deflection, or its motion at omega."""
        return self.size(np.zeros(1), omega)

    def length_scale(self, omega: float) -> float:
        """The continuation's least scale of s (m): the force's static deflection, or its motion at omega (an
        orbit at rest, a mass stuck to its moving support, has s = 0)."""
        return self.force_scale(omega)

    # ------------------------------------------------------------- solving at one frequency

    def _newton(self, omega: float, guess: np.ndarray) -> Optional[np.ndarray]:
        """Newton's method at ``omega`` from ``guess``: the unknowns, or None (not converged within
        NEWTON_ITERATIONS, or a trial state the stepper refuses)."""
        try:
            return self._iterate(omega, guess)
        except StepFailed:
            return None

    def _iterate(self, omega: float, guess: np.ndarray) -> Optional[np.ndarray]:
        s = np.array(guess, dtype=float)
        residual = self.residual(s, omega)
        for _ in range(NEWTON_ITERATIONS):
            step = solve_linear(self.jacobian(s, omega, residual), -residual)
            if step is None:
                return None
            # halved while the residual grows (a kink of the map between s and the step's end), at most 8 times
            for _ in range(8):
                moved = s + step
                new = self.residual(moved, omega)
                if np.max(np.abs(new)) <= np.max(np.abs(residual)) or np.max(np.abs(step)) <= \
                        STEP_TOLERANCE * self.size(s, omega):
                    break
                step = 0.5 * step
            s, residual = moved, new
            if np.max(np.abs(step)) <= STEP_TOLERANCE * self.size(s, omega) or \
                    np.max(np.abs(residual)) <= 1e-14 * self.size(s, omega):
                return s
        return None

    def solve_at(self, omega: float, guess: Optional[np.ndarray] = None) -> np.ndarray:
        """The unknowns at ``omega``: Newton from ``guess`` (default: rest); where it does not converge, the
        motion run on from where it stands (8, 16, ... periods) and Newton again, at most START_ATTEMPTS
        times; FrequencyError past them."""
        s = np.zeros(self.dimension) if guess is None else np.array(guess, dtype=float)
        for attempt in range(START_ATTEMPTS):
            solved = self._newton(omega, s)
            if solved is not None:
                return solved
            s = self.run(s, omega, 2 * 8 * 2**attempt)[0]
        periods = 8 * (2**START_ATTEMPTS - 1)
        raise FrequencyError(f"{self.system.source}: the periodic state at f = {float(omega) / (2 * math.pi)!r} Hz "
                             f"was not found: Newton's method did not converge from rest nor after {periods} periods of the "
                             "motion (a subharmonic, chaotic or unsymmetric motion?): see --method time")

    # ------------------------------------------------------------- what a point says

    def samples(self, s: np.ndarray, omega: float) -> np.ndarray:
        """x of every node over one period at t_j = j T / M, j = 0 ... M - 1, (n, M) (relative under base
        excitation): the first half run, the second its negative (the symmetry; without it, the whole period)."""
        _, xs = self.run(s, omega, 1 if self.symmetric else 2)
        half = np.concatenate((s[None, :self.system.n], xs[:-1]), axis=0).T
        return np.concatenate((half, -half), axis=1) if self.symmetric else half

    def coefficients(self, s: np.ndarray, omega: float) -> np.ndarray:
        """The mean and H harmonics of x of every node (absolute: y added under base excitation), (n, 2 H + 1),
        in the order of the harmonic balance (a_0, a_1, b_1, ...)."""
        out = self._harmonics(self.samples(s, omega))
        if self.base_amplitude is not None:
            out[:, 1] += self.base_amplitude
        return out

    def _harmonics(self, samples: np.ndarray) -> np.ndarray:
        """(a_0, a_1, b_1, ... a_H, b_H) of each row of ``samples`` over one period (rows, M)."""
        spectrum = np.fft.rfft(samples, axis=1) / self.M
        out = np.empty((samples.shape[0], self.L))
        out[:, 0] = spectrum[:, 0].real
        out[:, 1::2] = 2.0 * spectrum[:, 1:self.H + 1].real
        out[:, 2::2] = -2.0 * spectrum[:, 1:self.H + 1].imag
        return out

    def first_harmonic(self, s: np.ndarray, omega: float, node: Optional[int] = None) -> complex:
        c = self.coefficients(s, omega)[self.system.load_node if node is None else node]
        return complex(c[1], -c[2])

    def amplitude_at(self, s: np.ndarray, omega: float, node: Optional[int] = None) -> float:
        return abs(self.first_harmonic(s, omega, node))

    @property
    def monotone(self) -> bool:
        """Whether the scene is monotone (``floquet.monotone``: linear springs and dashpots of positive
        semi-definite matrices, branches, sliders and Coulomb friction on a fixed ground; no cubic spring, no
        Stribeck drop, no belt, no effect with memory): then no periodic state is unstable and the curve has no
        fold, a function of the frequency (``continuation.march_curve`` steps it in omega)."""
        return False

    def multipliers(self, s: np.ndarray, omega: float) -> np.ndarray:
        """The Floquet multipliers of the whole period: the squares of the eigenvalues of dG/ds (without the
        symmetry: the eigenvalues of dPhi/ds over the period)."""
        turn = self.jacobian(np.asarray(s, dtype=float), omega) + np.eye(self.dimension)
        return np.linalg.eigvals(turn) ** (2 if self.symmetric else 1)


class ElementShooting(Shooting):
    """An element scene with friction on its mass: s = (x, v / omega_ref, u_1 ... u_n), its own stepper."""

    def __init__(self, scene, force_amplitude, base_amplitude, steps, harmonics, reference, stepper="exact",
                 delay_harmonics: Optional[int] = None):
        from ..compiled import compile_loop, compile_model
        from ..loads import HarmonicLoad
        from ..scene_tables import Solver

        system = ShootingSystem(scene.name, scene.source, (ELEMENT_NODE,), np.array([float(scene.mass.m)]))
        branches = 0 if scene.branches is None else int(scene.branches.n)
        stiffness = (0.0 if scene.spring is None else float(scene.spring.k0)) + (
            0.0 if scene.branches is None else float(np.sum(scene.branches.stiffness)))
        self.smooth = smooth(scene)
        if self.smooth:
            stepper = "taylor"  # element_orbit.py: the Taylor series of the smooth phases
        history = scene.history
        self.history = 0 if history is None else len(history.weight)  # its z_j: unknowns after the branches' u
        # the delay's force on the periodic orbit, its odd harmonics up to delay_harmonics: unknowns after the z_j
        self.delay = scene.delay
        self.delay_harmonics = 0 if self.delay is None else int(delay_harmonics or harmonics)
        if self.delay is not None and not (self.delay_harmonics % 2 and self.delay_harmonics < steps // 2):
            raise ValueError(f"delay_harmonics: odd and below steps / 2, got {self.delay_harmonics!r}")
        # (on a belt no symmetry: the mean and every harmonic up to delay_harmonics, 2 K + 1 unknowns)
        on_belt = scene.friction.belt_velocity != 0.0
        self.delay_unknowns = 0 if self.delay is None else \
            (2 * self.delay_harmonics + 1 if on_belt else self.delay_harmonics + 1)
        super().__init__(system, force_amplitude, base_amplitude, steps, harmonics, reference, stepper,
                         2 + branches + self.history + self.delay_unknowns, stiffness)
        self.branches = branches
        self.element = scene  # as prepared (the stability beside a delay builds finer ones)
        self.belt = float(scene.friction.belt_velocity)
        self.symmetric = self.belt == 0.0
        # what holds the mass's position on a belt: a static stiffness (the spring's, a history's on x, sum w / r,
        # a delay's on x), a history's integral (a rate 0) or a cubic spring (a translation changes their force);
        # without any, every translation of a periodic state is one too
        static = (0.0 if scene.spring is None else float(scene.spring.k0)) + (
            0.0 if self.delay is None or self.delay.acts_on != "x" else float(self.delay.gain))
        integral = False
        if history is not None and history.acts_on == "x":
            static += sum(w / r for w, r in zip(history.weight, history.rate) if r > 0.0)
            integral = any(w != 0.0 and r == 0.0 for w, r in zip(history.weight, history.rate))
        held = static != 0.0 or integral or scene.cubic is not None
        self.static_stiffness = static  # (N/m) what holds x's mean against a constant force
        if self.belt != 0.0 and not held:
            raise FrequencyError(f"{scene.source}: [friction] on a moving belt with nothing that holds the mass's "
                                 "position (no static stiffness of [spring], [history] or [delay] on x, nor a "
                                 "[cubic]): every translation of a periodic state is one too: give it a [spring], "
                                 "or use --method time")
        lam = _relaxation(scene.branches)
        # the Prandtl branches (no series dashpot): their offsets are what a belt's family leaves free
        self.series = np.isfinite(lam) if lam.size else np.zeros(branches, dtype=bool)
        self._plain = False  # the residual without the family's conventions (the multipliers' monodromy)
        self.eta = np.zeros(0) if scene.branches is None else np.array(scene.branches.yield_displacement, float)
        self._out = np.empty((self.M // 2, 3))
        if self.smooth:
            friction = scene.friction
            self.parameters = (float(scene.mass.m), 0.0 if scene.spring is None else float(scene.spring.k0),
                               float(scene.damper.c) if scene.has_dashpot else 0.0,
                               0.0 if scene.cubic is None else float(scene.cubic.k3), float(friction.alpha),
                               float(friction.alpha_kinetic),
                               float(friction.stribeck_velocity) if friction.alpha_kinetic != friction.alpha else 0.0,
                               np.zeros(0) if scene.branches is None else np.array(scene.branches.stiffness, float),
                               self.eta, _relaxation(scene.branches),
                               np.array(history.weight if history else (), float),
                               np.array(history.rate if history else (), float),
                               bool(history is not None and history.acts_on == "v"))
            return
        self.scene = dataclasses.replace(scene, load=HarmonicLoad(1.0, reference),
                                         solver=Solver(stepper, 1.0 / steps, 1.0, 1.0 / steps))
        self.model = compile_model(self.scene, "play")
        self.loop = compile_loop(self.scene, stepper)

    def run(self, s: np.ndarray, omega: float, half_periods: int = 1) -> tuple:
        from ..stepping import ElementError, _failure, integrate

        if self.smooth:
            return self._run_smooth(s, omega, half_periods)
        h = 2.0 * math.pi / omega / self.M
        x, v = float(s[0]), float(s[1]) * self.reference
        # u within its elastic range (a Newton iterate may step past it; the orbit's u is within it)
        u = None if self.branches == 0 else np.clip(np.array(s[2:], dtype=float), -self.eta, self.eta)
        out = self._out if half_periods == 1 else np.empty((self.M // 2 * half_periods, 3))
        load = self._load(omega)
        try:
            x, v, taken = integrate(self.loop, self.model, load, x, v, u, 0.0, 0, h, 1, out, None, None, None)
        except ElementError as exc:
            self._refuse(omega, str(exc))
        if taken < out.shape[0]:
            self._refuse(omega, str(_failure(self.scene, self.stepper, load, taken * h, h, None)))
        end = np.empty(self.dimension)
        end[0], end[1] = x, v / self.reference
        if u is not None:
            end[2:] = u
        return self._checked(end, out[:, :1].copy(), omega)

    def _run_smooth(self, s: np.ndarray, omega: float, half_periods: int) -> tuple:
        """:meth:`run` on ``element_orbit.py``'s Taylor series (a cubic spring, Stribeck's drop)."""
        from .element_orbit import OK, explain, run, run_forced

        h = 2.0 * math.pi / omega / self.M
        state = np.array([float(s[0]), float(s[1]) * self.reference])
        u = np.clip(np.array(s[2:2 + self.branches], dtype=float), -self.eta, self.eta)
        z = np.array(s[2 + self.branches:2 + self.branches + self.history], dtype=float)
        steps = self.M // 2 * half_periods
        out = np.empty(steps)
        if self.delay is None:
            status, taken = run(*self.parameters, float(self.amplitude_of_force(omega)), float(omega), state, u, z,
                                h, steps, out, self.belt)
        else:
            delayed = np.array(s[self.dimension - self.delay_unknowns:], dtype=float)
            if self.symmetric:  # its odd harmonics
                extra = np.empty((delayed.size // 2, 3))
                extra[:, 0] = np.arange(1, self.delay_harmonics + 1, 2)
                extra[:, 1:] = self._delay_scale() * delayed.reshape(-1, 2)
            else:  # its mean, then every harmonic
                extra = np.zeros((self.delay_harmonics + 1, 3))
                extra[:, 0] = np.arange(self.delay_harmonics + 1)
                extra[0, 1] = self._delay_scale() * delayed[0]
                extra[1:, 1:] = self._delay_scale() * delayed[1:].reshape(-1, 2)
            status, taken = run_forced(*self.parameters, float(self.amplitude_of_force(omega)), float(omega), extra,
                                       np.zeros(0), np.zeros(0), state, u, z, h, steps, out, self.belt)
        if status != OK:
            self._refuse(omega, f"the motion from the trial state stopped at t = {taken * h!r} s: {explain(status)}")
        end = np.concatenate(([state[0], state[1] / self.reference], u, z))
        if self.delay is not None:
            # the residual -end - s asks the delay's force to be the one the half period's orbit gives (its
            # symmetric continuation over the whole period); run on (several half periods), it is kept
            if half_periods == 1 and self.symmetric:
                follows = -self._delayed(np.concatenate(([s[0]], out[:-1])), omega)
            elif half_periods == 2 and not self.symmetric:  # the whole period's orbit, on a belt
                follows = self._delayed(np.concatenate(([s[0]], out[:-1])), omega)
            else:
                follows = (-1.0) ** half_periods * delayed
            end = np.concatenate((end, follows))
        return self._checked(end, out[:, None].copy(), omega)

    def residual(self, s: np.ndarray, omega: float) -> np.ndarray:
        """As :meth:`Shooting.residual`; on a belt, each Prandtl branch's row the family's convention
        (:meth:`_centred`)."""
        if self.symmetric:
            return super().residual(s, omega)
        end, xs = self.run(s, omega, 2)
        residual = end - s
        if not self._plain:
            self._centred(s, residual, np.concatenate(([s[0]], xs[:, 0])))
        return residual

    def size_of(self, s: np.ndarray, omega: float) -> float:
        """The size of ``s`` that scales the continuation's arc length (``continuation._size``): its norm, less the
        mean of x over the orbit from x(0) on a belt (the drag's offset, which can dwarf the oscillation)."""
        s = np.asarray(s, dtype=float)
        if self.symmetric:
            return float(np.linalg.norm(s))
        try:
            mean = float(np.mean(self.samples(s, omega)[0]))
        except StepFailed:
            return float(np.linalg.norm(s))
        moved = s.copy()
        moved[0] -= mean
        return float(np.linalg.norm(moved))

    def _centred(self, s: np.ndarray, residual: np.ndarray, x: np.ndarray) -> None:
        """The rows of the Prandtl branches on a belt, in place (see the module): a branch that never slides keeps
        any preload (its offset o = u - x is conserved: every o that keeps u within its range is as periodic,
        and its row u(T) - u(0) is x(T) - x(0) again), so its row is the slide over the period, -(R_u - R_x),
        plus, while x's extremes leave room (their spread below 2 eta), the offset's distance from the centred
        one, clip(o, -eta - min x, eta - max x) + (max x + min x) / 2: zero at a periodic state only where the
        branch's elongation is centred in its range (the member continuous with the branch sliding both ways,
        which is centred: at its onset only the centred member is in range); continuous in s (at the family's
        edges the slide starts from 0 and the clip holds; as the spread reaches 2 eta the term vanishes), and a
        row operation on the plain rows (R_u - R_x) where the branch slides both ways. The extremes are those
        of the periodic cubic through the samples (:func:`periodic_extremes`): within a window of their error
        at the onset the row may vanish off a periodic state (u back off by 1.7e-6 of the spread, measured)."""
        low, high = periodic_extremes(x[:-1])
        room = 2.0 * self.eta - (high - low)
        for i in range(self.branches):
            if self.series[i]:
                continue
            row = residual[0] - residual[2 + i]
            if room[i] > 0.0:
                offset = float(np.clip(s[2 + i], -self.eta[i], self.eta[i])) - s[0]
                row += min(max(offset, -self.eta[i] - low), self.eta[i] - high) + 0.5 * (low + high)
            residual[2 + i] = row

    def _stuck(self, s: np.ndarray, omega: float) -> int:
        """How many branches never slide over the period run from ``s`` (u - x the same all along (a slide
        shorter than a sample is seen in the end state's offset), within the range)."""
        end, xs = self.run(s, omega, 2)
        x = np.concatenate(([s[0]], xs[:, 0]))
        size = max(float(np.max(np.abs(x))), 1e-300)
        u0 = np.clip(np.asarray(s[2:2 + self.branches], dtype=float), -self.eta, self.eta)
        count = 0
        for i in range(self.branches):
            along = u0[i] + x - x[0]
            if not self.series[i] and abs(end[2 + i] - along[-1]) <= 1e-12 * max(size, self.eta[i]) and \
                    float(np.max(np.abs(along))) < self.eta[i] * (1.0 - 1e-9):
                count += 1
        return count

    def family(self, s: np.ndarray, omega: float) -> Optional[str]:
        """Why the periodic state ``s`` is one of a family whose amplitudes depend on the member (no curve: the
        continuation says so in one line), or None: on a belt a branch that never slides keeps any preload, which
        :meth:`_centred` fixes by a convention; with a cubic spring the orbit is not a shift of another member's
        (the amplitudes move with the preload: ±15 % measured), so the convention would be the number."""
        if self.symmetric or self.element.cubic is None or not self._stuck(s, omega):
            return None
        return ("a branch never slides over the period, so its preload is free (every offset within its range is "
                "as periodic), and beside [cubic] the amplitudes depend on it")

    @property
    def monotone(self) -> bool:
        """As :meth:`Shooting.monotone`: the exact stepper's scenes (Coulomb friction on a fixed ground, linear
        springs and dashpot, branches); not a cubic spring, Stribeck's drop, a belt, a history or a delay."""
        return not self.smooth

    def multipliers(self, s: np.ndarray, omega: float):
        """As :meth:`Shooting.multipliers`; on a belt those of the plain monodromy dPhi_T/ds, less one 1 per branch
        that never slides (a neighbouring member of the family: its offset is conserved, neutral, see
        :meth:`_centred`), the nearest to 1; with a delay, :meth:`_delay_multipliers`."""
        if self.symmetric:
            return super().multipliers(s, omega) if self.delay is None else self._delay_multipliers(s, omega)
        s = np.asarray(s, dtype=float)
        stuck = self._stuck(s, omega)
        if self.delay is not None:
            values = self._delay_multipliers(s, omega, stuck)
            if values is None:
                return None
        else:
            self._plain = True
            try:
                values = super().multipliers(s, omega)
            finally:
                self._plain = False
        for _ in range(stuck):
            values = np.delete(values, int(np.argmin(np.abs(values - 1.0))))
        return values

    def _delay_scale(self) -> float:
        """The delay's unknowns are its force over this (N/m): lengths, as the rest of s."""
        gain = max(abs(self.delay.gain), 1e-300)
        return gain * (self.reference if self.delay.acts_on == "v" else 1.0)

    def _delayed(self, half: np.ndarray, omega: float) -> np.ndarray:
        """The delay's force -g y(t - tau) on the orbit whose first half period has the samples ``half`` of x
        (M / 2, at t_j = j T / M; the second half their negative): its odd harmonics up to delay_harmonics, (a_1,
        b_1, a_3, b_3, ...) of a cos(p omega t) + b sin(p omega t), over the scale :meth:`_delay_scale`. The
        harmonics of x by the trapezoid rule (x is C^1: aliasing like 1 / M^2), those of v = x' as i p omega
        times them."""
        if not self.symmetric:  # on a belt: ``half`` is the whole period; its mean and every harmonic
            spectrum = np.fft.rfft(half) / self.M
            p = np.arange(0, self.delay_harmonics + 1)
            X = 2.0 * spectrum[p]
            X[0] *= 0.5
        else:
            spectrum = np.fft.rfft(np.concatenate((half, -half))) / self.M
            p = np.arange(1, self.delay_harmonics + 1, 2)
            X = 2.0 * spectrum[p]
        Y = X * (1j * p * omega) if self.delay.acts_on == "v" else X
        C = -self.delay.gain * Y * np.exp(-1j * p * omega * self.delay.tau)
        out = np.empty(2 * p.size)
        out[0::2], out[1::2] = C.real, -C.imag
        if not self.symmetric:
            out = np.delete(out, 1)  # the mean's (a_0, no b_0)
        return out / self._delay_scale()

    def _delay_multipliers(self, s: np.ndarray, omega: float, neutral: int = 0):
        """With a delay (the map of s is not the delay equation's, whose state is the motion over the last tau)
        the multipliers of :meth:`_delay_period_multipliers` at DELAY_STEPS steps per period (the LARGEST, and
        ``neutral`` more: the stuck branches' 1s), doubled while the verdict is in doubt (the largest |mu| nearer
        1 than four times its change), at most DELAY_REFINEMENTS times; None where the buffer passes
        floquet.MAX_DELAY_STATES values or Arnoldi's iteration does not converge (unknown)."""
        from .floquet import LARGEST

        s = np.asarray(s, dtype=float)
        period = 2.0 * math.pi / omega
        # steps of at most tau (the buffer's grid), and more than twice the delay's harmonics; past
        # DELAY_MAX_STEPS (a delay shorter than T / DELAY_MAX_STEPS) not computed: unknown
        steps = max(DELAY_STEPS, 2 * self.delay_harmonics + 2, 2 * math.ceil(period / self.delay.tau / 2.0))
        if steps > DELAY_MAX_STEPS:
            return None
        values, previous = None, None
        for _ in range(DELAY_REFINEMENTS + 1):
            if steps > DELAY_MAX_STEPS:
                return values
            found = self._delay_period_multipliers(s, omega, steps, LARGEST + neutral)
            if found is None:
                return values
            values = found
            top = float(np.max(np.abs(values)))
            if previous is not None and abs(top - 1.0) > 4.0 * abs(top - previous):
                return values
            previous, steps = top, 2 * steps
        return values

    def _delay_period_multipliers(self, s: np.ndarray, omega: float, steps: int, count: int) -> Optional[np.ndarray]:
        """The multipliers (``floquet.leading``: all of them for a short buffer, else the ``count`` largest) of the
        monodromy of the delay equation about the orbit of ``s`` (None past floquet.MAX_DELAY_STATES, or where
        Arnoldi's iteration does not converge).

        Its state is x, v, the branches' u, the history's z and the buffer: y at the grid points t_k = k h, k =
        -(N + 1) ... 0 (h = T / steps, tau = N h + delta), between which y is taken linear (the semi-discretisation
        of Insperger and Stepan: an error like h^2 in the delayed force), on ``element_orbit.run_forced``'s Taylor
        orbit, events exact. The buffer is first the orbit's y (v by the samples' spectral derivative), then two
        periods of that equation make the point its own; each component is perturbed in turn (PERTURBATION of
        the motion), one period each: 2 + n + n_z + N + 2 runs (past floquet.DENSE_STATES, Arnoldi's products
        in its place, a few tens of runs). Measured on the friction damper with a delay: a
        finite-difference monodromy on the implicit stepper, the buffer's values as states (``floquet.py``'s for
        a delay without friction) called a point unstable (|mu| = 1.27) whose time sweep settles in 8 periods:
        its stick and slip move by a step between perturbed runs. Here they move with the perturbation."""
        from .element_orbit import OK, explain, run_forced
        from .floquet import MAX_DELAY_STATES, leading

        period = 2.0 * math.pi / omega
        h = period / steps
        lag = max(int(math.floor(self.delay.tau / h)), 1)  # h <= tau (multipliers): 0 only by rounding
        delta = max(self.delay.tau - lag * h, 0.0)
        if lag + 2 > MAX_DELAY_STATES:
            return None
        on_v = self.delay.acts_on == "v"
        fine = ElementShooting(self.element, self.force_amplitude, self.base_amplitude, steps, self.H,
                               self.reference, delay_harmonics=self.delay_harmonics)
        _, xs = fine.run(s, omega, 1 if self.symmetric else 2)
        half = np.concatenate(([s[0]], xs[:-1, 0]))
        y = np.concatenate((half, -half)) if self.symmetric else half
        if on_v:
            spectrum = np.fft.rfft(y)
            y = np.fft.irfft(spectrum * (1j * omega * np.arange(spectrum.size)), n=steps)
        nb, nz = self.branches, self.history
        start = np.concatenate(([s[0], float(s[1]) * self.reference],
                                np.clip(s[2:2 + nb], -self.eta, self.eta), s[2 + nb:2 + nb + nz],
                                y[np.arange(-(lag + 1), 1) % steps]))
        delay = np.array([self.delay.gain, float(lag), delta, 1.0 if on_v else 0.0])
        amplitude = float(self.amplitude_of_force(omega))

        def run(values, periods=1):
            count = steps * periods
            state, u, z = values[:2].copy(), values[2:2 + nb].copy(), values[2 + nb:2 + nb + nz].copy()
            buffer = np.empty(lag + 2 + count)
            buffer[:lag + 2] = values[2 + nb + nz:]
            status, taken = run_forced(*self.parameters, amplitude, float(omega), np.zeros((0, 3)), delay, buffer,
                                       state, u, z, h, count, np.empty(count), self.belt)
            if status != OK:
                self._refuse(omega, f"the stability's run stopped at t = {taken * h!r} s: {explain(status)}")
            return np.concatenate((state, u, z, buffer[count:]))

        base_state = run(start, 2)
        # at least the force's static deflection: an orbit at rest (a mass held by its friction) has size 0, and
        # a perturbation of 1e-306 m made the multipliers rounding over it (6e281: a point at rest called unstable)
        size = max(float(np.max(np.abs(half))), abs(float(base_state[1])) / omega, self.size(s, omega))
        scales = np.full(base_state.size, PERTURBATION * size)
        scales[1] *= omega
        if on_v:
            scales[2 + nb + nz:] *= omega
        values = leading(run, base_state, scales, count)
        return values if values is not None and np.all(np.isfinite(values)) else None

    def delay_tail(self, s: np.ndarray) -> float:
        """The highest kept harmonic of the delay's force relative to its first, at ``s``."""
        pairs = np.asarray(s[self.dimension - self.delay_unknowns + (0 if self.symmetric else 1):],
                           dtype=float).reshape(-1, 2)
        size = np.hypot(pairs[:, 0], pairs[:, 1])
        return float(size[-1] / max(size[0], 1e-300)) if size.size > 1 else math.inf

    def padded(self, s: np.ndarray, finer: "ElementShooting") -> np.ndarray:
        """``s`` as the unknowns of ``finer`` (more of the delay's harmonics: the new ones 0)."""
        out = np.zeros(finer.dimension)
        out[:self.dimension] = s
        return out


def periodic_extremes(x: np.ndarray) -> tuple:
    """``(min, max)`` of the periodic cubic through the samples ``x`` (one period, equally spaced: Catmull-Rom,
    the slopes the centred differences), its extremes within each interval among them: continuous in the
    samples (a max of continuous functions), off the function's by a term like h^3 where it is smooth."""
    p0, p1, p2, p3 = np.roll(x, 1), x, np.roll(x, -1), np.roll(x, -2)
    m1, m2 = 0.5 * (p2 - p0), 0.5 * (p3 - p1)
    b = 3.0 * (p2 - p1) - 2.0 * m1 - m2
    a = 2.0 * (p1 - p2) + m1 + m2
    values = [x]
    # c'(t) = m1 + 2 b t + 3 a t^2 on (0, 1): its roots where real (a linear one where a is 0)
    disc = np.maximum(b * b - 3.0 * a * m1, 0.0)
    real = b * b - 3.0 * a * m1 >= 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        for sign in (1.0, -1.0):
            root = np.where(a != 0.0, (-b + sign * np.sqrt(disc)) / (3.0 * a), -m1 / (2.0 * b))
            inside = real & np.isfinite(root) & (root > 0.0) & (root < 1.0)
            t = np.where(inside, root, 0.0)
            values.append(np.where(inside, p1 + t * (m1 + t * (b + t * a)), x))
    values = np.concatenate(values)
    return float(np.min(values)), float(np.max(values))


def _relaxation(branches) -> np.ndarray:
    """The branches' rates lambda_i = k_i / c_i through their series dashpots (empty: none, Prandtl branches)."""
    if branches is None or branches.damping is None:
        return np.zeros(0)
    return np.array(branches.stiffness, float) / np.array(branches.damping, float)


class NetworkShooting(Shooting):
    """A network with sliders: s = (x, v / omega_ref, u of the branches), the motion of ``network_orbit.py``
    (every node with a mass; the force on the load's node, or under base excitation m_i Y0 omega^2 on every node
    in coordinates relative to the ground)."""

    def __init__(self, scene, force_amplitude, base_amplitude, steps, harmonics, reference, load_node=None,
                 observed=None):
        network = scene.network
        n = network.n
        if not np.all(network.mass > 0):
            raise ValueError("NetworkShooting: a network with a massless node (prepared_network condenses them)")
        # the force's shares over the nodes (a massless node loaded passes it on: series.Observed), and the
        # massless node named (its motion a sum of theirs, ``views``)
        shares = np.zeros(n)
        if observed is not None and observed.load:
            for name, share in observed.load.items():
                shares[network.nodes.index(name)] = share
            load = int(np.argmax(np.abs(shares)))
        else:
            load = network.load_node if load_node is None else network.nodes.index(load_node)
            shares[load] = 1.0
        self.load_name = load_node if load_node is not None else network.nodes[load]
        self._observed = observed
        system = ShootingSystem(scene.name, scene.source, tuple(network.nodes), np.array(network.mass, float), load)

        def row(element):
            if element.kind == "lever":
                return element.row(n)
            out = np.zeros(n)
            p, q = element.between
            out[p] += 1.0
            if q >= 0:
                out[q] -= 1.0
            return out

        self.stiffness_matrix = np.zeros((n, n))
        self.damping = np.zeros((n, n))
        sliders, branches, cubic, series, named, relaxing = [], [], [], [], [], []
        for element in network.elements:
            d = row(element)
            if element.kind == "cubic":  # its force k3 (d . x)^3 along d (network_orbit.py: by its recurrence)
                cubic.append((d, element.value))
            elif element.kind == "spring":
                self.stiffness_matrix += element.value * np.outer(d, d)
            elif element.kind == "dashpot":
                self.damping += element.value * np.outer(d, d)
            elif element.kind == "slider" and element.value > 0.0:  # alpha = 0 carries nothing
                sliders.append((d, element.value))
            elif element.kind == "branch" and element.c > 0.0:  # a series dashpot: its u relaxes (network_orbit)
                series.append(np.concatenate((d, [element.value, element.eta, element.value / element.c, 0.0])))
                relaxing.append(element.name)
            elif element.kind == "branch":
                branches.append((d, element.value, element.eta))
                named.append(element.name)
            elif element.kind == "lever" and element.c > 0.0:  # a massless node's springs and dashpot (and a slider
                # beside the dashpot: a Bingham element): its u relaxes
                series.append(np.concatenate((d, [element.value, element.alpha / element.value,
                                                  element.value / element.c, 1.0 if element.bingham else 0.0])))
                relaxing.append(element.name)
            elif element.kind == "lever":  # a massless node's slider or branch (series.condensed): a branch
                branches.append((d, element.value, element.alpha / element.value))
                named.append(element.name)
        self.rows = np.array([d for d, _ in sliders], dtype=float).reshape(len(sliders), n)
        self.alpha = np.array([a for _, a in sliders], dtype=float)
        self.brows = np.array([b[0] for b in branches], dtype=float).reshape(len(branches), n)
        self.bk = np.array([b[1] for b in branches], dtype=float)
        self.eta = np.array([b[2] for b in branches], dtype=float)
        self.smooth = bool(cubic)  # its phases by their recurrence (network_orbit.py), as the figures say
        self.series = np.array(series, dtype=float).reshape(len(series), n + 4)
        self.crows = np.array([d for d, _ in cubic], dtype=float).reshape(len(cubic), n)
        self.ck3 = np.array([k3 for _, k3 in cubic], dtype=float)
        holding = self.stiffness_matrix + sum((k * np.outer(d, d) for d, k, _ in branches), np.zeros((n, n))) + \
            sum((row[n] * np.outer(row[:n], row[:n]) for row in series), np.zeros((n, n)))
        super().__init__(system, force_amplitude, base_amplitude, steps, harmonics, reference, "exact",
                         2 * n + len(branches) + len(series), float(holding[load, load]))
        self.force = shares if base_amplitude is None else np.array(system.mass, float)
        self.branches = len(branches)
        self.branch_names = tuple(named)  # the branches' (and levers') names, in the order of their u in s
        pulled = list(named) + relaxing  # the tensions a view reads: the branches', then the series rows'
        # the massless node named: (name, weights over the nodes, weight of the ground's motion, gain of the
        # force, weights over the branches' tensions k u) (series.Observed)
        self.views = []
        for name, (weights, gain, tensions) in ({} if observed is None else observed.views).items():
            row, pulls = np.zeros(n), np.zeros(len(pulled))
            for node, weight in weights.items():
                if node is not None:
                    row[network.nodes.index(node)] = weight
            for lever, weight in tensions.items():
                pulls[pulled.index(lever)] = weight
            self.views.append((name, row, weights.get(None, 0.0), gain, pulls))

    @property
    def monotone(self) -> bool:
        """As :meth:`Shooting.monotone`: no cubic spring, stiffness and damping positive semi-definite."""
        from .floquet import positive_semidefinite

        if self.smooth:
            return False
        return positive_semidefinite(self.stiffness_matrix) and positive_semidefinite(self.damping) and \
            bool(np.all(self.bk >= 0.0))

    @property
    def names(self) -> tuple:
        """The nodes of :meth:`coefficients`: those with a mass, then the massless one named (``views``)."""
        return tuple(self.system.nodes) + tuple(view[0] for view in self.views)

    def node_index(self, name: Optional[str]) -> int:
        """The index among :attr:`names` of node ``name`` (None: the first node with a mass)."""
        if name is not None and name in self.names:
            return self.names.index(name)
        return self.system.node_index(name)

    def coefficients(self, s: np.ndarray, omega: float) -> np.ndarray:
        """As :meth:`Shooting.coefficients`, then a row for the massless node named: x_p = sum_i w_i x_i + w_g y
        + gain F0 cos(omega t) + sum_e c_e k_e u_e(t) (series.Observed; u the branches' along the orbit)."""
        out = super().coefficients(s, omega)
        rows = []
        pulled = any(np.any(view[4]) for view in self.views)
        tensions = self._harmonics(self._tensions(s, omega)) if pulled else None
        for _, weights, ground, gain, pulls in self.views:
            row = weights @ out
            if self.base_amplitude is not None:
                row[1] += ground * self.base_amplitude
            else:
                row[1] += gain * self.force_amplitude
            if pulled:
                row = row + pulls @ tensions
            rows.append(row)
        return np.vstack([out] + rows) if rows else out

    def _tensions(self, s: np.ndarray, omega: float) -> np.ndarray:
        """The tensions k u of the branches, then of the series rows, over one period at t_j = j T / M,
        (branches + series rows, M): a run that writes u too (``network_orbit.run``), the second half period the
        first's negative (the symmetry)."""
        n, nb = self.system.n, self.branches
        _, out = self.run(s, omega, with_u=True)
        start = np.clip(np.array(s[2 * n:2 * n + nb], dtype=float), -self.eta, self.eta)
        series = np.array(s[2 * n + nb:], dtype=float)
        eta, bingham = self.series[:, n + 1], self.series[:, n + 3] != 0.0
        series = np.where(bingham, series, np.clip(series, -eta, eta))  # as the run starts them
        stiffness = np.concatenate((self.bk, self.series[:, n]))
        half = np.concatenate((np.concatenate((start, series))[None, :], out[:-1, n:]), axis=0).T * stiffness[:, None]
        return np.concatenate((half, -half), axis=1)

    def amplitude_of_force(self, omega: float) -> float:
        if self.force_amplitude is not None:
            return self.force_amplitude
        return float(np.max(self.system.mass)) * self.base_amplitude * omega * omega

    def run(self, s: np.ndarray, omega: float, half_periods: int = 1, with_u: bool = False) -> tuple:
        """As :meth:`Shooting.run`; ``with_u``: the branches' u, then the series rows', at the step ends too,
        after x's columns."""
        from .network_orbit import OK, explain, run

        n = self.system.n
        h = 2.0 * math.pi / omega / self.M
        x = np.array(s[:n], dtype=float)
        v = np.array(s[n:2 * n], dtype=float) * self.reference
        u = np.clip(np.array(s[2 * n:2 * n + self.branches], dtype=float), -self.eta, self.eta)
        su = np.array(s[2 * n + self.branches:], dtype=float)  # the series branches' u (run clips them)
        amplitude = self.force_amplitude if self.force_amplitude is not None else \
            self.base_amplitude * omega * omega
        steps = self.M // 2 * half_periods
        out = np.empty((steps, n + (self.branches + self.series.shape[0] if with_u else 0)))
        status, taken = run(self.system.mass, self.stiffness_matrix, self.damping, self.rows, self.alpha,
                            self.brows, self.bk, self.eta, self.crows, self.ck3, self.series, self.force,
                            float(amplitude), float(omega), x, v, u, su, h, steps, out)
        if status != OK:
            self._refuse(omega, f"the motion from the trial state stopped at t = {taken * h!r} s: {explain(status)}")
        end = np.concatenate((x, v / self.reference, u, su))
        return self._checked(end, out, omega)


# ----------------------------------------------------------------- the curve

def shooting_response(scene, force_amplitude, base_amplitude, frequencies, *, harmonics: Optional[int] = None,
                      node: Optional[str] = None, load_node: Optional[str] = None,
                      tolerance: float = DEFAULT_TOLERANCE, stability: bool = True, samples: Optional[int] = None):
    """The forced response of an element scene with friction (see the module): the fields of a ``curve.Curve``;
    the arguments are ``curve.harmonic_response``'s, checked there."""
    from ..network.model import NetworkScene
    from ..stepping import _progress_bar
    from .continuation import continue_curve, march_curve
    from .unbounded import refuse_unbounded

    loaded = None
    if isinstance(scene, NetworkScene) and base_amplitude is None:
        loaded = scene.network.nodes[scene.network.load_node] if load_node is None else load_node
    scene, observed = prepared(scene, node, loaded, observe=True)
    network = isinstance(scene, NetworkScene)
    if not network and load_node is not None and load_node != ELEMENT_NODE:
        raise FrequencyError(f"--load-node: {load_node!r} is not a node of {scene.source} ({ELEMENT_NODE})")
    H = DEFAULT_HARMONICS if harmonics is None else int(harmonics)
    low, high = 2.0 * math.pi * float(frequencies.min()), 2.0 * math.pi * float(frequencies.max())
    reference = math.sqrt(low * high)

    def make(steps, delay_harmonics=None):
        if network:
            return NetworkShooting(scene, force_amplitude, base_amplitude, steps, H, reference, loaded, observed)
        return ElementShooting(scene, force_amplitude, base_amplitude, steps, H, reference,
                               delay_harmonics=delay_harmonics or H + 1 - H % 2)

    shooting = make(max(FIRST_STEPS, 4 * H + 4 if samples is None else int(samples) + int(samples) % 2))
    where = shooting.node_index(node) if network else shooting.system.node_index(node)
    refuse_unbounded(scene, force_amplitude, base_amplitude, low, high, load_node,
                     None if observed is None else observed.load)
    # a network's curve can take minutes (a Jacobian is 2 n + 1 runs of its motion): a bar on a terminal
    bar = _progress_bar(None, total=None, label=f"{scene.name}: points of the curve")
    try:
        follow = march_curve if shooting.monotone else continue_curve
        points = follow(shooting, low, high, int(np.unique(frequencies).size), progress=bar, node=where)
    finally:
        bar.close()
    # the quadrature of the harmonics: the orbit is the exact stepper's whatever M, so only the samples change
    # (with a delay the state changes too: its force's harmonics, twice as many and more samples, solved again)
    coefficients = np.array([shooting.coefficients(s, w) for w, s, _ in points])
    change = math.inf
    delayed = getattr(shooting, "delay", None) is not None
    while True:
        if shooting.M * 2 > MAX_STEPS:
            raise FrequencyError(f"{scene.source}: the first harmonic still changed by {change:.3g} relative from "
                                 f"{shooting.M // 2} to {shooting.M} samples per period (tolerance {tolerance:g}): "
                                 "give a larger --tolerance")
        if delayed:
            # the delay's harmonics doubled while the highest kept carries more than a tenth of the tolerance of
            # the first (a review's find: doubled with every M, each level cost 8 times the last)
            tail = max(shooting.delay_tail(s) for _, s, _ in points)
            grown = 2 * shooting.delay_harmonics + 1 if tail > 0.1 * tolerance else shooting.delay_harmonics
            finer = make(2 * shooting.M, grown)
            points, kept = _solved_again(shooting, finer, points, low, high, 0.1 * tolerance)
        else:
            finer = make(2 * shooting.M)
            kept = np.arange(len(points))
        refined = np.array([finer.coefficients(s, w) for w, s, _ in points])
        # the change at the points found again (a bridged one has no coarser twin: _solved_again)
        found = kept >= 0
        X, X_fine = (c[:, where, 1] - 1j * c[:, where, 2] for c in (coefficients[kept[found]], refined[found]))
        # relative to the node's first harmonic, or to 1e-9 of the whole motion's where that is 0 (a massless node
        # held by a slider that sticks all along: its rounding against its rounding made 5e280 and a refusal)
        floor = 1e-9 * np.max(np.abs(refined[found]).reshape(int(np.sum(found)), -1), axis=1, initial=1e-300)
        change = float(np.max(np.abs(X_fine - X) / np.maximum(np.abs(X_fine), floor)))
        shooting, coefficients = finer, refined
        # the error at M is about 4/3 of the change (the trapezoid rule: 1 / M^2); not at a level that bridged
        # points (no coarser twin to measure them against: the next level finds them again, and measures them)
        if change <= 0.5 * tolerance and np.all(kept >= 0):
            break
    return _curve(shooting, points, coefficients, where, stability, change)


def _solved_again(shooting, finer, points, low, high, spacing: float) -> tuple:
    """The ``points`` (omega, s, fold) of ``shooting``'s curve as points of the ``finer`` one (more samples, more of
    a delay's harmonics), and the indices of those kept: each by Newton at its frequency from the coarser state;
    where that does not converge, on the normal to the coarser curve through it (``continuation.across``: a fold
    the finer curve has moved past, where the state at the same frequency does not exist: the delay oscillator
    at 0.2 N, whose fold near 0.0912 Hz moves by 4e-4 of its frequency), kept only within half the way to its
    neighbours (near a corner the normal can meet the finer curve on its far side: a review's find, a point
    moved by 1e-3 across a corner and kept out of order; a second review's, three points moved by 2e-5). At a
    fold on a corner (a slip's onset where the curve turns back: the delay oscillator at 0.1 N at 0.3705 Hz)
    neither finds the points the finer corner has moved past, by less than the spacing that the corner's search
    made tiny (there the finer corner is 4e-9 Hz lower and three points, within 1.1e-8 Hz of it, are past it): a
    run of points not found that holds a fold or lies next to one, whose points are all within ``spacing``
    (relative, in frequency and in the state; a tenth of the tolerance: the fold is located to it) of the points
    found on either side of it, is left out, the point before it then marked the fold where the fold was in the
    run. A run next to a fold whose points are farther than that is bridged: the finer curve followed from the
    point before it to the one after it, through its fold (``continuation.bridge``: the delay oscillator at 0.3
    N, whose fold near 0.1063 Hz moves past the fold point and a point 3e-6 of it away, too close to each other
    for the normal's guard); those points have no coarser twin (index -1). FrequencyError for any other point
    not found, or a bridge that does not get there."""
    from .continuation import across, bridge

    solved = []
    for index, (omega, s, fold) in enumerate(points):
        state = finer._newton(omega, shooting.padded(s, finer))
        if state is None:
            found = across(shooting, finer, lambda v: shooting.padded(v, finer), s, omega, low, high)
            # moved by less than half the way to either neighbour (else it can pass it: near a corner the normal
            # meets the finer curve on its far side, out of order)
            reach = min([math.inf] + [0.5 * _gap(points[other], points[index]) for other in (index - 1, index + 1)
                                      if 0 <= other < len(points)])
            if found is not None and _gap((found[1], found[0][:s.size]), (omega, s)) <= reach:
                omega, state = found[1], found[0]
        solved.append(None if state is None else (omega, state, fold))
    out, kept = [], []
    index = 0
    while index < len(points):
        if solved[index] is not None:
            out.append(solved[index])
            kept.append(index)
            index += 1
            continue
        end = index
        while end < len(points) and solved[end] is None:
            end += 1
        run = points[index:end]
        beside = points[max(index - 1, 0):end + 1]
        inside = 0 < index and end < len(points) and any(fold for _, _, fold in beside)
        close = inside and all(_close(point, points[index - 1], spacing) and _close(point, points[end], spacing)
                               for point in run)
        if inside and not close:
            # the finer curve from the point before the run to the one after it, through its fold
            (omega_0, q_0, _), (omega_1, q_1, _) = out[-1], solved[end]
            scale = max(float(np.linalg.norm(q_0)), float(np.linalg.norm(q_1)), 1e-300)
            heading = np.concatenate((shooting.padded(run[0][1] - points[index - 1][1], finer) / scale,
                                      [(run[0][0] - points[index - 1][0]) / (high - low)]))
            between = bridge(finer, (omega_0, q_0), (omega_1, q_1), heading, low, high)
            if between is not None:
                out.extend(between)
                kept.extend([-1] * len(between))
                index = end
                continue
        if not close:
            raise FrequencyError(f"{finer.system.source}: at f = {float(points[index][0]) / (2 * math.pi)!r} Hz the "
                                 f"periodic state with {finer.delay_harmonics} harmonics of the delay's force and "
                                 f"{finer.M} samples per period was not found from the coarser one's: see --method "
                                 "time")
        if any(fold for _, _, fold in run):
            out[-1] = (out[-1][0], out[-1][1], True)
        index = end
    return out, np.array(kept, dtype=int)


def _close(point, other, spacing: float) -> bool:
    """Whether two points of a curve (omega, s, fold) are within ``spacing`` of each other (relative)."""
    return _gap(point, other) <= spacing


def _gap(point, other) -> float:
    """The distance of ``point`` (omega, s, ...) from ``other``, relative: the larger of the frequency's and the
    state's (max norm, over the other's largest)."""
    return max(abs(point[0] - other[0]) / other[0],
               float(np.max(np.abs(point[1] - other[1]))) / max(float(np.max(np.abs(other[1]))), 1e-300))


def _curve(shooting, points, coefficients, where, stability, change) -> dict:
    """The fields of ``curve.Curve`` (which curve.py builds: it imports this module)."""
    from .floquet import is_stable

    system = shooting.system
    names = tuple(getattr(shooting, "names", system.nodes))
    omega = np.array([p[0] for p in points])
    X = coefficients[:, where, 1] - 1j * coefficients[:, where, 2]
    largest = np.full(len(points), np.nan)
    stable = None
    if stability:
        from ..stepping import _progress_bar

        stable = np.ones(len(points), dtype=bool)
        known = np.ones(len(points), dtype=bool)
        proven = shooting.monotone  # every periodic state stable, by the energy (floquet.monotone)
        bar = _progress_bar(None, total=len(points), label=f"{system.name}: stability")
        try:
            for index, (w, s, _) in enumerate(points):
                values = shooting.multipliers(s, w)
                if values is None:  # not computed (a delay: ElementShooting.multipliers): unknown, never a guess
                    known[index] = False
                else:
                    largest[index] = float(np.max(np.abs(values)))
                    stable[index] = is_stable(values)
                    if proven and not stable[index]:  # the finite differences contradict the proof
                        stable[index], largest[index] = True, math.nan
                bar.update(1)
        finally:
            bar.close()
        if not np.all(known):
            stable = np.ma.MaskedArray(stable, mask=~known)
    amplitudes = {system.nodes[i]: np.hypot(coefficients[:, i, 1], coefficients[:, i, 2]) for i in system.massive}
    phase = np.where(np.abs(X) > 0, np.angle(X), 0.0)
    return dict(frequency=omega / (2.0 * math.pi), amplitude=np.abs(X), phase=phase, stable=stable,
                fold=np.array([p[2] for p in points], dtype=bool), multiplier=largest, amplitudes=amplitudes,
                coefficients=coefficients, harmonics=shooting.H, change=change, node=names[where],
                force_amplitude=shooting.force_amplitude,
                load_node=getattr(shooting, "load_name", system.nodes[system.load_node]),
                base_amplitude=shooting.base_amplitude, method="shooting", node_names=names,
                orbit="Taylor series" if getattr(shooting, "smooth", False) else "exact motion")
