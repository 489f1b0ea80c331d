"""The physical effects an element can have: plain data, one class per effect.

The element is a point of mass m at displacement x (m) with velocity v (m/s),
loaded by a force F(t) (N) and held by effects in parallel:

    x' = v
    m v' = F - k0 x - k3 x^3 - c v - sum_i k_i u_i
    u_i' + d psi_[-eta_i, eta_i](u_i) ∋ v            (i = 1..n)

and the *reaction* is the force the effects exert on the point,

    reaction = k0 x + k3 x^3 + c v + sum_i k_i u_i   (= F - m v').

A scene holds one object per effect that is present and ``None`` for an effect
that is absent; the kernels receive ``None`` for an absent effect and numba
compiles it away, so an absent effect costs nothing in the time loop.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Mass:
    """Inertia m v' of the point: ``m`` (kg) > 0, initial ``x0`` (m), ``v0`` (m/s)."""

    m: float
    x0: float = 0.0
    v0: float = 0.0


@dataclass(frozen=True)
class Spring:
    """Linear spring in parallel (hardening): force ``k0 * x``, ``k0`` in N/m, >= 0."""

    k0: float


@dataclass(frozen=True)
class CubicSpring:
    """Cubic spring in parallel: force ``k3 * x**3``, ``k3`` in N/m^3, >= 0."""

    k3: float


@dataclass(frozen=True)
class Damper:
    """Viscous dashpot in parallel: force ``c * v``, ``c`` in N s/m, >= 0."""

    c: float


@dataclass(frozen=True, eq=False)
class Branches:
    """n Prandtl branches: a spring k_i in series with a Coulomb slider.

    Branch i carries the elastic elongation u_i (m) of its spring, confined to
    the elastic range [-eta_i, eta_i]; its slider slips when the spring force
    k_i |u_i| reaches the threshold alpha_i = k_i eta_i (N). The elongation
    follows the play (stop) operator of the displacement:

        u_i' + d psi_[-eta_i, eta_i](u_i) ∋ v,   force k_i u_i.

    Arrays of shape (n,): ``stiffness`` k_i > 0 (N/m),
    ``yield_displacement`` eta_i >= 0 (m), ``u0`` initial elongations (m).
    """

    stiffness: np.ndarray
    yield_displacement: np.ndarray
    u0: np.ndarray

    continuum = False

    @property
    def stiffness_sum(self) -> float:
        """sum_i k_i (N/m): the stiffness of the branches while they all stick."""
        return float(np.sum(self.stiffness))

    @property
    def n(self) -> int:
        return int(self.stiffness.shape[0])

    @property
    def threshold(self) -> np.ndarray:
        """Slip thresholds alpha_i = k_i eta_i (N)."""
        return self.stiffness * self.yield_displacement

    @property
    def strength(self) -> float:
        """sum_i alpha_i (N): the largest force the branches can carry."""
        return float(np.sum(self.threshold))


@dataclass(frozen=True)
class ContinuousBranches:
    """The continuous Prandtl element: infinitely many branches s in [0, 1].

    Branch s has stiffness density k(s) = ``k_total`` (N/m per unit of s) and
    elastic range eta(s) = ``eta_min`` + (``eta_max`` - ``eta_min``) s (m), the
    family of the paper's section 8 (Bastien, Schatzman & Lamarque 2002 study
    its limit n -> infinity); it starts virgin, u(s) = 0. Its force is
    integral_0^1 k(s) u(s) ds. Simulated by the memory stack with integrals in
    place of sums (kernels/stack.py); the sampled elements of
    :func:`sample_spectrum` converge to it.
    """

    k_total: float
    eta_min: float
    eta_max: float

    continuum = True
    n = None

    @property
    def stiffness_sum(self) -> float:
        """integral k(s) ds = k_total (N/m): the stiffness while every branch sticks."""
        return float(self.k_total)

    @property
    def strength(self) -> float:
        """integral k(s) eta(s) ds (N): the largest force the branches can carry."""
        return float(self.k_total * 0.5 * (self.eta_min + self.eta_max))

    def sample(self, n: int, rule: str = "right") -> Branches:
        """n virgin branches sampling this spectrum (see :func:`sample_spectrum`)."""
        return sample_spectrum(n, self.k_total, (self.eta_min, self.eta_max), rule)


# How the sampled spectrum places its n branches in [0, 1]: the paper's right
# end points (eq. 7.19; the scene default) or the cell midpoints.
SAMPLING_RULES = ("right", "midpoint")


def sample_spectrum(n: int, k_total: float, eta_range, rule: str = "right", u0=None) -> Branches:
    """n branches of the spectrum k(s) = k_total, eta(s) = a + (b - a) s, each with weight 1/n.

    ``rule`` "right": s_i = i / n (eq. 7.19 of the paper; the force converges
    to the continuum's like 1/n); "midpoint": s_i = (i - 1/2) / n (like 1/n^2).
    """
    if rule not in SAMPLING_RULES:
        raise ValueError(f"sampling rule must be one of {', '.join(SAMPLING_RULES)}, got {rule!r}")
    a, b = float(eta_range[0]), float(eta_range[1])
    s = (np.arange(1, n + 1) - (0.5 if rule == "midpoint" else 0.0)) / n
    stiffness = np.full(n, float(k_total) / n)
    eta = a + (b - a) * s
    u0 = np.zeros(n) if u0 is None else np.asarray(u0, dtype=float)
    return Branches(stiffness, eta, u0)
