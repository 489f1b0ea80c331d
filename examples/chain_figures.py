"""The chain sliding on a fixed support (scene networks/chain-massless): the load against the end's
displacement, from the library, with the closed forms drawn beside it. Writes docs/networks/chain-loop.png.

    python examples/chain_figures.py [OUT.png]

Closed forms (uniform k, alpha, pulled at its end from rest; docs/networks.md): while F rises,
p = floor(F / alpha) nodes slide and x_end(F) = (1/k) sum_{q=1..p} (F - q alpha); from the turning point
(F_max, x_max) the curve is Masing's x_max - 2 x_end((F_max - F) / 2), and from (-F_max, -x_max) its mirror.
"""
import math
import sys

import numpy as np


def virgin(force, k, alpha, n):
    """x_end(F) of the virgin chain (F >= 0)."""
    p = min(math.floor(force / alpha), n)
    return (p * force - alpha * p * (p + 1) / 2) / k


def main(path="docs/networks/chain-loop.png"):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from prandtl_fmu.network import simulate
    from prandtl_fmu.plots import save_figure
    from prandtl_fmu.scene import load_scene

    scene = load_scene("networks/chain-massless")
    chain = scene.network
    k = chain.elements[0].value
    alpha = chain.of_kind("slider")[0].value
    n = chain.n
    result = simulate(scene)
    end = result.column(f"x_{chain.nodes[-1]}")
    top = float(np.max(result.F))
    x_top = virgin(top, k, alpha, n)
    rising = np.linspace(0.0, top, 400)
    falling = np.linspace(top, -top, 800)
    fig, ax = plt.subplots(figsize=(6.4, 4.6), layout="constrained")
    ax.plot(end, result.F, lw=2.5, color="tab:blue", alpha=0.45, label="library (implicit, h = 1 ms)")
    ax.plot([virgin(f, k, alpha, n) for f in rising], rising, "k--", lw=1, label="closed form: first loading")
    ax.plot([x_top - 2 * virgin((top - f) / 2, k, alpha, n) for f in falling], falling, "k:", lw=1.2,
            label="Masing: unloading and reloading")
    ax.plot([-x_top + 2 * virgin((f + top) / 2, k, alpha, n) for f in -falling], -falling, "k:", lw=1.2)
    ax.set_xlabel(f"x_{chain.nodes[-1]}: displacement of the loaded end (m)")
    ax.set_ylabel("F (N)")
    ax.set_title(f"chain of {n} massless nodes on a fixed support (k = {k:g} N/m, alpha = {alpha:g} N)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    save_figure(fig, path)
    print(path)


if __name__ == "__main__":
    main(*sys.argv[1:])
