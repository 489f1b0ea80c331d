"""Identification: from a measured force-displacement history to a scene.

For a displacement-driven element the force is

    F = k0 x + k3 x^3 + c v + sum_i k_i play_{eta_i}[x],

*linear* in (k0, k3, c, k_i) once the elastic ranges eta_i are fixed: on a
grid of candidate eta the fit is a non-negative least-squares problem on the
play-operator basis (each column the exact play update along the measured x,
``kernels/drive.play_basis``), solved by ``scipy.optimize.nnls``; the
branches with a non-zero weight are kept. The grid is refined around them
(midpoints to the neighbours) and the problem solved again, ``refine`` times.

A true elastic range that falls between grid points comes out as weights on
its neighbours. So the ranges themselves are then moved (variable
projection, started from the NNLS solution): each run of neighbouring kept
ranges becomes one branch at their weighted mean, and
``scipy.optimize.least_squares`` minimizes the residual over log eta, the
weights given by NNLS at every evaluation; branches that lose their weight
are dropped. The refined fit replaces the grid's only when its residual is
smaller. On a noise-free loop of n branches it finds the n ranges (the force
to ~1e-10 of its range; tests/analysis/test_fit.py).

The default grid mixes a geometric grid from the resolution of the data to
the largest excursion of x with points placed where the virgin curve bends
most (Whiteman 1959: along the virgin loading from x = 0 the force of the
branches is sum_i k_i min(x, eta_i), so -F''(x) is the density of stiffness
at eta = x): quantiles of |F''| along the virgin branch, where the data has
one (the first monotone stretch from x near 0 covers at least a fifth of the
largest excursion).

The continuous families (:func:`fit_continuum`, ``--continuum MODEL``):

* ``piecewise``: a piecewise-constant density over a grid of elastic ranges
  0 = e_0 < e_1 < ... < e_J. Segment j (stiffness w_j spread evenly over
  eta in [e_j-1, e_j]) adds w_j times the force of a unit continuum on that
  range, so the fit is again linear: NNLS on those J columns (each one
  compiled drive of the memory stack along x). The scene is
  ``density = { kind = "piecewise" }`` with equal s-segments, k_j = J w_j.
* ``iwan`` (Segalman's F_S, K_T, chi, beta) and ``linear`` (the paper's
  k_total, eta_range): for a fixed shape (phi_max, chi, beta; or eta_min,
  eta_max) the force is linear in the scale (K_T; k_total) and in k0, k3,
  c: variable projection. NNLS gives the linear weights of each shape, and
  ``scipy.optimize.least_squares`` moves the shape (bounded), started from
  the best of a coarse grid of shapes.

What it does not fit: rate-dependent branches (a dashpot in series with a
branch, ``[branches] c``) and friction of a mass on the ground
(``[friction]``): the fitted scene is the rate-independent connector, plus a
parallel dashpot with ``dashpot``. Every report says so
(:data:`NOT_FITTED`).

Needs scipy (the ``[fit]`` extra).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .kernels.drive import play_basis, spectrum_drive

CONTINUUM_MODELS = ("piecewise", "iwan", "linear")


# What every fit report says it left out (the module docstring).
NOT_FITTED = ("fit identifies rate-independent branches only: it does not fit series dashpots in the branches "
              "([branches] c, a rate-dependent loop) nor friction of a mass on the ground ([friction])")


class FitError(ValueError):
    """Data that cannot be fitted; the message is one line naming the culprit."""


@dataclass
class Fit:
    """A fitted element: coefficients (0 where absent), kept branches (k, eta), and the residual."""

    k0: float
    k3: float
    c: float
    k: np.ndarray
    eta: np.ndarray
    fitted: np.ndarray  # the fitted force at each sample
    residual_rms: float
    residual_max: float
    force_range: float
    grid_size: int
    effects: dict = field(default_factory=dict)  # which smooth terms were in the basis
    model: Optional[str] = None  # a continuous family (CONTINUUM_MODELS), or None for n branches
    density: dict = field(default_factory=dict)  # the [branches] keys of the fitted continuum
    notes: list = field(default_factory=list)  # what the data could not determine

    @property
    def relative_rms(self) -> float:
        return self.residual_rms / self.force_range

    @property
    def relative_max(self) -> float:
        return self.residual_max / self.force_range

    @property
    def label(self) -> str:
        """What was fitted, in a few words."""
        if self.model is None:
            return f"{len(self.k)} branches"
        if self.model == "piecewise":
            kept = int(np.count_nonzero(np.asarray(self.density["density"]["k"]) > 0))
            return f"continuum, {kept} of {len(self.density['density']['k'])} segments non-empty"
        if self.model == "iwan":
            d = self.density["density"]
            return f"Iwan F_S = {d['F_S']:.6g} N, K_T = {d['K_T']:.6g} N/m, chi = {d['chi']:.4g}, beta = {d['beta']:.4g}"
        return (f"continuum k_total = {self.density['k_total']:.6g} N/m, eta_range = "
                f"[{self.density['eta_range'][0]:.6g}, {self.density['eta_range'][1]:.6g}] m")

    def report(self) -> str:
        """One line of what was fitted and how well, the notes, and what fit never fits (:data:`NOT_FITTED`)."""
        head = (f"{len(self.k)} branches kept of {self.grid_size} candidates" if self.model is None
                else f"{self.label} ({self.grid_size} candidate {'segments' if self.model == 'piecewise' else 'shapes'})")
        return (f"{head}; k0 = {self.k0:.6g}"
                + (f", k3 = {self.k3:.6g}" if self.effects.get("cubic") else "")
                + (f", c = {self.c:.6g}" if self.effects.get("dashpot") else "")
                + f"; residual RMS {self.residual_rms:.3g} N ({100 * self.relative_rms:.3g} % of the force range "
                f"{self.force_range:.3g} N), max {self.residual_max:.3g} N ({100 * self.relative_max:.3g} %)"
                + "".join(f"\nnote: {note}" for note in self.notes + [NOT_FITTED]))

    def scene_text(self, name: str, time: Optional[np.ndarray] = None) -> str:
        """A scene in the contract's format: the connector ([fmu] causality = "displacement"); add [mass] and
        a [load] (and drop the [fmu] table) for an element with its mass."""
        lines = ["# Fitted by prandtl-fmu fit: " + self.report().replace("\n", "\n# "),
                 "# The connector (displacement in, force out). For the element with its mass under a force, add",
                 "# [mass] and [load] tables and remove [fmu].",
                 f"name = {_toml_string(name)}", ""]
        if self.k0 > 0:
            lines += ["[spring]", f"k0 = {self.k0!r}", ""]
        if self.effects.get("cubic") and self.k3 > 0:
            lines += ["[cubic]", f"k3 = {self.k3!r}", ""]
        if self.effects.get("dashpot") and self.c > 0:
            lines += ["[damper]", f"c = {self.c!r}", ""]
        if self.model is not None:
            lines += ["[branches]", "continuum = true"]
            lines += [f"{key} = {_toml_value(value)}" for key, value in self.density.items()] + [""]
        elif len(self.k):
            lines += ["[branches]", "k = [" + ", ".join(repr(float(v)) for v in self.k) + "]",
                      "eta = [" + ", ".join(repr(float(v)) for v in self.eta) + "]", ""]
        lines += ["[fmu]", 'causality = "displacement"', ""]
        duration = float(time[-1] - time[0]) if time is not None and len(time) > 1 else 1.0
        interval = float(np.median(np.diff(time))) if time is not None and len(time) > 1 else 0.01
        lines += ["[solver]", 'stepper = "implicit"', f"step = {interval!r}", f"stop_time = {duration!r}",
                  f"output_interval = {interval!r}", ""]
        return "\n".join(lines)


def _toml_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _toml_value(value) -> str:
    """A number, string, list or inline table in TOML (numbers as repr: full precision)."""
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{key} = {_toml_value(v)}" for key, v in value.items()) + " }"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(float(value))


def _roles(x, force, time, v) -> dict:
    """{"x": x, "force": force} plus "time" and "v" where given."""
    given = {"x": x, "force": force, "time": time, "v": v}
    return {role: value for role, value in given.items() if value is not None}


def check_data(x, force, time=None, v=None):
    """The arrays as float, or FitError naming what is wrong (one line)."""
    checked = {}
    for name, values in _roles(x, force, time, v).items():
        values = np.asarray(values, dtype=float).reshape(-1)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise FitError(f"{name}: row {bad[0] + 1} is not a finite number ({values[bad[0]]!r})")
        checked[name] = values
    count = checked["x"].shape[0]
    if any(values.shape[0] != count for values in checked.values()):
        raise FitError("the columns have different lengths")
    if count < 10:
        raise FitError(f"too few points: {count} (at least 10)")
    if np.ptp(checked["x"]) == 0:
        raise FitError("x is constant: a loop needs motion")
    if "time" in checked:
        steps = np.diff(checked["time"])
        if np.any(steps <= 0):
            row = int(np.flatnonzero(steps <= 0)[0]) + 2
            raise FitError(f"time: not increasing at row {row} ({checked['time'][row - 2]!r} then "
                           f"{checked['time'][row - 1]!r})")
    return checked


def default_grid(x, force, size: int = 40) -> np.ndarray:
    """Candidate elastic ranges: geometric from the data's resolution to the largest excursion of x, plus
    (Whiteman) quantiles of |F''| along the virgin loading branch where the data has one."""
    excursion = float(np.max(np.abs(x)))
    steps = np.abs(np.diff(x))
    resolution = max(float(np.median(steps[steps > 0])) if np.any(steps > 0) else excursion * 1e-3,
                     excursion * 1e-4)
    geometric = np.geomspace(resolution, excursion, size)
    virgin = _virgin_branch(x, force)
    if virgin is None:
        return geometric
    xv, fv = virgin
    order = np.argsort(xv)
    xv, fv = xv[order], fv[order]
    keep = np.concatenate([[True], np.diff(xv) > 0])
    xv, fv = xv[keep], fv[keep]
    if xv.shape[0] < 8:
        return geometric
    slope = np.gradient(fv, xv)
    bend = np.abs(np.gradient(slope, xv))
    weights = np.cumsum(bend)
    if weights[-1] <= 0:
        return geometric
    quantiles = np.interp(np.linspace(0, weights[-1], size // 2 + 2)[1:-1], weights, xv)
    grid = np.concatenate([geometric[::2], quantiles[quantiles > 0]])
    return np.unique(grid)


def _virgin_branch(x, force):
    """(|x|, |F|) along the first monotone stretch from x near 0, if it covers a fifth of the excursion."""
    excursion = np.max(np.abs(x))
    if abs(x[0]) > 0.05 * excursion:
        return None
    direction = np.sign(x[np.flatnonzero(x != x[0])[0]] - x[0]) if np.any(x != x[0]) else 0
    if direction == 0:
        return None
    moves = np.diff(x) * direction
    reversal = np.flatnonzero(moves < 0)
    end = int(reversal[0]) + 1 if reversal.size else x.shape[0]
    if abs(x[end - 1] - x[0]) < 0.2 * excursion:
        return None
    return np.abs(x[:end] - x[0]), np.abs(force[:end] - force[0])


def fit(x, force, *, time=None, v=None, etas=None, grid_size: int = 40, dashpot: bool = False,
        cubic: bool = False, refine: int = 2) -> Fit:
    """Fit the element to a measured history (see the module docstring).

    ``etas``: the candidate elastic ranges (default :func:`default_grid`); ``dashpot`` fits c on v (given, or
    the derivative of x in ``time``); ``cubic`` fits k3. FitError for data that cannot be fitted.
    """
    from scipy.optimize import nnls

    xs, fs, smooth = _smooth_columns(x, force, time, v, dashpot, cubic)
    _check_basis_memory(xs.shape[0], len(smooth) + (len(etas) if etas is not None else grid_size))
    grid = np.unique(np.asarray(etas if etas is not None else default_grid(xs, fs, grid_size), dtype=float))
    if grid.size == 0 or np.any(grid <= 0) or not np.all(np.isfinite(grid)):
        raise FitError("the elastic ranges of the grid must be finite and > 0")
    for _ in range(refine + 1):
        weights, columns = _solve(nnls, xs, fs, smooth, grid)
        branch_weights = weights[len(smooth):]
        kept = branch_weights > 1e-12 * max(branch_weights.max(initial=0.0), 1e-300)
        if etas is not None or _ == refine or not np.any(kept):
            break
        grid = _refined(grid, kept)
    kept = weights[len(smooth):] > 1e-12 * max(weights[len(smooth):].max(initial=0.0), 1e-300)
    result = _result(fs, columns, weights, len(smooth), dashpot, cubic, grid_size=int(grid.size),
                     k=weights[len(smooth):][kept], eta=grid[kept])
    if etas is None and np.any(kept):
        moved = _moved_ranges(nnls, xs, fs, smooth, grid, weights[len(smooth):], kept, dashpot, cubic)
        if moved is not None and moved.residual_rms < result.residual_rms:
            return moved
    return result


# Variable projection moves at most this many ranges (a noisy loop keeps many clusters: the grid fit stands)
_MOVED_RANGES = 60


def _moved_ranges(nnls, xs, fs, smooth, grid, branch_weights, kept, dashpot, cubic):
    """The fit with the kept ranges moved (see the module docstring), or None when there are too many.

    Two starts, the better kept: each run of neighbouring kept ranges as one branch per peak of its weights
    (two true ranges between the same grid points make a run with two peaks), and every kept range alone
    (ranges that meet are merged afterwards and moved once more)."""
    indices = np.flatnonzero(kept)
    if indices.shape[0] > _MOVED_RANGES:
        return None
    runs = []
    for run in np.split(indices, np.flatnonzero(np.diff(indices) > 1) + 1):
        w = branch_weights[run]
        cuts = [j for j in range(1, run.shape[0] - 1) if w[j] < w[j - 1] and w[j] <= w[j + 1]]
        runs += np.split(run, cuts)  # a valley of the weights separates two peaks
    peaks = np.array([np.exp(np.average(np.log(grid[run]), weights=branch_weights[run])) for run in runs])
    low, high = np.log(grid[0]) - np.log(4.0), np.log(max(grid[-1], np.max(np.abs(xs)))) + np.log(4.0)
    best = None
    for start in (peaks, grid[indices]):
        moved = _vary_ranges(nnls, xs, fs, smooth, np.clip(np.log(start), low, high), low, high)
        if moved is None:
            continue
        eta, _ = moved
        merged = _merge_close(eta)
        if merged.shape[0] < eta.shape[0]:
            moved = _vary_ranges(nnls, xs, fs, smooth, np.log(merged), low, high) or moved
        if best is None or moved[1] < best[1]:
            best = moved
    if best is None:
        return None
    eta = _fewest_ranges(nnls, xs, fs, smooth, best, low, high)
    weights, columns = _ranges_solved(nnls, xs, fs, smooth, eta)
    branch = weights[len(smooth):]
    kept = branch > 1e-12 * max(branch.max(initial=0.0), 1e-300)
    order = np.argsort(eta[kept])
    return _result(fs, columns, weights, len(smooth), dashpot, cubic, grid_size=int(grid.size),
                   k=branch[kept][order], eta=eta[kept][order])


def _ranges_solved(nnls, xs, fs, smooth, eta):
    """(weights, columns) of NNLS with the branches of elastic ranges ``eta``."""
    basis = np.empty((xs.shape[0], eta.shape[0]))
    play_basis(xs, eta, basis)
    return _nnls(nnls, fs, np.column_stack(smooth + [basis]))


def _vary_ranges(nnls, xs, fs, smooth, log_eta, low, high):
    """(eta, sum of squares) at the least-squares optimum over log eta in [low, high], the branches of zero
    weight dropped; None when no branch keeps a weight."""
    from scipy.optimize import least_squares

    def residual(values):
        weights, columns = _ranges_solved(nnls, xs, fs, smooth, np.exp(values))
        return columns @ weights - fs

    solution = least_squares(residual, log_eta, bounds=(np.full(log_eta.shape, low), np.full(log_eta.shape, high)),
                             diff_step=1e-9, xtol=1e-15, ftol=1e-15, gtol=1e-15,
                             max_nfev=20 * (log_eta.shape[0] + 1))  # a loop of another model crawls: bounded
    eta = np.exp(solution.x)
    weights, columns = _ranges_solved(nnls, xs, fs, smooth, eta)
    # a branch whose force never reaches 1e-9 of the force range is rounding, not a branch: dropped
    contribution = weights[len(smooth):] * np.max(np.abs(columns[:, len(smooth):]), axis=0)
    kept = contribution > 1e-9 * np.ptp(fs)
    if not np.any(kept):
        return None
    weights, columns = _ranges_solved(nnls, xs, fs, smooth, eta[kept])
    return eta[kept], float(np.sum((columns @ weights - fs) ** 2))


def _fewest_ranges(nnls, xs, fs, smooth, moved, low, high):
    """Parsimony: two neighbouring ranges closer than 10 % that the data cannot tell apart (no reversal of an
    amplitude between them) fit as well as one: merged (at the weighted geometric mean, then moved again) while
    the RMS residual grows by less than 1e-10 of the force range."""
    eta, squares = moved
    allowed = (1e-10 * np.ptp(fs)) ** 2 * xs.shape[0]
    merged_one = True
    while merged_one and eta.shape[0] > 1:
        merged_one = False
        weights, _ = _ranges_solved(nnls, xs, fs, smooth, eta)
        branch = weights[len(smooth):]
        gaps = np.diff(np.log(eta))
        for i in np.argsort(gaps):
            if gaps[i] > np.log(1.1):
                break
            pair = branch[i:i + 2]
            joined = np.exp(np.average(np.log(eta[i:i + 2]), weights=pair)) if pair.sum() > 0 else eta[i]
            start = np.log(np.concatenate([eta[:i], [joined], eta[i + 2:]]))
            trial = _vary_ranges(nnls, xs, fs, smooth, np.clip(start, low, high), low, high)
            if trial is not None and np.sqrt(trial[1]) <= np.sqrt(squares) + np.sqrt(allowed):
                eta, squares = trial
                merged_one = True
                break
    return eta


def _merge_close(eta, relative=1e-6):
    """The ranges with those closer than ``relative`` to their neighbour merged (their geometric mean)."""
    eta = np.sort(eta)
    groups = np.split(eta, np.flatnonzero(np.diff(np.log(eta)) > relative) + 1)
    return np.array([np.exp(np.mean(np.log(group))) for group in groups])


def _smooth_columns(x, force, time, v, dashpot, cubic):
    """(x, force, [x, x^3?, v?]): the checked data and the columns of the smooth terms."""
    data = check_data(x, force, time, v)
    xs, fs = data["x"], data["force"]
    if dashpot:
        if "v" in data:
            vs = data["v"]
        elif "time" in data:
            vs = np.gradient(xs, data["time"])
        else:
            raise FitError("--dashpot needs the velocity or the time column")
    return xs, fs, [xs] + ([xs ** 3] if cubic else []) + ([vs] if dashpot else [])


def _result(fs, columns, weights, smooth_count, dashpot, cubic, **fields) -> Fit:
    fitted = columns @ weights
    residual = fs - fitted
    smooth_weights = list(weights[:smooth_count])
    k0 = smooth_weights.pop(0)
    k3 = smooth_weights.pop(0) if cubic else 0.0
    c = smooth_weights.pop(0) if dashpot else 0.0
    fields.setdefault("k", np.zeros(0))
    fields.setdefault("eta", np.zeros(0))
    return Fit(k0=float(k0), k3=float(k3), c=float(c), fitted=fitted,
               residual_rms=float(np.sqrt(np.mean(residual ** 2))), residual_max=float(np.abs(residual).max()),
               force_range=float(np.ptp(fs)) or 1.0, effects={"cubic": cubic, "dashpot": dashpot}, **fields)


# Copies of the basis a least-squares solve holds at once: the basis, the columns stacked with the smooth terms,
# the same scaled to unit norm, and scipy's nnls's own copy (measured: tests/cli/test_hostile_inputs.py)
_BASIS_COPIES = 4


def _check_basis_memory(samples: int, columns: int) -> None:
    """FitError (one line) when the least-squares basis of ``samples`` x ``columns`` would not fit in memory."""
    from .resources import available_memory, size_text

    need = _BASIS_COPIES * 8.0 * samples * columns
    available = available_memory()
    if need > available:
        raise FitError(f"the fit's basis ({samples} samples x {columns} columns) needs about {size_text(need)} of "
                       f"memory, {size_text(available)} available: fewer candidates (--branches) or fewer samples")


def _solve(nnls, xs, fs, smooth, grid):
    _check_basis_memory(xs.shape[0], len(smooth) + grid.shape[0])
    basis = np.empty((xs.shape[0], grid.shape[0]))
    play_basis(xs, grid, basis)
    return _nnls(nnls, fs, np.column_stack(smooth + [basis]))


def _nnls(nnls, fs, columns):
    """(weights >= 0, columns): least squares on the columns scaled to unit norm (for the conditioning)."""
    scale = np.sqrt(np.sum(columns ** 2, axis=0))
    scale[scale == 0] = 1.0
    weights, _ = nnls(columns / scale, fs, maxiter=50 * columns.shape[1])
    return weights / scale, columns


def spectrum_response(params, xs) -> np.ndarray:
    """The force of a virgin continuum (memory-stack ``params``) along the samples xs, from x = 0."""
    from .kernels import stack

    out = np.empty(xs.shape[0])
    spectrum_drive(params, stack.fresh_state(params, 0.0), np.ascontiguousarray(xs, dtype=float), out)
    return out


def fit_continuum(x, force, model: str, *, time=None, v=None, etas=None, grid_size: int = 40,
                  dashpot: bool = False, cubic: bool = False) -> Fit:
    """Fit a continuous family (``model`` in CONTINUUM_MODELS; see the module docstring). ``etas``: the
    piecewise density's nodes beyond 0 (default :func:`default_grid`). FitError for data that cannot be
    fitted."""
    from scipy.optimize import nnls

    if model not in CONTINUUM_MODELS:
        raise FitError(f"--continuum must be one of {', '.join(CONTINUUM_MODELS)}, got {model!r}")
    xs, fs, smooth = _smooth_columns(x, force, time, v, dashpot, cubic)
    if model == "piecewise":
        _check_basis_memory(xs.shape[0], len(smooth) + 1 + (len(etas) if etas is not None else grid_size))
        grid = np.asarray(etas if etas is not None else default_grid(xs, fs, grid_size), dtype=float)
        if grid.size == 0 or np.any(grid <= 0) or not np.all(np.isfinite(grid)):
            raise FitError("the elastic ranges of the grid must be finite and > 0")
        return _fit_piecewise(nnls, xs, fs, smooth, grid, dashpot, cubic)
    return _fit_family(nnls, xs, fs, smooth, model, dashpot, cubic)


def _fit_piecewise(nnls, xs, fs, smooth, grid, dashpot, cubic) -> Fit:
    from .kernels import stack

    nodes = np.unique(np.concatenate([[0.0], grid]))
    basis = np.column_stack([spectrum_response(stack.continuum(1.0, lo, hi), xs)
                             for lo, hi in zip(nodes[:-1], nodes[1:])])
    weights, columns = _nnls(nnls, fs, np.column_stack(smooth + [basis]))
    segment = weights[len(smooth):]
    present = np.flatnonzero(segment > 1e-12 * max(segment.max(initial=0.0), 1e-300))
    fields = {"grid_size": int(segment.size), "model": "piecewise"}
    if present.size:
        first, last = int(present[0]), int(present[-1])
        kept = np.where(segment[first:last + 1] > 1e-12 * segment.max(), segment[first:last + 1], 0.0)
        count = kept.shape[0]  # equal s-segments of width 1 / count: density count * w_j
        fields["density"] = {"density": {"kind": "piecewise", "k": (count * kept).tolist(),
                                         "eta": nodes[first:last + 2].tolist()}}
    else:
        raise FitError("the fit found no friction: every segment's weight is 0 (fit the branches instead, "
                       "or check that force and x are the element's)")
    return _result(fs, columns, weights, len(smooth), dashpot, cubic, **fields)


def _family_params(model, shape):
    """(memory-stack params of the unit-scale spectrum, its [branches] keys as a function of the scale)."""
    from .effects import ContinuousBranches

    if model == "iwan":
        phi_max, chi, beta = np.exp(shape[0]), shape[1], shape[2]
        ratio = (chi + 1.0) / (chi + 2.0)
        f_s = phi_max * (beta + ratio) / (1.0 + beta)  # at K_T = 1
        spectrum = ContinuousBranches.iwan(f_s, 1.0, chi, beta)
        return spectrum.params, lambda scale: {"density": {"kind": "iwan", "F_S": float(scale * f_s),
                                                            "K_T": float(scale), "chi": float(chi),
                                                            "beta": float(beta)}}
    eta_min, eta_max = np.exp(shape[0]), np.exp(shape[0]) + np.exp(shape[1])
    spectrum = ContinuousBranches.linear(1.0, eta_min, eta_max)
    return spectrum.params, lambda scale: {"k_total": float(scale), "eta_range": [float(eta_min), float(eta_max)]}


def _fit_family(nnls, xs, fs, smooth, model, dashpot, cubic) -> Fit:
    """Variable projection: the shape by bounded least squares, the scale and smooth terms by NNLS."""
    from scipy.optimize import least_squares

    excursion = float(np.max(np.abs(xs)))
    low, high = np.log(excursion * 1e-4), np.log(excursion * 10.0)

    def projected(shape):
        params, _ = _family_params(model, shape)
        return _nnls(nnls, fs, np.column_stack(smooth + [spectrum_response(params, xs)]))

    def residual(shape):
        weights, columns = projected(shape)
        return columns @ weights - fs

    sizes = np.log(np.geomspace(excursion * 1e-3, excursion * 2.0, 10))
    if model == "iwan":
        starts = [(a, chi, beta) for a in sizes for chi in (-0.8, -0.5, -0.2, 0.5) for beta in (0.0, 0.3, 1.0, 3.0)]
        bounds = ([low, -0.99, 0.0], [high, 5.0, 100.0])
    else:
        starts = [(a, b) for a in sizes for b in sizes]
        bounds = ([low, low], [high, high])
    start = min(starts, key=lambda shape: float(np.sum(residual(shape) ** 2)))
    solution = least_squares(residual, start, bounds=bounds, x_scale="jac", xtol=1e-15, ftol=1e-15, gtol=1e-15,
                             max_nfev=2000)
    if solution.status == 0:
        raise FitError(f"the {model} fit did not converge in {solution.nfev} evaluations (the family may not "
                       "fit this loop: try --continuum piecewise or the branches)")
    weights, columns = projected(solution.x)
    scale = float(weights[-1])
    if not scale > 0:
        raise FitError(f"the {model} fit found no friction (scale 0): fit the branches or piecewise instead")
    _, keys = _family_params(model, solution.x)
    top = np.exp(solution.x[0]) if model == "iwan" else np.exp(solution.x[0]) + np.exp(solution.x[1])
    notes = []
    if top >= 0.99 * excursion:  # the optimum's top is anywhere beyond the data: it stops near the edge
        what = ("phi_max", "F_S, beta and the split of the stiffness between k0 and K_T") if model == "iwan" else (
            "eta_max", "the top of eta_range and the split of the stiffness between k0 and k_total")
        notes.append(f"the loop barely or never reaches macro-slip (max |x| = {excursion:.3g} m, {what[0]} = "
                     f"{top:.3g} m): "
                     f"{what[1]} are not determined by this data; this is one of many equally good fits")
    return _result(fs, columns, weights, len(smooth), dashpot, cubic, grid_size=len(starts), model=model,
                   density=keys(scale), notes=notes)


def _refined(grid, kept):
    """The grid plus the midpoints between each kept eta and its neighbours."""
    extra = []
    for i in np.flatnonzero(kept):
        if i > 0:
            extra.append(0.5 * (grid[i - 1] + grid[i]))
        if i + 1 < grid.shape[0]:
            extra.append(0.5 * (grid[i] + grid[i + 1]))
    return np.unique(np.concatenate([grid, extra]))


def read_columns(path, time: Optional[str], x: str, force: str, v: Optional[str]):
    """The named columns of a CSV file with a header; FitError for a missing file, column or bad value.

    Read row by row into arrays of the named columns only (8 bytes a value: a file of any size takes no more
    than its numbers do); a UTF-8 byte-order mark (as spreadsheets save CSV) is skipped."""
    import csv
    from array import array

    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            rows = csv.reader(fh)
            header = next(rows, None)
            if header is None:
                raise FitError(f"{path}: empty")
            header = [name.strip() for name in header]
            wanted = _roles(x, force, time, v)
            index = {}
            for role, name in wanted.items():
                if name not in header:
                    raise FitError(f"{path}: no column {name!r} (columns: {', '.join(header)}); name it with "
                                   f"--{role}")
                index[role] = header.index(name)
            columns = {role: array("d") for role in wanted}
            for number, row in enumerate(rows, start=2):
                if not row or all(not cell.strip() for cell in row):
                    continue
                for role, position in index.items():
                    try:
                        columns[role].append(float(row[position]))
                    except (IndexError, ValueError):
                        cell = row[position] if position < len(row) else "(missing)"
                        raise FitError(f"{path}: line {number}, column {wanted[role]!r}: not a number: "
                                       f"{cell[:40]!r}") from None
    except OSError as exc:
        raise FitError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise FitError(f"{path}: not a CSV text file ({exc.__class__.__name__})") from None
    return {role: np.frombuffer(values, dtype=float).copy() for role, values in columns.items()}


def plot_fit(path, x, force, fit_result: Fit, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (loop, error) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    loop.plot(x, force, lw=1.6, color="0.6", label="measured")
    loop.plot(x, fit_result.fitted, lw=0.8, color="C3", label="fitted")
    fig.suptitle(f"fitted: {fit_result.label}", fontsize="medium")
    loop.set(xlabel="x (m)", ylabel="force (N)", title=title)
    loop.legend(loc="upper left")
    error.plot(np.arange(len(x)), force - fit_result.fitted, lw=0.6)
    error.set(xlabel="sample", ylabel="measured - fitted (N)",
              title=f"residual: RMS {100 * fit_result.relative_rms:.2g} % of the range")
    for ax in (loop, error):
        ax.grid(alpha=0.3)
    from .plots import save_figure

    save_figure(fig, path)


