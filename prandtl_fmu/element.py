"""The element of a scene as a stateful object (:class:`Element`): what every FMU runs, and any co-simulation master.

It advances by arbitrary durations under a held force (whole internal steps of h, then one shorter step), keeps
its clock on its step grid, its energy account and its outputs, switches stepper, step and coefficients between
advances, and saves and restores its state as plain data (``get_state``/``set_state``; a cheap ``checkpoint``
and ``rollback`` for a refused advance). Every step is the stepper's compiled loop, as in the batch driver
(``driver.py``): an Element advanced over a run's steps gives :func:`driver.simulate`'s numbers to the bit.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Optional

import numpy as np

from .compiled import (_is_network, _memory_model, _smooth_model, branch_state, choose_branch_kernel, compile_loop,
                       compile_model, restore_branch_state, with_noise, with_scene_coefficients)
from .kernels import stack
from .kernels.drive import tangent
from .kernels.energy import kinetic, stored
from .kernels.friction import reaction
from .kernels.play import branch_force, write_elongations
from .kernels.rates import exact_rates, output_rates
from .loads import held, noise_problem, plus, polynomial, with_white_noise
from .memory import (check_memory_state, copy_memory, has_memory, memory_state, put_back, restore_memory)
from .memory import time_problem as memory_time_problem
from .noise import new_cache
from .saved_state import number_list, plain_number
from .scene import ADVANCE_BUDGET, MEMORY_COEFFICIENTS, Scene, _coefficient_key, coefficients_of, with_coefficients
from .scene_tables import MAX_STEPS, SHORTEST_STEP
from .scene import _check_memory_rules as check_memory_rules
from .stability import stability_problem
from .steppers import get_stepper
from .stepping import (ENERGY_COLUMNS, FRICTION_COLUMN, UNCHANGED, ElementError, OutputMemo, _account_columns,
                       _advance, _failure, initial_state, split_duration)


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

    def _load_of(self, force: float, scene_load: bool, derivatives=None):
        """The compiled load of an advance: ``force`` held (plus the scene's [load] with ``scene_load``), or with
        ``derivatives`` (F', F'') its Taylor polynomial from the element's time (:func:`loads.polynomial`), and
        the element's white noise."""
        if derivatives is not None:
            base = polynomial(force, derivatives[0], derivatives[1], self.time)
        else:
            base = plus(self.scene.load.compile(), force) if scene_load else held(force)
        return with_white_noise(base, self.noise, self._noise_cache)

    def _derivatives_of(self, force_derivatives, scene_load: bool):
        """``force_derivatives`` (F', F'') as two floats, None when both are zero (the force is held: the same
        compiled load, bit for bit, as without them); ValueError naming the culprit."""
        if force_derivatives is None:
            return None
        rate, curvature = (float(value) for value in force_derivatives)
        for order, value in ((1, rate), (2, curvature)):
            if not math.isfinite(value):
                raise ValueError(f"the force's derivative of order {order} must be finite, got {value!r}")
        if rate == 0.0 and curvature == 0.0:
            return None
        if scene_load:
            raise ValueError("force derivatives with scene_load: the force is F plus the scene's [load], which the "
                             "derivatives of F alone do not describe")
        if not getattr(get_stepper(self.stepper), "POLYNOMIAL_INPUT", True):
            raise ValueError(f"force derivatives with stepper {self.stepper!r}: its closed forms take the scene's "
                             "load kinds, not a polynomial force; use another stepper or hold the force")
        return rate, curvature

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
        """Set the clock (a master's communication point): a value within 1e-9 h and 1e-9 of itself of the
        element's own time is the same instant (a master's clock that adds up its steps drifts by ulps) and keeps
        the grid; another starts a new grid there."""
        value = float(value)
        if not math.isfinite(value):
            raise ValueError(f"time must be finite, got {value!r}")
        if self._grid is not None and abs(value - self.time) <= 1e-9 * min(self._grid, abs(value)):
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

    def output_derivatives(self, force: float, scene_load: bool = False) -> dict:
        """The time derivatives of the outputs at the current state under ``force`` held (plus the scene's [load]
        at the element's time with ``scene_load``), one-sided for the motion ahead (``kernels/rates.py``):
        ``{(name, order): value}`` with ("x", 1) = v, and for an element with a mass ("x", 2) = ("v", 1) = a,
        and where they are exact (``rates.exact_rates``: no friction on the mass, no series dashpot, no effect with
        memory) ("reaction", 1) = R' and, but with ``scene_load`` (whose F' it does not take), ("v", 2) = a'."""
        found = {("x", 1): float(self.v)}
        if self.scene.mass is None:
            return found
        out = np.empty(3)
        output_rates(self.model, self._load_of(force, scene_load), self.time, self.x, self.v, self.u, out)
        found[("x", 2)] = found[("v", 1)] = float(out[0])
        if exact_rates(self.scene):
            found[("reaction", 1)] = float(out[2])
            if not scene_load:
                found[("v", 2)] = float(out[1])
        return found

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

    def advance(self, duration: float, force: float, scene_load: bool = False, force_derivatives=None) -> None:
        """Advance by ``duration`` (s) with the force held at ``force`` (N); with ``scene_load``, the force is
        ``force`` plus the scene's ``[load]`` F(t), evaluated by the stepper as in :func:`simulate` (the
        element's ``time`` is the load's clock). With ``force_derivatives`` = (F', F'') (N/s, N/s^2) the force is
        F(t) = force + F' (t - t0) + F'' (t - t0)^2 / 2 from the element's time t0, evaluated wherever the stepper
        evaluates its force (an FMU input given with its derivatives; not with ``scene_load``, nor with a stepper
        whose closed forms know the scene's load kinds only: ValueError). A duration below 1e-9 h, like a remainder below it after the
        whole steps, is rounding of a master's clock (:func:`split_duration`): it changes nothing.

        ElementError (state unchanged) when a step cannot be taken.
        """
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be finite and >= 0, got {duration!r}")
        if not math.isfinite(force):
            raise ValueError(f"force must be finite, got {force!r}")
        derivatives = self._derivatives_of(force_derivatives, scene_load)
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
        whole, rest = split_duration(duration, h, self.time + duration)
        # below rounding of h: no step, and the clock stays on its grid (the time setter takes the master's next
        # communication point, within 1e-9 h of it, as this instant)
        if not (whole or rest):
            return
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
        load = self._load_of(force, scene_load, derivatives)
        # the reaction's F(t) after the advance is the force as set (an FMU's input variable), held
        self.force, self._load = float(force), load if derivatives is None else self._load_of(force, scene_load)
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
        if np.any(account[1:] < 0):  # (sliders, dashpot, friction: a dissipation never gives energy back)
            raise ValueError(f"state has energy_account = {booked!r}: a dissipated energy is negative")
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
