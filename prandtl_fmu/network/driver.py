"""Running a network: whole runs (:func:`simulate`, :func:`simulate_chunks`), and the stepped objects an FMU
drives: :class:`NetworkElement` (force in at the load's node) and :class:`NetworkConnector` (motion in there).

The output of a run has the columns ``time``, ``x_<node>`` and ``v_<node>`` for every node, ``F`` and
``reaction`` (the force of the elements on the ground); with ``states`` the elongation ``u_<branch>`` of every
branch; with ``energy`` the account of the element (kinetic_energy, stored_energy, work, dissipated_sliders,
dissipated_damper, energy_residual) and the dissipation of every slider, branch and dashpot,
``dissipated_<kind>_<name>``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from time import perf_counter
from typing import Optional

import numpy as np

from . import kernels
from .model import NetworkScene, stepper_problem
from ..compiled import with_noise
from ..stepping import UNCHANGED, ElementError, OutputGrid, OutputMemo, _progress_bar, split_duration
from ..loads import force_at, held, noise_problem, plus, with_white_noise
from ..noise import new_cache
from ..scene import ADVANCE_BUDGET
from ..scene_tables import MAX_STEPS, SHORTEST_STEP, SceneError

ENERGY_COLUMNS = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
                  "energy_residual")
DISSIPATING = ("slider", "branch", "dashpot")
_CHUNK_SECONDS = 0.05
_CHUNK_VALUES = 2_000_000


def loop_for(stepper: str):
    return {"implicit": kernels.run_implicit, "projected": kernels.run_projected}[stepper]


def run_loop(loop, model, load, x, v, u, piece, t_base, first_step, h, steps_per_row, out, out_u, energy,
             out_energy, dissipated, out_dissipated, work):
    """``loop`` (:func:`loop_for`) with the rows not asked for (None: the elongations, the energy, the dissipation)
    handed as arrays with no column: the loop writes nothing there, and runs with and without them share one
    compiled loop (numba compiles one for each combination of types; the native FMU hands the same)."""
    rows = out.shape[0]
    empty = np.empty((rows, 0))
    return loop(model, load, x, v, u, piece, t_base, first_step, h, steps_per_row, out,
                empty if out_u is None else out_u, energy, empty if out_energy is None else out_energy,
                dissipated, empty if out_dissipated is None else out_dissipated, work)


def step_for(stepper: str):
    return {"implicit": kernels.implicit_step, "projected": kernels.projected_step}[stepper]


def check_applies(scene: NetworkScene, stepper: str) -> None:
    problem = stepper_problem(scene, stepper)
    if problem:
        raise ValueError(f"{scene.source}: {problem}")


def dissipation_columns(scene: NetworkScene) -> list:
    """dissipated_<kind>_<name> for every element that dissipates, in the scene's order."""
    return [f"dissipated_{e.kind}_{e.name}" for e in scene.network.elements if e.kind in DISSIPATING]


def _dissipating(scene: NetworkScene) -> np.ndarray:
    return np.array([e.kind in DISSIPATING for e in scene.network.elements], dtype=bool)


def columns_of(scene: NetworkScene, states: bool = False, energy: bool = False) -> list:
    """The CSV columns of a run, in order."""
    names = ["time"]
    for node in scene.network.nodes:
        names += [f"x_{node}", f"v_{node}"]
    names += ["F", "reaction"]
    if states:
        names += [f"u_{e.name}" for e in scene.network.of_kind("branch")]
    if energy:
        names += list(ENERGY_COLUMNS) + dissipation_columns(scene)
    return names


def failure_message(scene: NetworkScene, stepper: str, status: int, time: float, force: float) -> str:
    """Why the step from ``time`` could not be taken, in words."""
    where = f"{scene.source}: the {stepper} step from t = {float(time)!r} s (F = {float(force)!r} N)"
    if stepper == "instant":
        where = f"{scene.source}: at t = {float(time)!r} s (F = {float(force)!r} N), the network (an instant's move)"
    if status == -2:
        return (f"{where} has no equilibrium: a part of the network with no mass is pushed beyond what holds it "
                "(e.g. a massless chain pulled beyond the total friction of its nodes, or a massless node beyond "
                "its branches' strength)")
    if status == -1:
        n, count = scene.network.n, len(scene.network.elements)
        return (f"{where} refused: the active-set search did not end within its budget of "
                f"{kernels.search_budget(n, count)} iterations ({kernels.SEARCH_PER_TERM} per node and element "
                f"+ {kernels.SEARCH_CONSTANT}); a smaller step needs fewer")
    return f"{where} refused: a number overflowed (not finite)"


# ------------------------------------------------------------------ the initial state

def initial_state(scene: NetworkScene, model, load):
    """(x, v, u, piece) at t = 0: the scene's x0, v0, u0, and every massless node in equilibrium with F(0)
    (:func:`kernels.initial_state`, compiled: the native FMU calls the same). ElementError if none exists."""
    network = scene.network
    x = np.array(network.x0, dtype=float)
    v = np.array(network.v0, dtype=float)
    u = np.array([e.u0 for e in network.elements], dtype=float)
    piece = np.zeros(len(network.elements), dtype=np.int64)
    force = float(force_at(load, 0.0))
    status = kernels.initial_state(model, x, v, u, piece, force)
    if status < 0:
        raise ElementError(failure_message(scene, "instant", status, 0.0, force))
    return x, v, u, piece


def initial_reaction(scene: NetworkScene, model, x, v, u, force: float) -> float:
    """The reaction at t = 0 (:func:`kernels.initial_reaction`)."""
    return float(kernels.initial_reaction(model, x, v, u, float(force)))


# ------------------------------------------------------------------ whole runs

@dataclass
class NetworkResult:
    """Rows of a run: ``table`` (rows x columns) with the names ``names`` (see :func:`columns_of`)."""

    names: list
    table: np.ndarray
    stepper: str
    scene: NetworkScene

    def column(self, name: str) -> np.ndarray:
        return self.table[:, self.names.index(name)]

    def columns(self) -> dict:
        return {name: self.table[:, j] for j, name in enumerate(self.names)}

    @property
    def time(self) -> np.ndarray:
        return self.table[:, 0]

    @property
    def x(self) -> np.ndarray:
        """rows x nodes."""
        n = self.scene.network.n
        return self.table[:, 1:1 + 2 * n:2]

    @property
    def v(self) -> np.ndarray:
        n = self.scene.network.n
        return self.table[:, 2:2 + 2 * n:2]

    @property
    def F(self) -> np.ndarray:
        return self.column("F")

    @property
    def reaction(self) -> np.ndarray:
        return self.column("reaction")

    def write_csv(self, file, header: bool = True) -> None:
        """Every float in full precision (repr), as the element's CSV; ``header=False``: the rows only."""
        if header:
            file.write(",".join(self.names) + "\n")
        block = max(1, 100_000 // self.table.shape[1])  # rows turned into text at a time: a few MB
        for first in range(0, self.table.shape[0], block):
            rows = self.table[first:first + block].tolist()
            file.write("".join(",".join(map(repr, row)) + "\n" for row in rows))


def simulate(scene: NetworkScene, stepper: Optional[str] = None, *, states: bool = False, energy: bool = False,
             progress: Optional[bool] = None) -> NetworkResult:
    """Run ``scene`` with its solver settings (``stepper`` overrides the scene's); ElementError when a step
    cannot be taken, ValueError when the stepper does not apply."""
    chunks = list(simulate_chunks(scene, stepper, states=states, energy=energy, progress=progress))
    return NetworkResult(chunks[0].names, np.concatenate([c.table for c in chunks]), chunks[0].stepper, scene)


def simulate_chunks(scene: NetworkScene, stepper: Optional[str] = None, *, states: bool = False,
                    energy: bool = False, progress: Optional[bool] = None):
    """:func:`simulate` as a generator of consecutive pieces (the first is the initial row); the same numbers
    however the run is cut (step p at t_p = p h). Checks everything before the first piece."""
    name = stepper or scene.solver.stepper
    if name not in ("implicit", "projected"):
        problem = stepper_problem(scene, name)
        raise ValueError(f"{scene.source}: {problem}")
    check_applies(scene, name)
    from ..resources import check_memory

    network = scene.network
    width = len(columns_of(scene, states, energy))
    # the model and the workspace (about 20 numbers per node and element) and a few output rows
    check_memory(8.0 * (4 * width + 20 * (network.n + len(network.elements))),
                 f"{scene.source}: a network of {network.n} nodes and {len(network.elements)} elements")
    return _chunks(scene, name, states, energy, progress)


def _chunks(scene, name, states, energy, progress):
    solver = scene.solver
    network = scene.network
    model = network.compile()
    load = scene.load.compile()
    n, count = network.n, len(network.elements)
    names = columns_of(scene, states, energy)
    branches = len(network.of_kind("branch"))
    sense = network.branch_sense()
    keep = _dissipating(scene)
    h, per_row = solver.step, solver.steps_per_output
    grid = OutputGrid(solver.stop_time, solver.output_interval, solver.step)
    x, v, u, piece = initial_state(scene, model, load)
    work = kernels.workspace(n, count)
    account = np.zeros(3) if energy else None
    dissipated = np.zeros(count) if energy else None
    loop = loop_for(name)
    initial_energy = 0.0

    def piece_arrays(rows):
        out = np.empty((rows, 2 * n + 2))
        out_u = np.empty((rows, branches)) if states else None
        out_energy = np.zeros((rows, 5)) if energy else None
        out_dissipated = np.zeros((rows, count)) if energy else None
        return out, out_u, out_energy, out_dissipated

    def result(first, out, out_u, out_energy, out_dissipated):
        rows = out.shape[0]
        parts = [grid.times(first, rows)[:, None], out]
        if states:
            parts.append(out_u * sense)  # as written (x_j - x_i), not as kept: Element.sense
        if energy:
            residual = out_energy[:, 2] - out_energy[:, 3] - out_energy[:, 4] - (
                out_energy[:, 0] + out_energy[:, 1] - initial_energy)
            parts += [out_energy, residual[:, None], out_dissipated[:, keep]]
        table = np.concatenate(parts, axis=1)
        bad = ~np.isfinite(table)
        if np.any(bad):
            row, col = np.argwhere(bad)[0]
            raise ElementError(f"{scene.source}: {names[col]} is not finite at t = {table[row, 0]!r} s (an "
                               "overflow): the run stops there")
        return NetworkResult(names, table, name, scene)

    out, out_u, out_energy, out_dissipated = piece_arrays(1)
    force0 = float(force_at(load, 0.0))
    kernels.write_row(model, load, 0.0, x, v, u, initial_reaction(scene, model, x, v, u, force0), out[0],
                      account, None if out_energy is None else out_energy[0], None if out_u is None else out_u[0])
    if energy:
        initial_energy = out_energy[0, 0] + out_energy[0, 1]
    yield result(0, out, out_u, out_energy, out_dissipated)

    rows = grid.rows
    last_is_short = grid.last_is_short
    full_rows = rows - 1 - last_is_short
    most = max(1, _CHUNK_VALUES // max(1, 2 * n + 2 + branches + count))
    chunk = 1
    bar = _progress_bar(progress, total=rows - 1, label=f"{scene.name} [{name}]")
    try:
        j = 0
        while j < full_rows:
            rows_now = min(chunk, full_rows - j)
            started = perf_counter()
            out, out_u, out_energy, out_dissipated = piece_arrays(rows_now)
            taken, status = run_loop(loop, model, load, x, v, u, piece, 0.0, j * per_row, h, per_row, out, out_u,
                                     account, out_energy, dissipated, out_dissipated, work)
            if taken < per_row * rows_now:
                time = (j * per_row + taken) * h
                raise ElementError(failure_message(scene, name, status, time, force_at(load, time + h)))
            elapsed = perf_counter() - started
            chunk = min(most, max(1, int(rows_now * min(_CHUNK_SECONDS / max(elapsed, 1e-9), 8.0))))
            yield result(1 + j, out, out_u, out_energy, out_dissipated)
            j += rows_now
            bar.update(rows_now)
        if last_is_short:
            whole, rest = grid.tail(h)
            out, out_u, out_energy, out_dissipated = piece_arrays(1)
            first = full_rows * per_row
            if whole:
                taken, status = run_loop(loop, model, load, x, v, u, piece, 0.0, first, h, whole, out, out_u,
                                         account, out_energy, dissipated, out_dissipated, work)
                if taken < whole:
                    time = (first + taken) * h
                    raise ElementError(failure_message(scene, name, status, time, force_at(load, time + h)))
            if rest:
                start = (first + whole) * h
                taken, status = run_loop(loop, model, load, x, v, u, piece, start, 0, rest, 1, out, out_u,
                                         account, out_energy, dissipated, out_dissipated, work)
                if taken < 1:
                    raise ElementError(failure_message(scene, name, status, start, force_at(load, start + rest)))
            yield result(rows - 1, out, out_u, out_energy, out_dissipated)
            bar.update(1)
    finally:
        bar.close()


# ------------------------------------------------------------------ stepped objects (FMUs)

class NetworkElement(OutputMemo):
    """The network driven by a force at its load's node, advanced by communication steps (an element FMU).

    ``advance(duration, force)`` holds ``force`` (plus the scene's [load] with ``scene_load``) over
    ``duration``, in steps of the scene's h on a grid that does not depend on how the advances are cut (the
    element's rules: :class:`prandtl_fmu.driver.Element`). Outputs: :attr:`x`, :attr:`v` (per node),
    :attr:`reaction`, :meth:`energy`."""

    # set_state checks a saved reaction against what the state's x, v and u fix of it (kernels.reaction_fits)
    CHECKS_REACTION = True

    def __init__(self, scene: NetworkScene, stepper: Optional[str] = None, step: Optional[float] = None,
                 noise=UNCHANGED):
        self.scene = scene
        self.stepper = stepper or scene.solver.stepper
        # the white noise on the load's node (set_noise; default the scene's), the stepper checked with it
        self.noise = scene.load.noise if noise is UNCHANGED else noise
        check_applies(with_noise(scene, self.noise), self.stepper)
        self.h = float(step if step is not None else scene.solver.step)
        if not (math.isfinite(self.h) and self.h > 0):
            raise ValueError(f"step must be a finite number > 0, got {step!r}")
        problem = noise_problem(self.noise, self.h)
        if problem:
            raise ValueError(problem)
        self.reset()

    def set_noise(self, noise) -> None:
        """The white noise (``loads.WhiteNoise``, or None: none) on the load's node from the next advance on,
        whether or not the scene's [load] is added (an FMU's noise_intensity, noise_seed, noise_unit);
        ValueError (nothing changed) where the network cannot carry one (a massless load node without a
        dashpot)."""
        check_applies(with_noise(self.scene, noise), self.stepper)
        problem = noise_problem(noise, self.h)
        if problem:
            raise ValueError(problem)
        self.noise = noise
        self._touch()

    def reset(self, force: float = 0.0) -> None:
        network = self.scene.network
        self.model = network.compile()
        self._origin, self._steps, self._grid = 0.0, 0, None
        self.held_force = float(force)
        self._load = held(self.held_force)
        self.x, self.v, self.u, self.piece = initial_state(self.scene, self.model, self._load)
        self.work = kernels.workspace(network.n, len(network.elements))
        # the Brownian tree's cache of a white noise in [load]: scratch (never saved; any cache gives the same
        # increments), kept across advances so that stepping forward costs about one normal per step
        self._noise_cache = new_cache()
        self.account = np.zeros(3)
        self.dissipated = np.zeros(len(network.elements))
        self._reaction = initial_reaction(self.scene, self.model, self.x, self.v, self.u, self.held_force)
        self.initial_energy = self._energies()[0] + self._energies()[1]
        self._touch()

    @property
    def time(self) -> float:
        return self._origin + self._steps * self._grid if self._steps else self._origin

    @time.setter
    def time(self, value: float) -> None:
        value = float(value)
        if not math.isfinite(value):
            raise ValueError(f"time must be finite, got {value!r}")
        if self._grid is not None and abs(value - self.time) <= 1e-9 * min(self._grid, abs(value)):
            return
        self._origin, self._steps = value, 0

    @property
    def reaction(self) -> float:
        return float(self._reaction)

    def elongation(self, e: int) -> float:
        """The elongation of element ``e`` (a branch: its spring's u) as its ``between = [i, j]`` is written, x_j -
        x_i's sense (the state keeps it as the kernels do: :class:`network.model.Element`'s ``sense``)."""
        return float(self.scene.network.elements[e].sense * self.u[e])

    def _energies(self):
        return (float(kernels.kinetic(self.model[0], self.v)), float(kernels.stored(self.model, self.x, self.u)))

    def energy(self) -> dict:
        """kinetic_energy, stored_energy, work, dissipated_sliders, dissipated_damper, energy_residual (J)."""
        def account():
            kinetic, stored = self._energies()
            work, sliders, damper = self.account.tolist()
            return {"kinetic_energy": kinetic, "stored_energy": stored, "work": work, "dissipated_sliders": sliders,
                    "dissipated_damper": damper,
                    "energy_residual": work - sliders - damper - (kinetic + stored - self.initial_energy)}
        return dict(self._memo("energy", account))

    def checkpoint(self):
        return (self.x.copy(), self.v.copy(), self.u.copy(), self.piece.copy(), self.account.copy(),
                self.dissipated.copy(), self._reaction, self._origin, self._steps, self._grid, self.held_force,
                self._load)

    def rollback(self, saved) -> None:
        (x, v, u, piece, account, dissipated, self._reaction, self._origin, self._steps, self._grid,
         self.held_force, self._load) = saved
        self.x[:], self.v[:], self.u[:], self.piece[:] = x, v, u, piece
        self.account[:], self.dissipated[:] = account, dissipated
        self._touch()

    def advance(self, duration: float, force: float, scene_load: bool = False) -> None:
        """Advance by ``duration`` (s) under ``force`` (N); ElementError (state unchanged) when a step cannot be
        taken or an output would overflow, ValueError for a bad argument."""
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be finite and >= 0, got {duration!r}")
        if not math.isfinite(force):
            raise ValueError(f"force must be finite, got {force!r}")
        if duration == 0:
            return
        h = self.h
        if duration < SHORTEST_STEP:
            raise ValueError(f"duration {duration!r} s is shorter than {SHORTEST_STEP:g} s")
        if not duration / h < MAX_STEPS:
            raise ValueError(f"duration {duration!r} s is more than 2^53 steps of h = {h!r} s")
        whole, rest = split_duration(duration, h, self.time + duration)
        if not (whole or rest):  # shorter than rounding of h: no step, the clock on its grid (Element.advance)
            return
        if whole + (rest > 0) > ADVANCE_BUDGET:
            raise ElementError(f"{self.scene.source}: an advance of {duration!r} s takes {whole + (rest > 0):.4g} "
                               f"steps of h = {h!r} s, more than the budget of {ADVANCE_BUDGET:.0e} steps of one "
                               "advance: advance by shorter durations or with a larger step")
        problem = noise_problem(self.noise, self.h, self.time + duration)  # the Brownian tree's end
        if problem:
            raise ElementError(f"{self.scene.source}: the advance to t = {self.time + duration!r} s refused: "
                               f"{problem}")
        saved = self.checkpoint()
        load = plus(self.scene.load.compile(), force) if scene_load else held(force)
        load = with_white_noise(load, self.noise, self._noise_cache)
        self.held_force, self._load = float(force), load
        self._touch()
        if self._grid != h:
            self._origin, self._steps, self._grid = self.time, 0, h
        step = step_for(self.stepper)
        try:
            self._steps_from(step, load, self._origin, self._steps, whole, h)
            if rest:
                self._steps_from(step, load, self._origin + (self._steps + whole) * h, 0, 1, rest)
        except ElementError:
            self.rollback(saved)
            raise
        if rest:
            self._origin, self._steps = self._origin + (self._steps + whole) * h + rest, 0
        else:
            self._steps += whole
        values = np.concatenate([self.x, self.v, [self._reaction], list(self.energy().values())])
        if not np.all(np.isfinite(values)):
            time = self.time
            self.rollback(saved)
            raise ElementError(f"{self.scene.source}: the advance to t = {time!r} s with F = {float(force)!r} N "
                               "refused: an output would not be finite (an overflow); the state is unchanged")

    def _steps_from(self, step, load, t_base, first, count, h):
        if count == 0:
            return
        out = np.empty((1, 2 * self.scene.network.n + 2))
        taken, status = run_loop(loop_for(self.stepper), self.model, load, self.x, self.v, self.u, self.piece,
                                 t_base, first, h, count, out, None, self.account, None, self.dissipated, None,
                                 self.work)
        if taken < count:
            time = t_base + (first + taken) * h
            raise ElementError(failure_message(self.scene, self.stepper, status, time, force_at(load, time + h)))
        self._reaction = out[0, -1]

    def set_parameters(self, **values) -> None:
        """Change coefficients by parameter name (m_<node>, k_spring_1, alpha_n3, ...): SceneError names the
        culprit and changes nothing. A change of a mass to or from 0 or of a topology rule is checked."""
        network = self.scene.network.with_parameters(**values)
        for e, element in enumerate(network.elements):
            if element.kind == "branch" and abs(self.u[e]) > element.eta:
                raise SceneError(f"eta_{element.name}: {element.eta!r} is below the branch's elongation now, "
                                 f"|u| = {abs(float(self.u[e]))!r}: it would drop stored energy unbooked")
        scene = self.scene.with_network(network)
        problem = stepper_problem(with_noise(scene, self.noise), self.stepper)
        if problem:
            raise SceneError(f"{', '.join(values)}: {problem}")
        model = network.compile()
        # the reaction in the state as it stands, under the new coefficients (as the element's): what x, v, u fix
        # of it changes with them, the stuck sliders' part stays (set_state checks a saved one against the same)
        if self.CHECKS_REACTION:
            stepped = np.bool_(self._grid is not None)
            before = kernels.reaction_range(self.model, self.x, self.v, self.u, self.piece, stepped)[0]
            after = kernels.reaction_range(model, self.x, self.v, self.u, self.piece, stepped)[0]
            if after != before:
                self._reaction = self._reaction - before + after
        self.scene = scene
        self.model = model
        self._touch()

    def get_state(self) -> dict:
        """Everything that determines the continuation, as plain data."""
        return {"time": self.time, "origin": self._origin, "steps": self._steps, "grid": self._grid,
                "force": self.held_force, "x": self.x.tolist(), "v": self.v.tolist(), "u": self.u.tolist(),
                "piece": self.piece.tolist(), "account": self.account.tolist(),
                "dissipated": self.dissipated.tolist(), "reaction": self._reaction,
                "initial_energy": self.initial_energy, "parameters": self.scene.network.parameters()}

    def set_state(self, state: dict) -> None:
        """Restore :meth:`get_state`'s data; checked whole before anything changes (ValueError names what)."""
        network = self.scene.network
        n, count = network.n, len(network.elements)
        try:
            arrays = {key: np.array(state[key], dtype=float) for key in ("x", "v", "u", "account", "dissipated")}
            piece = np.array(state["piece"], dtype=float)
            scalars = [float(state[key]) for key in ("origin", "force", "reaction", "initial_energy")]
            steps = state["steps"]
            grid = state["grid"]
            parameters = state["parameters"]
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"state does not fit the network: {exc}") from None
        shapes = {"x": n, "v": n, "u": count, "account": 3, "dissipated": count}
        for key, size in shapes.items():
            if arrays[key].shape != (size,) or not np.all(np.isfinite(arrays[key])):
                raise ValueError(f"state's {key} must be {size} finite numbers")
        if np.any(arrays["account"][1:] < 0) or np.any(arrays["dissipated"] < 0):
            raise ValueError("state's dissipated energies must be >= 0 (a dissipation never gives energy back)")
        if piece.shape != (count,) or not np.all(np.isin(piece, (-2, -1, 0, 1, 2))):
            raise ValueError("state's piece must hold one of -2..2 per element")
        if not all(math.isfinite(s) for s in scalars):
            raise ValueError("state's time, force, reaction and energy must be finite")
        if isinstance(steps, bool) or not isinstance(steps, int) or steps < 0 or grid is not None and not (
                isinstance(grid, float) and math.isfinite(grid) and grid > 0):
            raise ValueError("state's clock (steps, grid) is broken")
        if not isinstance(parameters, dict):
            raise ValueError("state has no table of parameters")
        try:
            restored = network.with_parameters(**parameters)
        except SceneError as exc:
            raise ValueError(f"state's parameters: {exc}") from None
        allowed = {"slider": (-1, 0, 1), "branch": (-2, -1, 0, 1, 2)}
        for e, element in enumerate(restored.elements):
            if piece[e] not in allowed.get(element.kind, (0,)):
                raise ValueError(f"state's piece of {element.name} ({piece[e]!r}) is not one of its law's pieces")
            u = arrays["u"][e]
            if element.kind == "branch" and not abs(u) <= element.eta or element.kind != "branch" and u != 0:
                raise ValueError(f"state's u of {element.name} ({u!r}) is outside its elastic range")
        problem = stepper_problem(with_noise(self.scene.with_network(restored), self.noise), self.stepper)
        if problem:
            raise ValueError(f"state's parameters: {problem}")
        model = restored.compile()
        reaction, pieces, stepped = scalars[2], piece.astype(np.int64), np.bool_(grid is not None)
        if self.CHECKS_REACTION and not kernels.reaction_fits(model, arrays["x"], arrays["v"], arrays["u"], pieces,
                                                              stepped, reaction):
            fixed, free, _ = kernels.reaction_range(model, arrays["x"], arrays["v"], arrays["u"], pieces, stepped)
            raise ValueError(f"state's reaction ({reaction!r} N) is not the one its x, v and u give ({fixed!r} N, "
                             f"{free!r} N either way by its stuck sliders)")
        self.scene = self.scene.with_network(restored)
        self.model = model
        self.x[:], self.v[:], self.u[:] = arrays["x"], arrays["v"], arrays["u"]
        self.piece[:] = piece.astype(np.int64)
        self.account[:], self.dissipated[:] = arrays["account"], arrays["dissipated"]
        self._origin, self.held_force, self._reaction, self.initial_energy = scalars
        self._steps, self._grid = steps, grid
        self._load = held(self.held_force)
        self._touch()


class NetworkConnector(NetworkElement):
    """The network with the motion of its load's node imposed (a connector FMU: x, v in; force out).

    ``move_to(x, v, time)`` advances from the committed time to ``time`` in steps of the scene's h from the
    committed time (and a last shorter one), the load's node following the line from the committed x to ``x``;
    the rest of the network responds (masses, dashpots, sliders). A move at the committed time is an instant
    (:func:`kernels.jump_node`: the masses and dashpots do not move). :attr:`force` is the force of the
    network's elements on that node (what holds the motion). The load's node must stay massless."""

    # its reaction after an instant's move is the last step's, and its node's v the master's: not what x, v fix
    CHECKS_REACTION = False

    def __init__(self, scene: NetworkScene, stepper: Optional[str] = None, step: Optional[float] = None,
                 noise=UNCHANGED):
        if scene.network.mass[scene.network.load_node] > 0:
            raise ValueError(f"{scene.source}: the connector imposes the motion of the load's node "
                             f"{scene.network.nodes[scene.network.load_node]}, which must be massless")
        super().__init__(scene, stepper, step, noise)
        if self.stepper != "implicit":
            raise ValueError(f"{scene.source}: the connector takes 'implicit' steps (the imposed motion is a "
                             "constraint)")
        self._force = 0.0

    def reset(self, force: float = 0.0) -> None:
        super().reset(0.0)
        self._force = self._reaction_force()
        self._touch()

    @property
    def force(self) -> float:
        return float(self._force)

    def get_state(self) -> dict:
        state = super().get_state()
        state["connector_force"] = self._force
        return state

    def set_state(self, state: dict) -> None:
        """:meth:`NetworkElement.set_state`, and the force that held the node (part of the state: it comes from
        the last step's equilibrium)."""
        force = state.get("connector_force") if isinstance(state, dict) else None
        if isinstance(force, bool) or not isinstance(force, (int, float)) or not math.isfinite(force):
            raise ValueError("state has no finite connector_force")
        parameters = state.get("parameters")
        load = f"m_{self.scene.network.nodes[self.scene.network.load_node]}"
        if isinstance(parameters, dict) and parameters.get(load, 0.0) != 0.0:
            raise ValueError(f"state's {load} must be 0: the connector's load node is massless")
        super().set_state(state)
        self._force = float(force)

    def set_parameters(self, **values) -> None:
        """:meth:`NetworkElement.set_parameters`; the load node's mass stays 0."""
        load = f"m_{self.scene.network.nodes[self.scene.network.load_node]}"
        if load in values and values[load] != 0:
            raise SceneError(f"{load}: the connector imposes the motion of its load node, which must stay massless")
        super().set_parameters(**values)

    def _reaction_force(self) -> float:
        return float(kernels.node_force(self.model, self.work[5], self.scene.network.load_node))

    def move_to(self, x: float, v: float, time: float) -> None:
        """Commit the motion (x, v) of the load's node at ``time``; ValueError for a bad argument, ElementError
        (state unchanged) when a step cannot be taken."""
        if not (math.isfinite(x) and math.isfinite(v) and math.isfinite(time)):
            raise ValueError(f"the motion must be finite, got x = {x!r}, v = {v!r}, time = {time!r}")
        start = self.time
        if time < start:
            raise ValueError(f"time {time!r} goes back (the connector is at t = {start!r})")
        saved = self.checkpoint()
        saved_force = self._force
        node = self.scene.network.load_node
        duration = time - start
        if split_duration(duration, self.h, time) == (0, 0.0):  # below rounding of h: a sample at the instant it is at
            duration = 0.0
        try:
            if duration == 0:
                status, held = kernels.jump_node(self.model, self.x, self.v, self.u, self.piece, self.account,
                                                 self.dissipated, node, float(x))
                if status < 0:
                    raise ElementError(failure_message(self.scene, "instant", status, start, 0.0))
            else:
                h = self.h
                whole, rest = split_duration(duration, h, time)
                if whole + (rest > 0) > ADVANCE_BUDGET:
                    raise ElementError(f"{self.scene.source}: a move over {duration!r} s takes more than "
                                       f"{ADVANCE_BUDGET:.0e} steps")
                status, _ = kernels.move_node(self.model, self.x, self.v, self.u, self.piece, self.work,
                                              self.account, self.dissipated, node, float(x), whole, h, rest)
                if status < 0:
                    raise ElementError(failure_message(self.scene, "implicit", status, start, 0.0))
                self._origin, self._steps, self._grid = time, 0, h
        except ElementError:
            self.rollback(saved)
            self._force = saved_force
            raise
        self.v[node] = v
        self._force = held if duration == 0 else self._reaction_force()
        if duration != 0:  # the reaction on the ground after the last step (an instant keeps the last one)
            ends = self.model[2]
            self._reaction = float(np.sum(self.work[5][ends[:, 1] == kernels.GROUND]))
        if not math.isfinite(self._force) or not np.all(np.isfinite(self.x)):
            self.rollback(saved)
            self._force = saved_force
            raise ElementError(f"{self.scene.source}: the motion x = {x!r} at t = {time!r} s refused: an output "
                               "would not be finite (an overflow); the connector is unchanged")
        self._touch()
