"""One place that decides how the kernels are compiled.

Kernels are compiled with numba on first use and cached on disk next to the
sources. Inside an FMU the sources live in a temporary resources folder where
numba's on-disk cache has crashed host processes, so the FMU slave sets
``PRANDTL_FMU_JIT_CACHE=0`` before importing the library.
"""
import os

from numba import njit

CACHE = os.environ.get("PRANDTL_FMU_JIT_CACHE", "1") != "0"


def kernel(fn):
    """Compile ``fn`` in nopython mode (IEEE arithmetic: no fastmath), cached on disk."""
    return njit(cache=CACHE)(fn)


def loop_kernel(fn):
    """:func:`kernel` for a loop that takes compiled functions as arguments: never cached.

    numba can cache such a function only until a second process adds a
    specialisation to the cache index: re-saving the index then fails
    ("underlying object has vanished"), because the keys it reloads refer to
    compiled-function types it cannot rebuild. The loop is small; what it
    calls is cached.
    """
    return njit(cache=False)(fn)
