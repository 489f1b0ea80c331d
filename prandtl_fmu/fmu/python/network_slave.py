"""A network (``[network]`` or ``[chain]`` scene) under a force at its load's node: an FMI 2.0 co-simulation slave
(PythonFMU).

Glue only: the library's :class:`~prandtl_fmu.network.NetworkElement` computes every number; this class maps
FMU variables to it and back.

Variables (a contract, the same names as the library's CSV columns):

* input ``F`` (N): the force on the load's node, held over each communication step;
* outputs ``x_<node>`` (m), ``v_<node>`` (m/s) of every node, ``reaction`` (N: the force of the elements on
  the ground), the energy account under the element FMU's names (``kinetic_energy``, ``stored_energy``,
  ``work``, ``dissipated_sliders``, ``dissipated_damper``, ``energy_residual``), the share of every
  dissipating element ``dissipated_<kind>_<name>`` and the elongation ``u_<branch>`` of every branch;
* parameters: every coefficient of the network by its scene name (``Network.parameters()``: ``m_<node>``,
  ``k_<spring>``, ``c_<dashpot>``, ``alpha_<slider>``, ``k_``/``eta_``/``c_<branch>``, ``k3_<cubic>``), and
  ``step``, ``stepper`` (``implicit``, or ``projected`` where the network allows it), ``scene_load``, and the
  white noise the FMU adds to F, ``noise_intensity``, ``noise_seed``, ``noise_unit`` (start values: the scene's
  [load] noise, or none).

Stepping, refusals and FMU states follow the element's slave (``slave.py``): ``do_step(t, H)`` advances by
whole internal steps of ``step`` and one shorter last step for a remainder, with F held (plus the scene's
[load] with ``scene_load``: with no input connected the FMU then reproduces ``network.simulate`` of its
scene). A step the library cannot take (``ElementError``: no equilibrium of a massless part, the step budget,
an overflow) and a parameter the library refuses (``SceneError``) are fmi2Discard with the library's reason
logged, the state unchanged; a bad value at initialization, a forged state and a bad call fail that call
(fmi2Error under the FMU's own loader) with the reason logged, the instance intact. No output is handed out
with fmi2OK unless it is a finite number.

The outputs after ``doStep(t, H)`` are those of the network at t + H under the F held over the step: none
depends directly on F (a master that sets F sees the outputs change at the next step).
"""

from pythonfmu.enums import Fmi2Status

from ...stepping import UNCHANGED, ElementError
from ...loads import force_at
from ...network import NetworkElement
from ...scene import SceneError
from ..description import scene_load_notice, scene_load_start
from .common import NoiseParameters, SlaveBase, finite_number, register_variables


class PrandtlNetwork(NoiseParameters, SlaveBase):
    """A network under a force (module docstring); its variables: ``description.network_variables``."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.element = NetworkElement(self.scene)
        self.initialized = False
        # what the master set; checked and handed to the library at each step
        self.F = 0.0
        self.scene_load = scene_load_start(self.scene)  # true when the scene names a load
        self.stepper = self.element.stepper
        self.step = self.element.h
        self._handed_over = None
        self.parameters = self.scene.network.parameters()
        self._init_noise()
        self._register()

    # ------------------------------------------------------------ variables

    def _register(self):
        """The FMU's variables (``description.network_variables``), each read and set here."""
        accessors = {
            "F": (lambda: self.F, lambda value: setattr(self, "F", value)),
            "reaction": (lambda: self.element.reaction, None),
            "step": (lambda: self.step, lambda value: setattr(self, "step", value)),
            "scene_load": (lambda: self.scene_load, lambda value: setattr(self, "scene_load", value)),
            "stepper": (lambda: self.stepper, lambda value: setattr(self, "stepper", value)),
            **self._noise_accessors(),
            **output_getters(self.scene.network, lambda: self.element),
        }
        for name in self.parameters:
            accessors[name] = (lambda name=name: self.parameters[name],
                               lambda value, name=name: self.parameters.__setitem__(name, value))
        register_variables(self, accessors)

    # ------------------------------------------------------------ stepping

    def exit_initialization_mode(self):
        problem = None
        if not finite_number(self.F):
            problem = f"F = {self.F!r} refused: the force must be finite"
        elif not self._hand_over_settings():
            problem = self.log_queue[-1].msg if self.log_queue else "a parameter does not fit the network"
        else:
            try:  # a massless part starts in equilibrium with the force at the start
                self.element.reset(self._force_at_start())
            except (ElementError, ValueError) as exc:
                problem = str(exc)
        if problem is not None:
            self._fail(f"initialization refused: {problem}")
        self.element.time = self.start_time
        self._handed_over = None
        self.initialized = True
        if self.scene_load:  # a master that connects F is told that the scene's load is added (whatever loggingOn)
            self.log(scene_load_notice(self.scene, "the load's node"), Fmi2Status.warning,
                     category="logStatusWarning")

    def _force_at_start(self) -> float:
        if self.scene_load:
            return self.F + float(force_at(self.scene.load.compile(), self.start_time))
        return self.F

    def do_step(self, current_time, step_size):
        problem = self._communication_problem(current_time, step_size)
        if problem:
            self._fail(f"{problem}; the instance is unchanged")
        if not self._apply_settings():
            return False
        force = self.F
        if not finite_number(force):
            return self._refuse(f"F = {force!r} refused: the force must be finite; step not taken")
        element = self.element
        saved = element.checkpoint()
        try:
            element.time = current_time
            element.advance(step_size, force, scene_load=bool(self.scene_load))
        except ElementError as exc:  # the library cannot take the step: fmi2Discard, the state as it was
            element.rollback(saved)
            return self._refuse(f"step from t = {current_time!r} with F = {force!r} refused: {exc}")
        except Exception as exc:  # a bad argument the checks above missed: fmi2Error, the state as it was
            element.rollback(saved)
            self._fail(f"step from t = {current_time!r} with F = {force!r} refused ({exc.__class__.__name__}: "
                       f"{exc}); the instance is unchanged")
        return True  # NetworkElement.advance refuses (ElementError) a step that leaves an output non-finite

    def _apply_settings(self) -> bool:
        settings = (tuple(self.parameters.values()), self.stepper, self.step, self._noise_settings())
        if settings == self._handed_over:
            return True
        accepted = self._hand_over_settings()
        self._handed_over = settings if accepted else None
        return accepted

    def _hand_over_settings(self) -> bool:
        """Hand the parameters, stepper and step the master set to the library; False (logged: fmi2Discard) if it
        refuses one, nothing changed then."""
        element = self.element
        # a noise turned off goes first and one turned on last: a mass's check sees the noise that will be
        # there (a massless load node needs a dashpot under a noise)
        noise_first = not self.noise_intensity
        if noise_first and not self._hand_over_noise(element):
            return False
        current = element.scene.network.parameters()
        changed = {name: value for name, value in self.parameters.items() if not value == current[name]}
        if changed:
            try:
                element.set_parameters(**changed)
            except SceneError as exc:
                return self._refuse(f"parameter {exc}; steps are refused until it is set right")
        if self.stepper != element.stepper or self.step != element.h:
            try:
                self.element = rebuilt(element, self.stepper, self.step)
            except (SceneError, ValueError, ElementError) as exc:
                return self._refuse(f"parameter stepper = {self.stepper!r}, step = {self.step!r} refused: {exc}; "
                                    "steps are refused until it is set right")
        return noise_first or self._hand_over_noise(self.element)

    # ------------------------------------------------------------ FMU state

    def _get_fmu_state(self):
        """The whole state as plain data (PythonFMU serializes it as JSON: no code can hide in it)."""
        return {"network": self.element.get_state(),
                "settings": {"F": self.F, "step": self.step, "stepper": self.stepper,
                             "scene_load": bool(self.scene_load), "parameters": dict(self.parameters),
                             "start_time": self.start_time, **self._noise_state()}}

    def _set_fmu_state(self, state):
        try:
            if not isinstance(state, dict) or "invalid" in state:
                raise ValueError(state.get("invalid") if isinstance(state, dict) else "not a state of this FMU")
            settings = state["settings"]
            parameters = dict(settings["parameters"])
            if set(parameters) != set(self.parameters):
                raise ValueError("its parameters are not this FMU's")
            self.scene.network.with_parameters(**parameters)  # SceneError names a bad one
            values = (settings["F"], settings["step"], settings["stepper"], settings["start_time"])
            if not (finite_number(settings["F"]) and finite_number(settings["start_time"])):
                raise ValueError(f"F = {settings['F']!r}, start time {settings['start_time']!r}: must be finite "
                                 "numbers")
            if not isinstance(settings["scene_load"], bool):
                raise ValueError(f"scene_load = {settings['scene_load']!r}: must be true or false")
            noise = self._check_noise_state(settings)
            element = restored(self.element, state["network"], settings["stepper"], settings["step"], noise)
        except Exception as exc:  # any malformed or forged content: a reason, the instance unchanged
            self._fail(f"FMU state refused ({exc.__class__.__name__}: {exc}); the instance is unchanged")
        self.element = element
        self.F, self.step, self.stepper, self.start_time = values
        self.scene_load = settings["scene_load"]
        self.parameters = parameters
        self._set_noise_values(settings)
        self._handed_over = None


def output_getters(network, stepped) -> dict:
    """name -> (getter, None) of the outputs a network's FMU may have (``description.network_outputs``), read from
    the library's stepped object ``stepped()``."""
    getters = {}
    for i, node in enumerate(network.nodes):
        getters[f"x_{node}"] = (lambda i=i: stepped().x[i], None)
        getters[f"v_{node}"] = (lambda i=i: stepped().v[i], None)
    for name in ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
                 "energy_residual"):
        getters[name] = (lambda name=name: stepped().energy()[name], None)
    for e, element in enumerate(network.elements):
        if element.kind in ("slider", "branch", "dashpot"):
            getters[f"dissipated_{element.kind}_{element.name}"] = (lambda e=e: stepped().dissipated[e], None)
        if element.kind == "branch":
            getters[f"u_{element.name}"] = (lambda e=e: stepped().u[e], None)
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
