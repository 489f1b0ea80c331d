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
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

JOINED = ("spring", "slider", "branch")


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
    from ..network.model import Element

    touching = [e for e in network.elements if node in e.between]
    ends = {}
    for e in touching:
        end = e.between[1] if e.between[0] == node else e.between[0]
        ends[end] = ends.get(end, 0.0) + e.value
    total = sum(ends.values())
    rest = [e for e in network.elements if node not in e.between]
    if total == 0.0:  # springs of zero stiffness: they carry no force
        return _without(network, node, rest)
    far = sorted(ends, reverse=True)  # the ground (-1) last, only ever q: an element to the ground is (p, -1)
    name = network.nodes[node]
    for i, p in enumerate(far):
        for q in far[i + 1:]:
            other = "ground" if q < 0 else network.nodes[q]
            rest.append(Element("spring", f"{name}({network.nodes[p]},{other})", (p, q), ends[p] * ends[q] / total))
    return _without(network, node, rest)


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
