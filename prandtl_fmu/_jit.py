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
    """Compile ``fn`` in nopython mode (IEEE arithmetic: no fastmath)."""
    return njit(cache=CACHE)(fn)
