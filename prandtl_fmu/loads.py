"""Force histories F(t) (N) for standalone runs.

Each load compiles to the tuple ``(kind, offset, amplitude, omega, time, force)``
(``offset`` is added to every kind: see :func:`plus`) that the kernels evaluate with :func:`force_at`; an FMU instead holds its
input F constant over a communication step (:func:`held`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._jit import kernel

CONSTANT, HARMONIC, TABLE = 0, 1, 2
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
    j = np.searchsorted(time, t, side="right")  # time[j-1] <= t < time[j]
    if j == 0:
        return offset + force[0]
    if j == time.shape[0]:
        return offset + force[-1]
    t0, t1 = time[j - 1], time[j]
    return offset + (force[j - 1] + (force[j] - force[j - 1]) * ((t - t0) / (t1 - t0)))
