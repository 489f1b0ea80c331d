"""Figures of the effects with memory (docs/memory.md).

    python examples/memory_figures.py [--out docs/memory]

* ``delay-oscillator.png``: scenes/delay-oscillator.toml with and without its [delay]: the delayed position
  feedback turns a decaying hysteretic oscillation into a growing one (the rightmost root of the linear part's
  characteristic equation, branches sliding, is in the title).
* ``belt-tensioner.png``: scenes/belt-tensioner.toml, the arm's torque (spring and Dahl friction) against its
  angle once the start has died out: the hysteresis loop of the tensioner, over the spring's line.
"""
import argparse
import dataclasses
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))

from prandtl_fmu import load_scene, simulate  # noqa: E402


def rightmost_root(m, c, k, g, tau):
    """The root of m s^2 + c s + k + g e^(-s tau) = 0 of largest real part (Newton from a grid)."""
    best = None
    for re in np.linspace(-1, 1, 5):
        for im in np.linspace(0.5, 5, 10):
            s = complex(re, im)
            for _ in range(100):
                f = m * s * s + c * s + k + g * np.exp(-s * tau)
                s -= f / (2 * m * s + c - tau * g * np.exp(-s * tau))
            if abs(m * s * s + c * s + k + g * np.exp(-s * tau)) < 1e-9 and (best is None or s.real > best.real):
                best = s
    return best


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(HERE, "..", "docs", "memory"))
    out = parser.parse_args(argv).out
    os.makedirs(out, exist_ok=True)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene = load_scene(os.path.join(HERE, "..", "scenes", "delay-oscillator.toml"))
    delayed = simulate(scene).columns()
    plain = simulate(dataclasses.replace(scene, delay=None)).columns()
    root = rightmost_root(1.0, 0.1, 4.0, scene.delay.gain, scene.delay.tau)
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(plain["time"], plain["x"], lw=0.8, label="without [delay]")
    ax.plot(delayed["time"], delayed["x"], lw=0.8, label=f"with [delay] gain = {scene.delay.gain} N/m, "
                                                          f"tau = {scene.delay.tau} s")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("x (m)")
    ax.set_title("A delayed position feedback destabilizes a hysteretic oscillator\n"
                 f"(m s^2 + c s + k0 + g e^(-s tau) = 0: rightmost root s = {root:.3f})", fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "delay-oscillator.png"), dpi=110)

    scene = load_scene(os.path.join(HERE, "..", "scenes", "belt-tensioner.toml"))
    r = simulate(scene).columns()
    late = r["time"] > scene.solver.stop_time - 4 * 2 * np.pi / scene.load.omega
    angle, torque = r["x"][late], r["reaction"][late]
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.plot(angle, torque, lw=1.0, label="spring + Dahl friction (the arm's torque)")
    line = np.linspace(angle.min(), angle.max(), 2)
    ax.plot(line, scene.spring.k0 * line, "k--", lw=0.8, label="the spring alone")
    ax.set_xlabel("arm angle (rad)")
    ax.set_ylabel("torque (N m)")
    ax.set_title("Belt tensioner: the hysteresis loop (40 Hz)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "belt-tensioner.png"), dpi=110)
    print(f"wrote {out}/delay-oscillator.png and belt-tensioner.png")


if __name__ == "__main__":
    main()
