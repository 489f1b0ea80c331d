"""A network as a connector: the motion of its load's node in, the force that holds it out; an FMI 2.0
co-simulation slave (PythonFMU).

Glue only: the library's :class:`~prandtl_fmu.network.NetworkConnector` computes every number. Built from a
network scene whose load node is massless, with ``[fmu] causality = "displacement"`` (or ``prandtl-fmu build
--causality displacement``).

Variables (a contract): inputs ``x`` (m) and ``v`` (m/s), the motion of the load's node, under the names the
element's connector FMU uses; output ``force`` (N), the force of the network's elements on that node; the
other nodes' ``x_<node>``, ``v_<node>``, the energy account and the elements' shares as in the network's
element FMU (``network_slave.py``); parameters: every coefficient by its scene name but the load node's mass
(0: the motion is imposed there), and ``step``.

Semantics: the inputs set at a communication point belong to that time. ``doStep(t, H)`` commits the sample
set at t (the library moves the load's node along a line from the last committed sample, in implicit steps of
``step``; the first sample is an instant move from the scene's x0). The outputs always show the network at the
inputs and parameters set last and the FMU's current time, without committing: ``force`` depends directly on
``x`` and ``v``, and a master may set x several times at one communication point.

Refusals: a non-finite input at ``doStep``, a motion the library cannot follow (``ElementError``) or a
parameter it refuses (``SceneError``) is logged and the step returns fmi2Discard with the state unchanged; an
output at inputs the library refuses is refused (fmi2Error, never NaN with fmi2OK); a bad value at
``fmi2ExitInitializationMode`` or a forged state fails that call with the logged reason.
"""
import copy

from ...stepping import ElementError
from ...network import NetworkConnector
from ...scene import SceneError
from .common import Refused, SlaveBase, finite_number, register_variables
from .network_slave import output_getters, rebuilt, restored

STEPPER = "implicit"  # the connector's only one: the imposed motion is a constraint


class PrandtlNetworkConnector(SlaveBase):
    """A network as a connector (module docstring); its variables: ``description.network_connector_variables``."""

    check_stepper = False  # the connector takes implicit steps whatever the scene's [solver] stepper

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        network = self.scene.network
        self.load_node = network.nodes[network.load_node]
        self.connector = NetworkConnector(self.scene, stepper=STEPPER)
        self.time = 0.0  # the FMU's communication point: the time of the inputs set now
        self.x = float(network.x0[network.load_node])  # the inputs as set last
        self.v = float(network.v0[network.load_node])
        self.step = self.connector.h
        self.parameters = {name: value for name, value in network.parameters().items()
                           if name != f"m_{self.load_node}"}
        self._preview_key = None
        self._preview = None
        self._register()

    # ------------------------------------------------------------ variables

    def _register(self):
        """The FMU's variables (``description.network_connector_variables``), each read and set here."""
        accessors = {
            "x": (lambda: self.x, lambda value: setattr(self, "x", value)),
            "v": (lambda: self.v, lambda value: setattr(self, "v", value)),
            "force": (lambda: self._current().force, None),
            "step": (lambda: self.step, lambda value: setattr(self, "step", value)),
            **output_getters(self.scene.network, self._current),
        }
        for name in self.parameters:
            accessors[name] = (lambda name=name: self.parameters[name],
                               lambda value, name=name: self.parameters.__setitem__(name, value))
        register_variables(self, accessors)

    # ------------------------------------------------------------ the network at the inputs

    def _current(self):
        """The connector with the parameters set last, moved to the inputs set last at the FMU's current time,
        not committed (cached)."""
        problem = self._hand_over_settings()
        if problem is not None:  # no output is handed out for a network the library refuses
            self._fail(f"{problem}: the outputs of a network with it are not numbers (a doStep would be refused)")
        connector = self.connector
        key = (self.x, self.v, self.time, connector._memo("revision", object))  # a new object per state
        if key != self._preview_key:
            if not (finite_number(self.x) and finite_number(self.v)):  # no output is handed out for it
                self._fail(f"input x = {self.x!r}, v = {self.v!r}: the outputs at a motion that is not finite are "
                           "not numbers (a doStep would be refused)")
            preview = copy.deepcopy(connector)
            preview.move_to(self.x, self.v, max(self.time, connector.time))
            self._preview_key, self._preview = key, preview
        return self._preview

    # ------------------------------------------------------------ stepping

    def exit_initialization_mode(self):
        problem = self._hand_over_settings()
        if problem is None and not (finite_number(self.x) and finite_number(self.v)):
            problem = f"input x = {self.x!r}, v = {self.v!r} refused: the motion must be finite"
        if problem is None:
            self.connector.reset()
            self.connector.time = self.start_time
            self.time = self.start_time
            try:  # the first sample, checked now (committed by the first doStep)
                self._current()
            except (ElementError, ValueError) as exc:
                problem = str(exc)
        if problem is not None:
            self._fail(f"initialization refused: {problem}")

    def _hand_over_settings(self):
        """None, or why the library refuses a parameter the master set (nothing changed then)."""
        connector = self.connector
        current = connector.scene.network.parameters()
        changed = {name: value for name, value in self.parameters.items() if not value == current[name]}
        if changed:
            try:
                connector.set_parameters(**changed)
            except SceneError as exc:
                return f"parameter {exc}"
        if self.step != connector.h:
            try:
                self.connector = rebuilt(connector, STEPPER, self.step)
            except (SceneError, ValueError, ElementError) as exc:
                return f"parameter step = {self.step!r} refused: {exc}"
        if changed or self.connector is not connector:
            self._preview_key = None
        return None

    def do_step(self, current_time, step_size):
        problem = self._communication_problem(current_time, step_size)
        if problem:
            self._fail(f"{problem}; the instance is unchanged")
        problem = self._hand_over_settings()
        if problem is not None:
            return self._refuse(f"{problem}; steps are refused until it is set right")
        if not (finite_number(self.x) and finite_number(self.v)):
            return self._refuse(f"input x = {self.x!r}, v = {self.v!r} refused: the motion must be finite; "
                                "step not taken")
        # the input sample belongs to current_time: commit it (the connector's clock only moves forward)
        now, self.time = self.time, float(current_time)
        try:
            committed = self._current()
        except ElementError as exc:  # the library cannot follow the motion: fmi2Discard, the connector as it was
            self.time = now
            return self._refuse(f"step from t = {current_time!r} with x = {self.x!r} refused: {exc}")
        except Refused:
            self.time = now
            raise
        except Exception as exc:
            self.time = now
            self._fail(f"step from t = {current_time!r} with x = {self.x!r} refused ({exc.__class__.__name__}: "
                       f"{exc}); the instance is unchanged")
        self.connector = committed
        self._preview_key = None
        self.time = float(current_time) + float(step_size)
        return True

    # ------------------------------------------------------------ FMU state

    def _get_fmu_state(self):
        return {"network": self.connector.get_state(),
                "settings": {"x": self.x, "v": self.v, "step": self.step, "parameters": dict(self.parameters),
                             "start_time": self.start_time, "time": self.time}}

    def _set_fmu_state(self, state):
        try:
            if not isinstance(state, dict) or "invalid" in state:
                raise ValueError(state.get("invalid") if isinstance(state, dict) else "not a state of this FMU")
            settings = state["settings"]
            parameters = dict(settings["parameters"])
            if set(parameters) != set(self.parameters):
                raise ValueError("its parameters are not this FMU's")
            self.scene.network.with_parameters(**parameters)  # SceneError names a bad one
            values = (settings["x"], settings["v"], settings["start_time"], settings["time"])
            for name, value in zip(("x", "v", "start time", "time"), values):
                if not finite_number(value):
                    raise ValueError(f"{name} = {value!r}: must be a finite number")
            # the library checks the rest (the load node's mass is 0, the state fits the network)
            connector = restored(self.connector, state["network"], STEPPER, settings["step"])
        except Exception as exc:  # any malformed or forged content: a reason, the instance unchanged
            self._fail(f"FMU state refused ({exc.__class__.__name__}: {exc}); the instance is unchanged")
        self.connector = connector
        self.x, self.v, self.start_time, self.time = values
        self.step = settings["step"]
        self.parameters = parameters
        self._preview_key = None
