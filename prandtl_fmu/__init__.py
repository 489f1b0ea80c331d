"""prandtl_fmu: the generalized Prandtl element (dry-friction hysteresis).

    from prandtl_fmu import load_scene, simulate
    scene = load_scene("scenes/paper-section-8.toml")
    result = simulate(scene, stepper="projected")
    result.time, result.x, result.v, result.reaction

The layout follows the architecture: ``effects`` (what is simulated),
``steppers`` (how, one module per scheme), ``driver`` (how far; joins them),
``kernels`` (compiled building blocks), ``fmu`` (the FMI glue).
"""
from .driver import Element, Result, simulate
from .scene import Scene, SceneError, load_scene, parse_scene
from .steppers import STEPPERS

__all__ = ["Element", "Result", "Scene", "SceneError", "STEPPERS", "load_scene", "parse_scene", "simulate"]
__version__ = "0.1.0"
