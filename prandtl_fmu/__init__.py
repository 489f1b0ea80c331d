"""prandtl_fmu: the generalized Prandtl element (dry-friction hysteresis).

    from prandtl_fmu import load_scene, simulate
    scene = load_scene("scenes/paper-section-8.toml")
    result = simulate(scene, stepper="projected")
    result.time, result.x, result.v, result.reaction

The layout follows the architecture: a scene (``scene.py``; its effects in ``effects.py``, what is simulated)
is compiled once into flat arrays (``compiled.py``), a stepper (``steppers/``, one module per scheme: how)
advances it with compiled building blocks (``kernels/``), and two drivers run it (how far): the batch driver
``driver.py`` (``simulate``) and the stateful ``element.py`` (``Element``, what every FMU runs), which share
``stepping.py``. ``fmu/`` is the FMI glue of the two runtimes (``fmu/python/``, ``fmu/native/``);
``bench/``, ``sweep/`` and ``cli.py`` are tools on top.

The layers, bottom to top. A module imports from its own layer and those below, never from one above, and no
import circle exists (``tests/docs/test_layout.py`` checks both from the sources, with a short list of known
exceptions and their reasons):

1. base: ``__init__``, ``network`` (its lazy __init__), ``_jit``, ``catalog``, ``compiling``, ``libm``, ``noise``, ``outputs``,
   ``resources``, ``saved_state``
2. loads and effects with memory, compiled: ``loads``, ``memory``, ``memory.dahl``, ``memory.delay``,
   ``memory.history``
3. kernels: ``kernels``, ``network.kernels``, ``network.chain``
4. steppers: ``steppers``
5. scenes: ``schema``, ``effects``, ``masing``, ``scene_tables``, ``scene``, ``stability``, ``network.model``
6. a run's parts: ``compiled``, ``stepping``
7. the stepped objects and the network's driver: ``element``, ``connector``, ``network.driver``
8. the batch driver and the summaries of runs: ``driver``, ``summary``
9. the FMUs of both runtimes: ``fmu``
10. tools: ``sweep``, ``identify``, ``plots``, ``bench``, ``frequency``
11. the command line: ``cli``, ``__main__``

A folder groups a subject; the layers order its modules. ``network/`` is the one subject whose modules sit on
several layers, and must: its kernels (3) are the building blocks of its stepper, its scene model (5) is part of
what ``scene.py`` reads and ``compiled.py`` compiles, and its driver (7) runs them, as ``kernels/``, ``scene.py``
and ``element.py`` do for one mass. Each module's layer is listed above and checked; the folder as a whole
straddles them.

This ``__init__`` imports nothing at load: its public names resolve on first use.
"""
import importlib

__all__ = ["Element", "Result", "Scene", "SceneError", "STEPPERS", "load_scene", "parse_scene", "simulate"]
__version__ = "0.1.0"

# The names above are imported when first used (PEP 562): ``import prandtl_fmu.scene`` (or the command
# line's ``scenes``, ``--version``) does not define every kernel.
_HOMES = {"Element": "element", "Result": "driver", "simulate": "driver", "STEPPERS": "steppers",
          "Scene": "scene", "SceneError": "scene", "load_scene": "scene", "parse_scene": "scene"}


def __getattr__(name):
    if name in _HOMES:
        value = getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
