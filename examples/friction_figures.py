"""Friction of the mass on the ground: the stick-slip limit cycle on a moving belt, and the break-away.

Writes into --out (default docs/friction):

* belt.png: the packaged scene ``hard/belt-stick-slip`` (a mass on a spring riding a belt at 0.1 m/s,
  Stribeck friction from alpha = 1 N down to 0.5 N): x(t) and v(t) with the belt's speed (the mass sticks
  to it, v = 0.1 m/s to the bit, most of each cycle), and the phase portrait (x, v) converging to the limit
  cycle, for ``implicit`` and ``verlet`` at h = 1e-3 against ``verlet`` at h = 1e-4;
* breakaway.png: the packaged scene ``hard/breakaway-ramp`` (F = 0.5 t): x = 0 exactly until F reaches
  alpha at t = 1.2 s, then the slide; the reaction (the friction holds the mass: reaction = F up to alpha).

    python examples/friction_figures.py [--out docs/friction]
"""
import argparse
import os
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, ROOT)
from prandtl_fmu import load_scene, simulate  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "friction"))
    args = parser.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(args.out, exist_ok=True)
    belt = load_scene("hard/belt-stick-slip")
    runs = {"implicit, h = 1e-3": simulate(belt, "implicit"), "verlet, h = 1e-3": simulate(belt, "verlet"),
            "verlet, h = 1e-4": simulate(belt.with_solver(step=1e-4), "verlet")}
    figure, (top, middle, right) = plt.subplots(1, 3, figsize=(15, 4.2))
    for label, result in runs.items():
        top.plot(result.time, result.x, lw=1, label=label)
        middle.plot(result.time, result.v, lw=1, label=label)
        right.plot(result.x, result.v, lw=0.8, label=label)
    middle.axhline(belt.friction.belt_velocity, color="k", ls=":", lw=1, label="belt")
    top.set(xlabel="t (s)", ylabel="x (m)", title="stick-slip on a belt at 0.1 m/s")
    middle.set(xlabel="t (s)", ylabel="v (m/s)", title="v = belt speed while stuck (exactly)")
    right.set(xlabel="x (m)", ylabel="v (m/s)", title="phase portrait: the limit cycle")
    for axes in (top, middle, right):
        axes.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(os.path.join(args.out, "belt.png"), dpi=110)

    ramp = load_scene("hard/breakaway-ramp")
    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    for stepper in ("projected", "implicit", "verlet"):
        result = simulate(ramp, stepper)
        left.plot(result.time, result.x, lw=1, label=stepper)
        right.plot(result.time, result.reaction, lw=1, label=stepper)
    right.plot(result.time, 0.5 * result.time, "k:", lw=1, label="F = 0.5 t")
    left.axvline(1.2, color="grey", ls="--", lw=0.8)
    right.axvline(1.2, color="grey", ls="--", lw=0.8)
    left.set(xlabel="t (s)", ylabel="x (m)", title="break-away at F = alpha = 0.6 N (t = 1.2 s)")
    right.set(xlabel="t (s)", ylabel="reaction (N)", title="reaction = F while held, then the slide")
    left.legend(fontsize=8)
    right.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(os.path.join(args.out, "breakaway.png"), dpi=110)
    print(os.path.join(args.out, "belt.png"))
    print(os.path.join(args.out, "breakaway.png"))


if __name__ == "__main__":
    main()
