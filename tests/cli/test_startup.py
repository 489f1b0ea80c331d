"""Time to first result: every kernel a run needs is cached across processes, in the user's cache folder,
for the library and for the FMU (never in the FMU's extracted resources). Timings themselves are measured by
``benchmarks/startup.py``, not here."""
import json
import os
import pathlib
import shutil
import subprocess
import sys
import textwrap
import time

import pytest

from prandtl_fmu.fmu.build import build_fmu

from tests.conftest import base_tables, scene_text

# Runs the library on scenes that need every kind of kernel (each stepper, the massless element, the memory
# stack, states and the energy account, the stateful Element), then prints what numba compiled in this
# process and a fingerprint of the results.
LIBRARY_RUN = textwrap.dedent("""\
    import hashlib, json, sys
    import numpy as np
    from numba.core.registry import CPUDispatcher
    from prandtl_fmu import Element, parse_scene, simulate
    runs = json.loads(sys.argv[1])
    sha = hashlib.sha256()
    for text, stepper in runs:
        scene = parse_scene(text)
        result = simulate(scene, stepper, states=scene.branches is not None and not scene.branches.continuum,
                          energy=stepper != "exact", progress=False)
        for values in result.columns().values():
            sha.update(np.ascontiguousarray(values).tobytes())
        element = Element(scene, stepper=stepper)
        element.advance(0.37, 0.2)
        element.advance(1.0, -0.1)
        sha.update(np.array([element.x, element.v, element.reaction]).tobytes())
    compiled = []
    for name, module in list(sys.modules.items()):
        if not name.startswith("prandtl_fmu"):
            continue
        for attr, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.__module__ == name:
                misses = sum(value.stats.cache_misses.values()) if value._cache.__class__.__name__ != "NullCache" \\
                    else len(value.overloads)
                if misses:
                    compiled.append(f"{name}.{attr}: {misses}")
    print(json.dumps({"compiled": sorted(compiled), "results": sha.hexdigest()}))
""")


def _run_library(runs, cache):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    done = subprocess.run([sys.executable, "-c", LIBRARY_RUN, json.dumps(runs)], capture_output=True, text=True,
                          env=env, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def _scenes():
    linear = base_tables(cubic=None)
    many = base_tables(cubic=None, branches={"count": 80, "k_total": 1.0, "eta_range": [0.1, 1.1]})
    massless = base_tables(mass=None, damper=None, spring={"k0": 0.5})
    continuum = base_tables(cubic=None, branches={"continuum": True, "k_total": 1.0, "eta_range": [0.0, 1.0]})
    short = {"stepper": "projected", "step": 1e-2, "stop_time": 2.0, "output_interval": 0.1}
    runs = [(scene_text(dict(base_tables(), solver=short)), stepper) for stepper in ("projected", "implicit",
                                                                                     "symplectic", "verlet")]
    runs.append((scene_text(dict(linear, solver=short)), "exact"))
    runs.append((scene_text(dict(many, solver=short)), "projected"))  # the memory stack
    runs.append((scene_text(dict(massless, solver=dict(short, stepper="implicit"))), "implicit"))
    runs.append((scene_text(dict(continuum, solver=short)), "verlet"))
    return runs


@pytest.mark.slow
def test_a_second_process_compiles_nothing_and_gets_the_same_numbers(tmp_path):
    """The first process starts from a copy of this test run's cache (what the suite compiled so far; empty when
    the run is cold) and compiles what is missing from it; the second finds all of it in the cache: a kernel
    that numba could not cache, or cached under a key a second process does not find, would compile again."""
    from prandtl_fmu import _jit

    runs = _scenes()
    shared, cache = _jit.cache_root(), tmp_path / "cache"
    if shared.is_dir():  # the cold compile of every kernel is benchmarks/cold_start.py's; a copy saves it here
        shutil.copytree(shared, cache / shared.name,
                        ignore=shutil.ignore_patterns("*.tmp.*", ".probe-*", ".save.lock"))
    first = _run_library(runs, cache)
    second = _run_library(runs, cache)
    assert second["compiled"] == [], f"compiled again in a warm process: {second['compiled']}"
    assert second["results"] == first["results"]
    # the cache is the user's folder, one per package digest
    assert [p.name for p in cache.iterdir()] == [shared.name]
    assert shared.name.startswith("prandtl_fmu-")


@pytest.mark.slow  # a long check (the quick suite's cold budget, README)
def test_the_cache_folder_follows_the_sources(tmp_path):
    """An edit of a source file that compiled code can reach gives another cache folder (numba alone would miss
    an edit of a callee in another file): a kernel's module, and a module a kernel module imports (libm.py, whose
    functions the kernels call); an edit of a module no kernel reaches (the command line, the FMU glue) keeps the
    folder, so the compiled code stays. The same sources at another place give the same one (an FMU extracted
    anew)."""
    import prandtl_fmu

    package = pathlib.Path(prandtl_fmu.__file__).parent
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import prandtl_fmu._jit as j; "
            "print(j.cache_root().name, j.CACHE)")

    def folder_of(copy):
        env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
        done = subprocess.run([sys.executable, "-c", code, str(copy)], capture_output=True, text=True, env=env,
                              cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        name, enabled = done.stdout.split()
        assert enabled == "True"
        return name

    copies = []
    for where in ("a", "b"):
        target = tmp_path / where / "prandtl_fmu"
        shutil.copytree(package, target, ignore=shutil.ignore_patterns("__pycache__"))
        copies.append(target.parent)
    assert folder_of(copies[0]) == folder_of(copies[1])
    for outside in ("cli.py", "fmu/python/slave.py", "sweep/spec.py"):
        glue = copies[1] / "prandtl_fmu" / outside
        glue.write_text(glue.read_text() + "\n# an edit\n")
        assert folder_of(copies[0]) == folder_of(copies[1]), f"an edit of {outside} changed the cache folder"
    seen = {folder_of(copies[1])}
    for reached in ("kernels/smooth.py", "libm.py", "kernels/loop.py", "steppers/projected.py"):
        source = copies[1] / "prandtl_fmu" / reached
        source.write_text(source.read_text() + "\n# an edit\n")
        folder = folder_of(copies[1])
        assert folder not in seen, f"an edit of {reached} kept the cache folder"
        seen.add(folder)


def test_no_usable_cache_folder_means_no_cache_not_a_cache_beside_the_sources(tmp_path):
    """With a cache folder that cannot be created, the kernels compile in memory: nothing is written beside
    the sources (the FMU's extracted resources, which the importer deletes)."""
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    code = ("import prandtl_fmu._jit as j, prandtl_fmu.kernels.smooth as s; print(j.CACHE); "
            "print(s.elastic_force(1.0, 2.0, None))")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(blocker / "cache"))
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "2.0"]


# Saves entries into one index of the package's cache folder (NUMBA_CACHE_DIR) as numba saves a compiled function:
# worker w saves keys (w, 0) .. (w, count - 1), each with data naming its key, starting when the file "go" appears.
SAVER = textwrap.dedent("""\
    import os, pathlib, sys, time
    from numba.core import caching
    import prandtl_fmu._jit as jit
    worker, count, folder = int(sys.argv[1]), int(sys.argv[2]), pathlib.Path(sys.argv[3])
    assert jit.CACHE
    index = caching.IndexDataCacheFile(cache_path=str(jit.cache_root() / "race"), filename_base="f",
                                       source_stamp="s")
    os.makedirs(jit.cache_root() / "race", exist_ok=True)
    (folder / f"ready-{worker}").write_bytes(b"")
    deadline = time.monotonic() + 120
    while not (folder / "go").exists() and time.monotonic() < deadline:
        time.sleep(0.001)
    for i in range(count):
        index.save((worker, i), ("data of", worker, i))
""")


def test_processes_saving_into_one_cache_at_once_lose_no_entry_and_mix_no_data(tmp_path):
    """numba reads a function's index, adds an entry and writes the index back with no lock: of processes
    saving at once (the workers of a test run or a sweep, the FMUs of a co-simulation) the last index written
    wins, the others' entries are lost (every later process compiles them again), and two may take the same
    data file for different signatures. The package saves under a lock of its cache folder (``_jit``): six
    processes saving 40 entries each into one index, all at once, leave 240 entries, each naming its own data."""
    from numba.core import caching

    from prandtl_fmu import _jit

    workers, count = 6, 40
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PRANDTL_FMU_JIT_CACHE="1")
    running = [subprocess.Popen([sys.executable, "-c", SAVER, str(w), str(count), str(tmp_path)], env=env,
                                stderr=subprocess.PIPE, text=True) for w in range(workers)]
    try:
        deadline = time.monotonic() + 120
        while len(list(tmp_path.glob("ready-*"))) < workers and time.monotonic() < deadline:
            failed = [worker for worker in running if worker.poll() not in (None, 0)]
            assert not failed, failed[0].communicate()[1]
            time.sleep(0.01)
        (tmp_path / "go").write_bytes(b"")
        for worker in running:
            _, errors = worker.communicate(timeout=300)
            assert worker.returncode == 0, errors
    finally:
        for worker in running:
            if worker.poll() is None:
                worker.kill()
    [folder] = list((tmp_path / "cache").glob("prandtl_fmu-*/race"))
    index = caching.IndexDataCacheFile(cache_path=str(folder), filename_base="f", source_stamp="s")
    entries = {key: name for key, name in index._load_index().items() if key[0] != _jit.CHECKSUM}
    assert sorted(entries) == [(w, i) for w in range(workers) for i in range(count)]
    assert all(index.load(key) == ("data of", *key) for key in entries)  # each checked against its checksum
    assert len(set(entries.values())) == workers * count


@pytest.mark.parametrize("lock_error", ["no locks here", "held past the wait"])
def test_a_folder_that_cannot_be_locked_is_saved_without_the_lock_never_not_at_all(tmp_path, monkeypatch,
                                                                                      lock_error):
    """Where the lock cannot be had, the entry is saved without it: at once on a file system without locks
    (ENOLCK: no wait), after SAVE_LOCK_SECONDS when another process holds the lock, and that folder is then saved
    without the lock for the rest of the process (no wait at every save)."""
    import errno

    from numba.core import caching

    from prandtl_fmu import _jit

    roots = caching.IndexDataCacheFile.save.prandtl_fmu_guarded_roots
    calls = []

    def refuse(descriptor):
        calls.append(descriptor)
        if lock_error == "no locks here":
            raise OSError(errno.ENOLCK, "No locks available")
        raise BlockingIOError(errno.EWOULDBLOCK, "held by another process")

    monkeypatch.setattr(_jit, "_try_lock", refuse)
    monkeypatch.setattr(_jit, "SAVE_LOCK_SECONDS", 0.05)
    if lock_error == "no locks here":
        monkeypatch.setattr(_jit.time, "sleep", lambda seconds: pytest.fail("waited for a lock that cannot be had"))
    roots.add(str(tmp_path))
    try:
        index = caching.IndexDataCacheFile(cache_path=str(tmp_path / "kernels"), filename_base="f", source_stamp="s")
        (tmp_path / "kernels").mkdir()
        index.save(("a",), "data of a")
        tries = len(calls)
        index.save(("b",), "data of b")
    finally:
        roots.discard(str(tmp_path))
    entries = [key for key in index._load_index() if key[0] != _jit.CHECKSUM]
    assert {key: index.load(key) for key in entries} == {("a",): "data of a", ("b",): "data of b"}
    assert tries == 1 if lock_error == "no locks here" else tries >= 2  # one try, or tries until the wait ran out
    assert len(calls) == tries  # the second save did not try again


def test_a_process_marks_its_cache_folder_and_removes_ours_unused_for_a_month(tmp_path):
    """Each edit of the kernels or upgrade starts a cache folder of its own (15 to 85 MB): a process marks its
    folder as used and removes the folders of the library and of the FMUs' bundled copies that no process
    started on for 30 days (by their mark, else their own time), and what a removal cut short left. Folders
    that are not ours, or ours but used within the month, stay."""
    day = 24 * 3600.0
    now = time.time()
    ages = {"prandtl_fmu-0123456789abcdef": 40, "prandtl_fmu-fedcba9876543210": 29,
            "prandtl_slave_a9b740f31440_lib-0123456789abcdef": 31, "prandtl_slave_a9b740f31440_source": 400,
            "other-0123456789abcdef": 400, "prandtl_fmu-0123": 400, ".prandtl_fmu-00112233aabbccdd.removing-7": 0}
    for name, age in ages.items():
        folder = tmp_path / name
        (folder / "sub").mkdir(parents=True)
        (folder / "sub" / "kernel.nbi").write_bytes(b"x")
        if name.startswith("prandtl_fmu-f"):
            (folder / "last-used").write_bytes(b"")  # marked 29 days ago, the folder itself older
            os.utime(folder / "last-used", (now - age * day,) * 2)
            age = 400
        os.utime(folder, (now - age * day,) * 2)
    code = "import prandtl_fmu._jit as j; print(j.CACHE, j.cache_root().name)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path)))
    assert done.returncode == 0, done.stderr
    cache, own = done.stdout.split()
    assert cache == "True"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([
        own, "prandtl_fmu-fedcba9876543210", "prandtl_slave_a9b740f31440_source", "other-0123456789abcdef",
        "prandtl_fmu-0123"])
    assert now - (tmp_path / own / "last-used").stat().st_mtime < day


FMU_RUN = textwrap.dedent("""\
    import json, os, shutil, sys
    from fmpy import extract, simulate_fmu
    fmu, work = sys.argv[1], sys.argv[2]
    results = []
    first = extract(fmu, unzipdir=os.path.join(work, "first"))
    results.append(simulate_fmu(first, stop_time=1.0, output_interval=0.1)["x"][-1])
    beside = [p for p, _, files in os.walk(first) for f in files if f.endswith((".nbi", ".nbc"))]
    # the importer deletes its extraction folder; the library it loaded stays in the process
    shutil.rmtree(first)
    second = extract(fmu, unzipdir=os.path.join(work, "second"))
    results.append(simulate_fmu(second, stop_time=1.0, output_interval=0.1,
                                start_values={"stepper": "verlet"})["x"][-1])
    compiled = []
    from numba.core.registry import CPUDispatcher
    for name, module in list(sys.modules.items()):
        if name.startswith("_prandtl_slave_"):
            for attr, value in vars(module).items():
                if isinstance(value, CPUDispatcher) and value.__module__ == name:
                    compiled += [f"{name}.{attr}"] * sum(value.stats.cache_misses.values())
    print(json.dumps({"results": [float(r) for r in results], "beside": beside, "compiled": compiled}),
          flush=True)
""")


@pytest.mark.slow
def test_the_fmu_uses_the_user_cache_and_survives_its_deleted_resources(tmp_path):
    scene = tmp_path / "cached.toml"
    scene.write_text(scene_text(dict(base_tables(), solver={"stepper": "projected", "step": 1e-2,
                                                            "stop_time": 1.0, "output_interval": 0.1})))
    fmu = build_fmu(scene, tmp_path / "cached.fmu")
    cache = tmp_path / "cache"
    # the FMU's own copy of the library (entry.py), the one that lives in its resources: this host's prandtl_fmu
    # has the FMU's sources, and would run it otherwise
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), PRANDTL_FMU_BUNDLED_LIBRARY="1")
    outcomes = []
    for run in ("cold", "warm"):
        work = tmp_path / run
        work.mkdir()
        done = subprocess.run([sys.executable, "-c", FMU_RUN, str(fmu), str(work)], capture_output=True,
                              text=True, env=env, timeout=900)
        assert done.returncode == 0, done.stderr[-3000:]
        outcomes.append(json.loads(done.stdout.strip().splitlines()[-1]))
    cold, warm = outcomes
    assert cold["beside"] == [] and warm["beside"] == [], "compiled code was written into the FMU's resources"
    assert cold["compiled"], "the cold process should have compiled the FMU's kernels"
    assert warm["compiled"] == [], f"the FMU compiled again with a warm cache: {warm['compiled']}"
    assert warm["results"] == cold["results"]
    folders = sorted(p.name for p in cache.iterdir())  # the kernels', and the library's lasting copy (entry.py)
    assert len(folders) == 2 and folders[0].startswith("prandtl_slave_") and folders[1].endswith("_source"), \
        folders


BLAS_PROBE = textwrap.dedent("""\
    import importlib.util, sys
    if sys.argv[1] == "numba-first":  # numba's numpy implementations loaded, and BLAS probed, before us
        import numba.np.arraymath
    from prandtl_fmu import load_scene, simulate
    result = simulate(load_scene("paper-section-8"), "projected", progress=False)
    scipy_linalg_before = "scipy.linalg" in sys.modules
    from numba.np import arraymath
    import numpy as np
    from numba import njit
    @njit
    def dot(a, b):  # a host's own code that needs BLAS, compiled after our kernels
        return np.dot(a, b)
    print(repr(float(result.x[-1])), scipy_linalg_before, arraymath._HAVE_BLAS,
          importlib.util.find_spec("scipy") is not None, dot(np.arange(3.0), np.ones(3)), flush=True)
""")


@pytest.mark.slow
def test_numba_does_not_import_scipy_linalg_for_our_kernels_and_nothing_else_changes(tmp_path):
    """_jit.skip_blas_probe: numba probes BLAS by importing scipy.linalg (0.2-0.4 s) when it loads its numpy
    implementations; our kernels need none. With the probe skipped, scipy.linalg is not imported by a run,
    numba's flag is what the probe finds, np.dot still compiles in the same process, and the results are
    bit for bit those of a process where numba probed first."""
    script = tmp_path / "probe.py"
    script.write_text(BLAS_PROBE)
    outputs = {}
    for order in ("ours-first", "numba-first"):
        done = subprocess.run([sys.executable, str(script), order], capture_output=True, text=True, timeout=900)
        assert done.returncode == 0, done.stderr[-2000:]
        outputs[order] = done.stdout.split()
    x, scipy_linalg_before, have_blas, scipy_present, dot = outputs["ours-first"]
    assert scipy_linalg_before == "False"  # not imported for our kernels
    assert have_blas == scipy_present  # what the probe would have found
    assert dot == "3.0"
    assert outputs["numba-first"][0] == x and outputs["numba-first"][2] == have_blas
