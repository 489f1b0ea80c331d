"""What every run of a compiled scene shares, whoever drives it: the batch driver (``driver.py``), the
stateful :class:`element.Element`, the network's (``network/driver.py``) and the summaries (``summary.py``).

* the state at t = 0 (:func:`initial_state`: the scene's x0, v0, u0, or the
  massless element's equilibrium with F(0));
* a stretch of steps of a stepper's compiled loop (:func:`integrate`,
  :func:`_advance`: whole steps of h, then one shorter step; :func:`split_duration`),
  and the :class:`ElementError` when a step cannot be taken (:func:`_failure`
  says why);
* the energy account's columns (:data:`ENERGY_COLUMNS`, :func:`energy_columns`);
* the output grid of a run (:class:`OutputGrid`), the outputs computed once
  per state of a stepped object (:class:`OutputMemo`), and the progress bar.
"""
from __future__ import annotations

import math
import os
import sys
from typing import Optional

import numpy as np

from .kernels.increment import solve_increment
from .kernels import stack
from .kernels.play import branch_force, move
from .kernels.smooth import elastic_force
from .loads import force_at
from .memory import force_now, has_memory
from .memory import delay as memory_delay
from .memory.dahl import after as dahl_after
from .kernels.dahl_increment import solve_dahl_increment
from .scene import Scene
from .stability import stability_problem
from .steppers import get_stepper


class ElementError(RuntimeError):
    """The element cannot be advanced: plastic collapse, or a non-finite state. One line."""


ENERGY_COLUMNS = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper", "energy_residual")

# the column a scene with [friction] adds, before energy_residual
FRICTION_COLUMN = "dissipated_friction"


def energy_columns(scene: Scene) -> tuple:
    """The energy columns of ``scene``: :data:`ENERGY_COLUMNS`, with ``dissipated_friction`` before the residual
    when the mass has friction on the ground."""
    if scene.friction is None:
        return ENERGY_COLUMNS
    return ENERGY_COLUMNS[:-1] + (FRICTION_COLUMN, ENERGY_COLUMNS[-1])


def _energy_columns(scene: Scene, initial_energy: float, table: np.ndarray) -> dict:
    return _account_columns(scene, initial_energy, *table.T)


def _account_columns(scene, initial_energy, kinetic_, stored_, work, sliders, damper, friction) -> dict:
    """The energy columns of ``scene`` (:func:`energy_columns`) with the balance residual, for arrays of rows or
    for one row of floats."""
    residual = work - sliders - damper - friction - (kinetic_ + stored_ - initial_energy)
    if scene.friction is None:
        return dict(zip(ENERGY_COLUMNS, (kinetic_, stored_, work, sliders, damper, residual)))
    return dict(zip(energy_columns(scene), (kinetic_, stored_, work, sliders, damper, friction, residual)))


def _initial_x(scene: Scene) -> float:
    return scene.mass.x0 if scene.mass is not None else 0.0


def initial_state(scene: Scene, model, load):
    """(x, v, u) at t = 0, u a fresh array (or None).

    With inertia: the scene's x0, v0, u0. Massless: x = 0 and u0; with a
    dashpot v is the rate (F(0) - k0 x - k3 x^3 - sum k_i u_i) / c; without,
    the element jumps at t = 0 to the equilibrium with F(0) (the play
    operator moves the branches) and v = 0. ElementError if none exists.
    """
    m, k0, k3, c, k, eta, cs, friction, memory = model
    if has_memory(memory) and scene.mass is None and not scene.has_dashpot:
        return _initial_with_memory(scene, model, load)
    if stack.is_stack(k):  # the memory stack: its state stands for the elongations
        u = stack.fresh_state(k, _initial_x(scene))
    else:
        u = np.array(scene.branches.u0, dtype=float) if scene.branches is not None else None
    if scene.mass is not None:
        return scene.mass.x0, scene.mass.v0, u
    force = force_at(load, 0.0)
    if scene.has_dashpot:
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


def integrate(loop, model, load, x, v, u, t_base, first_step, h, steps_per_row, out, out_u, energy, out_energy):
    """Run a stepper's compiled ``loop`` (``kernels/loop.py``): ``out.shape[0] * steps_per_row`` steps of
    size ``h`` from step number ``first_step`` (t_p = t_base + p h). Returns ``(x, v, steps taken)``.

    ``out_u`` and ``out_energy`` not asked for (None) are handed as arrays with no column: the loop then writes
    nothing there, and a run with them and one without share one compiled loop (numba compiles one for each
    combination of types: docs/benchmarks.md)."""
    if out_u is None:
        out_u = np.empty((out.shape[0], 0))
    if out_energy is None:
        out_energy = np.empty((out.shape[0], 0))
    return loop(model, load, x, v, u, float(t_base), int(first_step), float(h), int(steps_per_row), out, out_u,
                energy, out_energy)


def split_duration(duration: float, h: float, end: float = math.inf) -> tuple:
    """``(whole, rest)``: ``duration`` as ``whole`` steps of h and a last shorter step ``rest`` (s, 0 if none).

    A duration within 1e-9 h of a whole multiple of h (rounding of a master's
    clock that adds up 0.05 s steps drifts by ulps, e.g. 0.04999999999999716)
    is whole steps only, so that a result does not depend on that drift. After
    the whole steps, a remainder below 1e-9 h and below 1e-9 |end| (``end``:
    the clock's time after the duration) is that rounding too and is dropped,
    also when the duration itself is below it: ``(0, 0.0)``, no step at all
    (OMSimulator's clock of 2000 x 0.1 s ends 7.1e-12 s short of 200 s and
    steps that remainder: a white noise's increment over it moved v by 2e-6).
    A clock's rounding is a fraction of its time: a step h far longer than the
    duration (1e20 s, advanced by 1 s) does not make the duration rounding, it
    is one step of the duration (the step cut to the interval). The native
    runtime's C (``fmu/native``) applies the same rule.
    """
    ratio = duration / h
    nearest = round(ratio)
    if nearest >= 1 and abs(ratio - nearest) <= 1e-9:
        return nearest, 0.0
    whole = math.floor(ratio)
    rest = duration - whole * h
    return whole, rest if rest >= 1e-9 * min(h, abs(end)) else 0.0


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
        if not (self.whole or self.rest):  # a run shorter than rounding of h is still asked for: one short step
            self.rest = stop_time
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


UNCHANGED = object()  # an argument's default: keep what the object has


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


class _NoBar:
    def update(self, count):
        pass

    def set_description(self, text):
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
