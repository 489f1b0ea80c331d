"""The tables every scene reads alike: the reader of one table (:class:`_Reader`, which names the culprit of a
broken rule in one :class:`SceneError` line, its keys and bounds from :mod:`schema`), the magnitudes a number
may have, ``[load]`` (with its white noise) and ``[solver]``. The element's scene (``scene.py``) and a
network's (``network/model.py``) are both read with these; neither imports the other's reader.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional, Union

import numpy as np

from . import schema
from .catalog import SceneError
from .loads import ConstantLoad, HarmonicLoad, RandomLoad, TableLoad, WhiteNoise, noise_problem
from .resources import ResourceError, check_memory

# More steps than this cannot be counted exactly in a double (t_p = p h): refused, never truncated.
MAX_STEPS = 2**53


# A step (or stop time) shorter than this is refused: the implicit steps divide by h^2, which underflows to 0
# below about 1e-160 s.
SHORTEST_STEP = 1e-150


# The magnitudes a physical number of a scene may have. A coefficient (a mass, a stiffness, a dashpot, a
# threshold...) is 0 or has |value| in [SMALLEST_MAGNITUDE, LARGEST_MAGNITUDE]: outside, it means nothing physical
# (a subnormal mass, a stiffness of 1e308) and the products the kernels form (k x^3, k h^2 / m, c / m) underflow
# or overflow. A value (an initial state, a belt's speed, a load's number: VALUES) only has the upper bound: a
# tiny one is as good as 0. Refused by the scene reader and by every FMU's setters. Six such factors stay within
# a double.
SMALLEST_MAGNITUDE = 1e-50


LARGEST_MAGNITUDE = 1e50


# the coefficients (FMU parameters) and scene keys that are values, not coefficients (with every key of [load])
VALUES = ("x0", "v0", "u0", "belt_velocity")


Load = Union[ConstantLoad, HarmonicLoad, TableLoad, RandomLoad]


@dataclass(frozen=True)
class Solver:
    """Time discretisation: ``stepper`` name, internal ``step`` h (s), ``stop_time`` (s),
    ``output_interval`` (s, a whole multiple of ``step``)."""

    stepper: str
    step: float
    stop_time: float
    output_interval: float

    @property
    def steps_per_output(self) -> int:
        return int(round(self.output_interval / self.step))


def magnitude_problem(value: float, coefficient: bool = True) -> Optional[str]:
    """Why the finite number ``value``, a coefficient or (``coefficient=False``) a value, has no physical
    magnitude (see SMALLEST_MAGNITUDE), or None."""
    if coefficient and value != 0 and not SMALLEST_MAGNITUDE <= abs(value) <= LARGEST_MAGNITUDE:
        return (f"|{value!r}| is outside [{SMALLEST_MAGNITUDE:g}, {LARGEST_MAGNITUDE:g}] (or 0): "
                "no physical magnitude, its products in a step would underflow or overflow")
    if not coefficient and not abs(value) <= LARGEST_MAGNITUDE:
        return (f"|{value!r}| is above {LARGEST_MAGNITUDE:g}: no physical magnitude, its products in a step would "
                "overflow")
    return None


_SCHEMA = object()  # a reader's argument left to the schema


class _Reader:
    """Reads one TOML table by the schema (``schema.py``) and names the culprit of any broken rule.

    The keys a table allows, each key's default and its bounds are the schema's: ``only(form)`` refuses the keys
    of no such form, ``number(key)`` (``integer``, ``numbers``, ``string``, ``boolean``) reads a key with the
    schema's default and bounds. A key the schema lacks, or a default or bound that contradicts it (a reader of
    ``memory/`` that states its own), is a :class:`schema.SchemaError`: a bug, never the scene's fault.
    ``schema_table`` names the schema's table when ``table``, the name in messages, differs (``network.spring 2``).
    """

    def __init__(self, source: str, table: str, data: Any, schema_table: Optional[str] = None):
        self.source, self.table = source, table
        self.schema = schema.table(schema_table or table)
        self.form = None
        if not isinstance(data, dict):
            self.fail(None, f"must be a table, got {_kind(data)}")
        self.data = data

    def fail(self, key, rule):
        where = f"[{self.table}] {key}" if key else f"[{self.table}]"
        raise SceneError(f"{self.source}: {where}: {rule}")

    def only(self, form=None):
        """Refuse a key that ``form`` (the schema's; None: the table's only form) does not allow. A set of key
        names stands for the form that has exactly these keys."""
        if isinstance(form, (set, frozenset)):
            form = self.schema.form_of(form)
        allowed = self.schema.keys(form)
        self.form = form
        for key in self.data:
            if key not in allowed:
                self.fail(key, f"unknown key (allowed here: {', '.join(sorted(allowed))})")

    def key(self, name: str, method: str) -> "schema.Key":
        """The schema's key ``name`` (of the form named by ``only``, if any), which ``method`` must be able to
        read."""
        key = self.schema.key(name, self.form)
        if method not in (schema.TYPES[key.type] or "").split():
            raise schema.SchemaError(f"[{self.schema.name}] {name}: a {key.type}, not read by {method}()")
        return key

    def _agree(self, key, **stated):
        """A reader that states a default or a bound must state the schema's."""
        for what, value in stated.items():
            if value is not _SCHEMA and value != getattr(key, what):
                raise schema.SchemaError(f"[{self.schema.name}] {key.name}: {what} {value!r} is not the schema's "
                                         f"{getattr(key, what)!r}")

    def _default(self, key):
        """The value of the absent ``key``, or the refusal of a missing one."""
        default = key.default
        if default is schema.REQUIRED or default is schema.OPTIONAL:
            self.fail(key.name, "missing (required)")
        if isinstance(default, schema.SameAs):
            return self.number(default.key)
        return default

    def number(self, name, default=_SCHEMA, *, minimum=_SCHEMA, positive=_SCHEMA):
        key = self.key(name, "number")
        self._agree(key, default=default, minimum=minimum, positive=positive)
        if name not in self.data:
            return float(self._default(key))
        return self._check_number(name, self.data[name], key)

    def _check_number(self, name, value, key):
        """``value`` of ``key`` (``name`` in messages: ``k[2]`` for an item of a list), checked."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(name, f"must be a number, got {_kind(value)}")
        try:
            value = float(value)
        except OverflowError:  # an integer beyond the doubles
            self.fail(name, "must be finite, got an integer beyond the range of a double")
        if not math.isfinite(value):
            self.fail(name, f"must be finite, got {value}")
        if self.schema.numbers != "times":  # the solver's times have their own rules
            problem = magnitude_problem(value, coefficient=self.schema.numbers == "coefficients" and not key.value)
            if problem:
                self.fail(name, problem)
        if key.positive and not value > 0:
            self.fail(name, f"must be > 0, got {value!r}")
        if key.minimum is not None and value < key.minimum:
            self.fail(name, f"must be >= {key.minimum}, got {value!r}")
        return value

    def integer(self, name, *, minimum=_SCHEMA):
        key = self.key(name, "integer")
        self._agree(key, minimum=minimum)
        if name not in self.data:
            return self._default(key)
        value = self.data[name]
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(name, f"must be an integer, got {_kind(value)}")
        if key.minimum is not None and value < key.minimum:
            self.fail(name, f"must be >= {key.minimum}, got {value}")
        if key.maximum is not None and value > key.maximum:
            self.fail(name, f"must be <= {key.maximum}, got {value}")
        return value

    def numbers(self, name, *, minimum=_SCHEMA, positive=_SCHEMA, length=None):
        """A list of numbers; ``length``: the count it must have (the other lists'). An absent key with a default
        is ``length`` times the default."""
        key = self.key(name, "numbers")
        self._agree(key, minimum=minimum, positive=positive)
        if name not in self.data:
            default = self._default(key)
            if length is None:
                raise schema.SchemaError(f"[{self.schema.name}] {name}: a default list needs its length")
            return np.full(length, float(default))
        values = self.data[name]
        if not isinstance(values, list):
            self.fail(name, f"must be a list of numbers, got {_kind(values)}")
        if not values:
            self.fail(name, "must not be empty")
        if length is not None and len(values) != length:
            self.fail(name, f"must have {length} values like the other lists, got {len(values)}")
        checked = [self._check_number(f"{name}[{i + 1}]", v, key) for i, v in enumerate(values)]
        return np.array(checked, dtype=float)

    def string(self, name, default=_SCHEMA, choices=_SCHEMA):
        key = self.key(name, "string")
        self._agree(key, default=default)
        if choices is not _SCHEMA and tuple(choices or ()) != tuple(key.choice_names() or ()):
            raise schema.SchemaError(f"[{self.schema.name}] {name}: choices {choices!r} are not the schema's")
        if name not in self.data:
            return self._default(key)
        value = self.data[name]
        if not isinstance(value, str):
            self.fail(name, f"must be a string, got {_kind(value)}")
        allowed = key.choice_names()
        if allowed is not None and value not in allowed:
            self.fail(name, f"must be one of {', '.join(repr(c) for c in allowed)}, got {value!r}")
        return value

    def boolean(self, name):
        key = self.key(name, "boolean")
        if name not in self.data:
            return self._default(key)
        if not isinstance(self.data[name], bool):
            self.fail(name, f"must be true or false, got {_kind(self.data[name])}")
        return self.data[name]


def _kind(value) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
            list: "a list", dict: "a table"}.get(type(value), type(value).__name__)


# the keys of [load] that add a white noise to a deterministic kind (see _noise)
NOISE_KEYS = ("noise_intensity", "noise_seed", "noise_unit")


def _load(source, data) -> Load:
    r = _Reader(source, "load", data)
    kind = r.string("kind")
    if kind == "white_noise":
        for key in ("noise_intensity", "noise_seed"):
            if key in r.data:
                r.fail(key, "a white_noise load is the noise itself: give its intensity and seed")
        r.only("white_noise")
        noise = _white_noise(r, "intensity", "seed")
        return ConstantLoad(r.number("offset"), noise)
    noise = _white_noise(r, "noise_intensity", "noise_seed") if "noise_intensity" in r.data else None
    if "noise_intensity" not in r.data:
        for key in NOISE_KEYS:
            if key in r.data:
                r.fail(key, "needs noise_intensity (the white noise's sigma, N sqrt(s))")
    if kind == "harmonic":
        r.only("harmonic")
        return HarmonicLoad(r.number("amplitude"), r.number("omega"), r.number("offset"), noise)
    if kind == "constant":
        r.only("constant")
        return ConstantLoad(r.number("value"), noise)
    if kind == "random":
        return _random_load(r, noise)
    r.only("table")
    time = r.numbers("time")
    force = r.numbers("force", length=len(time))
    steps = np.diff(time)
    if np.any(steps < 0):
        i = int(np.flatnonzero(steps < 0)[0]) + 2
        r.fail(f"time[{i}]", "times must be non-decreasing (a repeated time is a jump)")
    if np.any((steps[1:] == 0) & (steps[:-1] == 0)):
        r.fail("time", "a time may appear at most twice (one jump at a time)")
    return TableLoad(time, force, noise)


def _check_noise_unit(scene) -> None:
    """The white noise's unit against the run's step and stop time (loads.noise_problem), one line."""
    problem = noise_problem(scene.load.noise, scene.solver.step, scene.solver.stop_time)
    if problem:
        raise SceneError(f"{scene.source}: [load] {problem}")


def _white_noise(r, intensity_key, seed_key) -> Optional[WhiteNoise]:
    """The white noise sigma xi(t) of [load] (``docs/white-noise.md``), or None when sigma = 0 (no noise at all).
    ``noise_unit`` (s, default 1): the Brownian tree's time unit, a property of the path, never of the step."""
    intensity = r.number(intensity_key)
    seed = _seed(r, seed_key)
    unit = r.number("noise_unit")
    if intensity == 0.0:
        return None
    return WhiteNoise(intensity, seed, unit)


def _seed(r, key) -> int:
    """A seed: an integer, 0 <= seed < 2^63 (a Philox key and a TOML integer)."""
    seed = r.integer(key)
    if seed >= 2**63:
        r.fail(key, f"must be < 2^63, got {seed}")
    return seed


def _random_load(r, noise=None) -> RandomLoad:
    r.only("random")
    seed = _seed(r, "seed")
    band = r.numbers("band")
    if len(band) != 2 or not band[0] < band[1]:
        r.fail("band", f"must be [omega_min, omega_max] (rad/s) with omega_min < omega_max, got {list(band)}")
    components = r.integer("components")
    try:
        check_memory(components * 16, f"{r.source}: [load] components = {components}")
    except ResourceError as exc:
        raise SceneError(str(exc)) from None
    return RandomLoad(seed, r.number("rms"), float(band[0]), float(band[1]), components, r.number("offset"),
                      noise)


def _solver(source, data) -> Solver:
    r = _Reader(source, "solver", data)
    r.only()
    solver = Solver(stepper=r.string("stepper"), step=r.number("step"), stop_time=r.number("stop_time"),
                    output_interval=r.number("output_interval"))
    _check_solver(solver, source, where="[solver] ")
    return solver


def _check_solver(solver: Solver, source: str, where: str) -> None:
    """Rules that tie solver settings together (also applied to CLI overrides)."""
    from .steppers import STEPPERS

    if solver.stepper not in STEPPERS:
        raise SceneError(f"{source}: {where}stepper: must be one of {', '.join(STEPPERS)}, got {solver.stepper!r}")
    for key in ("step", "stop_time", "output_interval"):
        value = getattr(solver, key)
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise SceneError(f"{source}: {where}{key}: must be a finite number > 0, got {value!r}")
        if value < SHORTEST_STEP:
            raise SceneError(f"{source}: {where}{key}: {value!r} s is too small: must be >= {SHORTEST_STEP:g} s (an "
                             "implicit step divides by h^2, which underflows)")
    ratio = solver.output_interval / solver.step
    steps = solver.stop_time / solver.step
    if not (ratio < MAX_STEPS and steps < MAX_STEPS):
        raise SceneError(
            f"{source}: {where}step: {solver.step!r} s is too small: {max(ratio, steps):.3g} steps "
            f"(more than 2^53, the steps a double counts exactly; the run would not end)")
    if round(ratio) < 1 or abs(ratio - round(ratio)) > 1e-9 * ratio:
        raise SceneError(
            f"{source}: {where}output_interval: must be a whole multiple of step = {solver.step!r}, "
            f"got {solver.output_interval!r} ({ratio:.6g} steps)"
        )
