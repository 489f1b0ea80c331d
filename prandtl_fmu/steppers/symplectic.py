"""``symplectic``: semi-implicit (symplectic) Euler, positions first.

    dx    = h v
    u_i  <- clip(u_i + dx, -eta_i, eta_i)          (exact play update)
    x    <- x + dx
    v    <- ( v + h (F(t_{p+1}) - k0 x - k3 x^3 - sum_i k_i u_i) / m ) / (1 + h c / m)

The force is that of the *new* position and elongations; the dashpot is taken
implicitly. Order 1 like ``projected`` (same cost: one pass over the
branches), but symplectic: in the elastic regime it conserves a modified
energy instead of multiplying the energy by 1 + (omega h)^2 per step, so
its error does not grow exponentially in time and its constant is much
smaller. Stable for omega h < 2 (omega^2 = stiffness / m).

Friction on the mass: v is taken as above with the friction's sign graph
implicit (``kernels/friction.py``: inertia m/h + c); series dashpots follow
the exact flow along the step's straight path (``kernels/series.py``).

Massless elements: not applicable (use ``implicit``, or ``projected`` with a dashpot).
"""
from .._jit import kernel
from ..kernels.energy import book_apart
from ..kernels.batch import summary_loop
from ..kernels.loop import time_loop
from ..kernels.friction import book_friction, held_velocity
from ..kernels.series import FLOW, move_branches
from ..kernels.smooth import damped, elastic_force, plus_damping
from ..loads import force_at
from ..memory import refuse_memory

BRANCH_STACK = True  # takes the memory stack (kernels/stack.py) for many branches
ORDER = 1


def loop_for(scene):
    """The compiled time loop for ``scene``; ValueError if the scheme does not apply."""
    refuse_memory(scene, "symplectic")
    if scene.mass is None:
        raise ValueError("'symplectic' needs [mass]; a massless element is solved by 'implicit'")
    if scene.load.noise is not None:
        raise ValueError("'symplectic' takes no white noise (no strong order measured for it): use 'implicit' (backward Euler-Maruyama) or 'projected' (Euler-Maruyama)")
    return run


@kernel
def step(model, load, t, h, x, v, s, u, energy):
    m, k0, k3, c, k, eta, cs, friction, memory = model
    dx = h * v
    s = move_branches(k, eta, cs, u, dx, h, FLOW, energy)
    x = x + dx
    force = force_at(load, t + h)
    v1, f = held_velocity(friction, plus_damping(m / h, c), damped(v + h * (force - elastic_force(x, k0, k3) - s) / m,
                                                                  c, h, m), v)
    book_apart(energy, force, dx, c, v1, h * v1)  # the dashpot: c v1^2 h >= 0 (see book_apart)
    book_friction(energy, friction, f, h, v1)
    return x, v1, s


_loop = time_loop(step)


@kernel
def run(model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy):
    """The time loop (``kernels/loop.py``) over :func:`step`, cached."""
    return _loop(model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy)


_summary = summary_loop(step)


@kernel
def run_summary(template, batch):
    """The summary loop (``kernels/batch.py``) over :func:`step`, cached."""
    _summary(template, batch)


# the summary loop of each time loop that loop_for gives
SUMMARY_LOOPS = {run: run_summary}
