"""A network of nodes joined by springs, dashpots, sliders, Prandtl branches and cubic springs, and its scene.

Nodes have names and masses (0: a massless node, in equilibrium at every instant); every element joins two
nodes, or a node and the ground ("ground" is reserved). An element ``between = [i, j]`` goes from i to j, as in
finite elements: its elongation is e = x_j - x_i (x of the ground: 0), positive when j moves away from i in +x,
and it pulls i towards j and j towards i with its tension:

* spring ``k`` (N/m): tension k e; cubic ``k3`` (N/m^3): k3 e^3;
* dashpot ``c`` (N s/m): tension c e', e' = v_j - v_i;
* slider ``alpha`` (N): a Saint-Venant element, tension in alpha sign(e') (any force in [-alpha, alpha]
  while it sticks);
* branch ``k``, ``eta`` (m), optional ``u0``, ``c``: a Prandtl branch, exactly the element's: a spring k in
  series with a slider of threshold alpha = k eta (and with a dashpot c, the series model), its elongation u
  with u' + d psi_[-eta, eta](u) ∋ e' - (k / c) u, tension k u. ``between = ["ground", a]`` is the element on
  node a (u follows x_a).

Inside, an element is kept as (p, q) acting on x_p - x_q with the ground always second (the kernels' form):
(j, i), or (i, ground) for ``between = [i, "ground"]``, whose u is then -e: ``Element.sense`` (+1 or -1) turns
the kept u into the elongation as written (initial u0, reported u_<name>); springs, dashpots, sliders and cubic
springs are odd in e, so their orientation changes no force.

The load F(t) acts on ``load_node``; the reaction is the force of the elements on the ground.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from typing import Optional

import numpy as np

from . import kernels
from .. import schema
from ..scene_tables import SceneError, Solver, _Reader, _check_noise_unit, _check_solver, _kind, _load, _solver
from ..loads import ConstantLoad

KINDS = {"spring": kernels.SPRING, "dashpot": kernels.DASHPOT, "slider": kernels.SLIDER, "branch": kernels.BRANCH,
         "cubic": kernels.CUBIC}
# the coefficients of each kind, as written in a scene (and as FMU parameters: <name>_<element>)
KEYS = {"spring": ("k",), "dashpot": ("c",), "slider": ("alpha",), "branch": ("k", "eta", "c"), "cubic": ("k3",)}
GROUND = "ground"
NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
NETWORK_STEPPERS = ("implicit", "projected")


@dataclass(frozen=True)
class Element:
    """One element: ``kind`` (a key of KINDS), ``name`` (unique in the network), ``between`` (p, q): node
    indices as the kernels keep them (acting on x_p - x_q, q = -1 for the ground: see the module docstring);
    ``value`` k, c, alpha or k3; for a branch ``eta``, ``c`` (0: no series dashpot) and ``u0``; ``sense``."""

    kind: str
    name: str
    between: tuple
    value: float
    eta: float = 0.0
    c: float = 0.0
    u0: float = 0.0  # as kept: sense * the u0 written
    sense: int = 1  # the elongation as written (x_j - x_i) is sense * the kept one (x_p - x_q)

    def coefficients(self) -> dict:
        """The element's coefficients by their scene key."""
        if self.kind == "branch":
            return {"k": self.value, "eta": self.eta, "c": self.c}
        return {KEYS[self.kind][0]: self.value}


@dataclass(frozen=True, eq=False)
class Network:
    """Nodes (names, masses, initial x0, v0), elements and the load's node."""

    nodes: tuple
    mass: np.ndarray
    x0: np.ndarray
    v0: np.ndarray
    elements: tuple
    load_node: int
    chain: bool = False  # written as [chain]: its names follow the chain's rules

    @property
    def n(self) -> int:
        return len(self.nodes)

    @property
    def massless(self) -> bool:
        return not np.any(self.mass > 0)

    def of_kind(self, kind: str) -> list:
        return [e for e in self.elements if e.kind == kind]

    def compile(self):
        """The kernels' tuple (mass, kind, ends, coef, load_node, has_cubic): see kernels.py."""
        count = len(self.elements)
        kind = np.array([KINDS[e.kind] for e in self.elements], dtype=np.int64).reshape(count)
        ends = np.array([e.between for e in self.elements], dtype=np.int64).reshape(count, 2)
        coef = np.array([(e.value, e.eta, e.c) for e in self.elements], dtype=float).reshape(count, 3)
        return (np.array(self.mass, dtype=float), kind, ends, coef, int(self.load_node),
                bool(any(e.kind == "cubic" for e in self.elements)))

    def branch_sense(self) -> np.ndarray:
        """For each branch, in the scene's order, the sign that turns its kept u into its elongation as written
        (``between = [i, j]``: x_j - x_i)."""
        return np.array([e.sense for e in self.elements if e.kind == "branch"], dtype=float)

    def parameters(self) -> dict:
        """Every coefficient by its parameter name: m_<node>, <key>_<element> (k_spring_1, alpha_n3, ...)."""
        names = {f"m_{node}": float(m) for node, m in zip(self.nodes, self.mass)}
        for e in self.elements:
            for key, value in e.coefficients().items():
                names[f"{key}_{e.name}"] = float(value)
        return names

    def with_parameters(self, **values) -> "Network":
        """A copy with some parameters changed, checked by the scene's rules (SceneError names the culprit)."""
        known = self.parameters()
        for name in values:
            if name not in known:
                raise SceneError(f"{name}: not a parameter of this network (e.g. {', '.join(list(known)[:4])})")
        mass = self.mass.copy()
        elements = list(self.elements)
        for name, value in values.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SceneError(f"{name}: must be a finite number, got {value!r}")
            value = float(value)
            if name.startswith("m_") and name[2:] in self.nodes:
                mass[self.nodes.index(name[2:])] = _checked(name, value, 0.0)
                continue
            for index, e in enumerate(elements):
                for key in e.coefficients():
                    if f"{key}_{e.name}" == name:
                        elements[index] = _changed(e, key, value, name)
        network = replace(self, mass=mass, elements=tuple(elements))
        problem = network.topology_problem()
        if problem:
            raise SceneError(f"{', '.join(values)}: {problem}")
        return network

    def topology_problem(self) -> Optional[str]:
        """Why this network has no solution as built (None if it may have one): see check_topology."""
        try:
            check_topology(self)
        except SceneError as exc:
            return str(exc)
        return None


def _checked(name, value, minimum, positive=False):
    from ..scene_tables import magnitude_problem

    problem = magnitude_problem(value)
    if problem:
        raise SceneError(f"{name}: {problem}")
    if positive and not value > 0:
        raise SceneError(f"{name}: must be > 0, got {value!r}")
    if value < minimum:
        raise SceneError(f"{name}: must be >= {minimum}, got {value!r}")
    return value


def _changed(e: Element, key: str, value: float, name: str) -> Element:
    if e.kind == "branch":
        if key == "k":
            return replace(e, value=_checked(name, value, 0.0, positive=True))
        if key == "eta":
            value = _checked(name, value, 0.0)
            if abs(e.u0) > value:
                raise SceneError(f"{name}: {value!r} would leave u0 = {e.u0!r} outside [-eta, eta]")
            return replace(e, eta=value)
        return replace(e, c=_checked(name, value, 0.0))
    return replace(e, value=_checked(name, value, 0.0))


@dataclass(frozen=True, eq=False)
class NetworkScene:
    """A scene whose system is a network (``[network]`` or ``[chain]``)."""

    name: str
    network: Network
    load: object
    solver: Solver
    source: str = "<scene>"
    causality: str = "force"

    def with_solver(self, **overrides) -> "NetworkScene":
        given = {k: v for k, v in overrides.items() if v is not None}
        solver = replace(self.solver, **given)
        _check_solver(solver, self.source, where="")
        scene = replace(self, solver=solver)
        check_stepper(scene, "")
        return scene

    def with_network(self, network: Network) -> "NetworkScene":
        return replace(self, network=network)

    @property
    def effects(self) -> list:
        return [kind for kind in KINDS if self.network.of_kind(kind)]


def stepper_problem(scene: NetworkScene, stepper: str) -> Optional[str]:
    """Why ``stepper`` does not apply to the network (None if it does)."""
    network = scene.network
    if stepper in NETWORK_STEPPERS and getattr(scene.load, "noise", None) is not None:
        node = network.load_node
        damped = any(e.kind == "dashpot" and node in e.between for e in network.elements)
        if not network.mass[node] > 0 and not damped:
            return (f"a white noise on the massless node {network.nodes[node]} with no dashpot on it has no solution "
                    "(its equilibrium would follow a force of infinite variance): give it a mass or a dashpot")
    if stepper == "implicit":
        return None
    if stepper == "projected":
        if network.of_kind("slider"):
            return ("'projected' (the paper's scheme) needs all plasticity in branches, and this network has "
                    f"sliders ({network.of_kind('slider')[0].name}): use 'implicit'")
        massless = [node for node, m in zip(network.nodes, network.mass) if not m > 0]
        if massless:
            return (f"'projected' is explicit and needs a mass at every node; {massless[0]} is massless: use "
                    "'implicit'")
        return None
    return (f"{stepper!r} integrates one mass (the element); a network takes {' or '.join(map(repr, NETWORK_STEPPERS))}"
            " ('implicit': any network)")


def check_stepper(scene: NetworkScene, where: str) -> None:
    problem = stepper_problem(scene, scene.solver.stepper)
    if problem:
        raise SceneError(f"{scene.source}: {where}stepper: {problem}")


# ------------------------------------------------------------------ reading

ELEMENT_TABLES = ("mass", "friction", "spring", "cubic", "damper", "branches")
TOP_KEYS = schema.top_level("network")


def network_scene(doc: dict, source: str, check: bool = True) -> NetworkScene:
    """The scene of a document holding [network] or [chain] (SceneError names the culprit)."""
    for key in doc:
        if key in ELEMENT_TABLES:
            raise SceneError(f"{source}: [{key}]: belongs to a one-mass element; in a network every part is an "
                             "element between nodes ([[network.spring]], [[network.branch]], ...)")
        if key not in TOP_KEYS:
            raise SceneError(f"{source}: {key}: unknown key (allowed at top level of a network scene: "
                             f"{', '.join(sorted(TOP_KEYS))})")
    if "network" in doc and "chain" in doc:
        raise SceneError(f"{source}: [chain]: a scene holds [network] or [chain] (its shorthand), not both")
    name = doc.get("name", source.rsplit("/", 1)[-1].rsplit(".", 1)[0])
    if not isinstance(name, str):
        raise SceneError(f"{source}: name: must be a string, got {_kind(name)}")
    network = _network(source, doc["network"]) if "network" in doc else _chain(source, doc["chain"])
    check_topology(network, source)
    load = _load(source, doc["load"]) if "load" in doc else ConstantLoad(0.0)
    if "solver" not in doc:
        raise SceneError(f"{source}: [solver]: missing (required: step, stop_time, output_interval)")
    solver = _solver(source, doc["solver"])
    causality = "force"
    if "fmu" in doc:
        r = _Reader(source, "fmu", doc["fmu"])
        r.only()
        causality = r.string("causality")
        if causality == "displacement" and network.mass[network.load_node] > 0:
            r.fail("causality", f'"displacement" imposes the motion of load node {network.nodes[network.load_node]}'
                   ", which must then be massless (the bodies hold its inertia): give it mass 0 or use \"force\"")
    scene = NetworkScene(name, network, load, solver, source, causality)
    _check_noise_unit(scene)
    if check:
        check_stepper(scene, "[solver] ")
    return scene


def _node_names(r, key, count=None):
    names = r.data.get(key)
    if not isinstance(names, list) or not names:
        r.fail(key, "must be a non-empty list of node names (strings)")
    seen = set()
    for index, name in enumerate(names):
        if not isinstance(name, str) or not NAME.match(name):
            r.fail(f"{key}[{index + 1}]", f"must be a name of letters, digits and _ (not starting with a digit), "
                   f"got {name!r}")
        if name == GROUND:
            r.fail(f"{key}[{index + 1}]", '"ground" is reserved for the fixed support')
        if name in seen:
            r.fail(f"{key}[{index + 1}]", f"{name!r} appears twice")
        seen.add(name)
    return tuple(names)


def _network(source, data) -> Network:
    r = _Reader(source, "network", data)
    r.only()
    nodes = _node_names(r, "nodes")
    n = len(nodes)
    mass = r.numbers("mass", length=n)
    x0 = r.numbers("x0", length=n)
    v0 = r.numbers("v0", length=n)
    load_node = n - 1
    if "load_node" in r.data:
        name = r.string("load_node")
        if name not in nodes:
            r.fail("load_node", f"must be one of the nodes ({', '.join(nodes)}), got {name!r}")
        load_node = nodes.index(name)
    elements = []
    names = set(nodes)
    for kind in KINDS:
        tables = r.data.get(kind, [])
        if not isinstance(tables, list) or any(not isinstance(t, dict) for t in tables):
            r.fail(kind, f"must be written [[network.{kind}]] (a list of tables), got {_kind(tables)}")
        for index, table in enumerate(tables):
            element = _element(source, kind, index, table, nodes)
            if element.name in names:
                raise SceneError(f"{source}: [[network.{kind}]] {index + 1}: name {element.name!r} is taken (by a "
                                 "node or another element)")
            names.add(element.name)
            elements.append(element)
    return Network(nodes, mass, x0, v0, tuple(elements), load_node)


def _element(source, kind, index, table, nodes) -> Element:
    r = _Reader(source, f"network.{kind} {index + 1}", table, schema_table=f"network.{kind}")
    r.only()
    between = table.get("between")
    if not isinstance(between, list) or len(between) != 2 or not all(isinstance(b, str) for b in between):
        r.fail("between", f"must be [i, j]: two node names or \"ground\", got {between!r}")
    ends = []
    for b in between:
        if b != GROUND and b not in nodes:
            r.fail("between", f"{b!r} is not a node ({', '.join(nodes)}) nor \"ground\"")
        ends.append(-1 if b == GROUND else nodes.index(b))
    if ends[0] == ends[1]:
        r.fail("between", f"an element between {between[0]!r} and itself does nothing: join two different nodes"
               if ends[0] >= 0 else "an element between the ground and itself does nothing")
    name = f"{kind}_{index + 1}"
    if "name" in table:
        name = r.string("name")
        if not NAME.match(name) or name == GROUND:
            r.fail("name", f"must be a name of letters, digits and _ (not starting with a digit), got {name!r}")
    # as written, [i, j] acts on x_j - x_i: kept as (j, i), or as (i, ground) with sense -1 when j is the ground
    kept, sense = (ends[1], ends[0]), 1
    if kept[0] == -1:
        kept, sense = (ends[0], -1), -1
    if kind == "branch":
        k = r.number("k")
        eta = r.number("eta")
        c = r.number("c") if "c" in table else 0.0
        u0 = r.number("u0")
        if abs(u0) > eta:
            r.fail("u0", f"must lie in [-eta, eta] = [{-eta!r}, {eta!r}], got {u0!r}")
        return Element(kind, name, kept, k, eta, c, sense * u0, sense)
    key = KEYS[kind][0]
    return Element(kind, name, kept, r.number(key), sense=sense)


def _per_node(r, key, count, required=True):
    """A scalar or a list of ``count`` numbers."""
    if key not in r.data:
        if required:
            r.fail(key, "missing (required)")
        return None
    if isinstance(r.data[key], list):
        return r.numbers(key, length=count)
    return np.full(count, r.number(key))


def _chain(source, data) -> Network:
    """[chain]: nodes n1..n<n>, springs spring_i between n<i> and n<i+1>, a slider of each node on the support
    (named by the node: alpha_n3), an optional dashpot of each node to the support (c_n3) and spring from n1
    to the ground (wall: k_wall); the load on the last node."""
    r = _Reader(source, "chain", data)
    r.only()
    n = r.integer("n")
    nodes = tuple(f"n{i + 1}" for i in range(n))
    mass = _per_node(r, "m", n)
    k = _per_node(r, "k", n - 1, required=n > 1) if n > 1 else np.zeros(0)
    if n == 1 and "k" in r.data:
        r.fail("k", "a chain of one node has no spring between neighbours (k_wall holds it)")
    if k is not None and np.any(k <= 0):
        r.fail("k", "must be > 0 (the springs hold the chain together)")
    alpha = _per_node(r, "alpha", n)
    c = _per_node(r, "c", n, required=False)
    elements = []
    if "k_wall" in r.data:
        elements.append(Element("spring", "wall", (0, -1), r.number("k_wall")))
    for i in range(n - 1):
        elements.append(Element("spring", f"spring_{i + 1}", (i, i + 1), float(k[i])))
    for i in range(n):
        elements.append(Element("slider", nodes[i], (i, -1), float(alpha[i])))
    if c is not None:
        for i in range(n):
            elements.append(Element("dashpot", nodes[i], (i, -1), float(c[i])))
    return Network(nodes, mass, np.zeros(n), np.zeros(n), tuple(elements), n - 1, chain=True)


def check_topology(network: Network, source: str = "") -> None:
    """SceneError when the network cannot have a solution as built: a node with no path to the ground or the
    load's node; a massless node held by sliders alone; two sliders between the same two nodes, or sliders that
    close a loop (through the ground or not: the forces of a loop of stuck sliders are statically
    indeterminate, which the active-set method does not resolve); a free part with no mass."""
    prefix = f"{source}: " if source else ""
    n = network.n
    parent = list(range(n + 1))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    def node(a):
        return "the ground" if a == n else network.nodes[a]

    def end(j):
        return n if j < 0 else j

    for e in network.elements:
        i, j = e.between[0], end(e.between[1])
        parent[find(i)] = find(j)
    for j in range(n):
        if find(j) != find(n) and find(j) != find(network.load_node):
            raise SceneError(f"{prefix}node {network.nodes[j]}: no element joins it, even through other nodes, to "
                             "the ground or to the load's node: nothing holds it and nothing moves it")
    grounded = find(n)
    if find(network.load_node) != grounded and not any(
            network.mass[j] > 0 for j in range(n) if find(j) == find(network.load_node)):
        raise SceneError(f"{prefix}the part of the network that carries the load ({network.nodes[network.load_node]}"
                         ") is joined to the ground by no element and has no mass: the load has no equilibrium")
    kinds = [set() for _ in range(n)]
    for e in network.elements:
        kinds[e.between[0]].add(e.kind)
        if e.between[1] >= 0:
            kinds[e.between[1]].add(e.kind)
    for j in range(n):
        if not network.mass[j] > 0 and kinds[j] == {"slider"}:
            raise SceneError(f"{prefix}node {network.nodes[j]}: massless and held by sliders alone: once a slider "
                             "slips, nothing sets where it stops (give it a mass, a spring or a dashpot)")
    parent = list(range(n + 1))
    seen = {}
    for e in network.of_kind("slider"):
        i, j = e.between[0], end(e.between[1])
        pair = (min(i, j), max(i, j))
        if pair in seen:
            raise SceneError(f"{prefix}sliders {seen[pair]} and {e.name} join the same {node(pair[0])} and "
                             f"{node(pair[1])}: give one slider with the sum of their alphas")
        seen[pair] = e.name
        if find(i) == find(j):
            raise SceneError(f"{prefix}slider {e.name} closes a loop of sliders (through {node(i)} and {node(j)}): "
                             "the forces of stuck sliders in a loop are statically indeterminate; not supported "
                             "(put a spring or a branch in the loop)")
        parent[find(i)] = find(j)
