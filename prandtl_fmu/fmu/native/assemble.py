"""What the native builds of the element (``build.py``) and of a network (``network_build.py``) share: the C text
they generate for ``scene.h`` and ``stubs.c`` (a string literal, the white noise's lines, the variables' table, the
stubs of what numba's code needs from Python and numba's runtime) and the FMU they pack.

The FMU holds ``modelDescription.xml`` (``fmu/description.py``, FMI 2.0 or 3.0), a binary per platform,
``documentation/index.html``, ``resources/scene.toml`` (the scene it was built from) and
``resources/<modelIdentifier>_OspModelDescription.xml`` (``fmu/osp.py``).
"""
from __future__ import annotations

import os
import uuid
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
FMI_HEADERS = {2: HERE.parent / "python" / "loader" / "src" / "fmi", 3: HERE / "fmi3"}
# the C layer's type of a variable (scene.h's VARS), by its type in fmu/description.py
C_TYPES = {"Float64": "T_REAL", "Int32": "T_INTEGER", "Boolean": "T_BOOLEAN", "String": "T_STRING"}


class NativeBuildError(ValueError):
    """A native FMU cannot be built (one line: the scene or the machine, and what to do)."""


def chosen_steppers(scene, available: list, wanted) -> list:
    """The steppers a native FMU of ``scene`` holds: ``available`` (those that apply), or only those of ``wanted``
    (``--steppers``: a comma-separated string or a list; None: all), in ``available``'s order. Each wanted one
    must apply, and the scene's own ``[solver] stepper`` (the FMU's default) must be among them: NativeBuildError
    names the culprit. Fewer steppers: fewer loops to compile, a smaller binary; the FMU refuses the others."""
    if wanted is None:
        return list(available)
    names = [name.strip() for name in (wanted.split(",") if isinstance(wanted, str) else wanted)]
    if not names or any(not name for name in names):
        raise NativeBuildError(f"--steppers {','.join(names)}: an empty name")
    for name in names:
        if name not in available:
            raise NativeBuildError(f"--steppers: {name!r} is not a stepper this scene's native FMU can hold (those "
                                   f"that apply: {', '.join(available) or 'none'})")
    if scene.solver.stepper not in names:
        raise NativeBuildError(f"--steppers {','.join(names)}: must hold the scene's own stepper "
                               f"{scene.solver.stepper!r} ([solver] stepper: the FMU's default)")
    return [name for name in available if name in names]


def c_variables(scene, fmi: int, arrays: bool = False) -> list:
    """The rows of the C layer's table of variables (scene.h's ``VARS``): the FMI 2.0 variables of
    ``fmu/description.py`` (their types as the C layer knows them), each under its value reference in the FMI version
    built (FMI 3.0: its 1-based position in ModelVariables). What FMI 3.0 adds (time, u_i, the arrays) the FMI 3.0
    layer finds by scene.h's VR_* macros, from the same list (``description.fmi3_references``)."""
    import dataclasses

    from .. import description

    rows = description.variables(scene)
    if fmi == 2:
        return rows
    references = {row.name: row.value_reference for row in description.variables(scene, fmi, arrays)}
    return [dataclasses.replace(row, value_reference=references[row.name]) for row in rows]


def new_guid() -> str:
    """A native FMU's GUID (FMI 3.0: instantiation token), new for every build: a state or an instance of
    another build is refused."""
    return str(uuid.uuid4())


def c_string(text: str) -> str:
    """A C string literal of ``text``."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def noise_words() -> dict:
    """The words of each rule of the noise's parameters (``description.check_noise_settings``: the seed an FMU
    takes, then ``loads.white_noise``), what follows "name = value: " in the PythonFMU slave's message."""
    from ..description import check_noise_settings

    words = {}
    for name, bad in (("noise_intensity", -1.0), ("noise_seed", -1), ("noise_unit", 0.0)):
        settings = {"noise_intensity": 0.0, "noise_seed": 0, "noise_unit": 1.0, name: bad}
        try:
            check_noise_settings(settings["noise_intensity"], settings["noise_seed"], settings["noise_unit"])
        except ValueError as exc:
            words[name] = str(exc).split(": ", 1)[1]
    return words


def noise_lines(scene, connector: bool) -> list:
    """scene.h's lines of the white noise: the Brownian tree's cache size, the scene's noise (the start values of
    noise_intensity, noise_seed, noise_unit: none for a connector, whose motion comes in), the seed's bound and
    the words of the parameters' rules (:func:`noise_words`)."""
    from ..description import NOISE_SEED_LIMIT
    from ...noise import CACHE_SIZE

    noise = None if connector else scene.load.noise
    sigma, seed, unit = (noise.intensity, noise.seed, noise.unit) if noise is not None else (0.0, 0, 1.0)
    words = noise_words()
    return [f"#define NOISE_CACHE_SIZE {CACHE_SIZE} /* noise.CACHE_SIZE: int64s */",
            f"#define NOISE_SCENE {{{float(sigma)!r}, {int(seed)}, {float(unit)!r}}} /* the scene's [load] noise */",
            f"#define NOISE_SEED_LIMIT {float(NOISE_SEED_LIMIT)!r} /* an FMI Integer's seed is below */",
            *[f"static const char {name.upper()}_WORDS[] = {c_string(text)};" for name, text in words.items()]]


def scene_load_lines(scene, where: str) -> list:
    """scene.h's lines of ``scene_load`` (``description._scene_load_variable``): its start value (true when the
    scene names a load; a connector has no such parameter: 0) and the warning an instance logs when it leaves
    initialization with it true (``description.scene_load_notice``; ``where``: "the element", "the load's
    node")."""
    from .. import description

    present = any(row.name == "scene_load" for row in description.variables(scene))
    start = present and description.scene_load_start(scene)
    return [f"#define SCENE_LOAD_START {int(start)} /* description.scene_load_start */",
            f"static const char SCENE_LOAD_NOTICE[] = {c_string(description.scene_load_notice(scene, where))};"]


def pack(out, description_text: str, scene, scene_bytes: bytes, identifier: str, folders, binaries,
         steppers=None) -> Path:
    """Write the native FMU ``out`` (in one rename: a failed build leaves no half-written FMU): its model
    description, the binary of each folder, its page (``documentation/index.html``, from the description; the
    steppers it holds when built with ``--steppers``), the scene's text and its OSP interface description."""
    from ..archive import add_entry
    from ..documentation import index_html
    from ..osp import file_name, osp_model_description, port_variables

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    partial = out.with_name(out.name + ".partial")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
        add_entry(archive, "modelDescription.xml", description_text)
        for folder in folders:
            add_entry(archive, f"binaries/{folder.name}/{identifier}.{folder.suffix}", binaries[folder.name],
                      mode=0o755)
        add_entry(archive, "documentation/index.html",
                  index_html(description_text.encode("utf-8"), scene, runtime="native", steppers=steppers))
        add_entry(archive, f"resources/{file_name(identifier)}",
                  osp_model_description(scene.causality, port_variables(scene)))
        add_entry(archive, "resources/scene.toml", scene_bytes)
    os.replace(partial, out)
    return out


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


def stubs(undefined) -> str:
    """C definitions of what the objects need from Python and numba (see the module docstring); ``undefined``:
    the symbols the kernels' modules declare."""
    lines = ["/* generated: numba's error path without Python (prandtl_fmu.fmu.native.build) */", "#include <math.h>",
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
