"""PythonFMU entry point of a prandtl_fmu FMU.

``build_fmu.py`` copies this file into the FMU as
``resources/prandtl_slave_<digest>.py``, where the digest is that of the
library's sources (``fmu/python/build.py``). It imports the library bundled
beside it (``resources/prandtl_fmu``) under a private package name made from
that digest, so that the FMU runs the code it was built and tested with
whatever ``prandtl_fmu`` the host may have imported, and hands PythonFMU the
slave class defined there. The library is imported once per process: FMUs
built from the same sources share it (each instance reads its scene from its
own resources), and their kernels compile once for all of them; its compiled
kernels come from the user's numba cache folder, never from the extracted
resources (see ``_jit.py``).

Where the host's Python has a ``prandtl_fmu`` with the same sources, file for
file (the same digest: the same version, unedited), the FMU runs that one
instead of its copy: the same code, whose kernels the host has often compiled
already (a script that runs the library and its FMUs), where the copy would
compile every one of them again under its private name. Any other
``prandtl_fmu``, or ``PRANDTL_FMU_BUNDLED_LIBRARY=1``, and the FMU imports its
own copy.

The library is imported from a copy in the user's cache folder
(``<numba cache folder>/prandtl_slave_<digest>_source/prandtl_fmu``, made once
and checked against the digest at every import), not from the resources: an
importer deletes its extraction folder when it unloads the FMU, and the
library imports some modules only when a scene needs them (a network, an
effect with memory), which a later FMU of the same sources may. Where that
folder cannot be written, the library is imported from the resources.

At every instantiation the loader executes this file again (globals: this
module's dict) and inserts the resources folder into ``sys.path`` once more:
the duplicate entries are dropped, so that a thousand instantiations do not
slow the host's imports down. PythonFMU 0.7.0's stock loader (the Windows
binary, or an FMU built with ``loader="pythonfmu"``) also releases one
reference to the module's dict that it never took: each execution under it
keeps one more reference. The FMU's own loader (``loader/``) marks the
globals with ``__prandtl_loader__`` before executing the file, and takes
nothing for this execution.
"""
import importlib
import importlib.util
import os
import sys

# The mark is taken away at once: it says which loader runs *this* execution (a process may load FMUs of
# both loaders, and a stale mark would leave the stock loader's release uncompensated: a freed dict).
if not globals().pop("__prandtl_loader__", False):  # the stock loader's extra release (module docstring)
    globals().setdefault("_DICT_REFERENCES", []).append(globals())

_HERE = os.path.dirname(os.path.abspath(__file__))
_LIBRARY = "_" + __name__ + "_lib"


def _drop_duplicate_path_entries(here):
    seen = False
    for entry in list(sys.path):
        if os.path.abspath(entry or ".") == here:
            if seen:
                sys.path.remove(entry)
            seen = True


def _sources_digest(folder):
    """``_jit.source_digest`` of the library at ``folder`` (its .py files' names and contents), 12 digits."""
    import hashlib

    sha = hashlib.sha256()
    paths = []
    for where, directories, files in os.walk(folder):
        directories[:] = [d for d in directories if d != "__pycache__"]
        paths += [os.path.join(where, f) for f in files if f.endswith(".py")]
    for path in sorted(paths, key=lambda p: tuple(os.path.relpath(p, folder).split(os.sep))):  # as pathlib sorts
        sha.update(os.path.relpath(path, folder).replace(os.sep, "/").encode())
        with open(path, "rb") as fh:
            sha.update(fh.read())
    return sha.hexdigest()[:12]


def _lasting_copy(folder):
    """The library at ``folder`` copied into the user's cache folder (once; a copy that does not match the
    digest in this module's name is replaced), or None where that cannot be done."""
    import shutil
    import tempfile

    digest = __name__.rpartition("_")[2]
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "numba")
    home = os.path.join(base, __name__ + "_source")
    copy = os.path.join(home, "prandtl_fmu")
    try:
        if os.path.isdir(copy) and _sources_digest(copy) == digest:
            return copy
        if _sources_digest(folder) != digest:
            return None  # resources that are not what the name says: import them as they are
        os.makedirs(base, exist_ok=True)
        partial = tempfile.mkdtemp(prefix=".prandtl_slave_source-", dir=base)
        try:
            shutil.copytree(folder, os.path.join(partial, "prandtl_fmu"),
                            ignore=shutil.ignore_patterns("__pycache__"))
            if os.path.isdir(home):
                shutil.rmtree(home, ignore_errors=True)  # a damaged copy
            try:
                os.rename(partial, home)
            except OSError:  # another process put its copy there first
                pass
        finally:
            shutil.rmtree(partial, ignore_errors=True)
        return copy if os.path.isdir(copy) and _sources_digest(copy) == digest else None
    except OSError:
        return None


def _host_library():
    """The host's own ``prandtl_fmu`` where its sources are this FMU's, file for file (the digest in this module's
    name), else None. The same code then runs, and its kernels are the ones the host has compiled already (a
    script that runs the library and its FMUs, the tests): the FMU's own copy would compile them all again under
    its private name (a minute or more for a new user, once). ``PRANDTL_FMU_BUNDLED_LIBRARY=1`` makes the FMU import
    its own copy whatever the host has."""
    if os.environ.get("PRANDTL_FMU_BUNDLED_LIBRARY", "0") not in ("", "0"):
        return None
    try:
        spec = importlib.util.find_spec("prandtl_fmu")
        folders = list(spec.submodule_search_locations or []) if spec is not None else []
        if len(folders) != 1 or _sources_digest(folders[0]) != __name__.rpartition("_")[2]:
            return None
        return importlib.import_module("prandtl_fmu")
    except Exception:  # a host whose prandtl_fmu cannot be found or imported: the FMU's own copy
        return None


def _import_library(here):
    """The library the FMU runs: the host's when it is the same (:func:`_host_library`), else the copy in the
    resources, imported under the private name; once per process (``sys.modules[_LIBRARY]`` holds it)."""
    if _LIBRARY in sys.modules:
        return sys.modules[_LIBRARY]
    host = _host_library()
    if host is not None:
        sys.modules[_LIBRARY] = host
        return host
    folder = _lasting_copy(os.path.join(here, "prandtl_fmu")) or os.path.join(here, "prandtl_fmu")
    spec = importlib.util.spec_from_file_location(
        _LIBRARY, os.path.join(folder, "__init__.py"), submodule_search_locations=[folder])
    package = importlib.util.module_from_spec(spec)
    sys.modules[_LIBRARY] = package
    try:
        spec.loader.exec_module(package)
    except BaseException:
        del sys.modules[_LIBRARY]
        raise
    return package


_drop_duplicate_path_entries(_HERE)
try:
    _slave_module = importlib.import_module(_import_library(_HERE).__name__ + ".fmu.python.slave")
except ImportError as _exc:  # a host whose Python lacks numpy/numba: say which Python, and what to do
    raise ImportError(
        f"prandtl_fmu FMU: {_exc} in the host's Python ({sys.version.split()[0]}, prefix {sys.prefix}): the FMU "
        "runs in the host's embedded Python, which needs numpy and numba; a host that is not itself Python needs "
        "LD_PRELOAD=<libpython3.X.so> and PYTHONPATH=<the site-packages that hold them> (README, 'Other masters')"
    ) from None
# The slave class, defined in the library: one for every kind of FMU (the scene in the resources says which kind
# this one is, at each instantiation). PythonFMU 0.7.0 finds it as the class of this module's namespace whose MRO
# is deepest in Fmi2Slave: exactly one is bound here, by a plain assignment (PythonFMU reads the names the file's
# execution defines).
PrandtlSlave = _slave_module.PrandtlSlave
