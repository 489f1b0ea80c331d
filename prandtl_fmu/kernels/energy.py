"""The energy account of a run (optional: ``energy`` is None when not asked for).

Over each step a stepper books, with the very forces its update uses,

    energy[0] += F dx            work done by the load
    energy[1] += sum alpha_i |slip_i|   dissipated by the sliders (booked by play.move or stack.move)
    energy[2] += c v dx          dissipated by the dashpot

and the state holds kinetic m v^2/2 and stored k0 x^2/2 + k3 x^4/4 + sum k_i u_i^2/2
energy. The balance residual  work - dissipated - (kinetic + stored - initial)
is then the energy the scheme itself dissipated (> 0) or created (< 0).
"""
from .._jit import kernel
from .play import stored_energy
from .smooth import elastic_energy


@kernel
def book(energy, force, dx, c, velocity):
    """Add the load's work F dx and the dashpot's c v dx to an energy account."""
    book_apart(energy, force, dx, c, velocity, dx)


@kernel
def book_apart(energy, force, dx, c, velocity, distance):
    """Add F dx and the dashpot's c v ``distance``: for a scheme whose dashpot acts at another velocity than
    the one that moves x (symplectic: x moves by h v_old, the dashpot's force is c v_new), booked over the
    distance that velocity covers, h v_new, so that a dissipation never decreases (c v_new h v_old < 0 at a
    reversal)."""
    if energy is None:
        return
    energy[0] += force * dx
    _book_damper(energy, c, velocity, distance)


@kernel
def _book_damper(energy, c, velocity, dx):
    if c is None:
        return
    energy[2] += c * velocity * dx


@kernel
def kinetic(m, v):
    """m v^2 / 2 (J), 0 for a massless element."""
    if m is None:
        return 0.0
    return 0.5 * m * v * v


@kernel
def stored(x, k0, k3, k, u):
    """k0 x^2/2 + k3 x^4/4 + sum_i k_i u_i^2/2 (J)."""
    return elastic_energy(x, k0, k3) + stored_energy(k, u)
