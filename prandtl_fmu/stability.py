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

The arithmetic is one compiled kernel, :func:`check` (the modes in real arithmetic, ``prandtl_fmu.libm``'s log,
exp and hypot: the same bits everywhere): :func:`stability_problem` calls it for the library and words what it
finds (:func:`explain`); the native FMU calls the same kernel, compiled into its binary (fmu/native/kernels.py), and
its C layer words the same findings in the same words.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from . import libm
from ._jit import kernel

GROWTH_LIMIT = 2.0  # amplitude factor per period of the stiffest mode

# How a stepper's step can be unstable (check's ``kind``): implicit never, projected as explicit Euler, the
# leapfrog type (symplectic, verlet) beyond omega h = 2, exact only by a Stribeck drop it resolves anyway (never)
IMPLICIT, PROJECTED, LEAPFROG, EXACT = range(4)
KINDS = {"projected": PROJECTED, "symplectic": LEAPFROG, "verlet": LEAPFROG, "exact": EXACT}
# What check finds (its return), and the numbers it leaves in ``out`` for the words (:func:`explain`)
STABLE = 0
LEAPFROG_UNSTABLE = 1  # out: omega h, omega, 2 / omega
RELAXATION_UNSTABLE = 2  # projected, massless with a dashpot; out: h K / c, K, the step limit
GROWTH_UNSTABLE = 3  # projected with a mass; out: omega h, omega, the growth per period (inf beyond), the step limit
STRIBECK_UNRESOLVED = 4  # out: the drop slope, m / h + c, the step limit
SERIES_UNSTABLE = 5  # projected's explicit series dashpots; out: h k_i / c_i, the branch (from 1), 2 c_i / k_i
NO_BRANCHES = np.zeros(0)


class StabilityWarning(UserWarning):
    """The step is beyond the stability limit of the stepper for this scene."""


def stepper_kind(stepper: str) -> int:
    """check's ``kind`` of a stepper's name (IMPLICIT for a stepper without a stability limit)."""
    return KINDS.get(stepper, IMPLICIT)


def stiffest(scene, x: Optional[float] = None) -> float:
    """K = k0 + 3 k3 x^2 + sum_i k_i (N/m): the tangent stiffness with every branch sticking."""
    if x is None:
        x = scene.mass.x0 if scene.mass is not None else 0.0
    k0, k3, k_sum = _stiffness_terms(scene)
    return _stiffest(k0, k3, float(x), k_sum)


def _stiffness_terms(scene) -> tuple:
    return (scene.spring.k0 if scene.spring is not None else 0.0, scene.cubic.k3 if scene.cubic is not None else 0.0,
            scene.branches.stiffness_sum if scene.branches is not None else 0.0)


@kernel
def _stiffest(k0, k3, x, k_sum):
    return k0 + 3.0 * k3 * x * x + k_sum


@kernel
def _modes(m, c, stiffness):
    """The modes mu of m mu^2 + c mu + K = 0 as (real, imaginary) parts of the first, of the second, and their
    count (1 or 2), computed from the rates c/(2m) and K/m (no overflow of c^2 or m K for any finite coefficients;
    a rate that is not representable comes out as an infinite real part)."""
    sigma = c / (2.0 * m)
    omega_sq = stiffness / m
    if not (math.isfinite(sigma) and math.isfinite(omega_sq)):
        return -math.inf, 0.0, -math.inf, 0.0, 1
    scale = max(sigma, math.sqrt(omega_sq))
    if scale == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 1
    discriminant = (sigma / scale) ** 2 - omega_sq / scale / scale
    if discriminant >= 0.0:  # two real modes
        root = scale * math.sqrt(discriminant)
        return -sigma + root, 0.0, -sigma - root, 0.0, 2
    root = scale * math.sqrt(-discriminant)  # a conjugate pair: -sigma +- i root
    return -sigma, root, -sigma, -root, 2


@kernel
def _mode_log_growth(re, im, h):
    """log |1 + h mu| of one mode, per period when it oscillates (but at least per step); +inf when it is not
    representable."""
    if not (math.isfinite(re) and math.isfinite(im)):
        return math.inf
    factor = libm.hypot(1.0 + h * re, h * im)
    if not math.isfinite(factor):
        return math.inf
    log_factor = libm.log(factor) if factor > 0 else -math.inf
    frequency = abs(im)
    if frequency > 0.0 and log_factor > 0.0:
        # per period, but at least per step (a period shorter than a step is no comfort)
        log_factor *= max(1.0, 2.0 * math.pi / (frequency * h))
    return log_factor


@kernel
def _log_growth(massive, m, c, stiffness, h):
    """log of the amplitude factor of explicit Euler's stiffest mode per period (per step if it does not
    oscillate); +inf when it is not representable. Computed in logs: no overflow for any finite input."""
    if not massive:  # c x' = -K x: one real mode
        if not c > 0:
            return 0.0
        factor = abs(1.0 - h * (stiffness / c))
        return libm.log(factor) if factor > 0 else -math.inf
    re1, im1, re2, im2, count = _modes(m, c, stiffness)
    worst = _mode_log_growth(re1, im1, h)
    if count == 2:
        worst = max(worst, _mode_log_growth(re2, im2, h))
    return worst


@kernel
def _allowed_growth(massive, m, c, stiffness):
    """The growth allowed: GROWTH_LIMIT per period for an oscillating mode, none (1) otherwise."""
    if not massive:
        return 1.0
    im1 = _modes(m, c, stiffness)[1]
    return GROWTH_LIMIT if im1 != 0.0 else 1.0


@kernel
def _step_limit(massive, m, c, stiffness):
    """The largest h whose growth per period stays within the allowed growth; found by bisection on log h over
    the whole range of floats."""
    log_limit = libm.log(_allowed_growth(massive, m, c, stiffness)) + 1e-12
    low, high = -745.0, 709.0  # log h
    if _log_growth(massive, m, c, stiffness, libm.exp(high)) <= log_limit:
        return math.inf
    if _log_growth(massive, m, c, stiffness, libm.exp(low)) > log_limit:
        return 0.0
    for _ in range(200):
        middle = 0.5 * (low + high)
        if _log_growth(massive, m, c, stiffness, libm.exp(middle)) <= log_limit:
            low = middle
        else:
            high = middle
    return libm.exp(low)


@kernel
def check(kind, massive, m, c, k0, k3, x, k_sum, drop, k_branch, c_branch, h, out):
    """Whether a step h of a stepper of ``kind`` is unstable for an element (``massive``: with its mass m; c its
    dashpot, 0 for none; k0, k3, the branches' total stiffness k_sum and the displacement x give K, every branch
    sticking; ``drop`` the Stribeck drop slope, 0 for none; k_branch, c_branch the branches' stiffnesses and series
    dashpots, empty for none): STABLE, or what is found first, with its numbers in ``out`` (4 doubles)."""
    stiffness = _stiffest(k0, k3, x, k_sum)
    if kind == LEAPFROG and massive:  # symplectic Euler and velocity Verlet: stable for omega h < 2
        omega = math.sqrt(stiffness / m)
        if not omega * h < 2.0:
            out[0], out[1], out[2] = omega * h, omega, 2.0 / omega
            return LEAPFROG_UNSTABLE
    if kind == PROJECTED and (massive or c != 0.0) and stiffness != 0.0:
        log_growth = _log_growth(massive, m, c, stiffness, h)
        if not log_growth <= libm.log(_allowed_growth(massive, m, c, stiffness)) + 1e-12:
            limit = _step_limit(massive, m, c, stiffness)
            if not massive:
                out[0], out[1], out[2] = h * stiffness / c, stiffness, limit
                return RELAXATION_UNSTABLE
            omega = math.sqrt(stiffness / m)
            out[0], out[1], out[3] = omega * h, omega, limit
            out[2] = libm.exp(log_growth) if log_growth < 709.0 else math.inf
            return GROWTH_UNSTABLE
    if kind != EXACT and drop != 0.0:  # the Stribeck drop against m/h + c
        inertia = m / h + c
        if not drop <= inertia:
            out[0], out[1], out[2] = drop, inertia, m / max(drop - c, 1e-300)
            return STRIBECK_UNRESOLVED
    if kind == PROJECTED and k_branch.size:  # the explicit relaxation of series dashpots
        fastest, which = -math.inf, 0
        for i in range(k_branch.size):
            rate = k_branch[i] / c_branch[i]
            if rate > fastest:
                fastest, which = rate, i
        if not h * fastest <= 2.0:
            out[0], out[1], out[2] = h * fastest, which + 1.0, 2.0 / fastest
            return SERIES_UNSTABLE
    return STABLE


def explain(found: int, out, stepper: str) -> Optional[str]:
    """The words of what :func:`check` found for ``stepper``, or None (the native FMU's C layer says the same)."""
    if found == LEAPFROG_UNSTABLE:
        return (f"stepper {stepper!r} is beyond its stability limit: omega h = {out[0]:.3g} >= 2 "
                f"(omega = sqrt(K/m) = {out[1]:.6g} rad/s with every branch sticking); "
                f"use 'implicit' or h < {out[2]:.3g} s")
    if found in (RELAXATION_UNSTABLE, GROWTH_UNSTABLE):
        limit = out[2] if found == RELAXATION_UNSTABLE else out[3]
        advice = f"use 'implicit' or h <= {limit:.3g} s" if limit > 0 else "use 'implicit' (no step is small enough)"
        if found == RELAXATION_UNSTABLE:
            return (f"stepper 'projected' is unstable here: h K / c = {out[0]:.3g} > 2 "
                    f"(K = {out[1]:.6g} N/m with every branch sticking); {advice}")
        growth_text = f"x{out[2]:.3g}" if math.isfinite(out[2]) else "beyond any float"
        return (f"stepper 'projected' is beyond its stability limit: omega h = {out[0]:.3g} "
                f"(omega = sqrt(K/m) = {out[1]:.6g} rad/s with every branch sticking) makes the amplitude grow "
                f"{growth_text} per period; {advice}")
    if found == STRIBECK_UNRESOLVED:
        return (f"[friction]: the Stribeck drop (alpha - alpha_kinetic) / stribeck_velocity = {out[0]:.6g} "
                f"N.s/m exceeds m/h + c = {out[1]:.6g} N.s/m: the step cannot resolve it (the implicit step may have "
                f"several roots; 'implicit' takes the least slip); use h < {out[2]:.3g} s")
    if found == SERIES_UNSTABLE:
        return (f"stepper 'projected' relaxes the series dashpots explicitly and is unstable here: h k_i / c_i = "
                f"{out[0]:.3g} > 2 (branch {int(out[1])}); use 'implicit', 'verlet' or h <= {out[2]:.3g} s")
    return None


def stability_problem(scene, stepper: str, h: float, x: Optional[float] = None) -> Optional[str]:
    """A one-line explanation when ``stepper`` with step ``h`` is unstable for ``scene`` (at the displacement
    ``x``, default the scene's x0), else None."""
    massive = scene.mass is not None
    if x is None:
        x = scene.mass.x0 if massive else 0.0
    k0, k3, k_sum = _stiffness_terms(scene)
    drop = scene.friction.drop_slope if scene.friction is not None else 0.0
    series = scene.has_series_dashpots
    k_branch = np.asarray(scene.branches.stiffness, dtype=np.float64) if series else NO_BRANCHES
    c_branch = np.asarray(scene.branches.damping, dtype=np.float64) if series else NO_BRANCHES
    out = np.zeros(4)
    found = check(stepper_kind(stepper), massive, float(scene.mass.m) if massive else 0.0,
                  float(scene.damper.c) if scene.damper is not None else 0.0, float(k0), float(k3), float(x),
                  float(k_sum), float(drop), k_branch, c_branch, float(h), out)
    return explain(found, out, stepper)


# ------------------------------------------------------------------ the pieces, for a scene's numbers


def log_growth_per_period(m: Optional[float], c: float, stiffness: float, h: float) -> float:
    """log of the amplitude factor of explicit Euler's stiffest mode per period (per step if it does not
    oscillate; m None: massless); +inf when it is not representable."""
    return _log_growth(m is not None, float(m or 0.0), float(c), float(stiffness), float(h))


def growth_per_period(m: Optional[float], c: float, stiffness: float, h: float) -> float:
    """Amplitude factor of explicit Euler's stiffest mode per period (per step if it does not oscillate);
    inf beyond what a float holds."""
    log_growth = log_growth_per_period(m, c, stiffness, h)
    return float(libm.exp(log_growth)) if log_growth < 709.0 else math.inf


def step_limit(m: Optional[float], c: float, stiffness: float) -> float:
    """The largest h whose growth per period stays within the allowed growth (GROWTH_LIMIT per period for an
    oscillating mode, none otherwise); found by bisection on log h over the whole range of floats."""
    return float(_step_limit(m is not None, float(m or 0.0), float(c), float(stiffness)))
