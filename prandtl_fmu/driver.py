"""The batch driver: joins a scene, a stepper and a time grid.

:func:`simulate` runs a scene from t = 0 to its stop time and returns the
output grid as arrays (:class:`Result`); :func:`simulate_chunks` streams the
same rows in pieces of bounded memory (what the CLI writes). A network scene
goes to the network's own driver (``network/driver.py``).

Both call :func:`stepping.integrate`, which runs the stepper's compiled time
loop (``kernels/loop.py``); Python runs once per chunk of output rows, never
once per step. The same element as a stateful object, advanced under a held
force (what an FMU runs), is :class:`element.Element`.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from time import perf_counter
from typing import Optional

import numpy as np

from .compiled import _is_network, choose_branch_kernel, compile_loop, compile_model
from .kernels.energy import kinetic, stored
from .kernels.friction import reaction
from .kernels.play import branch_force, write_elongations
from .scene import Scene
from .stability import StabilityWarning, stability_problem
from .stepping import (ENERGY_COLUMNS, FRICTION_COLUMN, ElementError, OutputGrid, _advance, _energy_columns, _failure,
                       _progress_bar, energy_columns, initial_state, integrate)
from .steppers import get_stepper


# About how long one compiled call of simulate_chunks runs (s): Python, and so a signal's handler and the
# progress bar, runs between two calls only.
_CHUNK_SECONDS = 0.05


@dataclass(frozen=True, eq=False)
class Result:
    """Output of :func:`simulate` on the grid t = 0, dt, 2 dt, ..., stop_time.

    ``time``, ``x`` (m), ``v`` (m/s), ``reaction`` (N): shape (rows,);
    ``u`` (m): shape (rows, n), or ``None`` unless states were asked for;
    ``energy``: column name -> array (J) (see :data:`ENERGY_COLUMNS`), or
    ``None`` unless asked for.
    """

    time: np.ndarray
    x: np.ndarray
    v: np.ndarray
    reaction: np.ndarray
    u: Optional[np.ndarray]
    energy: Optional[dict]
    stepper: str
    scene: Scene

    def columns(self) -> dict:
        """Column name -> array, in the order of the CSV contract (then the additions)."""
        cols = {"time": self.time, "x": self.x, "v": self.v, "reaction": self.reaction}
        if self.u is not None:
            for i in range(self.u.shape[1]):
                cols[f"u[{i + 1}]"] = self.u[:, i]
        if self.energy is not None:
            cols.update(self.energy)
        return cols

    def write_csv(self, file, header: bool = True) -> None:
        """Write ``time,x,v,reaction[,u[1]..u[n]][,energy columns]``, every float in full precision (repr);
        ``header=False`` writes the rows only (a later piece of :func:`simulate_chunks`)."""
        cols = self.columns()
        if header:
            file.write(",".join(cols) + "\n")
        table = np.column_stack(list(cols.values()))
        block = max(1, 100_000 // table.shape[1])  # rows turned into text at a time: a few MB
        for first in range(0, table.shape[0], block):
            rows = table[first:first + block].tolist()
            file.write("".join(",".join(map(repr, row)) + "\n" for row in rows))


def simulate(scene: Scene, stepper: Optional[str] = None, *, states: bool = False, energy: bool = False,
             progress: Optional[bool] = None, branch_kernel: Optional[str] = None) -> Result:
    """Simulate ``scene`` with its solver settings (``stepper`` overrides the scene's).

    ``states`` also returns the branch elongations, ``energy`` the energy
    account. ``progress`` shows a progress bar on stderr; by default only on
    a terminal and not under CI. Warns (:class:`StabilityWarning`) when the
    step is beyond the stability limit of an explicit stepper; raises
    :class:`ElementError` when a step cannot be taken (plastic collapse of a
    massless element, non-finite state) and ValueError when the stepper does
    not apply to the scene or the output would not fit in memory (stream it
    with :func:`simulate_chunks` instead). ``branch_kernel`` ("play" or
    "stack") overrides the automatic choice of :func:`choose_branch_kernel`.
    """
    from .resources import check_memory

    if _is_network(scene):  # a [network] or [chain] scene: its own driver (network/driver.py)
        from .network.driver import simulate as simulate_network

        return simulate_network(scene, stepper, states=states, energy=energy, progress=progress)
    columns = 4 + (_state_count(scene) if states else 0) + (len(energy_columns(scene)) if energy else 0)
    rows = _row_count(scene)
    check_memory(2 * rows * columns * 8, f"{scene.source}: the output ({rows:.0f} rows x {columns} columns)",
                 hint="write it to a file with the CLI, which streams the rows")
    chunks = list(simulate_chunks(scene, stepper, states=states, energy=energy, progress=progress,
                                  branch_kernel=branch_kernel, warn_level=3))
    first = chunks[0]

    def joined(name):
        parts = [getattr(chunk, name) for chunk in chunks]
        return None if parts[0] is None else np.concatenate(parts)

    energy_table = None
    if energy:
        energy_table = {key: np.concatenate([chunk.energy[key] for chunk in chunks]) for key in first.energy}
    return Result(joined("time"), joined("x"), joined("v"), joined("reaction"), joined("u"), energy_table,
                  first.stepper, scene)


def _row_count(scene: Scene) -> float:
    return scene.solver.stop_time / scene.solver.output_interval + 2


def _state_count(scene: Scene) -> int:
    return scene.branches.n if scene.branches is not None and not scene.branches.continuum else 0


# Rows of one chunk of :func:`simulate_chunks` hold at most this many values (16 MB).
_CHUNK_VALUES = 2_000_000


def simulate_chunks(scene: Scene, stepper: Optional[str] = None, *, states: bool = False, energy: bool = False,
                    progress: Optional[bool] = None, branch_kernel: Optional[str] = None, warn_level: int = 2):
    """:func:`simulate` as a generator of consecutive :class:`Result` pieces of the output grid, in bounded
    memory (the first piece is the initial row). The same numbers as :func:`simulate`: step p is taken at
    t_p = p h however the run is cut. Checks everything (stepper, options) before the first piece."""
    if _is_network(scene):
        from .network.driver import simulate_chunks as network_chunks

        return network_chunks(scene, stepper, states=states, energy=energy, progress=progress)
    solver = scene.solver
    name = stepper or solver.stepper
    loop = compile_loop(scene, name)
    module = get_stepper(name)
    if states and scene.branches is not None and scene.branches.continuum:
        raise ValueError(f"{scene.source}: [branches] continuum: the continuum has no list of elongations to "
                         "output (states): sample it with [branches] count = n instead")
    h, per_row = solver.step, solver.steps_per_output
    if getattr(module, "STEP_IS_OUTPUT", False):
        h, per_row = solver.output_interval, 1
    problem = stability_problem(scene, name, h)
    if problem:
        warnings.warn(f"{scene.source}: {problem}", StabilityWarning, stacklevel=warn_level + 1)
    return _chunks(scene, name, loop, h, per_row, states, energy, progress, branch_kernel)


def _chunks(scene, name, loop, h, per_row, states, energy, progress, branch_kernel):
    solver = scene.solver
    model = compile_model(scene, branch_kernel or choose_branch_kernel(scene, name))
    load = scene.load.compile()
    grid = OutputGrid(solver.stop_time, solver.output_interval, solver.step)
    rows = grid.rows
    n = _state_count(scene)
    n_out = n if states else 0
    account = np.zeros(4) if energy else None
    x, v, u = initial_state(scene, model, load)
    m, k0, k3, c, k, eta, cs, friction, memory = model

    def piece(first, count):
        """Empty output arrays for rows first .. first + count - 1."""
        out = np.empty((count, 3))
        out_u = np.empty((count, n)) if n_out else None
        out_energy = np.zeros((count, 6)) if energy else None
        return out, out_u, out_energy

    def result(first, out, out_u, out_energy):
        count = out.shape[0]
        _check_finite(scene, name, grid.times(first, count), out, out_energy)
        energy_table = None
        if energy:
            energy_table = _energy_columns(scene, initial_energy, out_energy)
        return Result(grid.times(first, count), out[:, 0].copy(), out[:, 1].copy(), out[:, 2].copy(), out_u,
                      energy_table, name, scene)

    out, out_u, out_energy = piece(0, 1)
    out[0] = (x, v, reaction(model, load, 0.0, x, v, branch_force(k, u)))
    if out_u is not None:
        write_elongations(k, u, out_u[0])
    initial_energy = 0.0
    if energy:
        out_energy[0, :2] = (kinetic(m, v), stored(x, k0, k3, k, u))
        initial_energy = out_energy[0, 0] + out_energy[0, 1]
    yield result(0, out, out_u, out_energy)

    last_is_short = grid.last_is_short
    full_rows = rows - 1 - last_is_short  # row 0 is the initial state
    most = max(1, _CHUNK_VALUES // (8 + n_out))  # rows of one chunk, for memory
    chunk = 1  # rows of the next chunk: grown to about _CHUNK_SECONDS of compiled work (see below)
    bar = _progress_bar(progress, total=rows - 1, label=f"{scene.name} [{name}]")
    try:
        j = 0
        while j < full_rows:
            count = min(chunk, full_rows - j)
            started = perf_counter()
            out, out_u, out_energy = piece(1 + j, count)
            x_start, v_start = x, v
            x, v, taken = integrate(loop, model, load, x, v, u, 0.0, j * per_row, h, per_row, out, out_u, account,
                                    out_energy)
            if taken < per_row * count:
                start = None  # the state where the failed step began: known when a step is a row (exact)
                if per_row == 1:
                    x_start, v_start = (out[taken - 1, 0], out[taken - 1, 1]) if taken else (x_start, v_start)
                    start = (model, x_start, v_start, u)
                raise _failure(scene, name, load, (j * per_row + taken) * h, h, start)
            # Python (a signal's handler, the progress bar) runs between chunks only: each chunk is sized from
            # the last one's measured speed to take about _CHUNK_SECONDS, whatever a step of this stepper costs
            # (an event-driven step can cost 1000x a projected one), so SIGINT/SIGTERM stop a run at once.
            elapsed = perf_counter() - started
            chunk = min(most, max(1, int(count * min(_CHUNK_SECONDS / max(elapsed, 1e-9), 8.0))))
            yield result(1 + j, out, out_u, out_energy)
            j += count
            bar.update(count)
        if last_is_short:  # a last, shorter output interval up to stop_time, on the step grid
            out, out_u, out_energy = piece(rows - 1, 1)
            x, v, failed_at = _advance(loop, model, load, x, v, u, 0.0, full_rows * per_row, *grid.tail(h), h,
                                       out, out_u, account, out_energy)
            if failed_at is not None:
                raise _failure(scene, name, load, failed_at, h)
            yield result(rows - 1, out, out_u, out_energy)
            bar.update(1)
    finally:
        bar.close()


def _check_finite(scene: Scene, stepper: str, times, out, out_energy) -> None:
    """ElementError naming the first output column and time where ``out`` (x, v, reaction) or the energy rows
    are not finite: no output is ever NaN or inf."""
    tables = [(("x", "v", "reaction"), ~np.isfinite(out))]
    if out_energy is not None:
        names = ("kinetic_energy", "stored_energy") + ENERGY_COLUMNS[2:5] + (FRICTION_COLUMN,)
        tables.append((names, ~np.isfinite(out_energy)))
    for names, bad in tables:
        if bad.any():
            row, column = np.argwhere(bad)[0]
            raise ElementError(f"{scene.source}: {names[column]} at t = {float(times[row])!r} s would not be finite "
                               f"(an overflow) with stepper {stepper!r}: the run is refused there")
