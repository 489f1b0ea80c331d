"""K(A), D(A) and the loss factor: the element driven in displacement to its steady cycle.

The element (its springs, branches, dashpots, Masing backbone, Dahl, continuum or spectrum; not its mass) is
driven by x = A sin(theta), theta = 2 pi f t, from x = 0 and its initial state. On the steady cycle the force
has the first harmonic a_1 sin(theta) + b_1 cos(theta),

    a_1 = (1/pi) int_0^{2 pi} F sin(theta) d theta,     b_1 = (1/pi) int_0^{2 pi} F cos(theta) d theta,

and the results are

    K(A) = a_1 / A                       (N/m)   the effective (secant, describing-function) stiffness,
    D(A) = oint F dx = pi A b_1          (J)     the energy dissipated per cycle,
    loss factor = D / (pi K A^2) = b_1 / a_1.

Two methods, chosen from the scene:

* ``exact`` (parallel springs, a cubic spring, a dashpot, Prandtl branches on either kernel, a Masing backbone;
  plain Coulomb friction): the branches are rate independent and piecewise linear, so once x has been to A
  and to -A every branch that slips in the steady cycle has slipped, and the next excursions repeat exactly
  (checked). Between two slip events the force is linear in x; the events of each half cycle are known from
  the elongations at the reversal (a branch sticking at u slips after eta - u more), so the cycle is driven
  through exactly those points (one compiled call per half cycle) and integrated in closed form segment by
  segment: int F dx by the trapezoid (exact on a line), int F x / sqrt(A^2 - x^2) dx with the antiderivatives
  -sqrt(A^2 - x^2) and (A^2/2) asin(x/A) - (x/2) sqrt(A^2 - x^2). No sampling error: rounding only. The cubic
  spring adds 3/4 k3 A^2 to K and nothing to D; the dashpot pi c omega A^2 to D; Coulomb friction alpha on
  the mass 4 alpha A to D and nothing to K;
* ``quadrature`` (the continuum, Dahl, branches with series dashpots, a delay, a history): N samples per
  cycle, the force at each from the exact moves between samples (x linear in between), cycles repeated until
  the first harmonic settles (:func:`prandtl_fmu.frequency.settled`: the last change and the geometric tail of
  those to come within a quarter of the tolerance; or a cycle that repeats to rounding), the trapezoid rule
  in theta for a_1, b_1; N doubled from 64 until two successive N agree to the tolerance (1e-3 relative by
  default), a_1 and b_1 each against its own size
  (:func:`relative_change`: K and D both to the tolerance). Past 2^16 samples per cycle or MAX_CYCLES
  cycles, the amplitude is refused with what was reached (deep macro-slip, where the stick after a reversal
  is shorter than a sample, is the usual case).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..compiled import choose_branch_kernel, compile_model
from ..kernels import stack
from ..kernels.drive import drive, drive_with_memory
from ..kernels.play import write_elongations
from ..loads import ConstantLoad
from ..memory import has_memory
from ..stepping import _progress_bar
from . import DEFAULT_TOLERANCE, FrequencyError, check_tolerance, positive_values, settled

# The quadrature's first and last number of samples per cycle, and the most cycles run to reach the steady one.
FIRST_SAMPLES = 64
MAX_SAMPLES = 2**16
MAX_CYCLES = 400


@dataclass(frozen=True, eq=False)
class Description:
    """K(A), D(A) and the loss factor at each amplitude: arrays of shape (amplitudes,).

    ``amplitude`` A (m), ``stiffness`` K (N/m), ``dissipation`` D (J per cycle), ``loss_factor``
    D / (pi K A^2); ``method`` "exact" or "quadrature" for each; ``error`` the estimated relative error of
    the first harmonic (0 for exact: rounding only); ``frequency`` (Hz) of the cycles, None for a rate-
    independent element (whose results do not depend on it).
    """

    amplitude: np.ndarray
    stiffness: np.ndarray
    dissipation: np.ndarray
    loss_factor: np.ndarray
    method: tuple
    error: np.ndarray
    frequency: Optional[float]

    def columns(self) -> dict:
        """The CSV's columns: amplitude, stiffness, dissipation, loss_factor (the contract), method, error."""
        return {"amplitude": self.amplitude, "stiffness": self.stiffness, "dissipation": self.dissipation,
                "loss_factor": self.loss_factor, "method": list(self.method), "error": self.error}


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
    return names


def describe_amplitudes(scene, amplitudes, frequency: Optional[float] = None, *,
                        tolerance: float = DEFAULT_TOLERANCE, progress: Optional[bool] = None) -> Description:
    """K(A), D(A) and the loss factor of ``scene``'s element at each of ``amplitudes`` (m, > 0) (see the module).

    ``frequency`` (Hz, > 0) of x = A sin(2 pi f t): required by a rate-dependent element (dashpot, series
    dashpots, delay, history), ignored otherwise. ``tolerance``: the relative accuracy of the quadrature.
    FrequencyError names the culprit (bad input, or an amplitude whose cycle does not settle or converge)."""
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
    coulomb = _coulomb_threshold(scene)
    element = dataclasses.replace(scene, mass=None, friction=None, load=ConstantLoad(0.0), causality="force")
    exact = _is_piecewise_linear(element)
    rows = []
    bar = _progress_bar(progress, total=amplitudes.shape[0], label=f"{scene.name} describe")
    try:
        for amplitude in amplitudes.tolist():
            if exact:
                a1, b1 = exact_harmonic(element, amplitude, frequency)
                error, method = 0.0, "exact"
            else:
                a1, b1, error = quadrature_harmonic(element, amplitude, frequency or 1.0, tolerance)
                method = "quadrature"
            b1 += 4.0 * coulomb / math.pi  # alpha sgn(cos theta): b_1 = 4 alpha / pi, a_1 = 0
            rows.append(_row(scene, amplitude, a1, b1, error, method))
            bar.update(1)
    finally:
        bar.close()
    table = np.array([row[:5] for row in rows], dtype=float)
    return Description(table[:, 0], table[:, 1], table[:, 2], table[:, 3], tuple(row[5] for row in rows),
                       table[:, 4], frequency)


def _row(scene, amplitude, a1, b1, error, method) -> tuple:
    stiffness = a1 / amplitude
    dissipation = math.pi * amplitude * b1
    loss = b1 / a1 if a1 != 0 else math.inf
    for name, value in (("K", stiffness), ("D", dissipation), ("the loss factor", loss)):
        if not math.isfinite(value):
            raise FrequencyError(f"{scene.source}: at A = {amplitude!r} m, {name} is not a finite number (K = "
                                 f"{stiffness!r} N/m): the element has no stiffness in phase with x there")
    return amplitude, stiffness, dissipation, loss, error, method


def _coulomb_threshold(scene) -> float:
    """alpha (N) of plain Coulomb friction of the mass on a fixed ground (0 without); FrequencyError for a
    Stribeck drop or a moving belt (not part of an element driven in displacement)."""
    friction = scene.friction
    if friction is None:
        return 0.0
    if friction.stribeck_velocity is not None or friction.belt_velocity != 0.0:
        raise FrequencyError(f"{scene.source}: [friction] with a Stribeck drop or a moving belt depends on the "
                             "velocity's size and the belt: describe takes plain Coulomb friction on a fixed "
                             "ground only")
    return float(friction.alpha)


def _is_piecewise_linear(element) -> bool:
    """Whether the exact method applies: no continuum, no series dashpots, no memory."""
    branches = element.branches
    return not (branches is not None and branches.continuum) and not element.has_series_dashpots \
        and element.delay is None and element.history is None and element.dahl is None


# ----------------------------------------------------------------- exact: the piecewise-linear cycle

def exact_harmonic(element, amplitude: float, frequency: Optional[float]) -> tuple:
    """``(a_1, b_1)`` (N) of the steady cycle of a piecewise-linear ``element`` (massless) under x = A sin(theta),
    in closed form segment by segment (see the module)."""
    A = float(amplitude)
    springs = dataclasses.replace(element, cubic=None, damper=None)  # k0 and the branches: linear between events
    model = compile_model(springs, choose_branch_kernel(springs, "projected"))
    k = model[4]
    u = _fresh_branches(springs, k)
    eta = springs.branches.yield_displacement if springs.branches is not None else np.zeros(0)

    def move(path, start):
        path = np.ascontiguousarray(path, dtype=float)
        forces = np.empty_like(path)
        zeros = np.zeros_like(path)
        drive(model, u, start, path, zeros, zeros, forces, None)
        return forces

    move(np.array([A, -A]), 0.0)  # the first quarter, the first descent: every branch that will slip has slipped
    at_bottom = _elongations(springs, k, u)
    force_bottom = move(np.array([A, -A]), -A)[-1]
    scale = max(A, float(np.max(eta, initial=0.0)))
    if not np.allclose(_elongations(springs, k, u), at_bottom, rtol=0.0, atol=1e-12 * scale):
        raise FrequencyError(f"{element.source}: at A = {A!r} m the cycle of the branches does not repeat after "
                             "the second excursion (a rate-independent element must): please report it")
    up = np.concatenate((_events(-A + eta - at_bottom, A, rising=True), [A]))
    forces_up = move(up, -A)
    at_top = _elongations(springs, k, u)
    down = np.concatenate((_events(A - eta - at_top, A, rising=False), [-A]))
    forces_down = move(down, A)
    work_up, moment_up = line_integrals(np.concatenate(([-A], up)), np.concatenate(([force_bottom], forces_up)), A)
    work_down, moment_down = line_integrals(np.concatenate(([A], down)),
                                            np.concatenate(([forces_up[-1]], forces_down)), A)
    a1 = (moment_up - moment_down) / (math.pi * A)
    b1 = (work_up + work_down) / (math.pi * A)
    if element.cubic is not None:
        a1 += 0.75 * element.cubic.k3 * A**3  # k3 A^3 sin^3 = k3 A^3 (3 sin - sin 3 theta) / 4
    if element.has_dashpot:
        b1 += element.damper.c * 2.0 * math.pi * frequency * A  # c v = c omega A cos(theta)
    return a1, b1


def _fresh_branches(element, k):
    if element.branches is None:
        return None
    if stack.is_stack(k):
        return stack.fresh_state(k, 0.0)
    return np.array(element.branches.u0, dtype=float)


def _elongations(element, k, u) -> np.ndarray:
    if element.branches is None:
        return np.zeros(0)
    out = np.empty(element.branches.n)
    write_elongations(k, u, out)
    return out


def _events(points, A, rising: bool) -> np.ndarray:
    """The slip events strictly inside (-A, A), in the order of the motion."""
    inside = np.unique(points[(points > -A) & (points < A)])
    return inside if rising else inside[::-1]


def line_integrals(xs, fs, A) -> tuple:
    """``(int F dx, int F x / sqrt(A^2 - x^2) dx)`` along the polyline through (xs[j], fs[j]) (xs monotone, in
    [-A, A], either direction: oriented integrals), exactly: F is linear on each segment.

    The second is A int F sin(t) dt with x = A sin(t), t = asin(x / A) in [-pi/2, pi/2]; on a segment
    F = F_1 + s (A sin t - x_1) and, with d = t_2 - t_1 and m = (t_1 + t_2) / 2, the integrals
    int sin t dt = 2 sin(m) sin(d / 2) and int sin^2 t dt = d sin^2(m) + cos(2 m) (d - sin d) / 2 are written
    without the cancellation of differences of antiderivatives (which lost digits on short segments)."""
    xs = np.asarray(xs, dtype=float)
    fs = np.asarray(fs, dtype=float)
    x1, x2, f1, f2 = xs[:-1], xs[1:], fs[:-1], fs[1:]
    keep = x2 != x1
    x1, x2, f1, f2 = x1[keep], x2[keep], f1[keep], f2[keep]
    work = float(np.sum(0.5 * (f1 + f2) * (x2 - x1)))
    slope = (f2 - f1) / (x2 - x1)
    t1 = np.arcsin(np.clip(x1 / A, -1.0, 1.0))
    t2 = np.arcsin(np.clip(x2 / A, -1.0, 1.0))
    d = t2 - t1
    mid = 0.5 * (t1 + t2)
    d2 = d * d
    d_minus_sin = np.where(np.abs(d) < 1e-2, d * d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0)), d - np.sin(d))
    sine = 2.0 * np.sin(mid) * np.sin(0.5 * d)
    square = d * np.sin(mid) ** 2 + 0.5 * np.cos(2.0 * mid) * d_minus_sin
    moment = A * float(np.sum((f1 - slope * x1) * sine + slope * A * square))
    return work, moment


# ----------------------------------------------------------------- quadrature: a sampled steady cycle

def quadrature_harmonic(element, amplitude: float, frequency: float, tolerance: float) -> tuple:
    """``(a_1, b_1, estimated relative error)`` of the steady cycle by the refined quadrature (see the
    module); FrequencyError when it does not settle or converge within the bounds."""
    previous = None
    samples = FIRST_SAMPLES
    while True:
        harmonic = steady_harmonic(element, amplitude, frequency, samples, tolerance)
        if previous is not None:
            change = relative_change(harmonic, previous)
            if change <= tolerance:
                return harmonic.real, harmonic.imag, change
        if samples >= MAX_SAMPLES:
            raise FrequencyError(f"{element.source}: at A = {amplitude!r} m the first harmonic did not settle to "
                                 f"{tolerance:g} relative by {MAX_SAMPLES} samples per cycle (the last two "
                                 f"refinements differ by {change:.3g} relative)")
        previous, samples = harmonic, 2 * samples


def steady_harmonic(element, amplitude: float, frequency: float, samples: int, tolerance: float) -> complex:
    """a_1 + i b_1 (N) of the steady cycle sampled at ``samples`` points: cycles from x = 0 and the initial
    state until two successive cycles agree to tolerance / 4 (with the geometric tail of their differences)."""
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
            if abs(new - harmonic) <= ROUNDING * abs(new) or settled(changes, tolerance):
                return new
        harmonic = new
    raise FrequencyError(f"{element.source}: at A = {amplitude!r} m the cycle did not settle within {MAX_CYCLES} "
                         f"cycles (f = {frequency!r} Hz): the first harmonic still changed by {change:.3g} "
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
