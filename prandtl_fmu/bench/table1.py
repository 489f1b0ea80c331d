"""The paper's Table 1 with the paper's own protocol, and the search for its convention:
``prandtl-fmu bench --table1 --protocol paper|search|quick --out DIR [--resume] [--workers N | --scheduler ADDR]``.

Bastien & Schatzman (M2AN 2002), section 8: the scene of :mod:`.paper` with n in {3, 10, 100, 700, 1500}, T = 500,
scheme (5.1) (the ``projected`` stepper) from U^0 = u_0 (5.2);

    eps(h) = || u_h - u_{h/2} ||_{C^0([0, T], l^q_{n+2})},    log eps = alpha log h + log(2 C)      (fit, r)

The paper fitted in base 10, log10 eps = alpha log10 h + b10, and printed C = exp(b10) / 2 (``printed_c``:
(2 C)^(1 / ln 10) / 2 of the true C); alpha and r do not depend on the base.

over h_j = h_min^((R - j) / R) h_max^(j / R), j = 0..R, with R = 99, h_min = 1e-6, h_max = 1e-2 (``PROTOCOLS``).
u = (x, y, u_1..u_n), u_h the piecewise-linear interpolant of the nodes, so the C^0 norm is the max over every node
of the fine run (``bench/lockstep.py``). Each (n, h) is one lockstep run of h and h/2 on the memory stack
(cost per node: the stack's depth, not n), written to DIR/runs/ as it finishes (``--resume`` skips those); the
runs go to dask.distributed when it is installed (the ``sweep`` extra), else one after the other.

Each run keeps, for the kinds of node (coarse nodes; fine nodes against the linear interpolant; fine nodes
against the coarse value held over its step, except in the paper protocol), the maxima over [0, T] of the
components of the difference (``bench/lockstep.MEASURES``). From them, without another run:

* ``DIR/table1_paper.csv`` (``table1_<protocol>.csv`` for the others; q, n, alpha, C, r, C_true, then the
  paper's values and how many h were done): the paper's definition read literally: plain l^q over the n + 2
  components, max over the interpolants, factor 2 C; C in the paper's printed convention, C_true the constant
  of eps ~ 2 C h^alpha;
* ``DIR/table1_alpha_checks_<protocol>.csv`` and ``DIR/table1_ranges_<protocol>.csv``: what the runs say about
  the rows whose alpha is not the printed one (``alpha_checks``: coarse nodes, the slope at both ends of the
  grid, the ranges of h that reproduce each row and the whole table, the horizon);
* ``DIR/table1_candidates_<protocol>.csv``: every convention of the search (``NORMS`` x ``TIMES`` x
  ``FACTORS`` x h ranges), each with its (q, n) rows and ratio to the printed C; :func:`merge` gathers those of
  several protocols into one table, a row per convention (docs/bench/table1_candidates.csv);
* ``DIR/table1_eps.png``: eps(h) against h beside the paper's line;
* ``DIR/figure3.png`` .. ``figure5.png``: the paper's figures 3-5, the loops {x(t), F(t) - m x''(t)} over
  400 <= t <= 500 with N = 10^6 (h = 5e-4).
"""
from __future__ import annotations

import csv
import glob
import json
import math
import os
import sys
import time
from dataclasses import dataclass

import numpy as np

from .paper import PAPER_CORRELATION, PAPER_FIGURE_STEPS, PAPER_GRID, PAPER_NS, PAPER_T, PAPER_TABLE_1, paper_scene

LOOP_WINDOW = (400.0, PAPER_T)  # s: the figures' time window
LOOP_STEP = PAPER_T / PAPER_FIGURE_STEPS  # s: N = 10^6 steps over T = 500
FIGURES = {"figure3": (3, 10), "figure4": (100, 700), "figure5": (1500,)}
CHUNK_STEPS = 4_000_000  # coarse steps per kernel call: the progress bar and Ctrl-C act between calls


@dataclass(frozen=True)
class Protocol:
    """The h grid h_j = h_min^((R - j)/R) h_max^(j/R), j = 0..R, the horizon T (s), the n, the stepper."""

    name: str
    h_min: float
    h_max: float
    R: int
    T: float
    ns: tuple
    stepper: str = "projected"
    theta: float = 0.0  # a step from t_p sees the load at t_p + theta h (bench/lockstep.py)
    held: bool = True  # also measure against the coarse run held over its step (a candidate; costs a third more)

    def steps(self):
        """The h_j (s), j = 0..R."""
        j = np.arange(self.R + 1)
        return self.h_min ** ((self.R - j) / self.R) * self.h_max ** (j / self.R)

    def manifest(self) -> dict:
        return dict(name=self.name, h_min=self.h_min, h_max=self.h_max, R=self.R, T=self.T, ns=list(self.ns),
                    stepper=self.stepper, theta=self.theta, held=self.held)

    def work(self, h: float) -> float:
        """Steps of one lockstep run at h: N at h and 2 N at h/2, N = round(T / h)."""
        return 3.0 * round(self.T / h)


PROTOCOLS = {
    "paper": Protocol("paper", PAPER_GRID["h_min"], PAPER_GRID["h_max"], PAPER_GRID["R"], PAPER_T, PAPER_NS,
                      held=False),
    # the convention search: the full T and the paper's n, 12 values of h down to 1e-4 (fits over its two halves
    # show how much the range moves C: a few per cent)
    "search": Protocol("search", 1e-4, 1e-2, 11, PAPER_T, PAPER_NS),
    # the scheme's candidates: the load at t_{p+1} (the g(t_{p+1}) of (1.12)), at the middle of the step, and
    # the symplectic Euler (x and u with the old velocity, y with the new forces)
    "search-theta1": Protocol("search-theta1", 1e-4, 1e-2, 11, PAPER_T, PAPER_NS, theta=1.0),
    "search-theta05": Protocol("search-theta05", 1e-4, 1e-2, 11, PAPER_T, PAPER_NS, theta=0.5),
    "search-symplectic": Protocol("search-symplectic", 1e-4, 1e-2, 11, PAPER_T, PAPER_NS, "symplectic"),
    # the horizon's candidates: the max over [0, T] with a shorter T (n = 3 and 10 reach their largest error
    # in the first period, n >= 100 later)
    "search-T8": Protocol("search-T8", 1e-4, 1e-2, 11, 8.0, PAPER_NS),
    "search-T50": Protocol("search-T50", 1e-4, 1e-2, 11, 50.0, PAPER_NS),
    "quick": Protocol("quick", 1e-3, 1e-2, 5, 20.0, (3, 10, 100)),
}

# the norms of the search: (q, name) -> how a norm over time comes from a run's maxima (bench/lockstep.MEASURES)
NORMS = {
    ("inf", "plain"): ("x", "v", "u_max"),          # l^inf over (x, y, u_1..u_n): the paper's definition
    ("inf", "u"): ("u_max",),                       # the elongations only
    ("inf", "vu"): ("v", "u_max"),                  # (y, u): f's first component is 0 in (7.8)-(7.11) as printed
    ("inf", "slider"): ("x", "v", "w_max"),         # (x, y, w) with the sliders' displacements w_i = x - u_i
    ("inf", "xnew"): ("x_new", "v", "u_max"),     # x^{p+1} = x^p + h y^{p+1} (same y, u: k0 = 0)
    ("inf", "xtrap"): ("x_trap", "v", "u_max"),   # x^{p+1} = x^p + h (y^p + y^{p+1}) / 2
    ("inf", "x"): ("x",),
    ("inf", "v"): ("v",),
    ("2", "plain"): ("l2",),                        # l^2 over (x, y, u_1..u_n): the paper's definition
    ("2", "u"): ("l2_u",),
    ("2", "vu"): ("l2_vu",),
    ("2", "slider"): ("l2_slider",),
    ("2", "energy"): ("l2_energy",),                # sqrt(k0 x^2 + m y^2 + sum k_i u_i^2): (7.11)'s scalar product
    ("2", "mean"): ("l2_mean",),                    # sqrt(x^2 + y^2 + sum u_i^2 / n): the 1/n of (7.19)
    ("2", "xv"): ("l2_xv",),
}
TIMES = {  # which nodes the max over [0, T] runs over (bench/lockstep.KINDS)
    "interpolants": ("coarse", "linear"),  # every fine node, the coarse run interpolated: the C^0 norm of (8.2)
    "coarse": ("coarse",),                 # the coarse nodes only
    "held": ("coarse", "held"),            # piecewise-constant u_h (the v_h of section 2)
}
FACTORS = {  # C from the fit's intercept b = log eps - alpha log h
    "2C": lambda b, alpha: math.exp(b) / 2.0,                      # log(2C), as printed
    "C": lambda b, alpha: math.exp(b),
    "C/2": lambda b, alpha: 2.0 * math.exp(b),
    "2C-fine": lambda b, alpha: math.exp(b) * 2.0 ** alpha / 2.0,  # log eps = alpha log(h/2) + log(2C)
}
PAPER = dict(norm="plain", time="interpolants", factor="2C")


class Table1Error(ValueError):
    """A refused option or folder: one line for the command line."""


# ------------------------------------------------ one (n, h): the lockstep run

def lockstep_run(scene, h: float, stepper: str = "projected", steps=None, progress=None, theta: float = 0.0,
                 held: bool = True) -> dict:
    """Run ``scene`` at h and h/2 in lockstep (``bench/lockstep.py``) over ``steps`` coarse steps (default
    round(T / h)) and return the maxima of the difference: ``{"maxima": {kind: {measure: value}}, "when":
    ..., "seconds": ..., "steps": ...}``. ValueError if the scene does not fit (the memory stack, no memory
    effects, no noise, a mass); RuntimeError if a state stops being finite."""
    from ..compiled import compile_model
    from ..kernels import stack
    from . import lockstep as kernels
    from ..memory import has_memory
    from ..stepping import initial_state

    if scene.mass is None or scene.branches is None or scene.branches.continuum:
        raise ValueError("the lockstep needs a mass and n branches")
    if scene.load.noise is not None:
        raise ValueError("the lockstep needs a deterministic load")
    model = compile_model(scene, "stack")
    if has_memory(model[8]) or model[7] is not None:
        raise ValueError("the lockstep runs the mass and the branches only: no memory effects, no friction")
    load = scene.load.compile()
    x0, v0, u = initial_state(scene, model, load)
    params = model[4]
    states = np.zeros((3, u.shape[0]))
    states[kernels.NEW] = u
    states[kernels.FINE] = u
    states[kernels.OLD] = u
    plain = kernels.plain_sums(params)
    with_c = bool(np.any(params[stack.C_ROW] != 0.0))
    total = round(scene.solver.stop_time / h) if steps is None else int(steps)
    maxima = np.zeros((len(kernels.KINDS), kernels.COUNT))
    when = np.zeros_like(maxima)
    state = np.array([x0, v0, x0, v0], dtype=float)
    loop = kernels.LOCKSTEPS[stepper]
    started = time.perf_counter()
    done = 0
    while done < total:
        count = min(CHUNK_STEPS, total - done)
        taken = loop(model, load, plain, with_c, states, float(h), float(theta), held, done, count, maxima, when,
                     state)
        if taken < count:
            raise RuntimeError(f"lockstep at h = {h!r}: the state stopped being finite (or the stack broke) near "
                               f"t = {(done + taken) * h:.6g} s")
        done += count
        if progress is not None:
            progress(count)
    seconds = time.perf_counter() - started
    kinds = [kind for kind in kernels.KINDS if held or kind != "held"]
    return dict(maxima={kind: dict(zip(kernels.MEASURES, maxima[i].tolist())) for i, kind in enumerate(kernels.KINDS)
                        if kind in kinds},
                when={kind: dict(zip(kernels.MEASURES, when[i].tolist())) for i, kind in enumerate(kernels.KINDS)
                      if kind in kinds},
                seconds=seconds, steps=total)


def measure_task(n: int, j: int, h: float, T: float, stepper: str, theta: float = 0.0, held: bool = True,
                 progress=None) -> dict:
    """One (n, h_j) of a protocol: the record written to DIR/runs/ (a dask task: plain arguments, plain result).
    ``progress(coarse_steps)`` is called after each chunk (in-process runs only)."""
    record = lockstep_run(paper_scene(n, T), h, stepper, progress=progress, theta=theta, held=held)
    record.update(n=n, j=j, h=h, T=T, stepper=stepper, theta=theta)
    return record


# ------------------------------------------------ the folder: one JSON per finished (n, h)

def _run_path(folder, n, j):
    return os.path.join(folder, "runs", f"n{n:05d}-j{j:03d}.json")


def open_folder(folder: str, protocol: Protocol, resume: bool) -> dict:
    """The finished runs of ``protocol`` in ``folder`` ({(n, j): record}), after checking the folder: Table1Error
    if it holds runs of another protocol, or runs without ``resume``."""
    manifest_path = os.path.join(folder, "runs", "protocol.json")
    existing = sorted(glob.glob(os.path.join(folder, "runs", "n*-j*.json")))
    if os.path.exists(manifest_path):
        with open(manifest_path) as fh:
            manifest = json.load(fh)
        if manifest != protocol.manifest():
            raise Table1Error(f"{folder}: holds the runs of protocol {manifest.get('name')!r}, not "
                              f"{protocol.name!r} (another --out)")
        if existing and not resume:
            raise Table1Error(f"{folder}: already holds {len(existing)} runs: --resume continues them, or "
                              "choose another --out")
    elif existing:
        raise Table1Error(f"{folder}/runs: runs without a protocol.json: not a folder of this command")
    os.makedirs(os.path.join(folder, "runs"), exist_ok=True)
    for stale in glob.glob(os.path.join(folder, "runs", "*.partial")):  # a run stopped while being written
        os.remove(stale)
    with open(manifest_path, "w") as fh:
        json.dump(protocol.manifest(), fh)
    done = {}
    for path in existing:
        with open(path) as fh:
            record = json.load(fh)
        done[(record["n"], record["j"])] = record
    return done


def _write_run(folder, record):
    path = _run_path(folder, record["n"], record["j"])
    partial = path + ".partial"
    with open(partial, "w") as fh:
        json.dump(record, fh)
    os.replace(partial, path)  # a run is in the folder whole or not at all


# ------------------------------------------------ the fit and the tables

def fit(hs, eps):
    """(alpha, b, r) of the least-squares line log eps = alpha log h + b and the correlation r of the points."""
    x, y = np.log(np.asarray(hs, dtype=float)), np.log(np.asarray(eps, dtype=float))
    alpha, b = np.polyfit(x, y, 1)
    r = float(np.corrcoef(x, y)[0, 1]) if len(x) > 2 else float("nan")
    return float(alpha), float(b), r


def eps_of(record, q, norm, time_norm):
    """eps(h) of one run under a convention (``NORMS``, ``TIMES``)."""
    maxima = record["maxima"]
    measures = NORMS[(q, norm)]
    return max(maxima[kind][measure] for kind in TIMES[time_norm] for measure in measures)


def when_of(record, q, norm, time_norm):
    """The time (s) at which eps(h) of one run (``eps_of``) reaches its max over [0, T]."""
    places = [(kind, measure) for kind in TIMES[time_norm] for measure in NORMS[(q, norm)]]
    kind, measure = max(places, key=lambda place: record["maxima"][place[0]][place[1]])
    return record["when"][kind][measure]


def table(records, protocol: Protocol, q, norm, time_norm, factor, h_range=None):
    """Rows {q, n, alpha, C, r, ...} of one convention over the finished runs (``h_range``: (lo, hi) to fit over
    the runs with lo <= h <= hi only)."""
    rows = []
    for n in protocol.ns:
        chosen = sorted((r for r in records.values() if r["n"] == n
                         and (h_range is None or h_range[0] * (1 - 1e-9) <= r["h"] <= h_range[1] * (1 + 1e-9))),
                        key=lambda r: r["h"])
        if len(chosen) < 2:
            continue
        hs = [r["h"] for r in chosen]
        eps = [eps_of(r, q, norm, time_norm) for r in chosen]
        if not all(e > 0 and math.isfinite(e) for e in eps):
            raise RuntimeError(f"n = {n}: eps(h) not positive and finite: {eps}")
        alpha, b, r = fit(hs, eps)
        paper_alpha, paper_c = PAPER_TABLE_1.get((q, n), (math.nan, math.nan))
        rows.append(dict(q=q, n=n, alpha=alpha, C=FACTORS[factor](b, alpha), r=r, paper_alpha=paper_alpha,
                         paper_C=paper_c, paper_r=PAPER_CORRELATION.get((q, n), math.nan), h_count=len(chosen),
                         h_min=hs[0], h_max=hs[-1]))
    return rows


def printed_c(c_true: float) -> float:
    """The C the paper prints for the true constant ``c_true`` of eps ~ 2 C h^alpha: its fit is base 10,
    log10 eps = alpha log10 h + b10, and it prints exp(b10) / 2, so C_printed = (2 C_true)^(1 / ln 10) / 2."""
    return (2.0 * c_true) ** (1.0 / math.log(10.0)) / 2.0


def true_c(c_printed: float) -> float:
    """The inverse of :func:`printed_c`: eps ~ 2 C h^alpha with C = (2 C_printed)^(ln 10) / 2."""
    return (2.0 * c_printed) ** math.log(10.0) / 2.0


def paper_rows(records, protocol: Protocol):
    """The table of the paper's definition (``PAPER``) for q = inf then 2, with how complete the h grid is:
    C in the paper's printed convention (:func:`printed_c`), C_true the constant of eps ~ 2 C h^alpha."""
    rows = []
    for q in ("inf", "2"):
        for row in table(records, protocol, q, PAPER["norm"], PAPER["time"], PAPER["factor"]):
            row.update(C=printed_c(row["C"]), C_true=row["C"], h_total=protocol.R + 1,
                       complete=row["h_count"] == protocol.R + 1, T=protocol.T, protocol=protocol.name,
                       stepper=protocol.stepper)
            rows.append(row)
    return rows


def matches_printed(value: float, printed: float, decimals: int) -> str:
    """How ``value`` gives the ``printed`` number with ``decimals`` decimals: "truncated", "rounded", "both" or ""
    (neither: it leaves the printed digits)."""
    target = round(printed * 10 ** decimals)
    ways = [name for name, digits in (("truncated", math.floor(value * 10 ** decimals)),
                                      ("rounded", round(value * 10 ** decimals))) if digits == target]
    return "both" if len(ways) == 2 else "".join(ways)


PRINTED_DECIMALS = dict(alpha=5, C=5, r=6)  # Table 1 prints alpha and C with 5 decimals, r with 6


def _line_fits(x, y, lo, hi):
    """alpha, b, r of the least-squares line over x[lo:hi], y[lo:hi] for arrays of (lo, hi), from prefix sums."""
    sums = [np.concatenate(([0.0], np.cumsum(v))) for v in (np.ones_like(x), x, y, x * x, x * y, y * y)]
    k, sx, sy, sxx, sxy, syy = (s[hi] - s[lo] for s in sums)
    vxx, vxy, vyy = sxx - sx * sx / k, sxy - sx * sy / k, syy - sy * sy / k
    alpha = vxy / vxx
    return alpha, (sy - alpha * sx) / k, vxy / np.sqrt(vxx * vyy)


def alpha_checks(records, protocol: Protocol, shortest: int = 20):
    """What the stored runs say about the rows whose alpha leaves the printed one: for each (q, n) of the paper's
    definition, with C in the printed convention,

    * ``alpha``, ``C``, ``r`` over every h, and how each gives the printed digits (``matches_printed``);
    * ``alpha_coarse``, ``C_coarse``: the max over the coarse nodes only (not the interpolants);
    * ``alpha_small``, ``alpha_large``: the slope over the ``shortest`` smallest and largest h (the curvature of
      eps(h): the fit's alpha is a property of its range);
    * ``windows``: how many ranges of consecutive h (at least ``shortest`` of them) reproduce alpha, C and r to
      the printed digits, and the widest (``window_h_min``, ``window_h_max``);
    * ``latest_max_t``: the latest time (s) at which an eps(h) of the row reaches its max over [0, T]: a shorter
      horizon leaves every eps(h) as it is down to that time, and the runs cannot say what it does below.

    Returns (rows, common): ``common`` lists, for every range of consecutive h, the rows it reproduces, the ranges
    that reproduce the most rows first (one range for the whole table: no range is fitted to one row)."""
    rows, matched = [], {}
    for q in ("inf", "2"):
        for n in protocol.ns:
            chosen = sorted((r for r in records.values() if r["n"] == n), key=lambda r: r["h"])
            if len(chosen) < max(shortest, 2):
                continue
            x = np.log([r["h"] for r in chosen])
            y = np.log([eps_of(r, q, PAPER["norm"], PAPER["time"]) for r in chosen])
            coarse = np.log([eps_of(r, q, PAPER["norm"], "coarse") for r in chosen])
            paper_alpha, paper_c = PAPER_TABLE_1.get((q, n), (math.nan, math.nan))
            paper_r = PAPER_CORRELATION.get((q, n), math.nan)
            count = len(x)
            lo, hi = (a.ravel() for a in np.meshgrid(np.arange(count + 1), np.arange(count + 1), indexing="ij"))
            keep = hi - lo >= shortest
            lo, hi = lo[keep], hi[keep]
            alphas, bs, rs = _line_fits(x, y, lo, hi)
            cs = np.array([printed_c(math.exp(b) / 2.0) for b in bs])
            good = np.array([all(matches_printed(v, p, PRINTED_DECIMALS[name]) for name, v, p in
                                 (("alpha", a, paper_alpha), ("C", c, paper_c), ("r", r, paper_r)))
                             for a, c, r in zip(alphas, cs, rs)])
            for a, b in zip(lo[good], hi[good]):
                matched.setdefault((int(a), int(b)), []).append((q, n))
            alpha, b, r = fit(np.exp(x), np.exp(y))
            alpha_coarse, b_coarse, _ = fit(np.exp(x), np.exp(coarse))
            c = printed_c(math.exp(b) / 2.0)
            widest = int(np.argmax(np.where(good, hi - lo, -1))) if good.any() else None
            rows.append(dict(
                q=q, n=n, alpha=alpha, C=c, r=r, paper_alpha=paper_alpha, paper_C=paper_c, paper_r=paper_r,
                alpha_digits=matches_printed(alpha, paper_alpha, 5), C_digits=matches_printed(c, paper_c, 5),
                r_digits=matches_printed(r, paper_r, 6), C_ratio=c / paper_c,
                alpha_coarse=alpha_coarse, C_coarse=printed_c(math.exp(b_coarse) / 2.0),
                alpha_small=fit(np.exp(x[:shortest]), np.exp(y[:shortest]))[0],
                alpha_large=fit(np.exp(x[-shortest:]), np.exp(y[-shortest:]))[0],
                windows=int(good.sum()),
                window_h_min=math.exp(x[lo[widest]]) if widest is not None else math.nan,
                window_h_max=math.exp(x[hi[widest] - 1]) if widest is not None else math.nan,
                latest_max_t=max(when_of(r, q, PAPER["norm"], PAPER["time"]) for r in chosen)))
    hs = sorted({r["h"] for r in records.values()})
    common = sorted(({"h_min": hs[a], "h_max": hs[b - 1], "h_count": b - a, "rows": len(which),
                      "which": " ".join(f"{q}/{n}" for q, n in which)} for (a, b), which in matched.items()),
                    key=lambda c: (-c["rows"], -c["h_count"]))
    return rows, common


def horizon_ratios(records, protocol: Protocol, ns, js, horizons):
    """eps(h_j) over [0, T'] divided by eps(h_j) over [0, T] (the stored run), for q = inf and 2, each n in ``ns``,
    j in ``js`` and T' in ``horizons``: how much a shorter horizon could lower eps (new lockstep runs of T' / h_j
    steps). Returns rows {n, j, h, horizon, ratio_inf, ratio_2}."""
    rows = []
    for n in ns:
        for j in js:
            stored = records[(n, j)]
            for horizon in horizons:
                run = lockstep_run(paper_scene(n, protocol.T), stored["h"], protocol.stepper,
                                   steps=round(horizon / stored["h"]), theta=protocol.theta, held=False)
                run.update(h=stored["h"])
                rows.append(dict(n=n, j=j, h=stored["h"], horizon=horizon,
                                 **{f"ratio_{q}": eps_of(run, q, PAPER["norm"], PAPER["time"])
                                    / eps_of(stored, q, PAPER["norm"], PAPER["time"]) for q in ("inf", "2")}))
    return rows


def load_runs(folder: str) -> dict:
    """The runs of a runs folder ({(n, j): record}), read only (``docs/bench/table1_paper_runs``)."""
    done = {}
    for path in sorted(glob.glob(os.path.join(folder, "n*-j*.json"))):
        with open(path) as fh:
            record = json.load(fh)
        done[(record["n"], record["j"])] = record
    return done


def h_ranges(protocol: Protocol):
    """The h ranges of the search: the whole grid, and its upper and lower halves (h >= or <= the middle
    value), to show whether the range moves C."""
    hs = protocol.steps()
    middle = float(hs[len(hs) // 2])
    return {"all": None, "upper": (middle, float(hs[-1])), "lower": (float(hs[0]), middle)}


def candidate_rows(records, protocol: Protocol):
    """Every convention of the search: one row per (convention, q, n), with the convention's worst ratio to the
    printed C (over the n it has) repeated on its rows."""
    rows = []
    measured = set.intersection(*(set(r["maxima"]) for r in records.values())) if records else set()
    for (q, norm) in NORMS:
        for time_norm in [name for name, kinds in TIMES.items() if set(kinds) <= measured]:
            for factor in FACTORS:
                for range_name, h_range in h_ranges(protocol).items():
                    part = table(records, protocol, q, norm, time_norm, factor, h_range)
                    ratios = [row["C"] / row["paper_C"] for row in part if math.isfinite(row["paper_C"])]
                    worst = max((abs(math.log(ratio)) for ratio in ratios), default=math.nan)
                    for row in part:
                        row.update(norm=norm, time=time_norm, factor=factor, h_range=range_name,
                                   stepper=protocol.stepper, theta=protocol.theta, ratio=row["C"] / row["paper_C"],
                                   worst_ratio=math.exp(worst))
                        rows.append(row)
    return rows


def merge(folders, out: str, rows_too: bool = False):
    """Gather the candidate tables of several protocol folders into ``out``/table1_candidates.csv: one row per
    convention (protocol, norm, time, factor, h range) and q, its C for each n beside the printed ones, its worst
    ratio to them (max over n of max(C / C_paper, C_paper / C)), the range of its alpha and its smallest r; sorted
    by q and that ratio. ``rows_too``: also ``out``/table1_candidate_rows.csv, one row per convention, q and n
    (several MB). Returns the convention rows."""
    rows = []
    for folder in folders:
        with open(os.path.join(folder, "runs", "protocol.json")) as fh:
            name = json.load(fh)["name"]
        with open(os.path.join(folder, f"table1_candidates_{name}.csv"), newline="") as fh:
            for row in csv.DictReader(fh):
                row["protocol"] = name
                rows.append(row)
    if rows_too:
        _write_csv(os.path.join(out, "table1_candidate_rows.csv"), rows,
                   ("protocol", "norm", "time", "factor", "h_range", "q", "n", "alpha", "C", "r", "paper_C", "ratio"))
    groups = {}
    for row in rows:
        key = (row["protocol"], row["norm"], row["time"], row["factor"], row["h_range"], row["q"])
        groups.setdefault(key, {})[int(row["n"])] = row
    conventions = []
    for key, by_n in groups.items():
        convention = dict(zip(("protocol", "norm", "time", "factor", "h_range", "q"), key))
        ratios = [float(row["ratio"]) for row in by_n.values() if math.isfinite(float(row["ratio"]))]
        convention["worst_ratio"] = _digits(math.exp(max((abs(math.log(r)) for r in ratios), default=math.nan)))
        for n in PAPER_NS:
            convention[f"C_{n}"] = _digits(float(by_n[n]["C"])) if n in by_n else math.nan
        for n in PAPER_NS:
            convention[f"paper_C_{n}"] = PAPER_TABLE_1[(key[5], n)][1]
        alphas = [float(row["alpha"]) for row in by_n.values()]
        convention["alpha_min"], convention["alpha_max"] = _digits(min(alphas)), _digits(max(alphas))
        convention["r_min"] = _digits(min(float(row["r"]) for row in by_n.values()))
        conventions.append(convention)
    conventions.sort(key=lambda c: (c["q"] != "inf", c["worst_ratio"]))
    _write_csv(os.path.join(out, "table1_candidates.csv"), conventions,
               ("q", "worst_ratio", "protocol", "norm", "time", "factor", "h_range"))
    return conventions


def _digits(value, digits=6):
    """``value`` rounded to ``digits`` significant digits (a table for people)."""
    return float(f"{value:.{digits}g}") if math.isfinite(value) else value


def _write_csv(path, rows, first):
    fields = list(first) + [f for f in (rows[0] if rows else {}) if f not in first]
    partial = path + ".partial"
    with open(partial, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=fields)
        writer.writeheader()
        for row in rows:
            writer.writerow({f: row.get(f, "") for f in fields})
    os.replace(partial, path)


# ------------------------------------------------ the figures 3-5

def loops(n: int, h: float = LOOP_STEP, window=LOOP_WINDOW):
    """(x, reaction) over ``window`` of the paper's scene with n branches, scheme (5.1) with step h: the
    reaction F - m x'' = k0 x + sum_i k_i u_i (N), every 0.01 s."""
    from ..driver import simulate

    scene = paper_scene(n, window[1]).with_solver(step=h, output_interval=0.01)
    result = simulate(scene, "projected", progress=False)
    inside = result.time >= window[0] - 1e-9
    return result.x[inside], result.reaction[inside]


def figures(folder: str):
    """Write ``figure3.png`` .. ``figure5.png`` into ``folder`` (the paper's figures 3-5); return their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    for name, ns in FIGURES.items():
        fig, axes = plt.subplots(1, len(ns), figsize=(5.2 * len(ns), 4.4), layout="constrained", squeeze=False)
        for ax, n, letter in zip(axes[0], ns, "ab"):
            x, reaction = loops(n)
            ax.plot(x, reaction, lw=0.8)
            label = f" ({letter})" if len(ns) > 1 else ""
            ax.set(xlabel="x (m)", ylabel="F - m x'' (N)", title=f"n = {n}{label}")
            ax.grid(alpha=0.3)
        fig.suptitle(f"{name.replace('figure', 'Figure ')} of the paper: {{x(t), F(t) - m x''(t)}}\n"
                     f"{LOOP_WINDOW[0]:g} <= t <= {LOOP_WINDOW[1]:g}, scheme (5.1), h = {LOOP_STEP:g} (N = 10^6)")
        path = os.path.join(folder, f"{name}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def figure_eps(folder: str, records, protocol: Protocol):
    """``table1_eps.png``: eps(h) of the paper's definition against h for every n (q = inf and 2), beside the line
    of the paper's Table 1, 2 C h^alpha with its printed C read in its convention (:func:`true_c`); return its
    path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6), layout="constrained")
    for ax, q in zip(axes, ("inf", "2")):
        for i, n in enumerate(protocol.ns):
            chosen = sorted((r for r in records.values() if r["n"] == n), key=lambda r: r["h"])
            if not chosen:
                continue
            hs = np.array([r["h"] for r in chosen])
            ax.loglog(hs, [eps_of(r, q, PAPER["norm"], PAPER["time"]) for r in chosen], "o", ms=3, color=f"C{i}",
                      label=f"n = {n}")
            alpha, c = PAPER_TABLE_1[(q, n)] if (q, n) in PAPER_TABLE_1 else (math.nan, math.nan)
            ax.loglog(hs, 2 * true_c(c) * hs ** alpha, "--", lw=0.8, color=f"C{i}")
        ax.set(xlabel="h (s)", ylabel=f"eps(h) = max_t |u_h - u_h/2|_{q}",
               title=f"q = {q}: measured (dots), the paper's Table 1 (dashed)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    path = os.path.join(folder, "table1_eps.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# ------------------------------------------------ the command

def _bar(total, label):
    if not (sys.stderr.isatty() and not os.environ.get("CI")):
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=label, unit="step", unit_scale=True, file=sys.stderr, leave=False)


def _client(scheduler, workers, owned):
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise Table1Error(f"--scheduler {scheduler}: cannot connect: {exc}") from None
        owned.append(client)
        return client
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
    owned.append(cluster)
    client = Client(cluster)
    owned.append(client)
    return client


def _has_dask():
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


def run(folder: str, protocol_name: str = "paper", resume: bool = False, workers=None, scheduler=None,
        ns=None, figures_too: bool = True, limit=None) -> dict:
    """Run ``protocol_name`` into ``folder`` (resumable), then write the tables (and the figures); return a
    summary. ``ns``: a subset of the protocol's n; ``limit``: at most this many new runs (then the tables are
    partial). Table1Error for a refused option or folder, before any run."""
    if protocol_name not in PROTOCOLS:
        raise Table1Error(f"--protocol {protocol_name}: unknown (one of {', '.join(PROTOCOLS)})")
    protocol = PROTOCOLS[protocol_name]
    if ns:
        unknown = [n for n in ns if n not in protocol.ns]
        if unknown:
            raise Table1Error(f"--n {unknown[0]}: not an n of protocol {protocol.name!r} "
                              f"({', '.join(map(str, protocol.ns))})")
    if workers is not None and workers < 1:
        raise Table1Error(f"--workers {workers}: needs at least 1")
    if limit is not None and limit < 0:
        raise Table1Error(f"--limit {limit}: needs at least 0")
    try:
        import matplotlib  # noqa: F401  (the figures and table1_eps.png, at the end of hours of runs)
    except ImportError:
        raise Table1Error("bench --table1 draws its figures with matplotlib: pip install \"prandtl_fmu[bench]\"") \
            from None
    dask = _has_dask()
    if (scheduler is not None or (workers or 1) > 1) and not dask:
        raise Table1Error("--workers/--scheduler need dask.distributed: pip install \"prandtl_fmu[sweep]\"")
    done = open_folder(folder, protocol, resume)
    hs = protocol.steps()
    todo = [(n, j, float(hs[j])) for j in range(protocol.R, -1, -1) for n in (ns or protocol.ns)
            if (n, j) not in done]
    if limit is not None:
        todo = todo[:limit]
    started = time.perf_counter()
    bar = _bar(sum(protocol.work(h) for _, _, h in todo), f"table 1 ({protocol.name})")
    pool = workers if workers is not None else os.cpu_count() or 1
    use_dask = dask and todo and (scheduler is not None or pool > 1)
    try:
        if use_dask:
            _run_dask(folder, protocol, todo, done, scheduler, pool, bar)
        else:
            advance = None if bar is None else (lambda coarse: bar.update(3 * coarse))  # h and twice h/2
            for n, j, h in todo:
                record = measure_task(n, j, h, protocol.T, protocol.stepper, protocol.theta, protocol.held,
                                      advance)
                _write_run(folder, record)
                done[(n, j)] = record
    finally:
        if bar is not None:
            bar.close()
    elapsed = time.perf_counter() - started
    return finish(folder, protocol, done, elapsed, len(todo), figures_too)


def _run_dask(folder, protocol, todo, done, scheduler, workers, bar):
    from distributed import as_completed

    owned = []
    try:
        client = _client(scheduler, workers, owned)
        futures = {client.submit(measure_task, n, j, h, protocol.T, protocol.stepper, protocol.theta, protocol.held,
                                 pure=False, key=f"prandtl-table1-{protocol.name}-{n}-{j}"): (n, j, h)
                   for n, j, h in todo}
        for future in as_completed(futures):
            n, j, h = futures[future]
            try:
                record = future.result()
            except Exception as exc:
                raise RuntimeError(f"table 1: the run n = {n}, h = {h!r} failed: {type(exc).__name__}: {exc}; "
                                   f"the finished runs are in {folder}/runs (--resume continues)") from exc
            _write_run(folder, record)
            done[(n, j)] = record
            if bar is not None:
                bar.update(protocol.work(h))
    finally:
        for thing in reversed(owned):
            thing.close()


def finish(folder, protocol, done, elapsed, new_runs, figures_too=True) -> dict:
    """Write the tables (and figures) from the finished runs; return a summary."""
    paper = paper_rows(done, protocol)
    name = "table1_paper.csv" if protocol.name == "paper" else f"table1_{protocol.name}.csv"
    _write_csv(os.path.join(folder, name), paper, ("q", "n", "alpha", "C", "r", "C_true"))
    checks, common = alpha_checks(done, protocol) if done else ([], [])
    _write_csv(os.path.join(folder, f"table1_alpha_checks_{protocol.name}.csv"), checks,
               ("q", "n", "alpha", "C", "r", "paper_alpha", "paper_C", "paper_r"))
    _write_csv(os.path.join(folder, f"table1_ranges_{protocol.name}.csv"), common,
               ("rows", "h_count", "h_min", "h_max", "which"))
    candidates = candidate_rows(done, protocol)
    _write_csv(os.path.join(folder, f"table1_candidates_{protocol.name}.csv"), candidates,
               ("norm", "time", "factor", "h_range", "q", "n", "alpha", "C", "r", "paper_C", "ratio"))
    paths = ([figure_eps(folder, done, protocol)] if done else []) + (figures(folder) if figures_too else [])
    run_seconds = sum(r["seconds"] for r in done.values())
    steps = sum(3 * r["steps"] for r in done.values())
    left = sum(protocol.work(h) for j, h in enumerate(protocol.steps()) for n in protocol.ns if (n, j) not in done)
    return dict(table=os.path.join(folder, name), rows=paper, runs=len(done), new_runs=new_runs,
                total_runs=(protocol.R + 1) * len(protocol.ns), elapsed=elapsed, run_seconds=run_seconds,
                steps=steps, steps_left=left, figures=paths)


def main(folder: str, protocol: str, resume: bool = False, workers=None, scheduler=None, ns=None,
         limit=None, figures_too=True) -> int:
    """The command: run, then print the table and how long it took. Exit 2 with one line for a refused option."""
    try:
        summary = run(folder, protocol, resume, workers, scheduler, ns, figures_too, limit)
    except Table1Error as exc:
        print(f"prandtl-fmu bench --table1: {exc}", file=sys.stderr)
        return 2
    rate = summary["steps"] / summary["run_seconds"] if summary["run_seconds"] > 0 else math.nan
    print("q,n,alpha,C,r,C_true,paper_alpha,paper_C,paper_r,h_count")
    for row in summary["rows"]:
        print(f"{row['q']},{row['n']},{row['alpha']:.7f},{row['C']:.7f},{row['r']:.8f},{row['C_true']:.5f},"
              f"{row['paper_alpha']},{row['paper_C']},{row['paper_r']},{row['h_count']}")
    status = "complete" if summary["runs"] == summary["total_runs"] else (
        f"PARTIAL: {summary['runs']} of {summary['total_runs']} (n, h) runs done; {summary['steps_left']:.3g} "
        f"steps left, about {summary['steps_left'] / rate / 3600:.3g} h at the measured rate on one worker")
    print(f"table 1 ({protocol}): {summary['new_runs']} runs in {summary['elapsed']:.1f} s wall; all runs: "
          f"{summary['steps']:.3g} steps in {summary['run_seconds']:.1f} s of run time ({rate:.3g} steps/s); "
          f"{status}; written: {summary['table']}" + (f", {', '.join(summary['figures'])}" if summary["figures"]
                                                      else ""), file=sys.stderr)
    return 0
