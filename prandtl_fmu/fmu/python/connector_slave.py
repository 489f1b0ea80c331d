"""The element as a connector between two bodies: an FMI 2.0 co-simulation slave (PythonFMU).

Glue only: the library's :class:`~prandtl_fmu.connector.Connector` computes
every number. Built from a massless scene with ``[fmu] causality =
"displacement"`` (or ``prandtl-fmu build --causality displacement``).

Variables (a contract): inputs ``x`` (m) and ``v`` (m/s), the relative
displacement and velocity of the two flanges; outputs ``force`` (N) =
k0 x + k3 x^3 + c v + sum_i k_i u_i, ``stiffness`` (N/m, the tangent dF/dx),
``stored_energy``, ``dissipated_sliders`` (J) and, with a dashpot,
``dissipated_damper`` (J); parameters ``k0``, ``k3``, ``c`` of the effects present.

Semantics. The outputs always show the element at the inputs set last: the
branches taken from the last committed x to the input x by the exact play
update (x linear in between: a master that gives only the end value of a
step gets the linear interpolant; the play operator is rate independent, so
the time between samples does not matter). ``force`` therefore depends
directly on ``x`` and ``v`` (declared in the model structure), and a master
may set x several times at one communication point (iterations) without
moving the element: only ``doStep`` commits the input sample. Initialization
takes the element from x = 0 (the scene's u0) to the first input x.

Refusals: a non-finite input at ``doStep``, or a sample whose outputs would
overflow, is logged and the step returns fmi2Discard with the state
unchanged; the outputs at a non-finite input are refused (fmi2Error, never
NaN with fmi2OK); a bad parameter or input at ``fmi2ExitInitializationMode``
fails that call with the logged reason.
"""

from ...connector import Connector
from ...stepping import ElementError
from ...scene import coefficient_problem
from .common import SlaveBase, finite_number, register_variables


class PrandtlConnector(SlaveBase):
    """The element as a connector (module docstring); its variables: ``description.connector_variables``."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.connector = Connector(self.scene)
        self.x = 0.0  # the inputs as set last
        self.v = 0.0
        self.parameters = dict(self.connector.coefficients())
        self._preview_key = None  # (x, v, coefficients) of the cached preview
        self._preview = None
        self._register()

    # ------------------------------------------------------------ variables

    def _register(self):
        """The FMU's variables (``description.connector_variables``), each read and set here."""
        accessors = {
            "x": (lambda: self.x, lambda value: setattr(self, "x", value)),
            "v": (lambda: self.v, lambda value: setattr(self, "v", value)),
            "force": (lambda: self._current().force, None),
            "stiffness": (lambda: self._current().stiffness(), None),
            "stored_energy": (lambda: self._current().stored_energy(), None),
            "dissipated_sliders": (lambda: self._current().energy()["dissipated_sliders"], None),
            "dissipated_damper": (lambda: self.connector.energy()["dissipated_damper"], None),
            "n": (lambda: self.n, None),
        }
        for name in self.parameters:
            accessors[name] = (lambda name=name: self.parameters[name],
                               lambda value, name=name: self._set_parameter(name, value))
        self._fixed = register_variables(self, accessors)

    # ------------------------------------------------------------ the element at the inputs

    def _current(self):
        """The connector moved to the inputs set last, without committing (cached per input)."""
        key = (self.x, self.v, self.connector._memo("revision", object))  # a new object per state
        if key != self._preview_key:
            if not (finite_number(self.x) and finite_number(self.v)):  # no output is handed out for it
                self._fail(f"input x = {self.x!r}, v = {self.v!r}: the outputs at a motion that is not finite are "
                           "not numbers (a doStep would be refused)")
            preview = self.connector.copy()
            preview.move_to(self.x, self.v)
            self._preview_key, self._preview = key, preview
        return self._preview

    # ------------------------------------------------------------ stepping

    def exit_initialization_mode(self):
        problem = self._hand_over_parameters()
        if problem is None and not (finite_number(self.x) and finite_number(self.v)):
            problem = f"input x = {self.x!r}, v = {self.v!r} refused: the motion must be finite"
        if problem is not None:
            self._fail(f"initialization refused: {problem}")
        self.connector.reset()
        self.connector.time = self.start_time
        try:
            self.connector.move_to(self.x, self.v)  # from x = 0 to the first input, monotonically
        except (ElementError, ValueError) as exc:
            self.connector.reset()
            self._fail(f"initialization refused: {exc}")
        self._initialized = True

    def _set_parameter(self, name, value):
        """Setter of a parameter: a fixed one (an effect with memory) is refused after initialization."""
        if name in self._fixed and getattr(self, "_initialized", False) and value != self.parameters[name]:
            self._fail(f"parameter {name} = {value!r} refused: {name} is fixed (an effect with memory) and cannot "
                       "change after initialization; the connector is unchanged")
        self.parameters[name] = value

    def _hand_over_parameters(self):
        """None, or why a parameter set by the master is refused (nothing changed then)."""
        for name, value in self.parameters.items():
            problem = coefficient_problem(name, value)
            if problem:
                return f"parameter {name}: {problem}"
        changed = {name: value for name, value in self.parameters.items()
                   if value != self.connector.coefficients()[name]}
        if changed:
            try:
                self.connector.set_coefficients(**changed)
            except ValueError as exc:
                return f"parameter {exc}"
        return None

    def do_step(self, current_time, step_size):
        problem = self._communication_problem(current_time, step_size)
        if problem:
            self._fail(f"{problem}; the instance is unchanged")
        problem = self._hand_over_parameters()
        if problem is not None:
            return self._refuse(f"{problem}; steps are refused until it is set right")
        if not (finite_number(self.x) and finite_number(self.v)):
            return self._refuse(f"input x = {self.x!r}, v = {self.v!r} refused: the motion must be finite; "
                                "step not taken")
        connector = self.connector
        # the input sample belongs to current_time: commit it (the master's clock may only move forward)
        try:
            connector.move_to(self.x, self.v, max(float(current_time), connector.time))
        except ElementError as exc:  # an output would overflow: fmi2Discard, the connector unchanged
            return self._refuse(f"step from t = {current_time!r} refused: {exc}")
        self._preview_key = None
        return True

    # ------------------------------------------------------------ FMU state

    def _get_fmu_state(self):
        return {"connector": self.connector.get_state(),
                "settings": {"x": self.x, "v": self.v, "parameters": dict(self.parameters),
                             "start_time": self.start_time}}

    def _set_fmu_state(self, state):
        try:
            if not isinstance(state, dict) or "invalid" in state:
                raise ValueError(state.get("invalid") if isinstance(state, dict) else "not a state of this FMU")
            settings = state["settings"]
            parameters = dict(settings["parameters"])
            if set(parameters) != set(self.parameters):
                raise ValueError("its parameters are not this FMU's")
            values = (settings["x"], settings["v"], settings["start_time"])
            for name, value in zip(("x", "v", "start time"), values):
                if not finite_number(value):
                    raise ValueError(f"{name} = {value!r}: must be a finite number")
            for name, value in parameters.items():
                problem = coefficient_problem(name, value)
                if problem:
                    raise ValueError(f"parameter {name}: {problem}")
            self.connector.set_state(state["connector"])  # checks everything before changing anything
        except Exception as exc:  # any malformed or forged content (IndexError, OverflowError, ...): a reason
            self._fail(f"FMU state refused ({exc.__class__.__name__}: {exc}); the instance is unchanged")
        self.x, self.v, self.start_time = values
        self.parameters = parameters
        self._preview_key = None

