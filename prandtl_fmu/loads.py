"""Force histories F(t) (N) for standalone runs.

Each load compiles to the tuple ``(kind, offset, amplitude, omega, time, force)``
(``offset`` is added to every kind: see :func:`plus`) that the kernels evaluate with :func:`force_at`; an FMU instead holds its
input F constant over a communication step (:func:`held`). A random load
puts its frequencies in ``time`` and its phases in ``force``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._jit import kernel

CONSTANT, HARMONIC, TABLE, RANDOM = 0, 1, 2, 3
_NO_TABLE = np.zeros(1)


@dataclass(frozen=True)
class ConstantLoad:
    """F(t) = value."""

    value: float

    def compile(self):
        return (CONSTANT, float(self.value), 0.0, 0.0, _NO_TABLE, _NO_TABLE)


@dataclass(frozen=True)
class HarmonicLoad:
    """F(t) = offset + amplitude * cos(omega * t)."""

    amplitude: float
    omega: float
    offset: float = 0.0

    def compile(self):
        return (HARMONIC, float(self.offset), float(self.amplitude), float(self.omega), _NO_TABLE, _NO_TABLE)


@dataclass(frozen=True, eq=False)
class TableLoad:
    """Piecewise linear through (time[j], force[j]), held before the first and after the last point.

    Times are non-decreasing; a repeated time is a jump, and F is
    right-continuous there (at the jump time F already has the value after it).
    """

    time: np.ndarray
    force: np.ndarray

    def compile(self):
        return (TABLE, 0.0, 0.0, 0.0, np.ascontiguousarray(self.time, float), np.ascontiguousarray(self.force, float))


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

    def frequencies_and_phases(self):
        """(omega_j, phi_j), arrays of shape (N,)."""
        n = int(self.components)
        draws = uniform_stream(self.seed, 2 * n)
        width = (self.omega_max - self.omega_min) / n
        omega = self.omega_min + (np.arange(n) + draws[:n]) * width
        phase = 2.0 * math.pi * draws[n:]
        return omega, phase

    def compile(self):
        omega, phase = self.frequencies_and_phases()
        amplitude = float(self.rms) * math.sqrt(2.0 / int(self.components))
        return (RANDOM, float(self.offset), amplitude, 0.0, omega, phase)


def uniform_stream(seed: int, count: int) -> np.ndarray:
    """``count`` doubles uniform in [0, 1) from the raw 64-bit output of PCG64(seed): the top 53 bits of each
    word. NumPy fixes the raw streams of its bit generators (not the streams of its distributions), so these
    numbers do not change with the NumPy version."""
    raw = np.random.PCG64(int(seed)).random_raw(int(count))
    return (raw >> np.uint64(11)).astype(np.float64) * (1.0 / 9007199254740992.0)


def held(value: float):
    """The compiled load of a force held constant (an FMU input over one step)."""
    return (CONSTANT, float(value), 0.0, 0.0, _NO_TABLE, _NO_TABLE)


def plus(load, value: float):
    """A compiled ``load`` plus a constant ``value`` (N): the scene's load and an FMU's input F."""
    kind, offset, amplitude, omega, time, force = load
    return (kind, offset + float(value), amplitude, omega, time, force)


@kernel
def force_at(load, t):
    """F(t) for a compiled load tuple."""
    kind, offset, amplitude, omega, time, force = load
    if kind == CONSTANT:
        return offset
    if kind == HARMONIC:
        return offset + amplitude * np.cos(omega * t)
    if kind == RANDOM:
        total = 0.0
        for j in range(time.shape[0]):
            total += np.cos(time[j] * t + force[j])
        return offset + amplitude * total
    j = np.searchsorted(time, t, side="right")  # time[j-1] <= t < time[j]
    if j == 0:
        return offset + force[0]
    if j == time.shape[0]:
        return offset + force[-1]
    t0, t1 = time[j - 1], time[j]
    return offset + (force[j - 1] + (force[j] - force[j - 1]) * ((t - t0) / (t1 - t0)))
