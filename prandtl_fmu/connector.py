"""The element as a connector: driven by the motion of its two flanges, it returns the force.

A massless scene (no ``[mass]``) between two bodies: the input is the
relative displacement x (m) and velocity v (m/s) of the flanges, the output
the force the element transmits,

    force = k0 x + k3 x^3 + c v + sum_i k_i u_i,

with the branches moved by the exact play update along x. Between two
samples x is taken linear; the play operator is rate independent, so one
monotone move per sample is exact whatever the time between the samples (a
master that gives only the end value of a step gets the linear interpolant).
Branches with series dashpots (``[branches] c``) are rate dependent: they
relax over the time between the samples, exactly along the linear path
(``kernels/series.py``).
The element starts at x = 0 with the scene's initial elongations u0; a first
sample x(0) != 0 moves it there monotonically (a virgin loading).

* :func:`displacement_response` runs a whole sampled history in one compiled call;
* :class:`Connector` is the same element as a stateful object for a
  co-simulation master: :meth:`Connector.preview` gives the force at a new
  input without moving the state, :meth:`Connector.move_to` commits it,
  :meth:`Connector.advance` is an FMU's doStep (the sample committed at the
  communication point, then, with the inputs' derivatives, the motion along
  their Taylor polynomial over the step, its turning point found).
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .compiled import (branch_state, choose_branch_kernel, compile_model, restore_branch_state,
                       with_scene_coefficients, _smooth_model)
from .saved_state import number_list, plain_number
from .stepping import ElementError, OutputMemo
from .kernels import stack
from .kernels.drive import drive, drive_polynomial, drive_with_memory, preview, tangent
from .memory import (check_memory_state, copy_memory, force_now, has_memory, memory_state, put_back,
                     restore_memory, tangent_now)
from .memory import time_problem as memory_time_problem
from .kernels.play import branch_force, write_elongations
from .kernels.smooth import smooth_force
from .kernels.energy import stored
from .kernels.rates import connector_rates
from .scene import MEMORY_COEFFICIENTS, Scene, _coefficient_key, coefficients_of, with_coefficients

# energy account of the connector: work is not booked (no load), energy[1] = sliders, energy[2] = dashpot
SLIDERS, DAMPER = 1, 2


def _require_massless(scene: Scene) -> None:
    if scene.mass is not None:
        raise ValueError(f"{scene.source}: the connector is the massless element: the scene must have no [mass] "
                         "(the bodies on either side hold the inertia)")


def _branch_kernel(scene: Scene) -> str:
    return choose_branch_kernel(scene, "projected")  # the memory stack for many branches and the continuum


def _initial_u(scene: Scene, model):
    k = model[4]
    if stack.is_stack(k):
        return stack.fresh_state(k, 0.0)
    return np.array(scene.branches.u0, dtype=float) if scene.branches is not None else None


def displacement_response(scene: Scene, x, v=None, energy: bool = False, time=None):
    """The force at each sample of a displacement history ``x`` (m), from x = 0 and the scene's u0.

    ``v`` (m/s) feeds the dashpot (zeros when None; a scene with a dashpot needs it); ``time`` (s, from 0,
    non-decreasing) the series dashpots of the branches (a scene with them needs it). Returns the forces,
    or ``(forces, dissipated_sliders)`` with ``energy=True``. One compiled call for the whole history.
    """
    _require_massless(scene)
    xs = np.ascontiguousarray(x, dtype=float).reshape(-1)
    if not np.all(np.isfinite(xs)):
        raise ValueError("x must be finite")
    if v is None:
        if scene.has_dashpot:
            raise ValueError("the scene has a dashpot: give the velocities v")
        vs = np.zeros_like(xs)
    else:
        vs = np.ascontiguousarray(v, dtype=float).reshape(-1)
        if vs.shape != xs.shape or not np.all(np.isfinite(vs)):
            raise ValueError("v must be finite and as long as x")
    durations = np.zeros_like(xs)
    if time is None:
        if scene.has_series_dashpots:
            raise ValueError("the branches have series dashpots (rate dependent): give the times of the samples")
        if scene.delay is not None or scene.history is not None:
            raise ValueError("the scene has a [delay] or a [history] (they depend on time): give the times of the "
                             "samples")
    else:
        times = np.ascontiguousarray(time, dtype=float).reshape(-1)
        if times.shape != xs.shape or not np.all(np.isfinite(times)) or np.any(np.diff(times) < 0) \
                or (times.size and times[0] < 0):
            raise ValueError("time must be finite, non-decreasing from >= 0 and as long as x")
        durations = np.diff(times, prepend=0.0)
    model = compile_model(scene, _branch_kernel(scene))
    u = _initial_u(scene, model)
    forces = np.empty_like(xs)
    account = np.zeros(3) if energy else None
    if has_memory(model[8]):  # the delay needs the samples' times: time = None means all at t = 0
        drive_with_memory(model, u, 0.0, 0.0, 0.0, xs, vs, durations, forces, account)
    else:
        drive(model, u, 0.0, xs, vs, durations, forces, account)
    return (forces, float(account[SLIDERS])) if energy else forces


class Connector(OutputMemo):
    """The massless element of a scene driven by the relative motion (x, v) of its flanges.

    ``move_to(x, v, time)`` commits a new sample; ``preview(x, v)`` is the
    force there without committing (what an FMU output shows for an input
    set but not yet stepped). ``stiffness(v)`` is the tangent dF/dx.
    """

    def __init__(self, scene: Scene):
        _require_massless(scene)
        self.scene = scene
        self.reset()

    def reset(self) -> None:
        """Back to x = 0, v = 0, the scene's u0, time 0; the energy account restarts."""
        self._touch()
        self.branch_kernel = _branch_kernel(self.scene)
        self.model = compile_model(self.scene, self.branch_kernel)
        self.u = _initial_u(self.scene, self.model)
        self.x = self.v = self.time = 0.0
        self.direction = 1.0  # of the last motion: increasing x before any
        self.account = np.zeros(3)

    # ------------------------------------------------------------ outputs

    @property
    def force(self) -> float:
        """k0 x + k3 x^3 + c v + sum_i k_i u_i (N) at the committed sample."""
        m, k0, k3, c, k, eta, cs, friction, memory = self.model
        return self._memo("force", lambda: float(smooth_force(self.x, self.v, k0, k3, c) + branch_force(k, self.u)
                                                 + force_now(memory, self.time, self.x, self.v)))

    def preview(self, x: float, v: float) -> float:
        """The force if the flanges moved (monotonically) from the committed x to ``x``, at velocity
        ``v``; the state does not change."""
        if has_memory(self.model[8]):  # the move at this instant, on a copy (Dahl's force moves with x)
            twin = self.copy()
            twin.move_to(x, v)
            return twin.force
        return float(preview(self.model, self.u, x - self.x, v, x))

    def stiffness(self, v: Optional[float] = None) -> float:
        """dF/dx (N/m) at the committed state for a motion in the direction of ``v`` (default: the committed
        v); for v = 0, in the direction of the last motion (increasing x before any): k0 + 3 k3 x^2 + the
        stiffnesses of the branches that stick. A branch on its threshold that the motion pushes on slides
        and adds nothing; one that the motion takes off its threshold sticks."""
        v = self.v if v is None else v
        direction = self.direction if v == 0 else math.copysign(1.0, v)
        return self._memo(("stiffness", direction), lambda: float(tangent(self.model, self.x, self.u, direction)
                                                                  + tangent_now(self.model[8], direction)))

    def output_derivatives(self, x: float, v: float, x_derivatives=None, v_derivatives=None) -> dict:
        """The time derivatives of the force at the inputs (x, v) (the force :meth:`preview` shows), along the path
        the inputs' derivatives describe (FMI 2.0's input derivatives; None: not set), one-sided for the motion
        ahead (``kernels/rates.connector_rates``): ``{("force", 1): F', ("force", 2): F''}`` (N/s, N/s^2); x' is
        v where x's derivatives are not set, v' and v'' zero where v's are not. Exact between switches; ValueError
        with series dashpots or effects with memory (their forces' rates are not the tangent's), or for a
        non-finite value."""
        xd, vd = self._derivatives(x_derivatives, "x"), self._derivatives(v_derivatives, "v")
        if not (math.isfinite(x) and math.isfinite(v)):
            raise ValueError(f"the motion must be finite, got x = {x!r}, v = {v!r}")
        if self.scene.has_series_dashpots or has_memory(self.model[8]):
            raise ValueError("the force's derivatives with series dashpots or effects with memory: their forces' "
                             "rates are not given")
        twin = self.copy()
        twin.move_to(x, v)
        out = np.empty(2)
        connector_rates(twin.model, twin.x, twin.v, twin.u, xd, vd, twin.direction, out)
        return {("force", 1): float(out[0]), ("force", 2): float(out[1])}

    def stored_energy(self) -> float:
        """k0 x^2/2 + k3 x^4/4 + sum_i k_i u_i^2/2 (J)."""
        m, k0, k3, c, k, eta, cs, friction, memory = self.model
        return self._memo("stored_energy", lambda: float(stored(self.x, k0, k3, k, self.u)))

    def energy(self) -> dict:
        """stored_energy, dissipated_sliders, dissipated_damper (J) since the start."""
        return {"stored_energy": self.stored_energy(), "dissipated_sliders": float(self.account[SLIDERS]),
                "dissipated_damper": float(self.account[DAMPER])}

    def elongations(self) -> Optional[np.ndarray]:
        """u_i (m) in the scene's order (None without branches or for the continuum)."""
        if self.u is None or self.scene.branches.continuum:
            return None
        u = np.empty(self.scene.branches.n)
        write_elongations(self.model[4], self.u, u)
        return u

    def copy(self) -> "Connector":
        """An independent copy (the state is copied, the parameters shared: they are never modified)."""
        twin = Connector.__new__(Connector)
        twin.__dict__.update(self.__dict__)
        twin.u = None if self.u is None else self.u.copy()
        twin.model = self.model[:8] + (copy_memory(self.model[8]),)
        twin.account = self.account.copy()
        twin._touch()
        return twin

    # ------------------------------------------------------------ motion

    def move_to(self, x: float, v: float, time: Optional[float] = None) -> None:
        """Commit the sample (x, v) at ``time`` (s; default: the committed time). The branches follow the
        exact play update along the line from the committed x; the dashpot dissipates c (v0^2 + v0 v + v^2)
        (time - t0) / 3 (v linear in between). ValueError (nothing changed) for a non-finite value or a time
        that goes back; ElementError (nothing changed) when an output (force, energies) would overflow."""
        time = self.time if time is None else float(time)
        if not (math.isfinite(x) and math.isfinite(v)):
            raise ValueError(f"the motion must be finite, got x = {x!r}, v = {v!r}")
        if not (math.isfinite(time) and time >= self.time):
            raise ValueError(f"time {time!r} goes back (the connector is at t = {self.time!r})")
        problem = memory_time_problem(self.model[8], self.time, time)
        if problem:
            raise ValueError(f"the sample at t = {time!r} s refused: {problem}")
        dx = x - self.x
        u, account, force = self.u, self.account.copy(), np.empty(1)
        saved = None if u is None else u[:stack.used(u)].copy() if stack.is_stack(self.model[4]) else u.copy()
        saved_memory = copy_memory(self.model[8])
        self._touch()
        if has_memory(self.model[8]):
            drive_with_memory(self.model, u, self.x, self.v, self.time, np.array([x]), np.array([float(v)]),
                              np.array([time - self.time]), force, account)
        else:
            drive(self.model, u, self.x, np.array([x]), np.array([float(v)]), np.array([time - self.time]), force,
                  account)
        c = self.model[3]
        if c is not None:
            account[DAMPER] += c * (self.v * self.v + self.v * v + v * v) * (time - self.time) / 3.0
        m, k0, k3, c, k, eta, cs, friction, memory = self.model
        outputs = {"force": float(force[0]), "stored_energy": float(stored(x, k0, k3, k, u)),
                   "dissipated_sliders": float(account[SLIDERS]), "dissipated_damper": float(account[DAMPER])}
        for name, value in outputs.items():
            if not math.isfinite(value):
                if saved is not None:
                    u[:saved.shape[0]] = saved
                put_back(self.model[8], saved_memory)
                raise ElementError(f"the sample x = {x!r}, v = {v!r} at t = {time!r} s refused: {name} would not "
                                   "be finite (an overflow); the connector is unchanged")
        self.account[:] = account
        if dx != 0:
            self.direction = math.copysign(1.0, dx)
        self.x, self.v, self.time = float(x), float(v), time

    def advance(self, x: float, v: float, time: float, duration: float, x_derivatives=None,
                v_derivatives=None) -> None:
        """An FMU's doStep from ``time`` over ``duration`` (s): commit the sample (x, v) at ``time`` (:meth:`move_to`);
        with ``x_derivatives`` (x', x'') or ``v_derivatives`` (v', v'') (m/s, m/s^2; m/s^2, m/s^3: FMI 2.0's input
        derivatives, None: held) the flanges then move over the step along

            x(t) = x + x' (t - time) + x'' (t - time)^2 / 2,   v(t) = v + v' (t - time) + v'' (t - time)^2 / 2,

        the branches by the exact play update along each monotone piece (the path cut at its turning point,
        ``kernels/drive.py`` drive_polynomial), the dashpot dissipating c times the integral of v^2; the connector
        ends at time + duration on the path's end. Without derivatives the sample is held: the connector stays at
        ``time``. ValueError (nothing changed) for a non-finite value, a negative duration, derivatives with series
        dashpots or effects with memory (their forces depend on the path's timing, which this does not follow);
        ElementError (nothing changed) when an output would overflow."""
        xd, vd = self._derivatives(x_derivatives, "x"), self._derivatives(v_derivatives, "v")
        duration = float(duration)
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be finite and >= 0, got {duration!r}")
        if not (np.any(xd) or np.any(vd)):
            self.move_to(x, v, time)
            return
        if self.scene.has_series_dashpots or has_memory(self.model[8]):
            raise ValueError("input derivatives with series dashpots or effects with memory: their forces depend on "
                             "the path's timing, which the connector does not follow; hold the inputs")
        twin = self.copy()
        twin.move_to(x, v, time)
        out = np.empty(4)
        drive_polynomial(twin.model, twin.u, twin.x, twin.v, xd, vd, duration, twin.account, out)
        m, k0, k3, c, k, eta, cs, friction, memory = twin.model
        outputs = {"x": out[0], "v": out[1], "force": out[2], "stored_energy": stored(out[0], k0, k3, k, twin.u),
                   "dissipated_sliders": twin.account[SLIDERS], "dissipated_damper": twin.account[DAMPER]}
        for name, value in outputs.items():
            if not math.isfinite(value):
                raise ElementError(f"the step from t = {time!r} s over {duration!r} s with x = {x!r}, x' = {xd[0]!r}, "
                                   f"x'' = {xd[1]!r} refused: {name} would not be finite (an overflow); the connector "
                                   "is unchanged")
        if out[3] != 0:
            twin.direction = float(out[3])
        twin.x, twin.v, twin.time = float(out[0]), float(out[1]), twin.time + duration
        self.__dict__.update(twin.__dict__)
        self._touch()

    @staticmethod
    def _derivatives(values, name: str) -> np.ndarray:
        """``values`` (the first and second derivatives of input ``name``) as a finite array of two, zeros for None."""
        if values is None:
            return np.zeros(2)
        found = np.array([float(value) for value in values], dtype=float)
        if found.shape != (2,) or not np.all(np.isfinite(found)):
            raise ValueError(f"{name}_derivatives must be two finite numbers, got {values!r}")
        return found

    def set_coefficients(self, **values) -> None:
        """Change k0, k3, c, c_branch, or (before the first move: they restart the memory) the coefficients of
        the effects with memory (ValueError names the culprit, nothing changed)."""
        unknown = {name for name in values if name not in ("k0", "k3", "c") and not name.startswith("c_branch")
                   and _coefficient_key(name) not in MEMORY_COEFFICIENTS}
        if unknown:
            raise ValueError(f"{sorted(unknown)[0]}: not a coefficient of the connector (k0, k3, c, c_branch, and "
                             "those of [delay], [history], [dahl])")
        scene = with_coefficients(self.scene, **values)
        memory = [name for name in values if _coefficient_key(name) in MEMORY_COEFFICIENTS
                  and values[name] != coefficients_of(self.scene)[name]]
        if memory and (self.time or self.x or self.v):
            raise ValueError(f"{memory[0]}: an effect with memory restarts with its coefficients: set them before "
                             "the first move, or reset the connector")
        self.scene = scene
        self.model = with_scene_coefficients(self.scene, self.model)
        if memory:
            self.model = self.model[:8] + (compile_model(scene, self.branch_kernel)[8],)
        self._touch()

    def coefficients(self) -> dict:
        """k0, k3, c of the effects present (a connector has no mass)."""
        return coefficients_of(self.scene)

    # ------------------------------------------------------------ state

    def get_state(self) -> dict:
        """Everything that determines the continuation, as plain data."""
        state = {"time": self.time, "x": self.x, "v": self.v, "direction": self.direction,
                 "branch_kernel": self.branch_kernel, "energy_account": self.account.tolist(),
                 "coefficients": self.coefficients()}
        state["u"], state["u_reference"] = branch_state(self.scene, self.model[4], self.branch_kernel, self.u)
        if has_memory(self.model[8]):
            state["memory"] = memory_state(self.model[8])
        return state

    def set_state(self, state: dict) -> None:
        """Restore a state of :meth:`get_state`; checks it fully before changing anything (ValueError)."""
        values = [plain_number(state[key], key) for key in ("time", "x", "v", "direction")]
        account = number_list(state["energy_account"], "energy_account")
        if account.shape[0] != 3 or values[3] not in (-1.0, 1.0):
            raise ValueError("state does not fit the connector")
        if np.any(account[1:] < 0):  # (sliders, dashpot: a dissipation never gives energy back)
            raise ValueError(f"state has energy_account = {account.tolist()!r}: a dissipated energy is negative")
        kind = state["branch_kernel"]
        if kind != self.branch_kernel:
            raise ValueError(f"state has branch kernel {kind!r}, the connector uses {self.branch_kernel!r}")
        model, restored = restore_branch_state(self.scene, self.model[4], kind, state["u"], state["u_reference"])
        if not isinstance(state["coefficients"], dict):
            raise ValueError("state has no table of coefficients")
        scene = with_coefficients(self.scene, **state["coefficients"])
        memory = compile_model(scene, self.branch_kernel)[8]  # the state's coefficients, its arrays filled below
        if has_memory(memory) or "memory" in state:
            check_memory_state(memory, state.get("memory"), values[0])
            restore_memory(memory, state["memory"], values[0])
        model = with_scene_coefficients(scene, _smooth_model(scene) + model + (None, memory))
        m, k0, k3, c, k, eta, cs, friction, memory = model
        x, v = values[1], values[2]
        outputs = (smooth_force(x, v, k0, k3, c) + branch_force(k, restored) + force_now(memory, values[0], x, v),
                   stored(x, k0, k3, k, restored))
        if not all(math.isfinite(value) for value in outputs):
            raise ValueError(f"state has x = {x!r}, v = {v!r}: its force or energy is not finite")
        self.scene = scene
        self.model = model
        self.time, self.x, self.v, self.direction = values
        self.u = restored
        self.account[:] = account
        self._touch()
