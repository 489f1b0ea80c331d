"""``build_native_fmu``: an FMI 2.0 or 3.0 co-simulation FMU of a scene (the element or the connector) whose
binary holds no Python.

The FMU has the PythonFMU FMU's model description (the same variables, names, value references, units,
causalities, documentation: it is built first, in a scratch folder, and its ``modelDescription.xml`` is
taken with ``needsExecutionTool="false"``; FMI 3.0's is derived from it) and a binary linked from

* the scene's kernels, compiled by numba from the library's own sources (``kernels.py``), as objects;
* ``stubs.c``, generated here: numba's error path, which a kernel reaches only when it raises, sets a
  flag instead of calling Python; the few functions of numba's runtime that ``exact``'s arrays call
  (:data:`NRT`); ``numba_nextafter`` is C's ``nextafter``;
* ``fmi2.c`` or ``fmi3.c``, the FMI layer, over ``element.h`` or ``connector.h`` (with ``common.h``,
  ``state.h``) and the generated ``scene.h``.

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
import os
import re
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from . import kernels
from . import platforms as targets

HERE = Path(__file__).resolve().parent
FMI_HEADERS = HERE.parent / "fmu" / "loader" / "src" / "fmi"
ENERGIES = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
            "dissipated_friction", "energy_residual")
TYPES = {"Real": "T_REAL", "Integer": "T_INTEGER", "Boolean": "T_BOOLEAN", "String": "T_STRING"}


class NativeBuildError(ValueError):
    """A native FMU cannot be built (one line: the scene or the machine, and what to do)."""


def build_native_network_fmu(scene_path, out, fmi: int = 2, causality=None, arrays: bool = False,
                             platforms=None) -> Path:
    """Build the native FMU of the network scene (``[network]`` or ``[chain]``) at ``scene_path`` into ``out``: the
    element (force in at the load's node) or, with causality "displacement", the connector (its motion in, force
    out); ``arrays`` (FMI 3.0): also the nodes' x and v as arrays (scalars x_<node>, v_<node> in any case: masters
    such as OMSimulator and ecos read an FMI 3.0 array as a scalar). See ``network_build.py``; NativeBuildError
    names what stops it."""
    from . import network_build

    if fmi not in (2, 3):
        raise NativeBuildError(f"--fmi {fmi}: must be 2 or 3")
    return network_build.build(scene_path, out, fmi, causality, arrays, NativeBuildError, platforms)


def build_native_fmu(scene_path, out, fmi: int = 2, causality=None, arrays: bool = False, platforms=None) -> Path:
    """Build the native FMU of the scene at ``scene_path`` into ``out``; NativeBuildError names what stops it.

    FMI 3.0 offers the branch elongations as the scalars u_1 .. u_n (every master reads them: OMSimulator and ecos
    read an FMI 3.0 array as a scalar); ``arrays`` (FMI 3.0 only) adds them as the array u, sized by the structural
    parameter n. A network scene goes to :func:`build_native_network_fmu` (its nodes' x and v).

    ``platforms``: the binaries the FMU holds (names of either FMI version, comma-separated, or "all"; None: this
    machine's platform), each linked as ``platforms.py`` says; the names and the toolchains are checked first."""
    from ..fmu.build import add_entry, build_fmu
    from ..fmu.documentation import index_html
    from ..scene import load_scene

    if fmi not in (2, 3):
        raise NativeBuildError(f"--fmi {fmi}: must be 2 or 3")
    scene = load_scene(scene_path, check_stepper=False)
    if hasattr(scene, "network"):  # a [network] or [chain] scene
        return build_native_network_fmu(scene_path, out, fmi, causality, arrays, platforms)
    folders = targets.resolve(platforms, fmi)
    chains = targets.toolchains(folders, default=platforms is None)
    if arrays and fmi != 3:
        raise NativeBuildError("arrays: the elongations u as an array are an FMI 3.0 option (fmi=3)")
    if arrays and elongation_count(scene) == 0:
        raise NativeBuildError("arrays: this scene has no branch elongations to offer as an array (no [branches], "
                               "or a continuum): build it without arrays")
    if causality is not None and causality != scene.causality:
        from ..fmu.build import _with_causality

        scene, _ = _with_causality(scene, Path(scene_path).read_bytes(), causality)
    connector = scene.causality == "displacement"
    out = Path(out)
    with tempfile.TemporaryDirectory(prefix="prandtl_native_") as scratch:
        scratch = Path(scratch)
        python_fmu = build_fmu(scene_path, scratch / "python.fmu", causality=causality)
        with zipfile.ZipFile(python_fmu) as archive:
            description = archive.read("modelDescription.xml").decode("utf-8")
            kept = {name: archive.read(name) for name in archive.namelist()
                    # not documentation/licenses/: PythonFMU's licence goes with its loader, which the native
                    # binary does not hold
                    if (name.startswith("documentation/") and not name.startswith("documentation/licenses/"))
                    or name == "resources/scene.toml"
                    or name.endswith("_OspModelDescription.xml")}
        root = ET.fromstring(description)
        identifier = root.find("CoSimulation").get("modelIdentifier")
        steppers = [] if connector else kernels.applicable(scene)
        if not steppers and not connector:
            raise NativeBuildError("no stepper of the native runtime applies to this scene")
        compiled = kernels.compile_kernels(scene, steppers)
        (scratch / "scene.h").write_text(_scene_header(scene, root, steppers, compiled, scene_path, arrays))
        vr_u = max(int(v.get("valueReference")) for v in root.iter("ScalarVariable")) + 1
        headers = FMI_HEADERS if fmi == 2 else HERE / "fmi3"
        n_vr = next((int(v.get("valueReference")) for v in root.iter("ScalarVariable") if v.get("name") == "n"), 0)
        binaries, _ = targets.build_binaries(folders, chains, compiled, scratch, _stubs, [HERE / f"fmi{fmi}.c"],
                                             [scratch, headers], [f"VR_U={vr_u}", f"VR_N={n_vr}",
                                                                  f"VR_TIME={vr_u + 1}"], fmi, identifier)
        native_description = (_native_description(description) if fmi == 2
                              else fmi3_description(root, scene, vr_u, arrays))
        out.parent.mkdir(parents=True, exist_ok=True)
        partial = out.with_name(out.name + ".partial")
        kept["documentation/index.html"] = index_html(native_description.encode("utf-8"), scene, runtime="native")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            add_entry(archive, "modelDescription.xml", native_description)
            for folder in folders:
                add_entry(archive, f"binaries/{folder.name}/{identifier}.{folder.suffix}", binaries[folder.name],
                          mode=0o755)
            for name, data in kept.items():
                add_entry(archive, name, data)
        os.replace(partial, out)
    return out


def _native_description(description: str) -> str:
    text = description.replace('needsExecutionTool="true"', 'needsExecutionTool="false"')
    return re.sub(r'generationTool="[^"]*"', 'generationTool="prandtl_fmu (native runtime)"', text, count=1)


def c_string(text: str) -> str:
    """A C string literal of ``text``."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def noise_words() -> dict:
    """The PythonFMU's words for each rule of the noise's parameters (``NoiseParameters._check_noise_state``:
    the seed an FMU takes, then ``loads.white_noise``), what follows "name = value: " in its message."""
    from ..fmu.common import NoiseParameters

    words = {}
    for name, bad in (("noise_intensity", -1.0), ("noise_seed", -1), ("noise_unit", 0.0)):
        try:
            NoiseParameters._check_noise_state({"noise_intensity": 0.0, "noise_seed": 0, "noise_unit": 1.0,
                                                name: bad})
        except ValueError as exc:
            words[name] = str(exc).split(": ", 1)[1]
    return words


def noise_lines(scene, connector: bool) -> list:
    """scene.h's lines of the white noise: the Brownian tree's cache size, the scene's noise (the start values of
    noise_intensity, noise_seed, noise_unit: none for a connector, whose motion comes in), the seed's bound and
    the words of the parameters' rules (the PythonFMU's, :func:`noise_words`)."""
    from ..fmu.common import NOISE_SEED_LIMIT

    noise = None if connector else scene.load.noise
    sigma, seed, unit = (noise.intensity, noise.seed, noise.unit) if noise is not None else (0.0, 0, 1.0)
    words = noise_words()
    return [f"#define NOISE_CACHE_SIZE {kernels.NOISE_CACHE_SIZE} /* noise.CACHE_SIZE: int64s */",
            f"#define NOISE_SCENE {{{float(sigma)!r}, {int(seed)}, {float(unit)!r}}} /* the scene's [load] noise */",
            f"#define NOISE_SEED_LIMIT {float(NOISE_SEED_LIMIT)!r} /* fmu.common: an FMI Integer's seed is below */",
            *[f"static const char {name.upper()}_WORDS[] = {c_string(text)};" for name, text in words.items()]]


ELEMENT_ARGS = "P, P, P, P, P, P, P, int64_t"  # p, k, eta, cs, u; the memory: mp, ms, nd (kernels.py)
# The most values of a delay's buffer (tau / step): a larger one is refused with the number (8 bytes each, 512 MiB);
# the library's bound is the machine's memory (scene._check_memory_rules)
DELAY_BOUND = 2**26


def memory_lines(scene) -> list:
    """scene.h's lines of the effects with memory (kernels.memory_layout): which are present, their parameters'
    names, start values and rules (scene.COEFFICIENTS: 0 finite, 1 > 0, 2 >= 0), the state's layout and the rules
    of scene._check_memory_rules (the delay's grid, the buffer's bound, whether the element is quasi-static)."""
    from ..memory import dahl as memory_dahl
    from ..memory import delay as memory_delay
    from ..scene import COEFFICIENTS, _coefficient_key, coefficients_of

    layout = kernels.memory_layout(scene)
    names = layout["names"]
    if scene.delay is not None:  # element.h's delay_size is memory.delay.size; its bound is DELAY_BOUND
        ratio = math.ceil(scene.delay.tau / scene.solver.step)
        if memory_delay.size(scene.delay, scene.solver.step) != memory_delay.HEAD + ratio + 4:
            raise NativeBuildError("the delay's buffer size is not memory.delay.size's: update element.h")
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


def elongation_count(scene) -> int:
    """n, the branch elongations u_1 .. u_n an FMU offers: 0 without branches or for the continuum."""
    branches = scene.branches
    return 0 if branches is None or branches.continuum else branches.n


def elongation_references(root) -> tuple:
    """(VR_U, VR_TIME, VR_U_FIRST): the value references the native FMU adds after the PythonFMU FMU's ``root``:
    the array u (FMI 3.0 with arrays), time (FMI 3.0), then the scalars u_1 .. u_n (FMI 3.0)."""
    vr_u = max(int(v.get("valueReference")) for v in root.iter("ScalarVariable")) + 1
    return vr_u, vr_u + 1, vr_u + 2


def _scene_header(scene, root, steppers, compiled, scene_path, arrays: bool = False) -> str:
    from .. import scene as library_rules
    from ..kernels import stack
    from ..steppers import get_stepper

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
    from ..scene import coefficients_of

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
    symbols = {name: function.native_name for name, function in compiled}
    guid = root.get("guid")
    digest = hashlib.sha256(Path(scene_path).read_bytes() + guid.encode()).hexdigest()
    lines = [
        "/* generated by prandtl_fmu.native.build for one scene: do not edit */",
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
        "static const int STEP_IS_OUTPUT[] = {" + ", ".join(
            [str(int(getattr(get_stepper(name), "STEP_IS_OUTPUT", False))) for name in steppers] + ["0"]) + "};",
        f'static const char DEFAULT_STEPPER[] = "{scene.solver.stepper}";',
        f"static const double DEFAULT_STEP = {float(scene.solver.step)!r};",
        f"static const int N_VALUE = {-1 if branches is not None and branches.continuum else n};",
        # FMI 3.0: the scalars u_1 .. u_n always, the array u and its structural parameter n with arrays only
        f"#define ARRAYS {int(arrays)}",
        f"#define VR_U_FIRST {elongation_references(root)[2]}u /* u_1; u_i is VR_U_FIRST + i - 1 */",
        "#define STRUCTURAL_N NB",
        "#define HAS_STRUCTURAL ARRAYS",
        '#define STRUCTURAL_TEXT "n is the scene\'s number of branches"',
        "typedef double* P;",
        f"typedef int64_t (*advance_fn)({ELEMENT_ARGS}, P, P, P, P, int64_t, P, P, P, int64_t, double, int64_t, "
        "double, int64_t);",
        f"typedef int64_t (*noisy_fn)({ELEMENT_ARGS}, P, P, P, P, int64_t, P, P, P, int64_t, double, int64_t, "
        "double, int64_t, double, int64_t, double, int64_t*);",
        *memory_lines(scene),
        *noise_lines(scene, scene.causality == "displacement"),
        # the library's refusal of a white noise by each stepper (steppers' loop_for), NULL: it takes one
        "static const char* NOISE_REFUSAL[] = {" + ", ".join(
            [c_string(reason) if reason else "NULL" for reason in (kernels.noise_refusal(scene, name)
                                                                   for name in steppers)] + ["NULL"]) + "};",
    ]
    variants = [suffix for suffix, _ in kernels.variants(scene)]
    e = ELEMENT_ARGS  # the element's arrays and its memory (kernels.py)
    declarations = {
        "advance": "int64_t {name}(" + e + ", P, P, P, P, int64_t, P, P, P, int64_t, double, int64_t, double, "
                   "int64_t)",
        "noisy": "int64_t {name}(" + e + ", P, P, P, P, int64_t, P, P, P, int64_t, double, int64_t, double, "
                 "int64_t, double, int64_t, double, int64_t*)",
        "record": "int64_t {name}(" + e + ", P, P, P, P, int64_t, P, P, P, int64_t, double)",
        "stiffness": "double {name}(" + e + ", P)",
        "initial": "int64_t {name}(" + e + ", P, int64_t, P, P, P, int64_t)",
        # the connector's own (kernels._CONNECTOR_SIGNATURES: the element's arrays and memory; its elongations
        # the branches' arrays alone)
        "elongations": ("int64_t {name}(P, P, P, P, P, P)" if scene.causality == "displacement"
                        else "int64_t {name}(" + e + ", P)"),
        "move": "int64_t {name}(" + e + ", double, double, double, P, P, P, P, P)",
        "cforce": "double {name}(" + e + ", double, double, double)",
        "ctangent": "double {name}(" + e + ", double, double)",
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
        else:
            lines.append(declarations[name.split("_")[0]].format(name=name) + f' KERNEL("{symbol}");')
    connector = scene.causality == "displacement"
    functions = (("move", "cforce", "ctangent", "cstored", "cinitial", "elongations") if connector
                 else ("record", "stiffness", "initial", "elongations"))
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
    for variable in root.find("ModelVariables"):
        name = variable.get("name")
        vr = int(variable.get("valueReference"))
        type_name = next(child.tag for child in variable if child.tag in TYPES)
        what, index = _what(name, memory_names)
        lines.append(f'    {{{vr}, {TYPES[type_name]}, {what}, {index}, "{name}"}},')
        count += 1
    lines += ["};", f"#define N_VARS {count}", "#endif", ""]
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


# numba's runtime for the arrays a kernel allocates (exact's matrix exponential): the few functions the modules call,
# with numba's MemInfo layout (numba/core/runtime/nrt.cpp, 0.58-0.68: refct, dtor, dtor_info, data, size,
# external allocator; the modules define NRT_incref/NRT_decref themselves and read refct and data in place)
NRT_PROVIDED = {"NRT_Allocate", "NRT_Free", "NRT_MemInfo_alloc", "NRT_MemInfo_alloc_aligned",
                "NRT_MemInfo_alloc_safe_aligned", "NRT_MemInfo_call_dtor"}
NRT = """
#include <stdint.h>
typedef void (*NRT_dtor_function)(void* data, size_t size, void* info);
typedef struct { size_t refct; NRT_dtor_function dtor; void* dtor_info; void* data; size_t size; void* allocator; } NRT_MemInfo;
void* NRT_Allocate(size_t size) { return malloc(size); }
void NRT_Free(void* ptr) { free(ptr); }
static NRT_MemInfo* meminfo(size_t size, unsigned align)
{
    NRT_MemInfo* mi = (NRT_MemInfo*)malloc(sizeof(NRT_MemInfo) + size + 2 * (size_t)align);
    uintptr_t data;
    if (mi == NULL) { prandtl_kernel_failed = 1; return NULL; }
    data = (uintptr_t)(mi + 1);
    if (align > 1 && data % align)
        data += align - data % align;
    mi->refct = 1; mi->dtor = NULL; mi->dtor_info = NULL; mi->data = (void*)data; mi->size = size; mi->allocator = NULL;
    return mi;
}
NRT_MemInfo* NRT_MemInfo_alloc(size_t size) { return meminfo(size, 0); }
NRT_MemInfo* NRT_MemInfo_alloc_aligned(size_t size, unsigned align) { return meminfo(size, align); }
NRT_MemInfo* NRT_MemInfo_alloc_safe_aligned(size_t size, unsigned align) { return meminfo(size, align); }
void NRT_MemInfo_call_dtor(NRT_MemInfo* mi)
{
    if (mi->dtor) mi->dtor(mi->data, mi->size, mi->dtor_info);
    free(mi);
}
"""


def _stubs(undefined) -> str:
    """C definitions of what the objects need from Python and numba (see the module docstring); ``undefined``:
    the symbols the kernels' modules declare."""
    lines = ["/* generated: numba's error path without Python (prandtl_fmu.native.build) */", "#include <math.h>",
             "#include <stdlib.h>", "__thread int prandtl_kernel_failed;", "static char dummy[64];"]
    if any(symbol.startswith("NRT_") for symbol in undefined):
        lines.append(NRT)
    for symbol in sorted(undefined):
        if symbol in NRT_PROVIDED:
            continue
        if symbol == "numba_nextafter":
            lines.append("double numba_nextafter(double a, double b) { return nextafter(a, b); }")
        elif symbol == "numba_frexp":  # numba's helpers (_helperlib.c), the same special cases
            lines.append("double numba_frexp(double x, int* e) { if (!isfinite(x) || x == 0) { *e = 0; return x; } "
                         "return frexp(x, e); }")
        elif symbol == "numba_ldexp":
            lines.append("double numba_ldexp(double x, int e) { return isfinite(x) && x != 0 && e ? ldexp(x, e) : x; }")
        elif symbol.startswith("PyExc_"):
            lines.append(f"void* {symbol} = dummy;")
        elif symbol.startswith(("Py", "_Py", "NRT_", "numba_")):
            lines.append(f"void* {symbol}(void) {{ prandtl_kernel_failed = 1; return dummy; }}")
    return "\n".join(lines) + "\n"


def fmi3_description(root, scene, vr_u, arrays: bool = False) -> str:
    """The FMI 3.0 model description from the FMI 2.0 one (one list of variables: the PythonFMU FMU's): the same
    scalars (Real -> Float64, Integer -> Int32, with their value references, units, causalities, variabilities,
    start values and dependencies), the independent variable ``time`` and the branch elongations as the scalars
    u_1 .. u_n (Float64 outputs, none without branches). With ``arrays`` also the array u of n Float64, sized by n,
    which becomes a structural parameter (UInt64, fixed, start n >= 1); without, n stays what FMI 2.0 says, a local
    Int32 constant (-1 for the continuum)."""
    n = elongation_count(scene)
    _, vr_time, vr_first = elongation_references(root)
    if vr_time != vr_u + 1:
        raise NativeBuildError("the FMI 3.0 description's value references do not follow the FMI 2.0 one's")
    top = ET.Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": root.get("modelName"), "instantiationToken": root.get("guid"),
        "description": root.get("description", ""), "author": root.get("author", ""),
        "version": root.get("version", ""), "generationTool": "prandtl_fmu (native runtime)",
        "variableNamingConvention": "structured"})
    cosim = root.find("CoSimulation")
    ET.SubElement(top, "CoSimulation", {
        "modelIdentifier": cosim.get("modelIdentifier"), "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false", "canGetAndSetFMUState": "true",
        "canSerializeFMUState": "true", "canHandleVariableCommunicationStepSize": "true",
        "providesIntermediateUpdate": "false", "canReturnEarlyAfterIntermediateUpdate": "false",
        "hasEventMode": "false"})
    for name in ("UnitDefinitions", "LogCategories", "DefaultExperiment"):
        if root.find(name) is not None:
            top.append(root.find(name))
        if name == "LogCategories" and top.find(name) is not None:  # the statuses are FMI 3.0's
            for category in top.find(name):
                if category.get("description"):
                    category.set("description", category.get("description").replace("fmi2", "fmi3"))
        if name == "UnitDefinitions":  # the independent variable's unit, and the elongations'
            units = top.find("UnitDefinitions")
            if units is None:
                units = ET.SubElement(top, "UnitDefinitions")
            for unit, base in (("s", {"s": "1"}), ("m", {"m": "1"})):
                if (unit == "s" or n) and not any(known.get("name") == unit for known in units):
                    ET.SubElement(ET.SubElement(units, "Unit", {"name": unit}), "BaseUnit", base)
    variables = ET.SubElement(top, "ModelVariables")
    ET.SubElement(variables, "Float64", {"name": "time", "valueReference": str(vr_time), "causality": "independent",
                                         "variability": "continuous", "unit": "s",
                                         "description": "the element's time"})
    scalars = list(root.find("ModelVariables"))
    index_to_vr = {}
    outputs = []
    for position, variable in enumerate(scalars, start=1):
        name, vr = variable.get("name"), variable.get("valueReference")
        index_to_vr[position] = vr
        kind = next(child for child in variable if child.tag in TYPES)
        attributes = {"name": name, "valueReference": vr}
        if variable.get("description"):
            attributes["description"] = variable.get("description")
        if name == "n" and arrays:  # the array's size: a structural parameter, n >= 1 (arrays needs branches)
            ET.SubElement(variables, "UInt64", dict(attributes, causality="structuralParameter", variability="fixed",
                                                    start=str(n)))
            continue
        for key in ("causality", "variability", "initial"):
            if variable.get(key):
                attributes[key] = variable.get(key)
        if kind.tag == "String":
            element = ET.SubElement(variables, "String", attributes)
            if kind.get("start") is not None:
                ET.SubElement(element, "Start", {"value": kind.get("start")})
            continue
        tag = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean"}[kind.tag]
        for key in ("start", "unit", "min", "max"):
            if kind.get(key) is not None:
                attributes[key] = kind.get(key)
        ET.SubElement(variables, tag, attributes)
        if variable.get("causality") == "output":
            outputs.append(vr)
    dependencies = {}
    old = root.find("ModelStructure/Outputs")
    for unknown in (old if old is not None else []):
        vr = index_to_vr[int(unknown.get("index"))]
        if unknown.get("dependencies") is not None:
            dependencies[vr] = " ".join(index_to_vr[int(i)] for i in unknown.get("dependencies").split())
    # the elongations are states (the connector's too: they move at doStep only): no input acts on them directly
    for i in range(1, n + 1):
        vr = str(vr_first + i - 1)
        ET.SubElement(variables, "Float64", {
            "name": f"u_{i}", "valueReference": vr, "causality": "output", "variability": "continuous",
            "unit": "m", "description": f"elongation u_{i} of the spring of Prandtl branch {i}"})
        outputs.append(vr)
        dependencies[vr] = ""
    if arrays:
        u = ET.SubElement(variables, "Float64", {
            "name": "u", "valueReference": str(vr_u), "causality": "output", "variability": "continuous",
            "unit": "m", "description": "elongations u_i of the springs of the Prandtl branches, in the scene's order "
                                        "(the scalars u_1 .. u_n as one array)"})
        n_vr = next(v.get("valueReference") for v in scalars if v.get("name") == "n")
        ET.SubElement(u, "Dimension", {"valueReference": n_vr})
        outputs.append(str(vr_u))
        dependencies[str(vr_u)] = ""
    structure = ET.SubElement(top, "ModelStructure")
    for tag in ("Output", "InitialUnknown"):
        for vr in outputs:
            attributes = {"valueReference": vr}
            if vr in dependencies:
                attributes["dependencies"] = dependencies[vr]
            ET.SubElement(structure, tag, attributes)
    ET.indent(top)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(top, encoding="unicode") + "\n"
