"""The sweep file: which scene keys vary, how, and what to keep per run.

    [grid]                              # every combination of these values (the first key varies slowest)
    "spring.k0" = [0.0, 0.5, 1.0]                                  # values (numbers or strings)
    "load.amplitude" = { from = 0.1, to = 0.5, count = 9 }         # evenly spaced, both ends included
    "load.omega" = { from = 0.1, to = 10.0, count = 5, spacing = "log" }

    [random]                            # samples, each combined with every grid point
    samples = 100                       # required in [random]
    seed = 1                            # default 0
    "mass.m" = { distribution = "uniform", low = 0.8, high = 1.2 }
    "damper.c" = { distribution = "loguniform", low = 1e-3, high = 1e-1 }
    "branches.k_total" = { distribution = "normal", mean = 1.0, std = 0.05 }
    "cubic.k3" = { distribution = "lognormal", median = 0.1, sigma = 0.3 }
    "load.seed" = { distribution = "integers", low = 0, high = 1000000 }    # both ends included
    "solver.stepper" = { distribution = "choice", values = ["verlet", "symplectic"] }

    [keep]
    summary = ["max_abs_x", "dissipated", "loop_area"]   # default: every quantity that applies
    history = false                     # also the output grid of every run (time, x, v, reaction)

    [tasks]
    runs_per_task = 2000                # default: the runs split into about 8 tasks per worker, at most 2000 each

    [seeds]                             # Monte Carlo: every grid point (and random sample) run with many seeds
    count = 1000                        # required in [seeds]: the seeds first .. first + count - 1
    first = 0                           # default 0
    key = "load.seed"                   # default: the scene's seeded load (load.seed, or load.noise_seed)

    [statistics]                        # the report (:mod:`.report`): mean, std, histogram, with intervals
    outputs = ["final_x"]               # default: every kept summary quantity
    bins = 20                           # default: ceil(2 n^(1/3)) (Rice's rule), n the runs of a group
    confidence = 0.95                   # default 0.95

    [law]                               # (or [[law]], one per output): the histogram against a density
    output = "final_x"
    density = "oscillator_x"            # LAWS (:mod:`.statistics`): normal, uniform, oscillator_x, ...
    sigma = 0.2                         # a parameter: a number, or a scene key ("damper.c"); default the scene's

A key is a scene key, ``table.key`` (``spring.k0``, ``load.amplitude``,
``branches.k_total``, ``friction.alpha``, ``solver.step``, ...) or one value of a list,
``table.key[i]`` (1-based: ``branches.k[2]``, ``branches.c[2]``, ``branches.eta_range[2]``).
Setting a key of a table the scene lacks adds the table (``spring.k0`` on a
scene without [spring] adds the spring); every run's scene is checked by the
rules of the scene format. Run r combines grid point r // (samples x seeds)
with random sample (r // seeds) % samples and seed first + r % seeds (runs =
grid points x samples x seeds; seeds = 1 without [seeds]): the runs of one
seed range are consecutive, a *group* (:meth:`SweepSpec.group`), and the
statistics are taken over each group. Without [seeds] a group is the random
samples of one grid point.

Random draws come from the raw PCG64 stream of ``seed`` (``loads.uniform_stream``),
sample by sample and key by key in the file's order, and are turned into each
distribution by its inverse CDF: the values do not depend on the NumPy version,
nor on how the runs are split into tasks. Each row of the result holds the
values of its run, so any run can be repeated alone.
"""
from __future__ import annotations

import copy
import functools
import hashlib
import json
import math
import os
import re
from dataclasses import dataclass
from statistics import NormalDist
from typing import Optional, Union

import numpy as np

from ..loads import uniform_stream
from ..scene import read_toml
from ..summary import SUMMARIES

# Scene keys that hold integers: a grid or a distribution gives them whole numbers.
INTEGER_KEYS = {"branches.count", "load.seed", "load.noise_seed", "load.components"}
DISTRIBUTIONS = {
    "uniform": ("low", "high"),
    "loguniform": ("low", "high"),
    "normal": ("mean", "std"),
    "lognormal": ("median", "sigma"),
    "integers": ("low", "high"),
    "choice": ("values",),
}
# table.key, table.key[i], or a key of an inline table: table.key.key (branches.density.chi)
_KEY = re.compile(r"^([a-z_]+)\.([A-Za-z_][A-Za-z_0-9]*(?:\.[A-Za-z_][A-Za-z_0-9]*)*)(?:\[([0-9]+)\])?$")
MAX_RUNS_PER_TASK = 2000


class SweepError(ValueError):
    """A sweep file breaks a rule; the message is one line naming the key."""


@dataclass(frozen=True)
class Distribution:
    kind: str
    args: tuple

    def draw(self, u: np.ndarray) -> list:
        """Values for uniform draws ``u`` in (0, 1)."""
        kind, args = self.kind, self.args
        if kind == "uniform":
            return list(args[0] + (args[1] - args[0]) * u)
        if kind == "loguniform":
            return list(np.exp(math.log(args[0]) + (math.log(args[1]) - math.log(args[0])) * u))
        if kind == "normal":
            dist = NormalDist(args[0], args[1])
            return [dist.inv_cdf(float(p)) for p in u]
        if kind == "lognormal":
            unit = NormalDist()
            return [args[0] * math.exp(args[1] * unit.inv_cdf(float(p))) for p in u]
        if kind == "integers":
            low, high = args
            return [int(low + min(high - low, math.floor(p * (high - low + 1)))) for p in u]
        values = args[0]  # choice
        return [values[min(len(values) - 1, math.floor(p * len(values)))] for p in u]


@dataclass(frozen=True)
class Seeds:
    """[seeds]: the scene key ``key`` (None: the scene's seeded load, chosen by the plan) takes the values
    first .. first + count - 1, innermost (the runs of one seed range are consecutive)."""

    key: Optional[str]
    first: int
    count: int


@dataclass(frozen=True)
class Statistics:
    """[statistics]: what the report gives (``outputs`` None: every kept summary quantity)."""

    outputs: Optional[tuple] = None
    bins: Optional[int] = None
    confidence: float = 0.95


@dataclass(frozen=True)
class LawSpec:
    """One [law]: the density ``density`` (a name of ``statistics.LAWS``) of the summary ``output``, with its
    ``parameters`` (name -> a number, or a scene key whose value each group's scene gives)."""

    output: str
    density: str
    parameters: dict


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file (see the module docstring)."""

    grid: dict                      # key -> list of values
    samples: int                    # random samples per grid point (1 and no distribution without [random])
    seed: int
    distributions: dict             # key -> Distribution
    summary: Optional[tuple]        # None: every quantity that applies
    history: bool = False
    runs_per_task: Optional[int] = None
    source: str = "<sweep>"
    seeds: Optional[Seeds] = None
    statistics: Optional[Statistics] = None   # None: no report
    laws: tuple = ()                          # LawSpec, at most one per output

    @property
    def keys(self) -> list:
        """The varied keys: the grid's, then the random ones, in the file's order, then the seeds' key."""
        return list(self.grid) + list(self.distributions) + ([self.seeds.key] if self.seeds else [])

    @property
    def seed_count(self) -> int:
        return self.seeds.count if self.seeds else 1

    @property
    def group_size(self) -> int:
        """Runs per group: the seeds of one grid point and sample, or (without [seeds]) the samples of one grid
        point."""
        return self.seeds.count if self.seeds else self.samples

    @property
    def group_keys(self) -> list:
        """The keys that are constant over a group (and tell the groups apart)."""
        return list(self.grid) + (list(self.distributions) if self.seeds else [])

    def group(self, run: int) -> int:
        return run // self.group_size

    @property
    def grid_size(self) -> int:
        return math.prod(len(values) for values in self.grid.values())

    @property
    def runs(self) -> int:
        return self.grid_size * self.samples * self.seed_count

    def values(self, first: int, stop: int) -> list:
        """``[(run, {key: value})]`` for runs first .. stop - 1."""
        shape = [len(values) for values in self.grid.values()]
        random = self._draws if self.distributions else None
        rows = []
        per_point, count = self.samples * self.seed_count, self.seed_count
        for run in range(first, stop):
            point, rest = divmod(run, per_point)
            sample, seed = divmod(rest, count)
            values = {}
            if shape:
                for key, index in zip(self.grid, np.unravel_index(point, shape)):
                    values[key] = self.grid[key][int(index)]
            if random is not None:
                for key in self.distributions:
                    values[key] = random[key][sample]
            if self.seeds is not None:
                values[self.seeds.key] = self.seeds.first + seed
            rows.append((run, values))
        return rows

    @functools.cached_property
    def _draws(self) -> dict:
        """key -> the values of every sample (drawn once)."""
        keys, samples = list(self.distributions), self.samples
        u = uniform_stream(self.seed, samples * len(keys)).reshape(samples, len(keys))
        u = u + 0.5 / 9007199254740992.0  # in (0, 1): the inverse CDFs are finite
        return {key: self.distributions[key].draw(u[:, j]) for j, key in enumerate(keys)}

    def digest(self) -> str:
        """A digest of what the sweep computes (not of how it is split into tasks)."""
        what = {"grid": self.grid, "samples": self.samples, "seed": self.seed,
                "distributions": {k: [d.kind, list(d.args) if d.kind != "choice" else d.args[0]]
                                  for k, d in self.distributions.items()},
                "summary": self.summary, "history": self.history}
        if self.seeds is not None:  # the report's tables change no run: a new [law] and --resume redo the report
            what["seeds"] = [self.seeds.key, self.seeds.first, self.seeds.count]
        return hashlib.sha256(json.dumps(what, sort_keys=True, default=str).encode()).hexdigest()[:16]


def load_spec(spec: Union[str, os.PathLike, dict, SweepSpec]) -> SweepSpec:
    """A sweep from a file, a dict (the parsed TOML) or a SweepSpec; SweepError names the culprit."""
    if isinstance(spec, SweepSpec):
        return spec
    if isinstance(spec, dict):
        return parse_spec(spec, "<sweep>")
    source = os.fspath(spec)
    return parse_spec(read_toml(source, "the sweep file", SweepError), source)


def parse_spec(doc: dict, source: str) -> SweepSpec:
    """The sweep of a parsed TOML document; SweepError names the culprit."""
    def fail(where, rule):
        raise SweepError(f"{source}: {where}: {rule}")

    for key in doc:
        if key not in TABLES:
            fail(key, f"unknown table (allowed: {', '.join(TABLES)})")
    for table in doc:
        if not isinstance(doc[table], dict) and not (table == "law" and isinstance(doc[table], list)):
            fail(f"[{table}]", "must be a table")
    grid = {}
    for key, value in doc.get("grid", {}).items():
        _check_key(key, f"[grid] {key}", fail)
        grid[key] = _grid_values(key, value, lambda rule: fail(f"[grid] {key}", rule))
    random = dict(doc.get("random", {}))
    distributions, samples, seed = {}, 1, 0
    if "random" in doc:
        if "samples" not in random:
            fail("[random] samples", "missing (required: the number of random samples per grid point)")
        samples = _integer(random.pop("samples"), 1, lambda rule: fail("[random] samples", rule))
        _check_values_fit(samples, lambda rule: fail("[random] samples", rule))
        seed = _integer(random.pop("seed", 0), 0, lambda rule: fail("[random] seed", rule))
        if seed >= 2**63:
            fail("[random] seed", f"must be < 2^63, got {seed}")
        for key, value in random.items():
            _check_key(key, f"[random] {key}", fail)
            if key in grid:
                fail(f"[random] {key}", "already in [grid]: a key varies one way")
            distributions[key] = _distribution(key, value, lambda rule: fail(f"[random] {key}", rule))
        if not distributions:
            fail("[random]", "names no key to draw (add e.g. \"load.seed\" = { distribution = \"integers\", ... })")
    seeds = _seeds(doc["seeds"], grid, distributions, fail) if "seeds" in doc else None
    if not grid and not distributions and seeds is None:
        fail("[grid]", "the sweep varies nothing: give [grid] values, [random] distributions or [seeds]")
    keep = doc.get("keep", {})
    for key in keep:
        if key not in ("summary", "history"):
            fail(f"[keep] {key}", "unknown key (allowed: history, summary)")
    summary = None
    if "summary" in keep:
        summary = keep["summary"]
        if not isinstance(summary, list) or not all(isinstance(q, str) for q in summary):
            fail("[keep] summary", "must be a list of names")
        for q in summary:
            if q not in SUMMARIES:
                fail("[keep] summary", f"unknown quantity {q!r} (known: {', '.join(SUMMARIES)})")
        if len(set(summary)) != len(summary):
            fail("[keep] summary", "names a quantity twice")
        summary = tuple(summary)
    history = keep.get("history", False)
    if not isinstance(history, bool):
        fail("[keep] history", "must be true or false")
    if summary == () and not history:
        fail("[keep]", "keeps nothing: name a summary quantity or set history = true")
    tasks = doc.get("tasks", {})
    for key in tasks:
        if key != "runs_per_task":
            fail(f"[tasks] {key}", "unknown key (allowed: runs_per_task)")
    runs_per_task = None
    if "runs_per_task" in tasks:
        runs_per_task = _integer(tasks["runs_per_task"], 1, lambda rule: fail("[tasks] runs_per_task", rule))
    laws = _laws(doc.get("law", []), summary, fail)
    statistics = None
    if "statistics" in doc or laws or seeds is not None:
        statistics = _statistics(doc.get("statistics", {}), summary, fail)
        if seeds is None and not distributions:
            fail("[statistics]" if "statistics" in doc else "[law]", "needs [seeds] or [random]: statistics are "
                 "taken over the seeds (or the random samples) of each grid point")
    spec = SweepSpec(grid, samples, seed, distributions, summary, history, runs_per_task, source,
                     seeds=seeds, statistics=statistics, laws=laws)
    if spec.runs > 10**9:
        fail("[grid]", f"{spec.runs} runs: more than 10^9 (split the sweep)")
    return spec


TABLES = ("grid", "random", "keep", "tasks", "seeds", "statistics", "law")


def _seeds(table, grid, distributions, fail) -> Seeds:
    for name in table:
        if name not in ("count", "first", "key"):
            fail(f"[seeds] {name}", "unknown key (allowed: count, first, key)")
    if "count" not in table:
        fail("[seeds] count", "missing (required: the number of seeds run for every grid point)")
    count = _integer(table["count"], 1, lambda rule: fail("[seeds] count", rule))
    first = _integer(table.get("first", 0), 0, lambda rule: fail("[seeds] first", rule))
    if first + count - 1 >= 2**63:
        fail("[seeds]", f"the last seed, first + count - 1 = {first + count - 1}, must be < 2^63")
    key = table.get("key")
    if key is not None:
        if not isinstance(key, str):
            fail("[seeds] key", f"must be a scene key (a string such as \"load.seed\"), got {key!r}")
        _check_key(key, "[seeds] key", fail)
        if _base(key) not in INTEGER_KEYS or not _base(key).endswith("seed"):
            fail("[seeds] key", f"{key!r} is not a seed (seed keys: load.seed, load.noise_seed)")
        if key in grid or key in distributions:
            fail("[seeds] key", f"{key} already varies in [{'grid' if key in grid else 'random'}]")
    return Seeds(key, first, count)


def _statistics(table, summary, fail) -> Statistics:
    for name in table:
        if name not in ("outputs", "bins", "confidence"):
            fail(f"[statistics] {name}", "unknown key (allowed: bins, confidence, outputs)")
    outputs = table.get("outputs")
    if outputs is not None:
        if not isinstance(outputs, list) or not outputs or not all(isinstance(q, str) for q in outputs):
            fail("[statistics] outputs", "must be a non-empty list of summary quantities")
        for q in outputs:
            _check_output(q, summary, lambda rule: fail("[statistics] outputs", rule))
        if len(set(outputs)) != len(outputs):
            fail("[statistics] outputs", "names a quantity twice")
        outputs = tuple(outputs)
    bins = table.get("bins")
    if bins is not None:
        bins = _integer(bins, 1, lambda rule: fail("[statistics] bins", rule))
        if bins > 10000:
            fail("[statistics] bins", f"must be <= 10000, got {bins}")
    confidence = table.get("confidence", 0.95)
    _number(confidence, lambda rule: fail("[statistics] confidence", rule))
    if not 0 < confidence < 1:
        fail("[statistics] confidence", f"must be in (0, 1), got {confidence!r}")
    return Statistics(outputs, bins, float(confidence))


def _check_output(q, summary, rule):
    if q not in SUMMARIES:
        rule(f"unknown quantity {q!r} (known: {', '.join(SUMMARIES)})")
    if summary is not None and q not in summary:
        rule(f"{q!r} is not kept: add it to [keep] summary")


def _laws(tables, summary, fail) -> tuple:
    from .statistics import LAWS

    laws = []
    for position, table in enumerate(tables if isinstance(tables, list) else [tables]):
        where = "[law]" if isinstance(tables, dict) else f"[[law]] {position + 1}"
        if not isinstance(table, dict):
            fail(where, "must be a table")
        for name in ("output", "density"):
            if name not in table:
                fail(f"{where} {name}", "missing (required: the summary quantity and its density)")
        output, density = table["output"], table["density"]
        if not isinstance(output, str):
            fail(f"{where} output", f"must be a summary quantity, got {output!r}")
        _check_output(output, summary, lambda rule: fail(f"{where} output", rule))
        if any(law.output == output for law in laws):
            fail(f"{where} output", f"{output} has a law already (one law per output)")
        if density not in LAWS:
            fail(f"{where} density", f"must be one of {', '.join(LAWS)}, got {density!r}")
        names = LAWS[density].parameters
        parameters = {}
        for name, value in table.items():
            if name in ("output", "density"):
                continue
            if name not in names:
                fail(f"{where} {name}", f"unknown parameter of {density} (allowed: {', '.join(names)})")
            if isinstance(value, str):
                if not _KEY.match(value):
                    fail(f"{where} {name}", f"{value!r} is neither a number nor a scene key (e.g. \"damper.c\")")
                _check_key(value, f"{where} {name}", fail)
            else:
                _number(value, lambda rule: fail(f"{where} {name}", rule + " or a scene key such as \"damper.c\""))
                value = float(value)
            parameters[name] = value
        laws.append(LawSpec(output, density, parameters))
    return tuple(laws)


def _check_key(key, where, fail):
    match = _KEY.match(key)
    if not match:
        fail(where.rsplit(" ", 1)[0] + f" {key!r}", "not a scene key: write table.key, table.key[i] or "
             "table.key.key (e.g. \"spring.k0\", \"branches.k[2]\", \"branches.density.chi\")")
    table = match.group(1)
    if table in ("fmu",) or table not in ("mass", "friction", "spring", "cubic", "damper", "branches", "load",
                                          "solver"):
        fail(where, f"[{table}] is not a table a sweep can vary (mass, friction, spring, cubic, damper, branches, "
             "load, solver)")
    if match.group(3) is not None and int(match.group(3)) < 1:
        fail(where, "list positions count from 1")


def _number(value, rule):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        rule(f"must be a finite number, got {value!r}")
    return value


def _integer(value, minimum, rule):
    if isinstance(value, bool) or not isinstance(value, int):
        rule(f"must be an integer, got {value!r}")
    if value < minimum:
        rule(f"must be >= {minimum}, got {value}")
    return value


def _grid_values(key, value, rule):
    if isinstance(value, list):
        if not value:
            rule("must not be empty")
        if all(isinstance(v, str) for v in value):
            return list(value)
        for v in value:
            _number(v, rule)
        return [_whole(key, v, rule) for v in value]
    if not isinstance(value, dict):
        rule("must be a list of values or a range { from, to, count }")
    for name in value:
        if name not in ("from", "to", "count", "spacing"):
            rule(f"unknown range key {name!r} (allowed: from, to, count, spacing)")
    for name in ("from", "to", "count"):
        if name not in value:
            rule(f"range: {name} missing")
    low, high = _number(value["from"], rule), _number(value["to"], rule)
    count = _integer(value["count"], 1, rule)
    _check_values_fit(count, rule)
    spacing = value.get("spacing", "linear")
    if spacing not in ("linear", "log"):
        rule(f"spacing must be \"linear\" or \"log\", got {spacing!r}")
    if count == 1:
        points = np.array([float(low)])
    elif spacing == "log":
        if not (low > 0 and high > 0):
            rule("a log range needs from > 0 and to > 0")
        points = np.geomspace(float(low), float(high), count)
    else:
        points = np.linspace(float(low), float(high), count)
    return [_whole(key, float(v), rule) for v in points]


# Memory of one grid value: a Python float in a list, and its array element while the points are made
_BYTES_PER_VALUE = 64


def _check_values_fit(count, rule):
    """A range of ``count`` values must fit in memory (the grid is made whole): one line before any work."""
    from ..resources import available_memory, size_text

    need = _BYTES_PER_VALUE * float(count)
    if need > available_memory():
        rule(f"{count} values need about {size_text(need)} of memory, {size_text(available_memory())} "
             "available: a sweep that large could not be run either")


def _whole(key, value, rule):
    """An integer key's value as an int (refused unless whole); others as float."""
    if _base(key) in INTEGER_KEYS:
        if not float(value).is_integer():
            rule(f"{key} takes whole numbers, got {value!r}")
        return int(value)
    return float(value)


def _base(key):
    return key.split("[", 1)[0]


def _distribution(key, value, rule) -> Distribution:
    if not isinstance(value, dict) or "distribution" not in value:
        rule("must be a table { distribution = ..., ... }")
    kind = value["distribution"]
    if kind not in DISTRIBUTIONS:
        rule(f"distribution must be one of {', '.join(DISTRIBUTIONS)}, got {kind!r}")
    names = DISTRIBUTIONS[kind]
    for name in value:
        if name != "distribution" and name not in names:
            rule(f"unknown key {name!r} for {kind} (allowed: {', '.join(names)})")
    for name in names:
        if name not in value:
            rule(f"{kind}: {name} missing")
    if kind == "choice":
        values = value["values"]
        if not isinstance(values, list) or not values:
            rule("choice: values must be a non-empty list")
        if not all(isinstance(v, str) for v in values):
            values = [_whole(key, _number(v, rule), rule) for v in values]
        return Distribution(kind, (list(values),))
    args = tuple(_number(value[name], rule) for name in names)
    if kind in ("uniform", "loguniform") and not args[0] < args[1]:
        rule(f"{kind}: needs low < high, got {args[0]!r}, {args[1]!r}")
    if kind == "loguniform" and not args[0] > 0:
        rule("loguniform: needs low > 0")
    if kind in ("normal",) and not args[1] > 0:
        rule("normal: needs std > 0")
    if kind == "lognormal" and not (args[0] > 0 and args[1] > 0):
        rule("lognormal: needs median > 0 and sigma > 0")
    if kind == "integers":
        if not all(isinstance(a, int) for a in args):
            rule("integers: low and high must be integers")
        if args[0] > args[1]:
            rule(f"integers: needs low <= high, got {args[0]}, {args[1]}")
    elif _base(key) in INTEGER_KEYS:
        rule(f"{key} takes whole numbers: use distribution = \"integers\" or \"choice\"")
    return Distribution(kind, args)


def apply(document: dict, values: dict) -> dict:
    """A copy of the scene ``document`` with the sweep's ``values`` set (``table.key``, ``table.key[i]`` or
    ``table.key.key`` for a key of an inline table).
    A key of a missing table adds the table; a position beyond a list's end is a SweepError."""
    doc = copy.deepcopy(document)
    for key, value in values.items():
        table, path, index = _KEY.match(key).groups()
        *inner, name = path.split(".")
        target = doc
        for depth, part in enumerate([table] + inner):
            target = target.setdefault(part, {})
            if not isinstance(target, dict):
                raise SweepError(f"{key}: the scene's {'.'.join(([table] + inner)[:depth + 1])} is not a table")
        if isinstance(value, np.generic):
            value = value.item()
        if index is None:
            target[name] = value
            continue
        values_list = target.get(name)
        if not isinstance(values_list, list) or int(index) > len(values_list):
            have = len(values_list) if isinstance(values_list, list) else 0
            raise SweepError(f"{key}: the scene's [{table}] {name} has {have} values")
        target[name] = list(values_list)
        target[name][int(index) - 1] = value
    return doc
