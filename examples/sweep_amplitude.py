"""The energy the element dissipates per cycle against the forcing amplitude and k0: a heat map.

A sweep (prandtl_fmu.sweep, on a dask LocalCluster) of the paper's section 8
scene over a grid of forcing amplitudes and hardening stiffnesses k0; each
run keeps ``loop_area``, the energy dissipated over the last period of the
load (the area of the steady hysteresis loop). The sweep file it runs is
``examples/sweep_amplitude.toml``; the same from the command line:

    prandtl-fmu sweep paper-section-8 examples/sweep_amplitude.toml --out amplitude-sweep

    python examples/sweep_amplitude.py [--workers N] [--out sweep_amplitude.png] [--quick]

Needs the sweep and plot extras: pip install "prandtl_fmu[sweep,plot]".
"""
import argparse
import os

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    parser.add_argument("--out", default="sweep_amplitude.png", help="the heat map (PNG); a CSV goes beside it")
    parser.add_argument("--quick", action="store_true", help="a 4 x 3 grid over 30 s (a smoke test)")
    args = parser.parse_args(argv)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from prandtl_fmu.sweep import sweep

    with open(os.path.join(HERE, "sweep_amplitude.toml"), "rb") as fh:
        spec = tomllib.load(fh)
    if args.quick:
        spec["grid"]["load.amplitude"]["count"] = 4
        spec["grid"]["spring.k0"]["count"] = 3
        spec["grid"]["solver.stop_time"] = [30.0]
    frame = sweep("paper-section-8", spec, workers=args.workers)
    failed = frame[frame["error"] != ""]
    if len(failed):
        raise SystemExit(f"{len(failed)} runs failed; first: {failed['error'].iloc[0]}")
    table = frame.pivot(index="spring.k0", columns="load.amplitude", values="loop_area")
    table.to_csv(os.path.splitext(args.out)[0] + ".csv")

    figure, axes = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    from matplotlib.colors import LogNorm

    positive = table.values[table.values > 0]
    norm = LogNorm(vmin=positive.min(), vmax=positive.max()) if positive.size else None  # it spans decades
    mesh = axes.pcolormesh(table.columns, table.index, table.values, shading="nearest", cmap="viridis", norm=norm)
    figure.colorbar(mesh, ax=axes, label="energy dissipated per cycle (J), log scale")
    axes.set_xlabel("forcing amplitude (N)")
    axes.set_ylabel("k0 (N/m)")
    axes.set_title(f"paper's section 8 scene, F = A cos(0.5 t): {len(frame)} runs (white: no slip)")
    figure.savefig(args.out, dpi=120)
    print(args.out)
    return frame


if __name__ == "__main__":
    main()
