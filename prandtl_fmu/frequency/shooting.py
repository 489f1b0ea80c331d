"""The periodic state of an element with Coulomb friction on its mass (``[friction]``), by shooting on the
scene's own stepper: the whole curve, its folds and the stability of every point.

Why not harmonic balance: the friction's force while the mass sticks is set by the balance of the other forces,
not by the motion, so alternating frequency-time cannot sample it (a slider behind a spring, a Prandtl branch,
is sampled exactly). The dynamic Lagrangian of the contact was tried and measured (docs/frequency.md): its root
depends on its penalty at finite H and it stays 0.1 to 0.6 % off the time sweep at H = 63. The orbit itself has
no such limit: the steppers that ``--method time`` runs integrate it exactly (``exact``: closed form between
events, stick and slip located to rounding) or to a stated order, so the periodic state is found as the fixed
point of the stepper's map over one period, and its harmonics are those of the orbit (never truncated).

**Half a period, by symmetry.** Every force of such a scene is odd in (x, v, u) (springs, the cubic spring, the
dashpot, the branches, Coulomb or Stribeck friction on a fixed ground) and the force F0 cos(omega t) turns sign
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
point. A branch stuck all along gives the neutral multiplier 1, as ``floquet.py`` says.

**Accuracy.** The stepper: ``exact`` where it applies (plain Coulomb friction, no cubic spring, at most
EXACT_UP_TO branches: ``response.choose_stepper``), where M steps only set the quadrature of the harmonics
(the trapezoid rule over the samples of x, error like 1 / M^2: x is C^1); else ``verlet`` or ``implicit``,
whose orbit depends on M. M is doubled from FIRST_STEPS (the stepper's first M of the time sweep) until the
first harmonic at the curve's ends and peak, solved again at 2 M, changes by at most half the tolerance
(relative: the error at M is 4/3 of that change where it falls like 1 / M^2, twice it like 1 / M);
past MAX_STEPS steps per period, refused with the change reached. The harmonics reported are those of the
orbit's samples (the curve's ``harmonics``: how many are kept in ``coefficients``, 7 unless given; they do not
limit the accuracy).

Base excitation (Y0 cos(omega t) of the ground): in relative coordinates z = x - y under m Y0 omega^2
cos(omega t), the friction on the relative velocity (the mass slides on the moving support); x = z + y
reported, as the harmonic balance does.

What is refused, one line each: a moving belt (not odd: the orbit has no half-period symmetry), effects with
memory beside the friction, a node other than the mass. Nonlinear modes (EPMC) of such a scene are refused by
``modes.py``: see docs/frequency.md.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import DEFAULT_TOLERANCE, FrequencyError
from .harmonic_balance import ELEMENT_NODE, solve_linear

PERTURBATION = 1e-7
NEWTON_ITERATIONS = 40
STEP_TOLERANCE = 1e-11
# a start from rest: Newton, then periods of the motion from where it stands, at most START_ATTEMPTS times
# (8, 16, 32, ... periods: 2040 in all)
START_ATTEMPTS = 8
DEFAULT_HARMONICS = 7
MAX_STEPS = 2**16


def takes(scene) -> bool:
    """Whether the forced response of ``scene`` is solved here: an element scene with ``[friction]``."""
    from ..network.model import NetworkScene

    return not isinstance(scene, NetworkScene) and scene.friction is not None


@dataclass(frozen=True)
class ShootingSystem:
    """The one node of an element scene, as ``harmonic_balance.PeriodicSystem`` names it to the curve and the
    continuation."""

    name: str
    source: str
    mass: float
    nodes: tuple = (ELEMENT_NODE,)
    load_node: int = 0
    n: int = 1

    @property
    def massive(self) -> list:
        return [0]

    def node_index(self, name: Optional[str], default: Optional[int] = None) -> int:
        if name is not None and name != ELEMENT_NODE:
            raise FrequencyError(f"--node: {name!r} is not a node of {self.source} ({ELEMENT_NODE})")
        return 0


def prepared(scene):
    """``scene`` as shooting runs it (a spectrum of branches as the harmonic balance's quadrature of branches);
    FrequencyError for what it does not take."""
    from ..effects import Branches
    from .harmonic_balance import spectrum_branches

    if scene.mass is None:
        raise FrequencyError(f"{scene.source}: the frequency response needs [mass] (the element alone has no "
                             "resonance: describe it with --amplitudes)")
    if scene.friction.belt_velocity != 0.0:
        raise FrequencyError(f"{scene.source}: [friction] on a moving belt (belt_velocity != 0) has no periodic "
                             "state symmetric over half a period, which the frequency response of friction on the "
                             "mass solves for: use --method time")
    memory = [name for name in ("delay", "history", "dahl") if getattr(scene, name) is not None]
    if memory:
        raise FrequencyError(f"{scene.source}: [friction] with [{memory[0]}] is not taken by the frequency response "
                             "of friction on the mass (shooting over half a period has no state for the memory): "
                             "use --method time")
    if scene.branches is not None and scene.branches.continuum:
        k, eta = spectrum_branches(scene.branches, DEFAULT_TOLERANCE, scene.source)
        scene = dataclasses.replace(scene, branches=Branches(k, eta, np.zeros(k.shape[0])))
    return scene


class Shooting:
    """The periodic state of an element scene with friction at each omega (see the module): the unknowns s
    (x, v / omega_ref, u) at t = 0, the interface of ``HarmonicBalance`` that ``continuation.py`` uses
    (:meth:`evaluate`, :meth:`solve_at`, :meth:`_newton`, :meth:`force_scale`, :meth:`amplitude_at`)."""

    def __init__(self, scene, force_amplitude: Optional[float], base_amplitude: Optional[float], steps: int,
                 harmonics: int, reference: float, stepper: str):
        from ..compiled import compile_loop, compile_model
        from ..loads import HarmonicLoad
        from ..scene_tables import Solver

        if steps % 2 or steps < 2 * harmonics + 2:
            raise ValueError(f"steps: an even number >= 2 H + 2, got {steps!r}")
        self.scene = dataclasses.replace(scene, load=HarmonicLoad(1.0, reference),
                                         solver=Solver(stepper, 1.0 / steps, 1.0, 1.0 / steps))
        self.system = ShootingSystem(scene.name, scene.source, float(scene.mass.m))
        self.force_amplitude = None if force_amplitude is None else float(force_amplitude)
        self.base_amplitude = None if base_amplitude is None else float(base_amplitude)
        self.M = int(steps)
        self.H = int(harmonics)
        self.L = 2 * self.H + 1
        self.reference = float(reference)
        self.stepper = stepper
        self.model = compile_model(self.scene, "play")
        self.loop = compile_loop(self.scene, stepper)
        self.branches = 0 if scene.branches is None else int(scene.branches.n)
        self.dimension = 2 + self.branches
        self._out = np.empty((self.M // 2, 3))
        self._loads = {}
        # the stiffness the mass feels when everything sticks, for the size of the motion
        self.stiffness = (0.0 if scene.spring is None else float(scene.spring.k0)) + (
            0.0 if scene.branches is None else float(np.sum(scene.branches.stiffness)))

    # ------------------------------------------------------------- the stepper's map

    def amplitude_of_force(self, omega: float) -> float:
        """F0, or m Y0 omega^2 under base excitation (the relative coordinates' force)."""
        if self.force_amplitude is not None:
            return self.force_amplitude
        return self.system.mass * self.base_amplitude * omega * omega

    def _load(self, omega: float):
        from ..loads import HarmonicLoad

        if omega not in self._loads:
            if len(self._loads) > 64:
                self._loads.clear()
            self._loads[omega] = HarmonicLoad(self.amplitude_of_force(omega), omega).compile()
        return self._loads[omega]

    def run(self, s: np.ndarray, omega: float, half_periods: int = 1) -> tuple:
        """``(state at the end, x at the step ends (M / 2 half_periods,))``: ``half_periods`` half periods of the
        stepper from the unknowns ``s`` at t = 0 (the state at the end in the same unknowns, not turned)."""
        from ..stepping import ElementError, _failure, integrate

        h = 2.0 * math.pi / omega / self.M
        x, v = float(s[0]), float(s[1]) * self.reference
        u = None if self.branches == 0 else np.array(s[2:], dtype=float)
        out = self._out if half_periods == 1 else np.empty((self.M // 2 * half_periods, 3))
        load = self._load(omega)
        try:
            x, v, taken = integrate(self.loop, self.model, load, x, v, u, 0.0, 0, h, 1, out, None, None, None)
        except ElementError as exc:
            raise FrequencyError(f"{self.system.source}: at f = {omega / (2 * math.pi)!r} Hz: {exc}") from None
        if taken < out.shape[0]:
            raise FrequencyError(f"{self.system.source}: at f = {omega / (2 * math.pi)!r} Hz: "
                                 f"{_failure(self.scene, self.stepper, load, taken * h, h, None)}")
        end = np.empty(self.dimension)
        end[0], end[1] = x, v / self.reference
        if u is not None:
            end[2:] = u
        if not (np.all(np.isfinite(end)) and np.all(np.isfinite(out[:, 0]))):
            raise FrequencyError(f"{self.system.source}: at f = {omega / (2 * math.pi)!r} Hz the motion is not "
                                 "finite (an overflow)")
        return end, out[:, 0].copy()

    def residual(self, s: np.ndarray, omega: float) -> np.ndarray:
        return -self.run(s, omega)[0] - s

    def size(self, s: np.ndarray, omega: float) -> float:
        """The orbit's size (m): its state's, or the force's static deflection, whichever is larger."""
        stiff = max(self.stiffness, self.system.mass * omega * omega)
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
        """``(R, dR/ds, dR/d omega, None)`` at ``s`` and ``omega``."""
        s = np.asarray(s, dtype=float)
        residual = self.residual(s, omega)
        step = PERTURBATION * omega
        by_omega = (self.residual(s, omega + step) - residual) / step
        return residual, self.jacobian(s, omega, residual), by_omega, None

    def force_scale(self, omega: float) -> float:
        """The residual's scale (m): the force's static deflection, or its motion at omega."""
        return self.size(np.zeros(1), omega)

    # ------------------------------------------------------------- solving at one frequency

    def _newton(self, omega: float, guess: np.ndarray) -> Optional[np.ndarray]:
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
        raise FrequencyError(f"{self.system.source}: the periodic state at f = {omega / (2 * math.pi)!r} Hz was not "
                             f"found: Newton's method did not converge from rest nor after {periods} periods of the "
                             "motion (a subharmonic, chaotic or unsymmetric motion?): see --method time")

    # ------------------------------------------------------------- what a point says

    def samples(self, s: np.ndarray, omega: float) -> np.ndarray:
        """x over one period at t_j = j T / M, j = 0 ... M - 1 (relative under base excitation): the first half
        run, the second its negative (the symmetry)."""
        _, xs = self.run(s, omega)
        half = np.concatenate(([s[0]], xs[:-1]))
        return np.concatenate((half, -half))

    def coefficients(self, s: np.ndarray, omega: float) -> np.ndarray:
        """The mean and H harmonics of x (absolute: y added under base excitation), (2 H + 1,), in the order
        of the harmonic balance (a_0, a_1, b_1, ...)."""
        spectrum = np.fft.rfft(self.samples(s, omega)) / self.M
        out = np.empty(self.L)
        out[0] = spectrum[0].real
        out[1::2] = 2.0 * spectrum[1:self.H + 1].real
        out[2::2] = -2.0 * spectrum[1:self.H + 1].imag
        if self.base_amplitude is not None:
            out[1] += self.base_amplitude
        return out

    def first_harmonic(self, s: np.ndarray, omega: float) -> complex:
        c = self.coefficients(s, omega)
        return complex(c[1], -c[2])

    def amplitude_at(self, s: np.ndarray, omega: float) -> float:
        return abs(self.first_harmonic(s, omega))

    def multipliers(self, s: np.ndarray, omega: float) -> np.ndarray:
        """The Floquet multipliers of the whole period: the squares of the eigenvalues of dG/ds."""
        turn = self.jacobian(np.asarray(s, dtype=float), omega) + np.eye(self.dimension)
        return np.linalg.eigvals(turn) ** 2


# ----------------------------------------------------------------- the curve

def shooting_response(scene, force_amplitude, base_amplitude, frequencies, *, harmonics: Optional[int] = None,
                      node: Optional[str] = None, load_node: Optional[str] = None,
                      tolerance: float = DEFAULT_TOLERANCE, stability: bool = True, samples: Optional[int] = None):
    """The forced response of an element scene with friction (see the module) as a ``curve.Curve``; the
    arguments are ``curve.harmonic_response``'s, checked there."""
    from .continuation import continue_curve
    from .response import FIRST_STEPS, FIRST_STEPS_DEFAULT, _forced, choose_stepper
    from ..stability import stability_problem

    scene = prepared(scene)
    system = ShootingSystem(scene.name, scene.source, float(scene.mass.m))
    where = system.node_index(node)
    if load_node is not None and load_node != ELEMENT_NODE:
        raise FrequencyError(f"--load-node: {load_node!r} is not a node of {scene.source} ({ELEMENT_NODE})")
    H = DEFAULT_HARMONICS if harmonics is None else int(harmonics)
    low, high = 2.0 * math.pi * float(frequencies.min()), 2.0 * math.pi * float(frequencies.max())
    count = int(np.unique(frequencies).size)
    stepper = choose_stepper(_forced(scene, 1.0, float(frequencies[0])))
    steps = FIRST_STEPS.get(stepper, FIRST_STEPS_DEFAULT)
    if samples is not None:
        steps = max(steps, int(samples) + int(samples) % 2)
    steps = max(steps, 2 * (2 * H + 2))
    while stability_problem(_forced(scene, 1.0, high / (2 * math.pi)), stepper, 2 * math.pi / high / steps) \
            is not None and steps < MAX_STEPS:
        steps *= 2  # an explicit stepper's limit (omega h < 2) at the highest frequency
    reference = math.sqrt(low * high)
    change = math.inf
    while True:
        shooting = Shooting(scene, force_amplitude, base_amplitude, steps, H, reference, stepper)
        points = continue_curve(shooting, low, high, count)
        first = np.array([shooting.first_harmonic(s, w) for w, s, _ in points])
        if steps * 2 > MAX_STEPS:
            raise FrequencyError(f"{scene.source}: the first harmonic still changed by {change:.3g} relative at "
                                 f"{steps} steps per period of {stepper!r} (tolerance {tolerance:g}): give a "
                                 "larger --tolerance")
        finer = Shooting(scene, force_amplitude, base_amplitude, 2 * steps, H, reference, stepper)
        change = 0.0
        for index in sorted({0, int(np.argmax(np.abs(first))), len(points) - 1}):
            w, s, _ = points[index]
            solved = finer._newton(w, s)
            if solved is None:
                solved = finer.solve_at(w, s)
            X = finer.first_harmonic(solved, w)
            change = max(change, abs(X - first[index]) / max(abs(X), 1e-300))
        if change <= 0.5 * tolerance:  # the error at M: 4/3 of the change for an error like 1 / M^2, 2 for 1 / M
            break
        steps *= 2
    return _curve(shooting, points, where, stability, change)


def _curve(shooting, points, where, stability, change):
    from .curve import Curve
    from .floquet import is_stable

    omega = np.array([p[0] for p in points])
    coefficients = np.array([shooting.coefficients(s, w) for w, s, _ in points])[:, None, :]
    X = coefficients[:, where, 1] - 1j * coefficients[:, where, 2]
    largest = np.full(len(points), np.nan)
    stable = None
    if stability:
        stable = np.ones(len(points), dtype=bool)
        for index, (w, s, _) in enumerate(points):
            values = shooting.multipliers(s, w)
            largest[index] = float(np.max(np.abs(values)))
            stable[index] = is_stable(values)
    amplitudes = {ELEMENT_NODE: np.hypot(coefficients[:, 0, 1], coefficients[:, 0, 2])}
    phase = np.where(np.abs(X) > 0, np.angle(X), 0.0)
    return Curve(omega / (2.0 * math.pi), np.abs(X), phase, stable, np.array([p[2] for p in points], dtype=bool),
                 largest, amplitudes, coefficients, shooting.H, change, ELEMENT_NODE, shooting.force_amplitude,
                 ELEMENT_NODE, shooting.base_amplitude)
