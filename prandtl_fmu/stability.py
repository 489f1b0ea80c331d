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

Two more checks, for every stepper that takes steps:

* series dashpots in ``projected`` (explicit relaxation u <- u (1 - h k_i/c_i)):
  unstable for h k_i / c_i > 2;
* Stribeck friction (``[friction]`` with alpha_kinetic < alpha): the
  sliding force falls with the slip speed at up to (alpha -
  alpha_kinetic) / stribeck_velocity, a negative damping. When that exceeds
  m/h + c, the implicit step's equation is not monotone (several roots:
  ``implicit`` takes the one of least slip) and the explicit ones amplify
  slow slips by more than a factor 2 per step: the step is too long to
  resolve the drop, and the continuous problem itself is sensitive to its
  data there (Bastien & Schatzman, ZAMM 88, 2008).
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


def _modes(m: float, c: float, stiffness: float):
    """The modes mu of m mu^2 + c mu + K = 0, computed from the rates c/(2m) and K/m (no overflow of c^2 or
    m K for any finite coefficients; a rate that is not representable comes out as inf)."""
    sigma = c / (2.0 * m)
    omega_sq = stiffness / m
    if not (math.isfinite(sigma) and math.isfinite(omega_sq)):
        return (complex(-math.inf, 0.0),)
    scale = max(sigma, math.sqrt(omega_sq))
    if scale == 0.0:
        return (0j,)
    root = scale * cmath.sqrt((sigma / scale) ** 2 - omega_sq / scale / scale)
    return (-sigma + root, -sigma - root)


def log_growth_per_period(m: Optional[float], c: float, stiffness: float, h: float) -> float:
    """log of the amplitude factor of explicit Euler's stiffest mode per period (per step if it does not
    oscillate); +inf when it is not representable. Computed in logs: no overflow for any finite input."""
    if m is None:  # c x' = -K x: one real mode
        if not c > 0:
            return 0.0
        factor = abs(1.0 - h * (stiffness / c))
        return math.log(factor) if factor > 0 else -math.inf
    worst = -math.inf
    for mu in _modes(m, c, stiffness):
        if not (cmath.isfinite(mu)):
            return math.inf
        factor = abs(1.0 + h * mu)
        if not math.isfinite(factor):
            return math.inf
        log_factor = math.log(factor) if factor > 0 else -math.inf
        frequency = abs(mu.imag)
        if frequency > 0.0 and log_factor > 0.0:
            # per period, but at least per step (a period shorter than a step is no comfort)
            log_factor *= max(1.0, 2.0 * math.pi / (frequency * h))
        worst = max(worst, log_factor)
    return worst


def growth_per_period(m: Optional[float], c: float, stiffness: float, h: float) -> float:
    """Amplitude factor of explicit Euler's stiffest mode per period (per step if it does not oscillate);
    inf beyond what a float holds."""
    log_growth = log_growth_per_period(m, c, stiffness, h)
    return math.exp(log_growth) if log_growth < 709.0 else math.inf


def _allowed(m: Optional[float], c: float, stiffness: float) -> float:
    """The growth allowed: GROWTH_LIMIT per period for an oscillating mode, none (1) otherwise."""
    if m is None:
        return 1.0
    oscillates = any(mu.imag != 0.0 for mu in _modes(m, c, stiffness))
    return GROWTH_LIMIT if oscillates else 1.0


def step_limit(m: Optional[float], c: float, stiffness: float) -> float:
    """The largest h whose growth per period stays within the allowed growth (see :func:`_allowed`);
    found by bisection on log h over the whole range of floats."""
    log_limit = math.log(_allowed(m, c, stiffness)) + 1e-12
    low, high = -745.0, 709.0  # log h
    if log_growth_per_period(m, c, stiffness, math.exp(high)) <= log_limit:
        return math.inf
    if log_growth_per_period(m, c, stiffness, math.exp(low)) > log_limit:
        return 0.0
    for _ in range(200):
        middle = 0.5 * (low + high)
        if log_growth_per_period(m, c, stiffness, math.exp(middle)) <= log_limit:
            low = middle
        else:
            high = middle
    return math.exp(low)


def stability_problem(scene, stepper: str, h: float, x: Optional[float] = None) -> Optional[str]:
    """A one-line explanation when ``stepper`` with step ``h`` is unstable for ``scene``, else None."""
    return _smooth_problem(scene, stepper, h, x) or _friction_problem(scene, stepper, h) \
        or _series_problem(scene, stepper, h)


def _friction_problem(scene, stepper, h):
    """The Stribeck drop against m/h + c (see the module docstring)."""
    friction = scene.friction
    if friction is None or stepper == "exact" or friction.drop_slope == 0.0:
        return None
    inertia = scene.mass.m / h + (scene.damper.c if scene.damper is not None else 0.0)
    if friction.drop_slope <= inertia:
        return None
    limit = scene.mass.m / max(friction.drop_slope - (scene.damper.c if scene.damper is not None else 0.0), 1e-300)
    return (f"[friction]: the Stribeck drop (alpha - alpha_kinetic) / stribeck_velocity = {friction.drop_slope:.6g} "
            f"N.s/m exceeds m/h + c = {inertia:.6g} N.s/m: the step cannot resolve it (the implicit step may have "
            f"several roots; 'implicit' takes the least slip); use h < {limit:.3g} s")


def _series_problem(scene, stepper, h):
    """The explicit relaxation of series dashpots in 'projected'."""
    if stepper != "projected" or not scene.has_series_dashpots:
        return None
    branches = scene.branches
    rates = branches.stiffness / branches.damping
    fastest = float(rates.max())
    if h * fastest <= 2.0:
        return None
    return (f"stepper 'projected' relaxes the series dashpots explicitly and is unstable here: h k_i / c_i = "
            f"{h * fastest:.3g} > 2 (branch {int(rates.argmax()) + 1}); use 'implicit', 'verlet' or "
            f"h <= {2.0 / fastest:.3g} s")


def _smooth_problem(scene, stepper, h, x):
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
    if log_growth_per_period(m, c, stiffness, h) <= math.log(_allowed(m, c, stiffness)) + 1e-12:
        return None
    limit = step_limit(m, c, stiffness)
    advice = f"use 'implicit' or h <= {limit:.3g} s" if limit > 0 else "use 'implicit' (no step is small enough)"
    if m is None:
        return (f"stepper 'projected' is unstable here: h K / c = {h * stiffness / c:.3g} > 2 "
                f"(K = {stiffness:.6g} N/m with every branch sticking); {advice}")
    omega = math.sqrt(stiffness / m)
    growth = growth_per_period(m, c, stiffness, h)
    growth_text = f"x{growth:.3g}" if math.isfinite(growth) else "beyond any float"
    return (f"stepper 'projected' is beyond its stability limit: omega h = {omega * h:.3g} "
            f"(omega = sqrt(K/m) = {omega:.6g} rad/s with every branch sticking) makes the amplitude grow "
            f"{growth_text} per period; {advice}")


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
