"""The figure of docs/networks.md that states how an element between two nodes counts its elongation.

    python examples/network_convention_figure.py [--out docs/networks/convention.png]

``between = [i, j]`` goes from i to j: the elongation is e = x_j - x_i, positive when j moves away from i in
+x; a stretched element (e > 0) pulls i towards j and j towards i. Drawn for two masses and for the ground.
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyArrowPatch, Rectangle  # noqa: E402


def spring(ax, x0, x1, y, turns=6, height=0.12):
    """A zigzag spring from x0 to x1 at height y."""
    xs = [x0, x0 + 0.1 * (x1 - x0)]
    ys = [y, y]
    step = 0.8 * (x1 - x0) / (2 * turns)
    for k in range(2 * turns):
        xs.append(xs[-1] + step)
        ys.append(y + (height if k % 2 == 0 else -height))
    xs += [x1 - 0.1 * (x1 - x0), x1]
    ys += [y, y]
    ax.plot(xs, ys, color="black", lw=1.2)


def arrow(ax, x0, x1, y, colour, text, above=True, centred=True):
    ax.add_patch(FancyArrowPatch((x0, y), (x1, y), arrowstyle="-|>", mutation_scale=12, color=colour, lw=1.4))
    ax.text((x0 + x1) / 2 if centred else x0, y + (0.12 if above else -0.22), text, ha="center" if centred else "left",
            color=colour, fontsize=10)


def panel(ax, first, second, ground_first):
    ax.set_xlim(-0.3, 6.3)
    ax.set_ylim(-1.1, 1.3)
    ax.axis("off")
    left, right = 0.6, 4.4
    if ground_first:
        ax.add_patch(Rectangle((0.0, -0.6), 0.25, 1.2, hatch="////", fill=False, lw=0))
        ax.plot([0.25, 0.25], [-0.6, 0.6], color="black", lw=1.5)
        spring(ax, 0.25, right, 0.0)
        ax.text(0.12, 0.75, first, ha="center", fontsize=10)
    else:
        ax.add_patch(Rectangle((left - 0.6, -0.35), 0.6, 0.7, fc="#dde6f3", ec="black"))
        ax.text(left - 0.3, -0.07, first, ha="center", fontsize=11)
        spring(ax, left, right, 0.0)
    ax.add_patch(Rectangle((right, -0.35), 0.6, 0.7, fc="#dde6f3", ec="black"))
    ax.text(right + 0.3, -0.07, second, ha="center", fontsize=11)
    arrow(ax, 0.25 if ground_first else left - 0.3, right + 0.3, 0.75, "tab:blue",
          f"between = [\"{first}\", \"{second}\"]:  e = x_{second} - x_{first}" if not ground_first
          else f"between = [\"ground\", \"{second}\"]:  e = x_{second}  (the element on {second})")
    arrow(ax, right + 0.65, right + 1.45, 0.0, "tab:green", f"x_{second} grows:\ne grows", centred=False)
    arrow(ax, right + 0.3, right - 0.5, -0.75, "tab:red", f"e > 0 pulls {second} back", above=False)
    if not ground_first:
        arrow(ax, left - 0.3, left + 0.5, -0.75, "tab:red", f"and {first} forward", above=False)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="docs/networks/convention.png")
    args = parser.parse_args()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 4.2), layout="constrained")
    panel(top, "a", "b", ground_first=False)
    panel(bottom, "ground", "a", ground_first=True)
    fig.suptitle("an element goes from the first name of between to the second (springs, dashpots, sliders, "
                 "branches)", fontsize=10)
    fig.savefig(args.out, dpi=110)
    print(args.out)


if __name__ == "__main__":
    main()
