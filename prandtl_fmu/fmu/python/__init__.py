"""The PythonFMU runtime: an FMI 2.0 co-simulation FMU of a scene whose slave runs the library in the host's Python.

* ``slave.py``: the element's slave (variables <-> :class:`prandtl_fmu.Element`); ``connector_slave.py``: the
  element as a connector (motion in, force out);
* ``network_slave.py``, ``network_connector_slave.py``: the same two for a network scene ([network], [chain]:
  :class:`prandtl_fmu.network.NetworkElement`, :class:`~prandtl_fmu.network.NetworkConnector`);
* ``common.py``: what the slaves share (refusals, FMU states, the white noise's parameters, the registration of the
  variables of ``fmu/description.py``);
* ``entry.py``: the FMU's script: imports the bundled library, hands over the slave class;
* ``loader/``: PythonFMU 0.7.0's native loader, patched, and its sources;
* ``build.py``: :func:`build_python_fmu`, what ``fmu/build.py``'s ``build_fmu`` runs for this runtime.
"""
