"""Masing models given by their backbone curve, turned into the element's Prandtl branches (Iwan 1966).

A Masing model (Masing 1926, with the "extended" rules for irregular
histories: return-point memory) is fixed by its backbone F_b(x), the force
under a monotone loading from the virgin state, odd and concave for x >= 0. Iwan (J. Appl. Mech. 33, 1966)
showed that a parallel set of Jenkins elements (our Prandtl branches: a
spring k_i in series with a slider of elastic range eta_i) beside a spring k0
follows the extended Masing rules exactly, with the backbone

    F_b(x) = k0 x + sum_i k_i min(x, eta_i)          (x >= 0),

so that k0 = F_b'(inf) and the density of stiffness at elastic range eta is
-F_b''(eta). This module is that correspondence, in the discrete form:

* :class:`Bilinear` is one branch and a spring, exactly;
* a smooth backbone (:class:`Hyperbolic`, :class:`RambergOsgood`) is cut at
  nodes 0 = x_0 < x_1 < ... < x_N = x_max (:func:`nodes`) and replaced by its
  piecewise-linear interpolant, which is the backbone of N branches
  (:func:`iwan_branches`): eta_j = x_j and k_j = s_j - s_{j+1}, s_j the chord
  slope on [x_{j-1}, x_j], s_{N+1} = k0. The discrete model's backbone equals
  F_b at every node; between them it lies below by at most
  :func:`interpolation_error`, and a Masing loop whose reversal stack holds D
  reversals is off by at most (D + 1) times that (docs/masing.md), as long as
  |x| <= x_max.

Everything here runs once when a scene is read; the kernels see only branches.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Union

import numpy as np

from .effects import Branches

# How the nodes of a smooth backbone are placed: equal steps of force F_b(x_j) = j F_b(x_max) / N (the
# default: short cells where the curve bends most, near the origin) or equal steps of displacement.
SPACINGS = ("force", "displacement")


@dataclass(frozen=True)
class Bilinear:
    """F_b(x) = k x for |x| <= f_y / k, f_y + alpha k (x - f_y / k) beyond (odd): initial stiffness ``k``
    (N/m, > 0), yield force ``f_y`` (N, > 0), post-yield stiffness ratio ``alpha`` (0 <= alpha < 1)."""

    k: float
    f_y: float
    alpha: float = 0.0

    @property
    def post_yield_stiffness(self) -> float:
        """F_b'(inf) = alpha k (N/m): the parallel spring k0."""
        return self.alpha * self.k

    def force(self, x):
        x = np.asarray(x, dtype=float)
        yield_displacement = self.f_y / self.k
        ax = np.abs(x)
        return np.sign(x) * np.where(ax <= yield_displacement, self.k * ax,
                                     self.f_y + self.alpha * self.k * (ax - yield_displacement))


@dataclass(frozen=True)
class Hyperbolic:
    """F_b(x) = k x / (1 + k |x| / f_u): initial stiffness ``k`` (N/m, > 0), ultimate force ``f_u`` (N, > 0),
    approached as x -> inf (Kondner's hyperbola; F_b'' = -2 k^2 / f_u / (1 + k x / f_u)^3)."""

    k: float
    f_u: float

    post_yield_stiffness = 0.0

    def force(self, x):
        x = np.asarray(x, dtype=float)
        return self.k * x / (1.0 + self.k * np.abs(x) / self.f_u)

    def displacement(self, force):
        """The inverse of F_b on [0, f_u): x = F / (k (1 - F / f_u))."""
        force = np.asarray(force, dtype=float)
        return force / (self.k * (1.0 - force / self.f_u))

    def where_slope(self, slope):
        """The x >= 0 where F_b'(x) = k / (1 + k x / f_u)^2 equals ``slope`` (0 < slope <= k)."""
        return self.f_u / self.k * (np.sqrt(self.k / np.asarray(slope, dtype=float)) - 1.0)


@dataclass(frozen=True)
class RambergOsgood:
    """x = F / k (1 + a |F / f_y|^(r - 1)) (F_b is its inverse, odd): initial stiffness ``k`` (N/m, > 0),
    reference force ``f_y`` (N, > 0), ``a`` (> 0), exponent ``r`` (> 1). F_b grows without bound like
    (k f_y^(r-1) x / a)^(1/r); dF_b/dx = k / (1 + a r |F / f_y|^(r - 1))."""

    k: float
    f_y: float
    a: float
    r: float

    post_yield_stiffness = 0.0

    def displacement(self, force):
        force = np.asarray(force, dtype=float)
        return force / self.k * (1.0 + self.a * np.abs(force / self.f_y) ** (self.r - 1.0))

    def force(self, x):
        """F_b(x) by Newton's method on the convex, increasing x(F), from an upper bound of the root (both
        F <= k x and F <= (k f_y^(r-1) x / a)^(1/r) hold): the iterates fall monotonically to it."""
        x = np.asarray(x, dtype=float)
        target = np.abs(x)
        with np.errstate(divide="ignore"):  # log(0) = -inf: the bound 0 at x = 0
            power_bound = np.exp((np.log(self.k / self.a) + (self.r - 1.0) * np.log(self.f_y) + np.log(target))
                                 / self.r)  # in logarithms: f_y^(r-1) alone may overflow
        force = np.minimum(self.k * target, power_bound)
        for _ in range(200):
            ratio = (force / self.f_y) ** (self.r - 1.0)
            residual = force / self.k * (1.0 + self.a * ratio) - target
            step = residual / ((1.0 + self.a * self.r * ratio) / self.k)
            new = np.maximum(force - step, 0.0)
            if np.all(new >= force):  # no more decrease: converged to rounding
                break
            force = np.minimum(new, force)
        return np.sign(x) * force

    def where_slope(self, slope):
        """The x >= 0 where dF_b/dx = ``slope`` (0 < slope <= k)."""
        ratio = (self.k / np.asarray(slope, dtype=float) - 1.0) / (self.a * self.r)
        return self.displacement(self.f_y * ratio ** (1.0 / (self.r - 1.0)))


Backbone = Union[Bilinear, Hyperbolic, RambergOsgood]


def nodes(backbone, count: int, x_max: float, spacing: str = "force") -> np.ndarray:
    """The count + 1 nodes 0 = x_0 < ... < x_N = x_max (m) of a smooth backbone: equal steps of force
    (F_b(x_j) = j F_b(x_max) / N, x_j by the explicit inverse) or of displacement (x_j = j x_max / N)."""
    if spacing not in SPACINGS:
        raise ValueError(f"spacing must be one of {', '.join(SPACINGS)}, got {spacing!r}")
    fraction = np.arange(count + 1) / count
    if spacing == "displacement":
        points = x_max * fraction
    else:
        points = backbone.displacement(float(backbone.force(x_max)) * fraction)
    points[0], points[-1] = 0.0, x_max
    return points


def iwan_branches(backbone, count: int = 100, x_max: Optional[float] = None, spacing: str = "force") -> tuple:
    """``(k0, branches)``: the parallel spring (N/m) and virgin branches whose backbone interpolates
    ``backbone`` at :func:`nodes` (one exact branch for :class:`Bilinear`, which takes no count or x_max;
    a smooth backbone needs x_max).

    ValueError when the chord slopes do not fall strictly (no positive k_j in double precision: too many
    nodes for the curve's bend)."""
    if isinstance(backbone, Bilinear):
        k = np.array([(1.0 - backbone.alpha) * backbone.k])
        eta = np.array([backbone.f_y / backbone.k])
        return backbone.post_yield_stiffness, Branches(k, eta, np.zeros(1))
    if x_max is None:
        raise ValueError(f"a smooth backbone ({type(backbone).__name__}) needs x_max, the last node")
    points = nodes(backbone, count, x_max, spacing)
    values = backbone.force(points)
    if not np.all(np.isfinite(values)):
        raise ValueError(f"the backbone overflows in double precision on [0, x_max = {x_max!r}]")
    slopes = np.diff(values) / np.diff(points)
    stiffness = slopes - np.append(slopes[1:], backbone.post_yield_stiffness)
    if not np.all(stiffness > 0) or not np.all(np.diff(points) > 0):
        raise ValueError(f"the chord slopes of {count} cells up to x_max = {x_max!r} do not fall strictly in "
                         "double precision (too many cells for the curve's bend, or a curve flat to rounding "
                         "there): use fewer branches (count) or a smaller x_max")
    eta = points[1:].copy()
    for array in (stiffness, eta):
        array.setflags(write=False)
    return backbone.post_yield_stiffness, Branches(stiffness, eta, np.zeros(count))


def interpolation_error(backbone, points) -> float:
    """max over [x_0, x_N] of F_b(x) minus its piecewise-linear interpolant at ``points`` (N): on each cell
    the gap of a concave curve over its chord peaks where F_b'(x) equals the chord slope s_j, a closed form
    (``where_slope``). 0 for :class:`Bilinear` at its own node."""
    if isinstance(backbone, Bilinear):
        return 0.0
    points = np.asarray(points, dtype=float)
    values = backbone.force(points)
    slopes = np.diff(values) / np.diff(points)
    peak = np.clip(backbone.where_slope(slopes), points[:-1], points[1:])
    chord = values[:-1] + slopes * (peak - points[:-1])
    return float(np.max(backbone.force(peak) - chord))
