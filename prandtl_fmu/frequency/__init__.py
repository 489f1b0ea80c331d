"""The frequency domain: what an element does at each amplitude, and a mass on it at each frequency.

Two questions that engineers who model joints and friction dampers ask first (docs/frequency.md):

* :func:`describe_amplitudes`: the element driven in displacement, x = A sin(theta), theta = 2 pi f t, to
  its steady cycle; its first harmonic F_1 = a_1 sin(theta) + b_1 cos(theta) gives the effective stiffness
  K(A) = a_1 / A (N/m, the in-phase part: the describing function), the energy dissipated per cycle
  D(A) = oint F dx = pi A b_1 (J), and the loss factor D / (pi K A^2) = b_1 / a_1. Exact (the closed forms
  of each part, added) for springs, a dashpot, Prandtl branches and friction of the mass; the closed forms
  integrated over a spectrum of branches; a refined quadrature of the sampled cycle otherwise; each with a
  stated relative accuracy (``describing.py``);
* :func:`frequency_response`: a scene with a mass under F = F0 cos(2 pi f t): the steady first harmonic of
  x, x_1 = amplitude cos(2 pi f t + phase) (m, radians), frequency by frequency, swept up and down with
  continuation where the response has several branches (``response.py``: time integration);
* :func:`harmonic_response`: the same response of an element with a mass or a network by harmonic balance
  (``harmonic_balance.py``, ``aft.py``), continued along the arc length through its folds
  (``continuation.py``), each point's stability from Floquet multipliers (``floquet.py``) (``curve.py``);
  under a force on a node or the motion of the base (base excitation); :func:`harmonic_responses`: one
  curve per amplitude (a parameter study), on dask.distributed or in this process;
* :func:`nonlinear_mode`: a nonlinear mode's frequency and damping ratio against its amplitude by the extended
  periodic motion concept (``modes.py``).

A scene needs no ``[load]`` or ``[solver]`` for either (:func:`read_scene`): both drive the element themselves
and choose their steps; a ``[solver]`` table, when present, names the stepper of the frequency response.
Bad input raises :class:`FrequencyError` (a ValueError) with one line naming the culprit.
"""
from __future__ import annotations

import math
import os
from typing import Union

# Light at import (the standard library only): the command line builds its parser from here without loading
# numpy or numba; the methods load with their first use (``__getattr__``).

# The relative accuracy of K, D and of the response's first harmonic unless asked otherwise.
DEFAULT_TOLERANCE = 1e-3

# The solver settings a scene without [solver] is read with (its step is replaced by the methods' own).
_NO_SOLVER = {"step": 1e-3, "stop_time": 1.0, "output_interval": 1e-3}


class FrequencyError(ValueError):
    """Bad input, or a computation that cannot reach its stated accuracy: one line saying which and why."""


def read_scene(path: Union[str, os.PathLike], networks: bool = False):
    """``(scene, stepper)``: the scene file (or packaged scene) ``path``, read without needing ``[load]`` or
    ``[solver]``, and the stepper its ``[solver]`` names (None when it has none). SceneError on a broken rule;
    FrequencyError for a network scene unless ``networks`` (harmonic balance takes them)."""
    from ..scene import read_document

    return scene_of_document(*read_document(path), networks=networks)


def parse_scene(text: Union[str, bytes], source: str = "<scene>", networks: bool = False):
    """:func:`read_scene` for scene TOML text (``source`` names it in messages)."""
    from ..scene import toml_document

    return scene_of_document(toml_document(text, source), source, networks=networks)


def scene_of_document(doc: dict, source: str, networks: bool = False):
    """:func:`read_scene` for a parsed TOML document."""
    from ..scene import scene_from_document

    if networks and isinstance(doc, dict) and ("network" in doc or "chain" in doc):
        if "solver" not in doc:
            doc = dict(doc, solver=dict(_no_solver(doc), stepper="implicit"))
        return scene_from_document(doc, source, check_stepper=False), None
    if isinstance(doc, dict) and ("network" in doc or "chain" in doc):
        raise FrequencyError(f"{source}: this takes an element scene ([mass], [spring], [branches], ...), not a "
                             "[network] or [chain] (a network's joint: --amplitudes with --between I,J; its "
                             "response: harmonic balance)")
    named = None
    if isinstance(doc, dict) and isinstance(doc.get("solver"), dict) and "stepper" in doc["solver"]:
        named = doc["solver"]["stepper"]
    if isinstance(doc, dict) and "solver" not in doc:
        doc = dict(doc, solver=_no_solver(doc))
    scene = scene_from_document(doc, source, check_stepper=False)
    return scene, (scene.solver.stepper if named is not None else None)


def _no_solver(doc: dict) -> dict:
    """The ``[solver]`` a scene without one is read with: _NO_SOLVER, its step no longer than a ``[delay]``'s tau
    (the scene's rules judge a negative gain by the step: a step the user never wrote must not refuse it)."""
    solver = dict(_NO_SOLVER)
    delay = doc.get("delay")
    tau = delay.get("tau") if isinstance(delay, dict) else None
    if isinstance(tau, (int, float)) and not isinstance(tau, bool) and 0.0 < tau < solver["step"]:
        solver.update(step=float(tau), output_interval=float(tau))
    return solver


def positive_values(values, name: str):
    """``values`` as a 1-D float array of finite numbers > 0; FrequencyError naming ``name`` otherwise."""
    import numpy as np

    if isinstance(values, (str, bytes)):
        raise FrequencyError(f"{name}: must be numbers, got {values!r:.80}")
    try:
        array = np.array(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise FrequencyError(f"{name}: must be numbers, got {values!r:.80}") from None
    if array.size == 0:
        raise FrequencyError(f"{name}: at least one value is needed")
    for value in array.tolist():
        if not (math.isfinite(value) and value > 0):
            raise FrequencyError(f"{name}: every value must be a finite number > 0, got {value!r}")
    return array


def check_tolerance(tolerance) -> float:
    """The relative accuracy asked for, checked: 1e-12 <= tolerance < 1 (FrequencyError otherwise)."""
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float)) or not math.isfinite(tolerance) \
            or not 1e-12 <= tolerance < 1:
        raise FrequencyError(f"tolerance: must be a number in [1e-12, 1), got {tolerance!r}")
    return float(tolerance)


def settled(changes: list, tolerance: float) -> bool:
    """The settling test of a run repeated period by period (or cycle by cycle): ``changes`` are the relative
    changes of the first harmonic from each period to the next. Steady when at least three are known and the
    last one plus the geometric tail of those still to come, d r / (1 - r) with r the larger of the last two
    ratios d_p / d_(p-1), is at most tolerance / 4 (a transient decaying like exp(-t / T) leaves what the
    tail counts; a ratio >= 1, no decay yet, is never steady)."""
    return settling_remainder(changes) <= 0.25 * tolerance


def settling_remainder(changes: list) -> float:
    """What :func:`settled` measures: the last change plus the geometric tail of those still to come (inf
    before three changes are known or while they do not decay): an estimate of how far the last harmonic is
    from the steady one."""
    if len(changes) < 3:
        return math.inf
    last = changes[-1]
    ratios = [b / a if a > 0 else (0.0 if b == 0 else math.inf) for a, b in zip(changes[-3:-1], changes[-2:])]
    ratio = max(ratios)
    if not ratio < 1.0:
        return math.inf
    return last + last * ratio / (1.0 - ratio)


_LAZY = {"Description": "describing", "describe_amplitudes": "describing", "Response": "response",
         "frequency_response": "response", "NotSettled": "response", "Curve": "curve",
         "harmonic_response": "curve", "harmonic_responses": "curve", "Curves": "curve", "Backbone": "modes",
         "nonlinear_mode": "modes"}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["Backbone", "Curve", "Curves", "DEFAULT_TOLERANCE", "Description", "FrequencyError", "NotSettled",
           "Response", "describe_amplitudes", "frequency_response", "harmonic_response", "harmonic_responses",
           "nonlinear_mode", "parse_scene",
           "read_scene"]
