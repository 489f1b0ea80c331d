"""A bolted joint as Segalman's four-parameter Iwan model: loops, and the dissipation per cycle against amplitude.

    python examples/iwan_joint.py [--out docs/spectra/iwan.png]

The continuum ([branches] continuum = true, density = { kind = "iwan", ... }) is driven by displacement cycles of
growing amplitude A. Left: the force-displacement loops (micro-slip, then macro-slip at F_S). Right: the energy
dissipated per cycle against A, measured (the sliders' account of the memory stack) and Segalman's closed form
4 R A^(chi+3) / ((chi+2)(chi+3)) below phi_max, with the fitted log-log slope for three values of chi.
"""
import argparse
import os
import sys

import numpy as np

from prandtl_fmu import parse_scene
from prandtl_fmu.connector import displacement_response
from prandtl_fmu.effects import iwan_parameters

JOINT = {"F_S": 1.0, "K_T": 1.0e6, "beta": 0.5}  # N, N/m: a lap joint of the order of Segalman's


def joint(chi):
    density = ", ".join(f"{key} = {value!r}" for key, value in {**JOINT, "chi": chi}.items())
    return parse_scene(f"""
[branches]
continuum = true
density = {{ kind = "iwan", {density} }}
[fmu]
causality = "displacement"
[solver]
step = 0.01
stop_time = 1.0
output_interval = 0.01
""")


def dissipation_per_cycle(scene, amplitude, points=4001):
    """Energy the sliders dissipate over one full cycle of amplitude A after a virgin quarter."""
    quarter = np.linspace(0.0, amplitude, points // 4)
    cycle = amplitude * np.cos(np.linspace(0.0, 2 * np.pi, points))
    _, before = displacement_response(scene, quarter, energy=True)
    _, after = displacement_response(scene, np.concatenate([quarter, cycle]), energy=True)
    return after - before


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join("out", "iwan.png"))
    args = parser.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (loops, energy) = plt.subplots(1, 2, figsize=(11, 4.4), layout="constrained")
    scene = joint(-0.5)
    phi_max = iwan_parameters(chi=-0.5, **JOINT)["phi_max"]
    for fraction in (0.25, 0.5, 1.0, 2.0):
        amplitude = fraction * phi_max
        x = np.concatenate([np.linspace(0.0, amplitude, 500), amplitude * np.cos(np.linspace(0, 2 * np.pi, 2000))])
        loops.plot(x[500:] * 1e6, displacement_response(scene, x)[500:], lw=1.0,
                   label=f"A = {fraction:g} phi_max")
    loops.set(xlabel="x (µm)", ylabel="force (N)", title="Iwan joint (chi = -0.5): loops up to macro-slip")
    loops.legend(fontsize="small")
    for chi, color in ((-0.8, "C0"), (-0.5, "C1"), (-0.2, "C2")):
        p = iwan_parameters(chi=chi, **JOINT)
        amplitudes = p["phi_max"] * np.geomspace(1e-3, 2.0, 25)
        measured = np.array([dissipation_per_cycle(joint(chi), a) for a in amplitudes])
        below = amplitudes < p["phi_max"]
        slope = np.polyfit(np.log(amplitudes[below]), np.log(measured[below]), 1)[0]
        energy.loglog(amplitudes * 1e6, measured, "o", ms=3, color=color,
                      label=f"chi = {chi}: slope {slope:.3f} (chi + 3 = {chi + 3:.1f})")
        closed = 4 * p["R"] * amplitudes[below] ** (chi + 3) / ((chi + 2) * (chi + 3))
        energy.loglog(amplitudes[below] * 1e6, closed, "-", lw=0.8, color=color)
        energy.axvline(p["phi_max"] * 1e6, color=color, lw=0.5, ls=":")
    energy.set(xlabel="amplitude A (µm)", ylabel="dissipated per cycle (J)",
               title="dots: memory stack; lines: Segalman's closed form")
    energy.legend(fontsize="small")
    for ax in (loops, energy):
        ax.grid(alpha=0.3)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
