"""The four kinds of FMU as the one slave (``slave.py``) sees them: the library's stepped object of a scene and the
calls that map the FMU's variables (``fmu/description.py``) to it. No FMI here, and no numerics: every number is
the library's.

* :class:`ElementKind`: the element under a force F (:class:`~prandtl_fmu.Element`, ``element_variables``);
* :class:`NetworkKind`: a network under a force F at its load's node (:class:`~prandtl_fmu.network.NetworkElement`,
  ``network_variables``);
* :class:`ConnectorKind`: the element as a connector, motion x, v in, force out (:class:`~prandtl_fmu.connector.
  Connector`, ``connector_variables``);
* :class:`NetworkConnectorKind`: a network as a connector, the motion of its load's node in
  (:class:`~prandtl_fmu.network.NetworkConnector`, ``network_connector_variables``).

A kind driven by a force (``driven_by_force``) offers ``hand_over`` (the settings the master set, to the library:
False when it refuses one, the reason logged as a Discard), ``reset``, ``stability_problem``, ``check_state`` and
``restore``; one driven by a motion offers ``hand_over`` (None, or why a parameter is refused), ``start``,
``commit`` and the same two for states. Each names its outputs' getters (``outputs``) and its parameters. The
library is imported by the kind in use only: an element's FMU never imports the network's code.
"""
import copy

from ...stepping import UNCHANGED, ElementError
from .common import Refused, finite_number

# the energy account's outputs (those of the effects present are the FMU's: description.element_variables)
ENERGIES = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
            "dissipated_friction", "energy_residual")
NETWORK_STEPPER = "implicit"  # the network connector's only one: the imposed motion is a constraint


def settings_problem(parameters: dict, stepper, step, scene_load) -> "str | None":
    """Why the parameters a master set (or a saved state holds) for an element cannot be used, or None."""
    from ...scene import coefficient_problem
    from ...steppers import STEPPERS

    for name, value in parameters.items():
        problem = coefficient_problem(name, value)
        if problem:
            return f"parameter {name}: {problem}"
    if not isinstance(stepper, str) or stepper not in STEPPERS:
        return f"parameter stepper = {stepper!r}: must be one of {', '.join(STEPPERS)}"
    if not (finite_number(step) and step > 0):
        return f"parameter step = {step!r}: must be finite and > 0"
    if not isinstance(scene_load, bool):
        return f"parameter scene_load = {scene_load!r}: must be true or false"
    return None


def finite_settings(settings: dict, inputs: tuple) -> None:
    """ValueError unless a saved state's inputs and start time are finite numbers (the force kinds' words)."""
    if not all(finite_number(settings[name]) for name in inputs + ("start_time",)):
        raise ValueError(f"F = {settings['F']!r}, start time {settings['start_time']!r}: must be finite numbers")


class Kind:
    """What every kind has unless it says otherwise (module docstring)."""

    stepped = None  # the library's stepped object
    noun = "element"  # what a refused fixed parameter leaves unchanged
    fixed = ""  # why its fixed parameters are (a kind without any: "")

    @staticmethod
    def settings_problem(slave) -> "str | None":
        """Why the settings the master set cannot be used (checked at initialization), or None: the library checks
        each when it is handed over."""
        return None

    @staticmethod
    def settings_in_use():
        """What a new stability problem depends on (None: the kind has no stability rule to warn about)."""
        return None

    @staticmethod
    def stability_problem():
        return None

    @staticmethod
    def saved_clock() -> dict:
        """What a state saves beside the settings the master set: a clock of the kind's own."""
        return {}


class ElementKind(Kind):
    """The element under a force (``description.element_variables``)."""

    driven_by_force = True
    state_key = "element"
    where = "the element"  # what the force acts on (description.scene_load_notice)
    misfit = "a parameter does not fit the scene"
    fixed = "(the initial state, or an effect with memory)"

    def __init__(self, scene):
        from ...element import Element
        from ...steppers import STEPPERS

        self.stepped = Element(scene)
        # every stepper a master may set, imported now (the registry imports one when first asked for): the
        # library is imported once per process, from the folder of the first instance, which may be gone by then
        # (FMPy deletes the folder it extracted after a run)
        for name in STEPPERS:
            STEPPERS[name]

    def parameters(self) -> dict:
        return dict(self.stepped.coefficients())

    def outputs(self, slave) -> dict:
        element = lambda: self.stepped  # noqa: E731
        getters = {
            "x": lambda: element().x,
            "v": lambda: element().v,
            "reaction": lambda: element().reaction_under(slave.values["F"], bool(slave.values["scene_load"])),
            "stiffness": lambda: element().stiffness(),
        }
        for name in ENERGIES:
            getters[name] = lambda name=name: element().energy_of(name)
        return getters

    @staticmethod
    def settings_problem(slave) -> "str | None":
        values = slave.values
        return settings_problem(slave.parameters, values["stepper"], values["step"], values["scene_load"])

    def settings_in_use(self) -> tuple:
        element = self.stepped
        return (element.coefficients(), element.stepper, element.h)

    def stability_problem(self) -> "str | None":
        return self.stepped.stability_problem()

    def hand_over(self, slave) -> bool:
        """Hand the parameters, stepper and step the master set to the element; False (logged) if refused."""
        from ...steppers import STEPPERS

        element, values = self.stepped, slave.values
        current = element.coefficients()
        changed = {name: value for name, value in slave.parameters.items() if value != current[name]}
        if changed:
            try:
                element.set_coefficients(**changed)
            except ValueError as exc:
                return slave._refuse(f"parameter {exc}; steps are refused until it is set right")
        stepper = values["stepper"]
        if stepper != element.stepper:
            if stepper not in STEPPERS:
                return slave._refuse(f"parameter stepper = {stepper!r} refused: must be one of "
                                     f"{', '.join(STEPPERS)}; steps are refused until it is set right")
            try:
                element.set_stepper(stepper)
            except ValueError as exc:
                return slave._refuse(f"parameter stepper = {stepper!r} refused: {exc}")
        step = values["step"]
        if step != element.h:
            if not (finite_number(step) and step > 0):
                return slave._refuse(f"parameter step = {step!r} refused: must be finite and > 0; "
                                     "steps are refused until it is set right")
            try:
                element.set_step(step)
            except ValueError as exc:  # a white noise's unit too coarse for it
                return slave._refuse(f"parameter {exc}; steps are refused until it is set right")
        return True

    @staticmethod
    def check_state(slave, settings: dict, parameters: dict) -> None:
        problem = settings_problem(parameters, settings["stepper"], settings["step"], settings["scene_load"])
        if problem:
            raise ValueError(problem)
        finite_settings(settings, ("F",))

    def restore(self, state: dict, settings: dict, noise) -> None:
        """Checks everything (the stepper with the state's noise) before changing anything."""
        self.stepped.set_state(state["element"], noise=noise)


class NetworkKind(Kind):
    """A network under a force at its load's node (``description.network_variables``): its stepper or step
    changed, the library's object is rebuilt in its state."""

    driven_by_force = True
    state_key = "network"
    where = "the load's node"
    misfit = "a parameter does not fit the network"

    def __init__(self, scene):
        from ...network import NetworkElement

        self.scene = scene
        self.stepped = NetworkElement(scene)

    def parameters(self) -> dict:
        return self.scene.network.parameters()

    def outputs(self, slave) -> dict:
        return {"reaction": lambda: self.stepped.reaction,
                **output_getters(self.scene.network, lambda: self.stepped)}

    def hand_over(self, slave) -> bool:
        """Hand the parameters, stepper and step the master set to the library; False (logged: fmi2Discard) if it
        refuses one, nothing changed then."""
        from ...scene import SceneError

        element, values = self.stepped, slave.values
        current = element.scene.network.parameters()
        changed = {name: value for name, value in slave.parameters.items() if not value == current[name]}
        if changed:
            try:
                element.set_parameters(**changed)
            except SceneError as exc:
                return slave._refuse(f"parameter {exc}; steps are refused until it is set right")
        if values["stepper"] != element.stepper or values["step"] != element.h:
            try:
                self.stepped = rebuilt(element, values["stepper"], values["step"])
            except (SceneError, ValueError, ElementError) as exc:
                return slave._refuse(f"parameter stepper = {values['stepper']!r}, step = {values['step']!r} "
                                     f"refused: {exc}; steps are refused until it is set right")
        return True

    def check_state(self, slave, settings: dict, parameters: dict) -> None:
        self.scene.network.with_parameters(**parameters)  # SceneError names a bad one
        finite_settings(settings, ("F",))
        if not isinstance(settings["scene_load"], bool):
            raise ValueError(f"scene_load = {settings['scene_load']!r}: must be true or false")

    def restore(self, state: dict, settings: dict, noise) -> None:
        self.stepped = restored(self.stepped, state["network"], settings["stepper"], settings["step"], noise)


class ConnectorKind(Kind):
    """The element as a connector (``description.connector_variables``): the outputs show it moved to the
    inputs set last (a preview, cached per input), ``doStep`` commits the sample at its communication point."""

    driven_by_force = False
    state_key = "connector"
    noun = "connector"
    fixed = "(an effect with memory)"

    def __init__(self, scene):
        from ...connector import Connector

        self.stepped = Connector(scene)

    def parameters(self) -> dict:
        return dict(self.stepped.coefficients())

    def outputs(self, slave) -> dict:
        current = lambda: self.current(slave)  # noqa: E731
        return {
            "force": lambda: current().force,
            "stiffness": lambda: current().stiffness(),
            "stored_energy": lambda: current().stored_energy(),
            "dissipated_sliders": lambda: current().energy()["dissipated_sliders"],
            "dissipated_damper": lambda: self.stepped.energy()["dissipated_damper"],
        }

    def current(self, slave):
        """The connector moved to the inputs set last, without committing (cached per input)."""
        key = (slave.values["x"], slave.values["v"], self.stepped._memo("revision", object))  # new per state
        return slave.preview(key, lambda preview: preview.move_to(slave.values["x"], slave.values["v"]),
                             self.stepped.copy)

    def hand_over(self, slave) -> "str | None":
        """None, or why a parameter set by the master is refused (nothing changed then)."""
        from ...scene import coefficient_problem

        for name, value in slave.parameters.items():
            problem = coefficient_problem(name, value)
            if problem:
                return f"parameter {name}: {problem}"
        changed = {name: value for name, value in slave.parameters.items()
                   if value != self.stepped.coefficients()[name]}
        if changed:
            try:
                self.stepped.set_coefficients(**changed)
            except ValueError as exc:
                return f"parameter {exc}"
        return None

    def start(self, slave) -> "str | None":
        """From x = 0 to the first input, monotonically."""
        connector = self.stepped
        connector.reset()
        connector.time = slave.start_time
        try:
            connector.move_to(slave.values["x"], slave.values["v"])
        except (ElementError, ValueError) as exc:
            connector.reset()
            return str(exc)
        return None

    def commit(self, slave, current_time, step_size) -> bool:
        """The input sample belongs to current_time: commit it (the master's clock may only move forward)."""
        connector, values = self.stepped, slave.values
        try:
            connector.move_to(values["x"], values["v"], max(float(current_time), connector.time))
        except ElementError as exc:  # an output would overflow: fmi2Discard, the connector unchanged
            return slave._refuse(f"step from t = {current_time!r} refused: {exc}")
        return True

    @staticmethod
    def check_state(slave, settings: dict, parameters: dict) -> None:
        from ...scene import coefficient_problem

        for name in ("x", "v", "start_time"):
            if not finite_number(settings[name]):
                raise ValueError(f"{name.replace('_', ' ')} = {settings[name]!r}: must be a finite number")
        for name, value in parameters.items():
            problem = coefficient_problem(name, value)
            if problem:
                raise ValueError(f"parameter {name}: {problem}")

    def restore(self, state: dict, settings: dict, noise) -> None:
        self.stepped.set_state(state["connector"])  # checks everything before changing anything


class NetworkConnectorKind(Kind):
    """A network as a connector (``description.network_connector_variables``): the inputs set at a communication
    point belong to that time; the outputs show the network moved to them at the FMU's current time (``time``),
    not committed; ``doStep`` commits the sample set at its communication point."""

    driven_by_force = False
    state_key = "network"

    def __init__(self, scene):
        from ...network import NetworkConnector

        self.scene = scene
        self.stepped = NetworkConnector(scene, stepper=NETWORK_STEPPER)
        self.time = 0.0  # the FMU's communication point: the time of the inputs set now

    def parameters(self) -> dict:
        network = self.scene.network
        load_mass = f"m_{network.nodes[network.load_node]}"  # 0: the motion is imposed there
        return {name: value for name, value in network.parameters().items() if name != load_mass}

    def outputs(self, slave) -> dict:
        return {"force": lambda: self.current(slave).force,
                **output_getters(self.scene.network, lambda: self.current(slave))}

    def current(self, slave):
        """The connector with the parameters set last, moved to the inputs set last at the FMU's current time,
        not committed (cached)."""
        problem = self.hand_over(slave)
        if problem is not None:  # no output is handed out for a network the library refuses
            slave._fail(f"{problem}: the outputs of a network with it are not numbers (a doStep would be refused)")
        connector, values = self.stepped, slave.values
        key = (values["x"], values["v"], self.time, connector._memo("revision", object))  # a new object per state
        return slave.preview(key, lambda preview: preview.move_to(values["x"], values["v"],
                                                                  max(self.time, connector.time)),
                             lambda: copy.deepcopy(connector))

    def hand_over(self, slave) -> "str | None":
        """None, or why the library refuses a parameter the master set (nothing changed then)."""
        from ...scene import SceneError

        connector, step = self.stepped, slave.values["step"]
        current = connector.scene.network.parameters()
        changed = {name: value for name, value in slave.parameters.items() if not value == current[name]}
        if changed:
            try:
                connector.set_parameters(**changed)
            except SceneError as exc:
                return f"parameter {exc}"
        if step != connector.h:
            try:
                self.stepped = rebuilt(connector, NETWORK_STEPPER, step)
            except (SceneError, ValueError, ElementError) as exc:
                return f"parameter step = {step!r} refused: {exc}"
        if changed or self.stepped is not connector:
            slave.forget_preview()
        return None

    def start(self, slave) -> "str | None":
        """The first sample, checked now (committed by the first doStep)."""
        self.stepped.reset()
        self.stepped.time = self.time = slave.start_time
        try:
            self.current(slave)
        except (ElementError, ValueError) as exc:
            return str(exc)
        return None

    def commit(self, slave, current_time, step_size) -> bool:
        """The input sample belongs to current_time: commit it (the connector's clock only moves forward)."""
        values = slave.values
        now, self.time = self.time, float(current_time)
        try:
            committed = self.current(slave)
        except ElementError as exc:  # the library cannot follow the motion: fmi2Discard, the connector as it was
            self.time = now
            return slave._refuse(f"step from t = {current_time!r} with x = {values['x']!r} refused: {exc}")
        except Refused:
            self.time = now
            raise
        except Exception as exc:
            self.time = now
            slave._fail(f"step from t = {current_time!r} with x = {values['x']!r} refused ({exc.__class__.__name__}: "
                        f"{exc}); the instance is unchanged")
        self.stepped = committed
        self.time = float(current_time) + float(step_size)
        return True

    def saved_clock(self) -> dict:
        return {"time": self.time}

    def check_state(self, slave, settings: dict, parameters: dict) -> None:
        self.scene.network.with_parameters(**parameters)  # SceneError names a bad one
        for name in ("x", "v", "start_time", "time"):
            if not finite_number(settings[name]):
                raise ValueError(f"{name.replace('_', ' ')} = {settings[name]!r}: must be a finite number")

    def restore(self, state: dict, settings: dict, noise) -> None:
        # the library checks the rest (the load node's mass is 0, the state fits the network)
        self.stepped = restored(self.stepped, state["network"], NETWORK_STEPPER, settings["step"])
        self.time = settings["time"]


KINDS = {(False, "force"): ElementKind, (False, "displacement"): ConnectorKind,
         (True, "force"): NetworkKind, (True, "displacement"): NetworkConnectorKind}


def output_getters(network, stepped) -> dict:
    """name -> getter of the outputs a network's FMU may have (``description.network_outputs``), read from the
    library's stepped object ``stepped()``."""
    getters = {}
    for i, node in enumerate(network.nodes):
        getters[f"x_{node}"] = lambda i=i: stepped().x[i]
        getters[f"v_{node}"] = lambda i=i: stepped().v[i]
    for name in ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
                 "energy_residual"):
        getters[name] = lambda name=name: stepped().energy()[name]
    for e, element in enumerate(network.elements):
        if element.kind in ("slider", "branch", "dashpot"):
            getters[f"dissipated_{element.kind}_{element.name}"] = lambda e=e: stepped().dissipated[e]
        if element.kind == "branch":
            getters[f"u_{element.name}"] = lambda e=e: stepped().elongation(e)  # as written: x_j - x_i
    return getters


def rebuilt(element, stepper, step):
    """The library's stepped object of ``element``'s network with another stepper or step, in its state (the
    library checks both: ValueError with the reason)."""
    if not isinstance(stepper, str) or not finite_number(step):
        raise ValueError("the stepper must be a name and the step a finite number")
    fresh = type(element)(element.scene, stepper=stepper, step=step, noise=element.noise)
    fresh.set_state(element.get_state())
    return fresh


def restored(element, network_state, stepper, step, noise=UNCHANGED):
    """A new stepped object like ``element`` with the parameters, stepper, step, white noise (default:
    ``element``'s; a connector has none of its own) and state of a saved FMU state; every check is the
    library's (ValueError, SceneError)."""
    noise = element.noise if noise is UNCHANGED else noise
    if not isinstance(network_state, dict) or not isinstance(network_state.get("parameters"), dict):
        raise ValueError("it holds no network state")
    if not isinstance(stepper, str) or not finite_number(step):
        raise ValueError(f"stepper = {stepper!r}, step = {step!r}: must be a name and a finite number")
    network = element.scene.network.with_parameters(**network_state["parameters"])
    fresh = type(element)(element.scene.with_network(network), stepper=stepper, step=step, noise=noise)
    fresh.set_state(network_state)
    return fresh
