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
