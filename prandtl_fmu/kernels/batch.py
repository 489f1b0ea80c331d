"""Many runs in one compiled call: the packed layout of a batch and its summary loop.

A sweep task runs thousands of short runs; a compiled call per run would
leave Python between runs (and a dispatcher per run). A batch instead packs
the runs that share one *structure* (the effects present, the branch kernel,
whether the branches have a state) into a few flat arrays, and one compiled
call per stepper runs them all (``summary_loop(step)``, wrapped in each
stepper's cached ``run_summary``). Plain arrays only: a batch costs no
compilation beyond the cached kernel, whatever the number of runs.

Run i of a batch is described by row i of two tables:

* ``real[i]`` (float): ``M, K0, K3, C`` (0 where the effect is absent: the
  batch's *template* says which are), the initial ``X0, V0``, the step ``H``,
  the remainder ``REST`` of the last output interval (0: none), the load's
  ``OFFSET, AMPLITUDE, OMEGA`` and the friction on the mass ``ALPHA,
  ALPHA_KINETIC, STRIBECK, BELT`` (unused without);
* ``index[i]`` (int): the load's ``LOAD_KIND``; ``FULL_STEPS`` (steps of h up
  to the last whole output interval), ``PER_ROW`` (steps per output row),
  ``MARK_STEP`` (after which step the energy account is copied to ``marks[i]``;
  -1: never), ``TAIL_STEPS`` (whole steps of h in the last, shorter interval),
  ``LAST_IS_SHORT`` (1 if the output grid ends with a shorter interval); and
  the ranges [A, B) of the run's slices of the flat data arrays:
  ``BRANCH_A, BRANCH_B`` (with ``BRANCH_ROWS, BRANCH_COLS``, the shape of the memory
  stack's parameters) in ``branch_data``, ``eta_data`` and ``damping_data`` (the series dashpots), ``TABLE_A, TABLE_B,
  TABLE_C`` in ``table_data`` (the load's time and force), ``STATE_A,
  STATE_B`` in ``state_data`` (the branches' state, advanced in place),
  ``HISTORY_A, HISTORY_B`` in ``history_data`` (the output rows, 3 values
  each; an empty range keeps none).

The arrays travel as one tuple, ``batch = (real, index, branch_data, eta_data,
damping_data, table_data, state_data, history_data, accounts, marks, out)``; the template
``(model, state, account)`` is the first run's model tuple, its
branch state (or None) and an energy account (or None: no account kept): it
carries the types only, so that every run of the batch compiles to the same
code as a run of its own (``kernels/loop.py``), and gives the same numbers,
bit for bit (tests/analysis/test_sweep.py, tests/analysis/test_summary.py).
"""
import numpy as np
from numba.core import types
from numba.extending import overload

from .play import branch_force
from .friction import reaction as reaction_of
from ..memory import prepare
from .._jit import kernel

# columns of ``real``
M, K0, K3, C, X0, V0, H, REST, OFFSET, AMPLITUDE, OMEGA, ALPHA, ALPHA_KINETIC, STRIBECK, BELT = range(15)
REAL_COLUMNS = 15
# columns of ``index``
(LOAD_KIND, FULL_STEPS, PER_ROW, MARK_STEP, TAIL_STEPS, LAST_IS_SHORT, BRANCH_A, BRANCH_B, BRANCH_ROWS,
 BRANCH_COLS, TABLE_A, TABLE_B, TABLE_C, STATE_A, STATE_B, HISTORY_A, HISTORY_B) = range(17)
INDEX_COLUMNS = 17
# columns of ``out``: the peaks of |x|, |v|, |reaction|, the final x, v, reaction, the start time and size of
# a step that could not be taken (NaN: none), the number of output rows written
PEAK_X, PEAK_V, PEAK_REACTION, FINAL_X, FINAL_V, FINAL_REACTION, FAILED_AT, FAILED_STEP, ROWS_WRITTEN = range(9)
OUT_COLUMNS = 9


def present(template, value):
    """``value``, or None where the template is None (compiled only: the choice is made from the types)."""
    raise NotImplementedError


@overload(present, inline="always")
def _present_overload(template, value):
    if isinstance(template, types.NoneType):
        return lambda template, value: None
    return lambda template, value: value


def branch_part(template, branch_data, eta_data, a, b, rows, cols):
    """``(k, eta)`` of a run, of the template's kind: none, the O(n) arrays, the memory stack's parameters
    (a 2-D array) or the continuum's (a tuple of one table). Views of the data arrays (compiled only)."""
    raise NotImplementedError


@overload(branch_part, inline="always")
def _branch_part_overload(template, branch_data, eta_data, a, b, rows, cols):
    if isinstance(template, types.NoneType):
        return lambda template, branch_data, eta_data, a, b, rows, cols: (None, None)
    if isinstance(template, types.BaseTuple):  # the continuum
        return lambda template, branch_data, eta_data, a, b, rows, cols: (
            (branch_data[a:b].reshape((rows, cols)),), None)
    if template.ndim == 2:  # the memory stack of n branches
        return lambda template, branch_data, eta_data, a, b, rows, cols: (
            branch_data[a:b].reshape((rows, cols)), None)
    return lambda template, branch_data, eta_data, a, b, rows, cols: (branch_data[a:b], eta_data[a:b])


@kernel
def _copy_row(source, target, i):
    """target[i, :] = source[i, :], element by element: a slice assignment compiles numba's check of the shapes,
    whose message formatting was 2.2 to 4.9 s of a cold compile of the summary loop (per process, cold suites)."""
    for q in range(source.shape[1]):
        target[i, q] = source[i, q]


def summary_loop(step):
    """The summary loop over the compiled ``step``, compiled (cached through each stepper's ``run_summary``,
    as ``kernels/loop.py`` explains for the time loop)."""
    from .._jit import generic_kernel

    def loop(template, batch):
        """Run every run of the ``batch`` (see the module docstring) from t = 0 to its stop time.

        Step number p starts at t_p = p h, as in the time loop; the last output
        interval, when shorter, takes its whole steps of h and one step of
        ``REST`` from (FULL_STEPS + TAIL_STEPS) h, as :func:`driver._advance`
        does. Watches every step: ``out[i]`` receives the peaks (the initial
        state counts) and the final state, ``accounts[i]`` the energy account
        (work, dissipated by the sliders, by the dashpots, by the friction on the mass; when the
        template has one), ``marks[i]`` the account after step MARK_STEP, and the output rows
        (after every PER_ROW steps up to FULL_STEPS, then the final state if the
        last interval is short) go to the run's history range. A step that
        cannot be taken (non-finite state) ends that run: ``out[i]`` then holds
        its start time and size, the values before it.
        """
        model_template, state_template, account_template = template
        real, index, branch_data, eta_data, damping_data, table_data, state_data, history_data, accounts, marks, out \
            = batch
        for i in range(real.shape[0]):
            k, eta = branch_part(model_template[4], branch_data, eta_data, index[i, BRANCH_A], index[i, BRANCH_B],
                                 index[i, BRANCH_ROWS], index[i, BRANCH_COLS])
            m = present(model_template[0], real[i, M])
            k0 = present(model_template[1], real[i, K0])
            k3 = present(model_template[2], real[i, K3])
            c = present(model_template[3], real[i, C])
            cs = present(model_template[6], damping_data[index[i, BRANCH_A]:index[i, BRANCH_B]])
            friction = present(model_template[7], (real[i, ALPHA], real[i, ALPHA_KINETIC], real[i, STRIBECK],
                                                   real[i, BELT]))
            model = (m, k0, k3, c, k, eta, cs, friction, (None, None, None))  # (no memory in a batch)
            load = (index[i, LOAD_KIND], real[i, OFFSET], real[i, AMPLITUDE], real[i, OMEGA],
                    table_data[index[i, TABLE_A]:index[i, TABLE_B]], table_data[index[i, TABLE_B]:index[i, TABLE_C]])
            u = present(state_template, state_data[index[i, STATE_A]:index[i, STATE_B]])
            energy = present(account_template, accounts[i])
            history = history_data[index[i, HISTORY_A]:index[i, HISTORY_B]].reshape((-1, 3))
            full_steps, per_row, mark = index[i, FULL_STEPS], index[i, PER_ROW], index[i, MARK_STEP]
            h, rest = real[i, H], real[i, REST]

            x, v = real[i, X0], real[i, V0]
            s = branch_force(k, u)
            reaction = reaction_of(model, load, 0.0, x, v, s)
            peak_x, peak_v, peak_reaction = abs(x), abs(v), abs(reaction)
            rows = 0
            if history.shape[0] > 0:
                history[0, 0], history[0, 1], history[0, 2] = x, v, reaction
                rows = 1
            if mark == 0:
                _copy_row(accounts, marks, i)
            failed_at, failed_step = np.nan, np.nan
            steps = full_steps + index[i, TAIL_STEPS]
            p = 0
            while p <= steps:
                if p < steps:
                    t, size = 0.0 + p * h, h
                elif rest > 0:
                    t, size = (full_steps + index[i, TAIL_STEPS]) * h, rest
                else:
                    break
                prepare(model[8], size)  # the memory's coefficients of this step (none without memory)
                x1, v1, s1 = step(model, load, t, size, x, v, s, u, energy)
                if not (abs(x1) < np.inf and abs(v1) < np.inf):
                    failed_at, failed_step = t, size
                    break
                x, v, s = x1, v1, s1
                p += 1
                reaction = reaction_of(model, load, t + size, x, v, s)
                peak_x = max(peak_x, abs(x))
                peak_v = max(peak_v, abs(v))
                peak_reaction = max(peak_reaction, abs(reaction))
                if p == mark:
                    _copy_row(accounts, marks, i)
                if rows > 0 and p <= full_steps and p % per_row == 0:
                    history[rows, 0], history[rows, 1], history[rows, 2] = x, v, reaction
                    rows += 1
            if rows > 0 and index[i, LAST_IS_SHORT] and np.isnan(failed_at):
                history[rows, 0], history[rows, 1], history[rows, 2] = x, v, reaction
                rows += 1
            out[i, PEAK_X], out[i, PEAK_V], out[i, PEAK_REACTION] = peak_x, peak_v, peak_reaction
            out[i, FINAL_X], out[i, FINAL_V], out[i, FINAL_REACTION] = x, v, reaction
            out[i, FAILED_AT], out[i, FAILED_STEP], out[i, ROWS_WRITTEN] = failed_at, failed_step, rows

    loop.__qualname__ = f"summary_loop.<locals>.loop_{step.__module__.rpartition('.')[2]}_{step.__name__}"
    return generic_kernel(loop)
