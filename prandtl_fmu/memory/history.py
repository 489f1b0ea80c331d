"""``[history]``: a history (convolution) force on the mass (Bastien & Lamarque, Nonlinear Analysis 63 (2005);
Nonlinear Dyn. 47 (2007); Lamarque, Bastien & Holland, Math. Probl. Eng. 2005:4, a delay of Volterra form).

    force on the point:   -int_0^t kappa(t - s) y(s) ds,   kappa(r) = sum_j weight_j exp(-rate_j r),

y = x (``acts_on = "x"``, default) or v (``"v"``, with [mass] only). ``weight`` (N/(m s) on x, N/m on v)
and ``rate`` (1/s, >= 0) are lists of equal length. A sum of exponentials makes the convolution exactly
internal variables,

    z_j' = -rate_j z_j + y,   z_j(0) = 0,   force = -sum_j weight_j z_j,

so the cost per step is O(number of terms) and the state is bounded (the z_j). Over a step from t to t + h,
with y linear along it (the steppers move x linearly), z_j is integrated exactly:

    z_j(t + h) = E z_j + phi0 y(t) + phi1 y(t + h),   E = exp(-a),  a = rate_j h,
    phi0 = h (1 - E - a E) / a^2,   phi1 = h (1 - E) / a - phi0,

(series in a below 0.5, where the closed forms cancel; a = 0: phi0 = phi1 = h / 2, the trapezoid), implicit in
y(t + h) for ``implicit``.

The kernel form: ``((n, on_v), data)``, one array (one array: every array a kernel receives costs a reference
count per call): ``data[0]`` the step h of the cached coefficients (NaN: none), then the n weights, the n rates, the n
z_j (the state), and E, phi0, phi1 of that h (n each: a function of h alone, they never change a result).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._jit import inline_kernel, kernel
from ..libm import exp, expm1

NAME = "history"


@dataclass(frozen=True)
class History:
    """The kernel sum_j weight_j exp(-rate_j r) of a convolution force on y = x or v (``acts_on``)."""

    weight: tuple
    rate: tuple
    acts_on: str = "x"


def read(r, scene_tables) -> History:
    r.only({"weight", "rate", "acts_on"})
    weight = r.numbers("weight")
    rate = r.numbers("rate", minimum=0.0, length=len(weight))
    if len(weight) == 0:
        r.fail("weight", "must list at least one term")
    acts_on = r.string("acts_on", "x", choices=("x", "v"))
    if acts_on == "v" and "mass" not in scene_tables:
        r.fail("acts_on", '"v" needs [mass]: the massless element\'s velocity is a rate of its state, not a '
                          "degree of freedom (convolve x)")
    return History(tuple(float(w) for w in weight), tuple(float(q) for q in rate), acts_on)


W, R, Z, E, P0, P1 = range(6)  # the blocks of data after data[0]


def compile(history: History):
    n = len(history.weight)
    data = np.zeros(1 + 6 * n)
    data[0] = np.nan  # no coefficients cached yet (NaN equals no step, 0 included)
    data[1:1 + n] = history.weight
    data[1 + n:1 + 2 * n] = history.rate
    return (n, 1.0 if history.acts_on == "v" else 0.0), data


def state(part) -> list:
    (n, on_v), data = part
    return data[1 + Z * n:1 + (Z + 1) * n].tolist()


def restore(part, values) -> None:
    (n, on_v), data = part
    if len(values) != n:
        raise ValueError(f"state has {len(values)} history variables, the element has {n}")
    data[1 + Z * n:1 + (Z + 1) * n] = np.asarray(values, dtype=float)
    data[0] = np.nan  # (the cached coefficients are recomputed)


@kernel
def weights(a):
    """(E, phi0 / h, phi1 / h) of a = rate h >= 0 (see the module docstring)."""
    if a < 0.5:  # the series of (1 - E - a E) / a^2 = sum_{n>=2} (-a)^(n-2) (n - 1) / n!, and of (1 - E) / a
        s0, s1 = 0.0, 0.0
        power = 1.0
        factorial = 2.0
        for n in range(2, 24):
            s0 += power * (n - 1) / factorial
            s1 += power / (factorial / n)
            power *= -a
            factorial *= n + 1
        return exp(-a), s0, s1 - s0
    em = expm1(-a)  # E - 1
    e = em + 1.0
    g1 = -em / a  # (1 - E) / a
    phi0 = (g1 - e) / a
    return e, phi0, g1 - phi0


@kernel
def prepare(part, h):
    """Cache E, phi0, phi1 of a step ``h`` (recomputed only when h changes). Called by the time loops before
    their steps (``memory.prepare``), never inside a step: the steps' code then holds no call, which measured
    9 ns of projected's 65 ns step."""
    (n, on_v), data = part
    if data[0] != h:
        for j in range(n):
            e, p0, p1 = weights(data[1 + R * n + j] * h)
            data[1 + E * n + j] = e
            data[1 + P0 * n + j] = p0 * h
            data[1 + P1 * n + j] = p1 * h
        data[0] = h


@inline_kernel
def terms(part, h, y_now):
    """(A, B): the history force after a step of h = A + B y(t + h); NaN if :func:`prepare` was not called for
    this h (a loud failure of the step, never a wrong number)."""
    (n, on_v), data = part
    if data[0] != h:
        return np.nan, np.nan
    a = 0.0
    b = 0.0
    for j in range(n):
        w = data[1 + W * n + j]
        a += w * (data[1 + E * n + j] * data[1 + Z * n + j] + data[1 + P0 * n + j] * y_now)
        b += w * data[1 + P1 * n + j]
    return a, b


@inline_kernel
def force(part):
    (n, on_v), data = part
    total = 0.0
    for j in range(n):
        total += data[1 + W * n + j] * data[1 + Z * n + j]
    return total


@inline_kernel
def record(part, h, y0, y1):
    """z_j after a step of h from y0 to y1 (nothing if :func:`prepare` was not called for this h: the step's
    force was NaN, and the step is refused)."""
    (n, on_v), data = part
    if data[0] != h:
        return
    for j in range(n):
        k = 1 + Z * n + j
        data[k] = data[1 + E * n + j] * data[k] + data[1 + P0 * n + j] * y0 + data[1 + P1 * n + j] * y1
