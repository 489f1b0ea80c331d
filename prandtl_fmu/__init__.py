"""prandtl_fmu: the generalized Prandtl element (dry-friction hysteresis).

    from prandtl_fmu import load_scene, simulate
    scene = load_scene("scenes/paper-section-8.toml")
    result = simulate(scene, stepper="projected")
    result.time, result.x, result.v, result.reaction

The layout follows the architecture: ``effects`` (what is simulated),
``steppers`` (how, one module per scheme), ``driver`` (how far; joins them),
``kernels`` (compiled building blocks), ``fmu`` (the FMI glue).
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
