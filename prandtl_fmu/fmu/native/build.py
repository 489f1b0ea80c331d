"""``build_native_fmu``: an FMI 2.0 or 3.0 co-simulation FMU of a scene (the element or the connector) whose
binary holds no Python.

The FMU's model description is ``fmu/description.py``'s (the PythonFMU FMU's variables: names, value references,
units, causalities, start values; FMI 3.0's with what FMI 3.0 adds), written with ``needsExecutionTool="false"``;
the C layer's table of variables (scene.h's ``VARS``) is made from the same list. The FMU is packed by
``assemble.py``; its binary is linked from

* the scene's kernels, compiled by numba from the library's own sources (``kernels.py``), as objects;
* ``stubs.c``, generated (``assemble.stubs``): numba's error path, which a kernel reaches only when it raises, sets a
  flag instead of calling Python; the few functions of numba's runtime that ``exact``'s arrays call
  (``assemble.NRT``); ``numba_nextafter`` is C's ``nextafter``;
* ``fmi2.c`` or ``fmi3.c``, the FMI front (``front.h``), over the state machine ``machine.h``, the kind
  ``element.h`` or ``connector.h`` (its types: ``element_types.h``, ``connector_types.h``), the services ``core.h``,
  ``state.h``, ``calls.h`` (with ``common.h``) and the generated ``scene.h``.

The element's white noise (``noise_intensity``, ``noise_seed``, ``noise_unit``): the kernels' noisy ``advance``
beside the deterministic one, the steppers' refusals of a noise as a table (``kernels.noise_refusal``), the
scene's noise as the start values (``docs/native-route.md``).

The binaries (one per platform: ``platforms.py``, docs/platforms.md) are linked by zig (Linux, glibc 2.17, and
macOS) and mingw-w64 (Windows); the default build (this machine's platform) by zig where it is installed, else by
the machine's C compiler (``cc`` or ``gcc``, or ``$CC``); a missing toolchain stops the build with one line saying
what to install. ``$PRANDTL_NATIVE_CFLAGS`` adds flags to a build by the machine's compiler (the tests build with
``-fsanitize=address,undefined``: such a binary runs only in a host that loads the sanitizers' runtime).
"""
from __future__ import annotations

import hashlib
import math
import re
import tempfile
from pathlib import Path

from ...compiling import stage
from . import kernels
from . import platforms as targets
from .assemble import (C_TYPES, FMI_HEADERS, HERE, NativeBuildError, c_string, c_variables, chosen_steppers, new_guid,
                       noise_lines, pack, scene_load_lines, stubs)
from .object_cache import KernelObjects, digest_of

ENERGIES = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
            "dissipated_friction", "energy_residual")


def build_native_network_fmu(scene_path, out, fmi: int = 2, causality=None, arrays: bool = False,
                             platforms=None, steppers=None) -> Path:
    """Build the native FMU of the network scene (``[network]`` or ``[chain]``) at ``scene_path`` into ``out``: the
    element (force in at the load's node) or, with causality "displacement", the connector (its motion in, force
    out); ``arrays`` (FMI 3.0): also the nodes' x and v as arrays (scalars x_<node>, v_<node> in any case: masters
    such as OMSimulator and ecos read an FMI 3.0 array as a scalar); ``steppers``: only these
    (``assemble.chosen_steppers``). See ``network_build.py``; NativeBuildError names what stops it."""
    from . import network_build

    if fmi not in (2, 3):
        raise NativeBuildError(f"--fmi {fmi}: must be 2 or 3")
    return network_build.build(scene_path, out, fmi, causality, arrays, platforms, steppers)


def build_native_fmu(scene_path, out, fmi: int = 2, causality=None, arrays: bool = False, platforms=None,
                     steppers=None) -> Path:
    """Build the native FMU of the scene at ``scene_path`` into ``out``; NativeBuildError names what stops it.

    FMI 3.0 offers the branch elongations as the scalars u_1 .. u_n (every master reads them: OMSimulator and ecos
    read an FMI 3.0 array as a scalar); ``arrays`` (FMI 3.0 only) adds them as the array u, sized by the structural
    parameter n. A network scene goes to :func:`build_native_network_fmu` (its nodes' x and v).

    ``platforms``: the binaries the FMU holds (names of either FMI version, comma-separated, or "all"; None: this
    machine's platform), each linked as ``platforms.py`` says; the names and the toolchains are checked first.

    ``steppers``: only these of the steppers that apply (``assemble.chosen_steppers``; None: all of them); the
    scene's own stepper must be among them, the FMU refuses the others."""
    from .. import description
    from ..archive import built_scene
    from ...scene import load_scene

    if fmi not in (2, 3):
        raise NativeBuildError(f"--fmi {fmi}: must be 2 or 3")
    scene = load_scene(scene_path, check_stepper=False)
    if description.is_network(scene):  # a [network] or [chain] scene
        return build_native_network_fmu(scene_path, out, fmi, causality, arrays, platforms, steppers)
    folders = targets.resolve(platforms, fmi)
    chains = targets.toolchains(folders, default=platforms is None)
    if arrays and fmi != 3:
        raise NativeBuildError("arrays: the elongations u as an array are an FMI 3.0 option (fmi=3)")
    if arrays and description.elongation_count(scene) == 0:
        raise NativeBuildError("arrays: this scene has no branch elongations to offer as an array (no [branches], "
                               "or a continuum): build it without arrays")
    scene, scene_bytes = built_scene(scene_path, causality)  # checked as the PythonFMU build checks it
    connector = scene.causality == "displacement"
    if connector and steppers is not None:
        raise NativeBuildError("--steppers: the connector has no stepper (its motion is given): drop --steppers")
    built = [] if connector else kernels.applicable(scene)
    if not built and not connector:
        raise NativeBuildError("no stepper of the native runtime applies to this scene")
    if not connector:
        built = chosen_steppers(scene, built, steppers)
    held = None if steppers is None else built  # what the description and the page name
    identifier = description.model_identifier(scene)
    guid = new_guid()
    variables = c_variables(scene, fmi, arrays)  # the C layer's table; FMI 3.0's extras by the macros
    references = description.fmi3_references(scene)
    with tempfile.TemporaryDirectory(prefix="prandtl_native_") as scratch:
        scratch = Path(scratch)
        compiled = element_objects(scene, scene_bytes, built, folders)
        (scratch / "scene.h").write_text(_scene_header(scene, variables, guid, built, compiled.symbols(),
                                                       scene_bytes, arrays))
        n_vr = next((row.value_reference for row in variables if row.name == "n"), 0)
        binaries, _ = targets.build_binaries(folders, chains, compiled, scratch, stubs, [HERE / f"fmi{fmi}.c"],
                                             [scratch, FMI_HEADERS[fmi]],
                                             [f"VR_U={references['u'] or 4294967295}u", f"VR_N={n_vr}",
                                              f"VR_TIME={references['time']}"], fmi, identifier)
        text = description.model_description(scene, fmi, guid, runtime="native", arrays=arrays, steppers=held)
        stage("native build: the FMU archive")
        return pack(out, text, scene, scene_bytes, identifier, folders, binaries, held)


def element_objects(scene, scene_bytes: bytes, steppers, folders) -> KernelObjects:
    """The kernels of the element or connector ``scene`` (built from ``scene_bytes``) for ``steppers``, as objects
    for the targets of ``folders``: from the cache (``object_cache.py``) or compiled when first asked for."""
    return KernelObjects(digest_of("element", scene_bytes, scene.causality, *steppers),
                         lambda: kernels.compile_kernels(scene, steppers),
                         [target for folder in folders for target in folder.targets])


ELEMENT_ARGS = "P, P, P, P, P, P, P, int64_t"  # p, k, eta, cs, u; the memory: mp, ms, nd (kernels.py)
# The most values of a delay's buffer (tau / step): a larger one is refused with the number (8 bytes each, 512 MiB);
# the library's bound is the machine's memory (scene._check_memory_rules)
DELAY_BOUND = 2**26


def memory_lines(scene) -> list:
    """scene.h's lines of the effects with memory (kernels.memory_layout): which are present, their parameters'
    names, start values and rules (scene.COEFFICIENTS: 0 finite, 1 > 0, 2 >= 0), the state's layout and the rules
    of scene._check_memory_rules (the delay's grid, the buffer's bound, whether the element is quasi-static)."""
    from ...memory import dahl as memory_dahl
    from ...memory import delay as memory_delay
    from ...scene import COEFFICIENTS, _coefficient_key, coefficients_of

    layout = kernels.memory_layout(scene)
    names = layout["names"]
    if scene.delay is not None:  # common.h's delay_size is memory.delay.size; its bound is DELAY_BOUND
        ratio = math.ceil(scene.delay.tau / scene.solver.step)
        if memory_delay.size(scene.delay, scene.solver.step) != memory_delay.HEAD + ratio + 4:
            raise NativeBuildError("the delay's buffer size is not memory.delay.size's: update common.h")
        if ratio > DELAY_BOUND:
            raise NativeBuildError(f"{scene.source}: [delay] tau: tau / step = {scene.delay.tau / scene.solver.step:.4g} "
                                   f"values in the delay's buffer, more than the native runtime's bound of "
                                   f"{DELAY_BOUND} ({DELAY_BOUND * 8 // 2**20} MiB): a longer [solver] step or a "
                                   "shorter tau, or --runtime python")
    values = coefficients_of(scene)
    rules = {"finite": 0, "> 0": 1, ">= 0": 2}
    markers = sorted(offset + i for part in layout["parts"] if part is not None for offset, _, fresh in part[1]
                     for i, source in fresh.items() if source == "np.nan")
    return [
        f"#define HAS_MEMORY {int(bool(names))}",
        f"#define HAS_DELAY {int(layout['delay'])}",
        f"#define HAS_DAHL {int(layout['dahl'])}",
        f"#define NH {layout['nh']} /* the history's terms */",
        f"#define N_MEMP {max(len(names), 1)}",
        f"#define N_MEMORY_PARAMS {len(names)}",
        f"#define MEM_HISTORY_AT {names.index('history_weight[1]') if layout['nh'] else 0} /* in mp */",
        f"#define MEM_DAHL_AT {names.index('dahl_sigma') if layout['dahl'] else 0} /* in mp: sigma, force, exponent */",
        f"#define MEM_DAHL_STATE {layout['dahl_state']}",
        f"#define MEM_FIXED {layout['fixed']} /* the memory's state before the delay's buffer */",
        f"#define DELAY_HEAD {memory_delay.HEAD}",
        f"#define DELAY_GRID {float(scene.solver.step)!r} /* the delay's grid: the scene's step */",
        f"#define DELAY_BOUND {DELAY_BOUND}.0 /* the most values of the delay's buffer */",
        # scene._check_memory_rules' quasi-static element (the connector solves nothing: its motion is given)
        f"#define QUASI_STATIC {int(scene.mass is None and scene.damper is None and scene.causality == 'force')}",
        f"#define DAHL_MAX_EXPONENT {float(memory_dahl.MAX_EXPONENT)!r} /* memory.dahl.MAX_EXPONENT */",
        # the fresh memory's NaN entries (the history's cache marker): the values a state may hold as NaN
        f"#define N_MEM_MARKERS {len(markers)}",
        "static const int MEM_MARKERS[] = {" + ", ".join(str(i) for i in markers or [-1]) + "};",
        "static const char* MEM_NAMES[] = {" + ", ".join([c_string(name) for name in names] or ['""']) + "};",
        f"static const double MEM_SCENE[N_MEMP] = {_c_array(values[name] for name in names)};",
        "static const int MEM_RULE[N_MEMP] = {" + ", ".join(
            [str(rules[COEFFICIENTS[_coefficient_key(name)][1]]) for name in names] or ["0"]) + "};",
    ]


def _c_array(values) -> str:
    values = list(values) or [0.0]
    return "{" + ", ".join(repr(float(value)) for value in values) + "}"


def _scene_header(scene, variables, guid, steppers, symbols, scene_bytes, arrays: bool = False) -> str:
    """scene.h of the element or connector: its arrays, the library's rules, the kernels' symbols, the variables
    (``variables``: the FMI 2.0 list of ``fmu/description.py``, by value reference)."""
    from ..description import fmi3_references, output_derivative_order

    from ... import scene as library_rules
    from ... import stability
    from ...kernels import stack
    from ...kernels.rates import exact_rates
    from ...loads import POLYNOMIAL
    from ...steppers import get_stepper

    branches = scene.branches
    continuum = branches is not None and branches.continuum
    n = 0 if branches is None or continuum else branches.n
    on_stack = kernels.is_stack_scene(scene)
    size = kernels.state_size(scene)
    if continuum:  # the spectrum's table and a state that initial() fills
        k_values, eta_values, u0_values = branches.params[0].ravel(), [], [0.0] * size
    elif on_stack:  # the stack's parameters, (10, n + 1), and a state that initial() fills
        k_values = stack.prepare(branches.stiffness, branches.yield_displacement, branches.u0)[0].ravel()
        eta_values, u0_values = [], [0.0] * size
    else:
        k_values = branches.stiffness if n else []
        eta_values = branches.yield_displacement if n else []
        u0_values = branches.u0 if n else []
    folds = kernels.folds(scene)  # the O(n) kernel's arrays too (exact)
    play_k, play_eta, play_u0 = ((branches.stiffness, branches.yield_displacement, branches.u0) if folds
                                 else ([], [], []))
    values = dict.fromkeys(kernels.PARAMETERS, 0.0)
    present = dict.fromkeys(kernels.PARAMETERS, 0)
    from ...scene import coefficients_of

    for name, value in coefficients_of(scene).items():
        if name in values:
            values[name], present[name] = float(value), 1
    rules = {"m": 1, "x0": 3, "v0": 3, "k0": 2, "k3": 2, "c": 2, "alpha": 1, "alpha_kinetic": 2,
             "stribeck_velocity": 1, "belt_velocity": 3}
    friction = scene.friction
    if friction is not None and friction.stribeck_velocity is None:
        values["alpha_kinetic"] = float(friction.alpha)
    load = scene.load.compile()
    kind, offset, amplitude, omega, times, forces = load[:6]  # (a noise: its settings are parameters)
    digest = hashlib.sha256(scene_bytes + guid.encode()).hexdigest()
    lines = [
        "/* generated by prandtl_fmu.fmu.native.build for one scene: do not edit */",
        "#ifndef PRANDTL_SCENE_H",
        "#define PRANDTL_SCENE_H",
        "#include <stdint.h>",
        *targets.KERNEL_MACRO,
        f"#define NB {n}",
        # the library's rules (prandtl_fmu.scene), never written twice
        f"#define ADVANCE_BUDGET {float(library_rules.ADVANCE_BUDGET)!r} /* the most internal steps of one doStep */",
        f"#define SMALLEST_MAGNITUDE {float(library_rules.SMALLEST_MAGNITUDE)!r} /* a nonzero coefficient's |value| */",
        f"#define LARGEST_MAGNITUDE {float(library_rules.LARGEST_MAGNITUDE)!r}",
        f"#define MAX_STEPS {float(library_rules.MAX_STEPS)!r} /* steps counted exactly */",
        f"#define SHORTEST_STEP {float(library_rules.SHORTEST_STEP)!r}",
        f"#define NB_ARR {max(size, 1)} /* the branches' state: n elongations or the memory stack's */",
        f"#define STACK {int(on_stack)}",
        f"#define STACK_HEADER {stack.HEADER} /* the memory stack's state: header, then rows of pieces */",
        f"#define STACK_ROW {stack.ROW}",
        f"#define FOLDS {int(folds)} /* the stack unfolds to n elongations for exact (kernels.folds) */",
        f"#define NB_PLAY {max(n, 1) if folds else 1}",
        f"#define K_LEN {10 * (n + 1) if folds else 1}",
        f"static const double K_PLAY[] = {_c_array(play_k)};",
        f"static const double ETA_PLAY[] = {_c_array(play_eta)};",
        f"static const double U0_PLAY[] = {_c_array(play_u0)};",
        f"#define CONNECTOR {int(scene.causality == 'displacement')}",
        f"#define NB_CS {max(n, 1)}",
        f"#define HAS_MASS {int(scene.mass is not None)}",
        f"#define HAS_DAMPER {int(scene.damper is not None)}",
        f"#define HAS_SPRING {int(scene.spring is not None)}",
        f"#define HAS_CUBIC {int(scene.cubic is not None)}",
        f"#define K_SUM {float(branches.stiffness_sum) if branches is not None else 0.0!r} /* the branches' "
        "stiffness, all sticking */",
        f"static const double K_BRANCH[] = {_c_array(branches.stiffness if n else [])};",
        f"#define HAS_FRICTION {int(friction is not None)}",
        f"#define HAS_STRIBECK {int(friction is not None and friction.stribeck_velocity is not None)}",
        f"#define HAS_SERIES {int(scene.has_series_dashpots)}",
        f"#define EXACT_RATES {int(exact_rates(scene))} /* kernels/rates.exact_rates: a' and R' are exact */",
        f"#define OUTPUT_DERIVATIVE_ORDER {output_derivative_order(scene, 'native')} /* maxOutputDerivativeOrder */",
        f'static const char GUID[] = "{guid}";',
        f'static const char DIGEST[] = "{digest}";',
        f"static const double P_SCENE[10] = {_c_array(values.values())};",
        f"static const int P_PRESENT[10] = {{{', '.join(str(v) for v in present.values())}}};",
        f"static const int P_RULE[10] = {{{', '.join(str(rules[name]) for name in kernels.PARAMETERS)}}};",
        # 1: a value (scene.VALUES: the upper magnitude bound only), 0: a coefficient
        f"static const int P_VALUE[10] = {{{', '.join(str(int(name in library_rules.VALUES)) for name in kernels.PARAMETERS)}}};",
        f"static const double K[] = {_c_array(k_values)};",
        f"static const double ETA[] = {_c_array(eta_values)};",
        f"static const double U0[NB_ARR] = {_c_array(u0_values)};",
        f"static const double CS_SCENE[NB_CS] = "
        f"{_c_array(branches.damping if scene.has_series_dashpots else [1.0] * max(n, 1))};",
        f"static const int64_t LOAD_KIND = {int(kind)};",
        f"static const double LOAD_LK[3] = {_c_array([offset, amplitude, omega])};",
        f"static const double LOAD_T[{max(len(times), 1)}] = {_c_array(times)};",
        f"static const double LOAD_F[{max(len(forces), 1)}] = {_c_array(forces)};",
        f"static const int64_t LOAD_N = {len(times)};",
        f"#define N_STEPPERS {len(steppers)}",
        "static const char* STEPPER_NAMES[] = {" + ", ".join(f'"{name}"' for name in steppers) + "};",
        f'static const char STEPPER_LIST[] = "{", ".join(steppers)}";',
        "static const int TAKES_STACK[] = {" + ", ".join(
            [str(int(kernels.takes_stack(name))) for name in steppers] + ["0"]) + "};",
        # stability.check's kind of each stepper and its findings (element.h words them as stability.explain)
        "static const int64_t STEPPER_STABILITY[] = {" + ", ".join(
            [str(stability.stepper_kind(name)) for name in steppers] + ["0"]) + "};",
        f"enum {{ STABLE = {stability.STABLE}, LEAPFROG_UNSTABLE = {stability.LEAPFROG_UNSTABLE}, "
        f"RELAXATION_UNSTABLE = {stability.RELAXATION_UNSTABLE}, GROWTH_UNSTABLE = {stability.GROWTH_UNSTABLE}, "
        f"STRIBECK_UNRESOLVED = {stability.STRIBECK_UNRESOLVED}, SERIES_UNSTABLE = {stability.SERIES_UNSTABLE} }};",
        "static const int STEP_IS_OUTPUT[] = {" + ", ".join(
            [str(int(getattr(get_stepper(name), "STEP_IS_OUTPUT", False))) for name in steppers] + ["0"]) + "};",
        # an input given with its derivatives (loads.polynomial): its load kind, and the steppers that take it
        f"static const int64_t LOAD_POLYNOMIAL = {POLYNOMIAL};",
        "static const int POLYNOMIAL_INPUT[] = {" + ", ".join(
            [str(int(getattr(get_stepper(name), "POLYNOMIAL_INPUT", True))) for name in steppers] + ["0"]) + "};",
        f'static const char DEFAULT_STEPPER[] = "{scene.solver.stepper}";',
        f"static const double DEFAULT_STEP = {float(scene.solver.step)!r};",
        f"static const int N_VALUE = {-1 if branches is not None and branches.continuum else n};",
        # FMI 3.0: the scalars u_1 .. u_n always, the array u and its structural parameter n with arrays only
        f"#define ARRAYS {int(arrays)}",
        f"#define VR_U_FIRST {fmi3_references(scene)['u_1']}u /* u_1; u_i is VR_U_FIRST + i - 1 */",
        "#define STRUCTURAL_N NB",
        "#define HAS_STRUCTURAL ARRAYS",
        '#define STRUCTURAL_TEXT "n is the scene\'s number of branches"',
        "typedef double* P;",
        f"typedef int64_t (*advance_fn)({ELEMENT_ARGS}, P, P, P, int64_t, P, P, P, int64_t, double, int64_t, "
        "double, int64_t);",
        f"typedef int64_t (*noisy_fn)({ELEMENT_ARGS}, P, P, P, int64_t, P, P, P, int64_t, double, int64_t, "
        "double, int64_t, double, int64_t, double, int64_t*);",
        *memory_lines(scene),
        *noise_lines(scene, scene.causality == "displacement"),
        *scene_load_lines(scene, "the element"),
        # the library's refusal of a white noise by each stepper (steppers' loop_for), NULL: it takes one
        "static const char* NOISE_REFUSAL[] = {" + ", ".join(
            [c_string(reason) if reason else "NULL" for reason in (kernels.noise_refusal(scene, name)
                                                                   for name in steppers)] + ["NULL"]) + "};",
    ]
    variants = [suffix for suffix, _ in kernels.variants(scene)]
    e = ELEMENT_ARGS  # the element's arrays and its memory (kernels.py)
    declarations = {
        "advance": "int64_t {name}(" + e + ", P, P, P, int64_t, P, P, P, int64_t, double, int64_t, double, "
                   "int64_t)",
        "noisy": "int64_t {name}(" + e + ", P, P, P, int64_t, P, P, P, int64_t, double, int64_t, double, "
                 "int64_t, double, int64_t, double, int64_t*)",
        "record": "int64_t {name}(" + e + ", P, P, P, P, int64_t, P, P, P, int64_t, double)",
        "stiffness": "double {name}(" + e + ", P)",
        "limits": "int64_t {name}(" + e + ", P)",
        "row": "int64_t {name}(" + e + ", P, P, P)",
        "initial": "int64_t {name}(" + e + ", P, int64_t, P, P, P, int64_t)",
        "rates": "int64_t {name}(" + e + ", P, int64_t, P, P, P, int64_t, double, P)",
        # the connector's own (kernels._CONNECTOR_SIGNATURES: the element's arrays and memory; its elongations
        # the branches' arrays alone)
        "elongations": ("int64_t {name}(P, P, P, P, P, P)" if scene.causality == "displacement"
                        else "int64_t {name}(" + e + ", P)"),
        "move": "int64_t {name}(" + e + ", double, double, double, P, P, P, P, P)",
        "cpath": "int64_t {name}(" + e + ", double, double, P, P, double, P, P)",
        "cforce": "double {name}(" + e + ", double, double, double)",
        "ctangent": "double {name}(" + e + ", double, double)",
        "cdirectional": "double {name}(" + e + ", double, double, double, double)",
        "crates": "int64_t {name}(" + e + ", double, double, P, P, double, P)",
        "cstored": "double {name}(" + e + ", double)",
        "cinitial": "int64_t {name}(" + e + ")",
    }
    if not folds:
        lines.append("#define stack_fold(k, u, x, state) 0")
    if "state_check" not in symbols:
        lines.append("#define state_check(k, state, scratch) 0")
    lines.append("static const char* STATE_CHECK_REASONS[] = {"
                 + ", ".join(f'"{reason}"' for reason in kernels.STATE_CHECK_REASONS[1:]) + "};")
    for name, symbol in symbols.items():
        if name == "force_at":
            lines.append(f'double scene_force_at(int64_t, P, P, P, int64_t, double, P) KERNEL("{symbol}");')
        elif name == "fold":
            lines.append(f'int64_t stack_fold(P, P, double, P) KERNEL("{symbol}");')
        elif name == "state_check":
            lines.append(f'int64_t state_check(P, P, P) KERNEL("{symbol}");')
        elif name == "stability":
            lines.append(f'int64_t stability_check(P, P, double, double, int64_t, P) KERNEL("{symbol}");')
        else:
            lines.append(declarations[name.split("_")[0]].format(name=name) + f' KERNEL("{symbol}");')
    connector = scene.causality == "displacement"
    functions = (("move", "cpath", "cforce", "ctangent", "cdirectional", "crates", "cstored", "cinitial",
                  "elongations")
                 if connector else ("record", "row", "stiffness", "limits", "initial", "elongations", "rates"))
    for suffix in ("c", "n"):
        chosen = suffix if suffix in variants else variants[0]
        unfolded = chosen + "p" if folds else chosen  # the O(n) kernel's functions: what exact runs on
        if not connector:
            lines.append(f"static const advance_fn ADVANCE_{suffix.upper()}[N_STEPPERS] = {{" + ", ".join(
                f"advance_{name}_{chosen if kernels.takes_stack(name) or not folds else unfolded}"
                for name in steppers) + "};")
            lines.append(f"static const advance_fn ADVANCE_{suffix.upper()}P[N_STEPPERS] = {{"
                         + ", ".join(f"advance_{name}_{unfolded}" for name in steppers) + "};")
            noisy = {name: f"noisy_{name}_{chosen if kernels.takes_stack(name) or not folds else unfolded}"
                     for name in steppers}  # NULL: the stepper takes no noise
            lines.append(f"static const noisy_fn NOISY_{suffix.upper()}[N_STEPPERS] = {{" + ", ".join(
                noisy[name] if noisy[name] in symbols else "NULL" for name in steppers) + "};")
            lines.append(f"static const noisy_fn NOISY_{suffix.upper()}P[N_STEPPERS] = {{" + ", ".join(
                f"noisy_{name}_{unfolded}" if f"noisy_{name}_{unfolded}" in symbols else "NULL"
                for name in steppers) + "};")
        for function in functions:
            lines.append(f"#define {function}_{suffix} {function}_{chosen}")
            if not connector:
                lines.append(f"#define {function}_{suffix}p {function}_{unfolded}")
    lines += [
        "enum { T_REAL, T_INTEGER, T_BOOLEAN, T_STRING };",
        "enum { W_F, W_X, W_V, W_REACTION, W_STIFFNESS, W_ENERGY, W_PARAM, W_CBRANCH, W_STEP, W_SCENE_LOAD, "
        "W_STEPPER, W_N, W_FORCE, W_NOISE_INTENSITY, W_NOISE_SEED, W_NOISE_UNIT, W_MEMORY };",
        "typedef struct { unsigned vr; int type; int what; int index; const char* name; } Var;",
        "static const Var VARS[] = {",
    ]
    count = 0
    memory_names = kernels.memory_layout(scene)["names"]
    for row in variables:
        what, index = _what(row.name, memory_names)
        lines.append(f'    {{{row.value_reference}, {C_TYPES[row.type]}, {what}, {index}, "{row.name}"}},')
        count += 1
    first = variables[0].value_reference  # (in order, without a gap: find() indexes VARS by vr - VR_FIRST)
    if [row.value_reference for row in variables] != list(range(first, first + count)):
        raise NativeBuildError("the FMU variables' value references are not in order without a gap")
    lines += ["};", f"#define N_VARS {count}", f"#define VR_FIRST {first}u", "#endif", ""]
    return "\n".join(lines)


def _what(name: str, memory_names=()) -> tuple:
    fixed = {"F": "W_F", "x": "W_X", "v": "W_V", "reaction": "W_REACTION", "stiffness": "W_STIFFNESS",
             "force": "W_FORCE", "step": "W_STEP", "scene_load": "W_SCENE_LOAD", "stepper": "W_STEPPER", "n": "W_N",
             "noise_intensity": "W_NOISE_INTENSITY", "noise_seed": "W_NOISE_SEED", "noise_unit": "W_NOISE_UNIT"}
    if name in fixed:
        return fixed[name], 0
    if name in ENERGIES:
        return "W_ENERGY", ENERGIES.index(name)
    if name in kernels.PARAMETERS:
        return "W_PARAM", kernels.PARAMETERS.index(name)
    if name in memory_names:
        return "W_MEMORY", list(memory_names).index(name)
    if name == "c_branch":
        return "W_CBRANCH", -1
    match = re.fullmatch(r"c_branch\[(\d+)\]", name)
    if match:
        return "W_CBRANCH", int(match.group(1)) - 1
    raise NativeBuildError(f"the native runtime does not know the FMU variable {name!r}")


def fmi3_description(root, scene, vr_u=None, arrays: bool = False) -> str:
    """The native FMU's FMI 3.0 description of the element or connector ``scene``
    (``description.model_description(scene, 3)``), with the GUID of its FMI 2.0 description ``root``, for a
    caller that holds that one (docs/gen_pages.py); ``vr_u``: not read (FMI 3.0's value references are the
    variables' positions, ``description.fmi3_references``)."""
    from .. import description

    return description.model_description(scene, 3, root.get("guid", ""), arrays=arrays)
