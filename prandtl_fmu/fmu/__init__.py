"""The FMUs of a scene, in two runtimes: the FMI glue, no numerics of its own.

* ``description.py``: the FMU's variables (one list for both runtimes) and its modelDescription.xml, FMI 2.0 and 3.0;
* ``osp.py``: the OSP interface description (libcosim's ``<modelName>_OspModelDescription.xml``);
* ``archive.py``: what both builds share (the scene an FMU is built from, its file names, its zip entries);
* ``documentation.py``: the FMU's ``documentation/index.html``;
* ``build.py``: :func:`build_fmu` (also ``python build_fmu.py``, ``prandtl-fmu build``), for either runtime;
* ``python/``: the PythonFMU runtime (FMI 2.0): the slaves over the library's stepped objects, the FMU's script,
  the patched loader, its build;
* ``native/``: the native runtime (FMI 2.0 and 3.0): the library's kernels compiled into the binary, the C FMI
  layer, its build for each platform.
"""
