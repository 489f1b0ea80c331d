"""The scenes shipped in the package, by name, and the error every scene reader raises.

Light on purpose (the standard library only): the command line's ``scenes``, ``--help`` and ``--version``, and a
misspelt scene name, are answered from here without loading numpy or numba.
"""
from __future__ import annotations

import difflib
import os
from typing import Union

SCENES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scenes")


class SceneError(ValueError):
    """A scene (or an override of it) breaks a rule; the message is one line."""


def packaged_scenes() -> list:
    """The names of the scenes shipped in the package ("paper-section-8", "hard/step-load", ...)."""
    names = []
    for folder, _, files in os.walk(SCENES):
        relative = os.path.relpath(folder, SCENES)
        for file in files:
            if file.endswith(".toml"):
                name = file[:-5] if relative == "." else f"{relative}/{file[:-5]}".replace(os.sep, "/")
                names.append(name)
    return sorted(names)


def scene_path(name_or_path: Union[str, os.PathLike]) -> str:
    """A scene file's path: ``name_or_path`` itself when it is an existing file, else the packaged scene of that
    name (``paper-section-8``, ``hard/step-load``, with or without ``.toml``), else ``name_or_path`` (whose
    reading then fails with :func:`unknown_scene`'s message)."""
    path = os.fspath(name_or_path)
    if os.path.exists(path):
        return path
    name = path[:-5] if path.endswith(".toml") else path
    packaged = os.path.join(SCENES, *name.split("/")) + ".toml"
    return packaged if name in packaged_scenes() else path


def closest_scenes(name: str) -> list:
    """The packaged scenes whose names are close to ``name`` (at most three, closest first); a name given
    without its folder ("step-load" for "hard/step-load") is matched on the last part."""
    given = name[:-5] if name.endswith(".toml") else name
    names = packaged_scenes()
    close = difflib.get_close_matches(given, names, n=3, cutoff=0.6)
    if not close:
        by_leaf = {n.rpartition("/")[2]: n for n in names}
        close = [by_leaf[leaf] for leaf in difflib.get_close_matches(given, list(by_leaf), n=3, cutoff=0.6)]
    return close


def unknown_scene(name: str) -> SceneError:
    """The one line for a scene that is neither a file nor a packaged scene: the closest packaged names, if any
    is close, and where the list is."""
    close = closest_scenes(name)
    hint = f"did you mean {' or '.join(close)}? " if close else ""
    return SceneError(f"{name}: no such scene file, and no packaged scene of that name ({hint}"
                      "prandtl-fmu scenes lists them)")
