"""``verlet``: velocity Verlet with the exact play update along the step.

    a0      = (F(t_p) - k0 x - k3 x^3 - c v - sum_i k_i u_i) / m
    v_half  = v + (h/2) a0
    dx      = h v_half
    u_i    <- clip(u_i + dx, -eta_i, eta_i)
    x      <- x + dx
    v      <- ( v_half + (h/2) (F(t_{p+1}) - k0 x - k3 x^3 - sum_i k_i u_i) / m ) / (1 + (h/2) c / m)

x moves along a straight path over the step, so its increment is monotone
and clip(u_i + dx) is the exact elongation of every branch at the end of
the step: the branch force there is exact for that path. Cost: one pass over
the branches per step, like ``projected``.

Order 2 (measured against ``exact``: tests/steppers/test_exact.py). Why this escapes Remark 1.2 of
Bastien & Schatzman (no classical order-2 scheme does better than order 1
for the general inclusion): there the solution's derivative jumps (u' is
discontinuous when a constraint becomes active), so any scheme sees an O(h)
local defect at each activation. Here the constrained variables u_i do not
enter the inertia: the velocity v is continuous and x is C^1 with a Lipschitz
acceleration, and u_i = P_i[x] is a Lipschitz function of the path of x
evaluated exactly by the play operator. The only non-smoothness is a kink of
the acceleration at each stick/slip switch, which costs O(h^2) locally (the
acceleration is continuous), so the global order stays 2. It would drop to 1
if the play update were not exact (e.g. a projected elongation from a
predicted velocity) or if the load had jumps (a table load with a jump).

Friction on the mass: each half step takes the friction's sign graph
implicitly and Stribeck's part at the velocity it starts from
(``kernels/friction.py``); the stick-slip switches make it order 1 there.
Series dashpots follow the exact flow along the straight path
(``kernels/series.py``), which keeps the argument above.

Stable for omega h < 2 (omega^2 = stiffness / m). Massless elements: not applicable.
"""
from .._jit import kernel
from ..kernels.energy import book
from ..kernels.batch import summary_loop
from ..kernels.loop import time_loop
from ..kernels.friction import book_friction, held_velocity
from ..kernels.series import FLOW, move_branches
from ..kernels.smooth import damped, elastic_force, plus_damping, smooth_force
from ..loads import force_at
from ..memory import refuse_memory

BRANCH_STACK = True  # takes the memory stack (kernels/stack.py) for many branches
ORDER = 2


def loop_for(scene):
    """The compiled time loop for ``scene``; ValueError if the scheme does not apply."""
    refuse_memory(scene, "verlet")
    if scene.mass is None:
        raise ValueError("'verlet' needs [mass]; a massless element is solved by 'implicit'")
    if scene.load.noise is not None:
        raise ValueError("'verlet' takes no white noise (its order 2 does not survive a white noise, and none was measured): use 'implicit' (backward Euler-Maruyama) or 'projected' (Euler-Maruyama)")
    return run


@kernel
def step(model, load, t, h, x, v, s, u, energy):
    m, k0, k3, c, k, eta, cs, friction, memory = model
    force0 = force_at(load, t)
    half, f0 = held_velocity(friction, 2.0 * m / h, v + 0.5 * h * (force0 - smooth_force(x, v, k0, k3, c) - s) / m, v)
    dx = h * half
    s = move_branches(k, eta, cs, u, dx, h, FLOW, energy)
    x = x + dx
    force1 = force_at(load, t + h)
    v1, f1 = held_velocity(friction, plus_damping(2.0 * m / h, c),
                           damped(half + 0.5 * h * (force1 - elastic_force(x, k0, k3) - s) / m, c, 0.5 * h, m), half)
    book(energy, 0.5 * (force0 + force1), dx, c, half)
    book_friction(energy, friction, f0, 0.5 * h, half)
    book_friction(energy, friction, f1, 0.5 * h, v1)
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
