"""From a measured loop to a scene, an FMU and a plot: prandtl-fmu fit on a CSV.

    python examples/fit_loop.py [DATA.csv] [--out DIR] [--continuum piecewise|iwan|linear]

Without DATA.csv it first writes a stand-in measurement, DIR/measured.csv (time, x, force): a bolted-joint-like
element (k0 and five branches) under a growing displacement cycle, with 1 % noise on the force. Then it runs
``prandtl-fmu fit`` on it: DIR/fitted.toml (the connector scene), DIR/fitted.fmu, DIR/fit.png (measured against
fitted loop and the residual), and prints the fit's report. With --continuum it fits that continuous family
instead of branches (the stand-in is then a bolted joint: Segalman's Iwan model and k0, with 1 % noise).
"""
import argparse
import os
import subprocess
import sys

import numpy as np


BRANCHES = """
[spring]
k0 = 0.4
[branches]
k = [2.0, 1.2, 0.8, 0.5, 0.3]
eta = [0.02, 0.06, 0.15, 0.3, 0.5]
"""
JOINT = """
[spring]
k0 = 0.4
[branches]
continuum = true
density = { kind = "iwan", F_S = 1.0, K_T = 8.0, chi = -0.5, beta = 0.3 }
"""


def stand_in_measurement(path, element, seed=3):
    from prandtl_fmu import parse_scene
    from prandtl_fmu.connector import displacement_response

    scene = parse_scene(element + """
[fmu]
causality = "displacement"
[solver]
step = 0.01
stop_time = 1.0
output_interval = 0.01
""")
    t = np.linspace(0.0, 60.0, 4000)
    x = (0.05 + 0.01 * t) * np.sin(0.9 * t)
    force = displacement_response(scene, x)
    force += 0.01 * np.ptp(force) * np.random.default_rng(seed).standard_normal(len(force))
    np.savetxt(path, np.column_stack([t, x, force]), delimiter=",", header="time,x,force", comments="")
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?")
    parser.add_argument("--out", default=os.path.join("out", "fit"))
    parser.add_argument("--continuum", choices=("piecewise", "iwan", "linear"))
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    data = args.data or stand_in_measurement(os.path.join(args.out, "measured.csv"),
                                             JOINT if args.continuum else BRANCHES)
    command = [sys.executable, "-m", "prandtl_fmu", "fit", data, "--time", "time",
               "--out", os.path.join(args.out, "fitted.toml"), "--fmu", os.path.join(args.out, "fitted.fmu"),
               "--plot", os.path.join(args.out, "fit.png")] + (["--continuum", args.continuum] if args.continuum
                                                              else [])
    return subprocess.run(command).returncode


if __name__ == "__main__":
    sys.exit(main())
