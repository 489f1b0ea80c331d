"""The paper's Figures 3-5 regenerated, with the continuum they tend to, and the convergence in n.

Bastien & Schatzman (M2AN 2002), section 8: m = 1, k0 = 0, F(t) = 0.45 cos(0.5 t), the spectrum
k(s) = 1, eta(s) = s + 0.1 sampled at the right end points s_i = i/n (eq. 7.19), scheme (5.1)
(our `projected`) with N = 10^6 steps on [0, 500] (h = 5e-4). Their Figures 3-5 plot the loops
(x, F - m x'') for 400 <= t <= 500 for n = 3, 10, 100, 700, 1500 and observe that they "seem to tend to a
limit cycle", that of the continuous element with infinitely many branches (their reference [2]).

Writes into --out (default docs/continuum):

* loops.png: the loops for n = 3, 10, 100, 1500 and the continuum (simulated directly, not sampled), and
  all of them overlaid;
* convergence.csv / convergence.png: |x_n(T) - x(T)| and max over [0, T] of |x_n - x| against n, for the
  right end points (the paper's, the scene default) and the midpoints, same stepper and step: 1/n and 1/n^2.

    python examples/continuum_figures.py [--out docs/continuum] [--stop-time 500] [--step 5e-4]
"""
import argparse
import os
import sys

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, ROOT)
from prandtl_fmu import simulate  # noqa: E402
from prandtl_fmu.bench.paper import paper_scene  # noqa: E402

LOOP_NS = (3, 10, 100, 1500, None)  # None: the continuum
CONVERGENCE_NS = (3, 10, 30, 100, 300, 1000, 3000)


def run(n, args, rule="right"):
    scene = paper_scene(n, args.stop_time, rule).with_solver(stepper="projected", step=args.step,
                                                              output_interval=args.output_interval)
    return simulate(scene, progress=False)


def label(n):
    return "continuum" if n is None else f"n = {n}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "continuum"))
    parser.add_argument("--stop-time", type=float, default=500.0)
    parser.add_argument("--step", type=float, default=5e-4)
    parser.add_argument("--output-interval", type=float, default=0.05)
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    from tqdm import tqdm

    jobs = [(n, "right") for n in LOOP_NS] + [(n, rule) for rule in ("right", "midpoint") for n in CONVERGENCE_NS]
    results = {}
    for n, rule in tqdm(jobs, desc="runs", unit="run", disable=None):
        if (n, rule) not in results and not (n is None and rule != "right"):
            results[(n, rule)] = run(n, args, rule)
    limit = results[(None, "right")]

    rows = []
    for rule in ("right", "midpoint"):
        for n in CONVERGENCE_NS:
            result = results[(n, rule)]
            rows.append({"sampling": rule, "n": n, "error_x_T": float(abs(result.x[-1] - limit.x[-1])),
                         "error_max": float(np.abs(result.x - limit.x).max())})
    with open(os.path.join(args.out, "convergence.csv"), "w") as fh:
        fh.write("sampling,n,error_x_T,error_max\n")
        for row in rows:
            fh.write(f"{row['sampling']},{row['n']},{row['error_x_T']!r},{row['error_max']!r}\n")
    for rule in ("right", "midpoint"):
        chosen = [r for r in rows if r["sampling"] == rule]
        slope = -np.polyfit(np.log([r["n"] for r in chosen]), np.log([r["error_max"] for r in chosen]), 1)[0]
        print(f"{rule}: max-norm error ~ n^-{slope:.2f}; x(T) = {float(limit.x[-1])!r} for the continuum")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    window = limit.time >= 0.8 * args.stop_time
    fig, axes = plt.subplots(2, 3, figsize=(13, 7.5), layout="constrained", sharex=True, sharey=True)
    for ax, n in zip(axes.flat, LOOP_NS):
        result = results[(n, "right")]
        ax.plot(result.x[window], result.reaction[window], lw=0.8, color="k" if n is None else None)
        ax.set_title(label(n))
        ax.grid(alpha=0.3)
    overlay = axes.flat[-1]
    for index, n in enumerate(LOOP_NS):
        result = results[(n, "right")]
        overlay.plot(result.x[window], result.reaction[window], lw=0.8, color="k" if n is None else f"C{index}",
                     label=label(n))
    overlay.set_title("all: the loops tend to the continuum's")
    overlay.legend(fontsize=8)
    overlay.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("x (m)")
    for ax in axes[:, 0]:
        ax.set_ylabel("F - m x'' (N)")
    fig.suptitle(f"Figures 3-5 of Bastien & Schatzman (2002): loops for {0.8 * args.stop_time:g} <= t <= "
                 f"{args.stop_time:g}, scheme (5.1) ('projected'), h = {args.step:g} s, eta_i = eta(i/n)")
    fig.savefig(os.path.join(args.out, "loops.png"), dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6.5, 4.5), layout="constrained")
    for index, rule in enumerate(("right", "midpoint")):
        chosen = [r for r in rows if r["sampling"] == rule]
        ns = np.array([r["n"] for r in chosen], dtype=float)
        ax.loglog(ns, [r["error_max"] for r in chosen], "o-", color=f"C{index}", label=f"{rule}: max over [0, T]")
        ax.loglog(ns, [r["error_x_T"] for r in chosen], "x:", color=f"C{index}", label=f"{rule}: at t = T")
    ns = np.array(CONVERGENCE_NS, dtype=float)
    last = [r for r in rows if r["sampling"] == "right"][-1]["error_max"]
    ax.loglog(ns, last * ns[-1] / ns, "k--", lw=0.7, label="1/n")
    last = [r for r in rows if r["sampling"] == "midpoint"][-1]["error_max"]
    ax.loglog(ns, last * (ns[-1] / ns) ** 2, "k-.", lw=0.7, label="1/n^2")
    ax.set(xlabel="number of sampled branches n", ylabel="|x_n - x_continuum| (m)",
           title="Sampled spectrum against the continuum (same scheme and h)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    fig.savefig(os.path.join(args.out, "convergence.png"), dpi=110)
    plt.close(fig)
    print(f"written: {args.out}/loops.png, convergence.png, convergence.csv")


if __name__ == "__main__":
    main()
