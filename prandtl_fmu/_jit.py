"""One place that decides how the kernels are compiled.

Kernels are compiled with numba on first use and cached on disk. numba
invalidates a cached function when *its own* source file changes, not when a
function it calls in another file does; so our cache lives in a folder named
after a digest of every source file of the package (``<numba cache>/prandtl_fmu-<digest>``):
any edit anywhere gives a fresh cache.

Inside an FMU the sources live in a temporary resources folder where numba's
on-disk cache has crashed host processes, so the FMU's entry point sets
``PRANDTL_FMU_JIT_CACHE=0`` before importing the library.
"""
import hashlib
import os
import pathlib

from numba import njit
from numba.core import caching

CACHE = os.environ.get("PRANDTL_FMU_JIT_CACHE", "1") != "0"
_PACKAGE = pathlib.Path(__file__).resolve().parent


def _digest() -> str:
    sha = hashlib.sha256()
    for path in sorted(_PACKAGE.rglob("*.py")):
        sha.update(str(path.relative_to(_PACKAGE)).encode())
        sha.update(path.read_bytes())
    return sha.hexdigest()[:16]


def _install_locator():
    """Put a locator in front of numba's own for this package's functions (numba internals:
    if they differ in some numba version, numba's default locator is kept)."""
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    mixin = getattr(caching, "_SourceFileBackedLocatorMixin", None)
    base = getattr(caching, "_CacheLocator", None)
    if impl is None or mixin is None or base is None:
        return

    class DigestLocator(mixin, base):
        """numba's cache locator for this package's functions: a folder per source digest."""

        root = None

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            relative = pathlib.Path(py_file).resolve().relative_to(_PACKAGE).parent
            self._cache_path = str(pathlib.Path(self.root) / str(relative))

        def get_cache_path(self):
            return self._cache_path

        @classmethod
        def from_function(cls, py_func, py_file):
            try:
                pathlib.Path(py_file).resolve().relative_to(_PACKAGE)
            except ValueError:
                return None  # not ours: numba's own locators decide
            if cls.root is None:
                base_dir = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
                    os.environ.get("XDG_CACHE_HOME", os.path.join(os.path.expanduser("~"), ".cache")), "numba")
                cls.root = os.path.join(base_dir, f"prandtl_fmu-{_digest()}")
            self = cls(py_func, py_file)
            try:
                self.ensure_cache_path()
            except OSError:
                return None
            return self

    if not any(getattr(c, "__name__", "") == "DigestLocator" for c in impl._locator_classes):
        impl._locator_classes.insert(0, DigestLocator)


if CACHE:
    try:
        _install_locator()
    except Exception:  # never let a cache refinement stop the library from importing
        pass


def kernel(fn):
    """Compile ``fn`` in nopython mode (IEEE arithmetic: no fastmath), cached on disk."""
    return njit(cache=CACHE)(fn)


def inline_kernel(fn):
    """:func:`kernel`, inlined into its callers by numba itself (for a hot helper whose callers fix some of
    its arguments, such as a flag: each caller then compiles only its own branch)."""
    return njit(cache=CACHE, inline="always")(fn)


def loop_kernel(fn):
    """:func:`kernel` for a loop that takes compiled functions as arguments: never cached.

    numba can cache such a function only until a second process adds a
    specialisation to the cache index: re-saving the index then fails
    ("underlying object has vanished"), because the keys it reloads refer to
    compiled-function types it cannot rebuild. The loop is small; what it
    calls is cached.
    """
    return njit(cache=False)(fn)
