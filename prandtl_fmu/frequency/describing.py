"""K(A), D(A) and the loss factor: the element driven in displacement to its steady cycle.

The element (its springs, branches, dashpots, Masing backbone, Dahl, continuum or spectrum; not its mass) is
driven by x = A sin(theta), theta = 2 pi f t, from x = 0 and its initial state. On the steady cycle the force
has the first harmonic a_1 sin(theta) + b_1 cos(theta),

    a_1 = (1/pi) int_0^{2 pi} F sin(theta) d theta,     b_1 = (1/pi) int_0^{2 pi} F cos(theta) d theta,

and the results are

    K(A) = a_1 / A                       (N/m)   the effective (secant, describing-function) stiffness,
    D(A) = oint F dx = pi A b_1          (J)     the energy dissipated per cycle,
    loss factor = D / (pi K A^2) = b_1 / a_1.

Three methods, chosen from the scene:

* ``exact`` (parallel springs, a cubic spring, a dashpot, Prandtl branches on either kernel, a Masing backbone;
  friction of the mass): every part has a closed form and K, D add over parallel parts. A branch k, eta
  that slips in the steady cycle (eta < A: once x has been to A and to -A its elongation is -eta at the
  bottom and eta at the top, whatever u0) gives K = (k / 2 pi)(y - sin y) with y = 4 asin(sqrt(eta / A))
  (the stick angle in a form that keeps eta / A below the rounding of 1; a series for small y) and
  D = 4 k eta (A - eta); one that does not (eta >= A) is elastic about its offset: K = k, D = 0. The cubic
  spring adds 3/4 k3 A^2 to K and nothing to D; the dashpot pi c omega A^2 to D; Coulomb friction alpha on
  the mass 4 alpha A to D and nothing to K (with a Stribeck drop or on a belt: :func:`friction_dissipation`,
  whose error is added). Rounding only: ``error`` 0;
* ``spectrum`` (the continuum, Segalman's joint, a piecewise spectrum, with the springs and dashpot above):
  the branch forms integrated over the spectrum by Gauss-Legendre on the pieces of each segment cut where
  eta(s) = A (:func:`closed_forms.spectrum_forms`), the nodes doubled from FIRST_NODES until a_1 and b_1
  each change by at most the tolerance; ``error`` the last change (the rule converges much faster than
  that: the error of the result is far below it);
* ``quadrature`` (Dahl, branches with series dashpots, a delay, a history): N samples per
  cycle, the force at each from the exact moves between samples (x linear in between), cycles repeated until
  the first harmonic settles (:func:`prandtl_fmu.frequency.settled`: the last change and the geometric tail of
  those to come within a quarter of the tolerance; or a cycle that repeats to rounding), the trapezoid rule
  in theta for a_1, b_1; N doubled from 64 until the error estimate is within the tolerance (1e-3 relative
  by default): the larger of the last two changes of a_1 and b_1 under a doubling, each against its own size
  (:func:`relative_change`: K and D both), plus the settling remainder (the last change from cycle to cycle
  and its geometric tail). One change alone is not enough: where a kink of the force (a slip) falls between
  samples the convergence is uneven, and a branch with a series dashpot in deep slip was 2.5 times further
  from the converged cycle than its last change. Past 2^16 samples per cycle or MAX_CYCLES cycles, the
  amplitude is refused with what was reached.

A number that overflows or underflows (K, D or the loss factor at an extreme amplitude) is refused naming the
amplitude; the loss factor D / (pi K A^2) is formed without A^2. Where K = 0 and D is not (a dashpot or
friction alone) the loss factor is infinite: ``math.inf``, written as an empty field in the CSV.
"""
from __future__ import annotations

import dataclasses
import math
import sys
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..compiled import choose_branch_kernel, compile_model
from ..kernels import stack
from ..kernels.drive import drive, drive_with_memory
from ..loads import ConstantLoad
from ..memory import has_memory
from ..stepping import _progress_bar
from .closed_forms import branch_forms, gauss_legendre, spectrum_forms
from . import DEFAULT_TOLERANCE, FrequencyError, check_tolerance, positive_values, settled, settling_remainder

# The quadrature's first and last number of samples per cycle, and the most cycles run to reach the steady one.
FIRST_SAMPLES = 64
MAX_SAMPLES = 2**16
MAX_CYCLES = 400
# The spectrum's first and last number of Gauss-Legendre nodes on each piece of a segment.
FIRST_NODES = 64
MAX_NODES = 1024
# The cuts of each piece of the cycle towards its ends for the Stribeck friction's layer: at 10^-1 ... 10^-GRADING
# of its length.
GRADING = 10
# A sum one of whose parts underflowed keeps its digits only if it is this large: the smallest normal number
# over the rounding.
SMALLEST_PART = sys.float_info.min / sys.float_info.epsilon


@dataclass(frozen=True, eq=False)
class Description:
    """K(A), D(A) and the loss factor at each amplitude: arrays of shape (amplitudes,).

    ``amplitude`` A (m), ``stiffness`` K (N/m), ``dissipation`` D (J per cycle), ``loss_factor``
    D / (pi K A^2) (+-inf where K = 0 and D is not); ``method`` "exact", "spectrum" or "quadrature" for each;
    ``error`` the estimated relative error of the first harmonic (0 for exact, rounding only, but for a
    Stribeck drop or a belt); ``frequency`` (Hz) of the cycles, None for a rate-independent element (whose
    results do not depend on it).
    """

    amplitude: np.ndarray
    stiffness: np.ndarray
    dissipation: np.ndarray
    loss_factor: np.ndarray
    method: tuple
    error: np.ndarray
    frequency: Optional[float]

    def columns(self) -> dict:
        """The CSV's columns: amplitude, stiffness, dissipation, loss_factor (the contract), method, error; an
        infinite loss factor (K = 0, D not) is None: an empty field."""
        loss = [None if math.isinf(value) else value for value in self.loss_factor.tolist()]
        return {"amplitude": self.amplitude, "stiffness": self.stiffness, "dissipation": self.dissipation,
                "loss_factor": loss, "method": list(self.method), "error": self.error}


def rate_dependent_effects(scene) -> list:
    """The scene's effects whose force depends on the rate of x (they need a frequency)."""
    names = []
    if scene.has_dashpot:
        names.append("[damper]")
    if scene.has_series_dashpots:
        names.append("[branches] c (series dashpots)")
    if scene.delay is not None:
        names.append("[delay]")
    if scene.history is not None:
        names.append("[history]")
    friction = scene.friction
    if friction is not None and (friction.stribeck_velocity is not None or friction.belt_velocity != 0.0):
        names.append("[friction] with a Stribeck drop or a moving belt")
    return names


def describe_amplitudes(scene, amplitudes, frequency: Optional[float] = None, *,
                        tolerance: float = DEFAULT_TOLERANCE, progress: Optional[bool] = None) -> Description:
    """K(A), D(A) and the loss factor of ``scene``'s element at each of ``amplitudes`` (m, > 0) (see the module).

    ``frequency`` (Hz, > 0) of x = A sin(2 pi f t): required by a rate-dependent element (dashpot, series
    dashpots, delay, history, friction with a Stribeck drop or on a belt), ignored otherwise. ``tolerance``:
    the relative accuracy of the quadratures. FrequencyError names the culprit (bad input, or an amplitude
    whose cycle does not settle or converge)."""
    amplitudes = positive_values(amplitudes, "amplitudes")
    tolerance = check_tolerance(tolerance)
    rate = rate_dependent_effects(scene)
    if frequency is not None:
        frequency = float(positive_values([frequency], "frequency")[0])
    if rate and frequency is None:
        raise FrequencyError(f"{scene.source}: the element has {', '.join(rate)}, whose force depends on the rate: "
                             "give the frequency of the cycles (--frequency)")
    if not rate:
        frequency = None  # rate independent: the results do not depend on it
    element = dataclasses.replace(scene, mass=None, friction=None, load=ConstantLoad(0.0), causality="force")
    method = _method(element)
    rows = []
    bar = _progress_bar(progress, total=amplitudes.shape[0], label=f"{scene.name} describe")
    try:
        for amplitude in amplitudes.tolist():
            lost = set()  # K or D with a part that underflowed: refused unless the total dwarfs it
            if method in ("exact", "spectrum"):
                stiffness, dissipation, error = exact_forms(element, amplitude, frequency, tolerance, lost)
            else:
                a1, b1, error = quadrature_harmonic(element, amplitude, frequency or 1.0, tolerance)
                stiffness, dissipation = a1 / amplitude, math.pi * amplitude * b1
                _check_range(scene, amplitude, "D", dissipation)
                if _underflowed(dissipation, b1):
                    lost.add("D")
            if scene.friction is not None:
                friction, friction_error = friction_dissipation(scene, amplitude, frequency, tolerance, lost)
                dissipation, error = dissipation + friction, max(error, friction_error)
            for name, total in (("K", stiffness), ("D", dissipation)):
                if name in lost and abs(total) < SMALLEST_PART:
                    raise _underflow(scene, amplitude, name)
            rows.append(_row(scene, amplitude, stiffness, dissipation, error, method))
            bar.update(1)
    finally:
        bar.close()
    table = np.array([row[:5] for row in rows], dtype=float)
    return Description(table[:, 0], table[:, 1], table[:, 2], table[:, 3], tuple(row[5] for row in rows),
                       table[:, 4], frequency)


def _row(scene, amplitude, stiffness, dissipation, error, method) -> tuple:
    """The row of one amplitude, its numbers checked: finite, and either 0 or normal (an overflow or an
    underflow is refused naming the amplitude). The loss factor of K = 0 and D not (a dashpot, friction
    alone) is infinite: +-``math.inf`` here, an empty field in the CSV."""
    for name, value in (("K", stiffness), ("D", dissipation)):
        _check_range(scene, amplitude, name, value)
    if stiffness == 0.0:
        if dissipation == 0.0:
            raise FrequencyError(f"{scene.source}: at A = {amplitude!r} m the element carries no force (K = D = 0): "
                                 "it has no loss factor")
        loss = math.copysign(math.inf, dissipation)
    else:
        loss = loss_factor(stiffness, dissipation, amplitude)
        _check_range(scene, amplitude, "the loss factor", loss, dissipation)
    return amplitude, stiffness, dissipation, loss, error, method


def loss_factor(stiffness: float, dissipation: float, amplitude: float) -> float:
    """D / (pi K A^2) without forming A^2 (which overflows from A ~ 1e154 and underflows below 1e-154): the
    mantissas and the exponents apart; inf past the largest float."""
    mk, ek = math.frexp(stiffness)
    md, ed = math.frexp(dissipation)
    ma, ea = math.frexp(amplitude)
    try:
        return math.ldexp(md / (math.pi * mk * ma * ma), ed - ek - 2 * ea)
    except OverflowError:
        return math.copysign(math.inf, md * mk)


def _underflowed(value, *factors) -> bool:
    """Whether a product of ``factors`` (none 0) came out below the smallest normal number."""
    return abs(value) < sys.float_info.min and all(factors)


def _check_range(scene, amplitude, name, value, *factors) -> None:
    """FrequencyError naming the amplitude when ``value`` overflowed (not finite) or underflowed (below the
    smallest normal number, or 0 while every one of ``factors`` is not)."""
    if not math.isfinite(value):
        raise FrequencyError(f"{scene.source}: at A = {amplitude!r} m, {name} overflows (beyond "
                             f"{sys.float_info.max:.3g}): the amplitude is too large for this element")
    if (value != 0.0 and abs(value) < sys.float_info.min) or (value == 0.0 and factors and all(factors)):
        raise _underflow(scene, amplitude, name)


def _underflow(scene, amplitude, name) -> FrequencyError:
    return FrequencyError(f"{scene.source}: at A = {amplitude!r} m, {name} underflows (below "
                          f"{sys.float_info.min:.3g}): this amplitude is out of the floating-point range of "
                          "this element")


def friction_dissipation(scene, amplitude: float, frequency: Optional[float], tolerance: float, lost: set) -> tuple:
    """``(D, estimated relative error)`` of the friction of the mass on the ground (``[friction]``) under
    x = A sin(theta): the force F = sign(w) a(|w|), w = A omega cos(theta) - v_b the velocity against the
    belt, a = alpha_k + (alpha - alpha_k) exp(-|w| / v_s) (Stribeck; alpha for Coulomb). F depends on cos(theta)
    only: nothing in phase with x (a_1 = 0), and D = pi A b_1 = 2 A int_0^pi F cos(theta) d theta. Its part
    alpha_k sign(w) in closed form, 4 alpha_k A sqrt(1 - r^2) for |r| = |v_b / (A omega)| < 1 (0 otherwise:
    w keeps its sign); the Stribeck part by Gauss-Legendre on the pieces of [0, pi] where w keeps its sign,
    each cut geometrically towards its ends (GRADING cuts at 10^-j of its length: the exponential is a layer
    of width v_s / (A omega) there), the nodes doubled from FIRST_NODES until D changes by at most the
    tolerance (the error)."""
    friction, A = scene.friction, float(amplitude)
    speed = A * 2.0 * math.pi * frequency if frequency is not None else math.inf  # A omega
    ratio = friction.belt_velocity / speed
    kinetic = friction.alpha_kinetic if friction.stribeck_velocity is not None else friction.alpha
    sliding = math.sqrt(max(0.0, (1.0 - ratio) * (1.0 + ratio)))  # sin(theta*), cos(theta*) = r
    dissipation = 4.0 * kinetic * A * sliding if abs(ratio) < 1.0 else 0.0
    _check_range(scene, A, "D", dissipation)
    if _underflowed(dissipation, kinetic, sliding):
        lost.add("D")
    if friction.stribeck_velocity is None or friction.alpha == friction.alpha_kinetic:
        return dissipation, 0.0
    turn = math.acos(ratio) if abs(ratio) < 1.0 else None
    ends = [0.0, turn, math.pi] if turn is not None else [0.0, math.pi]
    pieces = []
    for lo, hi in zip(ends[:-1], ends[1:]):  # graded towards both ends, where |w| is smallest (a thin layer)
        grading = [(hi - lo) * 0.1**k for k in range(1, GRADING + 1)]
        cuts = sorted({lo, hi, *(lo + g for g in grading), *(hi - g for g in grading)})
        pieces += [(a, b) for a, b in zip(cuts[:-1], cuts[1:]) if b > a]
    drop = friction.alpha - friction.alpha_kinetic
    nodes, previous = FIRST_NODES, None
    while True:
        x, w = gauss_legendre(nodes)
        total = 0.0
        for lo, hi in pieces:
            theta = lo + 0.5 * (hi - lo) * (x + 1.0)
            relative = speed * np.cos(theta) - friction.belt_velocity
            side = math.copysign(1.0, speed * math.cos(0.5 * (lo + hi)) - friction.belt_velocity)
            total += 0.5 * (hi - lo) * side * float(np.sum(w * np.exp(-np.abs(relative) / friction.stribeck_velocity)
                                                          * np.cos(theta)))
        stribeck = 2.0 * A * drop * total
        if previous is not None:
            change = abs(stribeck - previous) / max(abs(dissipation + stribeck), NEGLIGIBLE * abs(stribeck), 1e-300)
            if change <= tolerance:
                _check_range(scene, A, "D", dissipation + stribeck)
                return dissipation + stribeck, change
            if nodes >= MAX_NODES:
                raise FrequencyError(f"{scene.source}: at A = {A!r} m the Stribeck friction's integral over the "
                                     f"cycle did not converge to {tolerance:g} relative by {MAX_NODES} nodes")
        previous, nodes = stribeck, 2 * nodes


def _method(element) -> str:
    """"exact" for springs, a dashpot and Prandtl branches, "spectrum" with a spectrum of branches (the
    continuum) instead, "quadrature" with series dashpots, Dahl or memory."""
    if element.has_series_dashpots or element.delay is not None or element.history is not None \
            or element.dahl is not None:
        return "quadrature"
    return "spectrum" if element.branches is not None and element.branches.continuum else "exact"


# ----------------------------------------------------------------- exact and spectrum: closed forms

def exact_forms(element, amplitude: float, frequency: Optional[float], tolerance: float, lost: set) -> tuple:
    """``(K, D, estimated relative error)`` of the steady cycle of a rate-independent ``element`` (massless,
    its branches Prandtl's or a spectrum; a dashpot beside them) under x = A sin(theta): the closed forms of
    its parts (see the module), each checked against overflow; "K" or "D" added to ``lost`` where a part of
    it underflowed. Error 0 but for a spectrum."""
    A = float(amplitude)
    stiffness, dissipation = 0.0, 0.0
    if element.spring is not None:
        stiffness += element.spring.k0
    if element.cubic is not None:
        cubic = 0.75 * element.cubic.k3 * A * A  # k3 A^3 sin^3 = k3 A^3 (3 sin - sin 3 theta) / 4
        _check_range(element, A, "K", cubic)
        if _underflowed(cubic, element.cubic.k3):
            lost.add("K")
        stiffness += cubic
    if element.has_dashpot:
        rate = element.damper.c * 2.0 * math.pi * frequency  # c v = c omega A cos(theta)
        dashpot = math.pi * rate * A * A
        _check_range(element, A, "D", dashpot)
        if _underflowed(dashpot, rate):
            lost.add("D")
        dissipation += dashpot
    branches, error = element.branches, 0.0
    if branches is not None and branches.continuum:
        k, d, error = spectrum_integral(element, A, tolerance)
        if abs(k) < sys.float_info.min:
            lost.add("K")
        if abs(d) < sys.float_info.min and A > branches.eta[0]:  # some branches slip
            lost.add("D")
        stiffness, dissipation = stiffness + k, dissipation + d
    elif branches is not None:
        eta = branches.yield_displacement
        k, d = branch_forms(branches.stiffness, eta, A)
        slipping = (eta > 0) & (eta < A)  # K > 0 and D > 0 in truth
        if np.any(slipping & (k < sys.float_info.min)):
            lost.add("K")
        if np.any(slipping & (d < sys.float_info.min)):
            lost.add("D")
        stiffness += math.fsum(k.tolist())
        dissipation += math.fsum(d.tolist())
    return stiffness, dissipation, error


def exact_harmonic(element, amplitude: float, frequency: Optional[float],
                   tolerance: float = DEFAULT_TOLERANCE) -> tuple:
    """``(a_1, b_1)`` (N) of the steady cycle of a rate-independent ``element`` (see :func:`exact_forms`):
    a_1 = K A, b_1 = D / (pi A)."""
    stiffness, dissipation, _ = exact_forms(element, amplitude, frequency, tolerance, set())
    return stiffness * amplitude, dissipation / (math.pi * amplitude)


def spectrum_integral(element, amplitude: float, tolerance: float) -> tuple:
    """``(K, D, estimated relative error)`` of a spectrum of branches (the continuum): the branch forms
    integrated over s by Gauss-Legendre (:func:`closed_forms.spectrum_forms`), the nodes doubled from
    FIRST_NODES until a_1 = K A and b_1 = D / (pi A) each change by at most the tolerance (:func:`relative_change`);
    the error is that last change. FrequencyError past MAX_NODES."""
    A = amplitude
    nodes, previous = FIRST_NODES, None
    while True:
        k, d = spectrum_forms(element.branches, [A], nodes)
        harmonic = complex(float(k[0]) * A, float(d[0]) / (math.pi * A))
        if previous is not None:
            change = relative_change(harmonic, previous)
            if change <= tolerance:
                return float(k[0]), float(d[0]), change
            if nodes >= MAX_NODES:
                raise FrequencyError(f"{element.source}: at A = {A!r} m the integral over the spectrum did not "
                                     f"converge to {tolerance:g} relative by {MAX_NODES} nodes (the last two "
                                     f"differ by {change:.3g} relative)")
        previous, nodes = harmonic, 2 * nodes


def _fresh_branches(element, k):
    if element.branches is None:
        return None
    if stack.is_stack(k):
        return stack.fresh_state(k, 0.0)
    return np.array(element.branches.u0, dtype=float)


# ----------------------------------------------------------------- quadrature: a sampled steady cycle

def quadrature_harmonic(element, amplitude: float, frequency: float, tolerance: float) -> tuple:
    """``(a_1, b_1, estimated relative error)`` of the steady cycle by the refined quadrature (see the
    module): the error is the larger of the last two changes under a doubling of N (one alone can be small by
    chance where a kink of the force falls between samples) plus the settling remainder; FrequencyError when
    it does not settle or converge within the bounds."""
    previous, changes = None, []
    samples = FIRST_SAMPLES
    error = math.inf
    while True:
        harmonic, remainder = steady_harmonic(element, amplitude, frequency, samples, tolerance)
        if previous is not None:
            changes.append(relative_change(harmonic, previous))
            if len(changes) >= 2:
                error = max(changes[-2:]) + remainder
                if error <= tolerance:
                    return harmonic.real, harmonic.imag, error
        if samples >= MAX_SAMPLES:
            raise FrequencyError(f"{element.source}: at A = {amplitude!r} m the first harmonic did not settle to "
                                 f"{tolerance:g} relative by {MAX_SAMPLES} samples per cycle (its estimated "
                                 f"error is {error:.3g} relative)")
        previous, samples = harmonic, 2 * samples


def steady_harmonic(element, amplitude: float, frequency: float, samples: int, tolerance: float) -> tuple:
    """``(a_1 + i b_1 (N), remainder)`` of the steady cycle sampled at ``samples`` points: cycles from x = 0
    and the initial state until two successive cycles agree to tolerance / 4 (with the geometric tail of their
    differences: the remainder, :func:`settling_remainder`; 0 for a cycle that repeats to rounding)."""
    period = 1.0 / frequency
    step = period / samples
    scene = dataclasses.replace(element, solver=dataclasses.replace(element.solver, step=step))  # the delay's grid
    model = compile_model(scene, choose_branch_kernel(scene, "projected"))
    u = _fresh_branches(scene, model[4])
    theta = 2.0 * math.pi * np.arange(1, samples + 1) / samples
    xs = amplitude * np.sin(theta)
    xs[-1] = 0.0  # the cycle ends where it started
    vs = amplitude * 2.0 * math.pi * frequency * np.cos(theta)
    durations = np.full(samples, step)
    forces = np.empty(samples)
    sine, cosine = 2.0 / samples * np.sin(theta), 2.0 / samples * np.cos(theta)
    memory = has_memory(model[8])
    x, v, t = 0.0, amplitude * 2.0 * math.pi * frequency, 0.0
    harmonic, change, changes = None, math.inf, []
    for cycle in range(MAX_CYCLES):
        if memory:
            drive_with_memory(model, u, x, v, cycle * period, xs, vs, durations, forces, None)
        else:
            drive(model, u, x, xs, vs, durations, forces, None)
        x, v = xs[-1], vs[-1]
        if not np.all(np.isfinite(forces)):
            raise FrequencyError(f"{element.source}: at A = {amplitude!r} m the force is not finite (an overflow)")
        new = complex(float(forces @ sine), float(forces @ cosine))
        if harmonic is not None:
            change = relative_change(new, harmonic)
            changes.append(change)
            if abs(new - harmonic) <= ROUNDING * abs(new):
                return new, 0.0
            if settled(changes, tolerance):
                return new, settling_remainder(changes)
        harmonic = new
    raise FrequencyError(f"{element.source}: at A = {amplitude!r} m the cycle did not settle within {MAX_CYCLES} "
                         f"cycles (f = {float(frequency)!r} Hz): the first harmonic still changed by {change:.3g} "
                         "relative per cycle")


# A part of the first harmonic below this fraction of |a_1 + i b_1| is measured against that fraction (its own
# relative change is rounding noise: D of a cycle that does not slip).
NEGLIGIBLE = 1e-9
# A change of a_1 + i b_1 from one cycle to the next this small against |a_1 + i b_1| is rounding: the cycle
# repeats (the smaller part's own relative change may then still be well above it).
ROUNDING = 1e-12


def relative_change(new: complex, old: complex) -> float:
    """The larger relative change of a_1 (so K) and of b_1 (so D) from ``old`` to ``new``: each measured against
    its own size (at least NEGLIGIBLE |new|), so that the small one of the two (K in deep macro-slip, D in
    micro-slip) is converged too, not only |a_1 + i b_1|."""
    floor = NEGLIGIBLE * abs(new)
    if floor == 0.0:
        return 0.0 if new == old else math.inf
    return max(abs(new.real - old.real) / max(abs(new.real), floor),
               abs(new.imag - old.imag) / max(abs(new.imag), floor))


# ----------------------------------------------------------------- a network's joint

def joint_element(scene, between: str):
    """The elements of network ``scene`` joining the two nodes ``between`` ("i,j") as one element scene: their
    springs, cubic springs, dashpots and branches in parallel (sliders as Coulomb friction alpha), driven in the
    relative displacement x_j - x_i by :func:`describe_amplitudes` (the joint's force against the relative
    amplitude). FrequencyError when the names are not two nodes or no element joins them."""
    from . import scene_of_document

    names = [name.strip() for name in str(between).split(",")]
    nodes = scene.network.nodes
    if len(names) != 2 or any(name not in nodes and name != "ground" for name in names) or names[0] == names[1]:
        raise FrequencyError(f"--between: must be two different nodes of {scene.source} (or ground) as i,j "
                             f"({', '.join(nodes)}), got {between!r}")
    ends = {-1 if name == "ground" else nodes.index(name) for name in names}
    joint = [e for e in scene.network.elements if set(e.between) == ends]
    if not joint:
        raise FrequencyError(f"--between: no element joins {names[0]} and {names[1]} in {scene.source}")
    total = {kind: sum(e.value for e in joint if e.kind == kind) for kind in ("spring", "cubic", "dashpot", "slider")}
    branches = [e for e in joint if e.kind == "branch"]
    doc = {"name": f"{scene.name}-{names[0]}-{names[1]}", "mass": {"m": 1.0}}
    if total["spring"] > 0:
        doc["spring"] = {"k0": total["spring"]}
    if total["cubic"] > 0:
        doc["cubic"] = {"k3": total["cubic"]}
    if total["dashpot"] > 0:
        doc["damper"] = {"c": total["dashpot"]}
    if total["slider"] > 0:
        doc["friction"] = {"alpha": total["slider"]}
    if branches:
        doc["branches"] = {"k": [e.value for e in branches], "eta": [e.eta for e in branches],
                           "u0": [e.sense * e.u0 for e in branches]}
        if any(e.c > 0 for e in branches):
            doc["branches"]["c"] = [e.c for e in branches]
    return scene_of_document(doc, f"{scene.source} ({names[0]}-{names[1]})")[0]
