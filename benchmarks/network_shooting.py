"""A network with sliders by shooting: the arc length's corrector with Newton's method against the chord method,
and the march in omega that a monotone scene's curve takes against both.

Problem: the chain on a support of scenes/networks/chain-dynamic.toml shortened to n nodes (0.1 kg, springs of
1000 N/m, alpha = 1 N, c = 0.05 N s/m), F0 = 6 N on the last node, the curve from 1 to 2.5 Hz at 64 samples per
period on a ``NetworkShooting`` (the curve's points alone: no stability, no refinement of the samples). Its 2 n
unknowns: a Jacobian is 2 n + 1 runs of half a period of the motion.

Measured, in one run of this script, for each n: the points of the curve, the runs of the motion it took and
its time (warm), by ``continuation.continue_curve`` (the arc length) with the corrector as shooting uses it
(``chord``: from CHORD_UNKNOWNS unknowns on, the last point's Jacobian kept) and with Newton's method at every
iteration (``newton``), and by ``continuation.march_curve`` (``march``: what ``shooting_response`` takes for a
monotone scene such as this chain, stepped in omega, each point Newton's method at its frequency); the ratios
of runs and times, Newton's to the chord's and the chord's to the march's.

    python benchmarks/network_shooting.py [--nodes 4,6,8] [--out docs/bench/network_shooting.csv]
"""
import argparse
import math
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
from common import write_rows  # noqa: E402
from prandtl_fmu.frequency import continuation, shooting  # noqa: E402
from prandtl_fmu.scene import load_scene  # noqa: E402

CHAIN = ('name = "chain"\n[chain]\nn = {n}\nm = 0.1\nk = 1000.0\nalpha = 1.0\nc = 0.05\nk_wall = 1000.0\n'
         '[solver]\nstepper = "implicit"\nstep = 0.001\nstop_time = 1.0\noutput_interval = 0.01\n')
FORCE, LOW, HIGH = 6.0, 1.0, 2.5


def curve(scene, chord: bool, march: bool = False) -> tuple:
    """(points, runs, seconds) of the arc length's continuation, the chord method on or off, or of the march."""
    low, high = 2 * math.pi * LOW, 2 * math.pi * HIGH
    network = shooting.NetworkShooting(scene, FORCE, None, 64, 7, math.sqrt(low * high))
    runs = [0]
    run = network.run

    def counted(*args, **kwargs):
        runs[0] += 1
        return run(*args, **kwargs)

    network.run = counted
    saved = shooting.CHORD_UNKNOWNS
    shooting.CHORD_UNKNOWNS = saved if chord else 10**9
    try:
        started = time.perf_counter()
        follow = continuation.march_curve if march else continuation.continue_curve
        points = follow(network, low, high, 2)
        return len(points), runs[0], time.perf_counter() - started
    finally:
        shooting.CHORD_UNKNOWNS = saved


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", default="4,6,8")
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for n in [int(value) for value in args.nodes.split(",")]:
            path = os.path.join(folder, f"chain{n}.toml")
            with open(path, "w") as fh:
                fh.write(CHAIN.format(n=n))
            scene = load_scene(path)
            curve(scene, True)  # compiles
            measured = {how: curve(scene, how != "newton", how == "march") for how in ("newton", "chord", "march")}
            for how, (points, runs, seconds) in measured.items():
                rows.append({"nodes": n, "unknowns": 2 * n, "corrector": how, "points": points, "runs": runs,
                             "seconds": round(seconds, 2)})
                print(rows[-1], flush=True)
            for slow, fast in (("newton", "chord"), ("chord", "march")):
                rows.append({"nodes": n, "unknowns": 2 * n, "corrector": f"{slow} / {fast}", "points": "",
                             "runs": round(measured[slow][1] / measured[fast][1], 2),
                             "seconds": round(measured[slow][2] / measured[fast][2], 2)})
                print(rows[-1], flush=True)
    if args.out:
        write_rows(args.out, rows)


if __name__ == "__main__":
    main()
