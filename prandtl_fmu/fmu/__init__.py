"""The FMI glue: an FMI 2.0 co-simulation FMU of a scene, built with PythonFMU.

* ``slave.py``: the slave class (variables <-> :class:`prandtl_fmu.Element`); ``connector_slave.py``: the
  element as a connector (motion in, force out);
* ``network_slave.py``, ``network_connector_slave.py``: the same two for a network scene ([network],
  [chain]: :class:`prandtl_fmu.network.NetworkElement`, :class:`~prandtl_fmu.network.NetworkConnector`);
* ``entry.py``: the FMU's script: imports the bundled library, hands over the slave class;
* ``description.py``: the FMU's variables and its modelDescription.xml (FMI 2.0 and 3.0), for both runtimes: the
  slaves register their variables from it, the native build (``prandtl_fmu/native``) writes its description from it;
* ``archive.py``: what the builds of both runtimes share (the scene an FMU is built from, its files);
* ``build.py``: :func:`build_fmu` (also ``python build_fmu.py``);
* ``documentation.py``: the FMU's ``documentation/index.html``.
"""
