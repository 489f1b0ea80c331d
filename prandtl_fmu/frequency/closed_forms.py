"""Closed forms of K(A) and D(A), drawn over the computed ones (``--plot``, docs/frequency.md).

One elastic-perfectly-plastic branch (a spring k in series with a slider of elastic range eta) under
x = A sin(theta), A > eta, on its steady cycle:

    D = 4 k eta (A - eta),     K = (k / pi) (beta - sin(2 beta) / 2),   cos(beta) = 1 - 2 eta / A
                                                                     (beta = 2 asin(sqrt(eta / A))),

and K = k, D = 0 for A <= eta. K and D add over parallel effects: a spring k0 adds k0, a cubic spring
3/4 k3 A^2, a dashpot pi c omega A^2 to D, Coulomb friction alpha 4 alpha A to D. A spectrum of branches
(the continuum: a stiffness density k(s) at elastic range eta(s), s in [0, 1]) is the integral of the
branch's forms over s (Iwan's parallel Jenkins elements follow Masing's rules: the same D as
8 int_0^A F_b - 4 A F_b(A) of its backbone F_b); for Segalman's four-parameter Iwan model below phi_max
(micro-slip) that integral is D = 4 R A^(chi + 3) / ((chi + 2)(chi + 3)).
"""
from __future__ import annotations

import functools
import math
from typing import Optional

import numpy as np


def branch_forms(k, eta, amplitudes) -> tuple:
    """``(K, D)`` of one elastic-perfectly-plastic branch each (arrays k, eta broadcast against the amplitudes
    A): K (N/m), D (J per cycle).

    The stick angle is written beta = 2 asin(sqrt(eta / A)) (the same as acos(1 - 2 eta / A), which loses
    eta / A below the rounding of 1), and beta - sin(2 beta) / 2 = (y - sin y) / 2 with y = 2 beta by its
    series below y = 1 (:func:`y_minus_sine`): K keeps its digits at any eta / A, down to (2 / 3 pi) k beta^3
    in deep macro-slip."""
    k, eta, A = np.broadcast_arrays(np.asarray(k, dtype=float), np.asarray(eta, dtype=float),
                                    np.asarray(amplitudes, dtype=float))
    slips = A > eta
    ratio = np.where(slips, eta / np.where(slips, A, 1.0), 1.0)
    y = 4.0 * np.arcsin(np.sqrt(ratio))  # 2 beta
    stiffness = np.where(slips, k / (2.0 * math.pi) * y_minus_sine(y), k)
    dissipation = np.where(slips, 4.0 * k * eta * (A - eta), 0.0)
    return stiffness, dissipation


# 3! / (2 n + 3)!, n = 0 ... 8: y - sin(y) = y^3 sum_n (-1)^n y^(2n) / (2n + 3)!, to rounding for y < 1.
_SERIES = np.array([(-1.0) ** n * 6.0 / math.factorial(2 * n + 3) for n in range(9)])


def y_minus_sine(y):
    """y - sin(y) (array) without the cancellation of the difference: its series below y = 1 (relative error
    below 1e-16 there), the difference above (which loses at most a factor 1 / (1 - sin(1)) ~ 6 of it)."""
    y = np.asarray(y, dtype=float)
    y2 = y * y
    series = np.zeros_like(y)
    for coefficient in _SERIES[::-1]:
        series = series * y2 + coefficient
    return np.where(y < 1.0, y * y2 / 6.0 * series, y - np.sin(y))


def closed_form(scene, amplitudes, frequency: Optional[float] = None) -> Optional[tuple]:
    """``(K, D)`` at each amplitude from the closed forms, for a scene of springs, a cubic spring, a dashpot
    (with ``frequency``), Prandtl branches or a spectrum (the continuum) and Coulomb friction; None for an
    effect with no closed form here (series dashpots, memory, Stribeck friction)."""
    if scene.has_series_dashpots or scene.delay is not None or scene.history is not None or scene.dahl is not None:
        return None
    if scene.has_dashpot and frequency is None:
        return None
    friction = scene.friction
    if friction is not None and (friction.stribeck_velocity is not None or friction.belt_velocity != 0.0):
        return None
    A = np.asarray(amplitudes, dtype=float).reshape(-1)
    stiffness = np.zeros_like(A)
    dissipation = np.zeros_like(A)
    if scene.spring is not None:
        stiffness += scene.spring.k0
    if scene.cubic is not None:
        stiffness += 0.75 * scene.cubic.k3 * A**2
    if scene.has_dashpot:
        dissipation += math.pi * scene.damper.c * 2.0 * math.pi * frequency * A**2
    if friction is not None:
        dissipation += 4.0 * friction.alpha * A
    branches = scene.branches
    if branches is not None and branches.continuum:
        k, d = spectrum_forms(branches, A)
    elif branches is not None:
        k, d = branch_forms(branches.stiffness[:, None], branches.yield_displacement[:, None], A[None, :])
        k, d = k.sum(axis=0), d.sum(axis=0)
    else:
        k = d = 0.0
    return stiffness + k, dissipation + d


@functools.lru_cache(maxsize=8)
def gauss_legendre(nodes: int) -> tuple:
    """The Gauss-Legendre nodes and weights on [-1, 1] (made once per count: ``leggauss`` is O(nodes^3))."""
    return np.polynomial.legendre.leggauss(nodes)


def spectrum_forms(branches, amplitudes, nodes: int = 400) -> tuple:
    """``(K, D)`` of a spectrum of branches (``effects.ContinuousBranches``): the branch forms integrated over
    s, segment by segment (eta linear in s, k(s) = coefficient eta(s)^power), by Gauss-Legendre on each piece
    of a segment cut where eta(s) = A (the kink of the branch forms) with ``nodes`` points (a flat segment, a
    Dirac, is one branch of stiffness coefficient eta^power (s_1 - s_0))."""
    x, w = gauss_legendre(nodes)
    A_all = np.asarray(amplitudes, dtype=float).reshape(-1)
    stiffness = np.zeros_like(A_all)
    dissipation = np.zeros_like(A_all)
    for j in range(branches.coefficient.shape[0]):
        s0, s1 = float(branches.s[j]), float(branches.s[j + 1])
        e0, e1 = float(branches.eta[j]), float(branches.eta[j + 1])
        c, p = float(branches.coefficient[j]), float(branches.power[j])
        for i, A in enumerate(A_all.tolist()):
            if e1 == e0:
                k, d = branch_forms(c * e0**p * (s1 - s0), e0, A)
                stiffness[i] += float(k)
                dissipation[i] += float(d)
                continue
            cut = min(max(s0 + (A - e0) / (e1 - e0) * (s1 - s0), s0), s1)  # eta(cut) = A
            for lo, hi in ((s0, cut), (cut, s1)):
                if hi <= lo:
                    continue
                # s = lo + (hi - lo) t^2 on [0, 1] (t from the nodes) takes the end singularities of eta^power
                # (a power law at eta = 0) and of the sqrt in beta at eta = A
                t = 0.5 * (x + 1.0)
                for ends in ((lo, hi),):
                    s = ends[0] + (ends[1] - ends[0]) * (0.5 - 0.5 * np.cos(math.pi * t))
                    ds = (ends[1] - ends[0]) * 0.5 * math.pi * np.sin(math.pi * t) * 0.5
                    eta = e0 + (e1 - e0) * (s - s0) / (s1 - s0)
                    density = c * np.power(np.maximum(eta, 1e-300), p) if p != 0 else np.full_like(eta, c)
                    k, d = branch_forms(density, eta, A)
                    stiffness[i] += float(np.sum(w * ds * k))
                    dissipation[i] += float(np.sum(w * ds * d))
    return stiffness, dissipation


def iwan_microslip_dissipation(R: float, chi: float, amplitudes) -> np.ndarray:
    """Segalman's D = 4 R A^(chi + 3) / ((chi + 2)(chi + 3)) (J) for A <= phi_max (micro-slip)."""
    A = np.asarray(amplitudes, dtype=float)
    return 4.0 * R * A ** (chi + 3.0) / ((chi + 2.0) * (chi + 3.0))
