"""The native FMU of a network scene (``[network]`` or ``[chain]``, issue 32): its variables, its model description
(FMI 2.0 or 3.0), the generated ``scene.h`` and the link. :func:`prandtl_fmu.fmu.native.build.build_native_network_fmu`
is the entry.

The variables are ``fmu/description.py``'s, those of the PythonFMU FMU of the scene (``fmu/python/kinds.py``,
NetworkKind and NetworkConnectorKind: the same names, value references, units, causalities and semantics), written
with ``needsExecutionTool="false"``; FMI 3.0 adds ``time`` and, with ``arrays``, the structural parameter
``n_nodes`` and the nodes' x and v as arrays (``x`` and ``v``; the connector's ``x_nodes`` and ``v_nodes``) besides
the scalars x_<node>, v_<node> (OMSimulator and ecos read an FMI 3.0 array as a scalar: the arrays are an option).

The parameters' rules are the library's (``network.model``: ``Network.with_parameters``, ``check_topology``,
``stepper_problem``), written into ``scene.h`` as tables: each parameter's rule, and what a mass can break (a node
held by sliders alone, the load's part with neither support nor mass). Everything a parameter change cannot break
(which nodes are joined, loops of sliders) is the scene's topology, fixed. The white noise's rule (a massless load
node needs a dashpot on it) is :func:`noise_rule`'s, its parameters' rules ``common.h``'s (the PythonFMU's).
"""
from __future__ import annotations

import hashlib
import tempfile
from pathlib import Path

import numpy as np

from ...compiling import stage
from .assemble import (C_TYPES, FMI_HEADERS, HERE, NativeBuildError, c_string, c_variables, chosen_steppers, new_guid,
                       noise_lines, pack, scene_load_lines, stubs)
from .object_cache import KernelObjects, digest_of
from .platforms import KERNEL_MACRO

ENERGIES = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper", "energy_residual")


def parameter_table(network, exclude=()) -> list:
    """(name, node, element, column, rule, u0) of every FMU parameter of the network, in Network.parameters()
    order without ``exclude`` (the connector's load node mass: fixed at 0)."""
    rows = []
    for j, node in enumerate(network.nodes):
        rows.append((f"m_{node}", j, -1, 0, "R_MASS", 0.0))
    for e, element in enumerate(network.elements):
        for key in element.coefficients():
            column = {"k": 0, "eta": 1, "c": 2}[key] if element.kind == "branch" else 0
            rule = "R_POSITIVE" if (element.kind, key) == ("branch", "k") else "R_ETA" if key == "eta" else "R_NONNEG"
            rows.append((f"{key}_{element.name}", -1, e, column, rule, abs(float(element.u0))))
    if [row[0] for row in rows] != list(network.parameters()):
        raise ValueError("the native network's parameters do not follow Network.parameters()")
    return [row for row in rows if row[0] not in exclude]


def meanings(scene, connector: bool) -> dict:
    """What the C layer reads for each variable name of the FMU (the PythonFMU kinds'
    contract, ``fmu/python/kinds.py``): name -> (W_ code, index)."""
    network = scene.network
    names = {"F": ("W_F", 0), "reaction": ("W_REACTION", 0), "step": ("W_STEP", 0),
             "scene_load": ("W_SCENE_LOAD", 0), "stepper": ("W_STEPPER", 0)}
    if not connector:  # the white noise the FMU adds to F (the connector's motion comes in)
        names.update({"noise_intensity": ("W_NOISE_INTENSITY", 0), "noise_seed": ("W_NOISE_SEED", 0),
                      "noise_unit": ("W_NOISE_UNIT", 0)})
    if connector:
        names.update({"x": ("W_XIN", 0), "v": ("W_VIN", 0), "force": ("W_FORCE", 0)})
    for j, node in enumerate(network.nodes):
        names[f"x_{node}"] = ("W_X", j)
        names[f"v_{node}"] = ("W_V", j)
    for k, name in enumerate(ENERGIES):
        names[name] = ("W_ENERGY", k)
    for e, element in enumerate(network.elements):
        names[f"dissipated_{element.kind}_{element.name}"] = ("W_DISSIPATED", e)
        if element.kind == "branch":
            names[f"u_{element.name}"] = ("W_U", e)
    for i, row in enumerate(parameter_table(network, excluded(scene, connector))):
        names[row[0]] = ("W_PARAM", i)
    return names


def excluded(scene, connector: bool) -> tuple:
    network = scene.network
    return (f"m_{network.nodes[network.load_node]}",) if connector else ()


def steppers_of(scene, connector: bool) -> list:
    """The steppers of the network without its white noise (the parameters turn it on and off: network.h checks
    its rule, :func:`noise_rule`)."""
    from ...network.model import stepper_problem
    from .kernels import with_noise

    if connector:
        return ["implicit"]
    return [name for name in ("implicit", "projected") if stepper_problem(with_noise(scene, None), name) is None]


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


def noise_rule(scene) -> tuple:
    """(LOAD_DAMPED, NOISE_MASSLESS_LOAD): whether a dashpot is on the load's node (the scene's structure), and
    ``stepper_problem``'s words for a white noise on the load's node when it is massless and has none (what a mass
    parameter set to 0 can break; the C layer checks the mass)."""
    import dataclasses

    from ...loads import WhiteNoise
    from ...network.model import stepper_problem

    network = scene.network
    mass = np.array(network.mass, dtype=float)
    mass[network.load_node] = 0.0
    massless = dataclasses.replace(scene, network=dataclasses.replace(network, mass=mass),
                                   load=dataclasses.replace(scene.load, noise=WhiteNoise(1.0, 0)))
    problem = stepper_problem(massless, "implicit")
    return int(problem is None), problem or ""


def scene_header(scene, variables, guid, steppers, symbols, digest, connector, arrays, extra_vr) -> str:
    """scene.h of the network: its arrays, the parameters' rules, the kernels' symbols, the variables (``variables``:
    the FMI 2.0 list of ``fmu/description.py``, indexed by value reference)."""
    from ... import scene as library_rules
    from ...network import kernels as nk

    network = scene.network
    n, count = network.n, len(network.elements)
    mass, kind, ends, coef, load_node, has_cubic = network.compile()
    table = parameter_table(network, excluded(scene, connector))
    mass_param = [-1] * n
    for i, row in enumerate(table):
        if row[1] >= 0:
            mass_param[row[1]] = i
    slider_only, floating, part = topology_tables(network)
    load = scene.load.compile()
    load_kind, offset, amplitude, omega, times, forces = load[:6]
    load_damped, massless_load = noise_rule(scene)
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
        "move": f"int64_t move_c({net}, {ptr}, {ptr}, {ptr}, {iptr}, {ptr}, {ptr}, {work}, double, int64_t, double, "
                f"double, {ptr})",
        "load_force": f"double load_force({load_args}, double)",
        "jump": f"int64_t jump_c({net}, {ptr}, {ptr}, {ptr}, {iptr}, {ptr}, {ptr}, double, {ptr})",
        "reaction_check": f"int64_t reaction_check({net}, {ptr}, {ptr}, {ptr}, {iptr}, int64_t, double, {ptr})",
    }
    noisy = (f"int64_t {{name}}({net}, {ptr}, {ptr}, {ptr}, {iptr}, {ptr}, {ptr}, {ptr}, {work}, {load_args}, "
             f"double, int64_t, double, int64_t, {iptr}, double, int64_t, double, {iptr})")
    lines = [
        "/* generated by prandtl_fmu.fmu.native.network_build for one network scene: do not edit */",
        "#ifndef PRANDTL_SCENE_H",
        "#define PRANDTL_SCENE_H",
        "#include <math.h>",
        "#include <stdint.h>",
        *KERNEL_MACRO,
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
        # the sign from a branch's u as the kernels keep it to its elongation as written (network/model.py)
        f"static const double SENSE[NE_ARR] = {_doubles([e.sense for e in network.elements] or [1])};",
        f"static const char* NODE_NAMES[NN] = {_strings(network.nodes)};",
        f"static const char* ELEMENT_NAMES[NE_ARR] = {_strings([e.name for e in network.elements] or [''])};",
        f"static const int SLIDER_ONLY[NN] = {_ints(slider_only)};",
        f"#define LOAD_FLOATING {floating}",
        f"static const int LOAD_PART[NN] = {_ints(part)};",
        "enum { R_MASS, R_POSITIVE, R_NONNEG, R_ETA };",
        "typedef struct { const char* name; int node; int element; int column; int rule; double u0; } Param;",
        f"#define N_PARAMS {max(len(table), 1)}",
        "static const Param PARAMS[N_PARAMS] = {",
        *[f'    {{"{name}", {node}, {element}, {column}, {rule}, {u0!r}}},'
          for name, node, element, column, rule, u0 in table or [("none", 0, -1, 0, "R_MASS", 0.0)]],
        "};",
        f"#define N_PARAMS_USED {len(table)}",
        f"static const double P_SCENE[N_PARAMS] = {_doubles([network.parameters()[row[0]] for row in table])};",
        f"static const int MASS_PARAM[NN] = {_ints(mass_param)}; /* the parameter of node j's mass, or -1 */",
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
        *noise_lines(scene, connector),
        *scene_load_lines(scene, "the load's node"),
        f"#define LOAD_DAMPED {load_damped} /* a dashpot on the load's node: a white noise needs it or a mass */",
        f"static const char NOISE_MASSLESS_LOAD[] = {c_string(massless_load)}; /* stepper_problem's words */",
    ]
    for name, symbol in symbols.items():
        if name.startswith("advance_"):
            lines.append(advance.format(name=name) + f' KERNEL("{symbol}");')
        elif name.startswith("noisy_"):
            lines.append(noisy.format(name=name) + f' KERNEL("{symbol}");')
        else:
            lines.append(declarations[name] + f' KERNEL("{symbol}");')
    lines.append(f"typedef int64_t (*advance_fn)({advance.split('(', 1)[1]};")
    lines.append("static const advance_fn ADVANCE[N_STEPPERS] = {" + ", ".join(f"advance_{s}" for s in steppers)
                 + "};")
    lines.append(f"typedef int64_t (*noisy_fn)({noisy.split('(', 1)[1]};")
    lines.append("static const noisy_fn NOISY[N_STEPPERS] = {" + ", ".join(
        f"noisy_{s}" if f"noisy_{s}" in symbols else "NULL" for s in steppers) + "}; /* NULL: the connector's */")
    lines += [
        "enum { T_REAL, T_INTEGER, T_BOOLEAN, T_STRING };",
        "enum { W_NONE, W_F, W_X, W_V, W_REACTION, W_FORCE, W_ENERGY, W_DISSIPATED, W_U, W_PARAM, W_STEP, "
        "W_SCENE_LOAD, W_STEPPER, W_XIN, W_VIN, W_NOISE_INTENSITY, W_NOISE_SEED, W_NOISE_UNIT };",
        "typedef struct { unsigned vr; int type; int what; int index; const char* name; } Var;",
        "static const Var VARS[] = { /* VARS[vr - VR_FIRST]: the variable of value reference vr (a hole: vr = "
        "UINT32_MAX) */",
    ]
    known = meanings(scene, connector)
    table_of = {}
    for row in variables:
        if row.name not in known:
            raise ValueError(f"the native runtime does not know the FMU variable {row.name!r}")
        table_of[row.value_reference] = (C_TYPES[row.type], *known[row.name], row.name)
    for vr in range(min(table_of), max(table_of) + 1):
        if vr in table_of:
            type_code, what, index, name = table_of[vr]
            lines.append(f'    {{{vr}, {type_code}, {what}, {index}, "{name}"}},')
        else:
            lines.append('    {4294967295u, T_REAL, W_NONE, 0, ""},')
    lines += ["};", f"#define N_VARS {max(table_of) - min(table_of) + 1}", f"#define VR_FIRST {min(table_of)}u",
              "#endif", ""]
    return "\n".join(lines)


def build(scene_path, out, fmi: int, causality, arrays: bool, platforms=None, wanted=None) -> Path:
    """Build the native FMU of the network scene at ``scene_path`` into ``out`` (see the module docstring), with
    the binaries of ``platforms`` (``platforms.resolve``: None is this machine's) and the steppers ``wanted``
    (``--steppers``, ``assemble.chosen_steppers``; None: every one that applies); NativeBuildError names what stops
    it."""
    from .. import description
    from ..archive import built_scene
    from ...network.model import stepper_problem
    from . import network_kernels
    from . import platforms as targets

    folders = targets.resolve(platforms, fmi)
    chains = targets.toolchains(folders, default=platforms is None)
    scene, scene_bytes = built_scene(scene_path, causality)  # checked as the PythonFMU build checks it
    connector = scene.causality == "displacement"
    if arrays and fmi != 3:
        raise NativeBuildError("arrays: the nodes' x and v as arrays are an FMI 3.0 option (fmi=3)")
    steppers = steppers_of(scene, connector)
    if not connector and scene.solver.stepper not in steppers:
        raise NativeBuildError(f"{scene.source}: [solver] stepper: {stepper_problem(scene, scene.solver.stepper)}")
    if connector and wanted is not None:
        raise NativeBuildError("--steppers: the connector has no stepper to choose (its motion is given; it steps "
                               "with implicit): drop --steppers")
    if not connector:
        steppers = chosen_steppers(scene, steppers, wanted)
    held = None if wanted is None else steppers  # what the description and the page name
    identifier = description.model_identifier(scene)
    guid = new_guid()
    variables = c_variables(scene, fmi, arrays)  # the C layer's table; FMI 3.0's extras by the macros
    extra_vr = description.fmi3_references(scene)
    text = description.model_description(scene, fmi, guid, runtime="native", arrays=arrays, steppers=held)
    if connector:
        scene = scene.with_solver(stepper="implicit")
    digest = hashlib.sha256(scene_bytes + guid.encode()).hexdigest()
    with tempfile.TemporaryDirectory(prefix="prandtl_native_network_") as scratch:
        scratch = Path(scratch)
        compiled = KernelObjects(digest_of("network", scene_bytes, scene.causality, connector, *steppers),
                                 lambda: network_kernels.compile_network(scene, steppers, connector),
                                 [target for folder in folders for target in folder.targets])
        symbols = compiled.symbols()
        try:
            header = scene_header(scene, variables, guid, steppers, symbols, digest, connector, arrays, extra_vr)
        except ValueError as exc:
            raise NativeBuildError(str(exc)) from None
        (scratch / "scene.h").write_text(header)
        binaries, _ = targets.build_binaries(folders, chains, compiled, scratch, stubs, [HERE / f"fmi{fmi}.c"],
                                             [scratch, FMI_HEADERS[fmi]], [], fmi, identifier)
        stage("native build: the FMU archive")
        return pack(out, text, scene, scene_bytes, identifier, folders, binaries, held)


def fmi3_network_description(root, scene, extra_vr=None, arrays: bool = False, connector=None) -> str:
    """The native FMU's FMI 3.0 description of the network ``scene`` (``description.model_description(scene,
    3)``), with the GUID of its FMI 2.0 description ``root``, for a caller that holds that one
    (docs/gen_pages.py); ``connector``, if given, must be the scene's; ``extra_vr``: not read (FMI 3.0's value
    references are the variables' positions, ``description.fmi3_references``)."""
    from .. import description

    if connector is not None and connector != (scene.causality == "displacement"):
        raise NativeBuildError(f"connector = {connector}: the scene's causality is {scene.causality!r}")
    return description.model_description(scene, 3, root.get("guid", ""), arrays=arrays)
