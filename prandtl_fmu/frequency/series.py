"""Elements in series through a massless node, joined into one: a Jenkins element written with its node.

A node without mass, without load and with exactly two elements, each a spring, a slider or a branch without a
series dashpot, carries the same force through both at every instant (its balance has no inertia). In series
the compliances add and the weakest slider slides first, so the two are one element of stiffness k and
threshold alpha

    1 / k = 1 / k_1 + 1 / k_2   (a slider: no compliance),    alpha = min(alpha_1, alpha_2)   (a spring: none),

a spring (no threshold), a slider (no compliance) or a branch (k, eta = alpha / k) between the two other ends:
exactly the same force on them, whatever the motion. So a joint written as springs and sliders with their
nodes (an Iwan joint of Jenkins elements, each a spring to a massless node and a slider on from it) is the
network of branches harmonic balance samples exactly, and one with rigid sliders elsewhere is one that shooting
takes (it needs a mass at every node). Two elements whose other ends are the same node (or both the ground) act
on nothing, and go. A massless node held by three or more linear springs alone is their Schur complement (a
spring between each pair of far ends, :func:`_star`); one with a single element carries no force through it
(both go). Joined repeatedly, node by node, until no such node is left. The node's own motion is not
computed: a node named by ``--node``, and the node a force acts on (``--load-node``, else the scene's
``load_node``; none under base excitation), are kept as written (the callers name them in ``keep``).

**Levers** (:func:`condensed`: shooting only, which needs a mass at every node). A massless node p held by
springs k_i (to far ends i, S = sum k_i > 0) and by one threshold element (a slider, a branch, or a lever from a
node condensed before) is in balance at every instant: sum_i k_i (x_i - x_p) = d_p T, T the element's tension
and d_p its weight on p. So x_p = (sum_i k_i x_i - d_p T) / S, and in the element's elongation d . x the node's
share is the springs' weighted mean of their far ends plus a compliance d_p^2 / S in series:

    d'_i = d_i + d_p k_i / S,    1 / k' = 1 / k + d_p^2 / S,    alpha' = alpha,

an element of threshold alpha on the elongation d' . x (a :class:`Lever`: a slider's play, now with a spring,
between weighted means of nodes), and the springs are their Schur complement (k_i k_j / S between each pair of far
ends, as :func:`_star`): the force on every other node is the one the node passed on, exactly, whatever the
motion. A dashpot on the element stays where it is (a branch's series dashpot in series with all of it; a Bingham
lever's beside its slider, below): with u = T / k', the same rows with k' for k. A massless node held by springs
and one dashpot, nothing else, is their Schur complement and a lever with that series dashpot and a range it never
reaches, whose u shooting carries (:func:`_maxwell`; one spring: the Maxwell element between the two far ends).
One held by springs and by a slider and a dashpot side by side to one end (a Bingham element in series with the
springs) is their Schur complement and a lever whose u sticks within alpha / S and relaxes back at S / c past it
(:func:`_bingham`). A massless node between two threshold elements (its position a play of two references), or
with a dashpot otherwise (a first-order motion), is refused, one line; a massless node held by no spring carries
no force through it (its elements go). The node named and the node loaded, and each massless node their motion or
force passes through, are condensed where springs alone hold them, or (named, no force on it) springs and one
slider or branch, with its series dashpot or not, or springs and a dashpot, a slider beside it or not
(:class:`Observed` says how: the force passed on as k_i / S of it, the motion the springs' weighted mean plus F /
S, less the lever's tension times d_p / S); else refused, one line. Harmonic balance takes massless nodes as they
are (their balance is one of its equations): it never sees a lever.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import FrequencyError

JOINED = ("spring", "slider", "branch")
NEVER = 1e200  # the range (m) of a lever with a series dashpot (:func:`_maxwell`): never reached
THRESHOLDS = ("slider", "branch", "lever")


@dataclass(frozen=True, eq=False)
class Lever:
    """A threshold element on the elongation sum_j weights_j x_{between_j} (ground terms dropped): a spring of
    stiffness ``value`` (finite: the node's compliance d_p^2 / S is in series) with a slider of threshold
    ``alpha``; what :func:`condensed` leaves of a massless node between springs and one slider or branch. With
    ``c`` > 0, a dashpot in series too, and a threshold never reached (:func:`_maxwell`: a massless node between
    springs and one dashpot); with ``bingham``, the dashpot beside the slider instead (:func:`_bingham`).
    Shooting's rows (``shooting.NetworkShooting``) and the bound on the forces (``unbounded.py``) read it;
    nothing else does."""

    name: str
    between: tuple
    weights: tuple
    value: float
    alpha: float
    kind: str = "lever"
    c: float = 0.0
    through: tuple = ()  # the massless nodes it was passed through, in order (for the refusals)
    bingham: bool = False  # with ``c``: the dashpot beside the slider, not in series (:func:`_bingham`)

    @property
    def unbounded(self) -> bool:
        """Its force has no bound: the dashpot's lever (its range NEVER) and the Bingham lever (past the slider's
        alpha, the dashpot's share); a lever with its slider in series (a branch's series dashpot) stays within
        alpha."""
        return self.c > 0.0 and (self.bingham or self.alpha >= 0.5 * NEVER * self.value)

    def row(self, n: int) -> np.ndarray:
        """Its elongation's row over the ``n`` nodes."""
        out = np.zeros(n)
        for node, weight in zip(self.between, self.weights):
            out[node] += weight
        return out


def check_named(scene, node=None, load_node=None) -> None:
    """FrequencyError, one line, where ``--node`` or ``--load-node`` names no node of the network as written
    (listing its nodes: joined, the massless ones would be missing from the list)."""
    network = getattr(scene, "network", None)
    if network is None:
        return
    for flag, name in (("--node", node), ("--load-node", load_node)):
        if name is not None and name not in network.nodes:
            raise FrequencyError(f"{flag}: {name!r} is not a node of {scene.source} ({', '.join(network.nodes)})")


def joined(scene, keep=()):
    """``scene`` with every massless node between two elements in series joined (see the module); a network
    scene only (an element scene is returned as is). ``keep``: node names not to join (the loaded node among
    them: the scene's ``load_node`` is not kept unless named, as base excitation loads no node)."""
    from ..network.model import NetworkScene

    if not isinstance(scene, NetworkScene):
        return scene
    network = scene.network
    while True:
        found = _joinable(network, keep)
        if found is None:
            return scene if network is scene.network else dataclasses.replace(scene, network=network)
        node, how = found
        network = how(network, node)


def _joinable(network, keep):
    """``(node, how)`` of the first massless node not in ``keep`` that goes (``how``: :func:`_join`,
    :func:`_star` or :func:`_dangling`), or None."""
    for node, name in enumerate(network.nodes):
        if network.mass[node] > 0 or name in keep:
            continue
        touching = [e for e in network.elements if node in e.between]
        if len(touching) == 1:
            return node, _dangling
        if len(touching) == 2 and all(e.kind in JOINED and e.c == 0.0 for e in touching):
            return node, _join
        if len(touching) > 2 and all(e.kind == "spring" for e in touching):
            return node, _star
    return None


def _stiffness_and_threshold(element) -> tuple:
    if element.kind == "spring":
        return element.value, math.inf
    if element.kind == "slider":
        return math.inf, element.value
    return element.value, element.value * element.eta


def _join(network, node):
    from ..network.model import Element

    first, second = (e for e in network.elements if node in e.between)
    (k1, a1), (k2, a2) = _stiffness_and_threshold(first), _stiffness_and_threshold(second)
    if k1 == 0.0 or k2 == 0.0:
        k = 0.0  # a spring of zero stiffness in series: the two carry no force
    else:
        k = math.inf if math.isinf(k1) and math.isinf(k2) else 1.0 / (1.0 / k1 + 1.0 / k2)
    alpha = min(a1, a2)
    p, q = (e.between[1] if e.between[0] == node else e.between[0] for e in (first, second))
    rest = [e for e in network.elements if e is not first and e is not second]
    if p != q and k > 0.0 and alpha > 0.0:  # else they act on nothing (a zero spring or a zero threshold)
        if p < 0:
            p, q = q, p
        name = f"{first.name}+{second.name}"
        if math.isinf(alpha):
            rest.append(Element("spring", name, (p, q), k))
        elif math.isinf(k):
            rest.append(Element("slider", name, (p, q), alpha))
        else:
            rest.append(Element("branch", name, (p, q), k, alpha / k, 0.0, 0.0))
    return _without(network, node, rest)


def _star(network, node):
    """A massless node held by linear springs alone (three or more): its balance sum k_i (x - x_i) = 0 puts it at
    the springs' weighted mean, and the forces on the far ends are those of a spring k_i k_j / K between each pair
    of them (K = sum k_i: the Schur complement of the node in the stiffness), exactly; springs to one far end are
    summed first, pairs on one end (or both on the ground) act on nothing."""
    touching = [e for e in network.elements if node in e.between]
    ends, total = _spring_ends(touching, node)
    rest = [e for e in network.elements if node not in e.between]
    if total == 0.0:  # springs of zero stiffness: they carry no force
        return _without(network, node, rest)
    return _without(network, node, rest + _complement(network, node, ends, total))


def _complement(network, node, ends, total, kind="spring") -> list:
    """The springs of massless ``node``'s Schur complement: k_i k_j / S between each pair of its springs' far ends
    (``ends`` {far end: k_i}, ``total`` S > 0); ``kind`` "dashpot": of its dashpots, c_i c_j / C."""
    from ..network.model import Element

    far = sorted(ends, reverse=True)  # the ground (-1) last, only ever q: an element to the ground is (p, -1)
    name = network.nodes[node]
    out = []
    for i, p in enumerate(far):
        for q in far[i + 1:]:
            other = "ground" if q < 0 else network.nodes[q]
            called = f"{name}({network.nodes[p]},{other})" + ("" if kind == "spring" else f" {kind}")
            out.append(Element(kind, called, (p, q), ends[p] * ends[q] / total))
    return out


def _dangling(network, node):
    """A massless node with one element: the node's balance holds that element's force at 0, whatever it is:
    both go."""
    return _without(network, node, [e for e in network.elements if node not in e.between])


def _without(network, node, rest):
    """The network without ``node``, its elements ``rest`` (indices as with the node)."""
    # the node goes: the others' indices above it shift down by one
    def shifted(index):
        return index - 1 if index > node else index

    elements = tuple(dataclasses.replace(e, between=tuple(shifted(i) for i in e.between)) for e in rest)
    keep = [i for i in range(network.n) if i != node]
    # the scene's load node joined (no force acts on it: the callers keep the node a force acts on): any node
    load_node = 0 if network.load_node == node else shifted(network.load_node)
    return dataclasses.replace(network, nodes=tuple(network.nodes[i] for i in keep),
                               mass=np.asarray(network.mass)[keep], x0=np.asarray(network.x0)[keep],
                               v0=np.asarray(network.v0)[keep], elements=elements, load_node=load_node)


@dataclass(frozen=True)
class Observed:
    """What :func:`condensed` leaves of the node named and the node loaded: ``load`` {node with a mass: share}
    of the unit force (the loaded node's own, or passed on through massless nodes held by springs alone: k_i /
    S of it to each far end i; the ground's share is the support's), ``views`` {massless node named: (weights,
    gain, tensions)}, its motion x_p = sum_i weights[i] x_i + gain F(t) + sum_e tensions[e] T_e(t) (i a node
    with a mass, or None: the ground's motion, under base excitation; gain 1 / S where the force acts on it;
    T_e the tension of lever e, -d_p / S where p's slider or branch became it)."""

    load: dict
    views: dict


def condensed(scene, named=None, loaded=None, purpose="the forced response", observe=False):
    """``scene`` (a network) with every massless node gone (see the module: springs by their Schur complement,
    a slider or a branch on the node by a :class:`Lever`), or FrequencyError naming the node that cannot go:
    ``named`` (``--node``) and ``loaded`` (the node the force acts on) may be massless where springs alone hold
    them (and each massless node their force or motion passes through): ``observe`` returns ``(scene,``
    :class:`Observed` ``)``, which says how; else they must have a mass. ``purpose`` ("the forced response",
    "the nonlinear modes") for the refusals."""
    network = scene.network
    if not np.any(np.asarray(network.mass) > 0):
        raise FrequencyError(f"{scene.source}: no node has a mass (for {purpose}, one at least must have one: a "
                             "network of massless nodes is quasi-static: integrate it with prandtl-fmu run)")
    load = {} if loaded is None else {loaded: 1.0}
    views = {} if named is None else {named: ({named: 1.0}, 0.0, {})}
    while True:
        node = next((i for i in range(network.n) if not network.mass[i] > 0), None)
        if node is None:
            out = scene if network is scene.network else dataclasses.replace(scene, network=network)
            if not observe:
                return out
            return out, Observed(load, {name: view for name, view in views.items() if name not in network.nodes})
        name = network.nodes[node]
        if name in load or any(name in view[0] for view in views.values()):
            if not observe:
                _refuse_unobserved(name, scene.source, loaded, purpose)
            _pass_through(network, node, load, views, scene.source, named, loaded, purpose)
        network = _lever(network, node, scene.source, purpose)


def _pass_through(network, node, load, views, source, named, loaded, purpose) -> None:
    """``load`` and ``views`` (see :class:`Observed`) with massless ``node`` condensed, held by springs alone
    (and, where no force acts on it, by one slider or branch, with its series dashpot or not, which becomes a
    lever of tension T; or by a dashpot, a slider beside it or not, which becomes a lever of tension T = S u):
    its balance sum_i k_i (x_i - x_p) - d_p T + share F = 0 puts it at x_p = (sum_i k_i x_i - d_p T + share F)
    / S (d_p = 1 for the dashpot's lever), and its share of the force goes to its far ends as k_i / S of it;
    else FrequencyError (:func:`_refuse_observed`)."""
    name = network.nodes[node]
    forced = name in load
    touching = [e for e in network.elements if node in e.between and not _carries_nothing(e)]
    ends, total = _spring_ends(touching, node)
    viscous = None  # springs and a dashpot (a slider beside it): x_p = xbar - u, the lever's u = T / S
    if not forced:
        viscous = _maxwell(network, touching, node)
        if viscous is None:
            viscous = _bingham(network, touching, node)
    thresholds = [] if viscous is not None else _parallel([e for e in touching if e.kind in THRESHOLDS])
    others = [] if viscous is not None else [e for e in touching if e.kind not in ("spring",) + THRESHOLDS]
    why = None
    if others or (thresholds and forced):
        holding = (others + thresholds)[0]
        why = f"with {holding.kind} {_called(holding)} on it"
    elif len(thresholds) > 1:
        why = f"between {_called(thresholds[0])} and {_called(thresholds[1])}"
    elif total == 0.0:
        why = "held by dashpots alone (its position set only up to a constant)" if viscous else "held by no spring"
    if why is not None:
        _refuse_observed(network, node, source, named, loaded, purpose, why, forced)
    tension = {}  # the lever p's threshold becomes (none where it carries nothing: T = 0)
    if thresholds and _levered(thresholds[0], node, name, ends, total):
        tension[thresholds[0].name] = -_weights(thresholds[0])[node] / total
    for lever in viscous or ():
        if lever.kind == "lever":  # (none where every far end is the ground: u decays, x_p = xbar)
            tension[lever.name] = -1.0 / total
    share = load.pop(name, 0.0)
    for view, (weights, gain, tensions) in list(views.items()):
        weight = weights.pop(name, 0.0)
        if weight == 0.0:
            continue
        for end, stiffness in ends.items():
            key = None if end < 0 else network.nodes[end]
            weights[key] = weights.get(key, 0.0) + weight * stiffness / total
        for lever, value in tension.items():
            tensions[lever] = tensions.get(lever, 0.0) + weight * value
        views[view] = (weights, gain + weight * share / total, tensions)
    for end, stiffness in ends.items():
        if end >= 0 and share:
            key = network.nodes[end]
            load[key] = load.get(key, 0.0) + share * stiffness / total


def _refuse_unobserved(name, source, loaded, purpose) -> None:
    """FrequencyError for massless node ``name``, the one loaded or named, where the caller cannot take it."""
    how = f"{purpose} of a network with sliders is solved for by shooting on the motion of the nodes with a mass"
    if name == loaded:
        raise FrequencyError(f"{source}: node {name} is massless and the force acts on it: {how}: load a node "
                             "with a mass (--load-node), give it a mass, or integrate the network with prandtl-fmu "
                             "run")
    raise FrequencyError(f"--node: {name} is massless: {how} (a massless node's own motion is not computed): "
                         "name one of them")


def _refuse_observed(network, node, source, named, loaded, purpose, why, forced) -> None:
    """FrequencyError for massless ``node``, which the force acts on (``forced``: the node ``loaded``, or a node
    its force passes through) or whose motion ``named`` moves with, and which is not held as it must be
    (``why``)."""
    name = network.nodes[node]
    how = f"{purpose} of a network with sliders is solved for by shooting on the motion of the nodes with a mass"
    taken = ("(a massless node is taken there where springs alone hold it)" if forced else
             "(a massless node is taken there where springs hold it, and one slider or branch at most, or a "
             "dashpot with a slider beside it or not)")
    if forced:
        raise FrequencyError(f"{source}: node {name} is massless, {why}, and the force acts on it"
                             f"{'' if name == loaded else f' (through it from {loaded})'}: {how} {taken}: load a "
                             "node with a mass (--load-node), give it a mass, or integrate the network with "
                             "prandtl-fmu run")
    raise FrequencyError(f"--node: {name if name == named else named} is massless"
                         f"{'' if name == named else f' and moves with massless {name}'}, {why}: {how} {taken}: "
                         "name a node with a mass, or one held by springs")


def _weights(element) -> dict:
    """A threshold element's row as {node: weight} (the ground left out)."""
    if element.kind == "lever":
        return dict(zip(element.between, element.weights))
    p, q = element.between
    return {p: 1.0} if q < 0 else {p: 1.0, q: -1.0}


def _carries_nothing(element) -> bool:
    """A dashpot of c = 0, a slider of alpha = 0: on a massless node they change nothing, and go."""
    return element.kind in ("dashpot", "slider") and element.value == 0.0


def _called(element) -> str:
    """An element's name for a refusal: a lever says through which massless nodes it reaches this one."""
    if element.kind == "lever" and element.through:
        return f"{element.name} (through massless {', '.join(element.through)})"
    return element.name


def _lever(network, node, source, purpose):
    """The network without massless ``node`` (see the module), or FrequencyError."""
    name = network.nodes[node]
    tail = "give it a mass, or integrate the network with prandtl-fmu run"
    how = f"{purpose} of a network with sliders is solved for by shooting on the motion of the nodes with a mass"
    touching = [e for e in network.elements if node in e.between and not _carries_nothing(e)]
    viscous = _maxwell(network, touching, node)
    if viscous is None:
        viscous = _bingham(network, touching, node)
    if viscous is not None:
        return _without(network, node, [e for e in network.elements if node not in e.between] + viscous)
    for e in touching:
        if e.kind not in ("spring",) + THRESHOLDS:
            why = "its position a root of a cubic" if e.kind == "cubic" else "a first-order motion"
            raise FrequencyError(f"{source}: node {name} is massless, with {e.kind} {e.name} on it ({why}): {how}, "
                                 f"which takes a massless node held by linear springs and one slider or branch: "
                                 f"{tail}")
    thresholds = _parallel([e for e in touching if e.kind in THRESHOLDS])
    if len(thresholds) > 1:
        raise FrequencyError(f"{source}: node {name} is massless between {_called(thresholds[0])} and "
                             f"{_called(thresholds[1])} (its position a play on two references): {how}, which "
                             f"takes a massless node held by linear springs and one slider or branch: {tail}")
    rest = [e for e in network.elements if node not in e.between]
    ends, total = _spring_ends(touching, node)
    if total == 0.0:  # nothing holds the node: its elements carry no force
        return _without(network, node, rest)
    rest.extend(_complement(network, node, ends, total))
    if thresholds:
        rest.extend(_levered(thresholds[0], node, name, ends, total))
    return _without(network, node, rest)


def _maxwell(network, touching, node) -> Optional[list]:
    """A massless node held by springs k_i (to far ends i, S = sum k_i) and dashpots c_j (to far ends j, C = sum
    c_j > 0), nothing else on it, as what it is: its balance sum_i k_i (x_i - x_p) = sum_j c_j (x_p' - x_j')
    makes w = xbar - x_p (xbar = sum_i k_i x_i / S, the springs' weighted mean; jbar = sum_j c_j x_j / C, the
    dashpots') obey w' = (xbar' - jbar') - (S / C) w, and the force on each spring's end i is k_i (xbar - x_i) -
    k_i w, on each dashpot's end j c_j (jbar' - x_j') + (c_j / C) S w. So the springs are their Schur complement
    (k_i k_l / S between each pair of far ends, as :func:`_lever`), the dashpots theirs (c_j c_l / C), and the
    rest a :class:`Lever` of stiffness S on the elongation xbar - jbar, its u = w, with the series dashpot C and
    a range it never reaches (NEVER: no motion of finite numbers gets there), whose u shooting carries as a state
    (``network_orbit.py``). One spring and one dashpot: the Maxwell element between i and j; dashpots alone (S =
    0): the node follows jbar, and only their Schur complement is left. The elements it becomes (none where every
    far end is the ground), or None where the node is not such a node."""
    name = network.nodes[node]
    if any(e.kind not in ("spring", "dashpot") for e in touching):
        return None
    ends, total = _spring_ends(touching, node)
    dampers, damping = _spring_ends(touching, node, "dashpot")
    if not damping > 0.0:
        return None
    out = _complement(network, node, ends, total) + _complement(network, node, dampers, damping, "dashpot")
    if not total > 0.0:
        return out
    weights = {i: k / total for i, k in ends.items() if i >= 0}
    for j, c in dampers.items():
        if j >= 0:
            weights[j] = weights.get(j, 0.0) - c / damping
    weights = {i: w for i, w in weights.items() if abs(w) > 1e-12}  # a weight that cancels is 0, not rounding
    if weights:
        ordered = sorted(weights)
        called = "+".join(e.name for e in touching if e.kind == "dashpot")
        out.append(Lever(f"{name}({called})", tuple(ordered), tuple(weights[i] for i in ordered), total,
                         total * NEVER, c=damping, through=(name,)))
    return out


def _bingham(network, touching, node) -> Optional[list]:
    """A massless node held by springs k_i (to far ends i, S = sum k_i > 0), and by a slider (alpha) and a dashpot
    (c) side by side to one end j, nothing else on it, as what it is: its balance sum_i k_i (x_i - x_p) = T +
    c (x_p' - x_j'), T the slider's force (within alpha while it sticks, alpha sigma while it slips), with w =
    xbar - x_p (as :func:`_maxwell`) and e = xbar - x_j: stuck, w' = e' while |S w| <= alpha; slipping,
    c (e' - w') = S w - alpha sigma, so w' = e' - (S / c) (w - sigma alpha / S). The forces on the ends are
    :func:`_maxwell`'s: the springs' Schur complement and a :class:`Lever` of stiffness S on e, its u = w, of
    range alpha / S, with the dashpot beside its slider (``bingham``: ``network_orbit.py`` carries its u). The
    elements it becomes, or None where the node is not such a node (sliders to one end in parallel are one)."""
    name = network.nodes[node]
    dashpot, sliders = _dashpot(touching, node), _parallel([e for e in touching if e.kind == "slider"])
    if dashpot is None or len(sliders) != 1 or any(e.kind not in ("spring", "dashpot", "slider") for e in touching):
        return None
    (slider,) = sliders
    j = dashpot.between[1] if dashpot.between[0] == node else dashpot.between[0]
    if j != (slider.between[1] if slider.between[0] == node else slider.between[0]):
        return None
    ends, total = _spring_ends(touching, node)
    if not total > 0.0:
        return None
    out = _complement(network, node, ends, total)
    weights = {i: k / total for i, k in ends.items() if i >= 0}
    if j >= 0:
        weights[j] = weights.get(j, 0.0) - 1.0
    weights = {i: w for i, w in weights.items() if abs(w) > 1e-12}  # a weight that cancels is 0, not rounding
    if weights:
        ordered = sorted(weights)
        out.append(Lever(f"{name}({slider.name}, {dashpot.name})", tuple(ordered),
                         tuple(weights[i] for i in ordered), total, slider.value, c=dashpot.value, through=(name,),
                         bingham=True))
    return out


def _dashpot(touching, node):
    """The dashpots among ``touching`` on ``node`` as one where they all go to one far end (in parallel their c
    add), else None (none, or to two ends)."""
    dashpots = [e for e in touching if e.kind == "dashpot"]
    far = {e.between[1] if e.between[0] == node else e.between[0] for e in dashpots}
    if len(far) != 1:
        return None
    if len(dashpots) == 1:
        return dashpots[0]
    return dataclasses.replace(dashpots[0], name="+".join(e.name for e in dashpots),
                               value=sum(e.value for e in dashpots))


def _spring_ends(touching, node, kind="spring") -> tuple:
    """``({far end: stiffness}, their sum)`` of the springs among ``touching`` on ``node`` (the ground -1;
    springs to one far end summed); ``kind`` "dashpot": of the dashpots, {far end: c}."""
    ends = {}
    for e in touching:
        if e.kind == kind:
            end = e.between[1] if e.between[0] == node else e.between[0]
            ends[end] = ends.get(end, 0.0) + e.value
    return ends, sum(ends.values())


def _parallel(thresholds) -> list:
    """Rigid sliders between the same two ends as one (their thresholds add: in parallel they stick together
    and slide together); other thresholds as they are."""
    out, sliders = [], {}
    for e in thresholds:
        if e.kind == "slider":
            key = tuple(sorted(e.between))
            if key in sliders:
                first = out[sliders[key]]
                out[sliders[key]] = dataclasses.replace(first, name=f"{first.name}+{e.name}",
                                                        value=first.value + e.value)
                continue
            sliders[key] = len(out)
        out.append(e)
    return out


def _levered(element, node, name, ends, total) -> list:
    """The lever that threshold ``element`` on massless ``node`` becomes, the node held by springs to ``ends``
    ({far end: stiffness}, ``total`` their sum > 0) (see the module); none where it carries nothing."""
    if element.kind == "slider":
        k, alpha = math.inf, element.value
    elif element.kind == "branch":  # with its series dashpot, if any (all in series: it stays in series)
        k, alpha = element.value, element.value * element.eta
    else:
        k, alpha = element.value, element.alpha
    if not alpha > 0.0 or not k > 0.0:  # it carries nothing
        return []
    weights = _weights(element)
    share = weights.pop(node)
    size = dict.fromkeys(weights, 0.0)
    for end, w in weights.items():
        size[end] = abs(w)
    for end, stiffness in ends.items():
        if end >= 0:
            weights[end] = weights.get(end, 0.0) + share * stiffness / total
            size[end] = size.get(end, 0.0) + abs(share * stiffness / total)
    # a weight that cancels (a cluster of massless nodes hung from one node passes it no force) is 0, not its
    # rounding: which decides whether that node is refused for two thresholds
    weights = {end: w for end, w in weights.items() if abs(w) > 1e-12 * size[end]}
    compliance = (0.0 if math.isinf(k) else 1.0 / k) + share * share / total
    if not weights:  # it acts on nothing (every far end the ground)
        return []
    ordered = sorted(weights)
    through = (element.through if element.kind == "lever" else ()) + (name,)
    return [Lever(element.name, tuple(ordered), tuple(weights[i] for i in ordered), 1.0 / compliance, alpha,
                  c=element.c, through=through, bingham=element.kind == "lever" and element.bingham)]
