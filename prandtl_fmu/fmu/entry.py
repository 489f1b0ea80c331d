"""PythonFMU entry point of a prandtl_fmu FMU.

``build_fmu.py`` copies this file into the FMU as
``resources/prandtl_slave_<digest>.py``, a module name nothing else uses. It
imports the library bundled beside it (``resources/prandtl_fmu``) under a
private package name, so that the FMU runs the code it was built and tested
with whatever ``prandtl_fmu`` the host may have imported, and hands PythonFMU
the slave class defined there. The library is imported once per process;
its compiled kernels come from the user's numba cache folder, never from the
extracted resources (see ``_jit.py``).

Two defects of PythonFMU 0.7.0's loader are neutralised here. At every
instantiation it executes this file again (globals: this module's dict) and
then releases one reference to the module's dict that it never took; and it
inserts the resources folder into ``sys.path`` once more. Each execution
therefore keeps one more reference to the dict, and drops the duplicate
``sys.path`` entries, so that a thousand instantiations neither crash the
host nor slow its imports down.
"""
import importlib
import importlib.util
import os
import sys

globals().setdefault("_DICT_REFERENCES", []).append(globals())

_HERE = os.path.dirname(os.path.abspath(__file__))
_LIBRARY = "_" + __name__ + "_lib"


def _drop_duplicate_path_entries():
    seen = False
    for entry in list(sys.path):
        if os.path.abspath(entry or ".") == _HERE:
            if seen:
                sys.path.remove(entry)
            seen = True


def _import_library():
    if _LIBRARY in sys.modules:
        return sys.modules[_LIBRARY]
    folder = os.path.join(_HERE, "prandtl_fmu")
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


_drop_duplicate_path_entries()
_import_library()
# The slave class, defined in the library. PythonFMU 0.7.0 finds it as the
# class of this module's namespace whose MRO is deepest in Fmi2Slave.
PrandtlElement = importlib.import_module(_LIBRARY + ".fmu.slave").PrandtlElement
