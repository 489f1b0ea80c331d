"""The forced frequency response: a mass on the element under F = F0 cos(2 pi f t), frequency by frequency.

At each frequency f (Hz) the scene (with its ``[mass]``; its own ``[load]`` replaced by F0 cos(omega t),
omega = 2 pi f) is run period by period with a stepper, M steps of h = 1 / (f M) per period, from the
state that the previous frequency left (continuation; the first from the scene's initial state). After each
period the first harmonic of x over it,

    X = (2 / M) sum_j x(t_j) exp(-i omega t_j)      (t_j the step ends of the period),
    x_1(t) = Re(X exp(i omega t)) = amplitude cos(omega t + phase),  amplitude = |X| (m), phase = arg X (rad),

is compared with the last one's. **The settling test** (:func:`prandtl_fmu.frequency.settled`): the run is
steady when the relative change d_p of X over the last period (or, if larger, the drift |x(end) - x(start)|
of the period against |X|: a periodic motion comes back), plus the geometric tail d_p r / (1 - r) of the
changes still to come (r the larger of the last two ratios d_p / d_(p-1)), is at most tolerance / 4, after
at least four periods (or when X repeats to 1e-12); past MAX_PERIODS periods the frequency is refused with
the change reached. Then M is doubled (from the settled state) until the relative change of X under the last
doubling plus the settling remainder (:func:`prandtl_fmu.frequency.settling_remainder`: what the settling test
leaves) is at most the tolerance (1e-3 relative of |X| by default); past MAX_STEPS steps per period, refused. The phase is that of x against
the force: x lags by -phase, in (-pi, pi]; 0 where the mass does not move at all (amplitude 0). A frequency
so high that the mass's motion F0 / (m omega^2) underflows in the steps is refused (:func:`_check_resolved`).

The stepper: the one given, else the one the scene's ``[solver]`` names, else ``exact`` where it applies
(exact between events: M only sets the quadrature of X) and the branches are few (EXACT_UP_TO), else
``verlet`` (order 2), else ``implicit``.

Where the response has several branches (a jump), the sweep up (continuing from the lower frequency) and the
sweep down (from the higher) settle on different ones: both are run (``sweep``: "up", "down" or "both", the
default for a nonlinear scene with more than one frequency) and each row says which.

On dask.distributed (``client``, ``scheduler`` or ``workers``): each direction's frequencies are cut into
contiguous blocks, one task each (two blocks per direction and worker count); a block continues from the
scene's initial state at its first frequency, as a fresh sweep would. Needs the ``sweep`` extra.
"""
from __future__ import annotations

import dataclasses
import math
import sys
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..compiled import choose_branch_kernel, compile_loop, compile_model
from ..effects import Mass
from ..kernels import stack
from ..loads import HarmonicLoad
from ..stability import stability_problem
from ..steppers import STEPPERS, get_stepper
from ..stepping import ElementError, _failure, _progress_bar, integrate
from . import DEFAULT_TOLERANCE, FrequencyError, check_tolerance, positive_values, settled, settling_remainder

MAX_PERIODS = 3000
MAX_STEPS = 2**17
# The first steps per period: the exact stepper needs them for the quadrature of X only.
FIRST_STEPS = {"exact": 64, "verlet": 256}
FIRST_STEPS_DEFAULT = 1024
SWEEPS = ("up", "down", "both")
# The smallest move of x in one step that keeps its digits: the smallest normal number over the rounding.
SMALLEST_MOVE = sys.float_info.min / sys.float_info.epsilon
# The most branches for which the automatic choice takes ``exact`` (each slip is an event of its own: on the
# paper's 100 branches a period costs ~50 times one of verlet at 512 steps).
EXACT_UP_TO = 16


class NotSettled(FrequencyError):
    """A frequency whose response does not settle or converge within the bounds (not bad input)."""


@dataclass(frozen=True, eq=False)
class Response:
    """The steady first harmonic of x at each frequency of each sweep: arrays of shape (rows,).

    ``frequency`` (Hz), ``amplitude`` (m), ``phase`` (rad, of x against F0 cos(2 pi f t)); ``sweep`` "up" or
    "down" for each row; ``steps_per_period`` and ``periods`` (run at the last M) as taken; ``error`` the
    relative change of X at the last doubling of M plus the settling remainder (the stated accuracy). ``stepper``: the stepper used.
    """

    frequency: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    sweep: tuple
    steps_per_period: np.ndarray
    periods: np.ndarray
    error: np.ndarray
    stepper: str
    force_amplitude: float

    def columns(self) -> dict:
        """The CSV's columns: frequency, amplitude, phase (the contract), then sweep, steps_per_period, periods,
        error."""
        return {"frequency": self.frequency, "amplitude": self.amplitude, "phase": self.phase,
                "sweep": list(self.sweep), "steps_per_period": self.steps_per_period, "periods": self.periods,
                "error": self.error}


def is_nonlinear(scene) -> bool:
    """Whether the response may depend on the amplitude (branches, a cubic spring, friction, Dahl; a delay and
    a history are linear)."""
    return any(getattr(scene, name) is not None for name in ("branches", "cubic", "friction", "dahl"))


def choose_stepper(scene, stepper: Optional[str] = None) -> str:
    """``stepper`` if given (checked), else ``exact`` where it applies, else ``verlet``, else ``implicit``."""
    if stepper is not None:
        if stepper not in STEPPERS:
            raise FrequencyError(f"stepper: must be one of {', '.join(STEPPERS)}, got {stepper!r}")
        try:
            get_stepper(stepper).loop_for(scene)
        except ValueError as exc:
            raise FrequencyError(f"{scene.source}: stepper {stepper!r}: {exc}") from None
        return stepper
    for name in ("exact", "verlet", "implicit", "projected"):
        if name == "exact" and scene.branches is not None and not scene.branches.continuum \
                and scene.branches.n > EXACT_UP_TO:
            continue  # every slip an event: verlet is cheaper at this accuracy
        try:
            get_stepper(name).loop_for(scene)
        except ValueError:
            continue
        return name
    raise FrequencyError(f"{scene.source}: no stepper takes this scene")


def frequency_response(scene, force_amplitude: float, frequencies, *, tolerance: float = DEFAULT_TOLERANCE,
                       stepper: Optional[str] = None, sweep: Optional[str] = None, client=None,
                       scheduler: Optional[str] = None, workers: Optional[int] = None,
                       progress: Optional[bool] = None) -> Response:
    """The steady first harmonic of x under F0 cos(2 pi f t) at each of ``frequencies`` (Hz, > 0) (see the
    module). ``force_amplitude`` F0 (N, > 0); ``sweep`` "up", "down" or "both" (default: both for a nonlinear
    scene and more than one frequency); ``client``/``scheduler``/``workers``: run on dask.distributed.

    FrequencyError names the culprit of bad input; :class:`NotSettled` (a FrequencyError) a frequency that
    does not settle or converge."""
    if scene.mass is None:
        raise FrequencyError(f"{scene.source}: the frequency response needs [mass] (the element alone has no "
                             "resonance: describe it with --amplitudes)")
    force_amplitude = float(positive_values([force_amplitude], "force amplitude")[0])
    frequencies = positive_values(frequencies, "frequencies")
    tolerance = check_tolerance(tolerance)
    if sweep is None:
        sweep = "both" if is_nonlinear(scene) and np.unique(frequencies).size > 1 else "up"
    if sweep not in SWEEPS:
        raise FrequencyError(f"sweep: must be one of {', '.join(SWEEPS)}, got {sweep!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise FrequencyError(f"workers: must be a whole number >= 1, got {workers!r}")
    for frequency in frequencies.tolist():
        _check_resolved(scene, force_amplitude, frequency)
    forced = _forced(scene, force_amplitude, float(frequencies[0]))
    stepper = choose_stepper(forced, stepper)
    directions = ("up", "down") if sweep == "both" else (sweep,)
    ordered = np.sort(frequencies)
    tasks = [(direction, ordered if direction == "up" else ordered[::-1]) for direction in directions]
    if client is not None or scheduler is not None or workers is not None:
        rows = _on_cluster(scene, stepper, force_amplitude, tasks, tolerance, client, scheduler, workers)
    else:
        rows = []
        bar = _progress_bar(progress, total=sum(len(f) for _, f in tasks), label=f"{scene.name} response")
        try:
            for direction, order in tasks:
                rows += sweep_rows(scene, stepper, force_amplitude, order, direction, tolerance, bar)
        finally:
            bar.close()
    table = np.array([row[:4] + row[5:] for row in rows], dtype=float).reshape(-1, 6)
    return Response(table[:, 0], table[:, 1], table[:, 2], tuple(row[4] for row in rows), table[:, 3].astype(int),
                    table[:, 4].astype(int), table[:, 5], stepper, force_amplitude)


def _check_resolved(scene, force_amplitude: float, frequency: float) -> None:
    """FrequencyError when the motion at ``frequency`` is below what the steps resolve in floating point: far
    above resonance the mass moves F0 / (m omega^2), and a step of h = 1 / (f M) moves it by about that over
    M^2; once that falls below the smallest normal number over the rounding (SMALLEST_MOVE), x underflows to 0
    and its phase (-pi up there) is lost."""
    omega = 2.0 * math.pi * frequency
    motion = math.log10(force_amplitude) - math.log10(scene.mass.m) - 2.0 * math.log10(omega)
    if motion - 2.0 * math.log10(MAX_STEPS) < math.log10(SMALLEST_MOVE):
        raise FrequencyError(f"{scene.source}: at f = {float(frequency)!r} Hz the mass moves about "
                             f"F0 / (m (2 pi f)^2) = 1e{motion:.0f} m, too small for floating-point steps (x "
                             "would underflow): lower "
                             "the frequency or raise --force-amplitude")


def _forced(scene, force_amplitude: float, frequency: float):
    """The scene under F0 cos(2 pi f t) alone."""
    return dataclasses.replace(scene, load=HarmonicLoad(force_amplitude, 2.0 * math.pi * frequency))


def sweep_rows(scene, stepper: str, force_amplitude: float, frequencies, direction: str, tolerance: float,
               bar=None) -> list:
    """``[(frequency, amplitude, phase, steps per period, direction, periods, error)]`` along ``frequencies`` in
    their order, each continued from the state the previous one left (the first from the scene's)."""
    state = None
    rows = []
    for frequency in np.asarray(frequencies, dtype=float).tolist():
        harmonic, state, steps, periods, error = settle(scene, stepper, force_amplitude, frequency, state,
                                                        tolerance)
        amplitude = abs(harmonic)
        phase = math.atan2(harmonic.imag, harmonic.real) if amplitude > 0 else 0.0
        rows.append((frequency, amplitude, phase, steps, direction, periods, error))
        if bar is not None:
            bar.update(1)
    return rows


def settle(scene, stepper: str, force_amplitude: float, frequency: float, state, tolerance: float) -> tuple:
    """``(X, state, M, periods, error)`` at one frequency: periods until X settles, M doubled until it
    converges (see the module). ``state``: ``(x, v, u)`` to start from (None: the scene's initial state)."""
    forced = _forced(scene, force_amplitude, frequency)
    period = 1.0 / frequency
    steps = FIRST_STEPS.get(stepper, FIRST_STEPS_DEFAULT)
    while stability_problem(forced, stepper, period / steps) is not None and steps < MAX_STEPS:
        steps *= 2  # an explicit stepper's limit (omega h < 2) first
    previous = None
    while True:
        harmonic, state, periods, remainder = steady_period(forced, stepper, frequency, steps, state, tolerance)
        if previous is not None:
            error = abs(harmonic - previous) / abs(harmonic) if harmonic != 0 else abs(harmonic - previous)
            error += remainder
            if error <= tolerance:
                return harmonic, state, steps, periods, error
        if steps >= MAX_STEPS:
            raise NotSettled(f"{scene.source}: at f = {float(frequency)!r} Hz the first harmonic of x did not "
                             f"converge to {tolerance:g} relative by {MAX_STEPS} steps per period of {stepper!r} "
                             "(the last "
                             f"two differ by {error:.3g} relative)")
        previous, steps = harmonic, 2 * steps


def steady_period(forced, stepper: str, frequency: float, steps: int, state, tolerance: float) -> tuple:
    """``(X, state, periods, remainder)``: periods of ``steps`` steps from ``state`` until X settles (the
    settling test of the module); ``remainder`` what it leaves (:func:`settling_remainder`)."""
    period = 1.0 / frequency
    h = period / steps
    scene = forced
    if state is not None and (forced.delay is not None or forced.history is not None or forced.dahl is not None):
        # the memory restarts from the state reached (its history held at x): its grid is the step's
        scene = dataclasses.replace(forced, mass=Mass(forced.mass.m, state[0], state[1]))
    scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, step=h))
    kernel = choose_branch_kernel(scene, stepper)
    model = compile_model(scene, kernel)
    loop = compile_loop(scene, stepper)
    load = scene.load.compile()
    if state is None:
        x, v = scene.mass.x0, scene.mass.v0
        u = None if scene.branches is None else (
            stack.fresh_state(model[4], x) if stack.is_stack(model[4]) else np.array(scene.branches.u0, dtype=float))
    else:
        x, v, u = state[0], state[1], None if state[2] is None else state[2].copy()
    out = np.empty((steps, 3))
    theta = 2.0 * math.pi * np.arange(1, steps + 1) / steps
    kernel_cos, kernel_sin = 2.0 / steps * np.cos(theta), 2.0 / steps * np.sin(theta)
    harmonic, change, changes = None, math.inf, []
    for number in range(MAX_PERIODS):
        start = (x, v)
        try:
            x, v, taken = integrate(loop, model, load, x, v, u, 0.0, number * steps, h, 1, out, None, None, None)
        except ElementError as exc:
            raise NotSettled(f"at f = {float(frequency)!r} Hz: {exc}") from None
        if taken < steps:
            time = (number * steps + taken) * h
            where = (model, *(out[taken - 1, :2] if taken else start), u) if stepper == "exact" else None
            raise NotSettled(f"at f = {float(frequency)!r} Hz: {_failure(scene, stepper, load, time, h, where)}")
        xs = out[:, 0]
        if not np.all(np.isfinite(xs)):
            raise NotSettled(f"{scene.source}: at f = {float(frequency)!r} Hz x is not finite (an overflow)")
        new = complex(float(xs @ kernel_cos), -float(xs @ kernel_sin))
        drift = abs(x - start[0])  # a periodic motion comes back: a drift (a ratchet) has no steady harmonic
        if harmonic is not None:
            moved = max(abs(new - harmonic), drift)
            change = moved / abs(new) if new != 0 else (0.0 if moved == 0 else math.inf)
            changes.append(change)
            if change <= 1e-12 or settled(changes, tolerance):
                remainder = change if change <= 1e-12 else settling_remainder(changes)
                return new, (x, v, None if u is None else u.copy()), number + 1, remainder
        harmonic = new
    raise NotSettled(f"{forced.source}: at f = {float(frequency)!r} Hz the response did not settle within "
                     f"{MAX_PERIODS} periods ({stepper!r}, {steps} steps per period): X still changed by "
                     f"{change:.3g} relative "
                     "per period (a drift, a subharmonic or chaotic motion, or a transient slower than that)")


# ----------------------------------------------------------------- on dask.distributed

def _on_cluster(scene, stepper, force_amplitude, tasks, tolerance, client, scheduler, workers) -> list:
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise FrequencyError("a frequency response on dask.distributed needs the sweep extra (distributed is "
                             "missing): pip install \"prandtl_fmu[sweep]\"") from None
    from ..sweep import _client

    owned = []
    try:
        if client is None:
            client = _client(scheduler, workers, owned)
        count = len(client.scheduler_info().get("workers", {})) or 1
        blocks = max(1, (2 * count) // len(tasks))
        futures = []
        for direction, order in tasks:
            for block in np.array_split(order, min(blocks, len(order))):
                futures.append(client.submit(sweep_rows, scene, stepper, force_amplitude, block, direction,
                                             tolerance, pure=False))
        rows = []
        for future in futures:
            rows += future.result()
        return rows
    finally:
        for thing in reversed(owned):
            thing.close()
