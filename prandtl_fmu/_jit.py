"""One place that decides how the kernels are compiled and where their machine code is cached.

Every kernel, the time loops included, is compiled with numba on first use and
cached on disk, so that a second process loads machine code instead of
compiling (``benchmarks/startup.py``). The cache lives in the user's cache
folder, never beside the sources:

    $NUMBA_CACHE_DIR, else $XDG_CACHE_HOME/numba, else ~/.cache/numba
        / <package name>-<digest of every source file of the package> / <subpackage> / ...

* numba invalidates a cached function when *its own* source changes, not when
  a function it calls in another file does; the folder name is a digest of
  every module compiled code can reach (:func:`kernel_digest`: the modules that
  define kernels and, through their imports, everything they import from the
  package), so an edit to any of them starts a fresh cache, while an edit to the
  command line, the FMU glue, the docs' generator or a benchmark recompiles
  nothing. It stands for the source stamp numba would take from the file (so a
  copy of the same sources at another place, an FMU extracted to a new temporary
  folder, finds the same cache);
* the package name is part of the folder: the library bundled in an FMU is
  imported under a private name (``fmu/python/entry.py``), and cached code names the
  modules it was compiled in, so the FMU never loads code compiled for the
  installed ``prandtl_fmu`` nor the other way round;
* inside an FMU the sources sit in a temporary folder that the importer
  deletes when it unloads the FMU. numba's default locator caches beside the
  sources (``__pycache__``) and would write there, into a folder that can
  vanish under a running process (the crash the FMU used to meet). When the
  user's cache folder cannot be created, caching is off altogether
  (``CACHE``): never beside the sources;
* processes that fill one folder at once (the workers of a test run or of a
  sweep, the FMUs of one co-simulation) save their entries under a lock of the
  folder (:func:`_guard_entries`): numba's own save can lose one of two
  entries saved at the same moment;
* an entry is checked when it is loaded: the index records the SHA-256 of each
  data file beside numba's own keys, and a data file whose bytes are not the
  recorded ones (emptied, truncated, garbage, another signature's), an index
  that cannot be read, or code compiled for another signature is a miss: the
  function compiles again and its entry is written anew (numba itself stops
  with the error, or runs another signature's machine code: a crash);
* a save that fails (a full disk, a folder made read-only) is no failure of the
  run: one line on stderr names the cache folder, and the process carries on
  without saving; a cache folder that cannot be written at the start is said
  in one line too: a read-only one that exists is still read (a shared,
  prebuilt cache), else every process compiles what it runs;
* each edit of the kernels, or upgrade, starts a new folder; a process marks
  its own as used when it starts and removes the folders of the library and of
  the FMUs' bundled copies that no process started on for a month
  (:func:`prune_stale`).

``PRANDTL_FMU_JIT_CACHE=0`` turns the cache off (everything compiles in every
process).
"""
import hashlib
import os
import pathlib
import pickle
import re
import sys
import time

from numba import njit
from numba.core import caching

_PACKAGE = pathlib.Path(__file__).resolve().parent
_PACKAGE_NAME = __name__.rpartition(".")[0] or "prandtl_fmu"


def source_digest() -> str:
    """A digest of every source file of the package (names and contents)."""
    sha = hashlib.sha256()
    for path in sorted(_PACKAGE.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        sha.update(str(path.relative_to(_PACKAGE).as_posix()).encode())
        sha.update(path.read_bytes())
    return sha.hexdigest()[:16]


# an import inside the package, as text: "from .x import", "from ..a.b import c, d", "from . import a, b"
_IMPORT = re.compile(r"^[ \t]*from[ \t]+(\.+)([\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[\w \t,]*)", re.MULTILINE)
_DEFINES_KERNELS = re.compile(r"^@(kernel|inline_kernel|generic_kernel|njit)\b", re.MULTILINE)


def _module_file(parts: tuple):
    """The source file of the package's module ``parts`` (relative to the package), or None."""
    path = _PACKAGE.joinpath(*parts)
    for candidate in (path.with_suffix(".py"), path / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def kernel_digest() -> str:
    """A digest of the sources compiled code can depend on: every module that defines a kernel (a function under
    ``@kernel``, ``@inline_kernel``, ``@generic_kernel`` or ``@njit``) and, transitively, every module of the
    package it imports (at any depth of the file: a kernel reads the globals of its module when it compiles,
    and a loop is built from kernels that other modules hand it). Imports are read as text, over-approximated
    (a name imported from a package may be a module of it): a module too many costs a recompilation, never a
    stale entry."""
    texts = {}
    for path in _PACKAGE.rglob("*.py"):
        if "__pycache__" not in path.parts:
            texts[path] = path.read_text(encoding="utf-8", errors="replace")
    pending = [path for path, text in texts.items() if _DEFINES_KERNELS.search(text)]
    reached = set(pending)
    while pending:
        path = pending.pop()
        here = path.relative_to(_PACKAGE).parent.parts
        for dots, module, names in _IMPORT.findall(texts[path]):
            if len(dots) - 1 > len(here):
                continue  # above the package
            base = here[:len(here) - (len(dots) - 1)] + tuple(p for p in module.split(".") if p)
            targets = [_module_file(base)] + [_module_file(base + (name,))
                                              for name in re.split(r"[\s,()]+", names) if name.isidentifier()]
            for target in targets:
                if target is not None and target not in reached:
                    reached.add(target)
                    pending.append(target)
    sha = hashlib.sha256()
    for path in sorted(reached):
        sha.update(str(path.relative_to(_PACKAGE).as_posix()).encode())
        sha.update(texts[path].encode("utf-8", errors="replace"))
    return sha.hexdigest()[:16]


def cache_root() -> pathlib.Path:
    """The folder of this package's compiled code (see the module docstring)."""
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "numba")
    return pathlib.Path(base) / f"{_PACKAGE_NAME.lstrip('_')}-{kernel_digest()}"


def _usable_root():
    """:func:`cache_root`, created and marked as used now (:func:`prune_stale`); None if it cannot be (no home,
    read-only disk, ...), said once on stderr (:func:`_say`)."""
    root = None
    try:
        root = cache_root()
        root.mkdir(parents=True, exist_ok=True)
        probe = root / f".probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except (OSError, RuntimeError, ValueError) as error:
        if root is not None and root.is_dir() and os.access(root, os.R_OK | os.X_OK):
            # a cache made read-only (a shared, prebuilt one): what it holds is loaded, nothing new is saved
            _say(root, error, "what it holds is loaded, nothing newly compiled is saved (NUMBA_CACHE_DIR moves "
                 "the cache)")
            return root
        _say(root or "~/.cache/numba", error, "nothing compiled is saved: every process compiles "
             "what it runs (NUMBA_CACHE_DIR moves the cache)")
        return None
    try:
        prune_stale(root)
    except Exception:  # never let the cache's housekeeping stop the library from importing
        pass
    return root


_SAID = set()  # the cache folders this process has said something about


def _say(root, error: BaseException, consequence: str) -> None:
    """One line on stderr, once per process and folder: the compiled-code cache ``root`` cannot be written
    (``error``), and what follows from it."""
    if str(root) in _SAID:
        return
    _SAID.add(str(root))
    reason = getattr(error, "strerror", None) or str(error) or type(error).__name__
    try:
        print(f"warning: the compiled-code cache {root} cannot be written ({reason}): {consequence}",
              file=sys.stderr, flush=True)
    except Exception:  # no stderr (a GUI host of an FMU): nothing to say it on
        pass


# The folders of compiled code this package makes beside one another: the library's and, for the PythonFMU
# FMUs, the bundled copy's (fmu/python/entry.py), each named after the digest of its sources. An upgrade or an
# edit of the kernels starts a new one (15 to 85 MB); nothing else would ever remove the old ones.
_OURS = re.compile(r"(prandtl_fmu|prandtl_slave_[0-9a-f]+_lib)-[0-9a-f]{16}")
USED = "last-used"  # a file in each folder whose time is when a process last started on it
STALE_AFTER = 30 * 24 * 3600.0  # seconds: a folder no process started on for this long is removed


def prune_stale(root: pathlib.Path, now=None) -> list:
    """Mark ``root`` as used now; remove the folders of :data:`_OURS` beside it that no process has started on
    for :data:`STALE_AFTER` (by their mark, else their own time), and the remains of a removal that was cut
    short. A folder is renamed away first, so that no process sees half of it. Returns the names removed.
    Bounded: one listing of the cache folder; never raises (a folder it cannot remove stays). A process that
    runs for longer than :data:`STALE_AFTER` without another starting on its folder may see it removed: it
    then compiles again what it had not loaded yet."""
    import shutil
    import time

    now = time.time() if now is None else now
    removed = []
    try:
        (root / USED).touch()
        names = os.listdir(root.parent)
    except OSError:
        return removed
    for name in names:
        folder = root.parent / name
        if name.startswith(".") and ".removing-" in name and _OURS.fullmatch(name[1:].partition(".removing-")[0]):
            shutil.rmtree(folder, ignore_errors=True)  # a removal cut short (the process was killed)
            continue
        if name == root.name or not _OURS.fullmatch(name):
            continue
        try:
            used = _used_time(folder)
            if now - used < STALE_AFTER:
                continue
            doomed = root.parent / f".{name}.removing-{os.getpid()}"
            os.rename(folder, doomed)
        except OSError:
            continue
        shutil.rmtree(doomed, ignore_errors=True)
        if not doomed.exists():
            removed.append(name)
    return removed


def _used_time(folder: pathlib.Path) -> float:
    """When a process last started on ``folder``: the later of its mark's time and its own (which the start's
    probe file also moves: a process that could not move the mark, another user's, still counts)."""
    try:
        marked = (folder / USED).stat().st_mtime
    except FileNotFoundError:
        marked = 0.0
    return max(marked, folder.stat().st_mtime)


def _install_locator(root: pathlib.Path, digest: str) -> bool:
    """Put a locator in front of numba's own for this package's functions. False (no caching) if numba's
    internals differ from what it needs."""
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    mixin = getattr(caching, "_SourceFileBackedLocatorMixin", None)
    base = getattr(caching, "_CacheLocator", None)
    if impl is None or mixin is None or base is None or not hasattr(impl, "_locator_classes"):
        return False
    guarded = _guard_entries(root)

    class DigestLocator(mixin, base):
        """numba's cache locator for this package's functions: a folder per package digest."""

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            relative = pathlib.Path(py_file).resolve().relative_to(_PACKAGE).parent
            self._cache_path = str(root / relative)

        def get_cache_path(self):
            return self._cache_path

        def get_source_stamp(self):
            return digest  # the whole package's sources, wherever they sit

        @classmethod
        def from_function(cls, py_func, py_file):
            try:
                pathlib.Path(py_file).resolve().relative_to(_PACKAGE)
            except ValueError:
                return None  # not ours: numba's own locators decide
            self = cls(py_func, py_file)
            try:
                self.ensure_cache_path()
            except OSError:  # the root was writable at import (a full disk gets here)
                if not guarded:
                    return None
            return self  # loads miss, a failed save is said (_guard_entries); None: numba's next locator decides

    DigestLocator.prandtl_fmu = True
    impl._locator_classes.insert(0, DigestLocator)
    _refuse_unimportable_entries()
    return True


def _refuse_unimportable_entries() -> None:
    """Never cache code of ours whose module was not importable when it compiled. A copy of the library imported
    for an FMU's build and then dropped from ``sys.modules`` (``fmu/build.py``) can still compile a kernel
    later; numba then records its module as "<dynamic>", and every later process that loads the entry fails with
    "No module named '<dynamic>'" (an FMU's getReal refused). Such code compiles every time instead."""
    results = getattr(caching, "CompileResultCacheImpl", None)
    if results is None or getattr(results.check_cachable, "prandtl_fmu", False):
        return
    original = results.check_cachable

    def check_cachable(self, cres):
        if getattr(getattr(self, "_locator", None), "prandtl_fmu", False):
            environment = getattr(cres, "environment", None)
            name = getattr(environment, "globals", {}).get("__name__") if environment is not None else None
            if name is None or name == "<dynamic>":
                return False
        return original(self, cres)

    check_cachable.prandtl_fmu = True
    results.check_cachable = check_cachable


# How long a process waits for another one's save to the same cache folder (a save writes two small files). Past
# it (a holder stopped in a debugger, say), this process saves as numba does, without the lock, from then on.
SAVE_LOCK_SECONDS = 30.0


# A key of ours in a function's index, beside numba's (signature, target, bytecode) keys: (CHECKSUM, data file name)
# -> the SHA-256 of the bytes saved in that data file. numba's own load looks up its keys only and never sees these.
CHECKSUM = "prandtl_fmu sha256"


def _guard_entries(root: pathlib.Path) -> bool:
    """Make numba's cache entries under ``root`` safe to save from many processes, checked when loaded, and a
    failed save no failure of the run. Another package's caches keep numba's own load and save.

    * The save: numba reads a function's index, adds the entry and writes the index back with no lock: of two
      processes saving at once, the last one's index wins and the other's entry is lost (data files no index
      names were found in a cache here; every later process compiled those functions again), and both may pick
      the same data file for different signatures, so that the index names one signature's file for another.
      Here the read, the choice of the file and both writes happen under an exclusive lock of the folder's
      ``.save.lock`` (released by the system if the process dies), and the data is written before the index
      names it, with its SHA-256 (:data:`CHECKSUM`). Where the folder cannot be locked (a file system without
      locks, a lock file this user cannot open) or the wait runs out, the entry is saved the same way without
      the lock: never worse than numba's own save. An index that cannot be read is written anew.
    * The load: numba stops with the error of an index or data file it cannot unpickle (EOFError of an emptied
      one: every later run failed), and runs whatever machine code a data file holds (another signature's: a
      crash). Here a data file whose bytes are not the ones its index recorded, an index or a data file that
      cannot be read, a compile result for another signature than the one asked for, or one numba cannot
      rebuild, is a miss: the function compiles, and its save overwrites the entry.
    * A save that fails (ENOSPC, EROFS, EACCES, EDQUOT, ...) is said once on stderr, naming the folder
      (:func:`_say`), and this process saves nothing more there.

    False if numba's internals differ from what it needs (nothing guarded)."""
    cache_file = getattr(caching, "IndexDataCacheFile", None)
    cache = getattr(caching, "Cache", None)
    needed = ("save", "load", "_load_index", "_save_index", "_data_name", "_data_path", "_dump", "_open_for_write")
    if cache_file is None or cache is None or not all(hasattr(cache_file, name) for name in needed) \
            or not all(hasattr(cache, name) for name in ("load_overload", "save_overload")):
        return False
    roots = getattr(cache_file.save, "prandtl_fmu_guarded_roots", None)
    if roots is not None:  # another copy of the package (an FMU's) guards its folder: one guard for both
        roots.add(str(root))
        return True
    roots = {str(root)}
    unlockable = set()  # folders this process gave up locking (no locks there, or the wait ran out)
    unsaved = set()  # folders a save failed in: this process saves nothing more there
    original = {"save": cache_file.save, "load": cache_file.load, "load_overload": cache.load_overload,
                "save_overload": cache.save_overload}

    def root_of(holder):
        path = str(getattr(holder, "_cache_path", ""))
        return next((mine for mine in roots if path == mine or path.startswith(mine + os.sep)), None)

    def checked_save(self, key, data):
        try:
            overloads = self._load_index()
        except Exception:  # damaged: written anew
            overloads = {}
        name = overloads.get(key)
        if name is None:
            taken = set(overloads.values())
            name = next(self._data_name(i) for i in range(1, len(taken) + 2) if self._data_name(i) not in taken)
        saved = self._dump(data)
        with self._open_for_write(self._data_path(name)) as out:
            out.write(saved)
        overloads[key] = name
        overloads[(CHECKSUM, name)] = hashlib.sha256(saved).hexdigest()
        self._save_index(overloads)

    def save(self, key, data):
        root = root_of(self)
        if root is None:
            return original["save"](self, key, data)
        if root not in unlockable:
            with _Locked(os.path.join(root, ".save.lock")) as held:
                if held:
                    return checked_save(self, key, data)
            unlockable.add(root)
        return checked_save(self, key, data)

    def load(self, key):
        if root_of(self) is None:
            return original["load"](self, key)
        try:
            overloads = self._load_index()
            name = overloads.get(key)
            if name is None:
                return None
            with open(self._data_path(name), "rb") as saved_file:
                saved = saved_file.read()
            if hashlib.sha256(saved).hexdigest() != overloads.get((CHECKSUM, name)):
                return None  # damaged, another signature's, or saved by a save that did not record it
            data = pickle.loads(saved)
        except Exception:  # an index or a data file that cannot be read or unpickled
            return None
        return data if _compiled_for(key, data) else None

    def load_overload(self, sig, target_context):
        if root_of(self) is None:
            return original["load_overload"](self, sig, target_context)
        try:
            return original["load_overload"](self, sig, target_context)
        except Exception:  # an entry numba cannot rebuild (or a folder it cannot read): compiled again
            return None

    def save_overload(self, sig, data):
        root = root_of(self)
        if root is None:
            return original["save_overload"](self, sig, data)
        if root in unsaved:
            return None
        try:
            return original["save_overload"](self, sig, data)
        except OSError as error:
            unsaved.add(root)
            _say(root, error, "this process carries on without saving what it compiles")
            return None

    save.prandtl_fmu_guarded_roots = roots
    cache_file.save, cache_file.load = save, load
    cache.load_overload, cache.save_overload = load_overload, save_overload
    return True


def _compiled_for(key, data) -> bool:
    """Whether ``data``, a data file's payload, holds code for the signature of the index key ``key``: a compile
    result's payload holds its signature (numba's ``CompileResult._reduce``: the fourth item); a payload of
    another form is not checked (its checksum was)."""
    signature = data[3] if isinstance(data, tuple) and len(data) > 3 else None
    if not hasattr(signature, "args"):
        return True
    try:
        from numba.core import sigutils

        args, return_type = sigutils.normalize_signature(key[0])
        return tuple(signature.args) == tuple(args) and return_type in (None, signature.return_type)
    except Exception:
        return False


class _Locked:
    """An exclusive lock of the file ``path`` (created if missing, readable by every user of a shared folder) for
    a ``with`` block, which gets True once it holds it; False at once if the file cannot be opened or locked
    (a file system without locks), or after SAVE_LOCK_SECONDS of another process holding it (polls every 10 ms:
    bounded). The system releases it when the process ends, however it ends: no stale lock. POSIX flock (on a
    read-only descriptor if need be), or msvcrt's byte lock on Windows. A process that holds it already (a save
    inside a save) gets True at once."""

    held_here = set()  # the lock files this process holds

    def __init__(self, path: str):
        self.path = path
        self.descriptor = None
        self.held = False

    def __enter__(self) -> bool:
        if self.path in _Locked.held_here:
            return True
        try:
            self.descriptor = _open_lock_file(self.path)
            if self.descriptor is None:
                return False
            deadline = time.monotonic() + SAVE_LOCK_SECONDS
            while True:
                try:
                    _try_lock(self.descriptor)
                    break
                except OSError as error:
                    if not _held_elsewhere(error) or time.monotonic() >= deadline:
                        return False
                    time.sleep(0.01)
            self.held = True
            _Locked.held_here.add(self.path)
            return True
        except BaseException:  # an interrupt while locking: never leave the lock held by a forgotten descriptor
            self.__exit__()
            raise

    def __exit__(self, *exc):
        if self.held:
            _Locked.held_here.discard(self.path)
            self.held = False
            try:
                _unlock(self.descriptor)
            except OSError:
                pass
        if self.descriptor is not None:
            os.close(self.descriptor)
            self.descriptor = None
        return False


def _open_lock_file(path: str):
    """A descriptor of the lock file, created with every user's read and write rights (less the umask); read-only
    if this user may only read it (another user's, in a shared folder); None if it cannot be opened."""
    for flags in (os.O_RDWR | os.O_CREAT, os.O_RDONLY):
        try:
            return os.open(path, flags | getattr(os, "O_BINARY", 0), 0o666)
        except OSError:
            continue
    return None


try:
    import fcntl

    def _try_lock(descriptor):
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)

    def _unlock(descriptor):
        fcntl.flock(descriptor, fcntl.LOCK_UN)

    def _held_elsewhere(error: OSError) -> bool:
        return isinstance(error, BlockingIOError)  # EWOULDBLOCK; ENOLCK (no locks on this file system) is not
except ImportError:  # Windows
    import errno
    import msvcrt

    def _try_lock(descriptor):
        os.lseek(descriptor, 0, os.SEEK_SET)
        msvcrt.locking(descriptor, msvcrt.LK_NBLCK, 1)

    def _unlock(descriptor):
        os.lseek(descriptor, 0, os.SEEK_SET)
        msvcrt.locking(descriptor, msvcrt.LK_UNLCK, 1)

    def _held_elsewhere(error: OSError) -> bool:
        return error.errno in (errno.EACCES, errno.EDEADLOCK)


def _cache_enabled() -> bool:
    if os.environ.get("PRANDTL_FMU_JIT_CACHE", "1") == "0":
        return False
    root = _usable_root()
    if root is None:
        return False
    try:
        return _install_locator(root, root.name)
    except Exception:  # never let a cache refinement stop the library from importing
        return False


CACHE = _cache_enabled()


def skip_blas_probe() -> None:
    """Keep numba from importing scipy.linalg when it loads its numpy implementations (0.2-0.4 s of the
    start of a command or of an FMU when scipy is installed; ``benchmarks/startup.py``), with no other effect.

    ``numba.np.arraymath`` probes for BLAS at import (``import scipy.linalg.cython_blas``), and numba imports
    it with its registries before the first compiled call, even from the cache. The probe is made to fail
    once, without importing scipy; its result, the module flag ``_HAVE_BLAS``, is then set to what it would
    have found (BLAS comes with scipy). Nothing else reads that flag (numba 0.58-0.68: it picks np.cov's inner
    product when such code is compiled); np.dot and np.linalg import scipy when first compiled, as always, so
    a host's own numba code is unaffected. Does nothing if numba's numpy implementations are already loaded.
    """
    import importlib.util
    import sys

    blas = "scipy.linalg.cython_blas"
    if "numba.np.arraymath" in sys.modules or blas in sys.modules:
        return
    sys.modules[blas] = None  # "import scipy.linalg.cython_blas" raises ImportError without importing scipy
    try:
        from numba.np import arraymath  # the probe runs here
    finally:
        del sys.modules[blas]
    arraymath._HAVE_BLAS = importlib.util.find_spec("scipy") is not None


# What numba compiles around each kernel besides its code. A kernel is called from Python or from other kernels,
# never through a C function pointer (the native FMU's C functions are cfuncs of their own: fmu/native/kernels.py),
# so none gets numba's C wrapper (``no_cfunc_wrapper``). A closure of :func:`generic_kernel` is only ever called by
# the cached kernel that wraps it, so it gets no Python wrapper either: boxing and unboxing its model tuple, and
# the machine code of that, were a sixth of the compile time of a loop (benchmarks: docs/benchmarks.md).
_NO_C_WRAPPER = dict(no_cfunc_wrapper=True)


def kernel(fn):
    """Compile ``fn`` in nopython mode (IEEE arithmetic: no fastmath), cached on disk (see above)."""
    return njit(cache=CACHE, **_NO_C_WRAPPER)(fn)


def inline_kernel(fn):
    """:func:`kernel`, inlined into its callers by numba itself: for a hot helper whose callers fix some of
    its arguments, such as a flag (each caller then compiles only its own branch), and for a thin wrapper of a
    large kernel. A kernel that calls another links the callee's machine code into its own and optimises all of
    it again (numba's linking), so each level of calls above a large kernel costs as much as the kernel's own
    optimisation: ``exact``'s step, three lines over ``attempt``, took 3.6 of a loop's 22 s (its LLVM passes
    alone 5.0 s). Inlined, it costs its own lines. A large kernel stays a kernel: inlined, its body is typed again
    in each caller (the other steppers' steps inlined into their loops compiled no faster: ``implicit``'s the
    same, the others' 0.6 to 1.4 s slower)."""
    return njit(cache=CACHE, inline="always", **_NO_C_WRAPPER)(fn)


def generic_kernel(fn):
    """:func:`kernel` for a closure over compiled functions (the time loop around a step): never cached on its
    own, since numba keys a closure's cache entry on a pickle of what it closes over. The cached kernel that
    calls it holds its machine code, and is cached (``kernels/loop.py``): numba inlines the closure there
    (a level of calls less to optimise again: :func:`inline_kernel`). Only that kernel calls it: it cannot be
    called from Python (no Python wrapper, above)."""
    return njit(cache=False, no_cpython_wrapper=True, inline="always", **_NO_C_WRAPPER)(fn)


skip_blas_probe()  # before any kernel is defined (they load numba's registries)
