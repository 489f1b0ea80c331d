"""A resonance that friction cannot hold: Den Hartog's bound, for any scene whose nonlinear forces are bounded.

A mass on a spring and a Coulomb slider, forced by F0 cos(omega t) with F0 > 4 alpha / pi, has no periodic state
at its natural frequency (Den Hartog 1931): the force's work per period, pi F0 A, outgrows what the slider can
take, at most 4 alpha A. A curve from below climbs towards it without bound, so no curve passes that frequency.
The same holds for a scene of nodes

    M x'' + C x' + K x + g(t) = f cos(omega t),    |d_j . g| bounded element by element,

K and C the linear springs and dashpots, g the forces of the elements whose force is bounded: a slider (alpha), a
Prandtl branch (k eta: its spring's elongation stays within eta, also behind a series dashpot), Coulomb friction
on the mass (its static threshold alpha), Dahl's friction (its level: where |F| > force, F' has the sign that
shrinks |F| whichever way the mass moves, so a periodic F stays within it). Let phi be a mode of the springs
alone, K phi = omega_r^2 M phi, that no dashpot damps (C phi = 0). A periodic x at omega_r, projected on phi and
weighed by cos(omega_r t) over a period, loses its linear part (phi' (M x'' + K x) = phi' M (x'' + omega_r^2 x)
integrates to 0 against cos, and C phi = 0), so

    phi' f T / 2 = integral of phi' g(t) cos(omega_r t) dt,   |right| <= sum_j b_j |d_j . phi| 2 T / pi,

b_j the bound of element j's force and d_j its direction (x_p - x_q). Where |phi' f| > 4 / pi sum_j b_j
|d_j . phi|, no periodic state (of any period that omega_r divides) exists at omega_r: not in time, and not by
harmonic balance either (the same projection of its first harmonic). :func:`refuse_unbounded` refuses such a
curve before it starts, in one line that says where, why and what to change. Under base excitation the force
is M 1 Y0 omega^2 in coordinates relative to the ground.

The bound is a proof of refusal only: below it a periodic state may or may not exist, and the continuation
answers (a resonance it climbs without bound is refused past its bound of points, saying where). The check
applies where every force besides springs and dashpots is bounded and every node has a mass (a delay, a history
or a spectrum of branches: not checked). A cubic spring is unbounded, and so is a massless node's lever with a
series dashpot (``series._maxwell``: a Maxwell element written with its node), but one whose direction the mode
leaves alone (d . phi = 0: a joint between two nodes that move as one in the mode) projects to phi' d f = 0
whatever its force: of a mode's undamped vectors, those that stretch none of them (the null space of their rows,
as of C) are checked; a mode all of whose vectors stretch one is not. Repeated modes: each of the mode's
vectors that no dashpot damps, and the one of them the force drives most, are checked.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from . import FrequencyError

CLUSTER = 1e-9  # modes within this relative distance of omega_r^2 are one repeated mode
UNDAMPED = 1e-12  # C phi below this share of |C| |phi|: no dashpot damps the mode
MARGIN = 1e-9  # the bound exceeded by more than rounding
ROUNDING = 1e-12  # an element's stretch along a mode (|phi| <= 1) below this share of its row's size is 0


def _element_parts(scene, kinetic: bool = False) -> Optional[tuple]:
    """``(M, K, C, rows, bounds, node names)`` of an element scene with [mass], or None where the check does not
    apply (see the module); ``kinetic``: the friction's bound its sliding level at large speed (alpha_kinetic of
    Stribeck's drop), that of a large motion (:func:`refuse_unbounded`)."""
    if scene.mass is None or scene.cubic is not None or any(
            getattr(scene, name) is not None for name in ("delay", "history")):
        return None
    rows, bounds = [], []
    if scene.branches is not None:
        if scene.branches.continuum:
            return None
        for k, eta in zip(scene.branches.stiffness.tolist(), scene.branches.yield_displacement.tolist()):
            rows.append([1.0])
            bounds.append(k * eta)
    if getattr(scene, "dahl", None) is not None:  # its force never leaves [-force, force] on a periodic state
        rows.append([1.0])
        bounds.append(float(scene.dahl.force))
    if scene.friction is not None:
        rows.append([1.0])
        friction = scene.friction
        bounds.append(friction.alpha_kinetic if kinetic else max(friction.alpha, friction.alpha_kinetic))
    k0 = 0.0 if scene.spring is None else float(scene.spring.k0)
    c = float(scene.damper.c) if scene.has_dashpot else 0.0
    return (np.array([float(scene.mass.m)]), np.array([[k0]]), np.array([[c]]), np.array(rows).reshape(-1, 1),
            np.array(bounds), ("mass",), np.zeros((0, 1)))


def _network_parts(network) -> Optional[tuple]:
    """As :func:`_element_parts`, for a network, with the rows of its unbounded elements last (cubic springs, a
    massless node's springs and dashpot: of a mode, the vectors that stretch one are not checked)."""
    n = network.n
    if np.any(np.asarray(network.mass) <= 0):
        return None
    K, C, rows, bounds, loose = np.zeros((n, n)), np.zeros((n, n)), [], [], []
    for element in network.elements:
        if element.kind == "lever" and element.unbounded:  # a dashpot lever (Maxwell, Bingham): not bounded
            loose.append(element.row(n))
            continue
        if element.kind == "lever":  # a massless node's slider or branch (series.condensed)
            rows.append(element.row(n))
            bounds.append(element.alpha)
            continue
        d = np.zeros(n)
        p, q = element.between
        d[p] += 1.0
        if q >= 0:
            d[q] -= 1.0
        if element.kind == "spring":
            K += element.value * np.outer(d, d)
        elif element.kind == "dashpot":
            C += element.value * np.outer(d, d)
        elif element.kind == "slider":
            rows.append(d)
            bounds.append(element.value)
        elif element.kind == "branch":
            rows.append(d)
            bounds.append(element.value * element.eta)
        elif element.kind == "cubic":
            loose.append(d)
        else:  # no other kind's force is known bounded
            return None
    return (np.array(network.mass, dtype=float), K, C, np.array(rows, dtype=float).reshape(-1, n),
            np.array(bounds, dtype=float), tuple(network.nodes), np.array(loose, dtype=float).reshape(-1, n))


def refuse_unbounded(scene, force_amplitude: Optional[float], base_amplitude: Optional[float], low: float,
                     high: float, load_node: Optional[str] = None, shares: Optional[dict] = None) -> None:
    """FrequencyError where a mode of the springs alone, undamped, lies in [low, high] (rad/s) and the force
    drives it beyond what the bounded forces can take (see the module); else nothing. ``shares``: {node: share}
    of the force where a massless node loaded passes it on (``series.Observed``), else it acts on
    ``load_node``."""
    from ..network.model import NetworkScene

    if isinstance(scene, NetworkScene):
        nodes = scene.network.nodes
        load = np.zeros(len(nodes))
        if shares:
            for name, share in shares.items():
                load[nodes.index(name)] = share
        elif load_node is not None and load_node not in nodes:
            return  # refused where the load node is read, with the nodes listed
        else:
            load[scene.network.load_node if load_node is None else nodes.index(load_node)] = 1.0
        parts = _network_parts(scene.network)
    else:
        parts = _element_parts(scene)
        load = np.ones(1)
    if parts is None:
        return
    _check(scene, parts, load, force_amplitude, base_amplitude, low, high, False)
    friction = getattr(scene, "friction", None)
    if not isinstance(scene, NetworkScene) and friction is not None and friction.alpha_kinetic < friction.alpha:
        # Stribeck's drop: a large motion slides at speeds where the friction is alpha_kinetic (the drop's
        # exp(-|v| / v_s) is left only over the turns, a share that shrinks as 1 / amplitude): Den Hartog's bound
        # with alpha_kinetic is that of the curve's large amplitudes, which climb without bound towards the mode
        _check(scene, _element_parts(scene, kinetic=True), load, force_amplitude, base_amplitude, low, high, True)


def _check(scene, parts, load, force_amplitude, base_amplitude, low, high, kinetic) -> None:
    """:func:`refuse_unbounded` on ``parts`` (``kinetic``: the bounds of a large motion)."""
    mass, K, C, rows, bounds, nodes, loose = parts
    scale = 1.0 / np.sqrt(mass)
    values, vectors = np.linalg.eigh(scale[:, None] * K * scale[None, :])
    shapes = scale[:, None] * vectors  # K phi = lambda M phi
    damping = float(np.max(np.abs(C)))
    start = 0
    while start < values.size:  # each mode, its repeated values together
        stop = start + 1
        while stop < values.size and values[stop] - values[start] <= CLUSTER * abs(values[start]):
            stop += 1
        value, cluster = float(values[start:stop].mean()), shapes[:, start:stop]
        start = stop
        if value <= 0 or not low * low * (1 - CLUSTER) <= value <= high * high * (1 + CLUSTER):
            continue
        free = _undamped(cluster, C, damping)
        if free.shape[1] and loose.size:  # of those, the vectors that stretch no unbounded element
            free = _undamped(free, loose, 1.0)
        if free.shape[1] == 0:
            continue
        omega = math.sqrt(value)
        if base_amplitude is None:
            force = force_amplitude * load
        else:
            force = mass * base_amplitude * omega * omega
        # the mode's vectors, and the one among them the force drives most
        for phi in [free[:, j] for j in range(free.shape[1])] + [free @ (free.T @ force)]:
            if not np.any(phi):
                continue
            phi = phi / np.max(np.abs(phi))
            drive = abs(float(phi @ force))
            stretch = np.abs(rows @ phi)  # of each bounded element along the mode (|phi| <= 1), rounding left out
            stretch[stretch <= ROUNDING * np.sum(np.abs(rows), axis=1)] = 0.0
            hold = 4.0 / math.pi * float(np.sum(bounds * stretch))
            # a force orthogonal to the mode up to rounding does not drive it (its states are a family, not an
            # unbounded growth): only a drive above the rounding of phi . f counts
            # at the kinetic level: a force that never passes the static level alpha (the element has one node)
            # leaves the mass at rest, a periodic state at every frequency (a review's find: refused before)
            static = kinetic and drive <= float(scene.friction.alpha) * (1 + MARGIN)
            if drive > hold * (1 + MARGIN) and drive > 1e-9 * float(np.sum(np.abs(force))) and not static:
                _refuse(scene, nodes, phi, omega, drive, hold, force_amplitude, base_amplitude, kinetic)


def _undamped(cluster: np.ndarray, C: np.ndarray, damping: float) -> np.ndarray:
    """The vectors of the mode (columns of ``cluster``) that no dashpot damps: a basis of those with C phi = 0
    (to UNDAMPED of ``damping``, |C|'s size). With the rows of the unbounded elements for C (a cubic spring, a
    massless node's springs and dashpot) and 1 for their size: those that stretch none of them."""
    if damping == 0.0:
        return cluster
    _, sigma, right = np.linalg.svd(C @ cluster)
    size = np.max(np.abs(cluster))
    rank = int(np.sum(sigma > UNDAMPED * damping * size * math.sqrt(cluster.shape[0])))
    return cluster @ right[rank:].T


def _refuse(scene, nodes, phi, omega, drive, hold, force_amplitude, base_amplitude, kinetic=False) -> None:
    f = omega / (2 * math.pi)
    shape = ", ".join(f"{name} {value:.3g}" for name, value in zip(nodes, phi))
    if hold == 0.0 and not kinetic:  # nothing bounded acts along the mode: an undamped linear resonance
        raise FrequencyError(
            f"{scene.source}: no periodic state at f = {f:.6g} Hz: no dashpot acts on the springs' mode there "
            f"(shape {shape}), nor any slider, branch or friction, and "
            f"{'the force' if base_amplitude is None else 'the moving base'} drives it, so its amplitude grows "
            f"without bound (an undamped linear resonance): leave {f:.6g} Hz out of the frequencies, or put a "
            "dashpot on that mode")
    if base_amplitude is None:
        what, cure = "the force", f"a force amplitude below {force_amplitude * hold / drive:.6g} N"
    else:
        what, cure = "the moving base (m Y0 omega^2)", f"a base amplitude below {base_amplitude * hold / drive:.6g} m"
    if kinetic:
        raise FrequencyError(
            f"{scene.source}: the curve climbs without bound towards f = {f:.6g} Hz: no dashpot acts on the "
            f"springs' mode there (shape {shape}), and at large amplitude the friction slides at its kinetic level "
            f"alpha_kinetic = {scene.friction.alpha_kinetic:g} N (Stribeck's drop), so {what} drives it with "
            f"{drive:.6g} N, more than the most its friction and branches can hold at large amplitude, {hold:.6g} N "
            f"(Den Hartog's bound): leave {f:.6g} Hz out of the frequencies, or give {cure}, or a dashpot on that "
            "mode")
    raise FrequencyError(
        f"{scene.source}: no periodic state at f = {f:.6g} Hz: no dashpot acts on the springs' mode there (shape "
        f"{shape}), and {what} drives it with {drive:.6g} N, more than the most its friction, sliders and branches "
        f"can hold, {hold:.6g} N (4 / pi of their forces along the mode: Den Hartog's bound), so its amplitude grows "
        f"without bound: leave {f:.6g} Hz out of the frequencies, or give {cure}, or a dashpot on that mode")


# a resonance of the stuck branches held only by the first slip: refused where the top of its curve, a plateau
# within this relative height of the amplitude the first branch slips at, is finer than the sampled slip resolves
PLATEAU = 0.05


def refuse_slip_limited(system, force_amplitude: Optional[float], base_amplitude: Optional[float], low: float,
                        high: float) -> None:
    """FrequencyError where a mode of the system with every branch stuck (springs and branches' k), undamped,
    lies in [low, high] (rad/s), driven, and held only by the slip of its branches, with a top too flat for
    harmonic balance: at modal amplitude a* the first branch (i) slips, and the work of the force per period,
    pi (phi . f) a, is taken by its slip, 4 k_i eta_i (e_i a - eta_i) (e_i = |d_i . phi|), at
    a = a* (1 + h), h = pi (phi . f) a* / (4 sum k_i eta_i^2): the curve's top is a plateau of relative height h
    over a band |omega_r^2 - omega^2| < (phi . f) / (phi' M phi a*) on which the phase turns by pi. The sampled
    slip (``aft.py``: the turning points between the samples, off by up to pi^2 / (2 N^2) of the excursion)
    turns it into a staircase of kinks: below h = PLATEAU the continuation folds back and forth on it (F0 = 300 N
    on hard/large-forces, h = 0.03: 266 folds; F0 = 1000 N, h = 0.1: 36; none with N = 16384) or stops (h < 0.02).
    The check applies to a system of masses, springs, dashpots and branches without series dashpots."""
    if system.cubic_k3.size or system.series or system.memory is not None or not system.branch_k.size or \
            np.any(system.mass <= 0):
        return
    n = system.n
    rows = np.zeros((system.branch_k.size, n))
    for j, (p, q) in enumerate(system.branch_ends.tolist()):
        rows[j, p] += 1.0
        if q >= 0:
            rows[j, q] -= 1.0
    K = system.stiffness + rows.T @ (system.branch_k[:, None] * rows)
    C, mass = system.damping, system.mass
    scale = 1.0 / np.sqrt(mass)
    values, vectors = np.linalg.eigh(scale[:, None] * K * scale[None, :])
    shapes = scale[:, None] * vectors
    damping = float(np.max(np.abs(C)))
    for value, phi in zip(values.tolist(), shapes.T):
        if value <= 0 or value + value < low * low:  # (the band's overlap with the range is checked below)
            continue
        if _undamped(phi[:, None], C, damping).shape[1] == 0:
            continue
        omega = math.sqrt(value)
        if base_amplitude is None:
            force = np.zeros(n)
            force[system.load_node] = force_amplitude
        else:
            force = mass * base_amplitude * value
        phi = phi / np.max(np.abs(phi))
        drive = abs(float(phi @ force))
        e = np.abs(rows @ phi)
        acting = e > 1e-9
        if drive <= 1e-9 * float(np.sum(np.abs(force))) or not np.any(acting):
            continue  # not driven; or no branch along the mode: refuse_unbounded's undamped linear resonance
        onset = system.branch_eta[acting] / e[acting]
        first = float(np.min(onset))
        held = onset <= first * (1 + 1e-9)
        eta, k = system.branch_eta[acting][held], system.branch_k[acting][held]
        h = math.pi * drive * first / (4.0 * float(np.sum(k * eta * eta)))
        if h >= PLATEAU:
            continue
        modal = float(phi @ (mass * phi))
        band = drive / (modal * first)  # of omega^2 on either side of omega_r
        f = omega / (2 * math.pi)
        below, above = math.sqrt(max(value - band, 0.0)) / (2 * math.pi), math.sqrt(value + band) / (2 * math.pi)
        if above * 2 * math.pi < low or below * 2 * math.pi > high:  # the plateau's band outside the range
            continue
        i = int(np.argmax(np.abs(phi)))
        what = "a force amplitude" if base_amplitude is None else "a base amplitude"
        given = force_amplitude if base_amplitude is None else base_amplitude
        raise FrequencyError(
            f"{system.source}: at f = {f:.6g} Hz the branches, stuck, resonate with no dashpot on the mode, held "
            f"only by the slip of the first branch: the top of the curve is a plateau at {first:.6g} m at node "
            f"{system.nodes[i]} (within {h:.3g} relative), {above - below:.3g} Hz wide, finer than harmonic balance's "
            f"sampled slip resolves: leave {below!r} to {above!r} Hz out of the frequencies (the curve "
            f"either side of it is the stuck, linear response), or give {what} of at least "
            f"{_up(given * PLATEAU / h)}, or a dashpot on that mode")


def _up(value: float) -> str:
    """``value`` to 3 significant digits, rounded up (a suggested least force that the check then passes)."""
    if value <= 0:
        return f"{value:.3g}"
    exponent = math.floor(math.log10(value)) - 2
    return f"{math.ceil(value / 10**exponent * (1 - 1e-12)) * 10**exponent:.3g}"
