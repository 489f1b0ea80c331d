"""``implicit``: backward Euler on the whole inclusion (every term at t_{p+1}).

Not to be confused with what the papers call "the implicit Euler scheme",
which is our ``projected`` (implicit only in the multivalued term). Here

    x1 = x + h v1
    m (v1 - v) / h = F(t_{p+1}) - k0 x1 - k3 x1^3 - c v1 - sum_i k_i u1_i
    u1_i = clip(u_i + h v1, -eta_i, eta_i)

With the increment w = x1 - x = h v1 this is one scalar equation G(w) = 0,

    G(w) = (m/h^2 + c/h) w - m v/h + k0 (x+w) + k3 (x+w)^3
           + sum_i k_i clip(u_i + w, -eta_i, eta_i) - F(t_{p+1}),

non-decreasing in w and smooth between the kinks w = ±eta_i - u_i, solved to
rounding by :func:`prandtl_fmu.kernels.increment.solve_increment`.

With many branches the branch force and its pieces come from the memory
stack (``kernels/stack.py``, :func:`~prandtl_fmu.kernels.stack.peek`): the
solve then costs O(log n) per kink it crosses instead of O(n).

The new position is x + w, except where w's rounding would swamp it (x1 decades below x in one step: a
force that dropped by 1e15 on a cubic spring, a coefficient changed by 1e100):
:func:`~prandtl_fmu.kernels.increment.settle` then finds the root in x1 itself.

Order 1. Unconditionally stable: with no load the discrete energy
m v^2/2 + k0 x^2/2 + k3 x^4/4 + sum_i k_i u_i^2/2 never increases, for any h,
and with a load the energy balance residual (work - dissipated - change of
energy) is never negative: the scheme dissipates m (v1 - v)^2/2
+ k0 w^2/2 + sum_i k_i (u1_i - u_i)^2/2 (+ a cubic term >= 0) per step.

Friction on the mass (``[friction]``): the friction law A(v1 - v_b) joins G,
all of it at the new velocity; the mass sticks exactly while |G(h v_b)| <=
alpha. With Stribeck's drop steeper than m/h + c the equation may have
several roots: the one of least slip is taken
(:func:`~prandtl_fmu.kernels.increment.solve_held_increment`), and the
stability check warns. Series dashpots in the branches (``[branches] c``):
u1_i = clip((u_i + w) / (1 + h k_i / c_i)), backward Euler on the
relaxation (``kernels/series.py``); G keeps its shape.

White noise (``[load] kind = "white_noise"`` or ``noise_intensity``: F + sigma xi(t)): backward
Euler-Maruyama, the noise's impulse over the step in the momentum and everything else as above,

    m (v1 - v) = h (F(t_{p+1}) - k0 x1 - k3 x1^3 - c v1 - sum_i k_i u1_i) + sigma (B(t_{p+1}) - B(t_p)),

i.e. F(t_{p+1}) replaced by the step's mean force F(t_{p+1}) + sigma dB / h in G: the branches' boxes and
the friction's sign stay implicit. Strong order: about 1 measured with 7 branches, with or without Coulomb
friction (the literature proves 1/2 for convex boxes; ``docs/white-noise.md``). Massless with a dashpot: c (x1 - x) = h (...) +
sigma dB, backward Euler-Maruyama on the first-order SDE (v is then the step's mean rate, of size
sigma / (c sqrt(h)): it has no limit as h -> 0); massless without one: refused (no solution).

Effects with memory (``memory/``): the delay's and the history's forces at t_{p+1} are affine in the new
state (the delayed instant interpolated inside the step when tau < h; the history's variables integrated
exactly with x linear over the step), so they join G as a constant and a stiffness; Dahl's force at t_{p+1} is
the exact Dahl operator over the increment w, a non-decreasing term of G solved by bracketing and Illinois
(``kernels/dahl_increment.py``). Their work is booked with the load's.

Massless element (no [mass]): the same equation without the m terms. With a
dashpot it is backward Euler on c x' = F - ...; without, the quasi-static
element F(t_{p+1}) = k0 x + k3 x^3 + sum_i k_i u_i, i.e. the inverse of the
Prandtl operator, solved exactly. When no equilibrium exists (no hardening
spring and |F| above the strength sum_i alpha_i: plastic collapse) the step
returns NaN and leaves the elongations untouched; the driver reports it.
"""
import numpy as np

from .._jit import kernel
from ..kernels.energy import book
from ..kernels.friction import book_friction
from ..kernels.increment import settle, solve_held_increment, solve_increment
from ..kernels.batch import summary_loop
from ..kernels.loop import time_loop
from ..kernels.series import BACKWARD, move_branches
from ..loads import force_at, impulse, with_noise
from ..memory import linear_force, record
from ..memory.dahl import after
from ..kernels.dahl_increment import solve_dahl_increment

BRANCH_STACK = True  # takes the memory stack (kernels/stack.py) for many branches
ORDER = 1


def loop_for(scene):
    """The compiled time loop for ``scene``; ValueError for the continuum."""
    if scene.branches is not None and scene.branches.continuum:
        # the continuum's force is smooth (not piecewise linear) in the increment where branches
        # yield one after the other: the exact scalar solve does not apply
        raise ValueError("'implicit' solves a piecewise linear equation and the continuum yields smoothly: use "
                         "'verlet' (order 2), 'symplectic' or 'projected'")
    if scene.load.noise is not None and scene.mass is None and not scene.has_dashpot:
        raise ValueError("a white noise on a massless element without a dashpot has no solution (the equilibrium "
                         "would follow a force of infinite variance): add [mass] or a [damper]")
    return run


@kernel
def step(model, load, t, h, x, v, s, u, energy):
    m, k0, k3, c, k, eta, cs, friction, memory = model
    force = force_at(load, t + h)
    force = with_noise(load, force, force + impulse(load, t, h) / h)  # the mean force over the step
    linear = _plus_damping(_inertia(m, h), c, h)
    kept, stiffer = linear_force(memory, t, h, x, v)  # the delay's and the history's force: kept + stiffer w
    dahl = memory[2]
    if linear + stiffer < 0.0:  # a negative memory stiffness beyond the inertia's: no unique step (refused)
        return np.nan, np.nan, s
    offset = _momentum(m, v, h) - force + kept
    w, v1, f = _increment(friction, dahl, x, linear + stiffer, offset, k0, k3, k, eta, cs, u, h)
    if not abs(w) < np.inf:  # no equilibrium: plastic collapse
        return np.nan, np.nan, s
    dahl_force = _dahl_after(dahl, w)
    # the new position, settled where w's rounding swamps it; the friction's and Dahl's forces at w are
    # constants of the equation below w's rounding
    x1 = settle(w, x, linear + stiffer, offset - f + dahl_force, k0, k3, k, eta, cs, u, h)
    book(energy, force - kept - stiffer * w - dahl_force, w, c, v1)  # the load's and the memory's work
    book_friction(energy, friction, f, h, v1)
    s = move_branches(k, eta, cs, u, w, h, BACKWARD, energy)
    record(memory, t, h, x, v, x1, v1, w)
    return x1, v1, s


@kernel
def _dahl_after(dahl, w):
    """The Dahl force at the step's end (0 without [dahl])."""
    if dahl is None:
        return 0.0
    return after(dahl, dahl[1][0], w)[0]


@kernel
def _increment(friction, dahl, x, linear, offset, k0, k3, k, eta, cs, u, h):
    """(w, v1, f): the increment, the new velocity and the friction force on the mass (0 without friction)."""
    if dahl is not None:  # (never with [friction]: the scene refuses both)
        w = solve_dahl_increment(dahl, x, linear, offset, k0, k3, k, eta, cs, u, h)
        return w, w / h, 0.0
    if friction is None:
        w = solve_increment(x, linear, offset, k0, k3, k, eta, cs, u, h)
        return w, w / h, 0.0
    w, resisted, stuck = solve_held_increment(x, linear, offset, k0, k3, k, eta, cs, u, h, friction)
    if stuck:
        return w, friction[3], -resisted  # exactly the belt's velocity (w / h may differ by an ulp)
    return w, w / h, -resisted


@kernel
def _inertia(m, h):
    """m / h^2; 0 for a massless element."""
    if m is None:
        return 0.0
    return m / (h * h)


@kernel
def _momentum(m, v, h):
    """-m v / h; 0 for a massless element."""
    if m is None:
        return 0.0
    return -m * v / h


@kernel
def _plus_damping(value, c, h):
    """value + c / h; just value without a dashpot."""
    if c is None:
        return value
    return value + c / h


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
