"""The driver: joins a scene, a stepper and a time grid.

* :func:`simulate` runs a scene from t = 0 to its stop time and returns the
  output grid as arrays (:class:`Result`);
* :class:`Element` is the same element as a stateful object that advances by
  arbitrary durations under a held force: what an FMU (or any co-simulation
  master) needs.

Both call :func:`integrate`, which runs the stepper's compiled time loop
(``kernels/loop.py``); Python runs once per chunk of output rows, never once
per step.
"""
from __future__ import annotations

import math
import os
import sys
from time import perf_counter
import dataclasses
import warnings
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .kernels.energy import kinetic, stored
from .kernels.increment import solve_increment
from .kernels import stack
from .kernels.drive import tangent
from .kernels.friction import reaction
from .kernels.play import branch_force, move, write_elongations
from .kernels.smooth import elastic_force
from .loads import force_at, held, noise_problem, plus, with_white_noise
from .memory import (check_memory_state, compile_memory, copy_memory, force_now, has_memory, memory_state,
                     put_back, restore_memory)
from .memory import time_problem as memory_time_problem
from .memory import delay as memory_delay
from .memory.dahl import after as dahl_after
from .memory.solve import solve_dahl_increment
from .noise import new_cache
from .scene import (ADVANCE_BUDGET, MAX_STEPS, MEMORY_COEFFICIENTS, SHORTEST_STEP, Scene, _coefficient_key,
                    coefficients_of, with_coefficients)
from .scene import _check_memory_rules as check_memory_rules
from .stability import StabilityWarning, stability_problem
from .steppers import get_stepper

# About how long one compiled call of simulate_chunks runs (s): Python, and so a signal's handler and the
# progress bar, runs between two calls only.
_CHUNK_SECONDS = 0.05

ENERGY_COLUMNS = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper", "energy_residual")
# the column a scene with [friction] adds, before energy_residual
FRICTION_COLUMN = "dissipated_friction"


def energy_columns(scene: Scene) -> tuple:
    """The energy columns of ``scene``: :data:`ENERGY_COLUMNS`, with ``dissipated_friction`` before the residual
    when the mass has friction on the ground."""
    if scene.friction is None:
        return ENERGY_COLUMNS
    return ENERGY_COLUMNS[:-1] + (FRICTION_COLUMN, ENERGY_COLUMNS[-1])


class ElementError(RuntimeError):
    """The element cannot be advanced: plastic collapse, or a non-finite state. One line."""


# The memory stack (kernels/stack.py) replaces the O(n) play kernel from this
# many branches on: inside `projected` the two cost the same near n = 40
# (benchmarks/branch_scaling.py: 55 against 80 ns per step at n = 10, 129
# against 80 at n = 100).
STACK_FROM = 64


def compile_model(scene: Scene, branch_kernel: str = "play"):
    """The kernel form of a scene's effects: ``(m, k0, k3, c, k, eta, cs, friction, memory)``, ``None`` where
    absent.

    With ``branch_kernel="stack"``, ``k`` holds the memory stack's parameters
    and ``eta`` is None (see :func:`choose_branch_kernel`); the continuum
    always takes the stack (its parameters are a tuple). ``cs``: the series
    dashpots of the branches (an array, O(n) kernel only); ``friction``:
    :func:`friction_model`; ``memory``: the effects with memory and their state (``memory/__init__.py``).
    """
    return _smooth_model(scene) + _branch_model(scene, branch_kernel) + (friction_model(scene), _memory_model(scene))


def _memory_model(scene: Scene):
    """The kernel form of the effects with memory (``memory/``), fresh at t = 0; memory.NONE without any."""
    x0 = scene.mass.x0 if scene.mass is not None else 0.0
    v0 = scene.mass.v0 if scene.mass is not None else 0.0
    return compile_memory(scene, x0, v0)


def _branch_model(scene: Scene, branch_kernel: str) -> tuple:
    """``(k, eta, cs)``: the branch part of :func:`compile_model`."""
    branches = scene.branches
    if branches is None:
        return (None, None, None)
    if branches.continuum:
        return (branches.params, None, None)
    k = np.ascontiguousarray(branches.stiffness, dtype=float)
    eta = np.ascontiguousarray(branches.yield_displacement, dtype=float)
    if branches.damping is not None:
        if branch_kernel == "stack":
            raise ValueError("series dashpots run on the O(n) kernel only: a relaxing branch has no memory stack")
        return (k, eta, np.ascontiguousarray(branches.damping, dtype=float))
    if branch_kernel == "stack":
        params, _ = stack.prepare(k, eta, branches.u0)
        return (params, None, None)
    return (k, eta, None)


def friction_model(scene: Scene):
    """The kernel form of ``[friction]``: ``(alpha, alpha_kinetic, stribeck_velocity, belt_velocity)``, or None
    (``kernels/friction.py``)."""
    friction = scene.friction
    if friction is None:
        return None
    stribeck = friction.stribeck_velocity if friction.stribeck_velocity is not None else 1.0
    return (float(friction.alpha), float(friction.alpha_kinetic), float(stribeck), float(friction.belt_velocity))


def with_scene_coefficients(scene: Scene, model: tuple) -> tuple:
    """``model`` with the coefficients of ``scene`` (after a change of coefficients): its smooth part, its series
    dashpots and its friction; the branch kernel's parameters and state stay."""
    cs = model[6]
    if cs is not None:
        cs = np.ascontiguousarray(scene.branches.damping, dtype=float)
    return _smooth_model(scene) + model[4:6] + (cs, friction_model(scene), model[8])


def _smooth_model(scene: Scene):
    """``(m, k0, k3, c)``: the part of :func:`compile_model` that does not depend on the branches."""
    m = float(scene.mass.m) if scene.mass is not None else None
    k0 = scene.spring.k0 if scene.spring is not None else None
    k3 = scene.cubic.k3 if scene.cubic is not None else None
    c = scene.damper.c if scene.has_dashpot else None  # c = 0: no dashpot at all
    return (m, k0, k3, c)


def choose_branch_kernel(scene: Scene, stepper: str) -> str:
    """"stack" for the continuum, and for many branches with an admissible initial state and a stepper
    that takes it; "play" (one update per branch) otherwise."""
    branches = scene.branches
    if branches is None:
        return "play"
    if branches.continuum:
        return "stack"
    if branches.damping is not None:  # series dashpots: the O(n) kernel only (kernels/series.py)
        return "play"
    if branches.n < STACK_FROM or not getattr(get_stepper(stepper), "BRANCH_STACK", False):
        return "play"
    order = np.argsort(branches.yield_displacement, kind="stable")
    if not stack.admissible(branches.yield_displacement[order], branches.u0[order]):
        return "play"
    return "stack"


def _initial_x(scene: Scene) -> float:
    return scene.mass.x0 if scene.mass is not None else 0.0


UNCHANGED = object()  # an argument's default: keep what the object has


def with_noise(scene, noise):
    """The scene (an element's or a network's) with the white noise ``noise`` (``loads.WhiteNoise`` or None) on
    its load: what a stepper's rules are checked against when an FMU sets a noise of its own."""
    if noise is scene.load.noise:
        return scene
    return dataclasses.replace(scene, load=dataclasses.replace(scene.load, noise=noise))


def compile_loop(scene: Scene, stepper: str):
    """The compiled time loop of ``stepper`` for ``scene``; ValueError if the scheme does not apply."""
    return get_stepper(stepper).loop_for(scene)


def integrate(loop, model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy):
    """Run a stepper's compiled ``loop`` (``kernels/loop.py``): ``out.shape[0] * steps_per_row`` steps of
    size ``h`` from step number ``first_step`` (t_p = t_base + p h). Returns ``(x, v, steps taken)``."""
    return loop(model, load, x, v, u, float(t_base), int(first_step), float(h), int(steps_per_row), out, out_u,
                energy, out_energy)


def initial_state(scene: Scene, model, load):
    """(x, v, u) at t = 0, u a fresh array (or None).

    With inertia: the scene's x0, v0, u0. Massless: x = 0 and u0; with a
    dashpot v is the rate (F(0) - k0 x - k3 x^3 - sum k_i u_i) / c; without,
    the element jumps at t = 0 to the equilibrium with F(0) (the play
    operator moves the branches) and v = 0. ElementError if none exists.
    """
    m, k0, k3, c, k, eta, cs, friction, memory = model
    if has_memory(memory) and scene.mass is None and c is None:
        return _initial_with_memory(scene, model, load)
    if stack.is_stack(k):  # the memory stack: its state stands for the elongations
        u = stack.fresh_state(k, _initial_x(scene))
    else:
        u = np.array(scene.branches.u0, dtype=float) if scene.branches is not None else None
    if scene.mass is not None:
        return scene.mass.x0, scene.mass.v0, u
    force = force_at(load, 0.0)
    if c is not None:
        return 0.0, (force - elastic_force(0.0, k0, k3) - branch_force(k, u) - force_now(memory, 0.0, 0.0, 0.0)) / c, u
    w = solve_increment(0.0, 0.0, -force, k0, k3, k, eta, None, u, 0.0)  # an instant: no dashpot relaxes
    if not math.isfinite(w):
        raise ElementError(_collapse_message(scene, 0.0, force) if not _hardening(scene) else
                           f"{scene.source}: the equilibrium with F = {float(force)!r} N at t = 0 overflows")
    move(k, eta, u, w, None)  # the O(n) kernel or the memory stack
    return w, 0.0, u


def _initial_with_memory(scene: Scene, model, load):
    """The quasi-static massless element's equilibrium with F(0) when it has memory: the delay's history is
    that equilibrium itself (so a delay on x acts as a spring of its gain at t = 0), the Dahl force moves along
    the jump from 0 (``memory/``)."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    u = stack.fresh_state(k, 0.0) if stack.is_stack(k) else (
        np.array(scene.branches.u0, dtype=float) if scene.branches is not None else None)
    force = force_at(load, 0.0)
    linear = scene.delay.gain if scene.delay is not None else 0.0
    dahl = memory[2]
    if dahl is not None:
        w = solve_dahl_increment(dahl, 0.0, linear, -force, k0, k3, k, eta, None, u, 0.0)
    else:
        w = solve_increment(0.0, linear, -force, k0, k3, k, eta, None, u, 0.0)
    if not math.isfinite(w):
        raise ElementError(_collapse_message(scene, 0.0, force) if not _hardening(scene) else
                           f"{scene.source}: the equilibrium with F = {float(force)!r} N at t = 0 overflows")
    move(k, eta, u, w, None)
    if memory[0] is not None:
        buffer = memory[0][1]
        buffer[1] = buffer[memory_delay.HEAD] = w
    if dahl is not None:
        dahl[1][0] = dahl_after(dahl, 0.0, w)[0]
    return w, 0.0, u


def _collapse_message(scene: Scene, time: float, force: float) -> str:
    strength = scene.branches.strength if scene.branches is not None else 0.0
    time, force = float(time), float(force)
    return (f"{scene.source}: plastic collapse at t = {time!r} s: the load F = {force!r} N exceeds the strength "
            f"sum alpha_i = {strength!r} N of a massless element with no hardening spring: no equilibrium exists")


def _hardening(scene: Scene) -> bool:
    """Whether a spring holds the element whatever the load (then a massless element always has an
    equilibrium, and a step that fails has overflowed)."""
    return (scene.spring is not None and scene.spring.k0 > 0) or (scene.cubic is not None and scene.cubic.k3 > 0)


def _failure(scene: Scene, stepper: str, load, time: float, h: float, start=None) -> ElementError:
    """The error for a step from ``time`` that could not be taken; ``start``: ``(model, x, v, u)`` at the step's
    start, for a stepper that says why (``failure_reason_for(scene)``: which bound of an event search ran out)."""
    force = float(force_at(load, time + h))
    if scene.mass is None and not scene.has_dashpot and not _hardening(scene):
        return ElementError(_collapse_message(scene, time + h, force))
    reason_for = getattr(get_stepper(stepper), "failure_reason_for", None)
    if reason_for is not None and start is not None:
        model, x, v, u = start
        reason = reason_for(scene)(model, load, float(time), float(h), float(x), float(v),
                                   None if u is None else u.copy())
        if reason:
            return ElementError(f"{scene.source}: the step from t = {float(time)!r} s with stepper {stepper!r} "
                                f"refused: {reason}")
    problem = stability_problem(scene, stepper, h)
    hint = f" ({problem})" if problem else f" (F = {force!r} N: an overflow?)" if abs(force) > 1e150 else ""
    return ElementError(f"{scene.source}: the state became non-finite in the step from t = {float(time)!r} s with "
                        f"stepper {stepper!r} and h = {h!r}{hint}")


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


class OutputGrid:
    """t = 0, interval, 2 interval, ... and stop_time itself as the last row, computed row by row (a grid of
    10^13 rows costs nothing until its rows are asked for).

    The run is cut on the step grid of ``h`` (the stepper's step; an output interval is a whole number
    ``per_row`` of steps): stop_time is ``whole`` steps of h and a last shorter step ``rest`` (split_duration:
    within 1e-9 h of a whole multiple is whole steps). Row j >= 1 is the state after j * per_row steps, for
    the ``full`` rows that fit; a last row holds the state at stop_time when the run does not end on a row
    (``last_is_short``: ``tail_steps`` more steps, then ``rest``). So the final state depends on stop_time and
    h only, never on the output interval (issue 23, item 10), and a stop time shorter than a step is one short
    step (t = 0 and t = stop_time rows).

    ``rows``: the number of rows; :meth:`times` the times of rows first .. first + count - 1.
    """

    def __init__(self, stop_time: float, interval: float, h: Optional[float] = None):
        self.stop_time, self.interval = stop_time, interval
        self.h = h = interval if h is None else h
        self.per_row = max(1, round(interval / h))
        self.whole, self.rest = split_duration(stop_time, h)
        self.full = self.whole // self.per_row  # rows on the grid after row 0
        self.tail_steps = self.whole - self.full * self.per_row
        self.last_is_short = bool(self.tail_steps or self.rest)
        self.rows = self.full + 1 + self.last_is_short
        # j * interval, rounded to 14 significant digits of stop_time so that the CSV says 499.9 rather than
        # 499.90000000000003 (not where 10^digits would overflow: a stop time below 1e-290)
        self.digits = 13 - math.floor(math.log10(stop_time))

    def tail(self, loop_step: float) -> tuple:
        """``(whole, rest)`` of the last row for a loop whose steps are ``loop_step``: the scene's step h (whole
        steps, then the rest), or one step per output interval (``exact``): one step of what is left."""
        if loop_step == self.h:
            return self.tail_steps, self.rest
        return 0, self.stop_time - self.full * loop_step

    def _time(self, j):
        times = np.asarray(j, dtype=float) * self.interval
        return np.round(times, self.digits) if self.digits < 290 else times

    def times(self, first: int, count: int) -> np.ndarray:
        times = self._time(np.arange(first, first + count))
        times[np.arange(first, first + count) == self.rows - 1] = self.stop_time  # the last row: stop_time
        return times


def output_grid(stop_time: float, interval: float) -> np.ndarray:
    """The whole :class:`OutputGrid` as an array."""
    grid = OutputGrid(stop_time, interval)
    return grid.times(0, grid.rows)


def _energy_columns(scene: Scene, initial_energy: float, table: np.ndarray) -> dict:
    return _account_columns(scene, initial_energy, *table.T)


def _account_columns(scene, initial_energy, kinetic_, stored_, work, sliders, damper, friction) -> dict:
    """The energy columns of ``scene`` (:func:`energy_columns`) with the balance residual, for arrays of rows or
    for one row of floats."""
    residual = work - sliders - damper - friction - (kinetic_ + stored_ - initial_energy)
    if scene.friction is None:
        return dict(zip(ENERGY_COLUMNS, (kinetic_, stored_, work, sliders, damper, residual)))
    return dict(zip(energy_columns(scene), (kinetic_, stored_, work, sliders, damper, friction, residual)))


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


def _is_network(scene) -> bool:
    return type(scene).__name__ == "NetworkScene"


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


def split_duration(duration: float, h: float) -> tuple:
    """``(whole, rest)``: ``duration`` as ``whole`` steps of h and a last shorter step ``rest`` (s, 0 if none).

    A duration within 1e-9 h of a whole multiple of h (rounding of a master's
    clock that adds up 0.05 s steps drifts by ulps, e.g. 0.04999999999999716)
    is whole steps only, so that a result does not depend on that drift.
    """
    ratio = duration / h
    nearest = round(ratio)
    if nearest >= 1 and abs(ratio - nearest) <= 1e-9:
        return nearest, 0.0
    whole = math.floor(ratio)
    return whole, duration - whole * h


def _advance(loop, model, load, x, v, u, t_base, first_step, whole, rest, h, out, out_u, account,
             out_energy):
    """``whole`` steps of h from step number ``first_step`` (t_p = t_base + p h), then one step of ``rest``
    (s, if > 0) from t_base + (first_step + whole) h (see :func:`split_duration`). Returns ``(x, v,
    failed_at)``: the start time of a step that could not be taken, or None."""
    if whole:
        x, v, taken = integrate(loop, model, load, x, v, u, t_base, first_step, h, whole, out, out_u, account,
                                out_energy)
        if taken < whole:
            return x, v, t_base + (first_step + taken) * h
    if rest:
        start = t_base + (first_step + whole) * h
        x, v, taken = integrate(loop, model, load, x, v, u, start, 0, rest, 1, out, out_u, account, out_energy)
        if taken < 1:
            return x, v, start
    return x, v, None


class OutputMemo:
    """Outputs computed once per state. Every change of the state calls :meth:`_touch`; until the next one,
    :meth:`_memo` returns what was computed (an FMU master reads a dozen outputs per step: each would otherwise
    recompute the O(n) energy account or the tangent stiffness)."""

    _memo_values: dict

    def _touch(self) -> None:
        self._memo_values = {}

    def _memo(self, name: str, compute):
        values = self.__dict__.setdefault("_memo_values", {})
        if name not in values:
            values[name] = compute()
        return values[name]


class Element(OutputMemo):
    """The element of a scene as a stateful object, advanced under a held force.

    ``advance(duration, force)`` takes whole internal steps of ``step`` and one
    shorter last step for any remainder, with the force held constant. The
    energy account is always kept (:meth:`energy`). The state is saved and
    restored as plain data by :meth:`get_state` and :meth:`set_state`.

    Many branches are held by the memory stack (see :func:`choose_branch_kernel`;
    ``branch_kernel`` forces "play" or "stack"); switching to a stepper that
    does not take it (``exact``) expands them to one elongation per branch.
    """

    def __init__(self, scene: Scene, stepper: Optional[str] = None, step: Optional[float] = None,
                 branch_kernel: Optional[str] = None):
        if _is_network(scene):
            raise ValueError(f"{scene.source}: a network scene: step it with prandtl_fmu.network.NetworkElement")
        if branch_kernel not in (None, "play", "stack"):
            raise ValueError(f"branch_kernel must be 'play', 'stack' or None, got {branch_kernel!r}")
        if branch_kernel == "play" and scene.branches is not None and scene.branches.continuum:
            raise ValueError("the continuum has no O(n) kernel: it runs on the memory stack only")
        self.scene = scene
        self._forced_kernel = branch_kernel  # "play" or "stack"; None: the automatic choice
        self.stepper = stepper or scene.solver.stepper
        self._loop = compile_loop(scene, self.stepper)
        self.h = float(step if step is not None else scene.solver.step)
        if not (math.isfinite(self.h) and self.h > 0):
            raise ValueError(f"step must be a finite number > 0, got {step!r}")
        self._out = np.empty((1, 3))
        self._energy_row = np.empty((1, 6))
        self.account = np.zeros(4)
        self._load = held(0.0)  # the load of the last advance: the reaction's F(t)
        # the Brownian tree's cache of a white noise in [load] (loads.WhiteNoise): scratch beside the loop's, never
        # in the state (the path is a function of (seed, time) alone: a restored or rolled-back element redraws
        # the same increments whatever the cache holds)
        self._noise_cache = new_cache()
        self.noise = scene.load.noise  # the white noise on the force (set_noise; default the scene's)
        self.reset()

    def set_noise(self, noise) -> None:
        """The white noise (``loads.WhiteNoise``, or None: none) on the element's force from the next advance
        on, whether or not the scene's [load] is added (an FMU's noise_intensity, noise_seed, noise_unit);
        ValueError (nothing changed) if the stepper takes no noise or the element cannot carry one."""
        compile_loop(with_noise(self.scene, noise), self.stepper)  # the stepper's own refusal
        problem = noise_problem(noise, self.h)
        if problem:
            raise ValueError(problem)
        self.noise = noise
        self._touch()

    def _load_of(self, force: float, scene_load: bool):
        """The compiled load of an advance: ``force`` held (plus the scene's [load] with ``scene_load``), and
        the element's white noise."""
        base = plus(self.scene.load.compile(), force) if scene_load else held(force)
        return with_white_noise(base, self.noise, self._noise_cache)

    def reset(self, force: float = 0.0) -> None:
        """Back to the scene's initial state at time 0 under the held ``force`` (massless: see
        :func:`initial_state`); the energy account restarts."""
        self._origin, self._steps, self._grid = 0.0, 0, None  # the clock (see time)
        self.force = float(force)
        self.branch_kernel = self._forced_kernel or choose_branch_kernel(self.scene, self.stepper)
        self.model = compile_model(self.scene, self.branch_kernel)
        self._load = held(self.force)
        self.x, self.v, self.u = initial_state(self.scene, self.model, self._load)
        self.account[:] = 0.0
        self._record()
        self.initial_energy = float(self._energy_row[0, 0] + self._energy_row[0, 1])

    @property
    def time(self) -> float:
        """The element's time (s), kept on its step grid as ``origin + steps * h``: the time of step p is computed
        as :func:`simulate` computes it (t_base + p h), however the advances are cut (``time += duration``
        drifted by rounding, and a load evaluated at the drifted times differed in the last bits)."""
        return self._origin + self._steps * self._grid if self._steps else self._origin

    @time.setter
    def time(self, value: float) -> None:
        """Set the clock (a master's communication point): a value within 1e-9 h of the element's own time is
        the same instant (a master's clock that adds up its steps drifts by ulps) and keeps the grid; another
        starts a new grid there."""
        value = float(value)
        if not math.isfinite(value):
            raise ValueError(f"time must be finite, got {value!r}")
        if self._grid is not None and abs(value - self.time) <= 1e-9 * self._grid:
            return
        self._origin, self._steps = value, 0

    def _record(self) -> None:
        self._touch()
        m, k0, k3, c, k, eta, cs, friction, memory = self.model
        self._out[0] = (self.x, self.v, reaction(self.model, self._load, self.time, self.x, self.v,
                                                 branch_force(k, self.u)))
        self._energy_row[0] = (kinetic(m, self.v), stored(self.x, k0, k3, k, self.u), *self.account)

    @property
    def reaction(self) -> float:
        """k0 x + k3 x^3 + c v + sum_i k_i u_i (N), plus the friction on the mass (the force that holds it
        while it sticks: then the reaction is F)."""
        return float(self._out[0, 2])

    def reaction_under(self, force: float, scene_load: bool = False) -> float:
        """The reaction in the current state under the force ``force`` (N; plus the scene's [load] at the
        element's time with ``scene_load``). It differs from :attr:`reaction` (under the force of the last
        advance) only with friction on the mass: while the mass sticks, the friction holds it against the force
        of now, so the reaction is that force (up to alpha): what an FMU output shows once the master has set
        a new F."""
        if self.scene.friction is None:
            return self.reaction
        key = ("reaction_under", force, scene_load)
        load = self._load_of(force, scene_load)
        return self._memo(key, lambda: float(reaction(self.model, load, self.time, self.x, self.v,
                                                       branch_force(self.model[4], self.u))))

    def stiffness(self) -> float:
        """The tangent dF/dx (N/m) of the reaction at the current state, for a motion in the direction of v
        (of increasing x when v = 0): k0 + 3 k3 x^2 + the stiffnesses of the branches that stick (a branch
        on its threshold that the motion pushes on slides and adds nothing)."""
        direction = -1.0 if self.v < 0 else 1.0
        return self._memo("stiffness", lambda: float(tangent(self.model, self.x, self.u, direction)))

    def elongations(self) -> Optional[np.ndarray]:
        """The branch elongations u_i (m), in the scene's order, as a new array (O(n) with the memory
        stack); None without branches or for the continuum."""
        if self.u is None or self.scene.branches.continuum:
            return None
        u = np.empty(self.scene.branches.n)
        write_elongations(self.model[4], self.u, u)
        return u

    def energy(self) -> dict:
        """The energy account (J): see :data:`ENERGY_COLUMNS`."""
        return self._memo("energy", self._account).copy()

    def energy_of(self, name: str) -> float:
        """One entry of :meth:`energy` (J), without copying the account: what an FMU output reads."""
        return self._memo("energy", self._account)[name]

    def _account(self) -> dict:
        """_energy_columns for the one row of the element, in floats (numpy on a row of 5 costs 10 us)."""
        return _account_columns(self.scene, self.initial_energy, *self._energy_row[0].tolist())

    def advance(self, duration: float, force: float, scene_load: bool = False) -> None:
        """Advance by ``duration`` (s) with the force held at ``force`` (N); with ``scene_load``, the force is
        ``force`` plus the scene's ``[load]`` F(t), evaluated by the stepper as in :func:`simulate` (the
        element's ``time`` is the load's clock).

        ElementError (state unchanged) when a step cannot be taken.
        """
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be finite and >= 0, got {duration!r}")
        if not math.isfinite(force):
            raise ValueError(f"force must be finite, got {force!r}")
        if duration == 0:
            return
        h = self.h
        if getattr(get_stepper(self.stepper), "STEP_IS_OUTPUT", False):  # one step per advance (exact) ...
            h = duration
            if self._grid is not None and abs(duration - self._grid) <= 1e-9 * self._grid:
                h = self._grid  # ... of the grid's step when it is that to rounding (a master's step of H drifts)
        if duration < SHORTEST_STEP:
            raise ValueError(f"duration {duration!r} s is shorter than {SHORTEST_STEP:g} s (a step's square "
                             "underflows)")
        if not duration / h < MAX_STEPS:
            raise ValueError(f"duration {duration!r} s is {duration / h:.3g} steps of h = {h!r} s: more than 2^53 "
                             "cannot be counted exactly; advance by shorter durations or with a larger step")
        whole, rest = split_duration(duration, h)
        if whole + (rest > 0) > ADVANCE_BUDGET:
            raise ElementError(f"{self.scene.source}: an advance of {duration!r} s takes {whole + (rest > 0):.4g} "
                               f"steps of h = {h!r} s, more than the budget of {ADVANCE_BUDGET:.0e} steps of one "
                               "advance: advance by shorter durations (communication steps) or with a larger step")
        problem = noise_problem(self.noise, self.h, self.time + duration)  # the Brownian tree's end
        if problem is None:
            problem = memory_time_problem(self.model[8], self.time, self.time + duration)
        if problem:
            raise ElementError(f"{self.scene.source}: the advance to t = {self.time + duration!r} s refused: "
                               f"{problem}")
        saved = self.checkpoint()
        load = self._load_of(force, scene_load)
        self.force, self._load = float(force), load
        self._touch()  # the compiled loop writes the state and the outputs in place
        if self._grid != h:  # a new step: the grid starts again at the current time
            self._origin, self._steps, self._grid = self.time, 0, h
        x, v, failed_at = _advance(self._loop, self.model, load, self.x, self.v, self.u, self._origin,
                                         self._steps, whole, rest, h, self._out, None, self.account,
                                         self._energy_row)
        if failed_at is not None:
            self.rollback(saved)
            first = failed_at == self.time  # then the state rolled back to is the failed step's start
            raise _failure(self.scene, self.stepper, load, failed_at, h if whole else rest,
                           (self.model, self.x, self.v, self.u) if first else None)
        self.x, self.v = x, v
        if rest:  # a short last step: the grid starts again where it ends
            self._origin, self._steps = self._origin + (self._steps + whole) * h + rest, 0
        else:
            self._steps += whole
        overflowed = self._overflowed()
        if overflowed:
            time = self.time
            self.rollback(saved)
            raise ElementError(f"{self.scene.source}: the advance to t = {time!r} s with F = {float(force)!r} N "
                               f"refused: {overflowed} would not be finite (an overflow); the state is unchanged")

    def _overflowed(self) -> Optional[str]:
        """The first output of the current state that is not a finite number (x, v, reaction, an energy), or
        None."""
        names = ("x", "v", "reaction", "kinetic_energy", "stored_energy") + ENERGY_COLUMNS[2:5] + (FRICTION_COLUMN,)
        for name, value in zip(names, (*self._out[0].tolist(), *self._energy_row[0].tolist())):
            if not math.isfinite(value):
                return name
        return None

    def set_coefficients(self, **values) -> None:
        """Change coefficients (m, k0, k3, c; x0 and v0 take effect at :meth:`reset`).

        ValueError names the culprit and leaves the element unchanged.
        """
        scene = with_coefficients(self.scene, **values)
        memory = [name for name in values if _coefficient_key(name) in MEMORY_COEFFICIENTS
                  and values[name] != coefficients_of(self.scene)[name]]
        if memory and (self._steps or self._origin or self.time):
            raise ValueError(f"{memory[0]}: an effect with memory restarts with its coefficients: set them before "
                             "the run (an FMU's fixed parameter), or reset the element")
        # c -> 0 on a massless element: 'projected' no longer applies, nor a noise (checked with the noise in use)
        loop = compile_loop(with_noise(scene, self.noise), self.stepper)
        if memory:  # (at the start: the initial state with the new coefficients, fresh memory included)
            self.scene, self._loop = scene, loop
            self.reset(self.force)
            return
        self.scene, self.model, self._loop = scene, with_scene_coefficients(scene, self.model), loop
        self._record()

    def set_stepper(self, name: str) -> None:
        """Use another stepper from the next step on (every stepper is one-step).

        When the new stepper does not take the memory stack (``exact``), the
        elongations are expanded to one per branch (O(n), once); when it does
        and the branches are many, they are folded back into a stack.
        """
        loop = compile_loop(with_noise(self.scene, self.noise), name)  # (a stepper may refuse the noise)
        kind = choose_branch_kernel(self.scene, name) if self._can_fold() else "play"
        if self._forced_kernel and getattr(get_stepper(name), "BRANCH_STACK", False):
            kind = self._forced_kernel
        self._use_branch_kernel(kind)
        self._loop, self.stepper = loop, name

    def _can_fold(self) -> bool:
        """Whether the current elongations can be held by the memory stack."""
        if self.branch_kernel == "stack":
            return True
        if self.u is None:
            return False
        order = np.argsort(self.scene.branches.yield_displacement, kind="stable")
        return stack.admissible(self.scene.branches.yield_displacement[order], self.u[order])

    def _use_branch_kernel(self, kind: str) -> None:
        """Switch the branches between the O(n) kernel and the memory stack, keeping the elongations."""
        if kind == self.branch_kernel:
            return
        branches = self.scene.branches
        if kind == "play":
            u = np.empty(branches.n)
            write_elongations(self.model[4], self.u, u)
            branch_model = compile_model(self.scene, "play")[4:7]
        else:  # one initial piece that refers to the elongations now: u = (x - x_now) + u_now
            params, _ = stack.prepare(branches.stiffness, branches.yield_displacement, self.u)
            u = stack.fresh_state(params, self.x)
            branch_model = (params, None, None)
        self.branch_kernel = kind
        self.model = self.model[:4] + branch_model + self.model[7:]
        self.u = u
        self._record()

    def set_step(self, step: float) -> None:
        """Use another internal step h (s) from the next step on."""
        if not (math.isfinite(step) and step > 0):
            raise ValueError(f"step must be a finite number > 0, got {step!r}")
        problem = noise_problem(self.noise, step)
        if problem:
            raise ValueError(problem)
        if has_memory(self.model[8]):  # (a negative delay gain with tau below the step: not monotone)
            try:
                check_memory_rules(dataclasses.replace(self.scene, solver=dataclasses.replace(self.scene.solver,
                                                                                               step=float(step))))
            except ValueError as exc:
                raise ValueError(f"step = {step!r}: {str(exc).split(': ', 2)[-1]}") from None
        self.h = float(step)

    def stability_problem(self) -> Optional[str]:
        """Why the current stepper and step are unstable for this element, or None."""
        return stability_problem(self.scene, self.stepper, self.h, x=self.x)

    def coefficients(self) -> dict:
        """The coefficients of the effects present (see :data:`scene.COEFFICIENTS`)."""
        return coefficients_of(self.scene)

    def get_state(self) -> dict:
        """Everything that determines the continuation, as plain data (numbers, strings, lists).

        ``u`` is the list of elongations with the O(n) kernel, the part in use
        of the memory stack's state otherwise (then ``u_reference`` holds the
        elongations its initial piece refers to, for n branches).
        """
        state = {
            "time": self.time, "clock": [self._origin, self._steps, self._grid or 0.0],
            "x": self.x, "v": self.v, "force": self.force,
            "branch_kernel": self.branch_kernel, "u": [], "u_reference": [],
            "energy_account": self.account.tolist(),
            "initial_energy": self.initial_energy,
            "coefficients": self.coefficients(), "stepper": self.stepper, "step": self.h,
        }
        state["u"], state["u_reference"] = branch_state(self.scene, self.model[4], self.branch_kernel, self.u)
        if has_memory(self.model[8]):  # the effects with memory: the delay's buffer, the history, the Dahl force
            state["memory"] = memory_state(self.model[8])
        return state

    def set_state(self, state: dict, noise=UNCHANGED) -> None:
        """Restore a state from :meth:`get_state`; checks every field (types, finiteness, the admissibility of
        the branch state, finite outputs) before changing anything: ValueError naming what does not fit.
        ``noise``: the white noise in use from then on (an FMU state's own settings; default the element's),
        against which the state's stepper and coefficients are checked."""
        noise = self.noise if noise is UNCHANGED else noise
        values = [plain_number(state[key], key) for key in ("time", "x", "v", "force", "initial_energy")]
        clock = _clock(state.get("clock"), values[0])
        booked = state["energy_account"]
        if not isinstance(booked, (list, tuple)):
            raise ValueError(f"state has energy_account = {booked!r:.60}, not a list of numbers")
        account = np.array([plain_number(value, "energy_account") for value in booked], dtype=float)
        if account.shape[0] != 4:
            raise ValueError(f"state has {account.shape[0]} energy account entries, the element has 4")
        kind = state.get("branch_kernel", "play")
        if not isinstance(kind, str):
            raise ValueError(f"state has branch kernel {kind!r}, which does not fit the element")
        model, u = restore_branch_state(self.scene, self.model[4], kind, state["u"], state.get("u_reference", []))
        if not isinstance(state["coefficients"], dict):
            raise ValueError("state has no table of coefficients")
        scene = with_coefficients(self.scene, **state["coefficients"])
        stepper, step = state["stepper"], plain_number(state["step"], "step")
        if not isinstance(stepper, str):
            raise ValueError(f"state has stepper {stepper!r}, not a name")
        loop = compile_loop(with_noise(scene, noise), stepper)
        if not step > 0:
            raise ValueError(f"state has step = {step!r}, must be > 0")
        problem = noise_problem(noise, step)  # the state's step under the noise in use from then on
        if problem:
            raise ValueError(problem)
        memory = _memory_model(scene)  # the state's coefficients, its arrays filled below
        if has_memory(memory) or "memory" in state:
            check_memory_state(memory, state.get("memory"), values[0])
            restore_memory(memory, state["memory"], values[0])
        model = with_scene_coefficients(scene, _smooth_model(scene) + model + (None, memory))
        m, k0, k3, c, k, eta, cs, friction, memory = model
        _, x, v, force, _ = values
        outputs = (reaction(model, held(force), values[0], x, v, branch_force(k, u)), kinetic(m, v),
                   stored(x, k0, k3, k, u))
        if not all(math.isfinite(value) for value in outputs):
            raise ValueError(f"state has x = {x!r}, v = {v!r}: its reaction or energy is not finite")
        self.noise = noise
        self.set_step(step)  # (its noise rule checked above with this noise)
        self.scene, self.branch_kernel = scene, kind
        self.model = model
        self._loop, self.stepper = loop, stepper
        self.x, self.v, self.force, self.initial_energy = values[1:]
        self._load = held(self.force)
        self._origin, self._steps, self._grid = clock
        self.u = u
        self.account[:] = account
        self._record()

    def checkpoint(self):
        """A cheap copy of the dynamic state, for :meth:`rollback` (not plain data)."""
        u = None
        if self.u is not None:
            u = self.u[:stack.used(self.u)].copy() if self.branch_kernel == "stack" else self.u.copy()
        return ((self._origin, self._steps, self._grid), self.x, self.v, self.force, u, self.account.copy(),
                self._out.copy(), self._energy_row.copy(), copy_memory(self.model[8]))

    def rollback(self, checkpoint) -> None:
        """Return to a :meth:`checkpoint`, exactly."""
        clock, self.x, self.v, self.force, u, account, out, energy_row, memory = checkpoint
        put_back(self.model[8], memory)
        self._origin, self._steps, self._grid = clock
        self._touch()
        if u is not None:
            self.u[:u.shape[0]] = u
        self.account[:] = account
        self._out[:] = out
        self._energy_row[:] = energy_row


def _clock(saved, time: float) -> tuple:
    """(origin, steps, grid) of a saved element clock ``[origin, steps, h]`` (h = 0: none yet); a state
    without one (an older FMU's) starts a grid at its time. ValueError unless it is consistent with ``time``."""
    if saved is None:
        return time, 0, None
    values = number_list(saved, "clock")
    if values.shape[0] != 3 or values[1] < 0 or values[1] != int(values[1]) or values[2] < 0 \
            or (values[1] > 0 and values[2] == 0):
        raise ValueError(f"state has clock = {saved!r:.80}, not [origin, steps, step]")
    origin, steps, grid = float(values[0]), int(values[1]), float(values[2]) or None
    now = origin + steps * grid if steps else origin
    if now != time:
        raise ValueError(f"state has time = {time!r} but its clock says {now!r}")
    return origin, steps, grid


def plain_number(value, what: str) -> float:
    """``value`` as a float if it is a finite int or float (not a bool, a string or a list); ValueError naming
    ``what`` otherwise. What a saved state must hold where it holds a number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"state has {what} = {value!r}, not a finite number")
    return float(value)


def number_list(values, what: str) -> np.ndarray:
    """A list of finite numbers (:func:`plain_number` each) as a 1-D array; ValueError otherwise."""
    if not isinstance(values, (list, tuple)):
        raise ValueError(f"state has {what} = {values!r:.60}, not a list of numbers")
    return np.array([plain_number(value, what) for value in values], dtype=float)


def branch_state(scene: Scene, k, kind: str, u):
    """The branches' state as plain data: ``(u, u_reference)`` lists.

    ``u`` is the list of elongations with the O(n) kernel, the part in use of
    the memory stack's state otherwise (then ``u_reference`` holds the
    elongations its initial piece refers to, for n branches).
    """
    if kind == "stack":
        reference = []
        if not scene.branches.continuum:
            values = np.empty(scene.branches.n)
            values[k[stack.ORDER_ROW, :-1].astype(np.int64)] = k[stack.C_ROW, :-1]
            reference = values.tolist()
        return u[:stack.used(u)].tolist(), reference
    return ([] if u is None else u.tolist()), []


def restore_branch_state(scene: Scene, k, kind: str, u, reference):
    """(branch part of the model, branch state) of saved :func:`branch_state` data for ``scene`` whose
    current branch parameters are ``k``; ValueError if it does not fit."""
    u = number_list(u, "u")
    reference = number_list(reference, "u_reference")
    branches = scene.branches
    if branches is None:
        if u.size:
            raise ValueError(f"state has {u.shape[0]} branch values, the element has no branches")
        return (None, None, None), None
    if kind == "stack":
        if branches.continuum:
            params = k
        else:
            if reference.shape[0] != branches.n:
                raise ValueError(f"state has {reference.shape[0]} reference elongations, the element has "
                                 f"{branches.n} branches")
            params, _ = stack.prepare(branches.stiffness, branches.yield_displacement, reference)
        return (params, None, None), stack.restore(params, u)
    if kind != "play" or branches.continuum:
        raise ValueError(f"state has branch kernel {kind!r}, which does not fit the element")
    if u.shape[0] != branches.n:
        raise ValueError(f"state has {u.shape[0]} branch elongations, the element has {branches.n}")
    if np.any(np.abs(u) > branches.yield_displacement):
        raise ValueError("state has an elongation outside its elastic range")
    return compile_model(scene, "play")[4:7], u


class _NoBar:
    def update(self, count):
        pass

    def close(self):
        pass


def _progress_bar(progress: Optional[bool], total: int, label: str):
    if progress is None:
        progress = sys.stderr.isatty() and not os.environ.get("CI")
    if not progress:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, desc=label, unit="row", file=sys.stderr, leave=False)
