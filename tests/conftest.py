"""Shared helpers: write scenes as TOML text from Python dicts."""
import math
import os
import pathlib
import sys

import numpy as np
import pytest

from prandtl_fmu import parse_scene

ROOT = pathlib.Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"


def _value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):  # an inline table
        return "{ " + ", ".join(f"{k} = {_value(v)}" for k, v in value.items()) + " }"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    value = float(value)
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return repr(value)


def scene_text(tables: dict) -> str:
    """TOML text for ``{"name": ..., "mass": {...}, ...}``; a table set to None is left out."""
    lines = []
    for key, value in tables.items():
        if value is not None and not isinstance(value, dict):
            lines.append(f"{key} = {_value(value)}")
    for key, value in tables.items():
        if isinstance(value, dict):
            lines.append(f"\n[{key}]")
            lines += [f"{k} = {_value(v)}" for k, v in value.items()]
    return "\n".join(lines) + "\n"


def base_tables(**changes) -> dict:
    """A small scene with every effect present; ``changes`` replace or drop (None) tables."""
    tables = {
        "name": "test",
        "mass": {"m": 1.0, "x0": 0.0, "v0": 0.0},
        "spring": {"k0": 0.2},
        "cubic": {"k3": 0.05},
        "damper": {"c": 0.01},
        "branches": {"k": [0.5, 0.3, 0.2], "eta": [0.1, 0.3, 0.6], "u0": [0.05, -0.1, 0.0]},
        "load": {"kind": "harmonic", "amplitude": 0.8, "omega": 0.7, "offset": 0.0},
        "solver": {"stepper": "projected", "step": 1e-3, "stop_time": 20.0, "output_interval": 0.1},
    }
    for key, value in changes.items():
        tables[key] = value
    return {k: v for k, v in tables.items() if v is not None}


def make_scene(**changes):
    return parse_scene(scene_text(base_tables(**changes)), "test.toml")


@pytest.fixture
def write_scene(tmp_path):
    def write(tables, name="scene.toml"):
        path = tmp_path / name
        path.write_text(scene_text(tables))
        return path

    return write


# ------------------------------------------------------------------ FMPy's logger proxy (a defect of FMPy 0.3.x)
# FMPy formats an FMU's log messages in a small C proxy (fmpy/logging) that keeps the last logger handed to
# simulate_fmu(logger=...) in one C global. Once that call has returned, its ctypes callback is freed, and any later
# FMU that logs through FMPy's default callbacks (simulate_fmu without a logger, FMU2Slave without callbacks) calls
# freed memory: a segfault. Our FMUs log their warnings with logging off (a fresh FMU that runs its scene's load
# says so at the end of initialization), so the tests met it: a test process died in fmi2ExitInitializationMode and
# pytest-xdist then waited forever. Every simulate_fmu of the tests is followed by pointing that global back at a
# logger that lives as long as the process (tests/test_fmpy_logging.py; docs/masters/fmpy.md says it for users).


def restore_fmpy_logger():
    """Point FMPy's logger proxy at FMPy's own printing logger again (kept alive here)."""
    from ctypes import byref

    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, printLogMessage
    from fmpy.logging import addLoggerProxy

    if "callback" not in _FMPY_LOGGER:
        _FMPY_LOGGER["callback"] = fmi2CallbackLoggerTYPE(printLogMessage)
    functions = fmi2CallbackFunctions()  # a fresh one: the proxy replaces its logger field by itself
    functions.logger = _FMPY_LOGGER["callback"]
    addLoggerProxy(byref(functions))


_FMPY_LOGGER = {}


def _guard_fmpy_simulate_fmu():
    try:
        import fmpy
        import fmpy.simulation
    except ImportError:  # the tests that need FMPy skip saying so
        return
    simulate_fmu = fmpy.simulation.simulate_fmu
    if getattr(simulate_fmu, "restores_fmpy_logger", False):
        return

    def guarded(*args, **kwargs):
        try:
            return simulate_fmu(*args, **kwargs)
        finally:
            restore_fmpy_logger()

    guarded.__wrapped__ = simulate_fmu
    guarded.__doc__ = simulate_fmu.__doc__
    guarded.restores_fmpy_logger = True
    fmpy.simulate_fmu = fmpy.simulation.simulate_fmu = guarded


_guard_fmpy_simulate_fmu()  # before the test modules import simulate_fmu from fmpy


# The session's verdict, for pytest_unconfigure below.
_SESSION = {}


def pytest_sessionfinish(session, exitstatus):
    _SESSION["status"] = int(exitstatus)
    folder = getattr(session.config, "_prandtl_compile_log", None)
    if folder:
        import json

        os.makedirs(folder, exist_ok=True)
        with open(os.path.join(folder, f"compiles-{os.getpid()}.json"), "w") as fh:
            json.dump(_COMPILES, fh)


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    """End a test process that loaded PythonFMU's stock loader with the tests' verdict, without the
    interpreter's teardown, once pytest is done (summary printed).

    The stock loader (built with ``loader="pythonfmu"`` by the tests that compare it with ours) frees its
    interpreter state in a static destructor and writes to it again from its library destructor in exit():
    a use-after-free that corrupts the heap when the block was reused meanwhile (SIGABRT after every result
    is out; prandtl_fmu/fmu/python/loader fixes it in ours). Processes that loaded only our FMUs exit normally.
    PRANDTL_FMU_FULL_EXIT=1 exits normally in any case.
    """
    tools = sys.modules.get("tests.fmu_tools")
    if tools is not None and tools.STOCK_LOADER_LOADED and "status" in _SESSION \
            and not os.environ.get("PRANDTL_FMU_FULL_EXIT"):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_SESSION["status"])


# ------------------------------------------------------------------ where the suite's time goes: compiling
# PRANDTL_FMU_COMPILE_LOG=DIR: every test process writes DIR/compiles-<pid>.json, each kernel numba compiled
# (kernel, signature, inclusive seconds, depth: 0 when not inside another's compilation, the test that compiled
# it); benchmarks/suite_compiles.py sums them (issue 43).
_COMPILES = []
_CURRENT = {"test": "(collection)"}


def pytest_configure(config):
    folder = os.environ.get("PRANDTL_FMU_COMPILE_LOG")
    if not folder:
        return
    import time

    from numba.core import event

    started = []  # the compilations under way, outermost first

    class Compiles(event.Listener):
        def on_start(self, ev):
            started.append(time.perf_counter())

        def on_end(self, ev):
            function = ev.data["dispatcher"].py_func
            seconds = time.perf_counter() - started.pop()
            _COMPILES.append((f"{function.__module__}.{function.__qualname__}", str(ev.data.get("args")),
                              seconds, len(started), _CURRENT["test"]))  # depth 0: not inside another

    event.register("numba:compile", Compiles())
    config._prandtl_compile_log = folder


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    _CURRENT["test"] = item.nodeid
    yield

