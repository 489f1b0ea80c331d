"""The driver: joins a scene, a stepper and a time grid.

* :func:`simulate` runs a scene from t = 0 to its stop time and returns the
  output grid as arrays (:class:`Result`);
* :class:`Element` is the same element as a stateful object that advances by
  arbitrary durations under a held force: what an FMU (or any co-simulation
  master) needs.

Both call :func:`integrate`, the one compiled time loop, with the stepper's
compiled ``step`` as argument; Python runs once per chunk of output rows,
never once per step.
"""
from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ._jit import kernel
from .kernels.play import branch_force
from .kernels.smooth import smooth_force
from .loads import held
from .scene import Scene, with_coefficients
from .steppers import get_stepper

# How many branch updates one compiled call does at most, between two
# progress-bar updates (about 10 ms).
_CHUNK_WORK = 20_000_000


def compile_model(scene: Scene):
    """The kernel form of a scene's effects: ``(m, k0, k3, c, k, eta)``, ``None`` where absent."""
    k0 = scene.spring.k0 if scene.spring is not None else None
    k3 = scene.cubic.k3 if scene.cubic is not None else None
    c = scene.damper.c if scene.damper is not None else None
    if scene.branches is not None:
        k = np.ascontiguousarray(scene.branches.stiffness, dtype=float)
        eta = np.ascontiguousarray(scene.branches.yield_displacement, dtype=float)
    else:
        k = eta = None
    return (float(scene.mass.m), k0, k3, c, k, eta)


@kernel
def integrate(step, model, load, x, v, u, t0, h, steps_per_row, n_rows, out, out_u):
    """Advance ``n_rows * steps_per_row`` steps of size ``h`` from time ``t0``.

    After every ``steps_per_row`` steps, row j of ``out`` (shape (n_rows, 3))
    receives x, v and the reaction, and row j of ``out_u`` (shape (n_rows, n),
    or ``None``) the elongations. ``u`` is updated in place; returns (x, v).
    """
    m, k0, k3, c, k, eta = model
    s = branch_force(k, u)
    p = 0
    for j in range(n_rows):
        for _ in range(steps_per_row):
            x, v, s = step(model, load, t0 + p * h, h, x, v, s, u)
            p += 1
        out[j, 0] = x
        out[j, 1] = v
        out[j, 2] = smooth_force(x, v, k0, k3, c) + s
        if out_u is not None:
            out_u[j, :] = u
    return x, v


@dataclass(frozen=True, eq=False)
class Result:
    """Output of :func:`simulate` on the grid t = 0, dt, 2 dt, ..., stop_time.

    ``time``, ``x`` (m), ``v`` (m/s), ``reaction`` (N): shape (rows,);
    ``u`` (m): shape (rows, n), or ``None`` unless states were asked for.
    """

    time: np.ndarray
    x: np.ndarray
    v: np.ndarray
    reaction: np.ndarray
    u: Optional[np.ndarray]
    stepper: str
    scene: Scene

    def columns(self) -> dict:
        """Column name -> array, in the order of the CSV contract."""
        cols = {"time": self.time, "x": self.x, "v": self.v, "reaction": self.reaction}
        if self.u is not None:
            for i in range(self.u.shape[1]):
                cols[f"u[{i + 1}]"] = self.u[:, i]
        return cols

    def write_csv(self, file) -> None:
        """Write ``time,x,v,reaction[,u[1]..u[n]]``, every float in full precision (repr)."""
        cols = self.columns()
        file.write(",".join(cols) + "\n")
        table = np.column_stack(list(cols.values()))
        for row in table.tolist():
            file.write(",".join(map(repr, row)) + "\n")


def output_grid(stop_time: float, interval: float) -> np.ndarray:
    """t = 0, interval, 2 interval, ... and stop_time itself as the last row."""
    count = math.floor(stop_time / interval * (1 + 1e-12))
    # j * interval, rounded to 14 significant digits of stop_time so that
    # the CSV says 499.9 rather than 499.90000000000003.
    digits = 13 - math.floor(math.log10(stop_time))
    times = np.round(np.arange(count + 1) * interval, digits)
    if stop_time - times[-1] > 1e-9 * interval:
        times = np.append(times, stop_time)
    else:
        times[-1] = stop_time
    return times


def simulate(scene: Scene, stepper: Optional[str] = None, *, states: bool = False,
             progress: Optional[bool] = None) -> Result:
    """Simulate ``scene`` with its solver settings (``stepper`` overrides the scene's).

    ``states`` also returns the branch elongations. ``progress`` shows a
    progress bar on stderr; by default only on a terminal and not under CI.
    """
    solver = scene.solver
    name = stepper or solver.stepper
    step = get_stepper(name).step
    model = compile_model(scene)
    load = scene.load.compile()
    h = solver.step
    times = output_grid(solver.stop_time, solver.output_interval)
    rows = len(times)
    out = np.empty((rows, 3))
    n = scene.branches.n if scene.branches is not None else 0
    out_u = np.empty((rows, n)) if (states and n) else None
    u = np.array(scene.branches.u0, dtype=float) if n else None
    x, v = scene.mass.x0, scene.mass.v0
    out[0] = (x, v, smooth_force(x, v, model[1], model[2], model[3]) + branch_force(model[4], u))
    if out_u is not None:
        out_u[0] = u

    per_row = solver.steps_per_output
    last_is_short = rows > 1 and times[-1] - times[-2] < solver.output_interval * (1 - 1e-9)
    full_rows = rows - 1 - last_is_short  # row 0 is the initial state
    chunk = max(1, _CHUNK_WORK // max(1, per_row * max(n, 8)))
    bar = _progress_bar(progress, total=rows - 1, label=f"{scene.name} [{name}]")
    j = 0
    while j < full_rows:
        count = min(chunk, full_rows - j)
        x, v = integrate(step, model, load, x, v, u, times[j], h, per_row, count,
                         out[1 + j:1 + j + count], None if out_u is None else out_u[1 + j:1 + j + count])
        j += count
        bar.update(count)
    if last_is_short:  # a last, shorter output interval up to stop_time
        x, v = _advance(step, model, load, x, v, u, times[-2], times[-1] - times[-2], h,
                        out[-1:], None if out_u is None else out_u[-1:])
        bar.update(1)
    bar.close()
    return Result(times, out[:, 0].copy(), out[:, 1].copy(), out[:, 2].copy(),
                  out_u, name, scene)


def _advance(step, model, load, x, v, u, t0, duration, h, out, out_u):
    """Advance by ``duration``: whole steps of h, then one shorter step for the remainder.

    The remainder is dropped when it is below 1e-9 h (rounding of the
    duration), so a duration that is a whole multiple of h takes whole steps only.
    """
    whole = math.floor(duration / h * (1 + 1e-12))
    rest = duration - whole * h
    if rest <= 1e-9 * h:
        rest = 0.0
    if whole:
        x, v = integrate(step, model, load, x, v, u, t0, h, whole, 1, out, out_u)
    if rest:
        x, v = integrate(step, model, load, x, v, u, t0 + whole * h, rest, 1, 1, out, out_u)
    return x, v


class Element:
    """The element of a scene as a stateful object, advanced under a held force.

    ``advance(duration, force)`` takes whole internal steps of ``step`` and one
    shorter last step for any remainder, with the force held constant.
    The state (``time``, ``x``, ``v``, ``u``) is saved and restored as plain
    data by :meth:`get_state` and :meth:`set_state`.
    """

    def __init__(self, scene: Scene, stepper: Optional[str] = None, step: Optional[float] = None):
        self.scene = scene
        self.stepper = stepper or scene.solver.stepper
        self._step = get_stepper(self.stepper).step
        self.h = float(step if step is not None else scene.solver.step)
        if not (math.isfinite(self.h) and self.h > 0):
            raise ValueError(f"step must be a finite number > 0, got {step!r}")
        self.model = compile_model(scene)
        self._out = np.empty((1, 3))
        self.reset()

    def set_coefficients(self, **values) -> None:
        """Change coefficients (m, k0, k3, c; x0 and v0 take effect at :meth:`reset`).

        ValueError names the culprit and leaves the element unchanged.
        """
        self.scene = with_coefficients(self.scene, **values)
        self.model = compile_model(self.scene)
        self._out[0] = (self.x, self.v, self._reaction())

    def reset(self) -> None:
        """Back to the scene's initial state at time 0."""
        self.time = 0.0
        self.x, self.v = self.scene.mass.x0, self.scene.mass.v0
        branches = self.scene.branches
        self.u = np.array(branches.u0, dtype=float) if branches is not None else None
        self.force = 0.0
        self._out[0] = (self.x, self.v, self._reaction())

    def _reaction(self) -> float:
        m, k0, k3, c, k, eta = self.model
        return smooth_force(self.x, self.v, k0, k3, c) + branch_force(k, self.u)

    @property
    def reaction(self) -> float:
        """k0 x + k3 x^3 + c v + sum_i k_i u_i (N)."""
        return float(self._out[0, 2])

    def advance(self, duration: float, force: float) -> None:
        """Advance by ``duration`` (s) with the force held at ``force`` (N)."""
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be finite and >= 0, got {duration!r}")
        if not math.isfinite(force):
            raise ValueError(f"force must be finite, got {force!r}")
        self.force = float(force)
        if duration > 0:
            self.x, self.v = _advance(self._step, self.model, held(force), self.x, self.v, self.u,
                                      self.time, duration, self.h, self._out, None)
            self.time += duration

    def set_stepper(self, name: str) -> None:
        """Use another stepper from the next step on (every stepper is one-step)."""
        self._step = get_stepper(name).step
        self.stepper = name

    def set_step(self, step: float) -> None:
        """Use another internal step h (s) from the next step on."""
        if not (math.isfinite(step) and step > 0):
            raise ValueError(f"step must be a finite number > 0, got {step!r}")
        self.h = float(step)

    def coefficients(self) -> dict:
        """The coefficients of the effects present (see :data:`scene.COEFFICIENTS`)."""
        scene, values = self.scene, {}
        if scene.mass is not None:
            values.update(m=scene.mass.m, x0=scene.mass.x0, v0=scene.mass.v0)
        if scene.spring is not None:
            values["k0"] = scene.spring.k0
        if scene.cubic is not None:
            values["k3"] = scene.cubic.k3
        if scene.damper is not None:
            values["c"] = scene.damper.c
        return values

    def get_state(self) -> dict:
        """Everything that determines the continuation, as plain data (numbers, strings, lists)."""
        return {
            "time": self.time, "x": self.x, "v": self.v, "force": self.force,
            "u": [] if self.u is None else self.u.tolist(),
            "coefficients": self.coefficients(), "stepper": self.stepper, "step": self.h,
        }

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state`; checks it fully before changing anything."""
        n = 0 if self.u is None else self.u.shape[0]
        values = [float(state[key]) for key in ("time", "x", "v", "force")]
        u = np.array(state["u"], dtype=float).reshape(-1)
        if u.shape[0] != n:
            raise ValueError(f"state has {u.shape[0]} branch elongations, the element has {n}")
        if not all(math.isfinite(value) for value in values) or not np.all(np.isfinite(u)):
            raise ValueError("state has a value that is not finite")
        if n and np.any(np.abs(u) > self.scene.branches.yield_displacement):
            raise ValueError("state has an elongation outside its elastic range")
        scene = with_coefficients(self.scene, **state["coefficients"])
        step = get_stepper(state["stepper"]).step
        self.set_step(float(state["step"]))
        self.scene, self.model = scene, compile_model(scene)
        self._step, self.stepper = step, state["stepper"]
        self.time, self.x, self.v, self.force = values
        if n:
            self.u[:] = u
        self._out[0] = (self.x, self.v, self._reaction())

    def checkpoint(self):
        """A cheap copy of the dynamic state, for :meth:`rollback` (not plain data)."""
        return (self.time, self.x, self.v, self.force, None if self.u is None else self.u.copy(),
                self._out.copy())

    def rollback(self, checkpoint) -> None:
        """Return to a :meth:`checkpoint`, exactly."""
        self.time, self.x, self.v, self.force, u, out = checkpoint
        if u is not None:
            self.u[:] = u
        self._out[:] = out


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
