"""The kernels this run's numba cache holds a copy of for a constant argument.

numba compiles a kernel called with a constant (``active_set_step(..., -1, ...)``, ``_refine(..., 1, ...)``) once more
for that constant: a literal is a signature of its own. The network's implicit step was compiled twice that way;
the callers now hand such arguments as ``np.int64`` / ``np.bool_``.

The check reads the cache's index files (every signature any process compiled from these sources, with this
numba), not the dispatchers of this process, which hold only what this process compiled or loaded: a kernel
loaded whole from the cache never types its callees (the package saves each entry under a lock of the cache
folder, so no process's entry is lost from the index: ``_jit._guard_entries``); the checks name the
kernels they need to find, so that an empty or disabled cache fails instead of passing.
"""
import pickle

import numba

from prandtl_fmu import _jit


def cached_signatures() -> dict:
    """``{index name: [signature, ...]}`` of the cache of these sources for this numba (``kernels.run_implicit``:
    the module's file name and the function's)."""
    assert _jit.CACHE, "no cache folder: nothing to check"
    found = {}
    for path in sorted(_jit.cache_root().rglob("*.nbi")):
        try:
            with open(path, "rb") as index:
                if pickle.load(index) != numba.__version__:
                    continue  # another numba's entries, which this one ignores too
                _, overloads = pickle.loads(index.read())
        except Exception:  # being replaced by another process, or unreadable here: not this run's to judge
            continue
        name = path.name.split("-")[0]
        found.setdefault(name, []).extend(str(key[0]) for key in overloads if key[0] != _jit.CHECKSUM)
    return found


def literal_signatures(*needed) -> list:
    """``name(signature)`` of every cached signature with a literal argument, at any depth (a tuple of
    constants too); ``needed``: index names that must be in the cache (else AssertionError)."""
    signatures = cached_signatures()
    missing = [name for name in needed if name not in signatures]
    assert not missing, f"not in the cache: {missing}"
    return [f"{name}{signature}" for name, listed in signatures.items() for signature in listed
            if "Literal[" in signature]


if __name__ == "__main__":  # .ci/run, after both suites: the slow tests' kernels too, which no quick check sees
    import sys

    try:
        copies = literal_signatures("stability.check")
    except AssertionError as exc:  # no cache, or not this run's: nothing to judge, and that is a failure
        sys.exit(f"compiled_copies: {exc}")
    for copy in copies:
        print(f"compiled once more for a constant argument: {copy}", file=sys.stderr)
    print(f"{len(copies)} kernel signatures with a literal in the cache of this run ({_jit.cache_root()})")
    sys.exit(1 if copies else 0)
