"""Files the tools write (CSV, scene, PNG, FMU, OSP sidecar): whole or not at all, with the usual mode.

A file is written under a hidden temporary name in its target's folder (``.prandtl-*.part``) and renamed over
the target once complete, so a failed, interrupted or killed run leaves the target as it was. Two details any
tool gets right and ``tempfile.mkstemp`` alone does not:

* the mode: mkstemp creates 0600; the file renamed into place gets 0666 less the process's umask (0644
  usually), or the mode of the file it replaces, as ``open(path, "w")`` would give;
* the leftovers: every temporary still open is listed here, and :func:`remove_partial_files` (called by the
  command line's SIGINT, SIGTERM and SIGHUP handling) deletes them.
"""
from __future__ import annotations

import os
import stat
import tempfile

# temporaries created and not yet renamed or deleted (paths)
_PARTIAL: set = set()


def umask() -> int:
    """The process's umask (read from /proc on Linux: setting it to read it is not thread-safe)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def final_mode(path: str) -> int:
    """The mode the written file gets: the replaced file's, or 0666 less the umask."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        return 0o666 & ~umask()


class AtomicFile:
    """A file written under a temporary name in its folder and renamed into place by :meth:`commit`
    (``binary``: bytes, else text with newline="")."""

    def __init__(self, path, binary: bool = False):
        self.path = os.fspath(path)
        folder = os.path.dirname(os.path.abspath(self.path))
        handle, self.temporary = tempfile.mkstemp(prefix=".prandtl-", suffix=".part", dir=folder)
        _PARTIAL.add(self.temporary)
        self.file = os.fdopen(handle, "wb") if binary else os.fdopen(handle, "w", newline="")

    def write(self, data) -> None:
        self.file.write(data)

    def commit(self) -> None:
        self.file.flush()
        os.fchmod(self.file.fileno(), final_mode(self.path))
        self.file.close()
        os.replace(self.temporary, self.path)
        _PARTIAL.discard(self.temporary)

    def discard(self) -> None:
        try:
            self.file.close()
        except OSError:
            pass
        try:
            os.unlink(self.temporary)
        except OSError:
            pass
        _PARTIAL.discard(self.temporary)


def write_atomically(path, data) -> None:
    """Write ``data`` (bytes or str) to ``path`` whole, or leave ``path`` as it was."""
    sink = AtomicFile(path, binary=isinstance(data, bytes))
    try:
        sink.write(data)
        sink.commit()
    except BaseException:
        sink.discard()
        raise


def write_output(path, data: bytes) -> None:
    """Write ``data`` to ``path``: atomically for a regular file (or a new one), directly for a device or a
    pipe (``/dev/stdout``, ``/dev/full``: a write error is raised, never lost in a buffer)."""
    if not os.path.exists(path) or os.path.isfile(path):
        write_atomically(path, data)
        return
    with open(path, "wb") as fh:
        fh.write(data)
        fh.flush()


def clash(outputs, inputs=()) -> str:
    """The first clash among the files a command writes (``outputs``: (option, path), path None or empty where
    not asked for) and those it reads (``inputs``: (what, path)), as one line; "" where there is none. Two
    outputs that are one file would leave only the last (a CSV lost under its plot), and an output that is an
    input would be written over what it was read from (a scene lost under its CSV)."""
    def same(a, b) -> bool:
        try:
            if os.path.exists(a) and os.path.exists(b):
                return os.path.samefile(a, b)
        except OSError:
            pass
        return os.path.realpath(a) == os.path.realpath(b)

    outputs = [(option, path) for option, path in outputs if path]
    for index, (option, path) in enumerate(outputs):
        for other, earlier in outputs[:index]:
            if same(path, earlier):
                return f"{option} {path}: the same file as {other}: give each its own"
        for what, source in inputs:
            if source and os.path.exists(source) and same(path, source):
                return f"{option} {path}: the {what} it reads: it would be written over"
    return ""


def remove_partial_files() -> int:
    """Delete every temporary not yet renamed into place (a run being stopped by a signal); returns how many
    there were."""
    count = len(_PARTIAL)
    for temporary in list(_PARTIAL):
        try:
            os.unlink(temporary)
        except OSError:
            pass
        _PARTIAL.discard(temporary)
    return count
