"""What a chain costs: ``prandtl-fmu bench --networks [--quick] [--out DIR]``.

The chain sliding on a fixed support, n nodes (n = 10, 100, 1,000, 10,000; ``--quick``: up to 1,000), springs
k = 1000 N/m between neighbours and to the wall, a slider alpha = 1 N of each node on the support, the load
F = 0.6 n alpha sin(2 pi t / T) on the last node (it sets 60 % of the nodes sliding, whatever n), h = T / 2000:

* dynamic: every node 1 kg (and a dashpot 0.01 N s/m to the support);
* massless (quasi-static): no mass, no dashpot.

Seconds: the compiled time loop alone (compiled and warmed up first), over one period; reported per step and
per node and step, with the growth from 1,000 to 10,000 nodes (10x for a linear cost). Iterations: the
active-set iterations per step (each costs a few passes over the nodes and elements).

Writes DIR/network_scaling.csv, DIR/network_scaling.png and DIR/network_report.md.
"""
from __future__ import annotations

import csv
import os
import time

import numpy as np

PERIOD = 1.0
STEPS_PER_PERIOD = 2000


def chain_scene(n: int, dynamic: bool):
    from ..scene import parse_scene

    mass = "m = 1.0\nc = 0.01" if dynamic else "m = 0.0"
    text = f"""
name = "chain-{'dynamic' if dynamic else 'massless'}-{n}"
[chain]
n = {n}
{mass}
k = 1000.0
alpha = 1.0
k_wall = 1000.0
[load]
kind = "table"
time = {np.linspace(0.0, PERIOD, 201).tolist()}
force = {(0.6 * n * np.sin(2 * np.pi * np.linspace(0.0, PERIOD, 201))).tolist()}
[solver]
stepper = "implicit"
step = {PERIOD / STEPS_PER_PERIOD!r}
stop_time = {PERIOD!r}
output_interval = {PERIOD!r}
"""
    return parse_scene(text, source=f"<chain of {n}>")


def measure(n: int, dynamic: bool) -> dict:
    """Seconds and active-set iterations per step of one period of the chain of n nodes."""
    from ..network import kernels
    from ..network.driver import initial_state

    scene = chain_scene(n, dynamic)
    network = scene.network
    model = network.compile()
    load = scene.load.compile()
    h = scene.solver.step
    x, v, u, piece = initial_state(scene, model, load)
    work = kernels.workspace(network.n, len(network.elements))
    out = np.empty((1, 2 * n + 2))
    kernels.run_implicit(model, load, x.copy(), v.copy(), u.copy(), piece.copy(), 0.0, 0, h, 1, out, None, None,
                         None, None, None, work)  # compiled and warmed up
    iterations = 0
    started = time.perf_counter()
    taken, status = kernels.run_implicit(model, load, x, v, u, piece, 0.0, 0, h, STEPS_PER_PERIOD, out, None, None,
                                         None, None, None, work)
    seconds = time.perf_counter() - started
    if taken < STEPS_PER_PERIOD:
        raise RuntimeError(f"the chain of {n} failed at step {taken} (status {status})")
    # the iterations, counted in a second pass step by step (not timed)
    x, v, u, piece = initial_state(scene, model, load)
    counts = []
    for p in range(STEPS_PER_PERIOD):
        status, _ = kernels.implicit_step(model, load, p * h, h, x, v, u, piece, work, None, None)
        counts.append(status)
        iterations += status
    return {"case": "dynamic" if dynamic else "massless", "n": n, "steps": STEPS_PER_PERIOD,
            "seconds": seconds, "us_per_step": 1e6 * seconds / STEPS_PER_PERIOD,
            "ns_per_node_step": 1e9 * seconds / STEPS_PER_PERIOD / n,
            "iterations_per_step": iterations / STEPS_PER_PERIOD, "most_iterations": int(max(counts))}


def run(folder: str, quick: bool = False) -> str:
    os.makedirs(folder, exist_ok=True)
    sizes = [10, 100, 1000] if quick else [10, 100, 1000, 10000]
    rows = [measure(n, dynamic) for dynamic in (True, False) for n in sizes]
    with open(os.path.join(folder, "network_scaling.csv"), "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, os.path.join(folder, "network_scaling.png"))
    text = report(rows)
    with open(os.path.join(folder, "network_report.md"), "w") as fh:
        fh.write(text)
    return text


def report(rows) -> str:
    lines = ["| chain | n | us per step | ns per node and step | active-set iterations per step (most) |",
             "|---|---:|---:|---:|---:|"]
    for row in rows:
        lines.append(f"| {row['case']} | {row['n']:,} | {row['us_per_step']:.1f} | {row['ns_per_node_step']:.1f} | "
                     f"{row['iterations_per_step']:.2f} ({row['most_iterations']}) |")
    growth = []
    for case in ("dynamic", "massless"):
        by_n = {row["n"]: row["seconds"] for row in rows if row["case"] == case}
        if 1000 in by_n and 10000 in by_n:
            growth.append(f"{case}: {by_n[10000] / by_n[1000]:.1f}x from 1,000 to 10,000 nodes (linear: 10x)")
    return "\n".join(lines + [""] + growth) + "\n"


def plot(rows, path: str) -> None:
    try:
        import matplotlib
    except ImportError:
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plots import save_figure

    fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
    for case in ("dynamic", "massless"):
        data = [(row["n"], row["us_per_step"]) for row in rows if row["case"] == case]
        ax.loglog(*zip(*data), "o-", label=f"{case} chain")
    ns = np.array([row["n"] for row in rows if row["case"] == "dynamic"], dtype=float)
    first = [row["us_per_step"] for row in rows if row["case"] == "dynamic"][0]
    ax.loglog(ns, first * ns / ns[0], "k:", lw=0.8, label="linear in n")
    ax.set_xlabel("nodes n")
    ax.set_ylabel("time per implicit step (us)")
    ax.set_title("the chain on a fixed support: cost of a step")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    save_figure(fig, path)
