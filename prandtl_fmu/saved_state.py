"""The numbers of a saved state: what :meth:`element.Element.get_state`, :meth:`connector.Connector.get_state`
and the effects with memory (``memory/``) hold where they hold a number, checked when a state is restored (an
FMU's serialized state comes from outside: a bool, a string, a NaN or a list where a number belongs is refused
with a ValueError that names the field)."""
from __future__ import annotations

import math

import numpy as np


def plain_number(value, what: str) -> float:
    """``value`` as a float if it is a finite int or float (not a bool, a string or a list); ValueError naming
    ``what`` otherwise. What a saved state must hold where it holds a number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"state has {what} = {value!r}, not a finite number")
    return float(value)


def number_list(values, what: str) -> np.ndarray:
    """A list of finite numbers (:func:`plain_number` each) as a 1-D array; ValueError otherwise."""
    if not isinstance(values, (list, tuple)):
        raise ValueError(f"state has {what} = {values!r:.60}, not a list of numbers")
    return np.array([plain_number(value, what) for value in values], dtype=float)
