"""The work of one sweep task: a batch of runs of one scene, in the worker's process.

Everything a task receives and returns is plain data (the scene's TOML
document, the runs' values, lists of numbers): no compiled function ever
travels between processes. The worker loads the compiled kernels from its
numba cache (or compiles them once per process), then checks each run's
scene and runs them all with :func:`summary.summarize_many`: one compiled call
for the runs of one structure, never Python per step.

A run that cannot be done (its scene breaks a rule, the element collapses,
a step fails) gives a row whose ``error`` column says why, with NaN values;
a run that warns (a step beyond an explicit stepper's stability limit) keeps
the warning in its ``warning`` column. Neither stops the other runs.
"""
from __future__ import annotations

import math

from ..scene import scene_from_document
from ..summary import HISTORY_COLUMNS, summarize_many
from .spec import apply


def columns(keys, summary, history) -> list:
    """The columns of a sweep's rows, in order."""
    return ["run", *keys, *summary, *(HISTORY_COLUMNS if history else ()), "error", "warning"]


def run_batch(document: dict, source: str, keys: list, runs: list, summary: list, history: bool) -> dict:
    """Run ``runs`` (``[(run, {key: value})]``) of the scene ``document``; return the rows as
    ``{column: list}`` (see :func:`columns`)."""
    names = columns(keys, summary, history)
    rows, checked, where = [], [], []
    for run, values in runs:
        row = {"run": run, **values, "error": "", "warning": ""}
        rows.append(row)
        label = f"{source} with " + ", ".join(f"{key} = {value!r}" for key, value in values.items())
        try:
            scene = scene_from_document(apply(document, values), label)
        except ValueError as exc:  # SceneError, SweepError, ResourceError
            _failed(row, str(exc), summary, history)
            continue
        checked.append((scene, scene.solver.stepper))
        where.append(row)
    for row, outcome in zip(where, summarize_many(checked, summary, history=history)):
        row["warning"] = outcome.warning
        if outcome.error is not None:
            _failed(row, str(outcome.error), summary, history)
            continue
        row.update(outcome.values)
        if history:
            for name in HISTORY_COLUMNS:
                row[name] = row[name].tolist()
    return {name: [row[name] for row in rows] for name in names}


def _failed(row: dict, reason: str, summary: list, history: bool) -> None:
    row["error"] = reason
    row.update({q: math.nan for q in summary})
    if history:
        row.update({name: [] for name in HISTORY_COLUMNS})
