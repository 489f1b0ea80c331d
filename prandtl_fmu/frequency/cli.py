"""``prandtl-fmu describe``: the frequency domain from the command line (docs/frequency.md).

    prandtl-fmu describe SCENE --amplitudes A1,A2,... [--frequency F] [--between I,J] [--tolerance TOL] [--out CSV]
                         [--plot PNG]
    prandtl-fmu describe SCENE (--force-amplitude F0[,F1,...] | --base-amplitude Y0[,Y1,...])
                         --frequencies f1,f2,... [--harmonics H] [--harmonic-amplitudes K1,...] [--node NAME]
                         [--load-node NAME] [--tolerance TOL]
                         [--scheduler ADDRESS | --workers N] [--out CSV] [--plot PNG]
    prandtl-fmu describe SCENE --force-amplitude F0 --frequencies f1,f2,... --method time [--sweep up|down|both]
                         [--stepper S] [--tolerance TOL] [--scheduler ADDRESS | --workers N] [--out CSV]
                         [--plot PNG]
    prandtl-fmu describe SCENE --mode 1 --amplitudes A1,A2,... [--harmonics H] [--node NAME] [--out CSV]

The first writes ``amplitude,stiffness,dissipation,loss_factor,method,error``; the second (harmonic balance,
the default) ``frequency,amplitude,phase,stable``, ``amplitude_<node>`` for every node with a mass (then
``amplitude_<node>_h<k>`` for each harmonic k of ``--harmonic-amplitudes``), ``fold`` and
``multiplier`` (with several amplitudes, one curve per amplitude, one after the other, and the column
``force_amplitude`` or ``base_amplitude`` after ``stable``; under base excitation x is the absolute motion);
the third (the time sweep) ``frequency,amplitude,phase,sweep,steps_per_period,periods,error`` (phase in
radians); the fourth (a nonlinear mode) ``amplitude,frequency,damping_ratio``. Exit status 2, one
line and nothing written, on bad input (naming the culprit) and when a result cannot reach its accuracy
(saying what was reached); 0 otherwise (docs/cli.md: every exit is 0 or 2).
"""
from __future__ import annotations

import math
import sys

_EPILOG = ("Output columns: amplitude (m), stiffness K(A) (N/m), dissipation D(A) (J per cycle), loss_factor "
           "D/(pi K A^2) (an empty field where it is infinite: K = 0, a dashpot or friction alone), "
           "method (exact, spectrum or quadrature), error (estimated relative error; 0: rounding only); or "
           "frequency (Hz), amplitude (m) and phase (radians, of x against F0 cos(2 pi f t): x = amplitude "
           "cos(2 pi f t + phase); with --base-amplitude, of the absolute x against the base's Y0 cos(2 pi f t)), "
           "then stable, force_amplitude or base_amplitude (several amplitudes only), amplitude_<node>, "
           "amplitude_<node>_h<k> (--harmonic-amplitudes), fold, "
           "multiplier (harmonic balance) or sweep (up "
           "or down), steps_per_period, periods, error (--method time); or amplitude, frequency, damping_ratio "
           "(--mode). Exit status 2, one line, nothing written, on bad input and when a result cannot reach the "
           "tolerance.")
METHODS = ("harmonic-balance", "time")


def add_parser(commands, scene_help: str) -> None:
    """The ``describe`` subcommand on the subparsers ``commands``."""
    from ..steppers import STEPPERS

    describe = commands.add_parser(
        "describe", epilog=_EPILOG,
        help="the frequency domain: K(A), D(A) and the loss factor of the element driven in displacement "
             "(--amplitudes), or the steady response of its masses to F0 cos(2 pi f t) (--force-amplitude) or "
             "to the motion Y0 cos(2 pi f t) of their support (--base-amplitude)")
    describe.add_argument("scene", help=scene_help + "; needs no [load] or [solver]")
    describe.add_argument("--amplitudes", metavar="A1,A2,...",
                          help="displacement amplitudes (m, > 0): the describing function at each")
    describe.add_argument("--frequency", metavar="F",
                          help="frequency (Hz, > 0) of the cycles of --amplitudes: needed by a rate-dependent "
                               "element (dashpot, series dashpots, delay, history, Stribeck or belt friction)")
    describe.add_argument("--force-amplitude", metavar="F0[,F1,...]",
                          help="force amplitude F0 (N, > 0) of F0 cos(2 pi f t) on the mass (--load-node): the "
                               "frequency response; several: one curve each (harmonic balance)")
    describe.add_argument("--base-amplitude", metavar="Y0[,Y1,...]",
                          help="instead of --force-amplitude: the support (the ground) moves, y = Y0 cos(2 pi f t) "
                               "(m, > 0); amplitude and phase are of the absolute motion x against y (harmonic "
                               "balance); several: one curve each")
    describe.add_argument("--frequencies", metavar="f1,f2,...",
                          help="forcing frequencies (Hz, > 0); harmonic balance follows the curve from the lowest "
                               "to the highest")
    describe.add_argument("--method", choices=METHODS,
                          help="of the frequency response: harmonic-balance (default: the periodic state solved "
                               "for, continued through folds, its stability; with [friction] on the mass, by "
                               "shooting on the exact stepper) or time (the time-integration sweep)")
    describe.add_argument("--harmonics", metavar="H",
                          help="harmonics of the harmonic balance (default: chosen by --tolerance)")
    describe.add_argument("--harmonic-amplitudes", metavar="K1,K2,...",
                          help="of the frequency response (harmonic balance): the amplitudes of these higher "
                               "harmonics (whole numbers >= 2) of x at every node with a mass, as columns "
                               "amplitude_<node>_h<k> after amplitude_<node>")
    describe.add_argument("--node", metavar="NAME",
                          help="node whose first harmonic gives amplitude and phase (default: the first node with "
                               "a mass)")
    describe.add_argument("--load-node", metavar="NAME",
                          help="node the force acts on (default: the network's load_node; the element's mass)")
    describe.add_argument("--between", metavar="I,J",
                          help="with --amplitudes on a network: the describing function of the elements joining "
                               "nodes I and J (or ground), driven in the relative displacement")
    describe.add_argument("--mode", metavar="N",
                          help="with --amplitudes: the nonlinear mode N (1: the lowest) by the extended periodic "
                               "motion concept: frequency and damping ratio against the amplitude at --node")
    describe.add_argument("--sweep", choices=("up", "down", "both"),
                          help="--method time: sweep direction(s) (default: both for a nonlinear scene)")
    describe.add_argument("--stepper", choices=list(STEPPERS),
                          help="--method time: the stepper (default: the scene's [solver] stepper, else "
                               "exact where it applies, else verlet, else implicit)")
    describe.add_argument("--tolerance", metavar="TOL", default="1e-3",
                          help="relative accuracy of the first harmonic (default 1e-3)")
    describe.add_argument("--scheduler", metavar="ADDRESS",
                          help="run on a running dask scheduler (tcp://host:8786): the frequencies of --method "
                               "time; one curve per amplitude of harmonic balance")
    describe.add_argument("--workers", metavar="N",
                          help="run on a LocalCluster of N worker processes (as --scheduler)")
    describe.add_argument("--out", help="CSV file to write (default: standard output)")
    describe.add_argument("--plot", metavar="PNG",
                          help="figure: K(A) and the loss factor against A (log axes); the curve with its unstable "
                               "part dashed and its folds (with --mode: the backbone over it); the backbone; or the "
                               "time sweep's response by sweep; closed forms drawn over")


def _numbers(text, option: str, bounded: bool = False) -> list:
    """The comma-separated numbers of ``option``, each finite and > 0 (``bounded``: in a scene's range of
    magnitudes, [1e-50, 1e50]: a frequency of 1e-300 Hz overflowed the stability's step count, a force of
    1e-320 N lost its digits to subnormal numbers); ValueError naming the option."""
    from ..scene_tables import LARGEST_MAGNITUDE, SMALLEST_MAGNITUDE

    values = []
    for item in str(text).split(","):
        item = item.strip()
        try:
            value = float(item)
        except ValueError:
            raise ValueError(f"{option}: {item!r} is not a number") from None
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{option}: every value must be a finite number > 0, got {item!r}")
        if bounded and not SMALLEST_MAGNITUDE <= value <= LARGEST_MAGNITUDE:
            raise ValueError(f"{option}: every value must lie in [{SMALLEST_MAGNITUDE:g}, {LARGEST_MAGNITUDE:g}] (a "
                             f"scene's range of magnitudes), got {item!r}")
        values.append(value)
    return values


def _check(args) -> dict:
    """Every option checked before any work: the parsed values, or ValueError naming the culprit."""
    by_amplitude = args.amplitudes is not None and args.mode is None
    by_mode = args.mode is not None
    if args.force_amplitude is not None and args.base_amplitude is not None:
        raise ValueError("give either --force-amplitude (a force on a node) or --base-amplitude (the support's "
                         "motion), not both")
    by_force = args.force_amplitude is not None or args.base_amplitude is not None
    load_option = "--base-amplitude" if args.base_amplitude is not None else "--force-amplitude"
    if by_mode and not by_force:
        return _check_mode(args)
    if by_mode:  # the backbone over the curve
        if not args.plot or args.amplitudes is None:
            raise ValueError("--mode with --force-amplitude draws the backbone over the curve: give --amplitudes "
                             "and --plot (or --mode alone for its CSV)")
        if args.method == "time":
            raise ValueError("--mode belongs to --method harmonic-balance, not to --method time")
        mode = _check_mode(_copy_args(args, force_amplitude=None, base_amplitude=None, frequencies=None,
                                      load_node=None, scheduler=None, workers=None, harmonic_amplitudes=None))
        args = _copy_args(args, amplitudes=None, mode=None)
        values = _check(args)
        values["backbone"] = mode
        return values
    if by_amplitude == by_force:
        raise ValueError("give either --amplitudes (the describing function) or --force-amplitude (or "
                         "--base-amplitude) with --frequencies (the frequency response)"
                         + (", not both" if by_amplitude else ""))
    if by_amplitude:
        for option, value in (("--frequencies", args.frequencies), ("--sweep", args.sweep),
                              ("--stepper", args.stepper), ("--scheduler", args.scheduler),
                              ("--workers", args.workers), ("--method", args.method),
                              ("--harmonics", args.harmonics), ("--node", args.node),
                              ("--load-node", args.load_node), ("--harmonic-amplitudes", args.harmonic_amplitudes)):
            if value is not None:
                raise ValueError(f"{option} belongs to the frequency response (--force-amplitude or "
                                 "--base-amplitude), not to --amplitudes")
    else:
        if args.frequencies is None:
            raise ValueError(f"{load_option} needs --frequencies (Hz)")
        if args.frequency is not None:
            raise ValueError("--frequency sets the cycles of --amplitudes; the frequency response takes "
                             "--frequencies")
        if args.between is not None:
            raise ValueError("--between belongs to the describing function (--amplitudes) of a network")
        method = args.method or "harmonic-balance"
        wrong = (("--sweep", args.sweep), ("--stepper", args.stepper)) if method == "harmonic-balance" else (
                 ("--harmonics", args.harmonics), ("--node", args.node), ("--load-node", args.load_node),
                 ("--base-amplitude", args.base_amplitude), ("--harmonic-amplitudes", args.harmonic_amplitudes))
        for option, value in wrong:
            if value is not None:
                other = "time" if method == "harmonic-balance" else "harmonic-balance"
                raise ValueError(f"{option} belongs to --method {other}, not to --method {method}")
    values = {"tolerance": _numbers(args.tolerance, "--tolerance")[0]}
    if not values["tolerance"] < 1 or values["tolerance"] < 1e-12:
        raise ValueError(f"--tolerance: must be in [1e-12, 1), got {args.tolerance}")
    if by_amplitude:
        values["amplitudes"] = _numbers(args.amplitudes, "--amplitudes")
        values["frequency"] = None if args.frequency is None else _numbers(args.frequency, "--frequency")[0]
    else:
        values["base"] = args.base_amplitude is not None
        values["load_amplitudes"] = _numbers(args.base_amplitude if values["base"] else args.force_amplitude,
                                             load_option, bounded=True)
        if values["base"] and args.load_node is not None:
            raise ValueError("--load-node names where a force acts; --base-amplitude moves the support under every "
                             "node")
        values["frequencies"] = _numbers(args.frequencies, "--frequencies", bounded=True)
        values["method"] = args.method or "harmonic-balance"
        if values["method"] == "time" and len(values["load_amplitudes"]) > 1:
            raise ValueError("--force-amplitude: several amplitudes (one curve each) belong to --method "
                             "harmonic-balance; --method time takes one")
        if args.harmonics is not None:
            values["harmonics"] = _whole(args.harmonics, "--harmonics", 1, 256)
        if args.harmonic_amplitudes is not None:
            values["orders"] = tuple(_whole(k, "--harmonic-amplitudes", 2, 256)
                                     for k in args.harmonic_amplitudes.split(","))
        if args.workers is not None:
            if not args.workers.strip().isdigit() or int(args.workers) < 1:
                raise ValueError(f"--workers: must be a whole number >= 1, got {args.workers!r}")
            if args.scheduler:
                raise ValueError("--workers sets up a LocalCluster; with --scheduler the cluster has its own workers")
            values["workers"] = int(args.workers)
    return values


def _warn_truncation(curves, harmonics: int, tolerance: float, network: bool = False) -> None:
    """One ``warning:`` line on stderr for each harmonic balance curve whose first harmonic still changes by more
    than the tolerance at the next number of harmonics (``Curve.change``): the H given truncates it by about
    that much. The curve is written all the same (it is the H-harmonic balance asked for). Where the curves
    are by shooting (friction on a mass: the orbit is exact, H only the harmonics kept), one ``note:`` line
    says so, so that --harmonics 1 is not read as the one-harmonic balance."""
    import sys

    from .harmonic_balance import MOST_HARMONICS

    shot = [curve for curve in curves if curve.method == "shooting"]
    if shot:
        what = "a network's rigid sliders" if network else "friction on a mass"
        print(f"note: the periodic states are found by shooting on the {shot[0].orbit} ({what}), exact "
              f"whatever the harmonics: --harmonics {harmonics} sets only the harmonics kept (their columns and "
              "--harmonic-amplitudes), not the accuracy", file=sys.stderr)
    for curve in curves:
        load = (f"F0 = {curve.force_amplitude:g} N" if curve.force_amplitude is not None else
                f"Y0 = {curve.base_amplitude:g} m")
        if curve.method == "harmonic balance" and curve.change is None:
            why = ("it is the most a balance takes" if harmonics >= MOST_HARMONICS else
                   "the curve's ends or peak were not found with more")
            print(f"warning: with --harmonics {harmonics} ({load}) the first harmonic's change at more harmonics is "
                  f"not known ({why}): its truncation is not measured", file=sys.stderr)
        if curve.method == "harmonic balance" and curve.change is not None and curve.change > tolerance:
            print(f"warning: with --harmonics {harmonics} ({load}) the first harmonic changes by {curve.change:.3g} "
                  f"relative at the next number of harmonics (--tolerance {tolerance:g}): more harmonics, or none "
                  "given (chosen by --tolerance)", file=sys.stderr)


def _warn_unknown_stability(curves) -> None:
    """One ``warning:`` line for each curve with points whose stability is not computed (``stable`` empty there:
    a monodromy past its work bound on a scene not proven monotone, a delay's buffer past its bound, a delay's
    largest multipliers not converged within floquet.KRYLOV_RUNS runs, backward Euler's shrinking past
    floquet.SHRINK at the finest steps, a step of the check refused), so that an empty field is never read as a
    verdict."""
    import numpy as np

    for curve in curves:
        unknown = int(np.sum(np.ma.getmaskarray(curve.stable))) if curve.stable is not None else 0
        if unknown:
            load = (f"F0 = {curve.force_amplitude:g} N" if curve.force_amplitude is not None else
                    f"Y0 = {curve.base_amplitude:g} m")
            print(f"warning: ({load}) the stability of {unknown} of {len(curve.frequency)} points is not computed "
                  "(their stable field is empty: a monodromy past its work bound, a delay's buffer past its "
                  "bound, its largest multipliers not converged within the Arnoldi iteration's bound, backward "
                  "Euler's damping still shrinking them or the verdict still in doubt at 16384 steps a period, or "
                  "a step of the check refused by its stepper; docs/frequency.md)", file=sys.stderr)


def _warn_friction_error(scene, stepper: str) -> None:
    """One ``warning:`` line where the time sweep's stated error cannot be trusted: friction on the mass run by a
    stepper other than ``exact``. The friction's jump at each reversal puts the discrete orbit's error in a
    staircase of M: measured on a Duffing oscillator with friction at 0.15 Hz with ``verlet``, the error stayed
    at 3.3e-5 from 2048 to 8192 steps a period while the changes between them were 6e-7 and 2e-7 (the stated
    error 12 times too small). The rows are written all the same (the sweep asked for)."""
    import sys

    if getattr(scene, "friction", None) is not None and stepper != "exact":
        print(f"warning: with friction on the mass and {stepper!r} the sweep's error column (the change of the "
              "first harmonic as the steps are doubled) can be far too small (the friction's jumps make the error "
              "a staircase in the steps): --method harmonic-balance shoots on the orbit event by event", file=sys.stderr)


def _copy_args(args, **changes):
    """A copy of the parsed ``args`` with some options changed."""
    import argparse

    return argparse.Namespace(**dict(vars(args), **changes))


def _whole(text, option: str, low: int, high: int) -> int:
    """The whole number of ``option`` in [low, high]; ValueError naming the option."""
    text = str(text).strip()
    if not text.isdigit() or not low <= int(text) <= high:
        raise ValueError(f"{option}: must be a whole number in [{low}, {high}], got {text!r}")
    return int(text)


def _check_mode(args) -> dict:
    """The options of a nonlinear mode (--mode N --amplitudes ...), checked."""
    if args.amplitudes is None:
        raise ValueError("--mode needs --amplitudes (m, of x at --node)")
    for option, value in (("--force-amplitude", args.force_amplitude), ("--base-amplitude", args.base_amplitude),
                          ("--frequencies", args.frequencies),
                          ("--frequency", args.frequency), ("--sweep", args.sweep), ("--stepper", args.stepper),
                          ("--scheduler", args.scheduler), ("--workers", args.workers), ("--method", args.method),
                          ("--load-node", args.load_node), ("--between", args.between),
                          ("--harmonic-amplitudes", args.harmonic_amplitudes)):
        if value is not None:
            raise ValueError(f"{option} does not belong to a nonlinear mode (--mode)")
    values = {"mode": _whole(args.mode, "--mode", 1, 10000), "amplitudes": _numbers(args.amplitudes, "--amplitudes"),
              "tolerance": _numbers(args.tolerance, "--tolerance")[0]}
    if not values["tolerance"] < 1 or values["tolerance"] < 1e-12:
        raise ValueError(f"--tolerance: must be in [1e-12, 1), got {args.tolerance}")
    if args.harmonics is not None:
        values["harmonics"] = _whole(args.harmonics, "--harmonics", 1, 256)
    return values


def run(args) -> int:
    """The ``describe`` command; returns the exit status."""
    from ..catalog import SceneError
    from . import FrequencyError

    try:
        values = _check(args)
        if args.plot and _missing("matplotlib"):
            raise ValueError("--plot needs matplotlib: pip install 'prandtl_fmu[plot]'")
        if (args.scheduler or args.workers) and _missing("distributed"):
            raise ValueError("--scheduler and --workers need dask.distributed: pip install 'prandtl_fmu[sweep]'")
        _check_output_path(args.out, "--out")
        _check_output_path(args.plot, "--plot")
        from ..catalog import scene_path
        from ..outputs import clash

        clashing = clash([("--out", args.out), ("--plot", args.plot)], [("scene", scene_path(args.scene))])
        if clashing:
            raise ValueError(clashing)
        if args.plot:
            from ..plots import image_format

            try:
                image_format(args.plot)
            except ValueError as exc:  # it names the extensions matplotlib writes
                raise ValueError(f"--plot {exc}") from None
        from . import read_scene

        balance = "mode" in values or values.get("method") == "harmonic-balance"
        backbone = None
        scene, named = read_scene(args.scene, networks=balance or args.between is not None)
        if args.between is not None:
            if "mode" in values or "amplitudes" not in values:
                raise ValueError("--between belongs to the describing function (--amplitudes) of a network")
            from ..network.model import NetworkScene

            if not isinstance(scene, NetworkScene):
                raise ValueError(f"--between: {args.scene} is an element scene, not a network (describe it without "
                                 "--between)")
            from .describing import joint_element

            scene = joint_element(scene, args.between)
        if "mode" in values:
            from .modes import nonlinear_mode

            result = nonlinear_mode(scene, values["mode"], values["amplitudes"], harmonics=values.get("harmonics"),
                                    node=args.node, tolerance=values["tolerance"])
        elif balance:
            from .curve import harmonic_responses

            key = "base_amplitudes" if values["base"] else "force_amplitudes"
            curves = harmonic_responses(scene, values["frequencies"], **{key: values["load_amplitudes"]},
                                        harmonics=values.get("harmonics"), node=args.node,
                                        load_node=args.load_node, tolerance=values["tolerance"],
                                        orders=values.get("orders", ()), scheduler=args.scheduler,
                                        workers=values.get("workers"))
            result = curves.curves[0] if len(curves.curves) == 1 else curves
            if "harmonics" in values:
                _warn_truncation(curves.curves, values["harmonics"], values["tolerance"], hasattr(scene, "network"))
            _warn_unknown_stability(curves.curves)
            if "backbone" in values:
                from .modes import nonlinear_mode

                mode = values["backbone"]
                backbone = nonlinear_mode(scene, mode["mode"], mode["amplitudes"], harmonics=mode.get("harmonics"),
                                          node=args.node, tolerance=mode["tolerance"],
                                          load_node=None if values["base"] else curves.curves[0].load_node)
        elif "amplitudes" in values:
            from .describing import describe_amplitudes

            result = describe_amplitudes(scene, values["amplitudes"], values["frequency"],
                                         tolerance=values["tolerance"])
        else:
            from .response import frequency_response

            result = frequency_response(scene, values["load_amplitudes"][0], values["frequencies"],
                                        tolerance=values["tolerance"], stepper=args.stepper or named,
                                        sweep=args.sweep, scheduler=args.scheduler, workers=values.get("workers"))
            _warn_friction_error(scene, result.stepper)
    except (FrequencyError, SceneError, ValueError) as exc:
        import numpy as np

        if isinstance(exc, np.linalg.LinAlgError):  # numpy's, not a refusal of ours: the top level's internal
            raise  # error (it once said "error: Array must not contain infs or NaNs" as if the input were bad)
        print(f"error: {exc}", file=sys.stderr)
        return 2
    text = csv_text(result.columns())
    if args.out:
        from ..outputs import write_output

        try:
            write_output(args.out, text.encode())
        except OSError as exc:  # a full disk, a device that refuses: as `run` says it
            print(f"error: cannot write {args.out}: {exc.strerror or exc}", file=sys.stderr)
            return 2
    else:
        sys.stdout.write(text)
        sys.stdout.flush()
    if args.plot:
        from . import plots

        try:
            if "mode" in values:
                plots.plot_backbone(result, scene, args.plot)
            elif balance:
                plots.plot_curve(curves.curves, scene, args.plot, backbone)
            else:
                (plots.plot_description if "amplitudes" in values else plots.plot_response)(result, scene, args.plot)
        except OSError as exc:
            print(f"error: --plot {args.plot}: cannot write: {exc.strerror or exc}", file=sys.stderr)
            return 2
    return 0


def _missing(*modules) -> list:
    """The modules of an extra that cannot be imported."""
    import importlib.util

    return [name for name in modules if importlib.util.find_spec(name) is None]


def _check_output_path(path, option: str) -> None:
    """ValueError (one line) when ``path`` cannot be written: checked before any work."""
    import os

    if not path:
        return
    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise ValueError(f"{option} {path}: is a directory")
    if not os.path.isdir(folder):
        raise ValueError(f"{option} {path}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise ValueError(f"{option} {path}: not writable")


def csv_text(columns: dict) -> str:
    """The CSV of ``columns`` (name -> values): a header, then one row per value, floats in full precision."""
    names = list(columns)
    rows = zip(*(list(values) for values in columns.values()))
    lines = [",".join(names)]
    for row in rows:
        lines.append(",".join(_cell(value) for value in row))
    return "\n".join(lines) + "\n"


def _cell(value) -> str:
    value = value.item() if hasattr(value, "item") else value  # a numpy scalar
    if value is None:  # the infinite loss factor of K = 0
        return ""
    if isinstance(value, str):
        return value
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    if not math.isfinite(float(value)):  # every column says where it has no number (None): never nan or inf
        raise ValueError(f"a CSV cell would be {value!r} (a defect of prandtl_fmu: please report it)")
    return repr(float(value))
