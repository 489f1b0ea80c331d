"""Forces of the single-valued effects in parallel: k0 x + k3 x^3 + c v.

Each coefficient is a float, or ``None`` when the scene has no such effect.
"""
from .._jit import kernel


@kernel
def elastic_force(x, k0, k3):
    """k0 x + k3 x^3 (N): the smooth springs."""
    force = 0.0
    if k0 is not None:
        force += k0 * x
    if k3 is not None:
        force += k3 * x * x * x
    return force


@kernel
def elastic_stiffness(x, k0, k3):
    """k0 + 3 k3 x^2 (N/m): the slope of :func:`elastic_force`."""
    stiffness = 0.0
    if k0 is not None:
        stiffness += k0
    if k3 is not None:
        stiffness += 3.0 * k3 * x * x
    return stiffness


@kernel
def smooth_force(x, v, k0, k3, c):
    """k0 x + k3 x^3 + c v (N): springs and dashpot."""
    force = elastic_force(x, k0, k3)
    if c is not None:
        force += c * v
    return force


@kernel
def elastic_energy(x, k0, k3):
    """k0 x^2/2 + k3 x^4/4 (J)."""
    energy = 0.0
    if k0 is not None:
        energy += 0.5 * k0 * x * x
    if k3 is not None:
        energy += 0.25 * k3 * x * x * x * x
    return energy


@kernel
def damped(v, c, h, m):
    """v / (1 + h c / m): a dashpot taken implicitly over h; just v without a dashpot."""
    if c is None:
        return v
    return v / (1.0 + h * c / m)


@kernel
def plus_damping(value, c):
    """value + c (N s/m): an inertia m/h with the dashpot taken implicitly; just value without a dashpot."""
    if c is None:
        return value
    return value + c
