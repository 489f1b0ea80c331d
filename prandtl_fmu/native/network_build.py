"""The native FMU of a network scene (``[network]`` or ``[chain]``, issue 32): its variables, its model description
(FMI 2.0 or 3.0), the generated ``scene.h`` and the link. :func:`prandtl_fmu.native.build.build_native_network_fmu`
is the entry.

Variables (the value reference of a variable is its index in this list; FMI 3.0 adds ``time`` and, with
``arrays``, the structural parameter ``n_nodes`` and the arrays ``x`` and ``v``):

* the element (causality "force"): input ``F`` (N, at the load's node); outputs ``x_<node>``, ``v_<node>`` of
  every node, ``reaction`` (the force of the elements on the ground) and the energy account (kinetic_energy,
  stored_energy, work, dissipated_sliders, dissipated_damper, energy_residual); parameters: every coefficient of
  the network by its scene name (``scene.network.parameters()``: m_<node>, k_spring_1, alpha_n3, ...), ``step``,
  ``stepper`` (implicit, and projected where the network allows it) and ``scene_load``;
* the connector (causality "displacement"): inputs ``x``, ``v`` (the motion of the load's node); outputs
  ``force`` (what the network's elements exert on that node), ``reaction``, ``x_<node>``, ``v_<node>``,
  kinetic_energy, stored_energy, dissipated_sliders, dissipated_damper; the coefficients and ``step``.

The parameters' rules are the library's (``network.model``: ``Network.with_parameters``, ``check_topology``,
``stepper_problem``), written into ``scene.h`` as tables: each parameter's rule, and what a mass can break (a node
held by sliders alone, the load's part with neither support nor mass). Everything a parameter change cannot break
(which nodes are joined, loops of sliders) is the scene's topology, fixed.
"""
from __future__ import annotations

import hashlib
import html
import os
import re
import subprocess
import tempfile
import uuid
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ENERGIES = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper", "energy_residual")
CONNECTOR_ENERGIES = ("kinetic_energy", "stored_energy", "dissipated_sliders", "dissipated_damper")
UNITS = {"s": {"s": 1}, "m": {"m": 1}, "kg": {"kg": 1}, "m/s": {"m": 1, "s": -1}, "N": {"kg": 1, "m": 1, "s": -2},
         "N/m": {"kg": 1, "s": -2}, "N/m3": {"kg": 1, "m": -2, "s": -2}, "N.s/m": {"kg": 1, "s": -1},
         "J": {"kg": 1, "m": 2, "s": -2}}
KEY_UNITS = {("spring", "k"): "N/m", ("branch", "k"): "N/m", ("branch", "eta"): "m", ("branch", "c"): "N.s/m",
             ("dashpot", "c"): "N.s/m", ("slider", "alpha"): "N", ("cubic", "k3"): "N/m3"}
KEY_TEXT = {("spring", "k"): "stiffness of spring {name}: force k (x_i - x_j)",
            ("cubic", "k3"): "coefficient of cubic spring {name}: force k3 (x_i - x_j)^3",
            ("dashpot", "c"): "coefficient of dashpot {name}: force c (v_i - v_j)",
            ("slider", "alpha"): "threshold of slider {name} (Saint-Venant): |force| <= alpha",
            ("branch", "k"): "stiffness of Prandtl branch {name} (> 0)",
            ("branch", "eta"): "elastic range of Prandtl branch {name}: |u| <= eta (and >= |u0|)",
            ("branch", "c"): "dashpot in series with Prandtl branch {name} (0: none)"}
DBL_MAX = "1.7976931348623157e+308"


class Variable:
    """One FMU variable: what the C layer reads (``what``, ``index``) and what the description says."""

    def __init__(self, name, type_name, causality, variability, what, index=0, start=None, unit=None,
                 description="", initial=None):
        self.name, self.type, self.causality, self.variability = name, type_name, causality, variability
        self.what, self.index, self.start, self.unit = what, index, start, unit
        self.description, self.initial = description, initial


def parameter_table(network) -> list:
    """(name, node, element, column, rule, u0, unit, text) for every parameter, in Network.parameters() order."""
    rows = []
    for j, node in enumerate(network.nodes):
        rows.append((f"m_{node}", j, -1, 0, "R_MASS", 0.0, "kg", f"mass of node {node} (0: massless)"))
    for e, element in enumerate(network.elements):
        for key in element.coefficients():
            column = {"k": 0, "c": 0, "alpha": 0, "k3": 0}[key] if element.kind != "branch" else \
                {"k": 0, "eta": 1, "c": 2}[key]
            rule = "R_POSITIVE" if (element.kind, key) == ("branch", "k") else "R_ETA" if key == "eta" else "R_NONNEG"
            rows.append((f"{key}_{element.name}", -1, e, column, rule, abs(float(element.u0)),
                         KEY_UNITS[(element.kind, key)], KEY_TEXT[(element.kind, key)].format(name=element.name)))
    names = [row[0] for row in rows]
    if names != list(network.parameters()):
        raise ValueError("the native network's parameters do not follow Network.parameters()")
    return rows


def variables(scene, connector: bool) -> list:
    network = scene.network
    out = []
    load = network.nodes[network.load_node]
    if connector:
        out.append(Variable("x", "Real", "input", "continuous", "W_XIN", start=float(network.x0[network.load_node]),
                            unit="m", description=f"displacement of the load's node {load} (linear between "
                            "communication points)"))
        out.append(Variable("v", "Real", "input", "continuous", "W_VIN", start=float(network.v0[network.load_node]),
                            unit="m/s", description=f"velocity of the load's node {load}"))
        out.append(Variable("force", "Real", "output", "continuous", "W_FORCE", unit="N",
                            description=f"force of the network's elements on node {load} (what holds its motion)"))
    else:
        out.append(Variable("F", "Real", "input", "continuous", "W_F", start=0.0, unit="N",
                            description=f"force on the load's node {load}, held over a communication step"))
    for j, node in enumerate(network.nodes):
        out.append(Variable(f"x_{node}", "Real", "output", "continuous", "W_X", j, unit="m",
                            description=f"displacement of node {node}"))
        out.append(Variable(f"v_{node}", "Real", "output", "continuous", "W_V", j, unit="m/s",
                            description=f"velocity of node {node}"))
    out.append(Variable("reaction", "Real", "output", "continuous", "W_REACTION", unit="N",
                        description="force of the elements on the ground"))
    for name in (CONNECTOR_ENERGIES if connector else ENERGIES):
        out.append(Variable(name, "Real", "output", "continuous", "W_ENERGY", ENERGIES.index(name), unit="J",
                            description={"kinetic_energy": "sum m_j v_j^2 / 2",
                                         "stored_energy": "energy in the springs, cubic springs and branches",
                                         "work": "work of the load since the start",
                                         "dissipated_sliders": "dissipated by the sliders and branches' sliders",
                                         "dissipated_damper": "dissipated by the dashpots and series dashpots",
                                         "energy_residual": "work - dissipated - (kinetic + stored - initial)"}[name]))
    for index, (name, node, element, column, rule, u0, unit, text) in enumerate(parameter_table(network)):
        value = network.parameters()[name]
        out.append(Variable(name, "Real", "parameter", "tunable", "W_PARAM", index, start=value, unit=unit,
                            description=text))
    out.append(Variable("step", "Real", "parameter", "tunable", "W_STEP", start=float(scene.solver.step), unit="s",
                        description="the internal step h of the stepper (s)"))
    if not connector:
        out.append(Variable("stepper", "String", "parameter", "tunable", "W_STEPPER", start=scene.solver.stepper,
                            description="the stepper: implicit (every network) or projected (every node massive, "
                            "no slider)"))
        out.append(Variable("scene_load", "Boolean", "parameter", "tunable", "W_SCENE_LOAD", start=False,
                            description="add the scene's [load] to F"))
    return out


def dependencies(scene, variables_, connector: bool) -> dict:
    """The outputs' direct dependencies on the inputs (names): none for the element (every output follows the
    state); the connector's on x (its instant move), and v_<load node> on v."""
    if not connector:
        return {v.name: () for v in variables_ if v.causality == "output"}
    load = scene.network.nodes[scene.network.load_node]
    return {v.name: (("x", "v") if v.name == f"v_{load}" else ("x",)) for v in variables_ if v.causality == "output"}


def steppers_of(scene, connector: bool) -> list:
    from ..network.model import stepper_problem

    if connector:
        return ["implicit"]
    return [name for name in ("implicit", "projected") if stepper_problem(scene, name) is None]


def identifier_of(scene) -> str:
    return re.sub(r"\W", "_", f"prandtl_network_{scene.name}")[:100]


def guid_of(scene_bytes: bytes, connector: bool, fmi: int, arrays: bool) -> str:
    from .._jit import source_digest

    key = scene_bytes + f"{connector}{fmi}{arrays}".encode() + source_digest().encode()
    return "{" + str(uuid.UUID(hashlib.sha256(key).hexdigest()[:32])) + "}"


# ------------------------------------------------------------------ model descriptions

def _units(parent, used):
    units = ET.SubElement(parent, "UnitDefinitions")
    for name in sorted(used):
        unit = ET.SubElement(units, "Unit", {"name": name})
        ET.SubElement(unit, "BaseUnit", {k: str(v) for k, v in UNITS[name].items()})


def _log_categories(parent, fmi):
    categories = ET.SubElement(parent, "LogCategories")
    for name, text in (("logStatusWarning", "warnings"), ("logStatusDiscard", f"fmi{fmi}Discard: a refused step"),
                       ("logStatusError", f"fmi{fmi}Error: a refused call"), ("logStatusFatal", "fatal errors"),
                       ("logAll", "every message")):
        ET.SubElement(categories, "Category", {"name": name, "description": text})


def _start(v) -> str:
    if v.type == "Boolean":
        return "true" if v.start else "false"
    if v.type == "String":
        return str(v.start)
    return repr(float(v.start))


def description_fmi2(scene, variables_, guid, identifier, connector) -> str:
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": scene.name, "guid": guid,
        "description": f"network {scene.name} ({'connector' if connector else 'element'}, native runtime)",
        "generationTool": "prandtl_fmu (native runtime)", "variableNamingConvention": "flat",
        "numberOfEventIndicators": "0"})
    ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": identifier, "needsExecutionTool": "false", "canHandleVariableCommunicationStepSize": "true",
        "canInterpolateInputs": "false", "maxOutputDerivativeOrder": "0", "canRunAsynchronuously": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false", "canNotUseMemoryManagementFunctions": "true",
        "canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true", "providesDirectionalDerivative": "false"})
    _units(root, {v.unit for v in variables_ if v.unit})
    _log_categories(root, 2)
    ET.SubElement(root, "DefaultExperiment", {"startTime": "0.0", "stopTime": repr(float(scene.solver.stop_time)),
                                              "stepSize": repr(float(scene.solver.output_interval))})
    model = ET.SubElement(root, "ModelVariables")
    for vr, v in enumerate(variables_):
        attributes = {"name": v.name, "valueReference": str(vr), "description": v.description,
                      "causality": v.causality, "variability": v.variability}
        if v.causality == "parameter":
            attributes["initial"] = "exact"
        node = ET.SubElement(model, "ScalarVariable", attributes)
        kind = {}
        if v.unit:
            kind["unit"] = v.unit
        if v.start is not None:
            kind["start"] = _start(v)
        ET.SubElement(node, v.type, kind)
    structure = ET.SubElement(root, "ModelStructure")
    index = {v.name: i + 1 for i, v in enumerate(variables_)}
    depends = dependencies(scene, variables_, connector)
    outputs = ET.SubElement(structure, "Outputs")
    for v in variables_:
        if v.causality == "output":
            ET.SubElement(outputs, "Unknown", {"index": str(index[v.name]),
                                               "dependencies": " ".join(str(index[d]) for d in depends[v.name])})
    initial = ET.SubElement(structure, "InitialUnknowns")
    for v in variables_:
        if v.causality == "output":
            ET.SubElement(initial, "Unknown", {"index": str(index[v.name])})
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def description_fmi3(scene, variables_, guid, identifier, connector, arrays, extra_vr) -> str:
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": scene.name, "instantiationToken": guid,
        "description": f"network {scene.name} ({'connector' if connector else 'element'}, native runtime)",
        "generationTool": "prandtl_fmu (native runtime)", "variableNamingConvention": "structured"})
    ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": identifier, "needsExecutionTool": "false", "canBeInstantiatedOnlyOncePerProcess": "false",
        "canGetAndSetFMUState": "true", "canSerializeFMUState": "true",
        "canHandleVariableCommunicationStepSize": "true", "providesIntermediateUpdate": "false",
        "canReturnEarlyAfterIntermediateUpdate": "false", "hasEventMode": "false"})
    _units(root, {v.unit for v in variables_ if v.unit} | {"s"})
    _log_categories(root, 3)
    ET.SubElement(root, "DefaultExperiment", {"startTime": "0.0", "stopTime": repr(float(scene.solver.stop_time)),
                                              "stepSize": repr(float(scene.solver.output_interval))})
    model = ET.SubElement(root, "ModelVariables")
    ET.SubElement(model, "Float64", {"name": "time", "valueReference": str(extra_vr["time"]),
                                     "causality": "independent", "variability": "continuous", "unit": "s",
                                     "description": "the network's time"})
    depends = dependencies(scene, variables_, connector)
    vr_of = {v.name: str(vr) for vr, v in enumerate(variables_)}
    for vr, v in enumerate(variables_):
        attributes = {"name": v.name, "valueReference": str(vr), "description": v.description,
                      "causality": v.causality, "variability": v.variability}
        tag = {"Real": "Float64", "Boolean": "Boolean", "String": "String"}[v.type]
        if v.unit:
            attributes["unit"] = v.unit
        if v.type == "String":
            node = ET.SubElement(model, tag, attributes)
            ET.SubElement(node, "Start", {"value": v.start})
            continue
        if v.start is not None:
            attributes["start"] = _start(v)
        ET.SubElement(model, tag, attributes)
    outputs = [vr_of[v.name] for v in variables_ if v.causality == "output"]
    dependency_text = {vr_of[name]: " ".join(vr_of[d] for d in deps) for name, deps in depends.items()}
    if arrays:
        n = scene.network.n
        ET.SubElement(model, "UInt64", {"name": "n_nodes", "valueReference": str(extra_vr["n_nodes"]),
                                        "causality": "structuralParameter", "variability": "fixed", "start": str(n),
                                        "description": "number of nodes (the length of the arrays x and v)"})
        for name, unit in (("x", "m"), ("v", "m/s")):
            vr = str(extra_vr[f"{name}_nodes"])
            node = ET.SubElement(model, "Float64", {
                "name": f"{name}_nodes" if connector else name, "valueReference": vr, "causality": "output",
                "variability": "continuous", "unit": unit,
                "description": f"{'displacement' if name == 'x' else 'velocity'} of every node, in the nodes' order "
                               f"({', '.join(scene.network.nodes[:5])}{', ...' if n > 5 else ''})"})
            ET.SubElement(node, "Dimension", {"valueReference": str(extra_vr["n_nodes"])})
            outputs.append(vr)
            dependency_text[vr] = dependency_text[vr_of[f"{name}_{scene.network.nodes[0]}"]] if not connector else \
                vr_of["x"] + (" " + vr_of["v"] if name == "v" else "")
    structure = ET.SubElement(root, "ModelStructure")
    for tag in ("Output", "InitialUnknown"):
        for vr in outputs:
            ET.SubElement(structure, tag, {"valueReference": vr, "dependencies": dependency_text[vr]})
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


# ------------------------------------------------------------------ scene.h

def _doubles(values) -> str:
    values = [float(v) for v in values] or [0.0]
    return "{" + ", ".join(repr(v) if v == v and abs(v) != float("inf") else
                           ("INFINITY" if v > 0 else "-INFINITY") if v == v else "NAN" for v in values) + "}"


def _ints(values) -> str:
    return "{" + ", ".join(str(int(v)) for v in (list(values) or [0])) + "}"


def _strings(values) -> str:
    return "{" + ", ".join('"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"' for v in values) + "}"


def topology_tables(network):
    """SLIDER_ONLY[j] (node j held by sliders alone: massless it is refused), LOAD_FLOATING (the load's part is not
    joined to the ground) and LOAD_PART[j] (node j in it): what check_topology reads of the masses."""
    n = network.n
    parent = list(range(n + 1))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for e in network.elements:
        i, j = e.between[0], n if e.between[1] < 0 else e.between[1]
        parent[find(i)] = find(j)
    kinds = [set() for _ in range(n)]
    for e in network.elements:
        kinds[e.between[0]].add(e.kind)
        if e.between[1] >= 0:
            kinds[e.between[1]].add(e.kind)
    floating = find(network.load_node) != find(n)
    part = [int(floating and find(j) == find(network.load_node)) for j in range(n)]
    return [int(k == {"slider"}) for k in kinds], int(floating), part


def scene_header(scene, variables_, steppers, symbols, guid, digest, connector, arrays, extra_vr) -> str:
    from .. import scene as library_rules
    from ..network import kernels as nk

    network = scene.network
    n, count = network.n, len(network.elements)
    mass, kind, ends, coef, load_node, has_cubic = network.compile()
    table = parameter_table(network)
    slider_only, floating, part = topology_tables(network)
    load = scene.load.compile()
    load_kind, offset, amplitude, omega, times, forces = load
    ptr = "double*"
    iptr = "int64_t*"
    net = f"{ptr}, {ptr}, {iptr}, {iptr}, int64_t, int64_t"
    work = ", ".join([ptr, ptr, ptr, iptr, iptr, ptr, ptr, iptr, iptr, iptr, ptr])
    load_args = f"int64_t, {ptr}, {ptr}, {ptr}, int64_t"
    advance = (f"int64_t {{name}}({net}, {ptr}, {ptr}, {ptr}, {iptr}, {ptr}, {ptr}, {ptr}, {work}, {load_args}, "
               f"double, int64_t, double, int64_t, {iptr})")
    declarations = {
        "energies": f"int64_t energies({net}, {ptr}, {ptr}, {ptr}, {ptr})",
        "initial": f"int64_t initial({net}, {ptr}, {ptr}, {ptr}, {iptr}, double, {ptr})",
        "move": f"int64_t move_c({net}, {ptr}, {ptr}, {ptr}, {iptr}, {ptr}, {ptr}, {work}, double, double, double, "
                f"double, double, {ptr})",
        "load_force": f"double load_force({load_args}, double)",
    }
    lines = [
        "/* generated by prandtl_fmu.native.network_build for one network scene: do not edit */",
        "#ifndef PRANDTL_SCENE_H",
        "#define PRANDTL_SCENE_H",
        "#include <math.h>",
        "#include <stdint.h>",
        "#define NETWORK 1",
        f"#define CONNECTOR {int(connector)}",
        f"#define ARRAYS {int(arrays)}",
        "#define NB 0 /* no branch elongations u of the element (the network's are in its state) */",
        "#define N_VALUE 0",
        f"#define NN {n} /* nodes */",
        f"#define NE {count} /* elements */",
        f"#define NE_ARR {max(count, 1)}",
        f"#define LOAD_NODE {int(load_node)}",
        f"#define HAS_CUBIC {int(has_cubic)}",
        f"#define K_SPRING {nk.SPRING}",
        f"#define K_DASHPOT {nk.DASHPOT}",
        f"#define K_SLIDER {nk.SLIDER}",
        f"#define K_BRANCH {nk.BRANCH}",
        f"#define K_CUBIC {nk.CUBIC}",
        f"#define SEARCH_PER_TERM {nk.SEARCH_PER_TERM}",
        f"#define SEARCH_CONSTANT {nk.SEARCH_CONSTANT}",
        f"#define SEARCH_BUDGET {int(nk.search_budget(n, count))}",
        f"#define ADVANCE_BUDGET {float(library_rules.ADVANCE_BUDGET)!r}",
        f"#define SMALLEST_MAGNITUDE {float(library_rules.SMALLEST_MAGNITUDE)!r}",
        f"#define LARGEST_MAGNITUDE {float(library_rules.LARGEST_MAGNITUDE)!r}",
        f"#define MAX_STEPS {float(library_rules.MAX_STEPS)!r}",
        f"#define SHORTEST_STEP {float(library_rules.SHORTEST_STEP)!r}",
        f"#define VR_TIME {extra_vr['time']}",
        f"#define VR_N {extra_vr['n_nodes']}",
        f"#define VR_XA {extra_vr['x_nodes']}",
        f"#define VR_VA {extra_vr['v_nodes']}",
        "#define VR_U 4294967295u /* none */",
        "#define STRUCTURAL_N NN",
        f"#define HAS_STRUCTURAL {int(arrays)}",
        '#define STRUCTURAL_TEXT "n_nodes is the network\'s number of nodes"',
        f"static const int64_t KIND[NE_ARR] = {_ints(kind)};",
        f"static const int64_t ENDS[2 * NE_ARR] = {_ints(ends.ravel() if count else [0, 0])};",
        f"static const double MASS_SCENE[NN] = {_doubles(mass)};",
        f"static const double COEF_SCENE[3 * NE_ARR] = {_doubles(coef.ravel() if count else [0, 0, 0])};",
        f"static const double X0[NN] = {_doubles(network.x0)};",
        f"static const double V0[NN] = {_doubles(network.v0)};",
        f"static const double U0[NE_ARR] = {_doubles([e.u0 for e in network.elements])};",
        f"static const char* NODE_NAMES[NN] = {_strings(network.nodes)};",
        f"static const char* ELEMENT_NAMES[NE_ARR] = {_strings([e.name for e in network.elements] or [''])};",
        f"static const int SLIDER_ONLY[NN] = {_ints(slider_only)};",
        f"#define LOAD_FLOATING {floating}",
        f"static const int LOAD_PART[NN] = {_ints(part)};",
        "enum { R_MASS, R_POSITIVE, R_NONNEG, R_ETA };",
        "typedef struct { const char* name; int node; int element; int column; int rule; double u0; } Param;",
        f"#define N_PARAMS {len(table)}",
        "static const Param PARAMS[N_PARAMS] = {",
        *[f'    {{"{name}", {node}, {element}, {column}, {rule}, {u0!r}}},'
          for name, node, element, column, rule, u0, _, _ in table],
        "};",
        f"static const double P_SCENE[N_PARAMS] = {_doubles(network.parameters().values())};",
        f'static const char GUID[] = "{guid}";',
        f'static const char DIGEST[] = "{digest}";',
        f"static const int64_t LOAD_KIND = {int(load_kind)};",
        f"static const double LOAD_LK[3] = {_doubles([offset, amplitude, omega])};",
        f"static const double LOAD_T[{max(len(times), 1)}] = {_doubles(times)};",
        f"static const double LOAD_F[{max(len(forces), 1)}] = {_doubles(forces)};",
        f"static const int64_t LOAD_N = {len(times)};",
        f"#define N_STEPPERS {len(steppers)}",
        f"static const char* STEPPER_NAMES[] = {_strings(steppers)};",
        f'static const char STEPPER_LIST[] = "{", ".join(steppers)}";',
        f'static const char DEFAULT_STEPPER[] = "{scene.solver.stepper}";',
        f"static const double DEFAULT_STEP = {float(scene.solver.step)!r};",
    ]
    for name, symbol in symbols.items():
        if name.startswith("advance_"):
            lines.append(advance.format(name=name) + f' __asm__("{symbol}");')
        else:
            lines.append(declarations[name] + f' __asm__("{symbol}");')
    lines.append(f"typedef int64_t (*advance_fn)({advance.split('(', 1)[1]};")
    lines.append("static const advance_fn ADVANCE[N_STEPPERS] = {" + ", ".join(f"advance_{s}" for s in steppers)
                 + "};")
    lines += [
        "enum { T_REAL, T_INTEGER, T_BOOLEAN, T_STRING };",
        "enum { W_F, W_X, W_V, W_REACTION, W_FORCE, W_ENERGY, W_PARAM, W_STEP, W_SCENE_LOAD, W_STEPPER, W_XIN, "
        "W_VIN };",
        "typedef struct { unsigned vr; int type; int what; int index; const char* name; } Var;",
        "static const Var VARS[] = {",
    ]
    types = {"Real": "T_REAL", "Boolean": "T_BOOLEAN", "String": "T_STRING"}
    for vr, v in enumerate(variables_):
        lines.append(f'    {{{vr}, {types[v.type]}, {v.what}, {v.index}, "{v.name}"}},')
    lines += ["};", f"#define N_VARS {len(variables_)}", "#endif", ""]
    return "\n".join(lines)


def documentation(scene, variables_, fmi, connector) -> str:
    rows = "\n".join(f"<tr><td>{html.escape(v.name)}</td><td>{v.causality}</td><td>{v.unit or ''}</td>"
                     f"<td>{html.escape(v.description)}</td></tr>" for v in variables_)
    kind = "connector (the motion of the load's node in, the force out)" if connector else \
        "element (the force in at the load's node)"
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{html.escape(scene.name)}</title></head>"
            f"<body><h1>{html.escape(scene.name)}</h1><p>A network of {scene.network.n} nodes and "
            f"{len(scene.network.elements)} elements as an FMI {fmi}.0 co-simulation {kind}, native runtime: the "
            "library's compiled network kernels and a C FMI layer, no Python. The scene is resources/scene.toml. "
            "Refusals (a bad parameter, a step with no equilibrium, a non-finite output) are logged with their "
            f"reason, logging on or off.</p><table><tr><th>name</th><th>causality</th><th>unit</th>"
            f"<th>description</th></tr>\n{rows}\n</table></body></html>\n")


def build(scene_path, out, fmi: int, causality, arrays: bool, compiler: str, build_error) -> Path:
    """Build the native FMU of the network scene at ``scene_path`` into ``out`` (see the module docstring)."""
    from ..fmu.build import add_entry
    from ..network.model import stepper_problem
    from ..scene import load_scene, parse_scene
    from . import kernels as element_kernels
    from . import network_kernels

    scene_bytes = Path(scene_path).read_bytes()
    scene = load_scene(scene_path, check_stepper=False)
    if causality is not None and causality != scene.causality:
        if causality not in ("force", "displacement"):
            raise build_error(f"--causality {causality}: must be force or displacement")
        text = scene_bytes.decode("utf-8")
        text = re.sub(r"(?ms)^\[fmu\].*?(?=^\[|\Z)", "", text) + f'\n[fmu]\ncausality = "{causality}"\n'
        scene_bytes = text.encode("utf-8")
        scene = parse_scene(text, str(scene_path), check_stepper=False)
    connector = scene.causality == "displacement"
    if arrays and fmi != 3:
        raise build_error("arrays: the nodes' x and v as arrays are an FMI 3.0 option (--fmi 3)")
    steppers = steppers_of(scene, connector)
    if scene.solver.stepper not in steppers:
        problem = stepper_problem(scene, scene.solver.stepper) or "the connector takes 'implicit' steps"
        raise build_error(f"{scene.source}: [solver] stepper: {problem}")
    network = scene.network
    variables_ = variables(scene, connector)
    count = len(variables_)
    extra_vr = {"time": count, "n_nodes": count + 1, "x_nodes": count + 2, "v_nodes": count + 3}
    identifier = identifier_of(scene)
    guid = guid_of(scene_bytes, connector, fmi, arrays)
    digest = hashlib.sha256(scene_bytes + guid.encode()).hexdigest()
    out = Path(out)
    with tempfile.TemporaryDirectory(prefix="prandtl_native_network_") as scratch:
        scratch = Path(scratch)
        compiled = network_kernels.compile_network(scene, steppers, connector)
        objects, external = element_kernels.emit_objects(compiled, scratch)
        symbols = {name: function.native_name for name, function in compiled}
        (scratch / "scene.h").write_text(scene_header(scene, variables_, steppers, symbols, guid, digest, connector,
                                                      arrays, extra_vr))
        from .build import FMI_HEADERS, _stubs

        (scratch / "stubs.c").write_text(_stubs(external))
        library = scratch / f"{identifier}.so"
        exports = scratch / "exports.map"
        exports.write_text(f"{{ global: fmi{fmi}*; local: *; }};\n")
        headers = FMI_HEADERS if fmi == 2 else HERE / "fmi3"
        command = [compiler, "-shared", "-fPIC", "-O2", "-std=c99", "-D_POSIX_C_SOURCE=200809L", "-fvisibility=hidden",
                   *os.environ.get("PRANDTL_NATIVE_CFLAGS", "").split(), f"-I{scratch}", f"-I{headers}",
                   str(HERE / f"fmi{fmi}.c"), str(scratch / "stubs.c"), *map(str, objects), "-o", str(library),
                   "-lm", "-Wl,--no-undefined", f"-Wl,--version-script={exports}"]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            errors = [line for line in done.stderr.splitlines() if "error" in line] or done.stderr.splitlines()[-1:]
            raise build_error(f"linking the native FMU failed: {errors[0].strip() if errors else done.returncode}")
        description = (description_fmi2(scene, variables_, guid, identifier, connector) if fmi == 2 else
                       description_fmi3(scene, variables_, guid, identifier, connector, arrays, extra_vr))
        platform = "linux64" if fmi == 2 else "x86_64-linux"
        out.parent.mkdir(parents=True, exist_ok=True)
        partial = out.with_name(out.name + ".partial")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            add_entry(archive, "modelDescription.xml", description)
            add_entry(archive, f"binaries/{platform}/{identifier}.so", library.read_bytes(), mode=0o755)
            add_entry(archive, "resources/scene.toml", scene_bytes)
            add_entry(archive, "documentation/index.html", documentation(scene, variables_, fmi, connector))
        os.replace(partial, out)
    del network
    return out
