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
compiles it away, so an absent effect costs nothing in the time loop. The
springs and the dashpot are the exception in the library (``compiled.py``): an
absent one is a zero coefficient, a multiply-add measured within 1 % of none,
so that their combinations share one compiled loop.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

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


@dataclass(frozen=True)
class Friction:
    """Dry friction of the mass on the ground (the parallel model, eq. 14 of 004; Stribeck's law, eq. 16).

    The ground moves at ``belt_velocity`` v_b (m/s; 0: fixed ground) and the
    friction force on the mass is -A(v - v_b), A a maximal monotone graph plus
    a smooth part:

        A(w) = alpha sigma(w) + Psi(w),   sigma the sign graph (sigma(0) = [-1, 1]),
        A(w) = sign(w) (alpha_kinetic + (alpha - alpha_kinetic) exp(-|w| / stribeck_velocity))   (w != 0),

    so that the mass sticks (v = v_b) while the other forces on it stay within
    [-alpha, alpha], and slides against a force that falls from ``alpha``
    (N, > 0, the static threshold alpha_S) at rest to ``alpha_kinetic`` (N,
    0 <= alpha_kinetic <= alpha) at speed, over ``stribeck_velocity`` (m/s,
    > 0; None for plain Coulomb friction, alpha_kinetic = alpha). Psi(w) =
    sign(w) (alpha_kinetic - alpha) (1 - exp(-|w| / stribeck_velocity)) is C^1
    with Psi(0) = 0 and slope -(alpha - alpha_kinetic) / stribeck_velocity at 0.
    """

    alpha: float
    alpha_kinetic: float
    stribeck_velocity: Optional[float] = None
    belt_velocity: float = 0.0

    @property
    def drop_slope(self) -> float:
        """(alpha - alpha_kinetic) / stribeck_velocity (N s/m): the steepest negative slope of the sliding force,
        a negative damping where the mass slides slowly (0 for plain Coulomb friction)."""
        if self.stribeck_velocity is None:
            return 0.0
        return (self.alpha - self.alpha_kinetic) / self.stribeck_velocity


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

    ``damping`` (N s/m, shape (n,), > 0; None: none) puts a dashpot c_i in
    series with each branch's spring and slider: the series model (eq. 15 of
    004), a rate-dependent hysteresis. Then

        u_i' + d psi_[-eta_i, eta_i](u_i) ∋ v - (k_i / c_i) u_i,

    the spring relaxes through the dashpot at the rate lambda_i = k_i / c_i,
    which dissipates (k_i u_i)^2 / c_i; c_i -> infinity is the Prandtl branch.
    ``shared_damping``: the scene gave one c for every branch (``count = n``).
    """

    stiffness: np.ndarray
    yield_displacement: np.ndarray
    u0: np.ndarray
    damping: Optional[np.ndarray] = None
    shared_damping: bool = False

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

    Branch s has stiffness density k(s) (N/m per unit of s) and elastic range
    eta(s) (m); it starts virgin, u(s) = 0, and its force is integral_0^1
    k(s) u(s) ds. The spectrum is cut into segments [s_j, s_j+1): eta(s) is
    linear on each (``eta`` holds its J + 1 values at the ends: continuous,
    non-decreasing; a flat segment is a Dirac of the spectrum, branches that
    all slip at once) and k(s) = ``coefficient``_j eta(s)^``power``_j. Built
    by one of:

    * :meth:`linear`: k(s) = k_total, eta(s) = eta_min + (eta_max - eta_min) s,
      the family of the paper's section 8 (Bastien, Schatzman & Lamarque 2002
      study its limit n -> infinity);
    * :meth:`piecewise`: piecewise-constant k(s), piecewise-linear eta(s): any
      spectrum, to any accuracy;
    * :meth:`iwan`: Segalman's four-parameter Iwan model of bolted joints.

    Simulated by the memory stack with integrals in place of sums
    (kernels/stack.py); the sampled elements of :meth:`sample` converge to it.
    ``description`` says in words what the scene asked for.
    """

    s: np.ndarray
    eta: np.ndarray
    coefficient: np.ndarray
    power: np.ndarray
    description: str

    continuum = True
    n = None

    def __post_init__(self):
        from .kernels import stack

        stack.segments(self.s, self.eta, self.coefficient, self.power)  # ValueError names the broken rule
        for array in (self.s, self.eta, self.coefficient, self.power):
            array.setflags(write=False)

    @classmethod
    def linear(cls, k_total: float, eta_min: float, eta_max: float) -> "ContinuousBranches":
        """The paper's continuum: k(s) = k_total (N/m), eta(s) = eta_min + (eta_max - eta_min) s (m)."""
        return cls(np.array([0.0, 1.0]), np.array([float(eta_min), float(eta_max)]), np.array([float(k_total)]),
                   np.zeros(1), f"stiffness density {k_total:.6g} N/m and elastic range eta(s) = {eta_min:.6g} + "
                   f"{eta_max - eta_min:.6g} s m")

    @classmethod
    def piecewise(cls, s, k, eta) -> "ContinuousBranches":
        """k(s) = k_j (N/m per unit of s) on [s_j, s_j+1), eta(s) linear between its values ``eta`` at the
        ends ``s`` (0 = s_0 < ... < s_J = 1); eta_j = eta_j+1 makes segment j a Dirac of stiffness
        k_j (s_j+1 - s_j) at elastic range eta_j."""
        k = np.asarray(k, dtype=float)
        return cls(np.asarray(s, dtype=float), np.asarray(eta, dtype=float), k, np.zeros_like(k),
                   f"piecewise-constant stiffness density over {len(k)} segments, elastic ranges "
                   f"{float(eta[0]):.6g} to {float(eta[-1]):.6g} m")

    @classmethod
    def iwan(cls, F_S: float, K_T: float, chi: float, beta: float) -> "ContinuousBranches":
        """Segalman's four-parameter Iwan model (J. Appl. Mech. 72, 2005).

        Sliders of strength phi (m) with the density rho(phi) = R phi^chi on
        (0, phi_max) plus a Dirac S delta(phi - phi_max) (N/m per m of phi):
        K_T = integral rho (N/m) is the stiffness while everything sticks,
        F_S = integral phi rho (N) the force at macro-slip, -1 < chi the
        power (Segalman: -1 < chi < 0), beta = S / (R phi_max^(chi+1) / (chi + 1))
        >= 0 the weight of the Dirac against the power law. Then

            phi_max = F_S (1 + beta) / (K_T (beta + (chi + 1) / (chi + 2)))
            R = F_S (chi + 1) / (phi_max^(chi + 2) (beta + (chi + 1) / (chi + 2)))
            S = F_S beta / (phi_max (beta + (chi + 1) / (chi + 2)))

        and, in our terms, eta = phi and k = rho: segment 0 is the power law
        on s in [0, 1 / (1 + beta)) (eta = phi_max s (1 + beta)), segment 1
        the Dirac (its stiffness fraction beta / (1 + beta)).
        """
        params = iwan_parameters(F_S, K_T, chi, beta)
        phi_max, r, dirac = params["phi_max"], params["R"], params["S"]
        split = 1.0 / (1.0 + beta)
        text = f"Segalman's four-parameter Iwan model F_S = {F_S:.6g} N, K_T = {K_T:.6g} N/m, chi = {chi:.6g}, " \
               f"beta = {beta:.6g} (phi_max = {phi_max:.6g} m)"
        if beta == 0.0:
            return cls(np.array([0.0, 1.0]), np.array([0.0, phi_max]), np.array([r * phi_max]), np.array([chi]), text)
        # d eta / ds = phi_max / split on the power law: k(s) = rho(eta) d eta / ds
        return cls(np.array([0.0, split, 1.0]), np.array([0.0, phi_max, phi_max]),
                   np.array([r * phi_max / split, dirac / (1.0 - split)]), np.array([chi, 0.0]), text)

    @property
    def params(self):
        """The memory stack's parameters of this spectrum (kernels/stack.py :func:`segments`)."""
        from .kernels import stack

        return stack.segments(self.s, self.eta, self.coefficient, self.power)

    @property
    def stiffness_sum(self) -> float:
        """integral k(s) ds (N/m): the stiffness while every branch sticks."""
        from .kernels import stack

        return stack.spectrum_totals(self.params)[0]

    @property
    def strength(self) -> float:
        """integral k(s) eta(s) ds (N): the largest force the branches can carry."""
        from .kernels import stack

        return stack.spectrum_totals(self.params)[1]

    @property
    def is_linear(self) -> bool:
        """Whether this is the paper's family (one segment of constant density)."""
        return self.coefficient.shape[0] == 1 and self.power[0] == 0.0

    def sample(self, n: int, rule: str = "mean") -> Branches:
        """Virgin branches sampling this spectrum, one per cell: the n equal parts of [0, 1] in s, cut
        further at the segment ends (so no cell mixes two segments), except that the cells of a flat
        segment (a Dirac) make one branch and empty cells none: at most n + J - 1 branches.

        k_i = the integral of k(s) over the cell; eta_i = eta at the cell's right end ("right", the paper's
        eq. 7.19: the force converges like 1/n), at its midpoint ("midpoint"), or the cell's stiffness-
        weighted mean of eta ("mean": each segment's stiffness and strength are those of the continuum, and
        the force converges like 1/n^2 where the density is bounded; like n^-(chi+2) for a power law
        eta^chi, chi < 0, at eta = 0). For the paper's family, "right" and "midpoint" are
        :func:`sample_spectrum` and "mean" is "midpoint".
        """
        if rule not in SAMPLING_RULES + ("mean",):
            raise ValueError(f"sampling rule must be one of right, midpoint, mean, got {rule!r}")
        if self.is_linear:
            return sample_spectrum(n, float(self.coefficient[0]), (float(self.eta[0]), float(self.eta[1])),
                                   "midpoint" if rule == "mean" else rule)
        from .kernels import stack

        params = self.params
        flat = self.eta[1:] == self.eta[:-1]
        cuts = [np.arange(n + 1) / n, self.s]
        for j in np.flatnonzero(flat):  # a Dirac is one cell
            grid = cuts[0]
            cuts[0] = grid[(grid <= self.s[j]) | (grid >= self.s[j + 1])]
        ends = np.unique(np.concatenate(cuts))
        stiffness, moment, _ = stack.spectrum_integrals(params, ends)
        lo, hi = ends[:-1], ends[1:]
        if rule == "mean":
            safe = np.where(stiffness > 0, stiffness, 1.0)
            eta = np.clip(moment / safe, stack.eta_of(params, lo), stack.eta_of(params, hi))  # clip: rounding
        else:
            eta = stack.eta_of(params, hi if rule == "right" else 0.5 * (lo + hi))
        keep = stiffness > 0  # a cell where the density vanishes holds no branch
        return Branches(stiffness[keep], eta[keep], np.zeros(int(np.sum(keep))))


def iwan_parameters(F_S: float, K_T: float, chi: float, beta: float) -> dict:
    """phi_max (m), R, S of Segalman's four-parameter Iwan model (see :meth:`ContinuousBranches.iwan`);
    ValueError if F_S, K_T <= 0, chi <= -1 or beta < 0."""
    if not (F_S > 0 and K_T > 0 and chi > -1 and beta >= 0):
        raise ValueError("the Iwan model needs F_S > 0, K_T > 0, chi > -1 and beta >= 0")
    ratio = (chi + 1.0) / (chi + 2.0)
    phi_max = F_S * (1.0 + beta) / (K_T * (beta + ratio))
    return {"phi_max": phi_max, "R": F_S * (chi + 1.0) / (phi_max ** (chi + 2.0) * (beta + ratio)),
            "S": F_S * beta / (phi_max * (beta + ratio))}


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
