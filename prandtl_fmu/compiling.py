"""Saying so while the kernels compile: the first run on a machine compiles them (tens of seconds), every later
one loads them from the cache (``_jit.py``). On a terminal, a command that compiles shows one status line on
stderr while it does: what it compiles, for how long so far, and that this happens once per machine, with
where the cache lives; then one line saying what was compiled. Nothing goes to stdout, to a file or to a pipe:
with stderr not a terminal (CI logs, a script capturing it) it says nothing at all.

    with compiling_status():
        ...  # whatever may compile

It listens to numba's own compile events (``numba:compile``), fired only when a kernel is really compiled, never
when it is loaded from the cache. A long command says its stages on the same line with :func:`stage` (a native
build: its kernels, the objects of each platform, the link, the archive), each with its seconds so far; off a
terminal, ``stage`` does nothing.
"""
from __future__ import annotations

import contextlib
import sys
import threading
import time

REFRESH = 0.25  # s between two updates of the status line


class _Status:
    """The status line: a thread redraws it while a compilation is under way."""

    def __init__(self, stream, where: str):
        self.stream, self.where = stream, where
        self.depth, self.count, self.current = 0, 0, ""
        self.compiling_since, self.total = None, 0.0
        self.stage, self.stage_since = "", None
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.thread = None
        self.width = 0

    def started(self, name: str) -> None:
        with self.lock:
            self.count += 1
            self.depth += 1
            if self.depth == 1:
                self.current = name
                self.compiling_since = time.perf_counter()
                self._start_drawing()

    def staged(self, text: str) -> None:
        with self.lock:
            self.stage, self.stage_since = text, time.perf_counter()
            self._start_drawing()

    def _start_drawing(self) -> None:  # (under the lock)
        if self.thread is None:
            self.thread = threading.Thread(target=self._draw, name="compiling-status", daemon=True)
            self.thread.start()

    def ended(self) -> None:
        with self.lock:
            self.depth -= 1
            if self.depth == 0 and self.compiling_since is not None:
                self.total += time.perf_counter() - self.compiling_since
                self.compiling_since = None

    def _line(self) -> str:
        with self.lock:
            now = time.perf_counter()
            elapsed = self.total + (now - self.compiling_since if self.compiling_since else 0.0)
            current, busy = self.current, self.compiling_since is not None
            stage = f"{self.stage}: {now - self.stage_since:.0f} s" if self.stage else ""
        compiling = f"compiling for this machine, once ({current}): {elapsed:.0f} s" if busy else ""
        return "; ".join(part for part in (stage, compiling) if part)

    def _write(self, text: str) -> None:
        import shutil

        text = text[:max(20, shutil.get_terminal_size((100, 24)).columns - 1)]  # a line that wraps never returns
        pad = max(0, self.width - len(text))
        try:
            self.stream.write("\r" + text + " " * pad)
            self.stream.flush()
        except (OSError, ValueError):
            pass
        self.width = len(text)

    def _draw(self) -> None:
        while not self.stop.wait(REFRESH):
            with self.lock:
                busy = self.compiling_since is not None or bool(self.stage)
            if busy:
                self._write(self._line())

    def finish(self) -> None:
        self.stop.set()
        if self.thread is not None:
            self.thread.join()
            self._write("")
            try:  # the last line whole, wrapped as it may: it is not redrawn
                self.stream.write("\r")
                if not self.count:  # only stages were said: the line is left empty
                    self.stream.flush()
                    return
                self.stream.write(f"\rcompiled {self.count} kernels in {self.total:.0f} s, once for this machine: "
                                  f"later runs load them from {self.where}\n")
                self.stream.flush()
            except (OSError, ValueError):
                pass


def _short(dispatcher) -> str:
    function = getattr(dispatcher, "py_func", None)
    if function is None:
        return "a kernel"
    module = function.__module__.split(".", 1)[-1]
    return f"{module}.{function.__qualname__.split('.<locals>')[0]}"


_ACTIVE = []  # the status line of the command under way (on a terminal only)


def stage(text: str) -> None:
    """Say on the status line what a long command does now (e.g. "native build: linking x86_64-linux"); nothing
    off a terminal or outside :func:`compiling_status`."""
    if _ACTIVE:
        _ACTIVE[-1].staged(text)


@contextlib.contextmanager
def compiling_status(stream=None):
    """Show the status line while the body compiles kernels, on a terminal only (see the module docstring)."""
    stream = sys.stderr if stream is None else stream
    try:
        terminal = stream.isatty()
    except (AttributeError, ValueError):
        terminal = False
    if not terminal:
        yield
        return
    from numba.core import event

    from ._jit import CACHE, cache_root

    status = _Status(stream, str(cache_root()) if CACHE else "memory only (no usable cache folder)")

    class Listener(event.Listener):
        def on_start(self, ev):
            status.started(_short(ev.data.get("dispatcher")) if isinstance(ev.data, dict) else "a kernel")

        def on_end(self, ev):
            status.ended()

    listener = Listener()
    event.register("numba:compile", listener)
    _ACTIVE.append(status)
    try:
        yield
    finally:
        _ACTIVE.remove(status)
        event.unregister("numba:compile", listener)
        status.finish()
