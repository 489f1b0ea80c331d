"""The PythonFMU runtime: an FMI 2.0 co-simulation FMU of a scene whose slave runs the library in the host's Python.

* ``slave.py``: the one slave class, :class:`~prandtl_fmu.fmu.python.slave.PrandtlSlave`, for every kind of FMU: the
  variables of ``fmu/description.py`` mapped to the library's stepped object, initialization, steps, FMU states;
* ``kinds.py``: each kind's description, what the slave calls in the library: the element under a force
  (:class:`prandtl_fmu.Element`), the element as a connector (motion in, force out), a network scene ([network],
  [chain]: :class:`prandtl_fmu.network.NetworkElement`) and a network as a connector;
* ``common.py``: the FMI plumbing (refusals, the checked getters and setters, the registration of the variables);
* ``entry.py``: the FMU's script: imports the bundled library, hands over the slave class;
* ``loader/``: PythonFMU 0.7.0's native loader, patched, and its sources;
* ``build.py``: :func:`build_python_fmu`, what ``fmu/build.py``'s ``build_fmu`` runs for this runtime.
"""
