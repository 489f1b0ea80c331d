"""The work of one sweep task: a batch of runs of one scene, in the worker's process.

Everything a task receives and returns is plain data (the scene's TOML
document, the runs' values, lists of numbers): no compiled function ever
travels between processes. The worker loads the compiled kernels from its
numba cache (or compiles them once per process), then runs the batch: per
run, one scene check and one compiled call per chunk of steps
(:func:`summary.summarize`), never Python per step.

A run that cannot be done (its scene breaks a rule, the element collapses,
a step fails) gives a row whose ``error`` column says why, with NaN values;
a run that warns (a step beyond an explicit stepper's stability limit) keeps
the warning in its ``warning`` column. Neither stops the other runs.
"""
from __future__ import annotations

import math
import warnings

from ..driver import ElementError
from ..scene import SceneError, scene_from_document
from ..summary import HISTORY_COLUMNS, summarize
from .spec import SweepError, apply


def columns(keys, summary, history) -> list:
    """The columns of a sweep's rows, in order."""
    return ["run", *keys, *summary, *(HISTORY_COLUMNS if history else ()), "error", "warning"]


def run_batch(document: dict, source: str, keys: list, runs: list, summary: list, history: bool) -> dict:
    """Run ``runs`` (``[(run, {key: value})]``) of the scene ``document``; return the rows as
    ``{column: list}`` (see :func:`columns`)."""
    names = columns(keys, summary, history)
    table = {name: [] for name in names}
    for run, values in runs:
        row = one_run(document, source, values, summary, history)
        row["run"] = run
        row.update(values)
        for name in names:
            table[name].append(row[name])
    return table


def one_run(document: dict, source: str, values: dict, summary: list, history: bool) -> dict:
    """The row of one run (without its run number and values)."""
    row = {"error": "", "warning": ""}
    where = f"{source} with " + ", ".join(f"{key} = {value!r}" for key, value in values.items())
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            scene = scene_from_document(apply(document, values), where)
            result = summarize(scene, None, summary, history=history)
        row["warning"] = " | ".join(str(w.message) for w in caught)
        row.update(result)
        if history:
            for name in HISTORY_COLUMNS:
                row[name] = row[name].tolist()
    except (SceneError, SweepError, ElementError, ValueError) as exc:
        row["error"] = str(exc)
        row.update({q: math.nan for q in summary})
        if history:
            row.update({name: [] for name in HISTORY_COLUMNS})
    return row
