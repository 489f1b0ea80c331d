"""The compiled-code cache heals (prandtl_fmu/_jit.py): a damaged index or data file is a miss, compiled again and
written anew, never an error nor another signature's machine code; a save that fails (a full disk) and a cache
folder that cannot be written are said once on stderr, naming the folder, and the run goes on.

The kernel is ``kernels.smooth.elastic_force`` (k0 x + k3 x^3), small enough to compile in a fresh cache folder in
about a second, at two signatures: (2, 3, None) gives 6 and (2, None, 3) gives 24."""
import hashlib
import json
import os
import pickle
import subprocess
import sys
import textwrap

import pytest

RUN = textwrap.dedent("""\
    import json, sys
    if len(sys.argv) > 1:  # a file size limit: every write of a byte fails (EFBIG), as on a full disk
        import resource, signal
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (int(sys.argv[1]), resource.RLIM_INFINITY))
    from prandtl_fmu.kernels.smooth import elastic_force
    forces = [elastic_force(2.0, 3.0, None), elastic_force(2.0, None, 3.0)]
    print(json.dumps({"forces": forces, "misses": sum(elastic_force.stats.cache_misses.values())}))
""")
CLEAN = [6.0, 24.0]


def _without_overriding_file_rights():
    """In the child, before it runs Python: drop the capabilities that let root write a read-only folder
    (CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH) from its bounding set, so that the exec'ed interpreter is held to
    the folder's rights as any user is (Linux's prctl PR_CAPBSET_DROP; a user without them has nothing to drop)."""
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)
    for capability in (1, 2):
        libc.prctl(24, capability, 0, 0, 0)


def run(cache, *arguments, read_only=False):
    """RUN in a process of its own with the cache folder ``cache``: (its JSON line, its stderr). ``read_only``:
    held to the files' rights even as root (:func:`_without_overriding_file_rights`)."""
    done = subprocess.run([sys.executable, "-c", RUN, *arguments], capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, NUMBA_CACHE_DIR=str(cache), PRANDTL_FMU_JIT_CACHE="1"),
                          preexec_fn=_without_overriding_file_rights if read_only else None)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1]), done.stderr


def entry_files(cache):
    """The kernel's index and its data files, {name: path}."""
    [folder] = list(cache.glob("prandtl_fmu-*/kernels"))
    return {path.name: path for path in folder.glob("smooth.elastic_force-*")}


def checked(cache) -> dict:
    """{data file name: signature} of the kernel's index, each data file's bytes those the index recorded."""
    from prandtl_fmu import _jit

    files = entry_files(cache)
    [index] = [path for name, path in files.items() if name.endswith(".nbi")]
    with open(index, "rb") as opened:
        pickle.load(opened)
        _, overloads = pickle.loads(opened.read())
    names = {name: key[0] for key, name in overloads.items() if key[0] != _jit.CHECKSUM}
    for name in names:
        assert hashlib.sha256(files[name].read_bytes()).hexdigest() == overloads[(_jit.CHECKSUM, name)], name
    assert sorted(names) == sorted(name for name in files if name.endswith(".nbc"))
    return names


def damage(cache, how: str) -> None:
    files = entry_files(cache)
    index = next(path for name, path in files.items() if name.endswith(".nbi"))
    first, second = sorted(path for name, path in files.items() if name.endswith(".nbc"))
    if how == "swapped data":  # each signature's index entry names the other one's machine code
        one, other = first.read_bytes(), second.read_bytes()
        first.write_bytes(other)
        second.write_bytes(one)
        return
    target = index if how.endswith("index") else first
    data = target.read_bytes()
    target.write_bytes({"emptied": b"", "truncated": data[:len(data) // 2],
                        "garbage": os.urandom(len(data))}[how.split()[0]])


def heals(tmp_path, how: str, again: bool) -> None:
    """The kernel run in a fresh cache folder, its entry damaged ``how``, run again: the clean numbers, compiled
    again and written anew; ``again``: a third process then loads every signature (compiles nothing)."""
    cache = tmp_path / "cache"
    clean, said = run(cache)
    assert clean == {"forces": CLEAN, "misses": 2} and said == ""
    signatures = checked(cache)
    damage(cache, how)
    healed, said = run(cache)
    assert healed["forces"] == CLEAN and said == ""
    assert healed["misses"] >= 1  # compiled again what it could not load
    assert checked(cache) == signatures  # and wrote it anew: every data file the one its index recorded
    if again:
        loaded, _ = run(cache)
        assert loaded == {"forces": CLEAN, "misses": 0}


def test_data_files_swapped_between_signatures_are_a_miss_not_a_crash(tmp_path):
    """Each signature's data file holding the other's machine code (numba ran it: a crash, SIGSEGV, or another
    signature's number): both load as misses, compile again, and the entries are written anew."""
    heals(tmp_path, "swapped data", again=False)


@pytest.mark.slow  # four processes for each damage
@pytest.mark.parametrize("how", ["emptied index", "truncated index", "garbage index", "emptied data",
                                 "truncated data", "garbage data"])
def test_a_damaged_index_or_data_file_is_a_miss_that_heals(tmp_path, how):
    """An emptied, truncated or garbage index or data file (numba stopped every later run with EOFError or an
    unpickling error): the run gives the clean numbers, the entry is written anew, and the next run loads it."""
    heals(tmp_path, how, again=True)


def test_a_save_that_fails_is_said_once_naming_the_cache_and_the_run_goes_on(tmp_path):
    """Every write of the save failing (a file size limit of 0 bytes: EFBIG, as ENOSPC on a full disk): the run
    gives the clean numbers, exit 0, and one line on stderr names the cache folder; nothing was saved."""
    cache = tmp_path / "cache"
    result, said = run(cache, "0")
    assert result["forces"] == CLEAN
    [line] = said.splitlines()
    [folder] = list(cache.glob("prandtl_fmu-*"))
    assert line.startswith(f"warning: the compiled-code cache {folder} cannot be written ("), line
    assert not list(cache.rglob("*.nbi")) and not list(cache.rglob("*.nbc"))


def test_a_cache_folder_that_cannot_be_written_is_said_once(tmp_path):
    """A cache folder that cannot be made (below a file, as below a read-only mount): the run compiles in memory and
    gives the clean numbers, and says so in one line naming the folder, instead of compiling every run silently."""
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    result, said = run(blocker / "cache")
    assert result["forces"] == CLEAN
    [line] = said.splitlines()
    assert line.startswith(f"warning: the compiled-code cache {blocker / 'cache'}/prandtl_fmu-"), line
    assert "nothing compiled is saved" in line, line


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the child drops root's rights with Linux's prctl")
def test_a_read_only_cache_is_loaded_and_said_once(tmp_path):
    """A filled cache made read-only (a shared, prebuilt one): the next process loads every entry (compiles
    nothing: the cache serves, where it used to compile every run), gives the clean numbers and says in one line
    naming the folder that nothing new is saved; the cache's files are unchanged."""
    cache = tmp_path / "cache"
    clean, _ = run(cache)
    assert clean == {"forces": CLEAN, "misses": 2}
    files = sorted(cache.rglob("*"))
    before = {path: path.read_bytes() for path in files if path.is_file()}
    for path in [cache, *files]:
        path.chmod(path.stat().st_mode & ~0o222)
    try:
        loaded, said = run(cache, read_only=True)
    finally:
        for path in [cache, *files]:
            path.chmod(path.stat().st_mode | 0o200)
    assert loaded == {"forces": CLEAN, "misses": 0}
    [line] = said.splitlines()
    [folder] = list(cache.glob("prandtl_fmu-*"))
    assert line.startswith(f"warning: the compiled-code cache {folder} cannot be written ("), line
    assert "what it holds is loaded" in line, line
    assert sorted(cache.rglob("*")) == files and all(path.read_bytes() == data for path, data in before.items())
