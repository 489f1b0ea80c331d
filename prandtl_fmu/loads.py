"""Force histories F(t) (N) for standalone runs, and a white noise added to them.

Each load compiles to the tuple ``(kind, offset, amplitude, omega, time, force)``
(``offset`` is added to every kind: see :func:`plus`) that the kernels evaluate with :func:`force_at`; an FMU instead holds its
input F constant over a communication step (:func:`held`). A random load
puts its frequencies in ``time`` and its phases in ``force``.

A load with a white noise (``noise``: :class:`WhiteNoise`, the scene's ``kind = "white_noise"`` or
``noise_intensity``) compiles to that tuple and a seventh entry, ``(sigma, seed, unit, cache)``
(:meth:`WhiteNoise.compile`): the force is
F(t) + sigma xi(t), xi = dB/dt a standard white noise. A white noise has no value at an instant: a step
takes its impulse over [t, t + h], :func:`impulse` = sigma (B(t + h) - B(t)) (N s), and :func:`force_at`
stays the deterministic part. Without noise the tuple has six entries and every noise function compiles to
nothing (:func:`noise_of` is chosen from the tuple's type): an absent noise costs nothing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from numba.core import types
from numba.extending import overload

from . import libm
from . import noise as brownian_tree
from ._jit import kernel

CONSTANT, HARMONIC, TABLE, RANDOM, POLYNOMIAL = 0, 1, 2, 3, 4
_NO_TABLE = np.zeros(1)
# the Brownian tree sees time in noise units to this many significant bits (see tree_time)
TREE_TIME_BITS = 48


@dataclass(frozen=True)
class WhiteNoise:
    """sigma xi(t), xi = dB/dt a standard white noise: ``intensity`` sigma (N sqrt(s)), the path's ``seed``
    (0 <= seed < 2^63) and the Brownian tree's time ``unit`` T0 (s).

    B(t) = sqrt(T0) W(t / T0), W the virtual Brownian tree of :mod:`prandtl_fmu.noise`: a function of (seed, t)
    only, never of a step, an output interval or how a run is cut. Its cost per step is about one normal when
    the step times are dyadic points of the unit (h = T0 / 2^j: set T0 to the coarsest step of a study), up to
    about 40 otherwise (``docs/white-noise.md``).
    """

    intensity: float
    seed: int
    unit: float = 1.0

    def compile(self, cache=None):
        """``(sigma, seed, unit, cache)``; ``cache``: the Brownian tree's cache of the run (a new one if None)."""
        return (float(self.intensity), int(self.seed), float(self.unit),
                brownian_tree.new_cache() if cache is None else cache)


def white_noise(intensity, seed, unit=1.0) -> Optional[WhiteNoise]:
    """The noise an FMU's parameters ``noise_intensity``, ``noise_seed``, ``noise_unit`` give, by the rules of
    the scene's keys (None for intensity 0: no noise); ValueError naming the parameter otherwise."""
    if isinstance(intensity, bool) or not isinstance(intensity, (int, float)) or not (
            math.isfinite(intensity) and intensity >= 0):
        raise ValueError(f"noise_intensity = {intensity!r}: must be a finite number >= 0 (N sqrt(s))")
    if isinstance(seed, float) and seed.is_integer():
        seed = int(seed)  # (a master may pass an integer parameter as a double)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2 ** 63:
        raise ValueError(f"noise_seed = {seed!r}: must be an integer, 0 <= seed < 2^63")
    if isinstance(unit, bool) or not isinstance(unit, (int, float)) or not (math.isfinite(unit) and unit > 0):
        raise ValueError(f"noise_unit = {unit!r}: must be a finite number > 0 (s)")
    return WhiteNoise(float(intensity), seed, float(unit)) if intensity > 0 else None


# The Brownian tree resolves time to 2^-52 of its unit (below one unit; 2^-48 relative through tree_time) and
# ends at 2^52 units: a step shorter than this many units would see a path rounded to nothing.
FINEST_STEP_IN_UNITS = 2.0 ** -40


def noise_problem(noise: Optional[WhiteNoise], step: float, stop_time: Optional[float] = None) -> Optional[str]:
    """Why the noise's unit does not fit a run with internal step ``step`` up to ``stop_time`` (None if it does):
    beyond the tree's horizon (2^52 units) or a step below 2^-40 units the path would be frozen or rounded
    away, silently: refused instead."""
    if noise is None:
        return None
    if not step / noise.unit >= FINEST_STEP_IN_UNITS:
        return (f"noise_unit = {noise.unit!r} s is too coarse for the step {step!r} s: the Brownian tree resolves "
                f"2^-40 of its unit; take noise_unit <= {step / FINEST_STEP_IN_UNITS:.3g} s (the coarsest step of a "
                "study is the advice)")
    if stop_time is not None and not stop_time / noise.unit < brownian_tree.HORIZON:
        return (f"noise_unit = {noise.unit!r} s is too fine for the stop time {stop_time!r} s: the Brownian tree ends "
                f"at 2^52 units; take noise_unit >= {stop_time / brownian_tree.HORIZON:.3g} s")
    return None


def with_white_noise(load, noise: Optional[WhiteNoise], cache):
    """A compiled load tuple with its white noise (if any) replaced by ``noise`` (None: without noise): an
    FMU's force in, plus the noise its parameters set."""
    return _noisy(tuple(load[:6]), noise, cache)


def _noisy(compiled, noise, cache):
    """A compiled load tuple, with the seventh entry of its noise if it has one."""
    if noise is None:
        return compiled
    return compiled + (noise.compile(cache),)


@dataclass(frozen=True)
class ConstantLoad:
    """F(t) = value."""

    value: float
    noise: Optional[WhiteNoise] = None

    def compile(self, cache=None):
        return _noisy((CONSTANT, float(self.value), 0.0, 0.0, _NO_TABLE, _NO_TABLE), self.noise, cache)


@dataclass(frozen=True)
class HarmonicLoad:
    """F(t) = offset + amplitude * cos(omega * t)."""

    amplitude: float
    omega: float
    offset: float = 0.0
    noise: Optional[WhiteNoise] = None

    def compile(self, cache=None):
        return _noisy((HARMONIC, float(self.offset), float(self.amplitude), float(self.omega), _NO_TABLE, _NO_TABLE),
                      self.noise, cache)


@dataclass(frozen=True, eq=False)
class TableLoad:
    """Piecewise linear through (time[j], force[j]), held before the first and after the last point.

    Times are non-decreasing; a repeated time is a jump, and F is
    right-continuous there (at the jump time F already has the value after it).
    """

    time: np.ndarray
    force: np.ndarray
    noise: Optional[WhiteNoise] = None

    def compile(self, cache=None):
        return _noisy((TABLE, 0.0, 0.0, 0.0, np.ascontiguousarray(self.time, float),
                       np.ascontiguousarray(self.force, float)), self.noise, cache)


@dataclass(frozen=True)
class RandomLoad:
    """Band-limited Gaussian noise, a function of its seed alone:

        F(t) = offset + rms sqrt(2 / N) sum_{j=0}^{N-1} cos(omega_j t + phi_j)

    with N = ``components`` frequencies, one drawn uniformly in each of N equal
    cells of the band [omega_min, omega_max] (rad/s) and phases phi_j uniform in
    [0, 2 pi): a flat spectrum over the band, standard deviation ``rms`` (N),
    Gaussian in the limit of many components. The draws are the PCG64 bit
    stream of ``seed`` (:func:`uniform_stream`), fixed by NumPy for every
    version: the same seed gives the same F(t) everywhere.
    """

    seed: int
    rms: float
    omega_min: float
    omega_max: float
    components: int = 100
    offset: float = 0.0
    noise: Optional[WhiteNoise] = None

    def frequencies_and_phases(self):
        """(omega_j, phi_j), arrays of shape (N,)."""
        n = int(self.components)
        draws = uniform_stream(self.seed, 2 * n)
        width = (self.omega_max - self.omega_min) / n
        omega = self.omega_min + (np.arange(n) + draws[:n]) * width
        phase = 2.0 * math.pi * draws[n:]
        return omega, phase

    def compile(self, cache=None):
        omega, phase = self.frequencies_and_phases()
        amplitude = float(self.rms) * math.sqrt(2.0 / int(self.components))
        return _noisy((RANDOM, float(self.offset), amplitude, 0.0, omega, phase), self.noise, cache)


def uniform_stream(seed: int, count: int) -> np.ndarray:
    """``count`` doubles uniform in [0, 1) from the raw 64-bit output of PCG64(seed): the top 53 bits of each
    word. NumPy fixes the raw streams of its bit generators (not the streams of its distributions), so these
    numbers do not change with the NumPy version."""
    raw = np.random.PCG64(int(seed)).random_raw(int(count))
    return (raw >> np.uint64(11)).astype(np.float64) * (1.0 / 9007199254740992.0)


def held(value: float):
    """The compiled load of a force held constant (an FMU input over one step)."""
    return (CONSTANT, float(value), 0.0, 0.0, _NO_TABLE, _NO_TABLE)


def polynomial(value: float, rate: float, curvature: float, origin: float):
    """The compiled load of an FMU input given with its derivatives at a communication point ``origin`` (s):

        F(t) = value + rate (t - origin) + curvature (t - origin)^2 / 2

    (N, N/s, N/s^2), evaluated by :func:`force_at` wherever a stepper evaluates its force (FMI 2.0's
    fmi2SetRealInputDerivatives, orders 1 and 2). The tuple is ``(POLYNOMIAL, value, rate, curvature, [origin],
    [0])``: a C caller hands the origin as a table of one time."""
    return (POLYNOMIAL, float(value), float(rate), float(curvature), np.array([float(origin)]), _NO_TABLE)


def plus(load, value: float):
    """A compiled ``load`` plus a constant ``value`` (N): the scene's load and an FMU's input F (its noise kept)."""
    return (load[0], load[1] + float(value)) + tuple(load[2:])


@kernel
def force_at(load, t):
    """F(t) for a compiled load tuple: the deterministic part (a white noise has no value at an instant)."""
    kind, offset, amplitude, omega, time, force = load[0], load[1], load[2], load[3], load[4], load[5]
    if kind == CONSTANT:
        return offset
    if kind == HARMONIC:
        return offset + amplitude * libm.cos(omega * t)
    if kind == POLYNOMIAL:  # (polynomial: offset, amplitude, omega hold F, F', F''; time[0] the origin)
        tau = t - time[0]
        return offset + tau * (amplitude + 0.5 * omega * tau)
    if kind == RANDOM:
        total = 0.0
        for j in range(time.shape[0]):
            total += libm.cos(time[j] * t + force[j])
        return offset + amplitude * total
    j = np.searchsorted(time, t, side="right")  # time[j-1] <= t < time[j]
    if j == 0:
        return offset + force[0]
    if j == time.shape[0]:
        return offset + force[-1]
    t0, t1 = time[j - 1], time[j]
    return offset + (force[j - 1] + (force[j] - force[j - 1]) * ((t - t0) / (t1 - t0)))


# --- the white noise -------------------------------------------------------------------------------------------


def noise_of(load):
    """The compiled noise ``(sigma, seed, unit, cache)`` of a load tuple, None for a tuple of six (compiled
    only: the choice is made from the tuple's type, so that a load without noise compiles no noise code)."""
    raise NotImplementedError


@overload(noise_of, inline="always")
def _noise_of_overload(load):
    if isinstance(load, types.BaseTuple) and len(load) == 7:
        return lambda load: load[6]
    return lambda load: None


_SPLITTER = 2.0 ** (53 - TREE_TIME_BITS) + 1.0  # Veltkamp's splitter: keeps the leading TREE_TIME_BITS bits


@kernel
def tree_time(t, unit):
    """t / unit (s / s) rounded to TREE_TIME_BITS significant bits (to nearest, Veltkamp's split: three IEEE
    operations): the point of the Brownian tree at time t.

    A step time t_p = p h computed in doubles is within a few ulps of p (h / unit); when h / unit = 2^-j that
    is a point of the tree of level j, and the rounding (16 ulps either way) puts it there exactly: about one
    normal per step, and the steps h and h / 2 share their points, for any unit (1e-3 s is not a double). A
    function of t alone, monotone (adjacent steps' increments add up); it resolves time to 3.6e-15 relative.
    """
    tau = t / unit
    if not tau > 0.0:  # t <= 0 and NaN: the path's start
        return 0.0
    if tau >= brownian_tree.HORIZON:
        return brownian_tree.HORIZON
    split = _SPLITTER * tau
    return split - (split - tau)


@kernel
def _impulse(noise, t, h):
    if noise is None:
        return 0.0
    sigma, seed, unit, cache = noise
    if sigma == 0.0:
        return 0.0
    if not (t + h) / unit < brownian_tree.HORIZON:
        return np.nan  # the tree ends at 2^52 units: the step fails (a frozen path would be a silent zero)
    # B = sqrt(T0) W(t / T0): one square root per step (a few ns beside the tree's normal)
    return (sigma * math.sqrt(unit)) * brownian_tree.increment(seed, tree_time(t, unit), tree_time(t + h, unit),
                                                                cache)


@kernel
def impulse(load, t, h):
    """sigma (B(t + h) - B(t)) (N s): the impulse of the load's white noise over the step [t, t + h]; 0 without
    noise (compiled away) or with sigma = 0 (one comparison)."""
    return _impulse(noise_of(load), t, h)


@kernel
def _choose(noise, deterministic, noisy):
    if noise is None:
        return deterministic
    return noisy


@kernel
def with_noise(load, deterministic, noisy):
    """``noisy`` for a load with a white noise, ``deterministic`` for one without: a stepper writes both forms of
    an update, and a run without noise compiles only the first (the same bits as before noise existed)."""
    return _choose(noise_of(load), deterministic, noisy)
