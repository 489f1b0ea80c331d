"""The native build's objects, kept once built: a second build of the same kernels only links.

A native build compiles its scene's C functions with numba (``kernels.compile_kernels``,
``network_kernels.compile_network``) and emits them as one object file per function for each target
(``platforms.emit_objects``): tens of seconds, even with numba's cache warm, since the C functions are made
for each scene. What they are compiled from is known before compiling: the scene as built (its bytes, the
causality), the steppers, the kind, and the code that reads the scene and compiles it. That code is spread over the
package (the scene's reader and schema, the Masing and effect tables, the compiled model, the networks' model, the
kernels, this folder), so the key takes all of it: a digest of every Python source of the installed package
(:func:`package_digest`, once per process), with Python's, numba's and llvmlite's versions; the target is the
entry's subfolder. Their digest names an entry under ``<cache root>/native-objects``:

    <digest>/symbols.json        {"token": ..., "symbols": {C name: the function's symbol in its object}}
    <digest>/<triple>/*.o        one object per C function
    <digest>/<triple>/external.json  {"token": ..., "external": the symbols its modules declare without
                                 defining (what the stubs provide), "sha256": {C name: its object's digest}}

What is linked is checked: an object whose SHA-256 is not the one its entry recorded (a flipped bit, a truncated
file, a file missing), or an entry that cannot be read, is a miss: the entry is removed, the build compiles and
writes a new one.

An entry is written whole into a folder of its own (``.<digest>-<random>``), then renamed into place, and two
builds of the same kernels at once both finish; a folder of a build killed while writing is removed once it is
:data:`PARTIAL_AFTER` old. An entry that lacks a target the build needs is replaced whole (the symbols of a new
compilation need not be those of the old one): removed, then the new one renamed into place. A reader that
raced such a replacement could read the old symbols and the new objects; each entry carries a random token in
its symbols and in each target's externals, read after that target's objects, and a reader that finds them
differ compiles (an entry that vanished under it too). Entries are made with every user's read rights that the
umask allows (folders 0755, files 0644 under the usual 022), so that users sharing a cache folder reuse them.
At most :data:`KEEP` entries are kept, the least recently used removed first. With no usable cache folder
(``_jit.CACHE`` false), every build compiles.
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
import sys
import time
import uuid
from pathlib import Path

HERE = Path(__file__).resolve().parent
PACKAGE = HERE.parents[1]  # prandtl_fmu (or an FMU's bundled copy of it)
KEEP = 64  # entries: a few MB each
PARTIAL_AFTER = 3600.0  # seconds: a folder being written that is this old was left by a build that was killed


@functools.lru_cache(maxsize=None)
def package_digest() -> str:
    """A digest of every Python source of the package (names relative to it and contents), with Python's, numba's
    and llvmlite's versions: whatever decides what a native build compiles. Computed once per process."""
    import llvmlite
    import numba

    digest = hashlib.sha256()
    for version in (sys.version, numba.__version__, llvmlite.__version__):
        digest.update(version.encode() + b"\0")
    for path in sorted(PACKAGE.rglob("*.py")):
        if "__pycache__" not in path.parts:
            digest.update(path.relative_to(PACKAGE).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def digest_of(*parts) -> str:
    """The entry's name: a digest of ``parts`` (bytes or text) and of the package (:func:`package_digest`)."""
    digest = hashlib.sha256(package_digest().encode())
    for part in parts:
        digest.update(b"\0" + (part if isinstance(part, bytes) else str(part).encode()))
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
                if not where.is_dir():
                    return None  # a target it lacks: compiled, and the entry replaced whole (keep)
                objects = {name: (where / f"{name}.o").read_bytes() for name in read["symbols"]}
                external = json.loads((where / "external.json").read_text())  # after the objects: the token
                if external["token"] != symbols["token"]:  # says they are of the symbols' entry
                    return None  # replaced while this build read it: compile
                if any(hashlib.sha256(data).hexdigest() != external["sha256"][name]
                       for name, data in objects.items()):
                    raise ValueError("an object is not the one its entry recorded")
                read[target.triple] = (objects, set(external["external"]))
            os.utime(entry)  # recently used
        except (OSError, ValueError, KeyError, TypeError, AttributeError):  # damaged, or removed meanwhile
            _remove(entry)  # never linked: the build compiles and writes it again
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
        failure of the build (said once on stderr, naming the folder)."""
        root = _root()
        if root is None or self._compiled is None:
            return
        try:
            root.mkdir(parents=True, exist_ok=True)
            token = uuid.uuid4().hex
            partial = root / f".{self.digest[:16]}-{token}"
            partial.mkdir()  # every user's rights less the umask (a temporary folder would be 0700: never shared)
            try:
                for target, (paths, external) in emitted.items():
                    where = partial / target.triple
                    where.mkdir()
                    digests = {}
                    for path in paths:
                        data = Path(path).read_bytes()
                        (where / path.name).write_bytes(data)
                        digests[Path(path).stem] = hashlib.sha256(data).hexdigest()
                    (where / "external.json").write_text(json.dumps({"token": token, "external": sorted(external),
                                                                     "sha256": digests}))
                (partial / "symbols.json").write_text(json.dumps({"token": token, "symbols": self.symbols()}))
                entry = root / self.digest
                if entry.exists():
                    shutil.rmtree(entry, ignore_errors=True)  # it lacked a target: replaced whole
                os.rename(partial, entry)  # (another build's entry there first: this one is dropped)
            finally:
                shutil.rmtree(partial, ignore_errors=True)
            _prune(root)
        except OSError as error:
            from ... import _jit

            _jit._say(root, error, "this build's objects are not kept: the next build of these kernels compiles")


def _remove(entry: Path) -> None:
    """Remove the entry ``entry``: renamed away first (no reader sees half of it), then deleted; never raises."""
    doomed = entry.parent / f".{entry.name[:16]}-removing-{uuid.uuid4().hex}"
    try:
        os.rename(entry, doomed)
    except OSError:
        return  # gone already, or not ours to remove
    shutil.rmtree(doomed, ignore_errors=True)


def _prune(root: Path, now=None) -> None:
    """Keep the :data:`KEEP` entries last used; remove the folders of builds killed while writing (or removing)
    one, once they are :data:`PARTIAL_AFTER` old."""
    now = time.time() if now is None else now
    entries = []
    for path in root.iterdir():
        try:
            if not path.is_dir():
                continue
            if not path.name.startswith("."):
                entries.append((path.stat().st_mtime, path))
            elif now - path.stat().st_mtime > PARTIAL_AFTER:
                shutil.rmtree(path, ignore_errors=True)
        except OSError:
            continue  # removed meanwhile
    for _, stale in sorted(entries, reverse=True)[KEEP:]:
        shutil.rmtree(stale, ignore_errors=True)
