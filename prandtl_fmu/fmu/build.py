"""Build the FMU of a scene: ``build_fmu(scene_path, out)``, for either runtime (also ``python build_fmu.py`` and
``prandtl-fmu build``).

``runtime="python"`` (the default): the PythonFMU runtime's FMU (``fmu/python/build.py``: the slave script, a copy
of the library and the scene in ``resources/``; it runs in the host's Python). ``runtime="native"``: an FMU whose
binary holds the scene's compiled kernels and a C FMI layer, no Python (``fmu/native/build.py``; a network scene:
``fmu/native/network_build.py``). Both take their model description from ``fmu/description.py`` and the scene
from ``fmu/archive.py``.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Optional, Union

from ..outputs import write_atomically
from ..scene import load_scene, scene_path as resolve_scene
from .archive import check_osp_name, file_stem
from .description import is_network


def build_fmu(scene_path: Union[str, os.PathLike], out: Optional[Union[str, os.PathLike]] = None,
              causality: Optional[str] = None, osp: bool = False, loader: Optional[str] = None,
              runtime: str = "python", fmi: int = 2, arrays: bool = False, platforms=None, steppers=None) -> Path:
    """Build the FMU of the scene at ``scene_path`` (or a packaged scene's name) into ``out`` (default
    ``./<scene name>.fmu``).

    ``causality`` ("force" or "displacement", the connector) overrides a scene without an ``[fmu]`` table
    (SceneError if the scene's table says otherwise). With ``osp``, also write
    ``<modelName>_OspModelDescription.xml`` beside the FMU, where libcosim looks for it (it is always inside
    the FMU, in ``resources/``). ``loader`` is the FMU's native library on Linux x86-64: "prandtl" (None: the
    default), PythonFMU 0.7.0's patched (``fmu/python/loader/``: a refused call is fmi2Error and the instance stays
    usable), or "pythonfmu", PythonFMU's own (refusals fmi2Fatal); the other platforms always get PythonFMU's own.
    The scene is checked first (:class:`SceneError` on any broken rule). Returns the path of the FMU.

    ``runtime="native"``: an FMU whose binary holds the scene's compiled kernels and a C FMI layer, no Python
    (``prandtl_fmu/fmu/native``: the element, FMI 2.0 or, with ``fmi=3``, 3.0); a ``loader`` is refused with it. A
    network scene goes to ``prandtl_fmu.fmu.native.build.build_native_network_fmu`` (ValueError where the native
    runtime has none). FMI 3.0 offers scalar variables only (the element's u_1 .. u_n, a network's x_<node> and
    v_<node>: every master reads them); ``arrays`` (native, FMI 3.0) adds them as arrays (u; x and v) for the
    masters that handle arrays. ``platforms`` (native): the binaries the FMU holds, names of either FMI version
    (comma-separated or a list) or "all"; None: this machine's (``prandtl_fmu/fmu/native/platforms.py``).
    ``steppers`` (native): only these steppers in the binary (comma-separated or a list; None: every one that
    applies to the scene), the scene's own among them: fewer loops to compile, and the FMU refuses the others.
    """
    if runtime not in ("python", "native"):
        raise ValueError(f"--runtime: must be python or native, got {runtime!r}")
    if arrays and (runtime != "native" or fmi != 3):
        raise ValueError("--arrays: arrays are an FMI 3.0 option of the native runtime: build with --runtime native "
                         "--fmi 3, or drop --arrays")
    if platforms is not None and runtime != "native":
        raise ValueError("--platforms: the PythonFMU runtime's binaries are PythonFMU's own: build with --runtime "
                         "native, or drop --platforms")
    if steppers is not None and runtime != "native":
        raise ValueError("--steppers: the PythonFMU runtime compiles a stepper when a run first uses it: build with "
                         "--runtime native, or drop --steppers")
    if runtime == "native" and loader is not None:
        raise ValueError(f"--loader {loader}: the native runtime has no PythonFMU loader (its binary is the FMU's "
                         "own C layer): drop --loader, or build with --runtime python")
    if runtime == "python":
        if fmi != 2:
            raise ValueError(f"--fmi {fmi}: the PythonFMU runtime builds FMI 2.0 FMUs only")
        from .python.build import build_python_fmu

        return build_python_fmu(scene_path, out, causality, osp, loader)
    from .osp import file_name, osp_model_description, port_variables

    native_scene = load_scene(scene_path, check_stepper=False)
    if is_network(native_scene):
        from .native import build as native_build

        build_native = getattr(native_build, "build_native_network_fmu", None)
        if build_native is None:
            raise ValueError("--runtime native: networks are not in the native runtime yet")
    else:
        from .native.build import build_native_fmu as build_native
    target = Path(out) if out is not None else Path.cwd() / f"{file_stem(native_scene.name)}.fmu"
    if target.is_dir():
        raise ValueError(f"{target}: is a directory")
    if osp:
        check_osp_name(native_scene.name)
    built = build_native(resolve_scene(scene_path), target, fmi=fmi, causality=causality, arrays=arrays,
                         platforms=platforms, steppers=steppers)
    if osp:
        kind = causality or native_scene.causality
        write_atomically(target.parent / file_name(native_scene.name),
                         osp_model_description(kind, port_variables(native_scene, kind)).encode("utf-8"))
    return built
