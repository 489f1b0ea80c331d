"""Scenes: TOML files that name the effects of an element and their coefficients.

The format is the contract written down in ``docs/scene-format.md``. A scene is data: it is parsed with :mod:`tomllib` and checked key by
key; nothing in it is ever evaluated. Every broken rule raises
:class:`SceneError` with one line naming the file, the key and the rule.

Additions to the contract (all optional):

* ``[load]`` may be omitted: no external force, F(t) = 0;
* ``[solver] stepper`` defaults to ``"projected"``;
* a scene without ``[mass]`` is the massless element: x(0) = 0, and without
  a dashpot the quasi-static element (see :func:`driver.initial_state`).
"""
from __future__ import annotations

import math
import os
import pathlib
from dataclasses import dataclass, replace
from typing import Any, Optional, Union

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from . import schema
from .catalog import SCENES, closest_scenes, packaged_scenes, scene_path, unknown_scene  # noqa: F401 (re-exported)
from .effects import (Branches, ContinuousBranches, CubicSpring, Damper, Friction, Mass, Spring,
                      sample_spectrum)
from .loads import ConstantLoad
from .resources import ResourceError, check_memory
from .scene_tables import (Load, SceneError, Solver, VALUES, _Reader, _check_noise_unit, _check_solver, _kind, _load,
                           _solver, magnitude_problem)
# the scene's bounds, read as scene.<name> by the FMU builds (their C rules) and the tests
from .scene_tables import LARGEST_MAGNITUDE, MAX_STEPS, SHORTEST_STEP, SMALLEST_MAGNITUDE  # noqa: F401

# Memory per branch at the peak of a run: the scene's arrays, the kernel's sorted copies, the memory stack's ten
# rows and their temporaries, an Element's saved state. Measured 197 bytes (n = 10^6, projected; the issue's
# measure of the old figure, 96, was 145): tests/cli/test_hostile_inputs.py checks the peak against this.
BYTES_PER_BRANCH = 256
# The most internal steps one advance of an element (an FMU's doStep) takes: a communication step that needs
# more is refused (fmi2Discard, ElementError) with the count, never run for hours. About 10 s of the paper's
# 100-branch scene on the stack (~100 ns a step); a master splits a longer interval into several doSteps.
ADVANCE_BUDGET = 100_000_000







@dataclass(frozen=True, eq=False)
class Scene:
    """An element: its effects (``None`` where absent), its load and its solver settings."""

    name: str
    mass: Optional[Mass]
    spring: Optional[Spring]
    cubic: Optional[CubicSpring]
    damper: Optional[Damper]
    branches: Optional[Branches]
    load: Load
    solver: Solver
    source: str = "<scene>"
    causality: str = "force"  # of its FMU: see CAUSALITIES
    friction: Optional[Friction] = None  # of the mass on the ground: ``[friction]``
    # the effects with memory (memory/: the registry EFFECTS names them): ``[delay]``, ``[history]``, ``[dahl]``
    delay: Optional[Any] = None
    history: Optional[Any] = None
    dahl: Optional[Any] = None

    def with_solver(self, **overrides) -> "Scene":
        """A copy with some solver settings replaced (``None`` values are ignored), checked."""
        given = {k: v for k, v in overrides.items() if v is not None}
        solver = replace(self.solver, **given)
        _check_solver(solver, self.source, where="")
        scene = replace(self, solver=solver)
        _check_stepper_applies(scene, where="")
        return scene

    @property
    def has_dashpot(self) -> bool:
        """Whether the element has a dashpot with c > 0 (a c = 0 damper is no damper: it costs nothing and a
        massless element with it is quasi-static)."""
        return self.damper is not None and self.damper.c > 0

    @property
    def effects(self) -> list[str]:
        """Names of the tables present, in contract order."""
        names = ["mass", "friction", "spring", "cubic", "damper", "branches", "delay", "history", "dahl"]
        return [name for name in names if getattr(self, name) is not None]

    @property
    def has_series_dashpots(self) -> bool:
        """Whether the branches carry dashpots in series (the series model, rate-dependent)."""
        return self.branches is not None and not self.branches.continuum and self.branches.damping is not None


# Coefficients a running element may change (an FMU's parameters): the
# table that holds each, and its rule. The same rules check the scene files.
COEFFICIENTS = {
    "m": ("mass", "> 0"),
    "x0": ("mass", "finite"),
    "v0": ("mass", "finite"),
    "k0": ("spring", ">= 0"),
    "k3": ("cubic", ">= 0"),
    "c": ("damper", ">= 0"),
    "alpha": ("friction", "> 0"),
    "alpha_kinetic": ("friction", ">= 0"),
    "stribeck_velocity": ("friction", "> 0"),
    "belt_velocity": ("friction", "finite"),
    "c_branch": ("branches", "> 0"),
    # the effects with memory (an FMU's fixed parameters: they restart the memory, so they are set before a run)
    "delay_gain": ("delay", "finite"),
    "delay_tau": ("delay", "> 0"),
    "history_weight": ("history", "finite"),
    "history_rate": ("history", ">= 0"),
    "dahl_sigma": ("dahl", "> 0"),
    "dahl_force": ("dahl", "> 0"),
    "dahl_exponent": ("dahl", "> 0"),
}
MEMORY_COEFFICIENTS = ("delay_gain", "delay_tau", "history_weight", "history_rate", "dahl_sigma", "dahl_force",
                       "dahl_exponent")
# Branch dashpots are coefficients too: ``c_branch`` (one for every branch, a scene with ``count = n``) or
# ``c_branch[i]`` (i = 1..n, a scene that lists its branches).


def _coefficient_key(name: str) -> str:
    """The COEFFICIENTS key of a coefficient name (``c_branch[3]`` -> ``c_branch``)."""
    for listed in ("c_branch", "history_weight", "history_rate"):  # one per branch / per term: name[i]
        if name.startswith(listed + "[") and name.endswith("]"):
            return listed
    return name


def coefficients_of(scene: "Scene") -> dict:
    """The coefficients of the effects present in ``scene`` (names of COEFFICIENTS)."""
    values = {}
    if scene.mass is not None:
        values.update(m=scene.mass.m, x0=scene.mass.x0, v0=scene.mass.v0)
    if scene.spring is not None:
        values["k0"] = scene.spring.k0
    if scene.cubic is not None:
        values["k3"] = scene.cubic.k3
    if scene.damper is not None:
        values["c"] = scene.damper.c
    friction = scene.friction
    if friction is not None:
        values["alpha"] = friction.alpha
        if friction.stribeck_velocity is not None:  # plain Coulomb: alpha_kinetic is alpha
            values.update(alpha_kinetic=friction.alpha_kinetic, stribeck_velocity=friction.stribeck_velocity)
        values["belt_velocity"] = friction.belt_velocity
    if scene.delay is not None:
        values.update(delay_gain=scene.delay.gain, delay_tau=scene.delay.tau)
    if scene.history is not None:
        values.update({f"history_weight[{j + 1}]": w for j, w in enumerate(scene.history.weight)})
        values.update({f"history_rate[{j + 1}]": r for j, r in enumerate(scene.history.rate)})
    if scene.dahl is not None:
        values.update(dahl_sigma=scene.dahl.sigma, dahl_force=scene.dahl.force, dahl_exponent=scene.dahl.exponent)
    if scene.has_series_dashpots:
        damping = scene.branches.damping
        if scene.branches.shared_damping:
            values["c_branch"] = float(damping[0])
        else:
            values.update({f"c_branch[{i + 1}]": float(value) for i, value in enumerate(damping)})
    return values




def coefficient_problem(name: str, value) -> Optional[str]:
    """Why ``value`` is not a valid coefficient ``name`` (see COEFFICIENTS), or None."""
    rule = COEFFICIENTS[_coefficient_key(name)][1]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"must be a number, got {value!r}"
    if not math.isfinite(value):
        return f"must be finite, got {value!r}"
    problem = magnitude_problem(value, coefficient=name not in VALUES)
    if problem:
        return problem
    if rule == "> 0" and not value > 0:
        return f"must be > 0, got {value!r}"
    if rule == ">= 0" and value < 0:
        return f"must be >= 0, got {value!r}"
    return None


def with_coefficients(scene: Scene, **values) -> Scene:
    """A copy of ``scene`` with some coefficients replaced; ValueError names the culprit.

    Only effects present in the scene can be changed: an absent effect has no coefficient.
    """
    present = coefficients_of(scene)
    for name, value in values.items():
        if _coefficient_key(name) not in COEFFICIENTS:
            raise ValueError(f"{name}: not a coefficient (known: {', '.join(COEFFICIENTS)})")
        table = COEFFICIENTS[_coefficient_key(name)][0]
        if getattr(scene, table) is None:
            raise ValueError(f"{name}: the scene has no [{table}]")
        if name not in present:
            raise ValueError(f"{name}: not a coefficient of this scene (its coefficients: {', '.join(present)})")
        problem = coefficient_problem(name, value)
        if problem:
            raise ValueError(f"{name}: {problem}")
    mass, spring, cubic, damper = scene.mass, scene.spring, scene.cubic, scene.damper
    friction, branches = scene.friction, scene.branches
    if friction is not None:
        alpha = float(values.get("alpha", friction.alpha))
        stribeck = friction.stribeck_velocity
        kinetic = alpha if stribeck is None else float(values.get("alpha_kinetic", friction.alpha_kinetic))
        if stribeck is not None:
            stribeck = float(values.get("stribeck_velocity", stribeck))
        if kinetic > alpha:
            culprit = "alpha_kinetic" if "alpha_kinetic" in values else "alpha"
            raise ValueError(f"{culprit}: alpha_kinetic must be <= alpha, got alpha_kinetic = {kinetic!r} and "
                             f"alpha = {alpha!r}")
        friction = Friction(alpha, kinetic, stribeck, float(values.get("belt_velocity", friction.belt_velocity)))
    if scene.has_series_dashpots and any(_coefficient_key(name) == "c_branch" for name in values):
        damping = branches.damping.copy()
        if branches.shared_damping:
            damping[:] = float(values.get("c_branch", damping[0]))
        else:
            for i in range(damping.shape[0]):
                damping[i] = float(values.get(f"c_branch[{i + 1}]", damping[i]))
        damping.setflags(write=False)
        branches = replace(branches, damping=damping)
    if mass is not None:
        mass = Mass(float(values.get("m", mass.m)), float(values.get("x0", mass.x0)), float(values.get("v0", mass.v0)))
    if spring is not None:
        spring = Spring(float(values.get("k0", spring.k0)))
    if cubic is not None:
        cubic = CubicSpring(float(values.get("k3", cubic.k3)))
    if damper is not None:
        damper = Damper(float(values.get("c", damper.c)))
    memory = {}
    if scene.delay is not None:
        memory["delay"] = replace(scene.delay, gain=float(values.get("delay_gain", scene.delay.gain)),
                                  tau=float(values.get("delay_tau", scene.delay.tau)))
    if scene.history is not None:
        history = scene.history
        memory["history"] = replace(
            history, weight=tuple(float(values.get(f"history_weight[{j + 1}]", w)) for j, w in enumerate(history.weight)),
            rate=tuple(float(values.get(f"history_rate[{j + 1}]", r)) for j, r in enumerate(history.rate)))
    if scene.dahl is not None:
        memory["dahl"] = replace(scene.dahl, sigma=float(values.get("dahl_sigma", scene.dahl.sigma)),
                                 force=float(values.get("dahl_force", scene.dahl.force)),
                                 exponent=float(values.get("dahl_exponent", scene.dahl.exponent)))
    changed = replace(scene, mass=mass, spring=spring, cubic=cubic, damper=damper, friction=friction,
                      branches=branches, **memory)
    if memory:
        try:
            _check_memory_rules(changed)
        except SceneError as exc:  # the culprit is the coefficient set, not the scene file
            culprit = next((name for name in values if _coefficient_key(name) in MEMORY_COEFFICIENTS),
                           next(iter(values), "memory"))
            raise ValueError(f"{culprit}: {str(exc).split(': ', 2)[-1]}") from None
    return changed


# ---------------------------------------------------------------- parsing

_TOP_KEYS = schema.top_level("element")
# (a scene with [network] or [chain] is a network: network/model.py reads it)
CAUSALITIES = schema.CAUSALITIES  # how the FMU of a scene is driven: ``[fmu] causality``






# The example scenes shipped in the package (``scenes/`` of the repository links here): ``catalog.py``
PACKAGED_SCENES = pathlib.Path(SCENES)


def load_scene(path: Union[str, os.PathLike], check_stepper: bool = True) -> Scene:
    """Read and check a scene file, or a packaged scene named without a path (:func:`scene_path`); raise
    :class:`SceneError` on any broken rule.

    ``check_stepper=False`` leaves out the check that the scene's stepper
    applies, for a caller that replaces the stepper (``with_solver`` checks it).
    """
    doc, source = read_document(path)
    return scene_from_document(doc, source, check_stepper)


def parse_scene(text: Union[str, bytes], source: str = "<scene>", check_stepper: bool = True) -> Scene:
    """Parse scene TOML text; ``source`` names it in error messages."""
    return scene_from_document(toml_document(text, source), source, check_stepper)


def toml_document(text: Union[str, bytes], source: str, error=SceneError) -> dict:
    """TOML text (or UTF-8 bytes) as a dict; ``error`` (one line naming ``source``) if it is not."""
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError:
            raise error(f"{source}: not a UTF-8 text file") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:
        raise error(f"{source}: not valid TOML: nested too deeply") from None


def read_toml(path: Union[str, os.PathLike], what: str, error=SceneError) -> dict:
    """The TOML file ``path`` (``what`` it is, for the message) as a dict; ``error`` (one line) if it cannot be
    read or parsed."""
    try:
        with open(path, "rb") as fh:
            text = fh.read()
    except OSError as exc:
        raise error(f"{os.fspath(path)}: cannot read {what}: {exc.strerror}") from None
    return toml_document(text, os.fspath(path), error)


def read_document(path: Union[str, os.PathLike]) -> tuple:
    """``(document, source)``: a scene file (or packaged scene) parsed as TOML but not yet checked, for a caller
    that changes some keys before :func:`scene_from_document` (a sweep). SceneError on an unreadable file."""
    source = scene_path(path)
    if not os.path.exists(source) and (os.sep not in source and "/" not in source or closest_scenes(source)):
        raise unknown_scene(source)  # a name, or a path that looks like a misspelt packaged name
    return read_toml(source, "the scene"), source


def scene_from_document(doc: dict, source: str = "<scene>", check_stepper: bool = True) -> Scene:
    """The scene of a parsed TOML document (a dict), checked key by key like a file."""
    with np.errstate(all="ignore"):
        return _scene_from_document(doc, source, check_stepper)


def _scene_from_document(doc, source, check_stepper) -> Scene:
    if isinstance(doc, dict) and ("network" in doc or "chain" in doc):
        from .network.model import network_scene

        return network_scene(doc, source, check_stepper)
    for key in doc:
        if key not in _TOP_KEYS:
            raise SceneError(f"{source}: {key}: unknown key (allowed at top level: {', '.join(sorted(_TOP_KEYS))})")
    name = doc.get("name", os.path.splitext(os.path.basename(source))[0])
    if not isinstance(name, str):
        raise SceneError(f"{source}: name: must be a string, got {_kind(name)}")

    mass = _mass(source, doc["mass"]) if "mass" in doc else None
    spring = cubic = damper = branches = None
    if "spring" in doc:
        r = _Reader(source, "spring", doc["spring"])
        r.only()
        spring = Spring(r.number("k0"))
    if "cubic" in doc:
        r = _Reader(source, "cubic", doc["cubic"])
        r.only()
        cubic = CubicSpring(r.number("k3"))
    if "damper" in doc:
        r = _Reader(source, "damper", doc["damper"])
        r.only()
        damper = Damper(r.number("c"))
    if "branches" in doc:
        branches = _branches(source, doc["branches"])
    if "masing" in doc:  # a backbone curve: its parallel spring and its Iwan spectrum of branches
        spring, branches = _masing(source, doc)
    friction = _friction(source, doc["friction"], mass) if "friction" in doc else None
    load = _load(source, doc["load"]) if "load" in doc else ConstantLoad(0.0)
    if "solver" not in doc:
        raise SceneError(f"{source}: [solver]: missing (required: step, stop_time, output_interval)")
    solver = _solver(source, doc["solver"])
    causality = "force"
    if "fmu" in doc:
        r = _Reader(source, "fmu", doc["fmu"])
        r.only()
        causality = r.string("causality")
        if causality == "displacement" and mass is not None:
            r.fail("causality", '"displacement" is the connector, the massless element between two bodies: '
                   "remove [mass] (the bodies hold the inertia) or use \"force\"")
    memory = _memory(source, doc)
    scene = Scene(name, mass, spring, cubic, damper, branches, load, solver, source, causality, friction, **memory)
    if memory:
        _check_memory_rules(scene)
    _check_noise_unit(scene)
    if check_stepper and causality == "force":  # the connector takes no time steps: no stepper to check
        _check_stepper_applies(scene, where="[solver] ")
    return scene


def _memory(source, doc) -> dict:
    """The effects with memory of the document (``memory.EFFECTS``: one reader per table)."""
    from .memory import EFFECTS

    return {name: module.read(_Reader(source, name, doc[name]), set(doc)) for name, module in EFFECTS.items()
            if name in doc}


def _check_memory_rules(scene) -> None:
    """What the effects with memory need of the rest of the scene: a buffer (tau / step values) that fits in
    memory, refused with the number before the run; and a step whose equation stays monotone (``implicit``
    takes the delay inside the step when tau < step, and the quasi-static massless element has nothing but its
    springs against a negative memory force)."""
    quasi_static = scene.mass is None and not scene.has_dashpot and scene.causality == "force"  # (the connector
    # solves nothing: its motion is given)
    if scene.delay is not None and scene.delay.gain < 0 and scene.causality == "force" \
            and (quasi_static or scene.delay.tau < scene.solver.step):
        if quasi_static:
            why, fix = "on a massless element without a dashpot", "add [mass] or a [damper]"
        else:  # (a mass or a dashpot does not make that step's equation monotone: the step does)
            why = f"with tau = {scene.delay.tau!r} s below the step {scene.solver.step!r} s"
            fix = "a [solver] step no longer than tau, or a longer tau"
        raise SceneError(f"{scene.source}: [delay] gain: a negative gain {why} makes the implicit equation of a "
                         f"step non-monotone (no unique solution): {fix}")
    from .memory.dahl import MAX_EXPONENT

    if scene.dahl is not None and scene.dahl.exponent > MAX_EXPONENT:
        raise SceneError(f"{scene.source}: [dahl] exponent: must be <= {MAX_EXPONENT:g} (sigma 2^exponent, the "
                         f"slope at a reversal, would overflow), got {scene.dahl.exponent!r}")
    if scene.history is not None and quasi_static and min(scene.history.weight) < 0:
        raise SceneError(f"{scene.source}: [history] weight: a negative weight on a massless element without a "
                         "dashpot makes the implicit equation of a step non-monotone: add [mass] or a [damper]")
    if scene.delay is not None:
        from .memory import delay

        count = delay.size(scene.delay, scene.solver.step)
        if count > 2**31:
            raise SceneError(f"{scene.source}: [delay] tau: tau / step = {scene.delay.tau / scene.solver.step:.4g} "
                             f"values in the delay's buffer, more than 2^31: a longer [solver] step or a shorter "
                             "tau")
        check_memory(8.0 * count, f"{scene.source}: [delay] tau = {scene.delay.tau!r} s (a buffer of {count} values "
                                  f"at step {scene.solver.step!r} s)")


def _mass(source, data) -> Mass:
    r = _Reader(source, "mass", data)
    r.only()
    return Mass(m=r.number("m"), x0=r.number("x0"), v0=r.number("v0"))


def _friction(source, data, mass) -> Friction:
    r = _Reader(source, "friction", data)
    r.only()
    if mass is None:
        r.fail(None, "friction of the mass on the ground needs [mass] (a massless element has no mass to hold)")
    alpha = r.number("alpha")
    kinetic = r.number("alpha_kinetic")  # default: alpha
    if kinetic > alpha:
        r.fail("alpha_kinetic", f"must be <= alpha = {alpha!r} (the sliding force falls from alpha at rest to "
               f"alpha_kinetic at speed), got {kinetic!r}")
    stribeck = None
    if "stribeck_velocity" in r.data:
        stribeck = r.number("stribeck_velocity")
    elif kinetic < alpha:
        r.fail("stribeck_velocity", "missing (required when alpha_kinetic < alpha: the speed over which the "
               "sliding force falls)")
    return Friction(alpha, kinetic, stribeck, r.number("belt_velocity"))


def _series_damping(r, n: int, shared: bool):
    """The branch dashpots ``c`` (None if absent): a list of n values, or one value for every branch."""
    if "c" not in r.data:
        return None
    if shared and not isinstance(r.data["c"], list):
        return np.full(n, r.number("c"))
    if shared:
        r.fail("c", "give one value for every branch with count = n, got a list")
    return r.numbers("c", length=n)


def _branches(source, data):
    r = _Reader(source, "branches", data)
    if "continuum" in r.data:
        if r.boolean("continuum"):
            if "c" in r.data:
                r.fail("c", "series dashpots are not available with continuum = true (sample it with count = n)")
            if "density" in r.data:
                r.only("density continuum")
                return _density(r)
            r.only("continuum")
            return _continuum(r)
        r = _Reader(source, "branches", {key: v for key, v in data.items() if key != "continuum"})
    if "density" in r.data:
        r.only("density count")
        if "count" not in r.data:
            r.fail("density", "give count = n for n sampled branches, or continuum = true for the continuum")
        n = _branch_count(r)
        rule = r.string("sampling")
        sampled_branches = _density(r).sample(n, rule)
        damping = _series_damping(r, sampled_branches.n, shared=True)
        if damping is None:
            return sampled_branches
        return replace(sampled_branches, damping=damping, shared_damping=True)
    if "count" in r.data or "k_total" in r.data or "eta_range" in r.data:
        r.only("count")
        n = _branch_count(r)
        k_total, ends = _spectrum(r)
        rule = r.string("sampling")
        branches = sample_spectrum(n, k_total, ends, rule)  # right end points s_i = i / n: eq. (7.19)
        stiffness, eta = branches.stiffness, branches.yield_displacement
    else:
        r.only("lists")
        stiffness = r.numbers("k")
        n = len(stiffness)
        if "eta" in r.data and "alpha" in r.data:
            r.fail("alpha", "give either eta or alpha, not both")
        if "eta" in r.data:
            eta = r.numbers("eta", length=n)
        elif "alpha" in r.data:
            eta = r.numbers("alpha", length=n) / stiffness
            if not np.all(np.isfinite(eta)):
                r.fail("alpha", "alpha / k overflows")
        else:
            r.fail("eta", "missing (give eta or alpha)")
    u0 = r.numbers("u0", length=n)
    bad = np.flatnonzero(np.abs(u0) > eta)
    if bad.size:
        i = int(bad[0])
        r.fail(f"u0[{i + 1}]", f"|u0| must be <= eta = {float(eta[i])!r}, got {float(u0[i])!r}")
    shared = "count" in r.data
    damping = _series_damping(r, n, shared)
    for array in (stiffness, eta, u0) + ((damping,) if damping is not None else ()):
        array.setflags(write=False)
    return Branches(stiffness, eta, u0, damping, shared)


def _branch_count(r) -> int:
    n = r.integer("count")
    try:
        check_memory(n * BYTES_PER_BRANCH, f"{r.source}: [branches] count = {n}",
                     hint="use [branches] continuum = true for the limit of many branches")
    except ResourceError as exc:
        raise SceneError(str(exc)) from None
    return n


def _density(branches_reader) -> ContinuousBranches:
    """The spectrum of ``[branches] density = { kind = ... }``: Segalman's Iwan model or piecewise."""
    r = _Reader(branches_reader.source, "branches.density", branches_reader.data["density"])
    kind = r.string("kind")
    if kind == "iwan":
        r.only("iwan")
        F_S, K_T = r.number("F_S"), r.number("K_T")
        chi, beta = r.number("chi"), r.number("beta")
        if not chi > -1.0:
            r.fail("chi", f"must be > -1 (the density phi^chi must be integrable at 0), got {chi!r}")
        try:
            spectrum = ContinuousBranches.iwan(F_S, K_T, chi, beta)
        except (ValueError, ZeroDivisionError, OverflowError) as exc:
            r.fail("F_S", f"with K_T, chi, beta gives no finite spectrum ({exc})")
        if not (0 < spectrum.strength < math.inf and 0 < spectrum.stiffness_sum < math.inf):
            r.fail("F_S", "with K_T, chi, beta gives no finite spectrum (phi_max or the density overflows or "
                   "underflows)")
        return spectrum
    r.only("piecewise")
    k = r.numbers("k")
    if not np.any(k > 0):
        r.fail("k", "at least one segment needs a stiffness density > 0")
    eta = r.numbers("eta", length=len(k) + 1)
    drops = np.flatnonzero(np.diff(eta) < 0)
    if drops.size:
        r.fail(f"eta[{int(drops[0]) + 2}]", "eta(s) must be non-decreasing")
    if "s" in r.data:
        ends = r.numbers("s", length=len(k) + 1)
        if ends[0] != 0.0 or ends[-1] != 1.0:
            r.fail("s", f"the segment ends must run from 0 to 1, got {ends[0]!r} to {ends[-1]!r}")
        flat = np.flatnonzero(np.diff(ends) <= 0)
        if flat.size:
            r.fail(f"s[{int(flat[0]) + 2}]", "the segment ends must rise strictly")
    else:
        ends = np.linspace(0.0, 1.0, len(k) + 1)
    try:
        spectrum = ContinuousBranches.piecewise(ends, k, eta)
    except ValueError as exc:
        r.fail("k", str(exc))
    if not spectrum.strength < math.inf:  # 0 is allowed: branches of zero elastic range, as in the lists
        r.fail("k", "the spectrum's strength integral k eta ds overflows")
    return spectrum


def _spectrum(r):
    """k_total and eta_range = [a, b] of a spectrum."""
    k_total = r.number("k_total")
    ends = r.numbers("eta_range")
    if len(ends) != 2:
        r.fail("eta_range", f"must be [a, b] (two numbers), got {len(ends)} values")
    return k_total, ends


def _continuum(r) -> ContinuousBranches:
    k_total, (a, b) = _spectrum(r)
    if not a < b:
        r.fail("eta_range", f"the continuum needs a < b (eta(s) = a + (b - a) s increasing), got [{a!r}, {b!r}]")
    return ContinuousBranches.linear(k_total, float(a), float(b))


def _masing(source, doc) -> tuple:
    """``(spring, branches)`` of ``[masing]``: a Masing model given by its backbone curve, turned into the
    parallel spring k0 = F_b'(inf) and the branches of its Iwan spectrum (masing.py, docs/masing.md)."""
    from . import masing

    r = _Reader(source, "masing", doc["masing"])
    for other in ("branches", "spring"):
        if other in doc:
            r.fail(None, f"gives the branches and their parallel spring by a backbone curve: remove [{other}] "
                   "(a scene gives its branches one way)")
    kind = r.string("kind")
    smooth = {"count", "x_max", "spacing"}
    if kind == "bilinear":
        for key in sorted(smooth & set(r.data)):
            r.fail(key, "the bilinear backbone is one branch and a spring exactly: no count, x_max or spacing")
    r.only(kind)
    k = r.number("k")
    if kind == "bilinear":
        alpha = r.number("alpha")
        if not alpha < 1.0:
            r.fail("alpha", f"must be < 1 (the post-yield stiffness alpha k below the initial k), got {alpha!r}")
        k0, branches = masing.iwan_branches(masing.Bilinear(k, r.number("f_y"), alpha))
    else:
        if kind == "hyperbolic":
            backbone = masing.Hyperbolic(k, r.number("f_u"))
        else:
            f_y, a, exponent = r.number("f_y"), r.number("a"), r.number("r")
            if not exponent > 1.0:
                r.fail("r", f"must be > 1 (the exponent of x = F/k (1 + a |F/f_y|^(r-1))), got {exponent!r}")
            backbone = masing.RambergOsgood(k, f_y, a, exponent)
        if "x_max" not in r.data:
            r.fail("x_max", "missing (required: the largest |x| the element will see, in m; the smooth backbone "
                   "is interpolated at nodes up to it)")
        x_max = r.number("x_max")
        count = r.integer("count")
        try:
            check_memory(count * BYTES_PER_BRANCH, f"{source}: [masing] count = {count}")
        except ResourceError as exc:
            raise SceneError(str(exc)) from None
        spacing = r.string("spacing")
        try:
            k0, branches = masing.iwan_branches(backbone, count, x_max, spacing)
        except ValueError as exc:
            r.fail("count" if "count" in str(exc) else "x_max", str(exc))
    return (Spring(k0) if k0 > 0 else None), branches
















def _check_stepper_applies(scene: Scene, where: str) -> None:
    from .steppers import get_stepper

    try:
        get_stepper(scene.solver.stepper).loop_for(scene)
    except ValueError as exc:
        raise SceneError(f"{scene.source}: {where}stepper: {exc}") from None


