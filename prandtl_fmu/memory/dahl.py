"""``[dahl]``: Dahl's friction force on the mass (P. R. Dahl, *Solid friction damping of mechanical
vibrations*, AIAA J. 14 (1976) 1675-1682; the form of Olsson, Astrom, Canudas de Wit, Gafvert & Lischinsky,
*Friction models and friction compensation*, Eur. J. Control 4 (1998), eq. 6):

    force on the point:  -F_d,   dF_d/dt = sigma (1 - F_d / F_c sgn v)^exponent v,   F_d(0) = 0,

``sigma`` (N/m, > 0) the stiffness at a reversal, ``force`` F_c (N, > 0) the Coulomb level it approaches,
``exponent`` (> 0, default 1). |F_d| <= F_c always. The law is rate independent: dF_d/dx = sigma (1 - F_d / F_c
s)^exponent along a motion of sign s, so over a monotone increment dx (s = sgn dx, d = sigma |dx| / F_c,
y = 1 - s F_d / F_c in [0, 2]) it is integrated exactly:

    exponent = 1:   y1 = y exp(-d)                              (F_d relaxes exponentially in x towards s F_c)
    exponent > 1:   y1 = y (1 + (exponent - 1) d y^(exponent - 1))^(-1 / (exponent - 1))
    exponent < 1:   y1 = max(0, y^(1 - exponent) - (1 - exponent) d)^(1 / (1 - exponent))   (reaches F_c)

and F_d1 = s F_c (1 - y1), computed as F_d + s F_c y (1 - y1 / y) with 1 - y1 / y by expm1 and log1p: where the
move is small beside F_c / sigma, y1 is within rounding of y and 1 - y1 lost the digits of F_d's change (an
error of F_c's rounding per move, 1e-16 F_c, where F_d itself was 1e-4 F_c: the harmonic balance's periodic
cycle, which divides the period's error by 1 - (its slope), 1e-3 there, saw its force jump by 1e-12 between
Newton iterations and its continuation crept by steps of 1e-5 on the packaged belt tensioner under base
excitation). The steppers move x linearly over a step, so this is the exact Dahl operator on
their path: ``implicit`` solves for the step with F_d1 at the new x (a monotone term: dF_d1/d(dx) = sigma
y1^exponent >= 0), ``projected`` takes F_d at the old state and moves it by h v.

The *modified* Dahl model of the belt tensioner (Bastien, Michon, Manin & Dufour, J. Sound Vib. 302 (2007)),
with upper and lower envelopes approached exponentially, is not built: its published equations could not be
read from any source reachable here (``docs/memory.md``).

The kernel form: ``((sigma, force, exponent), state)``, ``state[0]`` = F_d.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._jit import inline_kernel, kernel
from ..libm import expm1, log1p, pow

NAME = "dahl"
MAX_EXPONENT = 100.0


@dataclass(frozen=True)
class Dahl:
    """Dahl's friction: stiffness ``sigma`` at reversal (N/m), Coulomb level ``force`` (N), ``exponent``."""

    sigma: float
    force: float
    exponent: float = 1.0


def read(r, scene_tables) -> Dahl:
    r.only({"sigma", "force", "exponent", "kind"})
    if r.data.get("kind") == "envelope":
        r.fail("kind", '"envelope" (the modified Dahl model of the belt tensioner, J. Sound Vib. 302 (2007)) is not '
                       "built: its published equations could not be read here (docs/memory.md)")
    r.string("kind", "dahl", choices=("dahl",))
    if "friction" in scene_tables:
        r.fail("sigma", "[dahl] and [friction] are two laws of the mass's friction on the ground: keep one")
    # (exponent <= MAX_EXPONENT: scene._check_memory_rules, which also checks a coefficient set later)
    return Dahl(r.number("sigma", positive=True), r.number("force", positive=True),
                r.number("exponent", 1.0, positive=True))


def compile(dahl: Dahl):
    return (float(dahl.sigma), float(dahl.force), float(dahl.exponent)), np.zeros(1)


def state(part) -> list:
    return part[1].tolist()


def restore(part, values) -> None:
    (sigma, level, exponent), f = part
    if len(values) != 1:
        raise ValueError(f"state has {len(values)} Dahl forces, the element has 1")
    if not abs(values[0]) <= level:
        raise ValueError(f"state has a Dahl force {values[0]!r} beyond its level F_c = {level!r}")
    f[0] = values[0]


@inline_kernel
def after(part, fd, dx):
    """(F_d after a monotone move dx from F_d = ``fd``, its slope dF_d/d(dx) there)."""
    (sigma, level, exponent), f = part
    if dx == 0.0:
        return fd, sigma * _power(max(1.0 - abs(fd) / level, 0.0), exponent)  # (either side's slope: a bound)
    s = 1.0 if dx > 0.0 else -1.0
    y = max(1.0 - s * fd / level, 0.0)
    d = sigma * abs(dx) / level
    # shrink = 1 - y1 / y, without cancellation
    if y == 0.0:
        shrink = 0.0
    elif exponent == 1.0:
        shrink = -expm1(-d)
    elif exponent > 1.0:
        p = exponent - 1.0
        shrink = -expm1(-log1p(p * d * pow(y, p)) / p)
    else:
        p = 1.0 - exponent
        z = p * d / pow(y, p)
        shrink = 1.0 if z >= 1.0 else -expm1(log1p(-z) / p)
    y1 = y * (1.0 - shrink)
    if y1 >= 2.0 or y == 0.0:  # F_d past -s F_c (or at s F_c): as the law's bound [0, 2] on y says
        y1 = min(y1, 2.0)
        return s * level * (1.0 - y1), sigma * _power(y1, exponent)
    # within [-F_c, F_c]: the sum can round one ulp past it, a state set_state then refuses (a review's find)
    return min(max(fd + s * level * y * shrink, -level), level), sigma * _power(y1, exponent)


@inline_kernel
def _power(y, exponent):
    """y^exponent, without the general power for Dahl's usual exponents 1 and 2."""
    if exponent == 1.0:
        return y
    if exponent == 2.0:
        return y * y
    return pow(y, exponent)


@inline_kernel
def force(part):
    return part[1][0]
