"""Command line: ``prandtl-fmu`` (or ``python -m prandtl_fmu``).

    prandtl-fmu run SCENE [--stepper S] [--step H] [--stop-time T] [--output-interval DT] [--out CSV]
                          [--states] [--energy] [--plot PNG]
    prandtl-fmu build SCENE [-o OUT.fmu] [--causality force|displacement] [--osp] [--loader prandtl|pythonfmu]
                      [--runtime python|native] [--fmi 2|3] [--arrays] [--platforms P,P,...|all]
                      [--steppers S,S,...]
    prandtl-fmu fit DATA.csv [--time COL] [--x COL] [--force COL] [--v COL]
                    [--branches N | --continuum piecewise|iwan|linear] [--dashpot]
                    [--cubic] [--out SCENE.toml] [--fmu OUT.fmu] [--plot FIT.png]
    prandtl-fmu sweep SCENE SWEEP.toml [--scheduler ADDRESS] [--workers N] [--out DIR] [--resume]
    prandtl-fmu describe SCENE (--amplitudes A,... [--frequency F] | --force-amplitude F0 --frequencies f,...)
                         [--out CSV] [--plot PNG] [--tolerance R] [--stepper S] [--workers N | --scheduler ADDRESS]
    prandtl-fmu scenes
    prandtl-fmu bench [--quick] [--out DIR] [--from-csv] [--networks] [--table1 --protocol P [--resume] ...]
    prandtl-fmu bench --table1 [--protocol paper|search|quick|...] [--out DIR] [--resume] [--workers N] [--n N]
    prandtl-fmu --version

SCENE is a scene file, or the name of a scene shipped in the package
(``prandtl-fmu scenes`` lists them: ``paper-section-8``, ``hard/step-load``, ...).

Exit status 0 on success; 2 on a bad scene or option, or when the element
cannot be advanced (plastic collapse of a massless element, a non-finite
state): one line on stderr, no traceback. A step beyond the stability limit
of the stepper prints one ``warning:`` line on stderr and runs.
"""
from __future__ import annotations

import os
import signal
import sys

# Stopped while the modules load (the first second: numpy, numba): one line and the usual status, never an
# import's traceback. Only when this module is the program (the console script, python -m prandtl_fmu): a
# process that imports it (a test, a notebook) keeps its own handlers. main() installs the handlers of the run.
_SIGNALS = {signal.SIGINT: "interrupted"}
for _name in ("SIGTERM", "SIGHUP"):
    if hasattr(signal, _name):
        _SIGNALS[getattr(signal, _name)] = f"stopped by {_name}"


def _stop_while_loading(signum, frame):
    os.write(2, f"error: {_SIGNALS.get(signum, 'stopped')}\n".encode())
    os._exit(128 + signum)


_PROGRAM = os.path.basename(sys.argv[0]) == "prandtl-fmu" or sys.argv[0].replace(os.sep, "/").endswith(
    "prandtl_fmu/__main__.py")
if _PROGRAM:
    for _signum in _SIGNALS:
        signal.signal(_signum, _stop_while_loading)

import argparse  # noqa: E402  (after the handlers above)
import math  # noqa: E402
import tempfile  # noqa: E402
import warnings  # noqa: E402

# Light imports only (the standard library and the package's base): `--help`, `--version`, `scenes` and a bad
# option answer without loading numpy or numba; each command imports what it runs.
from .catalog import SceneError, scene_path  # noqa: E402
from .outputs import AtomicFile, clash, write_atomically  # noqa: E402


_SCENE_HELP = "scene file (TOML), or the name of a packaged scene (see: prandtl-fmu scenes)"


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit status 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def _parser() -> argparse.ArgumentParser:
    from .steppers import STEPPERS  # the names: no stepper is imported

    from . import __version__

    parser = _Parser(prog="prandtl-fmu", description="The generalized Prandtl element (dry-friction hysteresis).")
    parser.add_argument("--version", action="version", version=f"prandtl-fmu {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    run = commands.add_parser("run", help="simulate a scene and write the CSV time,x,v,reaction")
    run.add_argument("scene", help=_SCENE_HELP)
    run.add_argument("--stepper", choices=list(STEPPERS), help="time stepper (default: the scene's)")
    run.add_argument("--step", type=float, help="internal time step h (s)")
    run.add_argument("--stop-time", type=float, help="end of the run (s)")
    run.add_argument("--output-interval", type=float, help="time between output rows (s), a multiple of the step")
    run.add_argument("--out", help="CSV file to write (default: standard output)")
    run.add_argument("--states", action="store_true", help="add the columns u[1]..u[n]")
    run.add_argument("--energy", action="store_true",
                     help="add the energy account: kinetic_energy, stored_energy, work, dissipated_sliders, "
                          "dissipated_damper (and dissipated_friction, with [friction]), energy_residual")
    run.add_argument("--plot", help="PNG file: hysteresis loop (reaction against x) and x(t)")
    build = commands.add_parser("build", help="build the FMI 2.0 or 3.0 (--fmi 3) co-simulation FMU of a scene")
    build.add_argument("scene", help=_SCENE_HELP)
    build.add_argument("-o", "--out", help="FMU file to write (default: ./<scene name>.fmu)")
    build.add_argument("--causality", choices=("force", "displacement"),
                       help="force: force in; x, v, reaction out (default). displacement: the connector between "
                            "two bodies, massless scenes only (a network: its load node massless): x, v in; "
                            "force out. Same as the scene's [fmu] causality, which it must not contradict")
    build.add_argument("--osp", action="store_true",
                       help="also write <modelName>_OspModelDescription.xml beside the FMU (libcosim reads it "
                            "from there: mechanical ports for powerBond and ECCO); its path is printed second")
    build.add_argument("--loader", choices=("prandtl", "pythonfmu"),
                       help="PythonFMU runtime only: the FMU's native library on Linux x86-64: prandtl (default), "
                            "PythonFMU 0.7.0's loader "
                            "patched (a refused call is fmi2Error, the instance stays usable; no leaks), or "
                            "pythonfmu, its stock loader (refusals fmi2Fatal)")
    build.add_argument("--runtime", choices=("python", "native"), default="python",
                       help="python (default): PythonFMU, runs in the host's Python; native: the scene's compiled "
                            "kernels and a C FMI layer, no Python in the host (needs a C compiler to build; the "
                            "element, FMI 2.0 or 3.0)")
    build.add_argument("--fmi", type=int, choices=(2, 3), default=2,
                       help="FMI version: 2 (default) or 3 (the native runtime only)")
    build.add_argument("--arrays", action="store_true",
                       help="native FMI 3.0 only: besides the scalars every master reads (u_1 .. u_n; a network's "
                            "x_<node>, v_<node>), the same values as arrays (u; x and v) for masters that handle "
                            "FMI 3.0 arrays")
    build.add_argument("--platforms", metavar="P,P,...|all",
                       help="native runtime only: the binaries the FMU holds, comma-separated: FMI 2.0's linux64, "
                            "win64, darwin64 (a universal x86_64 + arm64 dylib) or FMI 3.0's x86_64-linux, "
                            "aarch64-linux, x86_64-windows, x86_64-darwin, aarch64-darwin (either version's name for "
                            "the same target), or all; default: this machine's. Linked by zig (Linux: glibc 2.17; "
                            "macOS) and mingw-w64 (Windows): docs/platforms.md")
    build.add_argument("--steppers", metavar="S,S,...",
                       help="native runtime only: the steppers the binary holds, comma-separated, the scene's own "
                            "among them (default: every one that applies): fewer steppers compile sooner (one "
                            "about a third of the CPU of all five, cold, on the paper scene); the FMU refuses the others")
    fit = commands.add_parser("fit", help="identify a scene (the connector) from a measured force-displacement "
                                          "history: non-negative least squares on the play-operator basis")
    fit.add_argument("data", help="CSV file with a header line")
    fit.add_argument("--time", help="time column (s); needed by --dashpot without --v and for [solver]")
    fit.add_argument("--x", default="x", help="displacement column (m), default 'x'")
    fit.add_argument("--force", default="force", help="force column (N), default 'force'")
    fit.add_argument("--v", help="velocity column (m/s), for --dashpot")
    spectrum = fit.add_mutually_exclusive_group()
    spectrum.add_argument("--branches", type=int, default=40, metavar="N",
                          help="number of candidate elastic ranges in the grid (default 40); the fit keeps those "
                               "with a non-zero stiffness")
    spectrum.add_argument("--continuum", metavar="MODEL", choices=("piecewise", "iwan", "linear"),
                          help="fit a continuous element instead: 'piecewise' (a density over a grid of 40 "
                               "elastic ranges, linear least squares), 'iwan' (Segalman's F_S, K_T, chi, beta) or "
                               "'linear' (the paper's k_total, eta_range), by nonlinear least squares")
    fit.add_argument("--dashpot", action="store_true", help="also fit a dashpot c v")
    fit.add_argument("--cubic", action="store_true", help="also fit a cubic spring k3 x^3")
    fit.add_argument("--out", help="scene file to write (default: print it)")
    fit.add_argument("--fmu", help="also build the connector FMU of the fitted scene")
    fit.add_argument("--plot", help="PNG: measured against fitted loop, and the residual")
    sweep = commands.add_parser("sweep", help="many runs of a scene (grid and random samples of its keys, seeds "
                                              "of its noise) on dask.distributed; one Parquet row per run, and "
                                              "with [seeds] a Monte Carlo report in DIR/_report")
    sweep.add_argument("scene", help=_SCENE_HELP)
    sweep.add_argument("spec", metavar="SWEEP.toml", help="the sweep file: the keys that vary and what to keep "
                                                          "(docs/sweeps.md)")
    sweep.add_argument("--scheduler", metavar="ADDRESS", help="a running dask scheduler (tcp://host:8786); default: "
                                                              "a LocalCluster on this machine's cores")
    sweep.add_argument("--workers", type=int, help="worker processes of the LocalCluster (default: one per core)")
    sweep.add_argument("--out", metavar="DIR", help="folder of the Parquet files (default: ./<scene name>-sweep)")
    sweep.add_argument("--resume", action="store_true", help="finish the sweep in --out: run only its unfinished "
                                                             "tasks")
    from .frequency.cli import add_parser as add_describe  # issue 47: the frequency domain

    add_describe(commands, _SCENE_HELP)
    commands.add_parser("scenes", help="list the scenes shipped in the package")
    bench = commands.add_parser("bench", help="work-precision benchmark of every method (see prandtl_fmu/bench/)")
    bench.add_argument("--quick", action="store_true", help="short horizon, n = 10 and 100 (under a minute)")
    bench.add_argument("--out", default="out/bench", help="folder for the CSV, plots and report (default out/bench)")
    bench.add_argument("--from-csv", action="store_true", help="redo the plots and report from the CSV files in --out")
    bench.add_argument("--networks", action="store_true",
                       help="the cost of a step of the chain on a support (dynamic and massless) for n = 10 .. "
                            "10,000 nodes (--quick: up to 1,000): network_scaling.csv, .png, network_report.md")
    table1 = bench.add_argument_group("the paper's Table 1 and figures 3-5 (prandtl_fmu/bench/table1.py)")
    table1.add_argument("--table1", action="store_true", help="eps(h) = |u_h - u_{h/2}| in lockstep on the memory "
                        "stack, the fits and the convention search: DIR/table1_paper.csv, candidates, figure3-5.png")
    table1.add_argument("--protocol", help="paper (R = 99, h 1e-6 .. 1e-2, T = 500: hours), search (12 h from "
                        "1e-4) and its variants search-*, quick (default); the list: bench/table1.PROTOCOLS")
    table1.add_argument("--resume", action="store_true", help="continue the runs already in --out")
    table1.add_argument("--workers", type=int, help="dask workers (the sweep extra); 1: in this process")
    table1.add_argument("--scheduler", help="an existing dask scheduler tcp://host:port")
    table1.add_argument("--n", type=int, action="append", help="only this n (repeatable)")
    table1.add_argument("--limit", type=int, help="at most this many new (n, h) runs, then the (partial) tables")
    table1.add_argument("--no-figures", action="store_true", help="skip the figures 3-5")
    return parser


def main(argv=None) -> int:
    """The command line (``argv``: the arguments, default the process's); returns the exit status. No input
    makes it print a traceback: a failure nobody foresaw is still one line naming the exception
    (PRANDTL_FMU_DEBUG=1 shows the traceback). ``prandtl-fmu run`` as the process's own command (no
    ``argv``) ends the process when done (``_end_process``)."""
    # the process's own command: SIGINT, SIGTERM, SIGHUP delete the partial outputs and exit with one line (a
    # caller of main(argv), a test or a notebook, keeps its own handlers)
    previous = _catch_signals() if argv is None else {}
    try:
        status = _main(argv)
    except BrokenPipeError:  # the reader stopped (`| head`): what it read is all it wanted
        _silence_stdout()
        return 0
    except Stopped as stop:
        print(f"error: {stop}", file=sys.stderr)
        return stop.status
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # the last line of defence, not a way of handling errors
        if os.environ.get("PRANDTL_FMU_DEBUG"):
            raise
        print(f"error: internal error ({exc.__class__.__name__}: {exc}); please report it with the scene",
              file=sys.stderr)
        return 2
    finally:
        from .outputs import remove_partial_files

        remove_partial_files()  # whatever stopped the run, no hidden .prandtl-*.part file stays behind
        _restore_signals(previous)
    if argv is None and sys.argv[1:2] == ["run"]:
        _end_process(status)
    return status


class Stopped(KeyboardInterrupt):
    """SIGINT, SIGTERM or SIGHUP during a sweep (:func:`_raise_stopped`): raised where the program is, so that
    the cluster is shut down and the finished tasks named; exit status 128 + the signal."""

    def __init__(self, signum: int):
        super().__init__(_SIGNALS.get(signum, f"stopped by signal {signum}"))
        self.status = 128 + signum


def _raise_stopped(signum, frame):
    raise Stopped(signum)


def _stop_now(signum, frame):
    """SIGINT, SIGTERM or SIGHUP during a command: delete the partial outputs, say so in one line and exit with
    128 + the signal. Done in the handler itself, not by an exception: an exception raised while numba compiles
    is swallowed by a ctypes callback ("Exception ignored ..."), and the run would go on."""
    from .outputs import remove_partial_files

    tail = "; no output written" if remove_partial_files() else ""
    os.write(2, f"error: {_SIGNALS.get(signum, 'stopped')}{tail}\n".encode())
    os._exit(128 + signum)


def _catch_signals(handler=_stop_now) -> dict:
    """Install ``handler`` for SIGINT, SIGTERM, SIGHUP (main thread only); returns the previous handlers."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        return {}
    previous = {}
    for signum in _SIGNALS:
        previous[signum] = signal.signal(signum, handler)
    return previous


def _restore_signals(previous: dict) -> None:
    for signum, handler in previous.items():
        signal.signal(signum, handler if handler is not None else signal.SIG_DFL)


def _end_process(status: int) -> None:
    """End the process of ``prandtl-fmu run`` without the interpreter's teardown. Its output is complete
    and closed by now (the CSV renamed into place, standard output flushed, errors caught in ``_run``);
    tearing down numba's typing registries and compiled code takes ~0.1 s, a fifth of a tiny run
    (``benchmarks/startup.py``: 0.64 s with the teardown, 0.52 s without), and nothing of ours runs at exit."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a reader that left (| head): what _run wrote is all there is
            pass
    os._exit(status)


def _main(argv) -> int:
    warnings.simplefilter("ignore", RuntimeWarning)  # numpy overflow chatter: errors are reported as one line
    parser = _parser()
    if not (sys.argv[1:] if argv is None else argv):  # a bare `prandtl-fmu`: what it does and its commands
        parser.print_help(sys.stderr)
        return 2
    args = parser.parse_args(argv)
    if args.command in ("scenes",):
        return _command(args)
    from .compiling import compiling_status

    with compiling_status():  # on a terminal, a line while the kernels compile (the first run on a machine)
        return _command(args)


def _command(args) -> int:
    if args.command == "run":
        return _run(args)
    if args.command == "build":
        return _build(args)
    if args.command == "fit":
        return _fit(args)
    if args.command == "sweep":
        return _sweep(args)
    if args.command == "describe":
        from .frequency.cli import run as describe

        return describe(args)
    if args.command == "scenes":
        from .catalog import packaged_scenes

        print("\n".join(packaged_scenes()))
        return 0
    if args.command == "bench" and (args.table1 or args.protocol or args.resume or args.workers or args.scheduler
                                    or args.n or args.limit or args.no_figures):
        from .bench.table1 import main as table1

        if not args.table1 or args.quick or args.networks or args.from_csv:
            return _error("bench: --protocol, --resume, --workers, --scheduler, --n, --limit, --no-figures go with "
                          "--table1, and --table1 alone (not with --quick, --networks, --from-csv)")
        return table1(args.out, args.protocol or "quick", args.resume, args.workers, args.scheduler, args.n,
                      args.limit, not args.no_figures)
    if args.command == "bench" and args.networks:
        from .bench.networks import run as network_bench

        print(network_bench(args.out, args.quick))
        return 0
    if args.command == "bench":
        missing = _missing("scipy", "matplotlib", "fmpy")
        if missing:
            return _error(f"bench needs {', '.join(missing)}: pip install 'prandtl_fmu[bench,fmpy]'")
        from .bench.work_precision import main as bench

        return bench(args.out, args.quick, args.from_csv)
    return 2


def require_extras(needs: dict) -> None:
    """For scripts (the examples): ``needs`` maps what is asked for (``"--plot"``) to ``(modules, extra)``; a
    missing module is one line naming the ``pip install`` that adds it, exit status 2, before any work."""
    for what, (modules, extra) in needs.items():
        missing = _missing(*modules)
        if missing:
            print(f"error: {what} needs {', '.join(missing)}: pip install 'prandtl_fmu[{extra}]'", file=sys.stderr)
            raise SystemExit(2)


def _missing(*modules) -> list:
    """The modules of an extra that cannot be imported (an install without that extra)."""
    import importlib.util

    return [name for name in modules if importlib.util.find_spec(name) is None]


def _build(args) -> int:
    from .fmu.build import build_fmu

    if _missing("pythonfmu"):
        return _error("build needs pythonfmu: pip install prandtl_fmu (a core dependency) or pip install pythonfmu")
    try:
        path = build_fmu(args.scene, args.out, causality=args.causality, osp=args.osp, loader=args.loader,
                         runtime=args.runtime, fmi=args.fmi, arrays=args.arrays, platforms=args.platforms,
                         steppers=args.steppers)
    except (SceneError, ValueError, RuntimeError) as exc:
        return _error(exc)
    except OSError as exc:
        return _error(f"cannot write {args.out or 'the FMU'}: {exc.strerror or exc}")
    print(path)  # the path alone: FMU=$(prandtl-fmu build SCENE)
    if args.osp:
        from .fmu.osp import file_name
        from .scene import load_scene

        print(path.parent / file_name(load_scene(args.scene, check_stepper=False).name))
    return 0


def _fit(args) -> int:
    from .identify import FitError, fit, fit_continuum, read_columns

    missing = _missing("scipy") + (_missing("matplotlib") if args.plot else [])
    if missing:
        return _error(f"fit needs {', '.join(missing)}: pip install 'prandtl_fmu[fit{',plot' if args.plot else ''}]'")
    try:
        for option in ("out", "fmu"):
            _check_output_path(getattr(args, option), f"--{option}")
        _check_image_path(args.plot, "--plot")
        clashing = clash([("--out", args.out), ("--fmu", args.fmu), ("--plot", args.plot)], [("data", args.data)])
        if clashing:
            raise FitError(clashing)
        if args.branches < 1:
            raise FitError(f"--branches must be >= 1, got {args.branches}")
        data = read_columns(args.data, args.time, args.x, args.force, args.v)
        if args.continuum:
            result = fit_continuum(data["x"], data["force"], args.continuum, time=data.get("time"),
                                   v=data.get("v"), dashpot=args.dashpot, cubic=args.cubic)
        else:
            result = fit(data["x"], data["force"], time=data.get("time"), v=data.get("v"),
                         grid_size=args.branches, dashpot=args.dashpot, cubic=args.cubic)
    except (FitError, SceneError) as exc:
        return _error(exc)
    name = os.path.splitext(os.path.basename(args.data))[0] + "-fit"
    text = result.scene_text(name, data.get("time"))
    print(result.report(), file=sys.stderr)
    try:
        return _write_fit(args, name, text, data, result)
    except OSError as exc:
        return _error(f"cannot write {exc.filename or 'the output'}: {exc.strerror or exc}")


def _write_fit(args, name, text, data, result) -> int:
    """The fitted scene (to --out or standard output), its FMU (--fmu) and figure (--plot)."""
    from .identify import plot_fit

    if args.out:
        write_atomically(args.out, text)
        print(args.out)
    else:
        print(text)
    if args.fmu:
        from .fmu.build import build_fmu

        with tempfile.TemporaryDirectory(prefix="prandtl-fit-") as folder:
            scene_file = args.out
            if scene_file is None:
                scene_file = os.path.join(folder, f"{name}.toml")
                write_atomically(scene_file, text)
            try:
                print(build_fmu(scene_file, args.fmu))
            except (SceneError, ValueError) as exc:
                return _error(exc)
    if args.plot:
        plot_fit(args.plot, data["x"], data["force"], result, f"{name}: measured and fitted")
        print(args.plot)
    return 0


def _sweep(args) -> int:
    missing = _missing("distributed", "pandas", "pyarrow")
    if missing:
        return _error(f"sweep needs {', '.join(missing)}: pip install 'prandtl_fmu[sweep]'")
    from .sweep import SweepError, plan, sweep

    if args.workers is not None and args.workers < 1:
        return _error(f"--workers must be >= 1, got {args.workers}")
    from .scene import load_scene

    if args.workers is not None and args.scheduler:
        return _error("--workers sets up a LocalCluster; with --scheduler the cluster has its own workers")
    out = args.out
    previous = _catch_signals(_raise_stopped)  # the cluster is shut down on the way out
    try:
        the_plan = plan(args.scene, args.spec)  # every check before a cluster starts
        out = out or f"{load_scene(args.scene, check_stepper=False).name}-sweep"
        frame = sweep(args.scene, the_plan.spec, out=out, resume=args.resume, scheduler=args.scheduler,
                      workers=args.workers)
    except (SweepError, SceneError) as exc:
        return _error(exc)
    except RuntimeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as stop:
        kept = f"; the finished tasks are in {out}: add --resume to finish the sweep" if out else ""
        what = str(stop) if isinstance(stop, Stopped) else "interrupted"
        print(f"error: {what}{kept}", file=sys.stderr)
        return getattr(stop, "status", 130)
    finally:
        _restore_signals(previous)
    failed = frame[frame["error"] != ""]
    print(out)
    if the_plan.spec.statistics is not None:
        print(os.path.join(out, "_report", "report.md"))
    print(f"{len(frame)} runs in {out}", file=sys.stderr)
    if len(failed):
        first = failed.iloc[0]
        print(f"error: {len(failed)} of {len(frame)} runs failed (column 'error'); first, run {first['run']}: "
              f"{first['error']}", file=sys.stderr)
        return 1
    return 0


def _run(args) -> int:
    from .driver import simulate_chunks
    from .scene import load_scene
    from .stability import StabilityWarning
    from .stepping import ElementError
    from .resources import ResourceError, check_disk

    try:
        scene = load_scene(args.scene, check_stepper=args.stepper is None)
        _check_step_option(scene, args)
        scene = scene.with_solver(stepper=args.stepper, step=args.step, stop_time=args.stop_time,
                                  output_interval=args.output_interval)
        _check_output_path(args.out, "--out")
        if args.plot and _missing("matplotlib"):
            raise SceneError("--plot needs matplotlib: pip install 'prandtl_fmu[plot]'")
        _check_image_path(args.plot, "--plot")
        clashing = clash([("--out", args.out), ("--plot", args.plot)], [("scene", scene_path(args.scene))])
        if clashing:
            raise SceneError(clashing)
        if args.out:
            columns = _column_count(scene, args)
            rows = scene.solver.stop_time / scene.solver.output_interval + 2
            check_disk(rows * columns * 24.0, _folder(args.out), f"--out {args.out} ({rows:.3g} rows x {columns} "
                       "columns)")
    except (SceneError, ResourceError) as exc:
        return _error(exc)
    from .network.model import NetworkScene

    if isinstance(scene, NetworkScene):
        return _run_network(args, scene)
    plot_rows = _PlotRows() if args.plot else None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", StabilityWarning)
        try:
            chunks = simulate_chunks(scene, states=args.states, energy=args.energy)
        except (ElementError, ValueError) as exc:  # ValueError: an option that does not fit the scene
            return _error(exc)
    # A stability warning is printed once the run is done: should the run fail, its one error line
    # already says why (it carries the same explanation).
    stability = [w for w in caught if issubclass(w.category, StabilityWarning)]
    sink = None
    try:
        sink = AtomicFile(args.out) if args.out and _is_regular(args.out) else (
            open(args.out, "w", newline="") if args.out else sys.stdout)
        for index, chunk in enumerate(chunks):
            chunk.write_csv(sink, header=index == 0)
            if plot_rows is not None:
                plot_rows.add(chunk)
        if isinstance(sink, AtomicFile):
            sink.commit()
        elif args.out:
            sink.close()
        else:
            sys.stdout.flush()
    except BrokenPipeError:  # the reader stopped (`| head`): nothing more to say
        _silence_stdout()
        return 0
    except KeyboardInterrupt:  # a KeyboardInterrupt raised by code of the process (the handler exits itself)
        _discard(sink)
        print("error: interrupted; no output written" if args.out else "error: interrupted", file=sys.stderr)
        return 130
    except (ElementError, ValueError) as exc:
        _discard(sink)
        return _error(exc)
    except OSError as exc:  # a full disk, a vanished folder
        _discard(sink)
        return _error(f"cannot write {args.out or 'the output'}: {exc.strerror or exc}")
    _print_warnings(stability)
    if plot_rows is not None:
        from .plots import plot_result

        try:
            note = f"every {plot_rows.stride}th output row" if plot_rows.stride > 1 else ""
            plot_result(plot_rows.result(), args.plot, note=note)
        except OSError as exc:
            return _error(f"--plot {args.plot}: cannot write: {exc.strerror or exc}")
    return 0


def _check_step_option(scene, args) -> None:
    """A ``--step`` that the scene's output interval is not a whole multiple of, with no ``--output-interval``:
    the one line says which option to add (the scene's rule would blame its output_interval key)."""
    if args.step is None or args.output_interval is not None:
        return
    if not (isinstance(args.step, float) and math.isfinite(args.step) and args.step > 0):
        return  # the scene's rules say why
    interval = scene.solver.output_interval
    ratio = interval / args.step
    if round(ratio) >= 1 and abs(ratio - round(ratio)) <= 1e-9 * ratio:
        return
    how = "is longer than" if args.step > interval else "does not divide"
    suggestion = math.ceil(ratio * (1 - 1e-9)) * args.step
    raise SceneError(f"{scene.source}: --step {args.step!r} {how} the scene's output interval of {interval!r} s: give "
                     f"--output-interval too, a whole multiple of the step (e.g. --output-interval {suggestion:.6g})")


def _column_count(scene, args) -> int:
    from .stepping import energy_columns
    from .network.model import NetworkScene

    if isinstance(scene, NetworkScene):
        from .network.driver import columns_of

        return len(columns_of(scene, args.states, args.energy))
    return 4 + (_branch_count(scene) if args.states else 0) + (len(energy_columns(scene)) if args.energy else 0)


def _run_network(args, scene) -> int:
    """``run`` for a network scene: the columns time, x_<node>, v_<node>, F, reaction (network/driver.py)."""
    from .stepping import ElementError
    from .network.driver import simulate_chunks

    try:
        chunks = simulate_chunks(scene, states=args.states, energy=args.energy)
    except (ElementError, ValueError) as exc:
        return _error(exc)
    sink = None
    kept = []
    try:
        sink = AtomicFile(args.out) if args.out and _is_regular(args.out) else (
            open(args.out, "w", newline="") if args.out else sys.stdout)
        for index, chunk in enumerate(chunks):
            chunk.write_csv(sink, header=index == 0)
            if args.plot:
                kept.append(chunk.table[:: max(1, chunk.table.shape[0] // 20000)])
        if isinstance(sink, AtomicFile):
            sink.commit()
        elif args.out:
            sink.close()
        else:
            sys.stdout.flush()
    except BrokenPipeError:
        _silence_stdout()
        return 0
    except KeyboardInterrupt:
        _discard(sink)
        print("error: interrupted; no output written" if args.out else "error: interrupted", file=sys.stderr)
        return 130
    except (ElementError, ValueError) as exc:
        _discard(sink)
        return _error(exc)
    except OSError as exc:
        _discard(sink)
        return _error(f"cannot write {args.out or 'the output'}: {exc.strerror or exc}")
    if args.plot:
        import numpy as np

        from .network.driver import NetworkResult
        from .plots import plot_network

        try:
            plot_network(NetworkResult(chunks_names(scene, args), np.concatenate(kept),
                                       args.stepper or scene.solver.stepper, scene), args.plot)
        except OSError as exc:
            return _error(f"--plot {args.plot}: cannot write: {exc.strerror or exc}")
    return 0


def chunks_names(scene, args) -> list:
    from .network.driver import columns_of

    return columns_of(scene, args.states, args.energy)


def _error(exc) -> int:
    print(f"error: {exc}", file=sys.stderr)
    return 2


def _print_warnings(caught) -> None:
    from .stability import StabilityWarning

    for warning in caught:
        if issubclass(warning.category, StabilityWarning):
            print(f"warning: {warning.message}", file=sys.stderr)


def _is_regular(path: str) -> bool:
    """Whether ``path`` is (or will be) a regular file: only those are replaced atomically (a device such as
    /dev/stdout or a pipe is written directly)."""
    return not os.path.exists(path) or os.path.isfile(path)


def _branch_count(scene) -> int:
    branches = scene.branches
    return 0 if branches is None or branches.continuum else branches.n


def _folder(path: str) -> str:
    return os.path.dirname(os.path.abspath(path))


def _check_output_path(path, option) -> None:
    """SceneError-like one line when ``path`` cannot be written: checked before any work."""
    if not path:
        return
    folder = _folder(path)
    if os.path.isdir(path):
        raise SceneError(f"{option} {path}: is a directory")
    if not os.path.isdir(folder):
        raise SceneError(f"{option} {path}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise SceneError(f"{option} {path}: the folder {folder} is not writable")
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise SceneError(f"{option} {path}: the file is not writable")
    try:
        longest = os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError):
        longest = 255
    if len(os.fsencode(os.path.basename(path))) > longest:
        raise SceneError(f"{option} {path[:60]}...: the file name is longer than the {longest} bytes the folder "
                         "allows")


def _check_image_path(path, option) -> None:
    """:func:`_check_output_path`, and an image format matplotlib writes (from the extension)."""
    _check_output_path(path, option)
    if path:
        from .plots import image_format

        try:
            image_format(path)
        except ValueError as exc:
            raise SceneError(f"{option} {exc}") from None


def _discard(sink) -> None:
    """Drop a failed run's output: the temporary file, or close a device opened directly."""
    if isinstance(sink, AtomicFile):
        sink.discard()
    elif sink is not None and sink is not sys.stdout:
        try:
            sink.close()
        except OSError:
            pass


def _silence_stdout() -> None:
    """After a broken pipe, point stdout at /dev/null so that the interpreter's final flush is silent."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


class _PlotRows:
    """The rows the plot needs (x, reaction, time), thinned to at most ~200 000 points in bounded memory:
    every row while there are few, then every 2nd, 4th, ... row (the plot says which)."""

    LIMIT = 200_000

    def __init__(self):
        self.stride, self.seen, self.parts, self.kept, self.first = 1, 0, [], 0, None

    def add(self, chunk) -> None:
        import numpy as np

        if self.first is None:
            self.first = chunk
        index = self.seen + np.arange(chunk.time.shape[0])
        keep = index % self.stride == 0
        self.parts.append(np.column_stack([chunk.time[keep], chunk.x[keep], chunk.reaction[keep]]))
        self.kept += int(keep.sum())
        self.seen += chunk.time.shape[0]
        while self.kept > self.LIMIT:
            self.stride *= 2
            table = np.concatenate(self.parts)
            table = table[::2]
            self.parts, self.kept = [table], table.shape[0]

    def result(self):
        import numpy as np

        from .driver import Result

        table = np.concatenate(self.parts)
        first = self.first
        return Result(table[:, 0], table[:, 1], np.full(table.shape[0], np.nan), table[:, 2], None, None,
                      first.stepper, first.scene)
