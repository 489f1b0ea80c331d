"""Networks of nodes joined by the element's parts: springs, dashpots, Saint-Venant sliders, Prandtl branches
and cubic springs, with masses (or massless nodes); the chain sliding on a fixed support (Bastien & Lamarque,
Math. Probl. Eng. 2009) is the shorthand ``[chain]``.

* ``model.py``: the network, its scene (``[network]``, ``[chain]``) and its rules;
* ``kernels.py``: the compiled steps, ``implicit`` (exact active-set method, every network) and ``projected``
  (the paper's scheme, where all plasticity is in branches and every node has a mass);
* ``driver.py``: whole runs and the stepped objects the FMUs drive.

A one-node network with its elements to the ground is the generalized Prandtl element.

This ``__init__`` imports nothing at load (its names resolve on first use, PEP 562): the scene reader imports
``network.model`` without the drivers, which sit above it.
"""
import importlib

__all__ = ["Network", "NetworkScene", "NetworkElement", "NetworkConnector", "NetworkResult", "simulate",
           "simulate_chunks", "columns_of"]
_HOMES = {"Network": "model", "NetworkScene": "model", "NetworkElement": "driver", "NetworkConnector": "driver",
          "NetworkResult": "driver", "simulate": "driver", "simulate_chunks": "driver", "columns_of": "driver"}


def __getattr__(name):
    if name in _HOMES:
        value = getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
