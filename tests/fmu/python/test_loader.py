"""The FMU's native loader (``prandtl_fmu/fmu/python/loader``: PythonFMU 0.7.0's, patched) against the stock one.

Each test runs the same scene's FMU under both loaders where the stock loader behaves differently, so that
the test shows the defect it guards against (and would fail if the patched library were not in the FMU).
The refusal statuses themselves are tested in test_hostile_host.py for both loaders.
"""
import ctypes
import gc
import os
import shutil
import subprocess
import sys
import tracemalloc
import zipfile
from pathlib import Path

import pytest

from prandtl_fmu.fmu.python import loader
from tests.paths import ROOT

pytest.importorskip("fmpy")

SCENE = """\
name = "loader"
[mass]
m = 1.0
[spring]
k0 = 1.0
[branches]
k = [0.5, 2.0]
eta = [0.1, 0.3]
[solver]
stepper = "projected"
step = 0.01
stop_time = 1.0
output_interval = 0.1
"""


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    from prandtl_fmu.fmu.build import build_fmu

    from tests.fmu_tools import stock_loader_loaded

    folder = tmp_path_factory.mktemp("loader")
    scene = folder / "loader.toml"
    scene.write_text(SCENE)
    stock_loader_loaded()
    return {name: build_fmu(scene, folder / f"{name}.fmu", loader=name) for name in loader.LOADERS}


def _slave(fmu):
    from tests.fmu_tools import Slave

    return Slave(fmu)


def test_the_prebuilt_library_is_built_from_the_sources_in_the_repository():
    assert loader.stale() is None
    assert loader.STAMP.read_text().strip() == loader.source_digest()


@pytest.mark.skipif(shutil.which("g++") is None, reason="no g++ on this machine: the prebuilt library is used as is")
@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_the_sources_compile_without_a_warning(tmp_path):
    """What ``python -m prandtl_fmu.fmu.python.loader`` does, into a scratch file: -Wall is silent."""
    import sysconfig

    if not (Path(sysconfig.get_paths()["include"]) / "Python.h").is_file():
        pytest.skip("no Python headers on this machine")
    out = tmp_path / "loader.so"
    warnings = loader.compile_loader(out)  # -Wall
    assert warnings == "", warnings
    exported = subprocess.run(["nm", "-D", "--defined-only", str(out)], capture_output=True, text=True).stdout
    for function in ("fmi2Instantiate", "fmi2DoStep", "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeInstance"):
        assert f" T {function}\n" in exported


def test_the_fmu_carries_the_patched_library_on_linux_and_pythonfmus_elsewhere(fmus):
    import pythonfmu

    stock = Path(pythonfmu.__file__).parent / "resources" / "binaries"
    with zipfile.ZipFile(fmus["prandtl"]) as archive:
        assert archive.read("binaries/linux64/PrandtlElement.so") == loader.LINUX64.read_bytes()
        assert archive.read("binaries/win64/PrandtlElement.dll") == (stock / "win64" / "pythonfmu-export.dll").read_bytes()
        assert b"MIT License" in archive.read("documentation/licenses/PythonFMU.txt")
    with zipfile.ZipFile(fmus["pythonfmu"]) as archive:
        assert archive.read("binaries/linux64/PrandtlElement.so") == \
            (stock / "linux64" / "libpythonfmu-export.so").read_bytes()


def test_an_unknown_loader_is_refused(tmp_path):
    from prandtl_fmu.fmu.build import build_fmu

    scene = tmp_path / "s.toml"
    scene.write_text(SCENE)
    with pytest.raises(ValueError, match="--loader: must be one of prandtl, pythonfmu"):
        build_fmu(scene, tmp_path / "s.fmu", loader="stock")
    assert not (tmp_path / "s.fmu").exists()


def _state_memory_growth(slave, calls):
    """Python memory kept after ``calls`` fmi2GetFMUstate calls into one state pointer (FMI 2.0: a state
    returned earlier, to be overwritten), then fmi2FreeFMUstate; and the pointer after the free."""
    from fmpy.fmi2 import fmi2FMUstate

    state = fmi2FMUstate()
    slave.fmu.fmi2GetFMUstate(slave.fmu.component, ctypes.byref(state))
    gc.collect()
    tracemalloc.start()
    try:
        before, _ = tracemalloc.get_traced_memory()
        for _ in range(calls):
            slave.fmu.fmi2GetFMUstate(slave.fmu.component, ctypes.byref(state))
        gc.collect()
        after, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    slave.fmu.fmi2FreeFMUstate(slave.fmu.component, ctypes.byref(state))
    return after - before, state.value


def test_getting_a_state_into_an_earlier_one_does_not_leak(fmus):
    """The stock loader overwrote the pointer and leaked the state it held (a state per call, what a master
    that saves into the same slot, e.g. an iterative one, pays at every step); fmi2FreeFMUstate left the
    pointer set."""
    calls = 300
    growth = {}
    for name, fmu in fmus.items():
        slave = _slave(fmu)
        try:
            slave.step(0.1, 0.4)
            growth[name], pointer = _state_memory_growth(slave, calls)
            if name == "prandtl":
                assert pointer is None  # set to NULL by fmi2FreeFMUstate
                # three times the calls: a leak would keep 600 more states; ours keeps what it kept (the last
                # state, allocator slack and tracemalloc's own noise, ~20 kB here whatever the count)
                growth["prandtl x3"], _ = _state_memory_growth(slave, 3 * calls)
        finally:
            slave.close()
    per_state = growth["pythonfmu"] / calls
    assert per_state > 1000  # the defect is real (and this test can tell): one state kept per call
    assert growth["prandtl"] < 30 * per_state, growth  # a few states, not 300
    assert growth["prandtl x3"] - growth["prandtl"] < 60 * per_state, growth  # not one more per call


def test_terminated_reports_the_last_step(fmus):
    """After a Discard (a non-finite force) and a good step, fmi2Terminated is false: the stock loader kept it
    true for ever after the first Discard."""
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import fmi2Terminated

    terminated = {}
    for name, fmu in fmus.items():
        slave = _slave(fmu)
        try:
            slave.step(0.1, 0.4)
            assert slave.fmu.getBooleanStatus(fmi2Terminated) is False
            with pytest.raises(FMICallException) as discarded:
                slave.step(0.1, float("nan"))
            assert discarded.value.status == 2
            slave.time -= 0.1  # refused: the master steps again from the same time
            assert slave.fmu.getBooleanStatus(fmi2Terminated) is True
            slave.step(0.1, 0.4)
            terminated[name] = slave.fmu.getBooleanStatus(fmi2Terminated)
        finally:
            slave.close()
    assert terminated == {"prandtl": False, "pythonfmu": True}


def test_a_refused_call_logs_the_reason_and_the_exception(fmus):
    """The loader passes on what the slave logged before failing, then its own line naming the call and the
    exception (the stock loader: 'Fatal py exception encountered' and a repr)."""
    from fmpy.fmi1 import FMICallException

    slave = _slave(fmus["prandtl"])
    try:
        with pytest.raises(FMICallException) as refused:
            slave.set("x0", 0.25)
        assert refused.value.status == 3
        texts = [message for _, message in slave.messages]
        reason = next(i for i, text in enumerate(texts) if "x0 = 0.25 refused" in text)
        exception = next(i for i, text in enumerate(texts) if text.startswith("Python exception in [setReal]"))
        assert reason < exception and "Refused: " in texts[exception]
        assert slave.messages[reason][0] == slave.messages[exception][0] == 3  # both logged as fmi2Error
    finally:
        slave.close()


@pytest.mark.parametrize("name", loader.LOADERS)
def test_many_refusals_leave_the_instance_and_the_host_intact(fmus, name):
    """200 refused calls of each kind, then normal stepping, in a fresh process that exits normally: the
    stock loader's double release (compensated by the slave) and ours (nothing to compensate) both hold."""
    script = f"""
import sys
sys.path.insert(0, {str(ROOT)!r})
from fmpy.fmi1 import FMICallException
from tests.fmu_tools import Slave
slave = Slave({str(fmus[name])!r})
slave.step(0.1, 0.4)
x = slave.get("x")
for _ in range(200):
    for refuse in (lambda: slave.set("x0", 0.3),
                   lambda: slave.fmu.setFMUstate(slave.fmu.deSerializeFMUstate(b"garbage"))):
        try:
            refuse()
        except FMICallException:
            pass
        else:
            raise SystemExit("not refused")
assert slave.get("x") == x
for _ in range(10):
    slave.step(0.1, 0.4)
slave.close()
print("ok", flush=True)
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert done.stdout.strip() == "ok", done.stderr[-2000:]  # the instance survived and stepped on
    if done.returncode != 0 and name == "pythonfmu":
        # Once in CI (~30 runs; never in 200 runs here) the stock loader's process died at exit, after every
        # check above had passed, with glibc's "corrupted double-linked list". That loader runs the host's
        # logger while a Python exception is pending and frees the slave's objects on its exception path;
        # ours does neither (loader/__init__.py). Not ours to fix: recorded, not hidden.
        pytest.xfail(f"PythonFMU's stock loader crashed at exit ({done.returncode}): {done.stderr[-300:]!r}")
    assert done.returncode == 0, done.stderr[-2000:]


MIXED = """
import gc, sys
sys.path.insert(0, {root!r})
from tests.fmu_tools import Slave
first = Slave({patched!r})  # our loader executes the script first (and marks its globals)
first.step(0.1, 0.4)
module = next(m for name, m in sys.modules.items() if name.startswith("prandtl_slave_"))
before = sys.getrefcount(module.__dict__)
for _ in range(60):  # then PythonFMU's stock loader, which releases a reference to them each time
    slave = Slave({stock!r})
    slave.step(0.1, 0.4)
    slave.close()
gc.collect()
print(before, sys.getrefcount(module.__dict__), first.get("x"), flush=True)
first.close()
"""


def test_both_loaders_on_one_script_module_keep_its_dict_alive(fmus, tmp_path):
    """One script module run by both loaders in one process (the same FMU with its binary swapped): the
    stock loader's releases stay compensated after our loader has run the script. A mark left over from our
    loader made the script skip the compensation, and the module's dict was freed while in use (a worker
    of the test suite crashed in numba's compiler)."""
    import pythonfmu

    stock_binary = (Path(pythonfmu.__file__).parent / "resources" / "binaries" / "linux64" /
                    "libpythonfmu-export.so").read_bytes()
    swapped = tmp_path / "swapped.fmu"
    with zipfile.ZipFile(fmus["prandtl"]) as source, zipfile.ZipFile(swapped, "w") as target:
        for info in source.infolist():
            data = source.read(info)
            target.writestr(info, stock_binary if info.filename == "binaries/linux64/PrandtlElement.so" else data)
    script = MIXED.format(root=str(ROOT), patched=str(fmus["prandtl"]), stock=str(swapped))
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, PRANDTL_FMU_FULL_EXIT=""))
    assert done.returncode in (0, -6, 134) and done.stdout.strip(), done.stderr[-2000:]  # stock: abort at exit
    before, after, x = done.stdout.split()
    assert int(after) >= int(before)  # never fewer references to the dict than before the stock runs
    assert float(x) != 0.0
