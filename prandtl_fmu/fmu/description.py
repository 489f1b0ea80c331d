"""The variables of a scene's FMU and its model description: one source for both runtimes and both FMI versions.

:func:`variables` lists the FMU variables of a scene (the element or the connector, a network or its connector:
the scene's kind and ``[fmu] causality`` decide) as :class:`Variable` rows, in value-reference order: name, type,
causality, variability, unit, start, min/max, description, value reference and, for an output, the inputs it
depends on directly. :func:`model_description` writes ``modelDescription.xml`` from them, FMI 2.0 or 3.0.

* The PythonFMU slaves (``fmu/python/*slave.py``) register the FMI 2.0 list with PythonFMU, each variable with its
  getter and setter (``register_variables`` in ``fmu/python/common.py``), and hand PythonFMU the FMI 2.0
  description (:func:`fmi2_root`) as their own.
* The native build (``fmu/native/build.py``, ``fmu/native/network_build.py``) writes the same description (FMI
  2.0, or FMI 3.0 with what FMI 3.0 adds) and its C table of variables from the same list.

FMI 3.0 adds to the FMI 2.0 scalars (:func:`fmi3_references`): the independent variable ``time`` first; for the
element, its branch elongations as the scalars u_1 .. u_n and, with ``arrays``, the array ``u`` sized by ``n`` (a
structural parameter then); for a network, with ``arrays``, the structural parameter ``n_nodes`` and the nodes' x
and v as arrays (the connector's ``x_nodes``, ``v_nodes``), after them. In FMI 3.0 every value reference is the
variable's 1-based position in ModelVariables (OMSimulator reads FMI 3.0's dependencies as FMI 2.0's positions:
both readings then name the same variable); FMI 2.0 keeps 0, 1, 2, ... in order (PythonFMU's numbering).

A Real's start value is written with 16 significant digits when they give the value back, 17 otherwise (every
start is the double the FMU holds); min and max with 17.
"""
from __future__ import annotations

import dataclasses
import sys
import xml.etree.ElementTree as ET
from typing import Optional
from xml.dom.minidom import parseString

from .. import __version__

DBL_MAX = sys.float_info.max
SMALLEST = 5e-324  # the smallest positive double: FMI's min is inclusive, and 0 is refused
NOISE_SEED_LIMIT = 2 ** 31  # an FMI 2.0 Integer is 32 bits: an FMU's noise_seed is below this

# SI base-unit exponents of the units the FMUs use.
UNITS = {
    "s": {"s": 1},
    "m": {"m": 1},
    "kg": {"kg": 1},
    "m/s": {"m": 1, "s": -1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N/m3": {"kg": 1, "m": -2, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "J": {"kg": 1, "m": 2, "s": -2},
    "1/s": {"s": -1},
    "N/(m.s)": {"kg": 1, "s": -3},
    "1": {},
    # a white noise's intensity, N sqrt(s): FMI's base-unit exponents are integers, so the name alone says it
    "N.s0.5": None,
}

# The model of each kind of FMU: (modelIdentifier, the model's description). The identifier names the binaries
# and is the PythonFMU slave's class name.
MODELS = {
    (False, "force"): ("PrandtlElement", (
        "Generalized Prandtl element (dry-friction hysteresis) under a force F: the springs, dashpot and Prandtl "
        "branches (spring in series with a Coulomb slider) of its scene, with or without a mass "
        "(documentation/index.html)")),
    (False, "displacement"): ("PrandtlConnector", (
        "Generalized Prandtl element (dry-friction hysteresis) as a connector between two bodies: relative motion "
        "x, v in, force out; the springs, dashpot and Prandtl branches of its scene (documentation/index.html)")),
    (True, "force"): ("PrandtlNetwork", (
        "Network of nodes joined by springs, dashpots, sliders, Prandtl branches and cubic springs under a force "
        "F at its load's node (documentation/index.html)")),
    (True, "displacement"): ("PrandtlNetworkConnector", (
        "Network of nodes joined by springs, dashpots, sliders, Prandtl branches and cubic springs as a "
        "connector: the motion x, v of its load's node in, the force that holds it out (documentation/index.html)")),
}
AUTHOR = "prandtl_fmu"
NATIVE_TOOL = "prandtl_fmu (native runtime)"
# PythonFMU 0.7.0's log categories, which both runtimes declare (FMI 3.0: its statuses' names)
LOG_CATEGORIES = [
    ("logStatusWarning", "Log messages with fmi2Warning status."),
    ("logStatusDiscard", "Log messages with fmi2Discard status."),
    ("logStatusError", "Log messages with fmi2Error status."),
    ("logStatusFatal", "Log messages with fmi2Fatal status."),
    ("logAll", "Log all messages."),
]


@dataclasses.dataclass(frozen=True)
class Variable:
    """One FMU variable. ``type``: FMI 3.0's name (Float64, Int32, Boolean, String, UInt64; FMI 2.0 writes Real
    and Integer for the first two); ``causality``, ``variability``: FMI's words; ``depends``: an output's direct
    dependencies, the names of inputs (empty: none), None for any other variable; ``dimension``: an FMI 3.0
    array's size, the name of the structural parameter."""
    name: str
    type: str
    causality: str
    variability: str
    description: str
    value_reference: int = -1
    unit: Optional[str] = None
    start: object = None
    min: Optional[float] = None
    max: Optional[float] = None
    depends: Optional[tuple] = None
    dimension: Optional[str] = None


def check_noise_settings(intensity, seed, unit):
    """The white noise of an FMU's noise_intensity, noise_seed, noise_unit (None: none); ValueError naming the
    parameter whose rule is broken: the seed an FMI Integer holds, then ``loads.white_noise``'s rules (both runtimes
    refuse with these words: the native one has them in its scene.h)."""
    from ..loads import white_noise

    if not (isinstance(seed, int) and not isinstance(seed, bool) and 0 <= seed < NOISE_SEED_LIMIT):
        raise ValueError(f"noise_seed = {seed!r}: must be an integer, 0 <= seed < 2^31")
    return white_noise(intensity, seed, unit)


def is_network(scene) -> bool:
    return hasattr(scene, "network")


def model_identifier(scene) -> str:
    """The modelIdentifier of a scene's FMU (PrandtlElement, PrandtlConnector, PrandtlNetwork,
    PrandtlNetworkConnector)."""
    return MODELS[is_network(scene), scene.causality][0]


def branch_count(scene) -> int:
    """The FMU variable n: the number of Prandtl branches, -1 for the continuous element, 0 without branches."""
    branches = scene.branches
    return 0 if branches is None else -1 if branches.continuum else branches.n


def elongation_count(scene) -> int:
    """n, the branch elongations u_1 .. u_n an element FMU offers (FMI 3.0): 0 without branches or for the
    continuum."""
    return max(branch_count(scene), 0)


# ------------------------------------------------------------------ the element and its connector

def _real(name, unit, causality, variability, description, **more) -> Variable:
    if unit not in UNITS:
        raise ValueError(f"{name}: unit {unit!r} has no definition")
    return Variable(name, "Float64", causality, variability, description, unit=unit, **more)


def _output(name, unit, description, depends=()) -> Variable:
    return _real(name, unit, "output", "continuous", description, depends=tuple(depends))


def _parameter(name, unit, low, variability, description, start) -> Variable:
    return _real(name, unit, "parameter", variability, description, start=float(start), min=low, max=DBL_MAX)


# Parameters of the effects: (name, unit, min, variability, description).
EFFECT_PARAMETERS = [
    ("m", "kg", SMALLEST, "tunable", "mass of the point; must be > 0"),
    ("x0", "m", -DBL_MAX, "fixed", "initial displacement"),
    ("v0", "m/s", -DBL_MAX, "fixed", "initial velocity"),
    ("k0", "N/m", 0.0, "tunable", "stiffness of the linear spring: force k0 x"),
    ("k3", "N/m3", 0.0, "tunable", "coefficient of the cubic spring: force k3 x^3"),
    ("c", "N.s/m", 0.0, "tunable", "dashpot coefficient: force c v"),
    ("alpha", "N", SMALLEST, "tunable",
     "friction of the mass on the ground: static threshold alpha_S; must be > 0 and >= alpha_kinetic"),
    ("alpha_kinetic", "N", 0.0, "tunable",
     "friction of the mass on the ground: sliding force at speed (Stribeck); must be <= alpha"),
    ("stribeck_velocity", "m/s", SMALLEST, "tunable",
     "friction of the mass on the ground: the slip speed over which the sliding force falls from alpha to "
     "alpha_kinetic; must be > 0"),
    ("belt_velocity", "m/s", -DBL_MAX, "tunable",
     "velocity of the ground the mass rubs on (a moving belt); 0: fixed ground"),
]
# The effects with memory (memory/): fixed parameters (they restart the memory), units by what they act on.
MEMORY_PARAMETERS = {
    "delay_gain": ("delay", None, -DBL_MAX, "gain of the delayed force -gain y(t - tau), y = x or v ([delay] acts_on)"),
    "delay_tau": ("delay", "s", SMALLEST, "delay tau of the delayed force; must be > 0"),
    "history_weight": ("history", None, -DBL_MAX,
                       "weight w_j of the history kernel sum_j w_j exp(-r_j t) of the force -int kappa(t - s) y(s) ds"),
    "history_rate": ("history", "1/s", 0.0, "rate r_j of the history kernel; must be >= 0"),
    "dahl_sigma": ("dahl", "N/m", SMALLEST, "Dahl's friction: stiffness at a reversal; must be > 0"),
    "dahl_force": ("dahl", "N", SMALLEST, "Dahl's friction: the Coulomb level F_c it approaches; must be > 0"),
    "dahl_exponent": ("dahl", "1", SMALLEST, "Dahl's friction: the exponent of (1 - F_d / F_c sgn v); must be > 0"),
}


def memory_parameters(scene, values: dict) -> list:
    """The parameters of the effects with memory among the coefficients ``values`` (fixed: they restart the
    memory), with the units of what each acts on."""
    rows = []
    for name, value in values.items():
        key = name.split("[")[0]
        if key in MEMORY_PARAMETERS:
            table, unit, low, text = MEMORY_PARAMETERS[key]
            on_v = getattr(getattr(scene, table), "acts_on", "x") == "v"
            if key == "delay_gain":
                unit = "N.s/m" if on_v else "N/m"
            elif key == "history_weight":
                unit = "N/m" if on_v else "N/(m.s)"
            rows.append(_parameter(name, unit, low, "fixed", text + (f" (term {name[len(key) + 1:-1]})"
                                                                     if "[" in name else ""), value))
    return rows


def _noise_variables(scene) -> list:
    """noise_intensity, noise_seed, noise_unit: the white noise an FMU adds to its force (start: the scene's
    [load] noise, or none)."""
    noise = scene.load.noise
    intensity, seed, unit = (noise.intensity, noise.seed, noise.unit) if noise is not None else (0.0, 0, 1.0)
    return [
        _real("noise_intensity", "N.s0.5", "parameter", "tunable",
              "intensity sigma (N sqrt(s)) of the white noise the FMU adds to the force: F + sigma xi(t), "
              "xi = dB/dt; 0: none; must be >= 0 (docs/white-noise.md)", start=float(intensity), min=0.0,
              max=DBL_MAX),
        Variable("noise_seed", "Int32", "parameter", "tunable",
                 "seed of the white noise's Brownian path (0 <= seed < 2^31): the path is a function of the "
                 "seed and the time alone", start=int(seed)),
        _real("noise_unit", "s", "parameter", "tunable",
              "time unit of the Brownian tree (a property of the path, not of the step): about one normal per "
              "internal step when the step is the unit over a power of two; must be > 0", start=float(unit),
              min=SMALLEST, max=DBL_MAX),
    ]


def _n_variable(scene) -> Variable:
    return Variable("n", "Int32", "local", "constant",
                    "number of Prandtl branches (from the scene); -1 for the continuous element",
                    start=branch_count(scene))


def _step_variable(scene, text="internal time step h of the stepper; must be > 0") -> Variable:
    return _real("step", "s", "parameter", "tunable", text, start=float(scene.solver.step), min=SMALLEST,
                 max=DBL_MAX)


def scene_load_start(scene) -> bool:
    """``scene_load``'s start value: a scene that names a force history is a scene with that load, so a fresh FMU
    run with no input connected (``fmpy simulate``) reproduces the library's run of its scene; a scene whose load
    is nothing (no [load], or a constant 0 with at most a noise, which has parameters of its own) starts false."""
    from ..loads import ConstantLoad

    load = scene.load
    return not (isinstance(load, ConstantLoad) and load.value == 0.0)


def scene_load_notice(scene, where: str = "the element") -> str:
    """The message an FMU logs (status warning, whatever ``loggingOn`` says) when it leaves initialization with
    ``scene_load`` true: a master that connects F is told that the scene's load is added to it, and how not."""
    kind = type(scene.load).__name__.replace("Load", "").lower()
    return (f"scene_load is true: the force on {where} is the input F plus the scene's [load] ({kind}) at every "
            "internal step; set the parameter scene_load to false to drive it by F alone")


def _scene_load_variable(scene, where: str) -> Variable:
    start = scene_load_start(scene)
    return Variable("scene_load", "Boolean", "parameter", "tunable",
                    f"true: the force on {where} is F plus the scene's [load] F_scene(t), evaluated at every "
                    "internal step as in the library (with no input connected the FMU reproduces the library's run "
                    "of its scene; logged as a warning at the end of initialization); false: F alone. Starts "
                    + ("true: the scene names a load" if start else "false: the scene names no load"), start=start)


def element_variables(scene) -> list:
    """The element with its force input F (``fmu/python/slave.py``)."""
    from ..scene import coefficients_of
    from ..steppers import STEPPERS
    from .documentation import reaction_formula, stiffness_formula, stored_energy_formula

    values = coefficients_of(scene)
    friction = scene.friction is not None
    rows = [_real("F", "N", "input", "continuous", "external force on the element, held over each step",
                  start=0.0, min=-DBL_MAX, max=DBL_MAX)]
    # No output depends directly on the input F: x, v and the branch elongations are states, and the reaction is
    # a function of them; except with friction on the mass, which holds a stuck mass against F (then the
    # reaction is F itself).
    rows += [
        _output("x", "m", "displacement of the point"),
        _output("v", "m/s", "velocity of the point"),
        _output("reaction", "N", f"force of the element on the point: {reaction_formula(scene)}"
                + (" (= F - m v')" if scene.mass is not None else "")
                + ("; while the mass sticks, the friction holds it against the F set now" if friction else ""),
                depends=("F",) if friction else ()),
        _output("stiffness", "N/m", "tangent stiffness d(reaction)/dx at the current state for a motion in the "
                f"direction of v (of increasing x when v = 0): {stiffness_formula(scene)}"),
    ]
    energy = [  # the energy account, for the effects present
        ("kinetic_energy", "mass", "kinetic energy m v^2/2"),
        ("stored_energy", None, f"elastic energy {stored_energy_formula(scene)}"),
        ("work", None, "work done by F since the start (as the stepper books it; 'exact' exactly)"),
        ("dissipated_sliders", "branches", "work dissipated by the sliders: sum alpha_i |slip_i|"),
        ("dissipated_damper", "damper", "work dissipated by the dashpot"),
        ("dissipated_friction", "friction", "work dissipated by the friction of the mass on the ground"),
        ("energy_residual", None,
         "work - dissipated - change of kinetic and stored energy: dissipated (> 0) or created (< 0) by the "
         "scheme itself"),
    ]
    for name, table, text in energy:
        if name == "dissipated_damper" and scene.has_series_dashpots:
            table, text = None, "work dissipated by the dashpot and the branches' series dashpots"
        if table is None or getattr(scene, table) is not None:
            rows.append(_output(name, "J", text))
    for name, unit, low, variability, text in EFFECT_PARAMETERS:
        if name in values:  # an absent effect has no parameter
            rows.append(_parameter(name, unit, low, variability, text, values[name]))
    for name, value in values.items():
        if name.startswith("c_branch"):
            which = "every branch" if name == "c_branch" else f"branch {name[9:-1]}"
            rows.append(_parameter(name, "N.s/m", SMALLEST, "tunable", "dashpot in series with the spring and "
                                   f"slider of {which}: relaxation rate k_i / c_i; must be > 0", value))
    rows += memory_parameters(scene, values)
    rows += [_step_variable(scene), _scene_load_variable(scene, "the element"), *_noise_variables(scene),
             Variable("stepper", "String", "parameter", "tunable", "time stepper: " + ", ".join(STEPPERS),
                      start=scene.solver.stepper),
             _n_variable(scene)]
    return rows


def connector_variables(scene) -> list:
    """The element as a connector: x, v in, force out (``fmu/python/kinds.py`` ConnectorKind)."""
    from ..scene import coefficients_of
    from .documentation import reaction_formula, stiffness_formula, stored_energy_formula

    values = coefficients_of(scene)
    rows = [
        _real("x", "m", "input", "continuous",
              "relative displacement of the two flanges (linear between communication points)", start=0.0,
              min=-DBL_MAX, max=DBL_MAX),
        _real("v", "m/s", "input", "continuous", "relative velocity of the two flanges", start=0.0, min=-DBL_MAX,
              max=DBL_MAX),
        # The force depends directly on both inputs (springs on x, dashpot on v); the stiffness on x (the cubic
        # spring, which branches stick) and on v (the direction); the energies on x.
        _output("force", "N", f"force the element transmits: {reaction_formula(scene)}", depends=("x", "v")),
        _output("stiffness", "N/m", "tangent stiffness dF/dx for a motion in the direction of v (of the last "
                f"motion when v = 0): {stiffness_formula(scene)}", depends=("x", "v")),
        _output("stored_energy", "J", f"elastic energy {stored_energy_formula(scene)}", depends=("x",)),
    ]
    if scene.branches is not None:
        rows.append(_output("dissipated_sliders", "J", "work dissipated by the sliders since the start: "
                            "sum alpha_i |slip_i|", depends=("x",)))
    if scene.damper is not None or scene.has_series_dashpots:
        rows.append(_output("dissipated_damper", "J", "work dissipated by the dashpot and the branches' series "
                            "dashpots up to the last doStep (v linear between communication points)"))
    texts = {"k0": "stiffness of the linear spring: force k0 x", "k3": "coefficient of the cubic spring: force k3 x^3",
             "c": "dashpot coefficient: force c v"}
    units = {"k0": "N/m", "k3": "N/m3", "c": "N.s/m"}
    for name in ("k0", "k3", "c"):
        if name in values:  # an absent effect has no parameter
            rows.append(_parameter(name, units[name], 0.0, "tunable", texts[name], values[name]))
    for name, value in values.items():
        if name.startswith("c_branch"):
            which = "every branch" if name == "c_branch" else f"branch {name[9:-1]}"
            rows.append(_parameter(name, "N.s/m", SMALLEST, "tunable", f"dashpot in series with the spring and "
                                   f"slider of {which} (the force relaxes over the time between samples); must be "
                                   "> 0", value))
    rows += memory_parameters(scene, values)
    rows.append(_n_variable(scene))
    return rows


# ------------------------------------------------------------------ networks

# the unit, min and meaning of a coefficient, by its scene key (network/model.py KEYS) and the element's kind
NETWORK_COEFFICIENTS = {
    ("spring", "k"): ("N/m", 0.0, "stiffness of the spring {name}: force k (x_i - x_j)"),
    ("dashpot", "c"): ("N.s/m", 0.0, "coefficient of the dashpot {name}: force c (v_i - v_j)"),
    ("slider", "alpha"): ("N", 0.0, "threshold of the Saint-Venant slider {name}: force in alpha sign(v_i - v_j)"),
    ("branch", "k"): ("N/m", SMALLEST, "stiffness of the Prandtl branch {name} (force k u); must be > 0"),
    ("branch", "eta"): ("m", 0.0, "elastic range of the Prandtl branch {name}: |u| <= eta, threshold k eta"),
    ("branch", "c"): ("N.s/m", 0.0, "series dashpot of the Prandtl branch {name} (relaxation rate k / c); 0: none"),
    ("cubic", "k3"): ("N/m3", 0.0, "coefficient of the cubic spring {name}: force k3 (x_i - x_j)^3"),
}


def _end(network, j) -> str:
    return "the ground" if j < 0 else network.nodes[j]


def network_parameters(network, exclude=()) -> list:
    """Every network parameter but ``exclude``, in ``Network.parameters()`` order, tunable."""
    described = {}
    for node in network.nodes:
        described[f"m_{node}"] = ("kg", 0.0, f"mass of node {node}; 0: a massless node (in equilibrium at every "
                                  "instant)")
    for e in network.elements:
        where = f"{e.name} (between {_end(network, e.between[0])} and {_end(network, e.between[1])})"
        for key in e.coefficients():
            unit, low, text = NETWORK_COEFFICIENTS[(e.kind, key)]
            described[f"{key}_{e.name}"] = (unit, low, text.format(name=where))
    return [_parameter(name, *described[name][:2], "tunable", described[name][2], value)
            for name, value in network.parameters().items() if name not in exclude]


def network_outputs(network, nodes=None, depends=()) -> list:
    """The outputs of a network's FMU: x_<node>, v_<node> (of ``nodes``, default all), the energy account under
    the element FMU's names, dissipated_<kind>_<name> of every dissipating element, u_<branch> of every branch;
    each depending directly on ``depends``."""
    rows = []
    for node in network.nodes:
        if nodes is None or node in nodes:
            rows.append(_output(f"x_{node}", "m", f"displacement of node {node}", depends))
            rows.append(_output(f"v_{node}", "m/s", f"velocity of node {node}", depends))
    kinds = {e.kind for e in network.elements}
    energy = [
        ("kinetic_energy", "kinetic energy sum_j m_j v_j^2/2", True),
        ("stored_energy", "elastic energy of the springs, cubic springs and branches", True),
        ("work", "work done on the load's node since the start (as the stepper books it)", True),
        ("dissipated_sliders", "work dissipated by the sliders and the branches' sliders",
         bool(kinds & {"slider", "branch"})),
        ("dissipated_damper", "work dissipated by the dashpots and the branches' series dashpots",
         bool(kinds & {"dashpot", "branch"})),
        ("energy_residual", "work - dissipated - change of kinetic and stored energy: dissipated (> 0) or "
         "created (< 0) by the scheme itself", True),
    ]
    rows += [_output(name, "J", text, depends) for name, text, present in energy if present]
    for element in network.elements:
        if element.kind in ("slider", "branch", "dashpot"):
            rows.append(_output(f"dissipated_{element.kind}_{element.name}", "J",
                                f"work dissipated by the {element.kind} {element.name} since the start", depends))
    for element in network.elements:
        if element.kind == "branch":
            rows.append(_output(f"u_{element.name}", "m", f"elongation of the spring of branch {element.name} "
                                "(|u| <= eta)", depends))
    return rows


def stepper_choices(scene) -> str:
    """The network steppers, each with whether it applies to this network (and why not)."""
    from ..network.model import NETWORK_STEPPERS, stepper_problem

    texts = []
    for name in NETWORK_STEPPERS:
        problem = stepper_problem(scene, name)
        texts.append(f"{name}" + (" (default)" if name == scene.solver.stepper else "")
                     + (f" (does not apply as built: {problem})" if problem else ""))
    return "; ".join(texts)


def network_variables(scene) -> list:
    """A network under a force F at its load's node (``fmu/python/kinds.py`` NetworkKind): no output depends directly on F
    (they are those of the state at the end of the last step)."""
    network = scene.network
    load_node = network.nodes[network.load_node]
    rows = [_real("F", "N", "input", "continuous", f"external force on the load's node {load_node}, held over "
                  "each step", start=0.0, min=-DBL_MAX, max=DBL_MAX)]
    outputs = network_outputs(network)
    outputs.insert(2 * network.n, _output(
        "reaction", "N", "force of the elements on the ground (the sum over the elements with an end at the "
        "ground), at the end of the last step"))
    rows += outputs + network_parameters(network)
    rows += [_step_variable(scene), _scene_load_variable(scene, "the load's node"), *_noise_variables(scene),
             Variable("stepper", "String", "parameter", "tunable", "time stepper: " + stepper_choices(scene),
                      start=scene.solver.stepper)]
    return rows


def network_connector_variables(scene) -> list:
    """A network as a connector: the motion x, v of its load's node in, the force out
    (``fmu/python/kinds.py`` NetworkConnectorKind): every output shows the network moved to the inputs set now, so all
    depend directly on x and v."""
    network = scene.network
    j = network.load_node
    node = network.nodes[j]
    rows = [
        _real("x", "m", "input", "continuous", f"displacement of the load's node {node} (linear between "
              "communication points)", start=float(network.x0[j]), min=-DBL_MAX, max=DBL_MAX),
        _real("v", "m/s", "input", "continuous", f"velocity of the load's node {node}", start=float(network.v0[j]),
              min=-DBL_MAX, max=DBL_MAX),
        _output("force", "N", f"force of the network's elements on its load's node {node} (what holds the imposed "
                "motion)", ("x", "v")),
    ]
    rows += network_outputs(network, nodes=[name for name in network.nodes if name != node], depends=("x", "v"))
    rows += network_parameters(network, exclude=(f"m_{node}",))
    rows.append(_step_variable(scene, "internal time step h of the implicit steps; must be > 0"))
    return rows


# ------------------------------------------------------------------ the list, with value references

def variables(scene, fmi: int = 2, arrays: bool = False) -> list:
    """The FMU variables of ``scene`` (its kind and ``[fmu] causality`` decide which FMU), in value-reference
    order; FMI 3.0 (``fmi=3``): with what FMI 3.0 adds (module docstring), ``arrays`` its arrays. A scene whose
    names would give two variables the same name is refused (SceneError)."""
    from ..scene import SceneError

    kind = (is_network(scene), scene.causality)
    rows = {(False, "force"): element_variables, (False, "displacement"): connector_variables,
            (True, "force"): network_variables, (True, "displacement"): network_connector_variables}[kind](scene)
    rows = [_with(row, value_reference=vr) for vr, row in enumerate(rows)]
    seen = set()
    for row in rows:
        if row.name in seen:
            raise SceneError(f"two FMU variables would be named {row.name!r}: rename a node or an element")
        seen.add(row.name)
    if fmi == 3:
        rows = _fmi3_variables(scene, rows, arrays)
    elif fmi != 2 or arrays:
        raise ValueError(f"fmi={fmi}, arrays={arrays}: FMI 2.0 (no arrays) or 3.0")
    return rows


def _with(row: Variable, **changes) -> Variable:
    return dataclasses.replace(row, **changes)


def fmi3_references(scene) -> dict:
    """The value references of what FMI 3.0 adds to the FMI 2.0 variables: ``time``; the element's ``u_1`` (u_i is
    u_1 + i - 1) and ``u`` (the array; None without elongations); a network's ``n_nodes``, ``x_nodes``,
    ``v_nodes`` (its arrays, with ``arrays``); and ``offset``, what FMI 3.0 adds to an FMI 2.0 value reference.
    The same with or without ``arrays`` (its variables come last, the structural n stays where n is)."""
    rows = variables(scene, fmi=3, arrays=True) if is_network(scene) or elongation_count(scene) else \
        variables(scene, fmi=3)
    by_name = {row.name: row.value_reference for row in rows}
    offset = by_name[variables(scene)[0].name]  # the first FMI 2.0 variable's (its FMI 2.0 value reference is 0)
    if is_network(scene):
        arrays = ("x_nodes", "v_nodes") if scene.causality == "displacement" else ("x", "v")
        return {"time": by_name["time"], "n_nodes": by_name["n_nodes"], "x_nodes": by_name[arrays[0]],
                "v_nodes": by_name[arrays[1]], "offset": offset}
    return {"time": by_name["time"], "u": by_name.get("u"), "u_1": by_name.get("u_1", len(rows) + 1),
            "offset": offset}


def _fmi3_variables(scene, rows, arrays: bool) -> list:
    """FMI 3.0's list: ``time``, the FMI 2.0 rows, then what FMI 3.0 adds; every value reference the variable's
    1-based position in ModelVariables. FMI 3.0 names an output's dependencies by value reference, FMI 2.0 by that
    position: OMSimulator (2.x) reads FMI 3.0's as positions, and with this rule both readings name the same
    variable (issue 44; ``time`` has one too: FMI 3.0 gives every variable, the independent one included, a value
    reference, and 0 is left unused)."""
    network = is_network(scene)
    time = _real("time", "s", "independent", "continuous", f"the {'network' if network else 'element'}'s time")
    extra = []
    if network:
        if arrays:
            net = scene.network
            connector = scene.causality == "displacement"
            extra.append(Variable("n_nodes", "UInt64", "structuralParameter", "fixed", "number of nodes: the length "
                                  "of the arrays of the nodes' x and v", start=net.n))
            shown = ", ".join(net.nodes[:5]) + (", ..." if net.n > 5 else "")
            for name, unit, what in (("x", "m", "displacement"), ("v", "m/s", "velocity")):
                extra.append(_with(_output(f"{name}_nodes" if connector else name, unit,
                                           f"{what} of every node, in the nodes' order ({shown})",
                                           ("x", "v") if connector else ()), dimension="n_nodes"))
    else:
        n = elongation_count(scene)
        if arrays:  # the array's size: a structural parameter, n >= 1 (arrays needs branches)
            rows = [Variable("n", "UInt64", "structuralParameter", "fixed", row.description, start=n)
                    if row.name == "n" else row for row in rows]
        # the elongations are states (the connector's too: they move at doStep only): no input acts on them
        # directly
        extra = [_output(f"u_{i}", "m", f"elongation u_{i} of the spring of Prandtl branch {i}")
                 for i in range(1, n + 1)]
        if arrays:
            extra.append(_with(_output("u", "m", "elongations u_i of the springs of the Prandtl branches, in the "
                                       "scene's order (the scalars u_1 .. u_n as one array)"), dimension="n"))
    return [_with(row, value_reference=position) for position, row in enumerate([time] + rows + extra, start=1)]


# ------------------------------------------------------------------ the XML

def _real_text(value) -> str:
    """A double as the XML holds it: 16 significant digits when they give it back, else 17."""
    value = float(value)
    text = f"{value:.16g}"
    return text if float(text) == value else f"{value:.17g}"


def _start_text(row: Variable) -> str:
    if row.type == "Float64":
        return _real_text(row.start)
    if row.type == "Boolean":
        return str(bool(row.start)).lower()
    return str(row.start)


def _has_start(row: Variable) -> bool:
    return row.start is not None and (row.causality in ("input", "parameter", "structuralParameter")
                                      or row.variability == "constant")


def _header(scene) -> tuple:
    identifier, text = MODELS[is_network(scene), scene.causality]
    return identifier, text


def _unit_definitions(parent, units) -> None:
    node = ET.SubElement(parent, "UnitDefinitions")
    for name in units:
        unit = ET.SubElement(node, "Unit", name=name)
        if UNITS[name] is not None:
            ET.SubElement(unit, "BaseUnit", {k: str(e) for k, e in UNITS[name].items()})


def _default_experiment(parent, scene) -> None:
    solver = scene.solver
    attributes = {"startTime": str(0.0)}
    if solver.stop_time is not None:
        attributes["stopTime"] = str(solver.stop_time)
    if solver.output_interval is not None:
        attributes["stepSize"] = str(solver.output_interval)
    ET.SubElement(parent, "DefaultExperiment", attributes)


def _native_element(scene, runtime: str) -> bool:
    return runtime == "native" and not is_network(scene) and scene.causality != "displacement"


def interpolates_inputs(scene, runtime: str) -> bool:
    """Whether the FMU takes its inputs' derivatives (FMI 2.0 canInterpolateInputs, fmi2SetRealInputDerivatives,
    orders 1 and 2): the native element's of F, and the native connector's of x and v where the path's timing does
    not matter (no series dashpots, no effect with memory: ``Connector.advance``). The PythonFMU runtime's loader
    has no such call; the network's inputs are held."""
    if runtime != "native" or is_network(scene):
        return False
    if scene.causality == "displacement":
        return not (scene.has_series_dashpots or scene.delay is not None or scene.history is not None
                    or scene.dahl is not None)
    return True


def updates_intermediately(scene, runtime: str) -> bool:
    """Whether the FMU provides FMI 3.0's intermediate update (F set at its internal steps): the native element."""
    return _native_element(scene, runtime)


def output_derivative_order(scene, runtime: str) -> int:
    """FMI's maxOutputDerivativeOrder of the FMU (fmi2GetRealOutputDerivatives, fmi3GetOutputDerivatives,
    ``kernels/rates.py``): 2 for the native element (x: v, a; v: a, a' where exact; reaction: its rate where
    exact) and for the native connector's force (F', F'' along its inputs' path) but with series dashpots or effects
    with memory; else 0 (none given)."""
    if runtime != "native" or is_network(scene):
        return 0
    if scene.causality == "displacement":
        return 0 if (scene.has_series_dashpots or scene.delay is not None or scene.history is not None
                     or scene.dahl is not None) else 2
    return 2


def provides_directional_derivatives(scene, runtime: str) -> bool:
    """Whether the FMU gives directional derivatives (FMI 2.0 providesDirectionalDerivative, FMI 3.0
    providesDirectionalDerivatives): the native connector's, d force = (d force/d x) dx + (d force/d v) dv (its one
    output with direct feedthrough; the element has none)."""
    return runtime == "native" and not is_network(scene) and scene.causality == "displacement"


def fmi2_root(scene, guid: str, generation_tool: str, generated: Optional[str] = None,
              needs_execution_tool: bool = True, can_interpolate_inputs: bool = False,
              max_output_derivative_order: int = 0, directional: bool = False) -> ET.Element:
    """The FMI 2.0 model description of ``scene``'s FMU as an XML tree (PythonFMU's layout: what its builder
    writes from a slave's ``to_xml``): ``generated`` the generationDateAndTime (None: now);
    ``can_interpolate_inputs``, ``max_output_derivative_order``, ``directional``: see :func:`interpolates_inputs`,
    :func:`output_derivative_order`, :func:`provides_directional_derivatives`."""
    import datetime

    rows = variables(scene)
    identifier, text = _header(scene)
    if generated is None:
        generated = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": scene.name, "guid": guid, "generationTool": generation_tool,
        "generationDateAndTime": generated, "variableNamingConvention": "structured", "description": text,
        "author": AUTHOR, "version": __version__})
    ET.SubElement(root, "CoSimulation", {
        "needsExecutionTool": str(needs_execution_tool).lower(), "canHandleVariableCommunicationStepSize": "true",
        "canInterpolateInputs": str(can_interpolate_inputs).lower(), "canBeInstantiatedOnlyOncePerProcess": "false",
        "canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true", "modelIdentifier": identifier,
        "canNotUseMemoryManagementFunctions": "true",
        **({"maxOutputDerivativeOrder": str(max_output_derivative_order)} if max_output_derivative_order else {}),
        **({"providesDirectionalDerivative": "true"} if directional else {})})
    _unit_definitions(root, sorted({row.unit for row in rows if row.unit is not None}))
    categories = ET.SubElement(root, "LogCategories")
    for name, description in LOG_CATEGORIES:
        ET.SubElement(categories, "Category", {"name": name, "description": description})
    _default_experiment(root, scene)
    node = ET.SubElement(root, "ModelVariables")
    types = {"Float64": "Real", "Int32": "Integer", "Boolean": "Boolean", "String": "String"}
    for row in rows:
        variable = ET.SubElement(node, "ScalarVariable", {
            "name": row.name, "valueReference": str(row.value_reference), "description": row.description,
            "causality": row.causality, "variability": row.variability})
        typed = ET.SubElement(variable, types[row.type])
        if _has_start(row):
            typed.set("start", _start_text(row))
        if row.unit is not None:
            typed.set("unit", row.unit)
        for key in ("min", "max"):
            if getattr(row, key) is not None:
                typed.set(key, f"{getattr(row, key):.17g}")
    structure = ET.SubElement(root, "ModelStructure")
    index = {row.name: position for position, row in enumerate(rows, start=1)}
    outputs = [row for row in rows if row.causality == "output"]
    if outputs:
        node = ET.SubElement(structure, "Outputs")
        for row in outputs:
            ET.SubElement(node, "Unknown", index=str(index[row.name]),
                          dependencies=" ".join(str(index[name]) for name in row.depends))
        initial = ET.SubElement(structure, "InitialUnknowns")
        for row in outputs:
            ET.SubElement(initial, "Unknown", index=str(index[row.name]), dependencies=" ".join(
                str(index[name]) for name in initial_dependencies(scene, row, rows)))
    return root


def initial_dependencies(scene, row, rows) -> list:
    """The knowns an output's initial value depends on (ModelStructure's InitialUnknowns): every parameter (the
    initial state and the coefficients), and the inputs it depends on at initialization: those of its direct
    feedthrough (the connector's x and v), every input where a massless node's equilibrium follows the load (a
    massless element; any network). An element with a mass starts from its x0, v0: its outputs depend on no input
    (without the list a master takes them to depend on F, and OMSimulator reports an algebraic loop)."""
    inputs = [r.name for r in rows if r.causality == "input"]
    if is_network(scene) or (scene.causality != "displacement" and scene.mass is None):
        taken = inputs
    else:
        taken = [name for name in inputs if name in row.depends]
    return [r.name for r in rows if r.causality == "parameter" or r.name in taken]


def fmi3_root(scene, guid: str, arrays: bool = False) -> ET.Element:
    """The FMI 3.0 model description of ``scene``'s native FMU as an XML tree (``arrays``: with its arrays)."""
    rows = variables(scene, fmi=3, arrays=arrays)
    identifier, text = _header(scene)
    top = ET.Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": scene.name, "instantiationToken": guid, "description": text,
        "author": AUTHOR, "version": __version__, "generationTool": NATIVE_TOOL,
        "variableNamingConvention": "structured"})
    ET.SubElement(top, "CoSimulation", {
        "modelIdentifier": identifier, "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false", "canGetAndSetFMUState": "true",
        "canSerializeFMUState": "true", "canHandleVariableCommunicationStepSize": "true",
        "providesIntermediateUpdate": str(updates_intermediately(scene, "native")).lower(),
        "canReturnEarlyAfterIntermediateUpdate": "false", "hasEventMode": "false",
        **({"recommendedIntermediateInputSmoothness": "0"} if updates_intermediately(scene, "native") else {}),
        **({"maxOutputDerivativeOrder": str(output_derivative_order(scene, "native"))}
           if output_derivative_order(scene, "native") else {}),
        **({"providesDirectionalDerivatives": "true"} if provides_directional_derivatives(scene, "native") else {})})
    # FMI 2.0's units (sorted), then those only FMI 3.0's variables use (time's s, the elongations' m)
    units = sorted({row.unit for row in variables(scene) if row.unit is not None})
    units += [unit for unit in ("s", "m") if unit not in units and any(row.unit == unit for row in rows)]
    _unit_definitions(top, units)
    categories = ET.SubElement(top, "LogCategories")
    for name, description in LOG_CATEGORIES:
        ET.SubElement(categories, "Category", {"name": name, "description": description.replace("fmi2", "fmi3")})
    _default_experiment(top, scene)
    node = ET.SubElement(top, "ModelVariables")
    by_name = {row.name: row for row in rows}
    for row in rows:
        attributes = {"name": row.name, "valueReference": str(row.value_reference)}
        if row.description:
            attributes["description"] = row.description
        attributes.update(causality=row.causality, variability=row.variability)
        if row.type == "String":
            element = ET.SubElement(node, "String", attributes)
            if _has_start(row):
                ET.SubElement(element, "Start", {"value": _start_text(row)})
            continue
        if _has_start(row):
            attributes["start"] = _start_text(row)
        if row.unit is not None:
            attributes["unit"] = row.unit
        for key in ("min", "max"):
            if getattr(row, key) is not None:
                attributes[key] = f"{getattr(row, key):.17g}"
        if row.name == "F" and row.causality == "input" and updates_intermediately(scene, "native"):
            attributes["intermediateUpdate"] = "true"  # the master may set it at every internal step
        element = ET.SubElement(node, row.type, attributes)
        if row.dimension is not None:
            ET.SubElement(element, "Dimension", {"valueReference": str(by_name[row.dimension].value_reference)})
    structure = ET.SubElement(top, "ModelStructure")
    outputs = [row for row in rows if row.causality == "output"]
    for row in outputs:
        ET.SubElement(structure, "Output", {"valueReference": str(row.value_reference), "dependencies": " ".join(
            str(by_name[name].value_reference) for name in row.depends)})
    for row in outputs:
        known = initial_dependencies(scene, row, rows)
        ET.SubElement(structure, "InitialUnknown", {"valueReference": str(row.value_reference),
                                                    "dependencies": " ".join(str(by_name[name].value_reference)
                                                                             for name in known)})
    ET.indent(top)
    return top


def model_description(scene, fmi: int = 2, guid: str = "", runtime: str = "native", arrays: bool = False,
                      generation_tool: Optional[str] = None, generated: Optional[str] = None,
                      steppers: Optional[list] = None) -> str:
    """``modelDescription.xml`` of ``scene``'s FMU: FMI 2.0 (``fmi=2``) of either runtime (``runtime``
    "python": needsExecutionTool; ``generation_tool`` the builder's name) or FMI 3.0 (the native runtime's,
    ``arrays``: with its arrays); ``guid`` its GUID or instantiation token. ``steppers``: the only steppers a
    native FMU holds (a build with ``--steppers``), which the ``stepper`` parameter's description then names."""
    if fmi == 3:
        root = fmi3_root(scene, guid, arrays)
        _held_steppers(root, steppers)
        return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
    if fmi != 2 or arrays:
        raise ValueError(f"fmi={fmi}, arrays={arrays}: FMI 2.0 (no arrays) or 3.0")
    root = fmi2_root(scene, guid, generation_tool or NATIVE_TOOL, generated, needs_execution_tool=runtime == "python",
                     can_interpolate_inputs=interpolates_inputs(scene, runtime),
                     max_output_derivative_order=output_derivative_order(scene, runtime),
                     directional=provides_directional_derivatives(scene, runtime))
    _held_steppers(root, steppers)
    return fmi2_text(root)


def _held_steppers(root: ET.Element, steppers: Optional[list]) -> None:
    """The ``stepper`` parameter's description of an FMU built with only ``steppers`` (None: every one)."""
    if steppers is None:
        return
    for variable in root.find("ModelVariables"):
        if variable.get("name") == "stepper":
            variable.set("description", "time stepper: " + ", ".join(steppers) + " (the steppers this FMU holds: "
                         "built with --steppers)")


def fmi2_text(root: ET.Element) -> str:
    """An FMI 2.0 tree as its file's text: indented by tabs, as PythonFMU's builder writes it."""
    return parseString(ET.tostring(root, "UTF-8")).toprettyxml(encoding="UTF-8").decode("utf-8")
