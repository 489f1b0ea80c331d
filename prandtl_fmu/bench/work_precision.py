"""What accuracy costs in time: ``python -m prandtl_fmu bench [--quick] [--out DIR]``.

Problem (``paper.py``): the paper's section 8 scene (m = 1, k0 = 0, k_i = 1/n, eta_i = 0.1 +
i/n, F = 0.45 cos(0.5 t)) with n = 10, 100, 1500 branches over T = 500 s
(``--quick``: n = 10, 100 over T = 20 s, under a minute). Reference: the
``exact`` stepper. Error: the sup over the output grid (every 0.1 s) of
|x - x_exact|. Seconds: CPU time of the simulation alone (compiled code
warmed up first), all methods measured in the same process.

Methods, each over a range of steps or tolerances:

* the library's steppers ``projected``, ``implicit``, ``symplectic``, ``verlet``
  (and ``exact``'s own cost);
* the FMU built by build_fmu.py, driven by FMPy with a communication step of
  0.1 s and the force sampled at the middle of each communication step
  (``fmu-verlet``, ``fmu-projected``: the stepper inside the FMU);
* what practitioners do instead: scipy ``solve_ivp`` (LSODA, Radau with a
  sparse analytic Jacobian) on the regularized model
  u_i' = v - (u_i - clip(u_i, -eta_i, eta_i)) / eps, eps and rtol swept
  (n <= 100 only: a dense LSODA Jacobian of size 1502^2 is out of reach).

Then the paper's Table 1: order alpha and constant C of eps(h) =
|u_h - u_{h/2}| (max norm and Euclidean norm over (x, v, u_1..u_n), max over
every node of the two runs, in lockstep: ``table1.py``) for n = 3, 10, 100,
700, 1500, fitted over h = 1e-2 / 2^j, j = 0..6 (each run at h and h/2). The
paper's own protocol: ``bench --table1 --protocol paper``.

Writes DIR/work_precision.csv (stepper,n,h,error,seconds,...), DIR/table1.csv,
DIR/work_precision.png, DIR/error_vs_h.png and DIR/report.md (the tables).
"""
from __future__ import annotations

import csv
import math
import os
import platform
import sys
import tempfile
import time

import numpy as np

from ..driver import simulate
from ..loads import force_at
from .paper import OUTPUT, PAPER_TABLE_1, paper_scene


def _timed(function):
    start = time.process_time()
    value = function()
    return value, time.process_time() - start


def _sweeps(quick: bool):
    if quick:
        first = [1e-2, 4e-3, 1e-3]
        return {"projected": first, "implicit": first, "symplectic": first, "verlet": [5e-2, 1e-2, 2e-3]}
    first = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4]
    return {"projected": first, "implicit": first, "symplectic": first,
            "verlet": [1e-1, 5e-2, 2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4]}


def library_rows(scene, reference, quick, bar):
    n = scene.branches.n
    rows = []
    for stepper, hs in _sweeps(quick).items():
        simulate(scene.with_solver(step=hs[-1], stop_time=1.0), stepper)  # compile
        for h in hs:
            result, seconds = _timed(lambda: simulate(scene.with_solver(step=h), stepper))
            error = np.abs(result.x - reference.x).max()
            rows.append(dict(stepper=stepper, n=n, h=h, error=error, seconds=seconds,
                             steps=round(scene.solver.stop_time / h)))
            bar.update(1)
    return rows


def fmu_rows(scene, reference, quick, folder, bar):
    """The FMU through FMPy: communication step 0.1 s, force sampled mid-step."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    from ..fmu.build import build_fmu

    path = os.path.join(folder, f"scene-{scene.branches.n}.toml")
    _write_scene(scene, path)
    fmu = build_fmu(path, os.path.join(folder, f"element-{scene.branches.n}.fmu"))
    md = read_model_description(fmu)
    unzipped = extract(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    load = scene.load.compile()
    rows = []
    hs = [1e-2, 1e-3] if quick else [2e-2, 1e-2, 5e-3, 1e-3]
    def open_slave(name, stepper, h):
        slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setString([vr["stepper"]], [stepper])
        slave.setReal([vr["step"]], [h])
        slave.setBoolean([vr["scene_load"]], [False])  # driven by F alone: the force sampled below is the load
        slave.exitInitializationMode()
        return slave

    for stepper in ("verlet", "projected"):
        for h in hs:
            warm = open_slave("warm-up", stepper, h)
            warm.doStep(0.0, OUTPUT)  # compile the kernels inside the FMU before timing
            warm.terminate()
            warm.freeInstance()
            slave = open_slave("bench", stepper, h)
            count = round(scene.solver.stop_time / OUTPUT)

            def drive():
                xs = np.empty(count + 1)
                xs[0] = slave.getReal([vr["x"]])[0]
                for k in range(count):
                    t = k * OUTPUT
                    slave.setReal([vr["F"]], [force_at(load, t + 0.5 * OUTPUT)])
                    slave.doStep(t, OUTPUT)
                    xs[k + 1] = slave.getReal([vr["x"]])[0]
                return xs

            xs, seconds = _timed(drive)
            slave.terminate()
            slave.freeInstance()
            rows.append(dict(stepper=f"fmu-{stepper}", n=scene.branches.n, h=h,
                             error=np.abs(xs - reference.x).max(), seconds=seconds,
                             steps=round(scene.solver.stop_time / h)))
            bar.update(1)
    return rows


def _write_scene(scene, path):
    b = scene.branches
    with open(path, "w") as fh:
        fh.write(f'name = "paper-n{b.n}"\n[mass]\nm = {scene.mass.m!r}\n[spring]\nk0 = 0.0\n'
                 f"[branches]\ncount = {b.n}\nk_total = 1.0\neta_range = [0.1, 1.1]\n"
                 f'[load]\nkind = "harmonic"\namplitude = 0.45\nomega = 0.5\n'
                 f'[solver]\nstepper = "projected"\nstep = 1e-3\nstop_time = {scene.solver.stop_time!r}\n'
                 f"output_interval = {OUTPUT!r}\n")


def scipy_rows(scene, reference, quick, bar):
    """solve_ivp on the regularized model, LSODA and Radau with an analytic Jacobian."""
    from scipy.integrate import solve_ivp
    from scipy.sparse import csc_matrix

    n = scene.branches.n
    k = scene.branches.stiffness
    eta = scene.branches.yield_displacement
    m = scene.mass.m
    k0 = scene.spring.k0 if scene.spring is not None else 0.0
    amplitude, omega = scene.load.amplitude, scene.load.omega
    times = reference.time
    rows = []
    epsilons = [1e-3] if quick else [1e-2, 1e-3, 1e-4]
    rtols = [1e-6] if quick else [1e-5, 1e-8]
    for method in ("LSODA", "Radau"):
        for eps in epsilons:
            def rhs(t, y, eps=eps):
                x, v, u = y[0], y[1], y[2:]
                out = np.empty_like(y)
                out[0] = v
                out[1] = (amplitude * np.cos(omega * t) - k0 * x - k @ u) / m
                out[2:] = v - (u - np.clip(u, -eta, eta)) / eps
                return out

            def jacobian(t, y, eps=eps, sparse=(method == "Radau")):
                u = y[2:]
                rows_, cols, values = [0, 1], [1, 0], [1.0, -k0 / m]
                rows_ += [1] * n
                cols += list(range(2, n + 2))
                values += list(-k / m)
                rows_ += list(range(2, n + 2))
                cols += [1] * n
                values += [1.0] * n
                outside = np.abs(u) > eta
                index = np.flatnonzero(outside) + 2
                rows_ += list(index)
                cols += list(index)
                values += [-1.0 / eps] * len(index)
                matrix = csc_matrix((values, (rows_, cols)), shape=(n + 2, n + 2))
                return matrix if sparse else matrix.toarray()

            for rtol in rtols:
                y0 = np.zeros(n + 2)
                solution, seconds = _timed(lambda: solve_ivp(
                    rhs, (0.0, scene.solver.stop_time), y0, method=method, jac=jacobian, rtol=rtol,
                    atol=rtol * 1e-3, t_eval=times))
                if solution.success:
                    error = np.abs(solution.y[0] - reference.x).max()
                else:
                    error = math.nan
                rows.append(dict(stepper=f"scipy-{method}", n=n, h=math.nan, error=error, seconds=seconds,
                                 steps=solution.nfev, eps=eps, rtol=rtol))
                bar.update(1)
    return rows


def table_one(quick, bar):
    """The paper's Table 1 on a short h grid: alpha and C for q = inf and 2.

    eps(h) = max over every node of |u_h - u_{h/2}|_q over (x, y, u_1..u_n), the run at h and the one at h/2 in
    lockstep on the memory stack (``table1.lockstep_run``: the paper's C^0 norm of the interpolants), fitted as
    log eps = alpha log h + log(2 C). The paper's own h grid (100 values down to 1e-6, hours of runs) and the
    search for the convention of its constants: ``bench --table1`` (``table1.py``, docs/numerics.md)."""
    from .table1 import PAPER, eps_of, fit, FACTORS, lockstep_run

    ns = [3, 10, 100] if quick else [3, 10, 100, 700, 1500]
    stop = 20.0 if quick else 500.0
    levels = 5 if quick else 7
    hs = [1e-2 / 2**j for j in range(levels)]
    rows = []
    for n in ns:
        scene = paper_scene(n, stop)
        eps = {"inf": [], "2": []}
        for h in hs:
            record = lockstep_run(scene, h, held=False)
            for q in eps:
                eps[q].append(eps_of(record, q, PAPER["norm"], PAPER["time"]))
            bar.update(1)
        for q in ("inf", "2"):
            alpha, intercept, r = fit(hs, eps[q])
            paper = PAPER_TABLE_1.get((q, n), (math.nan, math.nan))
            rows.append(dict(q=q, n=n, alpha=alpha, C=FACTORS[PAPER["factor"]](intercept, alpha), r=r,
                             paper_alpha=paper[0], paper_C=paper[1], T=stop, h_min=hs[-1]))
    return rows


def _to_reach(rows, target):
    """(steps, seconds, how) to reach error <= target.

    Interpolated log-log between the method's runs; below the smallest error
    reached, extrapolated: steps along the measured order (log error against
    log steps, fitted over all runs) and seconds at the cost per step of the
    longest run (every stepper costs the same per step whatever h).
    """
    points = sorted((r["error"], r["seconds"], r["steps"]) for r in rows
                    if r["error"] > 0 and np.isfinite(r["error"]) and np.isfinite(r["steps"]))
    if not points:
        return None
    errors = np.log([p[0] for p in points])
    seconds = np.log([p[1] for p in points])
    steps = np.log([p[2] for p in points])
    goal = math.log(target)
    if goal >= errors[-1]:
        return points[-1][2], points[-1][1], "reached"
    if goal >= errors[0]:
        return math.exp(np.interp(goal, errors, steps)), math.exp(np.interp(goal, errors, seconds)), "interpolated"
    if len(points) < 2:
        return None
    slope = np.polyfit(errors, steps, 1)[0]  # -1 / order
    needed = math.exp(steps[0] + slope * (goal - errors[0]))
    longest = max(points, key=lambda p: p[2])
    return needed, needed * longest[1] / longest[2], "extrapolated"


def report(rows, table1, n_report, machine):
    lines = [f"Machine: {machine}.", "", f"To reach a max error on the n = {n_report} scene:", "",
             "| method | 1e-2: steps | seconds | 1e-4: steps | seconds | 1e-6: steps | seconds |",
             "|---|---|---|---|---|---|---|"]
    methods = sorted({r["stepper"] for r in rows if r["n"] == n_report}, key=lambda s: (s.startswith("scipy"), s))
    for method in methods:
        if method == "exact":
            continue
        chosen = [r for r in rows if r["n"] == n_report and r["stepper"] == method]
        cells = []
        for target in (1e-2, 1e-4, 1e-6):
            reach = _to_reach(chosen, target)
            if reach is None or (method.startswith(("scipy", "fmu")) and reach[2] == "extrapolated") \
                    or (reach[2] == "extrapolated" and reach[0] > 1e15):
                cells += ["not reached", "—"]
            else:
                mark = "~" if reach[2] == "extrapolated" else ""
                steps = f"{mark}{reach[0]:.3g}" if not method.startswith("scipy") else "—"
                cells += [steps, f"{mark}{reach[1]:.3g}"]
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    exact = [r for r in rows if r["n"] == n_report and r["stepper"] == "exact"]
    if exact:
        lines.append(f"| exact (reference) | — | {exact[0]['seconds']:.3g} | — | {exact[0]['seconds']:.3g} | — "
                     f"| {exact[0]['seconds']:.3g} |")
    lines += ["", "(~: extrapolated along the method's measured order; scipy: best over eps and rtol; "
              "steps: T / h)", ""]
    verlet = [r for r in rows if r["n"] == n_report and r["stepper"] == "verlet"]
    for method in ("scipy-LSODA", "scipy-Radau"):
        runs = [r for r in rows if r["n"] == n_report and r["stepper"] == method and np.isfinite(r["error"])]
        if not runs or not verlet:
            continue
        best = min(runs, key=lambda r: r["error"])
        reach = _to_reach(verlet, best["error"])
        lines.append(f"{method} on the regularized model reached at best {best['error']:.3g} (eps = {best['eps']:g}, "
                     f"rtol = {best['rtol']:g}) in {best['seconds']:.3g} s; verlet reaches that error in "
                     f"{reach[1]:.3g} s: {best['seconds'] / reach[1]:.3g} times faster.")
    from .table1 import true_c

    lines += ["", "Table 1 (projected, eps(h) = |u_h - u_{h/2}| ~ 2 C h^alpha; the paper printed exp(b10) / 2 of its "
              "base-10 fit, here also read as 2 C h^alpha: docs/numerics.md):", "",
              "| q | n | alpha | C | r | paper alpha | paper C (printed) | paper C (as 2 C h^alpha) |",
              "|---|---|---|---|---|---|---|---|"]
    for t in table1:
        lines.append(f"| {t['q']} | {t['n']} | {t['alpha']:.5f} | {t['C']:.5f} | {t['r']:.6f} | "
                     f"{t['paper_alpha']} | {t['paper_C']} | {true_c(t['paper_C']):.5f} |")
    return "\n".join(lines) + "\n"


def plots(rows, folder):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ns = sorted({r["n"] for r in rows})
    methods = sorted({r["stepper"] for r in rows})
    colors = {method: f"C{i}" for i, method in enumerate(methods)}
    fig, axes = plt.subplots(1, len(ns), figsize=(5.5 * len(ns), 4.5), layout="constrained", squeeze=False)
    for ax, n in zip(axes[0], ns):
        for method in sorted({r["stepper"] for r in rows if r["n"] == n}):
            chosen = [r for r in rows if r["n"] == n and r["stepper"] == method and r["error"] > 0]
            if not chosen:
                exact = [r for r in rows if r["n"] == n and r["stepper"] == method]
                ax.axvline(exact[0]["seconds"], color="k", ls=":", lw=1, label=f"{method} (reference)")
                continue
            chosen.sort(key=lambda r: r["h"] if np.isfinite(r["h"]) else r["seconds"])
            style = "x" if method.startswith("scipy") else ("s--" if method.startswith("fmu") else "o-")
            ax.loglog([r["seconds"] for r in chosen], [r["error"] for r in chosen], style, label=method, ms=4,
                      color=colors[method])
        ax.set(xlabel="CPU seconds", ylabel="max |x - x_exact|", title=f"n = {n}")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    fig.suptitle("Work-precision, the paper's section 8 scene")
    fig.savefig(os.path.join(folder, "work_precision.png"), dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(1, len(ns), figsize=(5.5 * len(ns), 4.5), layout="constrained", squeeze=False)
    for ax, n in zip(axes[0], ns):
        for method in ("projected", "implicit", "symplectic", "verlet", "fmu-verlet", "fmu-projected"):
            chosen = sorted((r for r in rows if r["n"] == n and r["stepper"] == method), key=lambda r: r["h"])
            if chosen:
                ax.loglog([r["h"] for r in chosen], [r["error"] for r in chosen], "o-", label=method, ms=4,
                          color=colors[method])
        ax.set(xlabel="h (s)", ylabel="max |x - x_exact|", title=f"n = {n}")
        ax.grid(alpha=0.3, which="both")
    axes[0][0].legend(fontsize=8)
    fig.savefig(os.path.join(folder, "error_vs_h.png"), dpi=110)
    plt.close(fig)


def run(folder: str, quick: bool = False, progress=None) -> str:
    """Run the benchmark and write its files into ``folder``; return the report (Markdown)."""
    from ..stepping import _progress_bar

    os.makedirs(folder, exist_ok=True)
    cases = [(10, 20.0), (100, 20.0)] if quick else [(10, 500.0), (100, 500.0), (1500, 500.0)]
    sweeps = sum(len(hs) for hs in _sweeps(quick).values())
    fmu_runs = 4 if quick else 8
    scipy_runs = 2 if quick else 12
    table_runs = (3 * 5) if quick else (5 * 7)
    total = len(cases) * (1 + sweeps + fmu_runs) + sum(scipy_runs for n, _ in cases if n <= 100) + table_runs
    bar = _progress_bar(progress, total=total, label="bench")
    rows = []
    try:
        with tempfile.TemporaryDirectory(prefix="prandtl_bench_") as scratch:
            for n, stop in cases:
                scene = paper_scene(n, stop)
                simulate(scene.with_solver(stop_time=1.0), "exact")  # compile
                reference, seconds = _timed(lambda: simulate(scene, "exact"))
                rows.append(dict(stepper="exact", n=n, h=OUTPUT, error=0.0, seconds=seconds, steps=math.nan))
                bar.update(1)
                rows += library_rows(scene, reference, quick, bar)
                rows += fmu_rows(scene, reference, quick, scratch, bar)
                if n <= 100:
                    rows += scipy_rows(scene, reference, quick, bar)
        table1 = table_one(quick, bar)
    finally:
        bar.close()
    fields = ["stepper", "n", "h", "error", "seconds", "steps", "eps", "rtol"]
    with open(os.path.join(folder, "work_precision.csv"), "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=fields)
        writer.writeheader()
        for row in rows:
            writer.writerow({f: row.get(f, "") for f in fields})
    with open(os.path.join(folder, "table1.csv"), "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(table1[0]))
        writer.writeheader()
        writer.writerows(table1)
    plots(rows, folder)
    text = report(rows, table1, 100, _machine())
    with open(os.path.join(folder, "report.md"), "w") as fh:
        fh.write(text)
    return text


def rebuild(folder: str) -> str:
    """Plots and report again from the CSV files of an earlier run in ``folder``."""
    def number(value):
        return float(value) if value not in ("", None) else math.nan

    with open(os.path.join(folder, "work_precision.csv"), newline="") as fh:
        rows = [{k: (v if k == "stepper" else (int(v) if k == "n" else number(v))) for k, v in row.items()}
                for row in csv.DictReader(fh)]
    with open(os.path.join(folder, "table1.csv"), newline="") as fh:
        table1 = [{k: (v if k in ("q",) else (int(v) if k == "n" else number(v))) for k, v in row.items()}
                  for row in csv.DictReader(fh)]
    plots(rows, folder)
    text = report(rows, table1, 100, _machine())
    with open(os.path.join(folder, "report.md"), "w") as fh:
        fh.write(text)
    return text


def _machine():
    return f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"


def main(folder: str, quick: bool, from_csv: bool = False) -> int:
    text = rebuild(folder) if from_csv else run(folder, quick)
    print(text)
    print(f"written: {folder}/work_precision.csv, table1.csv, work_precision.png, error_vs_h.png, report.md",
          file=sys.stderr)
    return 0
