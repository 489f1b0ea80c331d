"""Networks of nodes joined by the element's parts: springs, dashpots, Saint-Venant sliders, Prandtl branches
and cubic springs, with masses (or massless nodes); the chain sliding on a fixed support (Bastien & Lamarque,
Math. Probl. Eng. 2009) is the shorthand ``[chain]``.

* ``model.py``: the network, its scene (``[network]``, ``[chain]``) and its rules;
* ``kernels.py``: the compiled steps, ``implicit`` (exact active-set method, every network) and ``projected``
  (the paper's scheme, where all plasticity is in branches and every node has a mass);
* ``driver.py``: whole runs and the stepped objects the FMUs drive.

A one-node network with its elements to the ground is the generalized Prandtl element.
"""
from .driver import NetworkConnector, NetworkElement, NetworkResult, columns_of, simulate, simulate_chunks
from .model import Network, NetworkScene

__all__ = ["Network", "NetworkScene", "NetworkElement", "NetworkConnector", "NetworkResult", "simulate",
           "simulate_chunks", "columns_of"]
