"""The native build's object cache (fmu/native/object_cache.py): its key covers every source that decides what is
compiled, what it links is what it kept (a damaged entry is a miss, removed and written again), its entries are
readable by the other users of a shared cache folder, and what a killed build left is removed.

These tests fill a cache folder of their own with stand-in objects (bytes no linker reads): they compile nothing.
The cache as a build uses it (a second build only links, another scene compiles) is tested with the native FMU's
builds in test_against_library.py.
"""
import hashlib
import os
import shutil
import stat
import subprocess
import sys
import time
from collections import namedtuple
from pathlib import Path
from types import SimpleNamespace

import pytest

import prandtl_fmu

PACKAGE = Path(prandtl_fmu.__file__).resolve().parent
TARGET = namedtuple("Target", "triple")("x86_64-unknown-linux-gnu")
NAMES = ("prandtl_step", "prandtl_energy")


SCENE = ("element", b"[mass]\nm = 1\n", "force", "implicit")  # what a build hands digest_of besides the package


def digest_in(copy: Path) -> str:
    """The object cache's key of :data:`SCENE` as the package copied at ``copy`` computes it."""
    probe = f"from prandtl_fmu.fmu.native.object_cache import digest_of; print(digest_of(*{SCENE!r}))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, cwd=copy,
                          env={**os.environ, "PYTHONPATH": str(copy), "PRANDTL_FMU_JIT_CACHE": "0"})
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def test_the_key_covers_every_source_of_the_package(tmp_path):
    """A copy of the package at another place gives this one's key (the entry is found from anywhere); an edit of
    the scene's reader (scene.py, outside fmu/native and the kernels: it decides the structure compiled into the
    objects, such as a count's default) gives another."""
    from prandtl_fmu.fmu.native.object_cache import digest_of

    copies = [tmp_path / "copy", tmp_path / "edited"]
    for copy in copies:
        shutil.copytree(PACKAGE, copy / "prandtl_fmu", ignore=shutil.ignore_patterns("__pycache__"))
    reader = copies[1] / "prandtl_fmu" / "scene.py"
    reader.write_text(reader.read_text() + "\n# a change of the reader\n")
    here = digest_of(*SCENE)
    assert digest_in(copies[0]) == here
    assert digest_in(copies[1]) != here


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A cache folder of the test's own, as ``_jit`` would give it."""
    from prandtl_fmu import _jit

    root = tmp_path / "cache"
    monkeypatch.setattr(_jit, "cache_root", lambda: root)
    monkeypatch.setattr(_jit, "CACHE", True)
    return root / "native-objects"


def stand_in_build(tmp_path, digest: str, contents: dict):
    """A build's ``KernelObjects`` whose compilation hands ``NAMES``' functions and whose objects, once emitted,
    are ``contents`` ({C name: bytes}); returns it and what its build emitted (``keep``'s argument)."""
    from prandtl_fmu.fmu.native.object_cache import KernelObjects

    compiled = [(name, SimpleNamespace(native_name=f"_ZN{name}")) for name in NAMES]
    objects = KernelObjects(digest, lambda: compiled, [TARGET])
    emitted_in = tmp_path / f"emitted-{digest[:8]}-{len(list(tmp_path.iterdir()))}"
    emitted_in.mkdir()
    paths = []
    for name, data in contents.items():
        paths.append(emitted_in / f"{name}.o")
        paths[-1].write_bytes(data)
    objects.compiled()
    return objects, {TARGET: (paths, {"NRT_MemInfo_alloc"})}


def read(tmp_path, digest: str):
    """What a build of the same kernels reads from the cache: its objects ({C name: bytes}), or None (it compiles)."""
    from prandtl_fmu.fmu.native.object_cache import KernelObjects

    objects = KernelObjects(digest, lambda: pytest.fail("compiled although the entry was read"), [TARGET])
    if not objects.cached:
        return None
    where = tmp_path / f"linked-{len(list(tmp_path.iterdir()))}"
    paths, external = objects.objects(where, TARGET)
    assert external == {"NRT_MemInfo_alloc"}
    return {path.stem: path.read_bytes() for path in paths}


@pytest.mark.parametrize("damage", ["a flipped bit", "truncated", "emptied", "missing"])
def test_a_damaged_object_is_a_miss_removed_and_written_again(tmp_path, cache, damage):
    """An entry whose object is not the one it kept is never linked: the build compiles, the damaged entry is
    gone, and the build's own entry, written in its place, is read whole by the next build."""
    digest = hashlib.sha256(damage.encode()).hexdigest()
    contents = {name: os.urandom(4096) for name in NAMES}
    build, emitted = stand_in_build(tmp_path, digest, contents)
    build.keep(emitted)
    assert read(tmp_path, digest) == contents
    damaged = cache / digest / TARGET.triple / f"{NAMES[1]}.o"
    data = damaged.read_bytes()
    if damage == "a flipped bit":
        damaged.write_bytes(data[:1000] + bytes([data[1000] ^ 0x10]) + data[1001:])
    elif damage == "truncated":
        damaged.write_bytes(data[:len(data) // 2])
    elif damage == "emptied":
        damaged.write_bytes(b"")
    else:
        damaged.unlink()
    assert read(tmp_path, digest) is None
    assert not (cache / digest).exists()
    build, emitted = stand_in_build(tmp_path, digest, contents)
    build.keep(emitted)
    assert read(tmp_path, digest) == contents


def test_an_entry_is_readable_by_every_user_the_umask_allows(tmp_path, cache):
    """Under the usual umask 022 an entry's folders are 0755 and its files 0644 (never 0700: the other users of a
    shared cache folder read them); under 077, the user's alone."""
    for umask, folder_mode, file_mode in ((0o022, 0o755, 0o644), (0o077, 0o700, 0o600)):
        digest = hashlib.sha256(str(umask).encode()).hexdigest()
        build, emitted = stand_in_build(tmp_path, digest, {name: b"object" for name in NAMES})
        before = os.umask(umask)
        try:
            build.keep(emitted)
        finally:
            os.umask(before)
        entry = cache / digest
        folders = [entry, *(path for path in entry.rglob("*") if path.is_dir())]
        files = [path for path in entry.rglob("*") if path.is_file()]
        assert len(folders) == 2 and len(files) == 4, (folders, files)
        assert {stat.S_IMODE(path.stat().st_mode) for path in folders} == {folder_mode}, umask
        assert {stat.S_IMODE(path.stat().st_mode) for path in files} == {file_mode}, umask


def test_what_a_killed_build_left_is_removed(tmp_path, cache):
    """A folder a build was writing an entry into when it was killed (named ``.<digest>-<token>``) is removed by a
    later build once it is an hour old; one as young as a build in progress stays."""
    from prandtl_fmu.fmu.native.object_cache import PARTIAL_AFTER

    cache.mkdir(parents=True)
    left, writing = cache / ".0123456789abcdef-left", cache / ".fedcba9876543210-writing"
    for folder in (left, writing):
        (folder / TARGET.triple).mkdir(parents=True)
        (folder / TARGET.triple / "half.o").write_bytes(b"half an object")
    old = time.time() - PARTIAL_AFTER - 60
    os.utime(left, (old, old))
    build, emitted = stand_in_build(tmp_path, "ab" * 32, {name: b"object" for name in NAMES})
    build.keep(emitted)
    assert not left.exists()
    assert writing.exists()
    assert (cache / ("ab" * 32)).is_dir()


def test_an_entry_that_cannot_be_written_is_said_once_and_the_build_goes_on(tmp_path, cache, capsys):
    """A cache folder that cannot take the entry (here a file where the folder of entries should be, as a full or
    read-only disk): ``keep`` raises nothing, writes nothing, and one line on stderr names the folder."""
    from prandtl_fmu import _jit

    cache.parent.mkdir(parents=True)
    cache.write_text("not a folder")
    _jit._SAID.discard(str(cache))
    build, emitted = stand_in_build(tmp_path, "cd" * 32, {name: b"object" for name in NAMES})
    build.keep(emitted)
    build.keep(emitted)
    [line] = capsys.readouterr().err.splitlines()
    assert line.startswith(f"warning: the compiled-code cache {cache} cannot be written ("), line
    assert cache.read_text() == "not a folder"
