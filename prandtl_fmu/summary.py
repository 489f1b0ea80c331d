"""A run of a scene reduced to a few numbers: what a sweep keeps per run.

:func:`summarize` runs a scene like :func:`driver.simulate` (the same steps
at the same times, bit for bit) but watches *every internal step*, so that
the peaks do not depend on the output grid, and keeps only the quantities
asked for (and, on request, the output grid itself: the rows ``simulate``
would return). :func:`summarize_many` does many runs at once: the runs that
share a structure go through one compiled call per stepper
(``kernels/batch.py``, at most :data:`BATCH_BYTES` of state and history per
call); Python runs per run only to check and pack it, never per step.

The quantities (``SUMMARIES``):

* ``max_abs_x`` (m), ``max_abs_v`` (m/s), ``max_abs_reaction`` (N): the
  largest |x|, |v|, |reaction| at t = 0 and after every internal step (for
  ``exact``, whose steps are the output rows, after every output row);
* ``final_x``, ``final_v``, ``final_reaction``: the state at stop_time;
* ``work`` (J): the work of the load F (and of a moving ground, ``[friction]
  belt_velocity``); ``dissipated_sliders``, ``dissipated_damper`` (the
  dashpot and the branches' series dashpots), ``dissipated_friction`` (the
  friction of the mass on the ground) and their sum ``dissipated`` (J) over
  the run;
* ``loop_area`` (J): the energy dissipated over the last period 2 pi / omega
  of a harmonic load (the last whole number of steps closest to it): once the
  loop closes (the steady state), the area of the (x, reaction) loop;
* ``late_mean_x``, ``late_mean_v``, ``late_mean_square_x``,
  ``late_mean_square_v``: the time averages (2/T) int_{T/2}^{T} y(t) dt of
  y = x, v, x^2, v^2 over the run's second half (T = stop_time), by the
  trapezoidal rule on the output rows (the piecewise-linear y between rows,
  cut at T/2): for Monte Carlo of stationary laws (a linear oscillator under
  white noise sigma xi: <x^2> -> sigma^2/(2ck), <v^2> -> sigma^2/(2cm)). They
  are the output grid's, not every internal step's: an output interval much
  shorter than the correlation time 2m/c makes them the time averages. Asked
  for only by name (:func:`default_summaries` leaves them out: a run keeps its
  output rows in memory for them).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Iterable, Optional

import numpy as np

from .compiled import choose_branch_kernel, compile_loop, compile_model, friction_model, _smooth_model
from .stepping import ElementError, OutputGrid, initial_state, _failure
from .memory import NONE as NO_MEMORY, present as memory_effects
from .kernels import batch as packed
from .loads import HarmonicLoad
from .resources import check_memory
from .scene import Scene
from .stability import StabilityWarning, stability_problem
from .steppers import get_stepper

SUMMARIES = {
    "max_abs_x": "largest |x| over every internal step (m)",
    "max_abs_v": "largest |v| over every internal step (m/s)",
    "max_abs_reaction": "largest |reaction| over every internal step (N)",
    "final_x": "x at stop_time (m)",
    "final_v": "v at stop_time (m/s)",
    "final_reaction": "reaction at stop_time (N)",
    "work": "work of the load (and of a moving ground) over the run (J)",
    "dissipated": "energy dissipated by the sliders, the dashpots and the friction on the mass over the run (J)",
    "dissipated_sliders": "energy dissipated by the sliders over the run (J)",
    "dissipated_damper": "energy dissipated by the dashpot and the branches' series dashpots over the run (J)",
    "dissipated_friction": "energy dissipated by the friction of the mass on the ground over the run (J)",
    "loop_area": "energy dissipated over the last period of the harmonic load (J): the steady loop's area",
    "late_mean_x": "time average of x over the run's second half, on the output rows (m)",
    "late_mean_v": "time average of v over the run's second half, on the output rows (m/s)",
    "late_mean_square_x": "time average of x^2 over the run's second half, on the output rows (m^2)",
    "late_mean_square_v": "time average of v^2 over the run's second half, on the output rows (m^2/s^2)",
}
# Quantities from the output rows (the run keeps them in memory); never in the default set, so that a sweep
# file without [keep] summary keeps its columns and its cost.
LATE_SUMMARIES = ("late_mean_x", "late_mean_v", "late_mean_square_x", "late_mean_square_v")
ENERGY_SUMMARIES = ("work", "dissipated", "dissipated_sliders", "dissipated_damper", "dissipated_friction",
                    "loop_area")
HISTORY_COLUMNS = ("time", "x", "v", "reaction")

# The branch states and output rows of one compiled call hold at most this many bytes (a continuum's state
# takes 160 kB: 400 runs a call; a paper-scene run without history 1 kB).
BATCH_BYTES = 64 << 20


def summary_problem(scene: Scene, stepper: str, quantities: Iterable[str]) -> Optional[str]:
    """Why ``quantities`` cannot be had from ``scene`` run with ``stepper``, or None."""
    quantities = list(quantities)
    unknown = [q for q in quantities if q not in SUMMARIES]
    if unknown:
        return f"unknown summary {unknown[0]!r} (known: {', '.join(SUMMARIES)})"
    if "loop_area" in quantities:
        load = scene.load
        if not isinstance(load, HarmonicLoad) or load.omega == 0:
            return "loop_area needs a harmonic load with omega != 0 (it is the energy dissipated over its last period)"
        if 2 * math.pi / abs(load.omega) > scene.solver.stop_time:
            return (f"loop_area: the run ({scene.solver.stop_time!r} s) is shorter than one period of the load "
                    f"({2 * math.pi / abs(load.omega):.6g} s)")
    return None


def default_summaries(scene: Scene, stepper: str) -> list:
    """Every quantity of SUMMARIES that ``scene`` with ``stepper`` gives, but the LATE_SUMMARIES (asked for by
    name only)."""
    return [q for q in SUMMARIES if q not in LATE_SUMMARIES and summary_problem(scene, stepper, [q]) is None]


def summarize(scene: Scene, stepper: Optional[str] = None, quantities: Optional[Iterable[str]] = None, *,
              history: bool = False, branch_kernel: Optional[str] = None) -> dict:
    """Run ``scene`` and return ``{quantity: float}`` (see the module docstring; default: every quantity that
    applies), plus the output grid as arrays ``time, x, v, reaction`` with ``history``.

    Warns (:class:`stability.StabilityWarning`) as :func:`driver.simulate` does; ValueError if a quantity or
    the stepper does not apply; :class:`driver.ElementError` if a step cannot be taken.
    """
    name = stepper or scene.solver.stepper
    quantities = default_summaries(scene, name) if quantities is None else list(quantities)
    [outcome] = summarize_many([(scene, name)], quantities, history=history, branch_kernel=branch_kernel)
    if outcome.warning:
        warnings.warn(outcome.warning, StabilityWarning, stacklevel=2)
    if outcome.error is not None:
        raise outcome.error
    return outcome.values


@dataclass
class Outcome:
    """One run of :func:`summarize_many`: its ``values`` (as :func:`summarize` returns them) or the ``error``
    that stopped it (ValueError, ElementError), and its stability ``warning`` ("" if none)."""

    values: Optional[dict] = None
    error: Optional[Exception] = None
    warning: str = ""


def summarize_many(runs, quantities: Iterable[str], *, history: bool = False,
                   branch_kernel: Optional[str] = None) -> list:
    """:func:`summarize` for each ``(scene, stepper)`` of ``runs``, the same numbers bit for bit, as a list of
    :class:`Outcome` (a failed run does not stop the others).

    The runs of one structure (stepper loop, effects present, branch kernel)
    are packed into a batch and run by one compiled call (``kernels/batch.py``).
    A run whose load has a white noise, or with effects with memory, goes alone through
    :func:`driver.simulate`, every step an output row (:func:`_noisy_run`: the batch packs neither a noise nor a
    memory's state).
    """
    quantities = list(quantities)
    energy = any(q in ENERGY_SUMMARIES for q in quantities)
    outcomes = [Outcome() for _ in runs]
    batches, branch_models = {}, {}
    for position, (scene, name) in enumerate(runs):
        if getattr(scene.load, "noise", None) is not None or memory_effects(scene):
            _noisy_run(outcomes[position], scene, name, quantities, history, branch_kernel)
            continue
        try:
            job = _Job(scene, name, quantities, history, branch_kernel, branch_models)
        except (ValueError, ElementError) as exc:
            outcomes[position].error = exc
            continue
        outcomes[position].warning = job.warning
        key = job.structure()
        batch = batches.get(key)
        if batch is None:
            batch = batches[key] = _Batch(job, energy)
        batch.add(position, job)
        if batch.nbytes >= BATCH_BYTES:
            batch.run(outcomes, quantities)
            del batches[key]
    for batch in batches.values():
        batch.run(outcomes, quantities)
    return outcomes


class _Job:
    """One run, checked and compiled to kernel form: what :class:`_Batch` packs."""

    def __init__(self, scene: Scene, name: str, quantities: list, history: bool, branch_kernel: Optional[str],
                 branch_models: dict):
        problem = summary_problem(scene, name, quantities)
        if problem:
            raise ValueError(f"{scene.source}: {problem}")
        self.scene, self.name = scene, name
        module = get_stepper(name)
        loop = compile_loop(scene, name)
        self.kernel = module.SUMMARY_LOOPS[loop]
        solver = scene.solver
        h, per_row = solver.step, solver.steps_per_output
        if getattr(module, "STEP_IS_OUTPUT", False):
            h, per_row = solver.output_interval, 1
        self.h, self.per_row = h, per_row
        problem = stability_problem(scene, name, h)
        self.warning = f"{scene.source}: {problem}" if problem else ""
        self.model = _smooth_model(scene) + _branch_model(scene, name, branch_kernel, branch_models) \
            + (friction_model(scene), NO_MEMORY)  # (a run with memory goes alone: _noisy_run)
        self.load = scene.load.compile()
        self.x, self.v, self.u = initial_state(scene, self.model, self.load)

        self.grid = grid = OutputGrid(solver.stop_time, solver.output_interval, solver.step)
        self.full_steps = grid.full * per_row
        # the last, shorter output interval up to stop_time, on the step grid as the driver takes it
        self.tail_steps, self.rest = grid.tail(h)
        # loop_area: the account after step `mark`, one period of the load before the end
        self.mark = -1
        if "loop_area" in quantities:
            period = 2 * math.pi / abs(scene.load.omega)
            self.mark = min(self.full_steps, max(0, round((solver.stop_time - period) / h)))
        self.history = history  # the rows returned; kept in memory also for the late averages
        self.history_rows = grid.rows if history or any(q in LATE_SUMMARIES for q in quantities) else 0
        if self.history_rows:
            check_memory(24.0 * grid.rows, f"{scene.source}: the history ({grid.rows} rows)",
                         hint="keep summaries only")

    def structure(self):
        """What fixes the compiled code of a run: its loop, the effects present, the branch kernel."""
        k = self.model[4]
        kind = None if k is None else "continuum" if isinstance(k, tuple) else k.ndim
        return (self.kernel, tuple(value is None for value in self.model[:4] + self.model[6:]), kind,
                self.u is None)


def _branch_model(scene: Scene, name: str, branch_kernel: Optional[str], known: dict):
    """The branch part ``(k, eta, c)`` of :func:`driver.compile_model`, shared by the runs whose branches are
    equal (the kernels only read it): a sweep that varies the load prepares its memory stack once."""
    branches = scene.branches
    if branches is None or branches.continuum:
        return compile_model(scene)[4:7]
    key = (name, branch_kernel, branches.stiffness.tobytes(), branches.yield_displacement.tobytes(),
           branches.u0.tobytes(), None if branches.damping is None else branches.damping.tobytes())
    if key not in known:
        known[key] = compile_model(scene, branch_kernel or choose_branch_kernel(scene, name))[4:7]
    return known[key]


class _Batch:
    """Runs of one structure packed into the flat arrays of ``kernels/batch.py``."""

    def __init__(self, job: _Job, energy: bool):
        self.kernel = job.kernel
        self.template = (job.model, job.u, np.zeros(4) if energy else None)
        self.jobs, self.positions = [], []
        self.real, self.index = [], []
        self.branch, self.eta, self.damping, self.tables, self.states = [], [], [], [], []
        self.ends = {"branch": 0, "table": 0, "state": 0, "history": 0}
        self.packed = {}  # id of a branch parameter array -> its range in branch_data
        self.nbytes = 0

    def _extend(self, part: str, size: int):
        start = self.ends[part]
        self.ends[part] = start + size
        return start, start + size

    def add(self, position: int, job: _Job):
        m, k0, k3, c, k, eta, cs, friction, memory = job.model
        kind, offset, amplitude, omega, table_time, table_force = job.load
        real = [m, k0, k3, c, job.x, job.v, job.h, job.rest, offset, amplitude, omega]
        real += list(friction) if friction is not None else [0.0] * 4
        real[:4] = [0.0 if value is None else value for value in real[:4]]
        branch_a = branch_b = rows = cols = 0
        if k is not None:
            values = k[0] if isinstance(k, tuple) else k
            rows, cols = (values.shape if values.ndim == 2 else (1, values.shape[0]))
            if id(values) not in self.packed:  # runs that share their branches (_branch_model) share one copy
                self.packed[id(values)] = self._extend("branch", values.size)
                self.branch.append(values.ravel())
                self.eta.append(eta if eta is not None else np.zeros(values.size))
                self.damping.append(cs if cs is not None else np.zeros(values.size))
            branch_a, branch_b = self.packed[id(values)]
        table_a, table_b = self._extend("table", table_time.shape[0])
        _, table_c = self._extend("table", table_force.shape[0])
        self.tables += [table_time, table_force]
        state_a = state_b = 0
        if job.u is not None:
            state_a, state_b = self._extend("state", job.u.shape[0])
            self.states.append(job.u)
        history_a, history_b = self._extend("history", 3 * job.history_rows)
        self.real.append(real)
        self.index.append([kind, job.full_steps, job.per_row, job.mark, job.tail_steps, int(job.grid.last_is_short),
                           branch_a, branch_b, rows, cols, table_a, table_b, table_c, state_a, state_b,
                           history_a, history_b])
        self.jobs.append(job)
        self.positions.append(position)
        self.nbytes += 8 * (state_b - state_a + history_b - history_a) + 8 * (packed.REAL_COLUMNS + packed.INDEX_COLUMNS)

    def run(self, outcomes: list, quantities: list):
        """One compiled call for every run of the batch; their outcomes into ``outcomes``."""
        count = len(self.jobs)

        def flat(parts):
            return np.ascontiguousarray(np.concatenate(parts), dtype=float) if parts else np.zeros(0)

        real = np.array(self.real, dtype=float).reshape(count, packed.REAL_COLUMNS)
        index = np.array(self.index, dtype=np.int64).reshape(count, packed.INDEX_COLUMNS)
        history = np.zeros(self.ends["history"])
        accounts, marks = np.zeros((count, 4)), np.zeros((count, 4))
        out = np.zeros((count, packed.OUT_COLUMNS))
        self.kernel(self.template, (real, index, flat(self.branch), flat(self.eta), flat(self.damping), flat(self.tables),
                                    flat(self.states), history, accounts, marks, out))
        for j, (job, position) in enumerate(zip(self.jobs, self.positions)):
            row = out[j]
            if not math.isnan(row[packed.FAILED_AT]):
                outcomes[position].error = _failure(job.scene, job.name, job.load, row[packed.FAILED_AT],
                                                    row[packed.FAILED_STEP])
                continue
            account, mark = accounts[j], marks[j]
            values = {
                "max_abs_x": row[packed.PEAK_X], "max_abs_v": row[packed.PEAK_V],
                "max_abs_reaction": row[packed.PEAK_REACTION], "final_x": row[packed.FINAL_X],
                "final_v": row[packed.FINAL_V], "final_reaction": row[packed.FINAL_REACTION],
                "work": account[0], "dissipated_sliders": account[1], "dissipated_damper": account[2],
                "dissipated_friction": account[3], "dissipated": account[1] + account[2] + account[3],
                "loop_area": (account[1] + account[2] + account[3]) - (mark[1] + mark[2] + mark[3]),
            }
            if job.history_rows:
                written = int(row[packed.ROWS_WRITTEN])
                if written != job.history_rows:  # a broken invariant, never a short history
                    raise RuntimeError(f"summary: {written} of {job.history_rows} output rows written")
                a, b = index[j, packed.HISTORY_A], index[j, packed.HISTORY_B]
                rows = history[a:b].reshape(-1, 3)
                times = job.grid.times(0, job.grid.rows)
                if any(q in LATE_SUMMARIES for q in quantities):
                    values.update(late_averages(times, rows[:, 0], rows[:, 1]))
            result = {q: float(values[q]) for q in quantities}
            if job.history:
                result.update(time=times, x=rows[:, 0].copy(), v=rows[:, 1].copy(), reaction=rows[:, 2].copy())
            outcomes[position].values = result


def late_weights(time: np.ndarray) -> np.ndarray:
    """w such that w @ y = (2/T) int_{T/2}^{T} y dt, T = time[-1], for the piecewise-linear y through the rows
    ``(time, y)`` (time increasing from 0): the trapezoidal rule on the rows after T/2 and on the piece cut at
    T/2, whose value there is interpolated between its two rows. The same weights for x, v, x^2, v^2."""
    stop = time[-1]
    half = 0.5 * stop
    after = int(np.searchsorted(time, half, side="right"))  # the first row after T/2 (row 0 is at 0 <= T/2)
    weights = np.zeros(time.size)
    widths = np.diff(time[after - 1:])
    widths[0] = time[after] - half  # the cut piece: [T/2, time[after]]
    weights[after - 1:-1] += 0.5 * widths
    weights[after:] += 0.5 * widths
    # the cut piece's left end is the interpolated y(T/2) = (1 - theta) y[after - 1] + theta y[after]
    theta = (half - time[after - 1]) / (time[after] - time[after - 1])
    left = weights[after - 1]
    weights[after - 1] = left * (1 - theta)
    weights[after] += left * theta
    return weights / (stop - half)


def late_average(time: np.ndarray, y: np.ndarray) -> float:
    """(2/T) int_{T/2}^{T} y dt on the rows ``(time, y)`` (:func:`late_weights`)."""
    return float(late_weights(time) @ y)


def late_averages(time: np.ndarray, x: np.ndarray, v: np.ndarray) -> dict:
    """The LATE_SUMMARIES of a run's output rows."""
    weights = late_weights(time)
    return {"late_mean_x": float(weights @ x), "late_mean_v": float(weights @ v),
            "late_mean_square_x": float(weights @ (x * x)), "late_mean_square_v": float(weights @ (v * v))}


_EVERY_STEP = ("max_abs_x", "max_abs_v", "max_abs_reaction", "loop_area")


def _noisy_run(outcome: Outcome, scene: Scene, name: str, quantities: list, history: bool,
               branch_kernel: Optional[str]) -> None:
    """One run with a white noise or effects with memory (``kernels/batch.py`` packs neither): :func:`driver.simulate` with
    an output row after every step when a peak or loop_area is asked for (the same steps t_p = p h as the
    scene's own grid, so the same numbers), else on the scene's grid; the peaks, the final state and the
    energies from those rows, the late averages and the history from the rows of the scene's output grid."""
    from .driver import simulate
    from .stepping import energy_columns

    try:
        problem = summary_problem(scene, name, quantities)
        if problem:
            raise ValueError(f"{scene.source}: {problem}")
        solver = scene.solver
        h = solver.step
        problem = stability_problem(scene, name, h)
        outcome.warning = f"{scene.source}: {problem}" if problem else ""
        energy = any(q in ENERGY_SUMMARIES for q in quantities)
        # the peaks and the loop's mark need every step; the rest (the final state, the account at the end,
        # the late averages) the scene's own rows
        every_step = any(q in _EVERY_STEP for q in quantities)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StabilityWarning)  # kept in outcome.warning
            result = simulate(scene.with_solver(stepper=name, output_interval=h) if every_step else scene, name,
                              energy=energy, progress=False, branch_kernel=branch_kernel)
    except (ValueError, ElementError) as exc:
        outcome.error = exc
        return
    grid = OutputGrid(solver.stop_time, solver.output_interval, h)
    if every_step:
        rows = np.concatenate((np.arange(grid.full + 1) * grid.per_row,
                               [result.x.size - 1] if grid.last_is_short else [])).astype(np.int64)
    else:
        rows = np.arange(result.x.size)
    values = {"max_abs_x": np.abs(result.x).max(), "max_abs_v": np.abs(result.v).max(),
              "max_abs_reaction": np.abs(result.reaction).max(), "final_x": result.x[-1], "final_v": result.v[-1],
              "final_reaction": result.reaction[-1]}
    if energy:
        e = result.energy
        friction = e["dissipated_friction"] if "dissipated_friction" in energy_columns(scene) else np.zeros(1)
        total = e["dissipated_sliders"] + e["dissipated_damper"] + (friction if friction.size > 1 else 0.0)
        values.update(work=e["work"][-1], dissipated_sliders=e["dissipated_sliders"][-1],
                      dissipated_damper=e["dissipated_damper"][-1], dissipated_friction=friction[-1],
                      dissipated=total[-1])
        if "loop_area" in quantities:
            period = 2 * math.pi / abs(scene.load.omega)
            mark = min(grid.full * grid.per_row, max(0, round((solver.stop_time - period) / h)))
            values["loop_area"] = total[-1] - total[mark]
    times = grid.times(0, grid.rows)
    if any(q in LATE_SUMMARIES for q in quantities):
        values.update(late_averages(times, result.x[rows], result.v[rows]))
    outcome.values = {q: float(values[q]) for q in quantities}
    if history:
        outcome.values.update(time=times, x=result.x[rows], v=result.v[rows], reaction=result.reaction[rows])
