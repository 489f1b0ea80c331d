"""Identification: from a measured force-displacement history to a scene.

For a displacement-driven element the force is

    F = k0 x + k3 x^3 + c v + sum_i k_i play_{eta_i}[x],

*linear* in (k0, k3, c, k_i) once the elastic ranges eta_i are fixed: on a
grid of candidate eta the fit is a non-negative least-squares problem on the
play-operator basis (each column the exact play update along the measured x,
``kernels/drive.play_basis``), solved by ``scipy.optimize.nnls``; the
branches with a non-zero weight are kept. The grid is refined around them
(midpoints to the neighbours) and the problem solved again, ``refine`` times.

The default grid mixes a geometric grid from the resolution of the data to
the largest excursion of x with points placed where the virgin curve bends
most (Whiteman 1959: along the virgin loading from x = 0 the force of the
branches is sum_i k_i min(x, eta_i), so -F''(x) is the density of stiffness
at eta = x): quantiles of |F''| along the virgin branch, where the data has
one (the first monotone stretch from x near 0 covers at least a fifth of the
largest excursion).

Needs scipy (the ``[fit]`` extra).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .kernels.drive import play_basis


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

    @property
    def relative_rms(self) -> float:
        return self.residual_rms / self.force_range

    @property
    def relative_max(self) -> float:
        return self.residual_max / self.force_range

    def report(self) -> str:
        return (f"{len(self.k)} branches kept of {self.grid_size} candidates; k0 = {self.k0:.6g}"
                + (f", k3 = {self.k3:.6g}" if self.effects.get("cubic") else "")
                + (f", c = {self.c:.6g}" if self.effects.get("dashpot") else "")
                + f"; residual RMS {self.residual_rms:.3g} N ({100 * self.relative_rms:.3g} % of the force range "
                f"{self.force_range:.3g} N), max {self.residual_max:.3g} N ({100 * self.relative_max:.3g} %)")

    def scene_text(self, name: str, time: Optional[np.ndarray] = None) -> str:
        """A scene in the contract's format: the connector ([fmu] causality = "displacement"); add [mass] and
        a [load] (and drop the [fmu] table) for an element with its mass."""
        lines = [f"# Fitted by prandtl-fmu fit: {self.report()}",
                 "# The connector (displacement in, force out). For the element with its mass under a force, add",
                 "# [mass] and [load] tables and remove [fmu].",
                 f"name = {_toml_string(name)}", ""]
        if self.k0 > 0:
            lines += ["[spring]", f"k0 = {self.k0!r}", ""]
        if self.effects.get("cubic") and self.k3 > 0:
            lines += ["[cubic]", f"k3 = {self.k3!r}", ""]
        if self.effects.get("dashpot") and self.c > 0:
            lines += ["[damper]", f"c = {self.c!r}", ""]
        if len(self.k):
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


def check_data(x, force, time=None, v=None):
    """The arrays as float, or FitError naming what is wrong (one line)."""
    arrays = {"x": x, "force": force}
    if time is not None:
        arrays["time"] = time
    if v is not None:
        arrays["v"] = v
    checked = {}
    for name, values in arrays.items():
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

    data = check_data(x, force, time, v)
    xs, fs = data["x"], data["force"]
    if dashpot:
        if "v" in data:
            vs = data["v"]
        elif "time" in data:
            vs = np.gradient(xs, data["time"])
        else:
            raise FitError("--dashpot needs the velocity or the time column")
    smooth = [xs] + ([xs ** 3] if cubic else []) + ([vs] if dashpot else [])
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
    fitted = columns @ weights
    residual = fs - fitted
    smooth_weights = list(weights[:len(smooth)])
    k0 = smooth_weights.pop(0)
    k3 = smooth_weights.pop(0) if cubic else 0.0
    c = smooth_weights.pop(0) if dashpot else 0.0
    kept = weights[len(smooth):] > 1e-12 * max(weights[len(smooth):].max(initial=0.0), 1e-300)
    return Fit(k0=float(k0), k3=float(k3), c=float(c), k=weights[len(smooth):][kept], eta=grid[kept],
               fitted=fitted, residual_rms=float(np.sqrt(np.mean(residual ** 2))),
               residual_max=float(np.abs(residual).max()), force_range=float(np.ptp(fs)) or 1.0,
               grid_size=int(grid.size), effects={"cubic": cubic, "dashpot": dashpot})


def _solve(nnls, xs, fs, smooth, grid):
    basis = np.empty((xs.shape[0], grid.shape[0]))
    play_basis(xs, grid, basis)
    columns = np.column_stack(smooth + [basis])
    scale = np.sqrt(np.sum(columns ** 2, axis=0))
    scale[scale == 0] = 1.0
    weights, _ = nnls(columns / scale, fs, maxiter=50 * columns.shape[1])
    return weights / scale, columns


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
    """The named columns of a CSV file with a header; FitError for a missing file, column or bad value."""
    import csv

    try:
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    except OSError as exc:
        raise FitError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise FitError(f"{path}: not a CSV text file ({exc.__class__.__name__})") from None
    if not rows:
        raise FitError(f"{path}: empty")
    header = [name.strip() for name in rows[0]]
    wanted = {"x": x, "force": force}
    if time is not None:
        wanted["time"] = time
    if v is not None:
        wanted["v"] = v
    index = {}
    for role, name in wanted.items():
        if name not in header:
            raise FitError(f"{path}: no column {name!r} (columns: {', '.join(header)}); name it with --{role}")
        index[role] = header.index(name)
    columns = {role: [] for role in wanted}
    for number, row in enumerate(rows[1:], start=2):
        if not row or all(not cell.strip() for cell in row):
            continue
        for role, position in index.items():
            try:
                columns[role].append(float(row[position]))
            except (IndexError, ValueError):
                cell = row[position] if position < len(row) else "(missing)"
                raise FitError(f"{path}: line {number}, column {wanted[role]!r}: not a number: {cell!r}") from None
    return {role: np.array(values) for role, values in columns.items()}


def plot_fit(path, x, force, fit_result: Fit, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (loop, error) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    loop.plot(x, force, lw=1.6, color="0.6", label="measured")
    loop.plot(x, fit_result.fitted, lw=0.8, color="C3", label=f"fitted ({len(fit_result.k)} branches)")
    loop.set(xlabel="x (m)", ylabel="force (N)", title=title)
    loop.legend()
    error.plot(np.arange(len(x)), force - fit_result.fitted, lw=0.6)
    error.set(xlabel="sample", ylabel="measured - fitted (N)",
              title=f"residual: RMS {100 * fit_result.relative_rms:.2g} % of the range")
    for ax in (loop, error):
        ax.grid(alpha=0.3)
    fig.savefig(path, dpi=120)
    plt.close(fig)


