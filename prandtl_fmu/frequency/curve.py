"""The forced response by harmonic balance: the whole curve, its folds and the stability of each point.

:func:`harmonic_response` joins ``harmonic_balance.py`` (the periodic state at one frequency), ``continuation.py``
(the curve from the lowest listed frequency to the highest, through its folds) and ``floquet.py`` (stable or
not). Without ``harmonics`` H is chosen by the tolerance: curves with H = 1, 3, 5, 7, ... (HARMONIC_STEPS) until
the first harmonic of x at the node changes by at most ``tolerance`` relative from one H to the next twice in a
row (once at the last H), at the curve's peak and at both ends (the curve of the larger H is kept); past the
last H (``harmonic_balance.harmonic_steps``: those past 31 only for a balance small enough) it is refused with
the change reached.
An element with ``[friction]`` on its mass takes ``shooting.py`` instead (the periodic state by shooting on its own
stepper: harmonic balance cannot sample a rigid slider), into the same :class:`Curve`. A range that holds a
resonance friction cannot hold (``unbounded.py``: Den Hartog's bound) is refused before either curve starts,
once the scene and the options are known to be taken. Elements in series through a massless node are joined
into one first (``series.py``: a spring and a slider with their node are a branch).

The first harmonic of x at a node, x_1 = a_1 cos(omega t) + b_1 sin(omega t) = amplitude cos(omega t + phase):
amplitude = |a_1 - i b_1| (m), phase = arg(a_1 - i b_1) (rad), as the time sweep (``response.py``) defines
them. Under base excitation (``base_amplitude`` Y0: the ground moves, y = Y0 cos(omega t)) x is the absolute
motion, x = z + y from the relative z that the balance solves for, and its phase is against y.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import DEFAULT_TOLERANCE, FrequencyError, check_tolerance, positive_values, shooting
from .continuation import continue_curve
from .harmonic_balance import (HARMONIC_STEPS, MOST_CHOSEN_UNKNOWNS, MOST_HARMONICS, HarmonicBalance,
                               harmonic_steps, lifted, periodic_system)
from .series import check_named, joined
from .unbounded import refuse_slip_limited, refuse_unbounded


@dataclass(frozen=True, eq=False)
class Curve:
    """The points of the curve in the order taken: arrays of shape (points,).

    ``frequency`` (Hz), ``amplitude`` (m) and ``phase`` (rad) of the first harmonic of x at ``node``,
    ``stable`` (bool; None for a curve computed with ``stability=False``; a numpy masked array, masked where
    a point's multipliers were not computed (``floquet.py``: past a work bound, a delay's buffer past its bound or its
    Arnoldi iteration not converged), an empty field
    in the CSV), ``fold`` (bool: a located fold),
    ``multiplier`` the largest |Floquet multiplier| of each point (NaN where it was not computed: ``floquet.py``;
    an empty field in the CSV), ``amplitudes``: {node: first-harmonic amplitude (m)} for
    every node with a mass; ``coefficients`` (points, n, 2 H + 1) of x; ``harmonics`` H; ``change`` the relative
    change of the first harmonic at the last increase of H (H given: its change at the next H, None where
    that was not found); ``force_amplitude`` F0, or
    None under base excitation, whose ``base_amplitude`` Y0 it is (x then the absolute motion, see the
    module); ``method``: how the periodic states were found ("harmonic balance", or "shooting", whose
    ``harmonics`` are only those kept in ``coefficients``)."""

    frequency: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    stable: np.ndarray
    fold: np.ndarray
    multiplier: np.ndarray
    amplitudes: dict
    coefficients: np.ndarray
    harmonics: int
    change: Optional[float]
    node: str
    force_amplitude: Optional[float]
    load_node: str
    base_amplitude: Optional[float] = None
    method: str = "harmonic balance"  # or "shooting" (friction on the mass: shooting.py), as the figures say
    orders: tuple = ()  # the higher harmonics whose amplitudes the columns carry (amplitude_<node>_h<k>)
    node_names: tuple = ()  # every node's name, in the order of the coefficients' second axis
    orbit: str = "exact motion"  # what shooting shoots on: "exact motion", or "Taylor series" (element_orbit.py)

    def columns(self) -> dict:
        """frequency, amplitude, phase, stable (the contract), amplitude_<node> per node with a mass, then
        amplitude_<node>_h<k> per node with a mass and harmonic k of ``orders``, fold, multiplier. A curve
        computed without its stability (``stability=False``) has no such columns: it says nothing it did not
        compute."""
        if self.stable is None:
            raise ValueError("the curve was computed without its stability (stability=False): no stable column")
        out = {"frequency": self.frequency, "amplitude": self.amplitude, "phase": self.phase,
               "stable": [None if s is None else "true" if s else "false" for s in self.stable.tolist()]}
        for name, values in self.amplitudes.items():
            out[f"amplitude_{name}"] = values
        for index, name in self._massive():
            for k in self.orders:
                out[f"amplitude_{name}_h{k}"] = np.hypot(self.coefficients[:, index, 2 * k - 1],
                                                         self.coefficients[:, index, 2 * k])
        out["fold"] = ["true" if f else "false" for f in self.fold.tolist()]
        # an empty field where the multipliers were not computed (the point's stability is its neighbours')
        out["multiplier"] = [None if math.isnan(m) else m for m in self.multiplier.tolist()]
        return out

    def _massive(self) -> list:
        """(index among the coefficients' nodes, name) of every node with a mass, in the order of ``amplitudes``."""
        return [(self.node_names.index(name), name) for name in self.amplitudes]

    @property
    def folds(self) -> np.ndarray:
        """The indices of the located folds."""
        return np.flatnonzero(self.fold)


def harmonic_response(scene, force_amplitude: Optional[float] = None, frequencies=None, *,
                      harmonics: Optional[int] = None, node: Optional[str] = None, load_node: Optional[str] = None,
                      tolerance: float = DEFAULT_TOLERANCE, stability: bool = True,
                      samples: Optional[int] = None, base_amplitude: Optional[float] = None,
                      orders=()) -> Curve:
    """The forced response of ``scene`` (an element with ``[mass]`` or a network) to F0 cos(2 pi f t), or
    (``base_amplitude`` Y0 instead of ``force_amplitude``) to the base's motion Y0 cos(2 pi f t), from the
    lowest of ``frequencies`` (Hz) to the highest (see the module). ``node``: where amplitude and phase are
    taken (default: the first node with a mass); ``load_node``: where the force acts (default: the scene's
    load node); ``stability``: compute the Floquet multipliers (else ``stable`` is None and every multiplier
    NaN); ``samples``: N of the AFT (default
    ``harmonic_balance.sample_count``). FrequencyError names the culprit or says where the curve stopped and
    why."""
    if (force_amplitude is None) == (base_amplitude is None):
        raise FrequencyError("give either a force amplitude or a base amplitude"
                             + (", not both" if force_amplitude is not None else ""))
    if force_amplitude is not None:
        force_amplitude = float(positive_values([force_amplitude], "force amplitude")[0])
    else:
        base_amplitude = float(positive_values([base_amplitude], "base amplitude")[0])
        if load_node is not None:
            raise FrequencyError("load node: base excitation moves the ground under every node, not one node")
    if frequencies is None:
        raise FrequencyError("frequencies: at least one value is needed")
    frequencies = positive_values(frequencies, "frequencies")
    tolerance = check_tolerance(tolerance)
    orders = check_orders(orders, harmonics)
    # a Jenkins element written with its massless node: a branch; the node the force acts on is kept
    network = getattr(scene, "network", None)
    if base_amplitude is not None:
        loaded = None  # the support moves: no node is loaded
    elif load_node is not None or network is None:
        loaded = load_node
    else:
        loaded = network.nodes[network.load_node]
    # the named node kept for its motion; the stability from the scene without it where it is massless and joins
    # (:func:`_stability_balance`)
    check_named(scene, node, load_node)
    plain = joined(scene, keep=(loaded,)) if node is not None else None
    scene = joined(scene, keep=(node, loaded))
    if shooting.takes(scene):  # friction on the mass: its periodic state by shooting (shooting.py says why)
        fields = shooting.shooting_response(scene, force_amplitude, base_amplitude, frequencies,
                                            harmonics=harmonics if harmonics is not None or not orders else
                                            max(shooting.DEFAULT_HARMONICS, max(orders)),
                                            node=node, load_node=load_node, tolerance=tolerance, stability=stability,
                                            samples=samples)
        return _listed(Curve(**fields, orders=orders), frequencies)
    system = periodic_system(scene, load_node, tolerance)
    where = system.node_index(node)
    low, high = 2.0 * math.pi * float(frequencies.min()), 2.0 * math.pi * float(frequencies.max())
    refuse_unbounded(scene, force_amplitude, base_amplitude, low, high, load_node)
    refuse_slip_limited(system, force_amplitude, base_amplitude, low, high)
    count = int(np.unique(frequencies).size)
    from ..stepping import _progress_bar

    bar = _progress_bar(None, None, "harmonic balance")  # on a terminal: the points taken, H, the stability
    try:
        if harmonics is not None:
            balance = HarmonicBalance(system, harmonics, force_amplitude, samples, base_amplitude)
            bar.set_description(f"harmonic balance, H = {harmonics}")
            points = continue_curve(balance, low, high, count, progress=bar, node=where)
            change = _truncation(balance, points, where, samples)
        else:
            balance, points, change = _chosen_harmonics(system, force_amplitude, base_amplitude, low, high, count,
                                                        where, tolerance, samples, max(orders, default=1), bar)
        judged = _stability_balance(balance, plain, load_node, tolerance) if stability else None
        bar.set_description(f"stability of each point, H = {balance.H}")
        return _listed(_curve(balance, points, where, stability, change, orders, judged, bar), frequencies)
    finally:
        bar.close()


def _stability_balance(balance, plain, load_node, tolerance):
    """The balance whose multipliers judge ``balance``'s points, or None for its own: where ``--node`` names a
    massless node that would join (``series.joined``), kept only for its motion, ``plain`` (the scene joined
    without it) has the same forces on every other node, whatever the motion, and no node of its own; its
    points are ``balance``'s restricted to its nodes (:func:`_restricted`). Why: a massless node puts the
    multipliers on the finite differences of the implicit stepper (``floquet.py``) where the joined scene's come
    from the variational equation, exact for the orbit: a mass on a spring, in series a spring, a branch and a
    spring to the ground, named at the node between the first spring and the branch, had 0.897 where the
    oscillator's exp(-c T / 2 m) is 0.905, and 1.08 to 1.15 (unstable) where the branch slides, on a scene whose
    every periodic state is stable (floquet.monotone)."""
    if plain is None:
        return None
    system = periodic_system(plain, load_node, tolerance)
    if system.nodes == balance.system.nodes:
        return None
    return HarmonicBalance(system, balance.H, balance.force_amplitude, balance.N, balance.base_amplitude)


def _restricted(balance, judged, q: np.ndarray) -> np.ndarray:
    """The free unknowns of ``judged`` (a scene with fewer nodes: :func:`_stability_balance`) from those of
    ``balance``: the same coefficients at each node it has."""
    rows = [balance.system.nodes.index(name) for name in judged.system.nodes]
    full = balance.full(q).reshape(balance.system.n, balance.L)[rows]
    return full.reshape(-1)[judged.free]


def _listed(curve: Curve, frequencies) -> Curve:
    """``curve`` with its ends at the lowest and highest frequencies listed, exactly: the points are taken in
    omega, and 2 pi f / (2 pi) is f only to rounding (0.17 Hz came back as 0.17000000000000004)."""
    for value in (float(np.min(frequencies)), float(np.max(frequencies))):
        curve.frequency[np.abs(curve.frequency - value) <= 1e-13 * value] = value
    return curve


def _first_harmonic(balance, points, where) -> np.ndarray:
    """The first harmonic of x at node ``where`` at each point (absolute under base excitation)."""
    L = balance.L
    base = balance.base_amplitude or 0.0
    return np.array([complex(balance.full(q)[where * L + 1] + base, -balance.full(q)[where * L + 2])
                     for _, q, _ in points])


def _summary(balance, points, where) -> np.ndarray:
    """The first harmonic at the peak and at both ends: what the choice of H compares."""
    X = _first_harmonic(balance, points, where)
    return np.array([X[0], X[np.argmax(np.abs(X))], X[-1]])


def _truncation(balance, points, where, samples) -> Optional[float]:
    """With H given: how much the first harmonic changes, relative, at the peak and at both ends, when H grows to
    the next step of HARMONIC_STEPS (or 2 H + 1 past them, at most MOST_HARMONICS): what the choice of H by the
    tolerance compares. The
    ends at their frequencies; the peak by the larger balance's point on the normal through the curve's
    (``continuation.across``: at a fold, where the peak may be, the point at the same frequency is ill-posed).
    None where one is not found (no estimate)."""
    H = balance.H
    larger = next((h for h in HARMONIC_STEPS if h > H), min(2 * H + 1, MOST_HARMONICS))
    if larger <= H:  # the most harmonics a balance takes: nothing to compare with
        return None
    finer = HarmonicBalance(balance.system, larger, balance.force_amplitude,
                            None if samples is None else max(samples, 4 * larger), balance.base_amplitude)
    return _change(balance, points, finer, where)


def _change(balance, points, finer, where) -> Optional[float]:
    """How much the first harmonic of ``balance``'s curve (``points``) changes, relative, in ``finer`` (more
    harmonics) at the same points: its ends at their frequencies, its peak on the normal through it
    (``continuation.across``). Never the two curves' own peaks: their points fall at different frequencies, where
    the phase turns fast near a resonance (masing-bilinear, F0 = 1 N: the peaks of H = 21 and 31 at 0.775 and
    0.755 Hz, 0.0515 apart, the same point 1e-4). None where one is not found."""
    from .continuation import across

    def lift(free_values):
        return lifted(balance, finer, free_values)

    X = _first_harmonic(balance, points, where)
    low, high = points[0][0], points[-1][0]
    changes = []
    peak = int(np.argmax(np.abs(X)))
    for index in sorted({0, peak, len(points) - 1}):
        omega, q, _ = points[index]
        if index in (0, len(points) - 1):  # an end: at its frequency
            found = finer._newton(omega, lift(q))
            if found is None:  # full steps cycling between two slip patterns (harmonic_balance: _newton)
                found = finer._newton(omega, lift(q), damped=True)
            found = None if found is None else (found, omega)
        else:  # the peak, a fold's neighbour: on the normal
            found = across(balance, finer, lift, q, omega, low, high)
        if found is None:
            return None
        (finer_X,) = _first_harmonic(finer, [(found[1], found[0], False)], where)
        # relative to the node's first harmonic, or to 1e-9 of the whole motion's coefficients where that is 0
        # (a node that does not move: its rounding against its rounding is no change)
        floor = 1e-9 * max(float(np.max(np.abs(q))), abs(balance.base_amplitude or 0.0), 1e-300)
        changes.append(abs(finer_X - X[index]) / max(abs(finer_X), floor))
    return float(max(changes))


def _started(coarser, finer, point) -> Optional[np.ndarray]:
    """The first point of the coarser curve solved with ``finer``'s harmonics (Newton from it, full steps then
    damped), or None: there the finer curve starts from the linear response (``solve_at``). From the linear
    response alone, masing-bilinear at F0 = 3 N and 0.05 Hz was refused at H = 31 (Newton, damped or with the
    force raised in steps, does not converge there), where H = 21's point converges."""
    omega, q, _ = point
    guess = lifted(coarser, finer, q)
    found = finer._newton(omega, guess)
    return found if found is not None else finer._newton(omega, guess, damped=True)


def _chosen_harmonics(system, force_amplitude, base_amplitude, low, high, count, where, tolerance,
                      samples, lowest: int = 1, bar=None) -> tuple:
    previous, change = None, math.inf
    steps = harmonic_steps(system.n, lowest)
    if not steps:
        raise FrequencyError(f"harmonic amplitudes: harmonic {lowest} is above the "
                             f"{harmonic_steps(system.n)[-1]} harmonics --tolerance chooses from: give --harmonics")
    for H in steps:
        balance = HarmonicBalance(system, H, force_amplitude, None if samples is None else max(samples, 4 * H),
                                  base_amplitude)
        start = None if previous is None else _started(previous[0], balance, previous[1][0])
        if bar is not None:
            bar.set_description(f"harmonic balance, H = {H} (chosen by the tolerance)")
        points = continue_curve(balance, low, high, count, progress=bar, node=where, start=start)
        if previous is not None:
            # the last curve's ends and peak against this H at the same points (not this curve's own peak)
            found = _change(*previous, balance, where)
            if found is None:  # not found at the same points: the two curves' summaries, as before
                summary, last = _summary(balance, points, where), _summary(*previous, where)
                found = float(np.max(np.abs(summary - last) / np.maximum(np.abs(summary), 1e-300)))
            # twice in a row (or at the last H): one change within the tolerance can be a coincidence (a
            # Duffing oscillator with branches at 0.12 Hz: 9.7e-4 from H = 1 to 3, where H = 3 was 2.4e-3 off)
            if found <= tolerance and (change <= tolerance or H == steps[-1]):
                return balance, points, found
            change = found
        previous = (balance, points)
    raise FrequencyError(f"{system.source}: the first harmonic still changed by {change:.3g} relative from "
                         f"H = {steps[-2]} to {steps[-1]} harmonics (tolerance {tolerance:g}){_past(system.n, steps)}: "
                         "give --harmonics, or a larger --tolerance")


def _past(nodes: int, steps: tuple) -> str:
    """Why the tolerance's choice stopped at ``steps[-1]`` harmonics when HARMONIC_STEPS go on: the size."""
    if steps[-1] == HARMONIC_STEPS[-1]:
        return ""
    return (f"; {nodes} nodes with more harmonics would be past {MOST_CHOSEN_UNKNOWNS} unknowns, the most the "
            "tolerance chooses")


def _curve(balance, points, where, stability, change, orders=(), judged=None, bar=None) -> Curve:
    """The curve of ``balance``'s ``points``, each point's multipliers those of ``judged``
    (:func:`_stability_balance`) where it is given."""
    from .floquet import is_stable, monotone, multipliers

    system = balance.system
    L = balance.L
    omega = np.array([p[0] for p in points])
    coefficients = np.array([balance.full(q).reshape(system.n, L) for _, q, _ in points])
    if balance.base_amplitude is not None:
        coefficients[:, :, 1] += balance.base_amplitude  # x = z + y, y = Y0 cos(omega t)
    X = coefficients[:, where, 1] - 1j * coefficients[:, where, 2]
    largest = np.full(len(points), np.nan)
    stable = np.ones(len(points), dtype=bool)
    known = np.ones(len(points), dtype=bool)
    proven = stability and monotone(system)
    if stability:  # every point's own multipliers: a verdict is never inferred from the neighbours'
        for index, (w, q, _) in enumerate(points):
            values = multipliers(balance, q, w) if judged is None else \
                multipliers(judged, _restricted(balance, judged, q), w)
            if bar is not None:
                bar.update(1)
            if values is None:  # not computed (floquet.py says where): unknown, never a guess, unless the
                known[index] = proven  # scene is monotone: every periodic state stable, by the energy
                continue
            largest[index] = float(np.max(np.abs(values)))
            stable[index] = is_stable(values)
            if proven and not stable[index]:  # the finite differences contradict the proof: their artefact
                stable[index], largest[index] = True, math.nan
    if not stability:
        stable = None
    elif not np.all(known):
        stable = np.ma.MaskedArray(stable, mask=~known)
    amplitudes = {system.nodes[i]: np.hypot(coefficients[:, i, 1], coefficients[:, i, 2]) for i in system.massive}
    phase = np.where(np.abs(X) > 0, np.angle(X), 0.0)
    return Curve(omega / (2.0 * math.pi), np.abs(X), phase, stable, np.array([p[2] for p in points], dtype=bool),
                 largest, amplitudes, coefficients, balance.H, change, system.nodes[where], balance.force_amplitude,
                 system.nodes[system.load_node], balance.base_amplitude, orders=tuple(orders),
                 node_names=tuple(system.nodes))


def check_orders(orders, harmonics: Optional[int]) -> tuple:
    """The harmonics whose amplitudes the columns carry (``orders``: whole numbers in [2, 256], each once, in
    the order given); FrequencyError naming the culprit, or an order above the ``harmonics`` given."""
    out = []
    for k in orders:
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 2 <= k <= 256:
            raise FrequencyError(f"harmonic amplitudes: each must be a whole number in [2, 256] (the first "
                                 f"harmonic is the amplitude column), got {k!r}")
        if int(k) in out:
            raise FrequencyError(f"harmonic amplitudes: {int(k)} is given twice")
        if harmonics is not None and k > harmonics:
            raise FrequencyError(f"harmonic amplitudes: harmonic {int(k)} is above the {harmonics} harmonics kept "
                                 "(--harmonics): give more, or leave --harmonics out")
        out.append(int(k))
    return tuple(out)


# ----------------------------------------------------------------- many curves: a parameter study

@dataclass(frozen=True, eq=False)
class Curves:
    """The curves of one scene at several amplitudes (a parameter study): ``curves`` in the order of
    ``amplitudes``, the force amplitudes F0 (N) or, with ``base``, the base amplitudes Y0 (m)."""

    curves: tuple
    amplitudes: np.ndarray
    base: bool

    @property
    def column(self) -> str:
        """The column that says which amplitude a row belongs to."""
        return "base_amplitude" if self.base else "force_amplitude"

    def columns(self) -> dict:
        """One curve's columns (:meth:`Curve.columns`) for each curve, their rows one curve after the other in
        the order of ``amplitudes``; with several, the column :attr:`column` (the curve's amplitude) after the
        contract's first four (frequency, amplitude, phase, stable), before amplitude_<node>. One curve: its own
        columns, unchanged."""
        each = [curve.columns() for curve in self.curves]
        if len(each) == 1:
            return each[0]
        names = list(each[0])
        out = {name: [value for columns in each for value in list(columns[name])] for name in names[:4]}
        out[self.column] = [float(a) for a, columns in zip(self.amplitudes.tolist(), each)
                            for _ in range(len(columns["frequency"]))]
        for name in names[4:]:
            out[name] = [value for columns in each for value in list(columns[name])]
        return out


def harmonic_responses(scene, frequencies, *, force_amplitudes=None, base_amplitudes=None, client=None,
                       scheduler: Optional[str] = None, workers: Optional[int] = None, **options) -> Curves:
    """:func:`harmonic_response` at each of ``force_amplitudes`` (F0, N) or of ``base_amplitudes`` (Y0, m):
    one curve per amplitude. On dask.distributed (``client``, ``scheduler`` or ``workers``: a LocalCluster of
    that many processes; the ``sweep`` extra) each curve is one task; without, the curves run one after the
    other in this process. The same curves either way (each is computed by the same function from the same
    input). ``options``: those of :func:`harmonic_response`."""
    if (force_amplitudes is None) == (base_amplitudes is None):
        raise FrequencyError("give either force amplitudes or base amplitudes"
                             + (", not both" if force_amplitudes is not None else ""))
    base = base_amplitudes is not None
    amplitudes = positive_values(base_amplitudes if base else force_amplitudes,
                                 "base amplitudes" if base else "force amplitudes")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise FrequencyError(f"workers: must be a whole number >= 1, got {workers!r}")

    def arguments(amplitude):
        return dict(options, base_amplitude=amplitude) if base else dict(options, force_amplitude=amplitude)

    if client is None and scheduler is None and workers is None:
        curves = [harmonic_response(scene, frequencies=frequencies, **arguments(a)) for a in amplitudes.tolist()]
    else:
        curves = _on_cluster(scene, frequencies, [arguments(a) for a in amplitudes.tolist()], client, scheduler,
                             workers)
    return Curves(tuple(curves), amplitudes, base)


def _on_cluster(scene, frequencies, tasks, client, scheduler, workers) -> list:
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise FrequencyError("curves on dask.distributed need the sweep extra (distributed is missing): "
                             "pip install \"prandtl_fmu[sweep]\"") from None
    from ..sweep import _client

    owned = []
    try:
        if client is None:
            client = _client(scheduler, workers, owned)
        futures = [client.submit(_curve_or_refusal, scene, frequencies, task, pure=False) for task in tasks]
        curves = [future.result() for future in futures]
    finally:
        for thing in reversed(owned):
            thing.close()
    for curve in curves:
        if isinstance(curve, FrequencyError):
            raise curve
    return curves


def _curve_or_refusal(scene, frequencies, task):
    """A cluster's task: the curve, or its refusal returned as a value (raised there, a worker logs it as a failed
    compute, with its traceback, on the user's terminal; the caller raises it, one line as without a cluster).
    numpy's RuntimeWarnings (an overflow in a trial state the corrector then refuses) are not printed, as the
    command line does not print them in its own process."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            return harmonic_response(scene, frequencies=frequencies, **task)
        except FrequencyError as refusal:
            return refusal
