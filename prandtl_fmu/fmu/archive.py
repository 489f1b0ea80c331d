"""What the builds of both runtimes share: the scene an FMU is built from and the FMU's files.

:func:`built_scene` reads and checks the scene (its stepper unless the FMU is a connector, the noise's seed an FMU
can take), applies the causality a build asks for and returns the text the FMU keeps as ``resources/scene.toml``;
:func:`file_stem` makes a scene's name a file name (:func:`check_osp_name`: or refuses it); :func:`add_entry`
writes a file into the FMU's zip archive as every FMU's file is written.
"""
from __future__ import annotations

import re
import zipfile
from pathlib import Path

from ..scene import CAUSALITIES, SceneError, load_scene, parse_scene, scene_path as resolve_scene
from .description import NOISE_SEED_LIMIT


def built_scene(scene_path, causality=None) -> tuple:
    """(scene, text): the scene at ``scene_path`` (a file or a packaged scene's name), checked as an FMU needs it
    (SceneError on a broken rule), with ``[fmu] causality`` set to ``causality`` when given (:func:`with_causality`),
    and its text (with that table) for ``resources/scene.toml``."""
    scene = load_scene(scene_path, check_stepper=causality != "displacement")
    check_noise_seed(scene)
    scene_bytes = Path(resolve_scene(scene_path)).read_bytes()
    if causality is not None:
        scene, scene_bytes = with_causality(scene, scene_bytes, causality)
    return scene, scene_bytes


def check_noise_seed(scene) -> None:
    """An FMU's noise_seed is an FMI Integer (32 bits): a scene's seed beyond it is refused here, naming the
    user's scene (the PythonFMU slave checks it again where PythonFMU copies the scene)."""
    noise = getattr(scene.load, "noise", None)
    if noise is not None and noise.seed >= NOISE_SEED_LIMIT:
        raise SceneError(f"{scene.source}: [load] the noise's seed {noise.seed}: an FMU's noise_seed is an FMI "
                         "Integer (32 bits): it must be < 2^31")


def with_causality(scene, scene_bytes: bytes, causality: str):
    """The scene (and its text) with ``[fmu] causality`` set; SceneError if its own table says otherwise."""
    if causality not in CAUSALITIES:
        raise SceneError(f"--causality: must be one of {', '.join(CAUSALITIES)}, got {causality!r}")
    if b"[fmu]" in scene_bytes or scene.causality != "force":
        if scene.causality != causality:
            raise SceneError(f"{scene.source}: [fmu] causality = {scene.causality!r} contradicts --causality "
                             f"{causality}: change one of them")
        return scene, scene_bytes
    text = scene_bytes.rstrip(b"\n") + f'\n\n[fmu]\ncausality = "{causality}"\n'.encode()
    return parse_scene(text, scene.source), text


def file_stem(name: str) -> str:
    """A scene name as a file name: data, never a path. Letters, digits, '-', '_' and '.' are kept, anything
    else becomes '_'; no leading dot; an empty result is 'prandtl_element'."""
    stem = re.sub(r"[^A-Za-z0-9_.-]", "_", name).lstrip(".")[:100]
    return stem or "prandtl_element"


def check_osp_name(name: str) -> None:
    """An OSP interface description is written beside the FMU under the scene's name: a name that is not a plain
    file name is refused (ValueError)."""
    if file_stem(name) != name:
        raise ValueError(f"--osp: the scene name {name!r} is not a plain file name, and libcosim looks for "
                         "<modelName>_OspModelDescription.xml beside the FMU: name the scene with letters, digits, "
                         "'-', '_' and '.'")


def add_entry(archive: zipfile.ZipFile, name: str, data, mode: int = 0o644) -> None:
    """Write ``data`` (bytes or text) as the regular file ``name`` of ``archive``, deflated, with ``mode`` (0644:
    what every FMU has; ZipFile.writestr with a bare name writes 0600, which a master running as another user
    cannot read once unpacked)."""
    info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = (0o100000 | mode) << 16
    archive.writestr(info, data)
