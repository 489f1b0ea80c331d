"""Command line: ``python -m prandtl_fmu run SCENE.toml [options]``.

Exit status 0 on success; 2 on a bad scene or option, or when the element
cannot be advanced (plastic collapse of a massless element, a non-finite
state): one line on stderr, no traceback. A step beyond the stability limit
of the stepper prints one ``warning:`` line on stderr and runs.
"""
from __future__ import annotations

import argparse
import sys

import warnings

from .driver import ENERGY_COLUMNS, ElementError
from .scene import SceneError, load_scene
from .stability import StabilityWarning
from .steppers import STEPPERS


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit status 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="python -m prandtl_fmu", description="The generalized Prandtl element.")
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    run = commands.add_parser("run", help="simulate a scene and write the CSV time,x,v,reaction")
    run.add_argument("scene", help="scene file (TOML)")
    run.add_argument("--stepper", choices=list(STEPPERS), help="time stepper (default: the scene's)")
    run.add_argument("--step", type=float, help="internal time step h (s)")
    run.add_argument("--stop-time", type=float, help="end of the run (s)")
    run.add_argument("--output-interval", type=float, help="time between output rows (s), a multiple of the step")
    run.add_argument("--out", help="CSV file to write (default: standard output)")
    run.add_argument("--states", action="store_true", help="add the columns u[1]..u[n]")
    run.add_argument("--energy", action="store_true",
                     help="add the energy account: " + ", ".join(ENERGY_COLUMNS))
    run.add_argument("--plot", help="PNG file: hysteresis loop (reaction against x) and x(t)")
    bench = commands.add_parser("bench", help="work-precision benchmark of every method (see prandtl_fmu/bench.py)")
    bench.add_argument("--quick", action="store_true", help="short horizon, n = 10 and 100 (under a minute)")
    bench.add_argument("--out", default="out/bench", help="folder for the CSV, plots and report (default out/bench)")
    bench.add_argument("--from-csv", action="store_true", help="redo the plots and report from the CSV files in --out")
    return parser


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "run":
        return _run(args)
    if args.command == "bench":
        from .bench import main as bench

        return bench(args.out, args.quick, args.from_csv)
    return 2


def _run(args) -> int:
    from .driver import simulate

    try:
        scene = load_scene(args.scene).with_solver(
            stepper=args.stepper, step=args.step, stop_time=args.stop_time,
            output_interval=args.output_interval,
        )
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", StabilityWarning)
        try:
            result = simulate(scene, states=args.states, energy=args.energy)
        except (ElementError, ValueError) as exc:  # ValueError: an option that does not fit the scene
            error = exc
        else:
            error = None
    for warning in caught:
        if issubclass(warning.category, StabilityWarning):
            print(f"warning: {warning.message}", file=sys.stderr)
    if error is not None:
        print(f"error: {error}", file=sys.stderr)
        return 2
    if args.out:
        with open(args.out, "w", newline="") as fh:
            result.write_csv(fh)
    else:
        result.write_csv(sys.stdout)
    if args.plot:
        from .plots import plot_result

        plot_result(result, args.plot)
    return 0
