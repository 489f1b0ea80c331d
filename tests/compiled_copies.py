"""The kernels this run's numba cache holds a copy of for a constant argument.

numba compiles a kernel called with a constant (``solve_step(..., -1, ...)``, ``_refine(..., 1, ...)``) once more
for that constant: a literal is a signature of its own. The network's implicit step was compiled twice that way,
38 s of a cold run of the suite; the callers now hand such arguments as ``np.int64`` / ``np.bool_``.

The check reads the cache's index files (every signature any process compiled from these sources), not the
dispatchers of this process, which hold only what this process compiled or loaded: a kernel loaded whole from
the cache never types its callees.
"""
import pickle

from numba.core import types

from prandtl_fmu import _jit


def literal_signatures() -> list:
    """``name(signature)`` of every cached kernel signature with a literal argument."""
    found = []
    for path in sorted(_jit.cache_root().rglob("*.nbi")):
        try:
            with open(path, "rb") as index:
                pickle.load(index)  # numba's version
                _, overloads = pickle.loads(index.read())
        except (OSError, EOFError, pickle.UnpicklingError):  # another process is replacing it
            continue
        for key in overloads:
            if any(isinstance(argument, types.Literal) for argument in key[0]):
                found.append(f"{path.stem}{key[0]}")
    return found
