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

from pythonfmu import Fmi2Causality, Fmi2Variability, Integer

from .. import __version__
from ..connector import Connector
from ..stepping import ElementError
from ..scene import coefficient_problem
from .common import DBL_MAX, SMALLEST, SlaveBase, finite_number
from .description import RealVariable, complete
from .slave import memory_parameters
from .documentation import reaction_formula, stiffness_formula, stored_energy_formula

PARAMETERS = [  # (name, table of the scene, unit, description)
    ("k0", "spring", "N/m", "stiffness of the linear spring: force k0 x"),
    ("k3", "cubic", "N/m3", "coefficient of the cubic spring: force k3 x^3"),
    ("c", "damper", "N.s/m", "dashpot coefficient: force c v"),
]


class PrandtlConnector(SlaveBase):
    author = "prandtl_fmu"
    description = ("Generalized Prandtl element (dry-friction hysteresis) as a connector between two bodies: "
                   "relative motion x, v in, force out; the springs, dashpot and Prandtl branches of its scene "
                   "(documentation/index.html)")
    version = __version__

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
        real = RealVariable
        self.register_variable(real(
            "x", unit="m", causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
            min=-DBL_MAX, max=DBL_MAX, start=0.0,
            description="relative displacement of the two flanges (linear between communication points)",
            getter=lambda: self.x, setter=lambda value: setattr(self, "x", value)))
        self.register_variable(real(
            "v", unit="m/s", causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
            min=-DBL_MAX, max=DBL_MAX, start=0.0, description="relative velocity of the two flanges",
            getter=lambda: self.v, setter=lambda value: setattr(self, "v", value)))
        outputs = [
            ("force", "N", f"force the element transmits: {reaction_formula(self.scene)}",
             lambda: self._current().force),
            ("stiffness", "N/m", "tangent stiffness dF/dx for a motion in the direction of v (of the last motion "
             f"when v = 0): {stiffness_formula(self.scene)}", lambda: self._current().stiffness()),
            ("stored_energy", "J", f"elastic energy {stored_energy_formula(self.scene)}",
             lambda: self._current().stored_energy()),
        ]
        if self.scene.branches is not None:
            outputs.append(("dissipated_sliders", "J", "work dissipated by the sliders since the start: "
                            "sum alpha_i |slip_i|", lambda: self._current().energy()["dissipated_sliders"]))
        if self.scene.damper is not None or self.scene.has_series_dashpots:
            outputs.append(("dissipated_damper", "J", "work dissipated by the dashpot and the branches' series "
                            "dashpots up to the last doStep (v linear between communication points)",
                            lambda: self.connector.energy()["dissipated_damper"]))
        for name, unit, text, getter in outputs:
            self.register_variable(real(name, unit=unit, causality=Fmi2Causality.output,
                                        variability=Fmi2Variability.continuous, description=text, getter=getter))
        parameters = list(PARAMETERS)
        for name in self.parameters:
            if name.startswith("c_branch"):
                which = "every branch" if name == "c_branch" else f"branch {name[9:-1]}"
                parameters.append((name, "branches", "N.s/m", f"dashpot in series with the spring and slider of "
                                   f"{which} (the force relaxes over the time between samples); must be > 0"))
        for name, table, unit, text in parameters:
            if name not in self.parameters:
                continue  # an absent effect has no parameter
            self.register_variable(real(
                name, unit=unit, causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable,
                min=SMALLEST if name.startswith("c_branch") else 0.0, max=DBL_MAX, description=text, getter=lambda name=name: self.parameters[name],
                setter=lambda value, name=name: self.parameters.__setitem__(name, value)))
        for name, table, unit, low, variability, text in memory_parameters(self.scene, self.parameters):
            self.register_variable(real(
                name, unit=unit, causality=Fmi2Causality.parameter, variability=variability, min=low, max=DBL_MAX,
                description=text, getter=lambda name=name: self.parameters[name],
                setter=lambda value, name=name: self._set_fixed(name, value)))
        self.register_variable(Integer(
            "n", causality=Fmi2Causality.local, variability=Fmi2Variability.constant,
            description="number of Prandtl branches (from the scene); -1 for the continuous element",
            getter=lambda: self.n))

    def to_xml(self, model_options=dict()):
        root = super().to_xml(model_options)
        # The force depends directly on both inputs (springs on x, dashpot on v); the stiffness on x (the
        # cubic spring, which branches stick) and on v (the direction); the energies on x.
        depends = {"force": ("x", "v"), "stiffness": ("x", "v"), "stored_energy": ("x",),
                   "dissipated_sliders": ("x",)}
        return complete(root, list(self.vars.values()), output_dependencies=depends)

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

    def _set_fixed(self, name, value):
        """Setter of a fixed parameter (an effect with memory): refused after initialization."""
        if getattr(self, "_initialized", False) and value != self.parameters[name]:
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

