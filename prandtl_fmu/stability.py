"""When an explicit stepper's step is too long for a scene.

``projected`` is explicit Euler on the smooth part. Linearised with every
branch sticking (the stiffest state: K = k0 + 3 k3 x^2 + sum_i k_i), the
element is m x'' + c x' + K x = F, whose modes mu (m mu^2 + c mu + K = 0) are
multiplied by 1 + h mu per step. Explicit Euler never damps an undamped
oscillator: it multiplies its amplitude by sqrt(1 + (omega h)^2) per step,
about exp(pi omega h) per period. We call the step unstable when the
amplitude of the stiffest mode at least doubles within one period (undamped:
omega h > ln(2)/pi ~ 0.22), or grows at all for a non-oscillating mode (the
massless element with a dashpot: h K / c > 2): beyond that the output is
garbage. ``symplectic`` and ``verlet`` (leapfrog type) are stable for
omega h < 2. ``implicit`` is unconditionally stable, and ``exact`` has no
step to speak of.
"""
from __future__ import annotations

import cmath
import math
from typing import Optional

GROWTH_LIMIT = 2.0  # amplitude factor per period of the stiffest mode


class StabilityWarning(UserWarning):
    """The step is beyond the stability limit of the stepper for this scene."""


def stiffest(scene, x: Optional[float] = None) -> float:
    """K = k0 + 3 k3 x^2 + sum_i k_i (N/m): the tangent stiffness with every branch sticking."""
    if x is None:
        x = scene.mass.x0 if scene.mass is not None else 0.0
    stiffness = scene.spring.k0 if scene.spring is not None else 0.0
    if scene.cubic is not None:
        stiffness += 3.0 * scene.cubic.k3 * x * x
    if scene.branches is not None:
        stiffness += scene.branches.stiffness_sum
    return stiffness


def growth_per_period(m: Optional[float], c: float, stiffness: float, h: float) -> float:
    """Amplitude factor of explicit Euler's stiffest mode per period (per step if it does not oscillate)."""
    if m is None:  # c x' = -K x: one real mode
        return abs(1.0 - h * stiffness / c) if c > 0 else 1.0
    root = cmath.sqrt(c * c - 4.0 * m * stiffness)
    modes = ((-c + root) / (2.0 * m), (-c - root) / (2.0 * m))  # m mu^2 + c mu + K = 0
    factor = max(abs(1.0 + h * mu) for mu in modes)
    frequency = max(abs(mu.imag) for mu in modes)
    if frequency == 0.0:
        return factor
    # per period, but at least per step (a period shorter than a step is no comfort)
    return max(factor, factor ** (2.0 * math.pi / (frequency * h)))


def step_limit(m: Optional[float], c: float, stiffness: float) -> float:
    """The largest h whose growth per period stays within GROWTH_LIMIT (per step: 1 without oscillation)."""
    limit = GROWTH_LIMIT
    if m is None or (c * c >= 4 * m * stiffness):
        limit = 1.0
    low, high = 0.0, 1.0
    while growth_per_period(m, c, stiffness, high) <= limit * (1 + 1e-12):
        high *= 2.0
        if high > 1e300:
            return math.inf
    for _ in range(200):
        middle = 0.5 * (low + high)
        if growth_per_period(m, c, stiffness, middle) <= limit * (1 + 1e-12):
            low = middle
        else:
            high = middle
    return low


def stability_problem(scene, stepper: str, h: float, x: Optional[float] = None) -> Optional[str]:
    """A one-line explanation when ``stepper`` with step ``h`` is unstable for ``scene``, else None."""
    if stepper in ("symplectic", "verlet"):
        return _leapfrog_problem(scene, stepper, h, x)
    if stepper != "projected":
        return None
    m = scene.mass.m if scene.mass is not None else None
    c = scene.damper.c if scene.damper is not None else 0.0
    if m is None and c == 0.0:
        return None  # no explicit scheme applies (refused elsewhere)
    stiffness = stiffest(scene, x)
    if stiffness == 0.0:
        return None
    allowed = 1.0 if (m is None or c * c >= 4 * m * stiffness) else GROWTH_LIMIT
    if growth_per_period(m, c, stiffness, h) <= allowed * (1 + 1e-12):
        return None
    limit = step_limit(m, c, stiffness)
    if m is None:
        return (f"stepper 'projected' is unstable here: h K / c = {h * stiffness / c:.3g} > 2 "
                f"(K = {stiffness:.6g} N/m with every branch sticking); use 'implicit' or h <= {limit:.3g} s")
    omega = math.sqrt(stiffness / m)
    return (f"stepper 'projected' is beyond its stability limit: omega h = {omega * h:.3g} "
            f"(omega = sqrt(K/m) = {omega:.6g} rad/s with every branch sticking) makes the amplitude grow "
            f"x{min(growth_per_period(m, c, stiffness, h), 1e300):.3g} per period; "
            f"use 'implicit' or h <= {limit:.3g} s")


def _leapfrog_problem(scene, stepper, h, x):
    """Symplectic Euler and velocity Verlet are stable for omega h < 2 (every branch sticking)."""
    if scene.mass is None:
        return None
    omega = math.sqrt(stiffest(scene, x) / scene.mass.m)
    if omega * h < 2.0:
        return None
    return (f"stepper {stepper!r} is beyond its stability limit: omega h = {omega * h:.3g} >= 2 "
            f"(omega = sqrt(K/m) = {omega:.6g} rad/s with every branch sticking); "
            f"use 'implicit' or h < {2.0 / omega:.3g} s")
