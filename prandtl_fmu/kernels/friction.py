"""Dry friction of the mass on the ground (:class:`prandtl_fmu.effects.Friction`) in the kernels.

``friction`` is None (no ``[friction]``: numba compiles every call below
away) or the tuple ``(alpha, alpha_kinetic, stribeck_velocity,
belt_velocity)`` (N, N, m/s, m/s; ``stribeck_velocity`` is 1 and unused for
plain Coulomb friction, alpha_kinetic = alpha). With w = v - v_b the
velocity relative to the ground, the friction force on the mass is -A(w),

    A(w) = alpha sigma(w) + Psi(w),   Psi(w) = sign(w) (alpha_kinetic - alpha) (1 - exp(-|w| / stribeck_velocity)).

Every stepper takes the sign graph sigma implicitly, so that the mass sticks
exactly (w = 0 to the bit while the other forces stay within [-alpha,
alpha]). The explicit steppers take Psi at the velocity of the start of the
(half) step, as the paper takes every single-valued term
(:func:`held_velocity`); ``implicit`` takes all of A at the new velocity
(``steppers/implicit.py``).
"""
import math

from .. import libm
from .._jit import kernel
from ..loads import force_at
from ..memory import force_now
from .smooth import smooth_force


@kernel
def stribeck_part(friction, w):
    """Psi(w) (N): the smooth part of the friction law, 0 at w = 0 and for plain Coulomb friction."""
    alpha, kinetic, stribeck, belt = friction
    if w == 0.0 or kinetic == alpha:
        return 0.0
    return -math.copysign((alpha - kinetic) * -libm.expm1(-abs(w) / stribeck), w)


@kernel
def sliding_force(friction, speed):
    """alpha_kinetic + (alpha - alpha_kinetic) exp(-speed / stribeck_velocity) (N): the force against a slip at
    ``speed`` >= 0 (alpha at speed 0)."""
    alpha, kinetic, stribeck, belt = friction
    if kinetic == alpha:
        return alpha
    return kinetic + (alpha - kinetic) * libm.exp(-speed / stribeck)


@kernel
def held_velocity(friction, inertia, v_free, v_old):
    """One (half) step of the friction on the mass: ``(v1, f)``.

    ``v_free`` (m/s) is the velocity the step would give without friction and
    ``inertia`` (N s/m: m/h, plus the dashpot's c where the stepper takes it
    implicitly) its sensitivity to a force. The new relative velocity
    w1 = v1 - v_b solves

        inertia (w1 - w_free) + alpha sigma(w1) + Psi(w_old) ∋ 0,

    so w1 = sign(q) max(|q| - alpha, 0) / inertia with q = inertia w_free - Psi(w_old):
    the mass sticks (v1 = v_b exactly) when |q| <= alpha. ``f`` = inertia (w1 - w_free) is the
    friction force the step applied to the mass (N). Without friction: ``(v_free, 0)``.
    """
    if friction is None:
        return v_free, 0.0
    alpha, kinetic, stribeck, belt = friction
    q = inertia * (v_free - belt) - stribeck_part(friction, v_old - belt)
    w1 = 0.0
    if abs(q) > alpha:
        w1 = math.copysign((abs(q) - alpha) / inertia, q)
    return belt + w1, inertia * ((belt + w1) - v_free)


@kernel
def resistance(friction, v, push):
    """A(v - v_b) in the state (N): the force the friction resists with, counted in the reaction. Sliding, the
    sliding force against the slip; sticking (v = v_b), the force that holds the mass against the net force
    ``push`` of everything else (F minus the other effects), up to alpha. 0 without friction."""
    if friction is None:
        return 0.0
    alpha, kinetic, stribeck, belt = friction
    w = v - belt
    if w == 0.0:
        return min(max(push, -alpha), alpha)
    return math.copysign(sliding_force(friction, abs(w)), w)


@kernel
def book_friction(energy, friction, f, h, v1):
    """Book the friction force ``f`` (N, on the mass) applied over a step of ``h`` that ends at velocity ``v1``:
    the work dissipated -f h (v1 - v_b) goes to energy[3] (>= 0: f opposes the new slip, see
    :func:`held_velocity`) and the belt's work f h v_b to the work, energy[0]."""
    if energy is None:
        return
    if friction is None:
        return
    belt = friction[3]
    energy[3] -= f * h * (v1 - belt)
    energy[0] += f * h * belt


@kernel
def reaction(model, load, t, x, v, s):
    """The force of the effects on the point (N) in the state (x, v, branch force ``s``) at time t:
    k0 x + k3 x^3 + c v + s + the memory forces (``memory/``), plus the friction's :func:`resistance` against the load F(t) (= F - m v'
    while the mass sticks)."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    others = smooth_force(x, v, k0, k3, c) + s + force_now(memory, t, x, v)
    return others + _resisted(friction, load, t, v, others)


@kernel
def _resisted(friction, load, t, v, others):
    if friction is None:
        return 0.0
    return resistance(friction, v, force_at(load, t) - others)
