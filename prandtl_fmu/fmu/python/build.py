"""The PythonFMU runtime's build: ``build_python_fmu``, what ``build_fmu`` runs for ``runtime="python"``.

Every FMU has the one slave class (``slave.py``), which takes its kind from the scene it carries (the element or a
network, driven by a force or as a connector: ``kinds.py``); its model identifier is the kind's
(``description.model_identifier``: PrandtlElement, PrandtlConnector, PrandtlNetwork, PrandtlNetworkConnector),
which names its binaries. The FMU holds, in ``resources/``: the slave script under a unique module name
(``prandtl_slave_<digest>``, the digest of the library's sources: ``entry.py``), a copy of the
library (``prandtl_fmu/``, the code the tests run), the scene (``scene.toml``) and the OSP interface description
(``<modelIdentifier>_OspModelDescription.xml``, see ``fmu/osp.py``); ``documentation/index.html`` with the
equations and the variables; its model description is ``fmu/description.py``'s (the slaves hand it to PythonFMU's
builder). The host needs Python with numpy and numba (and nothing else): PythonFMU FMUs run in the host's Python.
"""
from __future__ import annotations

import shutil
import sys
import tempfile
import zipfile
from pathlib import Path

from ...outputs import write_atomically
from ..archive import add_entry, built_scene, check_osp_name, file_stem
from ..description import model_identifier

LIBRARY = Path(__file__).resolve().parent.parent.parent  # the prandtl_fmu package
ENTRY = Path(__file__).resolve().parent / "entry.py"


def _library_files():
    for path in sorted(LIBRARY.rglob("*.py")):
        if "__pycache__" not in path.parts:
            yield path


def _digest() -> str:
    """The library's sources (the digest that also names the kernel cache, ``_jit.py``): FMUs built from other
    sources never share their script's module nor their library in a host, and FMUs of the same sources share
    both, whatever their scenes and loaders (the scene is read by each instance from its own resources, the loader
    marks each execution of the script: ``entry.py``), so their kernels compile once for all of them."""
    from ..._jit import source_digest

    return source_digest()[:12]


def build_python_fmu(scene_path, out=None, causality=None, osp: bool = False, loader=None) -> Path:
    """Build the PythonFMU FMU of the scene at ``scene_path`` into ``out`` (``build_fmu``'s arguments: see
    there); returns its path."""
    from pythonfmu import FmuBuilder

    from . import loader as native
    from ..osp import file_name, osp_model_description, port_variables

    loader = "prandtl" if loader is None else loader
    if loader not in native.LOADERS:
        raise ValueError(f"--loader: must be one of {', '.join(native.LOADERS)}, got {loader!r}")
    if loader == "prandtl" and native.stale():
        raise RuntimeError(native.stale())
    scene, scene_bytes = built_scene(scene_path, causality)
    out = Path(out) if out is not None else Path.cwd() / f"{file_stem(scene.name)}.fmu"
    if out.is_dir():
        raise ValueError(f"{out}: is a directory")
    if out.suffix != ".fmu":
        raise ValueError(f"{out}: the FMU file name must end in .fmu")
    if not out.parent.is_dir():
        raise ValueError(f"{out}: the folder {out.parent} does not exist")
    sidecar = out.parent / file_name(scene.name) if osp else None
    if osp:
        check_osp_name(scene.name)
    identifier = model_identifier(scene)
    osp_text = osp_model_description(scene.causality, port_variables(scene))
    module = f"prandtl_slave_{_digest()}"
    with tempfile.TemporaryDirectory(prefix="prandtl_fmu_build_") as staging:
        staging = Path(staging)
        script = staging / f"{module}.py"
        script.write_text(ENTRY.read_text(encoding="utf-8"), encoding="utf-8")
        (staging / "scene.toml").write_bytes(scene_bytes)
        (staging / file_name(identifier)).write_text(osp_text, encoding="utf-8")
        package = staging / "prandtl_fmu"
        for path in _library_files():
            target = package / path.relative_to(LIBRARY)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(path, target)
        built = staging / "out" / f"{identifier}.fmu"
        built.parent.mkdir()
        try:
            FmuBuilder.build_FMU(script, dest=built, project_files=[package, staging / "scene.toml",
                                                                    staging / file_name(identifier)],
                                 canGetAndSetFMUstate=True, canSerializeFMUstate=True)
        finally:
            # The builder imported the slave (and its private copy of the
            # library) from the staging folder: forget them, so that the FMU,
            # when loaded in this process, imports its own resources.
            for name in [name for name in sys.modules if name == module or name.startswith(f"_{module}_lib")]:
                del sys.modules[name]
            if str(staging) in sys.path:
                sys.path.remove(str(staging))
        _finish(built, scene, loader)
        # into place in one rename, with the usual mode: a failed build never leaves a half-written FMU behind
        write_atomically(out, Path(built).read_bytes())
    if sidecar is not None:
        write_atomically(sidecar, osp_text.encode("utf-8"))
    return out


def _finish(fmu: Path, scene, loader: str) -> None:
    """Put the patched loader in place of PythonFMU's where there is one (with ``loader="prandtl"``; PythonFMU's
    licence in ``documentation/licenses/``) and add ``documentation/index.html``. (The model description is the
    slave's, ``description.fmi2_root``: named after the scene, with the units, bounds and dependencies.)"""
    from . import loader as native
    from ..documentation import index_html

    with zipfile.ZipFile(fmu) as archive:
        entries = [(info, archive.read(info)) for info in archive.infolist()]
    with zipfile.ZipFile(fmu, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for info, data in entries:
            if info.filename == "modelDescription.xml":
                model_description = data
            if loader == "prandtl":
                data = native.replacement(info.filename) or data
            if not info.is_dir():  # PythonFMU writes some entries 0600: readable by all, as every FMU's
                info.external_attr = (0o100000 | (0o755 if (info.external_attr >> 16) & 0o111 else 0o644)) << 16
            archive.writestr(info, data)
        add_entry(archive, "documentation/licenses/PythonFMU.txt", native.LICENSE.read_bytes())
        add_entry(archive, "documentation/index.html", index_html(model_description, scene))
