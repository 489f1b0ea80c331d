"""A run of a scene reduced to a few numbers: what a sweep keeps per run.

:func:`summarize` runs a scene like :func:`driver.simulate` (the same steps
at the same times, bit for bit) but watches *every internal step*, so that
the peaks do not depend on the output grid, and keeps only the quantities
asked for (and, on request, the output grid itself: the rows ``simulate``
would return). The steps run in compiled chunks; Python runs once per
chunk of up to :data:`_CHUNK_STEPS` steps.

The quantities (``SUMMARIES``):

* ``max_abs_x`` (m), ``max_abs_v`` (m/s), ``max_abs_reaction`` (N): the
  largest |x|, |v|, |reaction| at t = 0 and after every internal step (for
  ``exact``, whose steps are the output rows, after every output row);
* ``final_x``, ``final_v``, ``final_reaction``: the state at stop_time;
* ``work`` (J): the work of the load F; ``dissipated_sliders``,
  ``dissipated_damper`` and their sum ``dissipated`` (J) over the run;
* ``loop_area`` (J): the energy dissipated over the last period 2 pi / omega
  of a harmonic load (the last whole number of steps closest to it): once the
  loop closes (the steady state), the area of the (x, reaction) loop.
"""
from __future__ import annotations

import math
from typing import Iterable, Optional

import numpy as np

from .driver import (OutputGrid, choose_branch_kernel, compile_loop, compile_model, initial_state, integrate,
                     split_duration, _failure)
from .kernels.play import branch_force
from .kernels.smooth import smooth_force
from .loads import HarmonicLoad
from .scene import Scene
from .steppers import get_stepper

SUMMARIES = {
    "max_abs_x": "largest |x| over every internal step (m)",
    "max_abs_v": "largest |v| over every internal step (m/s)",
    "max_abs_reaction": "largest |reaction| over every internal step (N)",
    "final_x": "x at stop_time (m)",
    "final_v": "v at stop_time (m/s)",
    "final_reaction": "reaction at stop_time (N)",
    "work": "work of the load over the run (J)",
    "dissipated": "energy dissipated by the sliders and the dashpot over the run (J)",
    "dissipated_sliders": "energy dissipated by the sliders over the run (J)",
    "dissipated_damper": "energy dissipated by the dashpot over the run (J)",
    "loop_area": "energy dissipated over the last period of the harmonic load (J): the steady loop's area",
}
ENERGY_SUMMARIES = ("work", "dissipated", "dissipated_sliders", "dissipated_damper", "loop_area")
HISTORY_COLUMNS = ("time", "x", "v", "reaction")

# Steps of one compiled call (the per-step rows of a chunk take 24 bytes each: 6 MB).
_CHUNK_STEPS = 1 << 18


def summary_problem(scene: Scene, stepper: str, quantities: Iterable[str]) -> Optional[str]:
    """Why ``quantities`` cannot be had from ``scene`` run with ``stepper``, or None."""
    quantities = list(quantities)
    unknown = [q for q in quantities if q not in SUMMARIES]
    if unknown:
        return f"unknown summary {unknown[0]!r} (known: {', '.join(SUMMARIES)})"
    if any(q in ENERGY_SUMMARIES for q in quantities) and not getattr(get_stepper(stepper), "ENERGY_ACCOUNT", True):
        return f"stepper {stepper!r} keeps no energy account: drop {', '.join(q for q in quantities if q in ENERGY_SUMMARIES)}"
    if "loop_area" in quantities:
        load = scene.load
        if not isinstance(load, HarmonicLoad) or load.omega == 0:
            return "loop_area needs a harmonic load with omega != 0 (it is the energy dissipated over its last period)"
        if 2 * math.pi / abs(load.omega) > scene.solver.stop_time:
            return (f"loop_area: the run ({scene.solver.stop_time!r} s) is shorter than one period of the load "
                    f"({2 * math.pi / abs(load.omega):.6g} s)")
    return None


def default_summaries(scene: Scene, stepper: str) -> list:
    """Every quantity of SUMMARIES that ``scene`` with ``stepper`` gives."""
    return [q for q in SUMMARIES if summary_problem(scene, stepper, [q]) is None]


def summarize(scene: Scene, stepper: Optional[str] = None, quantities: Optional[Iterable[str]] = None, *,
              history: bool = False, branch_kernel: Optional[str] = None) -> dict:
    """Run ``scene`` and return ``{quantity: float}`` (see the module docstring; default: every quantity that
    applies), plus the output grid as arrays ``time, x, v, reaction`` with ``history``.

    ValueError if a quantity does not apply; :class:`driver.ElementError` if a step cannot be taken, as
    :func:`driver.simulate`.
    """
    name = stepper or scene.solver.stepper
    quantities = default_summaries(scene, name) if quantities is None else list(quantities)
    problem = summary_problem(scene, name, quantities)
    if problem:
        raise ValueError(f"{scene.source}: {problem}")
    loop = compile_loop(scene, name)
    solver = scene.solver
    h, per_row = solver.step, solver.steps_per_output
    if getattr(get_stepper(name), "STEP_IS_OUTPUT", False):
        h, per_row = solver.output_interval, 1
    model = compile_model(scene, branch_kernel or choose_branch_kernel(scene, name))
    load = scene.load.compile()
    x, v, u = initial_state(scene, model, load)
    m, k0, k3, c, k, eta = model
    account = np.zeros(3) if any(q in ENERGY_SUMMARIES for q in quantities) else None

    grid = OutputGrid(solver.stop_time, solver.output_interval)
    full_steps = (grid.rows - 1 - grid.last_is_short) * per_row
    watch = _Watch(x, v, smooth_force(x, v, k0, k3, c) + branch_force(k, u), per_row, grid.rows if history else 0)
    # loop_area: the account after step p0, one period of the load before the end
    p0 = None
    if "loop_area" in quantities:
        p0 = min(full_steps, max(0, round((solver.stop_time - 2 * math.pi / abs(scene.load.omega)) / h)))
    at_p0 = None

    def run(first, count, step, t_base=0.0):
        nonlocal x, v
        out = np.empty((count, 3))
        x, v, taken = integrate(loop, model, load, x, v, u, t_base, first, step, 1, out, None, account, None)
        if taken < count:
            raise _failure(scene, name, load, t_base + (first + taken) * step, step)
        watch.see(out)

    p = 0
    for end in sorted({full_steps} | ({p0} if p0 is not None else set())):
        while p < end:
            count = min(_CHUNK_STEPS, end - p)
            run(p, count, h)
            p += count
        if p == p0:
            at_p0 = account.copy()
    if grid.last_is_short:  # the last, shorter output interval up to stop_time, as driver._advance takes it
        last = grid.times(grid.rows - 2, 2)
        whole, rest = split_duration(last[1] - last[0], h)
        watch.row_every = 0  # the last row is the final state, whatever the steps
        for first in range(0, whole, _CHUNK_STEPS):
            run(full_steps + first, min(_CHUNK_STEPS, whole - first), h)
        if rest:
            run(0, 1, rest, t_base=(full_steps + whole) * h)
        watch.final_row()

    result = {}
    final = watch.last
    values = {
        "max_abs_x": watch.peak[0], "max_abs_v": watch.peak[1], "max_abs_reaction": watch.peak[2],
        "final_x": final[0], "final_v": final[1], "final_reaction": final[2],
    }
    if account is not None:
        values.update(work=account[0], dissipated_sliders=account[1], dissipated_damper=account[2],
                      dissipated=account[1] + account[2])
        if at_p0 is not None:
            values["loop_area"] = (account[1] + account[2]) - (at_p0[1] + at_p0[2])
    for q in quantities:
        result[q] = float(values[q])
    if history:
        rows = watch.history()
        result.update(time=grid.times(0, grid.rows), x=rows[:, 0], v=rows[:, 1], reaction=rows[:, 2])
    return result


class _Watch:
    """The peaks of |x|, |v|, |reaction| over every step seen, the last state, and (for a history) every
    ``row_every``-th step's state as an output row."""

    def __init__(self, x, v, reaction, row_every, rows):
        self.last = np.array([x, v, reaction], dtype=float)
        self.peak = np.abs(self.last)
        self.row_every, self.steps = row_every, 0
        self.rows = np.empty((rows, 3)) if rows else None
        self.filled = 0
        if self.rows is not None:
            self.rows[0] = self.last
            self.filled = 1

    def see(self, out):
        """The states after the next ``out.shape[0]`` steps."""
        np.maximum(self.peak, np.abs(out).max(axis=0), out=self.peak)
        self.last = out[-1].copy()
        if self.rows is not None and self.row_every:
            # rows after steps number row_every, 2 row_every, ... (counted over the whole run)
            first = (-self.steps - 1) % self.row_every
            picked = out[first::self.row_every]
            self.rows[self.filled:self.filled + picked.shape[0]] = picked
            self.filled += picked.shape[0]
        self.steps += out.shape[0]

    def final_row(self):
        if self.rows is not None:
            self.rows[self.filled] = self.last
            self.filled += 1

    def history(self):
        if self.filled != self.rows.shape[0]:  # a broken invariant, never a short history
            raise RuntimeError(f"summary: {self.filled} of {self.rows.shape[0]} output rows written")
        return self.rows
