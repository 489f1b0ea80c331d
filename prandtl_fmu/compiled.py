"""A scene compiled for the kernels: the tuple every stepper's time loop takes.

``compile_model(scene)`` is ``(m, k0, k3, c, k, eta, cs, friction, memory)``,
``None`` where an effect is absent (a scene that leaves an effect out has no
such entry: no flags tested in the hot loop), but for the springs and the dashpot:

* ``m`` (kg), ``k0`` (N/m), ``k3`` (N/m^3), ``c`` (N s/m): the smooth part. ``k0``, ``k3`` and ``c`` are
  always numbers, 0 where the scene has no such spring or dashpot: an absent one is then a multiply-add by
  zero (exact: the same numbers, bit for bit) and no loop of its own. Each None doubles the loops numba
  compiles for the combinations of effects a process meets (the quick suite compiled 215 loops, 472 s,
  before; 107, 276 s, after: docs/benchmarks.md). ``m`` stays None for the massless element
  (another equation, not a zero mass). The native FMU's kernels build the same tuple, so they share the
  library's compiled loops;
* ``k``, ``eta``, ``cs``: the branches, as the O(n) play kernel's arrays
  (stiffness, yield displacement, series dashpots: shape (n,)) or as the
  memory stack's parameters (``kernels/stack.py``; :func:`choose_branch_kernel`);
* ``friction``: ``[friction]`` on the mass (:func:`friction_model`);
* ``memory``: the effects with memory and their state (``memory/``).

Also here: the stepper's compiled loop for a scene (:func:`compile_loop`), and the branches' state as plain
data and back (:func:`branch_state`, :func:`restore_branch_state`), which the Element and the Connector save.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .kernels import stack
from .memory import compile_memory
from .saved_state import number_list
from .scene import Scene
from .steppers import get_stepper


# The memory stack (kernels/stack.py) replaces the O(n) play kernel from this
# many branches on: inside `projected` the two cost the same near n = 40
# (benchmarks/branch_scaling.py: 55 against 80 ns per step at n = 10, 129
# against 80 at n = 100).
STACK_FROM = 64


def compile_model(scene: Scene, branch_kernel: str = "play"):
    """The kernel form of a scene's effects: ``(m, k0, k3, c, k, eta, cs, friction, memory)``, ``None`` where
    absent.

    With ``branch_kernel="stack"``, ``k`` holds the memory stack's parameters
    and ``eta`` is None (see :func:`choose_branch_kernel`); the continuum
    always takes the stack (its parameters are a tuple). ``cs``: the series
    dashpots of the branches (an array, O(n) kernel only); ``friction``:
    :func:`friction_model`; ``memory``: the effects with memory and their state (``memory/__init__.py``).
    """
    return _smooth_model(scene) + _branch_model(scene, branch_kernel) + (friction_model(scene), _memory_model(scene))


def _memory_model(scene: Scene):
    """The kernel form of the effects with memory (``memory/``), fresh at t = 0; memory.NONE without any."""
    x0 = scene.mass.x0 if scene.mass is not None else 0.0
    v0 = scene.mass.v0 if scene.mass is not None else 0.0
    return compile_memory(scene, x0, v0)


def _branch_model(scene: Scene, branch_kernel: str) -> tuple:
    """``(k, eta, cs)``: the branch part of :func:`compile_model`."""
    branches = scene.branches
    if branches is None:
        return (None, None, None)
    if branches.continuum:
        return (branches.params, None, None)
    k = _read_only(branches.stiffness)
    eta = _read_only(branches.yield_displacement)
    if branches.damping is not None:
        if branch_kernel == "stack":
            raise ValueError("series dashpots run on the O(n) kernel only: a relaxing branch has no memory stack")
        return (k, eta, _read_only(branches.damping))
    if branch_kernel == "stack":
        params, _ = stack.prepare(k, eta, branches.u0)
        return (params, None, None)
    return (k, eta, None)


def _read_only(values) -> np.ndarray:
    """``values`` as a contiguous read-only float array: the branches' coefficients, never written by a kernel.
    One layout for all (a scene's arrays are read-only, one built otherwise may not be): numba compiles a loop
    for each."""
    array = np.ascontiguousarray(values, dtype=float)
    if array.flags.writeable:
        array = array.copy()
        array.setflags(write=False)
    return array


def friction_model(scene: Scene):
    """The kernel form of ``[friction]``: ``(alpha, alpha_kinetic, stribeck_velocity, belt_velocity)``, or None
    (``kernels/friction.py``)."""
    friction = scene.friction
    if friction is None:
        return None
    stribeck = friction.stribeck_velocity if friction.stribeck_velocity is not None else 1.0
    return (float(friction.alpha), float(friction.alpha_kinetic), float(stribeck), float(friction.belt_velocity))


def with_scene_coefficients(scene: Scene, model: tuple) -> tuple:
    """``model`` with the coefficients of ``scene`` (after a change of coefficients): its smooth part, its series
    dashpots and its friction; the branch kernel's parameters and state stay."""
    cs = model[6]
    if cs is not None:
        cs = _read_only(scene.branches.damping)
    return _smooth_model(scene) + model[4:6] + (cs, friction_model(scene), model[8])


def _smooth_model(scene: Scene):
    """``(m, k0, k3, c)``: the part of :func:`compile_model` that does not depend on the branches."""
    m = float(scene.mass.m) if scene.mass is not None else None
    k0 = float(scene.spring.k0) if scene.spring is not None else 0.0  # (0: no loop of its own, see above)
    k3 = float(scene.cubic.k3) if scene.cubic is not None else 0.0
    c = float(scene.damper.c) if scene.has_dashpot else 0.0  # c = 0: no dashpot at all
    return (m, k0, k3, c)


def choose_branch_kernel(scene: Scene, stepper: str) -> str:
    """"stack" for the continuum, and for many branches with an admissible initial state and a stepper
    that takes it; "play" (one update per branch) otherwise."""
    branches = scene.branches
    if branches is None:
        return "play"
    if branches.continuum:
        return "stack"
    if branches.damping is not None:  # series dashpots: the O(n) kernel only (kernels/series.py)
        return "play"
    if branches.n < STACK_FROM or not getattr(get_stepper(stepper), "BRANCH_STACK", False):
        return "play"
    order = np.argsort(branches.yield_displacement, kind="stable")
    if not stack.admissible(branches.yield_displacement[order], branches.u0[order]):
        return "play"
    return "stack"


def compile_loop(scene: Scene, stepper: str):
    """The compiled time loop of ``stepper`` for ``scene``; ValueError if the scheme does not apply."""
    return get_stepper(stepper).loop_for(scene)


def with_noise(scene, noise):
    """The scene (an element's or a network's) with the white noise ``noise`` (``loads.WhiteNoise`` or None) on
    its load: what a stepper's rules are checked against when an FMU sets a noise of its own."""
    if noise is scene.load.noise:
        return scene
    return dataclasses.replace(scene, load=dataclasses.replace(scene.load, noise=noise))


def _is_network(scene) -> bool:
    return type(scene).__name__ == "NetworkScene"


def branch_state(scene: Scene, k, kind: str, u):
    """The branches' state as plain data: ``(u, u_reference)`` lists.

    ``u`` is the list of elongations with the O(n) kernel, the part in use of
    the memory stack's state otherwise (then ``u_reference`` holds the
    elongations its initial piece refers to, for n branches).
    """
    if kind == "stack":
        reference = []
        if not scene.branches.continuum:
            values = np.empty(scene.branches.n)
            values[k[stack.ORDER_ROW, :-1].astype(np.int64)] = k[stack.C_ROW, :-1]
            reference = values.tolist()
        return u[:stack.used(u)].tolist(), reference
    return ([] if u is None else u.tolist()), []


def restore_branch_state(scene: Scene, k, kind: str, u, reference):
    """(branch part of the model, branch state) of saved :func:`branch_state` data for ``scene`` whose
    current branch parameters are ``k``; ValueError if it does not fit."""
    u = number_list(u, "u")
    reference = number_list(reference, "u_reference")
    branches = scene.branches
    if branches is None:
        if u.size:
            raise ValueError(f"state has {u.shape[0]} branch values, the element has no branches")
        return (None, None, None), None
    if kind == "stack":
        if branches.continuum:
            params = k
        else:
            if reference.shape[0] != branches.n:
                raise ValueError(f"state has {reference.shape[0]} reference elongations, the element has "
                                 f"{branches.n} branches")
            params, _ = stack.prepare(branches.stiffness, branches.yield_displacement, reference)
        return (params, None, None), stack.restore(params, u)
    if kind != "play" or branches.continuum:
        raise ValueError(f"state has branch kernel {kind!r}, which does not fit the element")
    if u.shape[0] != branches.n:
        raise ValueError(f"state has {u.shape[0]} branch elongations, the element has {branches.n}")
    if np.any(np.abs(u) > branches.yield_displacement):
        raise ValueError("state has an elongation outside its elastic range")
    return compile_model(scene, "play")[4:7], u
