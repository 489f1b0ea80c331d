"""The time loop: ``steps_per_row`` steps per output row, for every row of ``out``.

Each stepper builds it around its own step (``time_loop(step)``, a closure:
the step is a compile-time constant, not a run-time value) and wraps it in
``run``, a one-line cached kernel into which numba inlines it. The machine
code of ``run`` holds the loop, so a later process loads it from the cache and
compiles nothing. The closure itself is not cached (numba keys a closure's
cache entry on a pickle of the functions it closes over, which is not stable
across processes); a loop taking the step as an argument could not be cached
either (the dispatcher would be a run-time Python object: "dynamic globals").

Each closure gets a name of its own, made from its step's module and name.
numba names a compiled function by module, qualified name, argument types and
a counter of compilations *in the process* ("loop$6"; its own source says the
name "*must* be unique, else the wrong function can be chosen at link time"),
and the machine code of a closure was linked into every ``run`` that called it
(it is inlined now, so it has no machine code of its own; the names stay unique).
With one qualified name for all the closures, the loops of two steppers
compiled first in two different processes (a test's subprocess, a dask
worker) both got the name ``time_loop.<locals>.loop$6``. Once, in CI, a
process whose cache had been filled that way saw ``projected`` return exactly
the numbers of ``implicit``; that clash is the explanation we have (not
reproduced on demand since). tests/steppers/test_physics.py checks the names and runs
every stepper from a cache filled one stepper per process.
"""
import numpy as np

from .._jit import generic_kernel
from .energy import kinetic, stored
from .play import branch_force, record_elongations
from .friction import reaction
from ..memory import prepare


def time_loop(step):
    """The time loop over the compiled ``step``, compiled (not cached on its own: see above)."""

    def loop(model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy):
        """Advance ``out.shape[0] * steps_per_row`` steps of size ``h`` with ``step``, from step number
        ``first_step``.

        Step number p starts at t_p = t_base + p h, computed from p alone: the
        load a step sees does not depend on how a run is cut into calls (output
        rows, chunks of rows, communication steps).

        After every ``steps_per_row`` steps, row j of ``out`` (shape (rows, 3))
        receives x, v and the reaction, row j of ``out_u`` (shape (rows, n); (rows, 0) or
        ``None``: not asked for) the elongations and row j of ``out_energy`` (shape (rows, 6);
        (rows, 0) or ``None``) the kinetic and stored energy and the account ``energy``
        (work, dissipated by the sliders, by the dashpots, by the friction on the mass). ``u`` and ``energy``
        are updated in place. Returns ``(x, v, steps)``: ``steps`` is the number
        of steps taken, fewer than asked if a step failed (non-finite result; the
        state returned is the one before that step).
        """
        m, k0, k3, c, k, eta, cs, friction, memory = model
        s = branch_force(k, u)
        prepare(memory, h)  # the memory's coefficients of h, once (memory/__init__.py)
        p = 0
        for j in range(out.shape[0]):
            for _ in range(steps_per_row):
                x1, v1, s1 = step(model, load, t_base + (first_step + p) * h, h, x, v, s, u, energy)
                if not (abs(x1) < np.inf and abs(v1) < np.inf):
                    return x, v, p
                x, v, s = x1, v1, s1
                p += 1
            out[j, 0] = x
            out[j, 1] = v
            out[j, 2] = reaction(model, load, t_base + (first_step + p) * h, x, v, s)
            if out_u is not None:
                record_elongations(k, u, out_u[j])
            if out_energy is not None:
                if energy is not None:  # (rows, 6) with the account; (rows, 0) when not asked for
                    if out_energy.shape[1] > 0:
                        out_energy[j, 0] = kinetic(m, v)
                        out_energy[j, 1] = stored(x, k0, k3, k, u)
                        out_energy[j, 2] = energy[0]
                        out_energy[j, 3] = energy[1]
                        out_energy[j, 4] = energy[2]
                        out_energy[j, 5] = energy[3]
        return x, v, p

    loop.__qualname__ = f"time_loop.<locals>.loop_{step.__module__.rpartition('.')[2]}_{step.__name__}"
    return generic_kernel(loop)
