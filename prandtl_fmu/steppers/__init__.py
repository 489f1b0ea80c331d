"""Time steppers: one module per scheme, and the registry of their names.

A stepper module defines

* compiled steps ``step(model, load, t, h, x, v, s, u, energy) -> (x, v, s)``
  that advance the state from t to t + h. ``model = (m, k0, k3, c, k, eta)``
  holds the coefficients of the scene (``None`` for an absent effect),
  ``load`` the compiled force history, ``u`` the branch elongations (updated
  in place), ``s = sum_i k_i u_i`` their force, carried from step to step, and
  ``energy`` an energy account or ``None`` (see ``kernels/energy.py``). A
  step that cannot be taken returns a non-finite x;
* for each step, its compiled time loop ``run(model, load, x, v, u, t_base, first_step, h, ...)``: one
  line, ``return time_loop(step, ...)`` (``kernels/loop.py``), so that the loop is cached across processes;
* for each step, its compiled summary loop ``run_summary(template, batch)``: one line,
  ``return summary_loop(step)(...)`` (``kernels/batch.py``: many runs in one call, for sweeps), and
  ``SUMMARY_LOOPS = {run: run_summary, ...}``;
* ``loop_for(scene)``: the loop of the step that fits the scene (ValueError if none);
* ``ORDER``: the order of convergence in h (``math.inf`` for ``exact``);
* optionally ``STEP_IS_OUTPUT = True`` (the driver then takes one step per
  output interval: h does not set the accuracy) and ``failure_reason_for(scene)`` (a function that says in
  words why a step that failed could not be taken: which bound of an event search ran out), and
  ``POLYNOMIAL_INPUT = False`` for a scheme whose closed forms know the scene's load kinds only, not an FMU input
  given with its derivatives (``loads.polynomial``);
* every stepper books the energy account (``kernels/energy.py``): no output is ever NaN;
* a docstring with the update formula and the stability of the scheme.

To add a scheme: write one such module and add it to ``STEPPERS`` below.
``exact`` is three modules: ``exact.py`` (the registered stepper: plain branches, and the choice of loop),
``exact_series.py`` (branches with series dashpots) and ``exact_common.py`` (what both use: the matrix
exponential, the step's budgets and the words of a failed step).
"""
import importlib
from collections.abc import Mapping


class _Registry(Mapping):
    """Stepper name -> its module, imported when first asked for: the names (a command line's choices, a scene's
    check) are known without defining a single kernel, and a run imports only the stepper it uses."""

    def __init__(self, *names: str):
        self._names = names

    def __getitem__(self, name):
        if name not in self._names:
            raise KeyError(name)
        return importlib.import_module(f"{__name__}.{name}")

    def __contains__(self, name):
        return name in self._names  # without importing it (Mapping's own would)

    def __iter__(self):
        return iter(self._names)

    def __len__(self):
        return len(self._names)


STEPPERS = _Registry(
    "projected",
    "implicit",
    "symplectic",
    "verlet",
    "exact",
)


def get_stepper(name: str):
    """The stepper module registered under ``name``."""
    try:
        return STEPPERS[name]
    except KeyError:
        raise ValueError(f"unknown stepper {name!r} (known: {', '.join(STEPPERS)})") from None
