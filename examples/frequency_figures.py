"""The figures of docs/frequency.md: the describing function and the frequency response of three elements.

    python examples/frequency_figures.py [--out docs/frequency]

* ``paper.png``: the paper's element (scene paper-section-8: 100 branches, k_i = 1/100, eta_i = 0.1 + i/100):
  K(A) and the loss factor (exact), with the sum of the branches' closed forms and the continuum's (n -> inf)
  drawn over; its frequency response to F0 = 0.3 and 0.45 N (the paper's), both sweeps;
* ``iwan.png``: a lap joint as Segalman's four-parameter Iwan model (F_S = 1 N, K_T = 10^6 N/m, chi = -0.5,
  beta = 0.5): K(A), D(A) and the loss factor (spectrum), with the spectrum's closed forms and
  Segalman's micro-slip D = 4 R A^(chi+3) / ((chi+2)(chi+3));
* ``damper.png``: a friction damper (m = 1 kg, k0 = 1 N/m, one branch k = 1 N/m, alpha = 0.1 N, c = 0.02 N s/m):
  K(A) and the loss factor with the closed forms, and |X| / F0 against f for F0 from 0.02 to 2 N: from the
  stuck linear oscillator (k0 + k) to the slipping one (k0), both sweeps.
"""
import argparse
import math
import os
import sys
import time

import numpy as np

from prandtl_fmu.cli import require_extras
from prandtl_fmu.effects import ContinuousBranches, iwan_parameters
from prandtl_fmu.frequency import describe_amplitudes, frequency_response, parse_scene, read_scene
from prandtl_fmu.frequency.closed_forms import closed_form, iwan_microslip_dissipation, spectrum_forms
from prandtl_fmu.frequency.plots import draw_description, draw_response
from prandtl_fmu.plots import save_figure

IWAN = {"F_S": 1.0, "K_T": 1.0e6, "chi": -0.5, "beta": 0.5}
DAMPER = """
name = "friction-damper"
[mass]
m = 1.0
[spring]
k0 = 1.0
[damper]
c = 0.02
[branches]
k = [1.0]
alpha = [0.1]
"""


def paper(plt, out):
    scene, _ = read_scene("paper-section-8")
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.4), layout="constrained")
    started = time.perf_counter()
    description = describe_amplitudes(scene, np.geomspace(0.02, 5.0, 40))
    draw_description(description, scene, axes[:2], label="exact (n = 100)")
    fine = np.geomspace(0.02, 5.0, 200)
    continuum = ContinuousBranches.linear(1.0, 0.1, 1.1)
    K, D = spectrum_forms(continuum, fine)
    axes[0].loglog(fine, K, "--", lw=1, label="continuum (n -> inf)")
    axes[1].semilogx(fine, D / (math.pi * K * fine**2), "--", lw=1, label="continuum (n -> inf)")
    for ax in axes[:2]:
        ax.legend(fontsize=8)
    frequencies = np.linspace(0.03, 0.3, 28)
    for force, color in ((0.3, "C0"), (0.45, "C3")):
        response = frequency_response(scene, force, frequencies, stepper="verlet")
        for direction, marker in (("up", "^-"), ("down", "v--")):
            rows = np.array(response.sweep) == direction
            axes[2].plot(response.frequency[rows], response.amplitude[rows], marker, color=color, ms=3, lw=1,
                         label=f"F0 = {force:g} N, sweep {direction}")
    axes[2].axvline(1 / (2 * math.pi), color="grey", lw=0.8, ls=":", label="f of k = 1 N/m (all stick)")
    axes[2].set_xlabel("frequency f (Hz)")
    axes[2].set_ylabel("amplitude of x (m)")
    axes[2].set_title("frequency response (verlet, 1e-3)")
    axes[2].grid(alpha=0.3)
    axes[2].legend(fontsize=8)
    fig.suptitle("the paper's element (paper-section-8): 100 branches, k0 = 0, no dashpot")
    save_figure(fig, os.path.join(out, "paper.png"))
    return time.perf_counter() - started


def iwan(plt, out):
    density = ", ".join(f"{key} = {value!r}" for key, value in IWAN.items())
    scene, _ = parse_scene(f'name = "iwan-joint"\n[branches]\ncontinuum = true\ndensity = {{ kind = "iwan", '
                           f'{density} }}\n')
    params = iwan_parameters(**IWAN)
    started = time.perf_counter()
    A = params["phi_max"] * np.geomspace(1e-3, 30.0, 36)
    description = describe_amplitudes(scene, A)
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.4), layout="constrained")
    draw_description(description, scene, [axes[0], axes[2]], label="computed (spectrum)")
    fine = np.geomspace(A.min(), A.max(), 200)
    axes[1].loglog(description.amplitude, description.dissipation, "o", ms=4, label="computed (spectrum)")
    axes[1].loglog(fine, closed_form(scene, fine)[1], "-", lw=1, label="closed form (the spectrum)")
    micro = fine[fine <= params["phi_max"]]
    axes[1].loglog(micro, iwan_microslip_dissipation(params["R"], IWAN["chi"], micro), "--", lw=1,
                   label="Segalman: 4 R A^(chi+3) / ((chi+2)(chi+3))")
    for ax in axes:
        ax.axvline(params["phi_max"], color="grey", lw=0.8, ls=":", label="phi_max (macro-slip)")
    axes[1].set_xlabel("amplitude A (m)")
    axes[1].set_ylabel("D(A) (J per cycle)")
    axes[1].set_title("dissipation per cycle")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.suptitle("a lap joint: Segalman's four-parameter Iwan model, F_S = 1 N, K_T = 1e6 N/m, chi = -0.5, "
                 "beta = 0.5")
    save_figure(fig, os.path.join(out, "iwan.png"))
    return time.perf_counter() - started


def damper(plt, out):
    scene, _ = parse_scene(DAMPER, "friction-damper")
    started = time.perf_counter()
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.4), layout="constrained")
    description = describe_amplitudes(scene, np.geomspace(0.01, 10.0, 30), frequency=1 / (2 * math.pi))
    draw_description(description, scene, axes[:2])
    frequencies = np.linspace(0.08, 0.32, 25)
    for force, color in zip((0.02, 0.1, 0.2, 0.4, 2.0), ("C0", "C1", "C2", "C3", "C4")):
        response = frequency_response(scene, force, frequencies)
        for direction, marker in (("up", "^-"), ("down", "v--")):
            rows = np.array(response.sweep) == direction
            axes[2].plot(response.frequency[rows], response.amplitude[rows] / force, marker, color=color, ms=3,
                         lw=1, label=f"F0 = {force:g} N" if direction == "up" else None)
    fine = np.linspace(frequencies[0], frequencies[-1], 400)
    w = 2 * math.pi * fine
    for stiffness, name in ((2.0, "stuck: k0 + k"), (1.0, "slipping: k0")):
        axes[2].plot(fine, 1 / np.abs(stiffness - w**2 + 0.02j * w), ":", color="grey", lw=1, label=name)
    axes[2].set_yscale("log")
    axes[2].set_xlabel("frequency f (Hz)")
    axes[2].set_ylabel("|X| / F0 (m/N)")
    axes[2].set_title("frequency response (exact; up ^, down v)")
    axes[2].grid(alpha=0.3, which="both")
    axes[2].legend(fontsize=8)
    fig.suptitle("a friction damper: m = 1 kg, k0 = 1 N/m, a branch k = 1 N/m, alpha = 0.1 N, c = 0.02 N s/m "
                 "(K and D at f = 1/(2 pi) Hz)")
    save_figure(fig, os.path.join(out, "damper.png"))
    return time.perf_counter() - started


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join("docs", "frequency"))
    args = parser.parse_args()
    require_extras({"the figures": (("matplotlib",), "plot")})
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(args.out, exist_ok=True)
    for name, figure in (("paper", paper), ("iwan", iwan), ("damper", damper)):
        seconds = figure(plt, args.out)
        print(f"{os.path.join(args.out, name + '.png')}: {seconds:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
