"""The native build's objects, kept once built: a second build of the same kernels only links.

A native build compiles its scene's C functions with numba (``kernels.compile_kernels``,
``network_kernels.compile_network``) and emits them as one object file per function for each target
(``platforms.emit_objects``): tens of seconds, even with numba's cache warm, since the C functions are made
for each scene. What they are compiled from is known before compiling: the scene as built (its bytes, the
causality), the steppers, the kind, the sources of the kernels (the package's compiled-code digest names the
folder, ``_jit.cache_root``) and of this folder's Python, numba's and llvmlite's versions, and the target. Their
digest names an entry under ``<cache root>/native-objects``:

    <digest>/symbols.json        {"token": ..., "symbols": {C name: the function's symbol in its object}}
    <digest>/<triple>/*.o        one object per C function
    <digest>/<triple>/external.json  {"token": ..., "external": the symbols its modules declare without
                                 defining (what the stubs provide)}

An entry is written whole into a folder of its own, then renamed into place, and two builds of the same kernels
at once both finish. An entry that lacks a target the build needs is replaced whole (the symbols of a new
compilation need not be those of the old one): removed, then the new one renamed into place. A reader that
raced such a replacement could read the old symbols and the new objects; each entry carries a random token in
its symbols and in each target's externals, read after that target's objects, and a reader that finds them
differ compiles (an entry that vanished under it too). At most :data:`KEEP` entries are kept, the least
recently used removed first. With no usable cache folder (``_jit.CACHE`` false), every build compiles.
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
import uuid
from pathlib import Path

HERE = Path(__file__).resolve().parent
KEEP = 64  # entries: a few MB each


def digest_of(*parts) -> str:
    """The entry's name: a digest of ``parts`` (bytes or text) with this folder's Python, numba's and
    llvmlite's versions."""
    import llvmlite
    import numba

    digest = hashlib.sha256()
    for part in (numba.__version__, llvmlite.__version__, *parts):
        digest.update(part if isinstance(part, bytes) else str(part).encode())
        digest.update(b"\0")
    for path in sorted(HERE.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def _root():
    from ... import _jit

    return _jit.cache_root() / "native-objects" if _jit.CACHE else None


class KernelObjects:
    """A build's kernels as objects per target: read whole from the cache when it holds every target, else
    compiled (``compile()`` returns ``[(C name, cfunc), ...]``) and emitted, then kept (:meth:`keep`)."""

    def __init__(self, digest: str, compile, targets):
        self.digest, self._compile = digest, compile
        self._compiled = None
        self._read = self._read_entry(list(targets))  # {"symbols": ..., triple: ({name: bytes}, external)}
        self.cached = self._read is not None

    def _read_entry(self, targets):
        root = _root()
        entry = root / self.digest if root is not None else None
        if entry is None or not entry.is_dir():
            return None
        try:
            symbols = json.loads((entry / "symbols.json").read_text())
            read = {"symbols": symbols["symbols"]}
            for target in targets:
                where = entry / target.triple
                objects = {name: (where / f"{name}.o").read_bytes() for name in read["symbols"]}
                external = json.loads((where / "external.json").read_text())  # after the objects: the token
                if external["token"] != symbols["token"]:  # says they are of the symbols' entry
                    return None  # replaced while this build read it: compile
                read[target.triple] = (objects, set(external["external"]))
            os.utime(entry)  # recently used
        except (OSError, ValueError, KeyError, TypeError):  # a target missing, removed meanwhile, or damaged
            return None
        return read

    def compiled(self) -> list:
        if self._compiled is None:
            from ...compiling import stage

            stage("native build: compiling the kernels")
            self._compiled = self._compile()
        return self._compiled

    def symbols(self) -> dict:
        """``{C name: symbol}`` for scene.h."""
        if self._read is not None:
            return dict(self._read["symbols"])
        return {name: function.native_name for name, function in self.compiled()}

    def objects(self, folder, target) -> tuple:
        """The object files of ``target`` written into ``folder``, and the symbols they need from outside."""
        from .platforms import emit_objects

        if self._read is None:
            return emit_objects(self.compiled(), folder, target)
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        objects, external = self._read[target.triple]
        paths = []
        for name, data in objects.items():
            path = folder / f"{name}.o"
            path.write_bytes(data)
            paths.append(path)
        return paths, set(external)

    def keep(self, emitted: dict) -> None:
        """Keep what this build compiled and emitted (``{target: (paths, external)}``); a failure to write is no
        failure of the build."""
        root = _root()
        if root is None or self._compiled is None:
            return
        try:
            root.mkdir(parents=True, exist_ok=True)
            partial = Path(tempfile.mkdtemp(prefix=f".{self.digest[:16]}-", dir=root))
            token = uuid.uuid4().hex
            try:
                for target, (paths, external) in emitted.items():
                    where = partial / target.triple
                    where.mkdir()
                    for path in paths:
                        shutil.copyfile(path, where / path.name)
                    (where / "external.json").write_text(json.dumps({"token": token, "external": sorted(external)}))
                (partial / "symbols.json").write_text(json.dumps({"token": token, "symbols": self.symbols()}))
                entry = root / self.digest
                if entry.exists():
                    shutil.rmtree(entry, ignore_errors=True)  # it lacked a target: replaced whole
                os.rename(partial, entry)  # (another build's entry there first: this one is dropped)
            finally:
                shutil.rmtree(partial, ignore_errors=True)
            _prune(root)
        except OSError:
            pass


def _prune(root: Path) -> None:
    entries = sorted((path for path in root.iterdir() if path.is_dir() and not path.name.startswith(".")),
                     key=lambda path: path.stat().st_mtime, reverse=True)
    for stale in entries[KEEP:]:
        shutil.rmtree(stale, ignore_errors=True)
