"""``projected``: the scheme of Bastien & Schatzman (M2AN 2002, eq. 5.1).

    U^{p+1} = proj_K( U^p + h f(t_p, U^p) ),   U = (x, v, u_1..u_n),
    K = R x R x [-eta_1, eta_1] x ... x [-eta_n, eta_n]

that is, with every force taken at the *old* state and the load at t_p:

    a     = ( F(t_p) - k0 x - k3 x^3 - c v - sum_i k_i u_i ) / m
    u_i  <- clip(u_i + h v, -eta_i, eta_i)
    x    <- x + h v
    v    <- v + h a

The papers call this "the implicit Euler scheme" because it is implicit in the
multivalued term d psi_K only (the projection); it is explicit in everything
else. (Our ``implicit`` stepper is implicit in every term.)

Friction on the mass (``[friction]``, eq. 14 and 16 of 004) joins the
multivalued term: v <- v_b + w1 with w1 = sign(q) max(|q| - h alpha / m, 0),
q = v + h a - v_b - h Psi(v - v_b) / m (the sign graph implicit, Stribeck's
smooth part Psi explicit: ``kernels/friction.py``), so the mass sticks
exactly. Its energy account books the friction at the new velocity (so that
the dissipation never decreases) while x moves at the old one: with friction
the balance residual may take either sign. Series dashpots (``[branches] c``): u_i <- clip(u_i + h (v - k_i u_i / c_i)),
stable for h k_i / c_i <= 2 (``kernels/series.py``).

Order 1, with a constant uniform in the number of branches n in the max norm
(Bastien & Schatzman, Prop. 6.3 and eq. 7.20).

Stability: explicit Euler on the smooth part. In the elastic regime it
multiplies the oscillator's energy by exactly 1 + (omega h)^2 per step
(omega^2 = stiffness / m): the energy balance residual is never positive,
the scheme creates energy, O(h) over a fixed time. The amplitude doubles
within one period once omega h > ln(2)/pi ~ 0.22; :mod:`prandtl_fmu.stability`
warns before such a run.

White noise (F + sigma xi(t)): Euler-Maruyama, the impulse sigma (B(t_{p+1}) - B(t_p)) added to the
momentum, v <- v + h a + sigma dB / m (before the friction's projection), and to the massless element's
motion, x <- x + h v + sigma dB / c; the work booked is that of the step's mean force F + sigma dB / h.
Strong order: about 1 measured with 7 branches, friction and series dashpots (``docs/white-noise.md``).

Effects with memory (``memory/``): their forces at the old state join the load (the delay's y(t_p - tau)
from its buffer, the history's sum_j w_j z_j, Dahl's F_d), then they move along the step (z_j integrated
exactly with x linear, F_d by the exact Dahl operator over h v).

Massless element with a dashpot (no [mass]): the same scheme on
c x' = F - k0 x - k3 x^3 - sum_i k_i u_i, i.e. x <- x + h v with the rate
v = (F(t_p) - k0 x - k3 x^3 - sum_i k_i u_i) / c of the old state; stable
while h (k0 + sum_i k_i) / c <= 2. Without a dashpot the massless element is
quasi-static and has no explicit scheme: use ``implicit``.
"""
from .._jit import kernel
from ..kernels.energy import book
from ..kernels.batch import summary_loop
from ..kernels.loop import time_loop
from ..kernels.friction import book_friction, held_velocity
from ..kernels.series import EXPLICIT, move_branches
from ..kernels.smooth import elastic_force, smooth_force
from ..loads import force_at, impulse, with_noise
from ..memory import force_now, record

BRANCH_STACK = True  # takes the memory stack (kernels/stack.py) for many branches
ORDER = 1


def loop_for(scene):
    """The compiled time loop for ``scene``; ValueError if the scheme does not apply."""
    if scene.mass is not None:
        return run
    if scene.has_dashpot:
        return run_massless
    raise ValueError("'projected' is explicit and needs [mass] or a [damper] with c > 0; a massless element "
                     "without a dashpot is quasi-static: use 'implicit'")


@kernel
def step(model, load, t, h, x, v, s, u, energy):
    m, k0, k3, c, k, eta, cs, friction, memory = model
    force = force_at(load, t)
    force = with_noise(load, force, force + impulse(load, t, h) / h)  # the mean force over the step
    force = force - force_now(memory, t, x, v)  # the load and the memory forces of the old state
    a = (force - smooth_force(x, v, k0, k3, c) - s) / m
    dx = h * v
    book(energy, force, dx, c, v)
    v1, f = held_velocity(friction, m / h, v + h * a, v)
    book_friction(energy, friction, f, h, v1)
    s = move_branches(k, eta, cs, u, dx, h, EXPLICIT, energy)
    record(memory, t, h, x, v, x + dx, v1, dx)
    return x + dx, v1, s


@kernel
def step_massless(model, load, t, h, x, v, s, u, energy):
    """Massless element with a dashpot: ``v`` is the rate of the current state."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    force = force_at(load, t) - force_now(memory, t, x, v)
    kick = impulse(load, t, h)
    dx = with_noise(load, h * v, h * v + kick / c)  # c (x1 - x) = h c v + sigma dB
    book(energy, with_noise(load, force, force + kick / h), dx, c, with_noise(load, v, dx / h))
    s = move_branches(k, eta, cs, u, dx, h, EXPLICIT, energy)
    record(memory, t, h, x, v, x + dx, dx / h, dx)
    x = x + dx
    return x, (force_at(load, t + h) - elastic_force(x, k0, k3) - s - force_now(memory, t + h, x, 0.0)) / c, s


_loop = time_loop(step)


@kernel
def run(model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy):
    """The time loop (``kernels/loop.py``) over :func:`step`, cached."""
    return _loop(model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy)


_loop_massless = time_loop(step_massless)


@kernel
def run_massless(model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy):
    """The time loop (``kernels/loop.py``) over :func:`step_massless`, cached."""
    return _loop_massless(model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy,
                          out_energy)


_summary = summary_loop(step)


@kernel
def run_summary(template, batch):
    """The summary loop (``kernels/batch.py``) over :func:`step`, cached."""
    _summary(template, batch)


_summary_massless = summary_loop(step_massless)


@kernel
def run_summary_massless(template, batch):
    """The summary loop (``kernels/batch.py``) over :func:`step_massless`, cached."""
    _summary_massless(template, batch)


# the summary loop of each time loop that loop_for gives
SUMMARY_LOOPS = {run: run_summary, run_massless: run_summary_massless}
