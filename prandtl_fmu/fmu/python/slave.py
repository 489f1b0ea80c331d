"""The Prandtl element as an FMI 2.0 co-simulation slave (PythonFMU).

Glue only: this class maps FMU variables to the library's :class:`Element`
and back; every number is computed by the library. In an FMU this module is
part of the library copy in ``resources/prandtl_fmu``, imported under a
private name by the entry point (``entry.py``, see there).

Stepping: ``do_step(t, H)`` advances by whole internal steps of ``step`` and,
when H is not a multiple of it, one shorter last step for the remainder, with
the input F held at the value set before the call. With the parameter
``scene_load`` true the force is F plus the scene's ``[load]`` F_scene(t),
evaluated by the stepper at every internal step exactly as the library does:
with no input connected, the FMU then reproduces ``simulate`` of its scene.
The parameters ``noise_intensity``, ``noise_seed`` and ``noise_unit`` add a
white noise sigma xi(t) that the FMU generates (start values: the scene's
[load] noise, or none), with or without ``scene_load``: its path is a function
of (seed, time) alone, so a rolled-back step redraws the same increments.

Refusals: a non-finite F, a parameter outside its range or a step that would
leave a non-finite state during stepping is refused: a message naming the
variable and the value is logged, ``do_step`` returns fmi2Discard, and the
state is exactly what it was before (a master may set a good value and step
again; FMPy's ``simulate_fmu`` ends the run early on a Discard).

A bad start value (set before or during initialization) is refused at
``fmi2ExitInitializationMode``, a fixed parameter (x0, v0) set after
initialization where it is set, and a state of another FMU or a tampered
blob at ``fmi2SetFMUstate``/``fmi2DeSerializeFMUstate``: the reason is logged
and the call fails, so that a master such as FMPy raises with that reason.
Such a call fails with fmi2Error under the FMU's own loader (fmi2Fatal under
PythonFMU's stock one, see ``common.py``); the instance stays intact. So
does a non-finite clock or a negative communication step (``fmi2DoStep``),
an unknown value reference, a variable of another type, and a getter whose
value is not a finite number: no Real is handed out with fmi2OK unless it is
finite. A step the library cannot take (``ElementError``: its step budget, a
non-finite result) is a Discard with the library's reason.
"""

from pythonfmu.enums import Fmi2Status

from ...element import Element
from ...stepping import ElementError
from ...loads import force_at
from ...steppers import STEPPERS
from ..description import scene_load_notice, scene_load_start
from .common import NoiseParameters, SlaveBase, finite_number, register_variables

# the energy account's outputs (those of the effects present are the FMU's: description.element_variables)
ENERGIES = ("kinetic_energy", "stored_energy", "work", "dissipated_sliders", "dissipated_damper",
            "dissipated_friction", "energy_residual")

def settings_problem(parameters: dict, stepper, step, scene_load) -> "str | None":
    """Why the parameters a master set (or a saved state holds) cannot be used, or None."""
    from ...scene import coefficient_problem

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


class PrandtlElement(NoiseParameters, SlaveBase):
    """The element under a force (module docstring); its variables: ``description.element_variables``."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.element = Element(self.scene)
        self.initialized = False  # after fmi2ExitInitializationMode: fixed parameters are frozen
        # What the master set; checked and handed to the element at each step.
        self.F = 0.0
        self.scene_load = scene_load_start(self.scene)  # true when the scene names a load
        self.stepper = self.element.stepper
        self.step = self.element.h
        self._handed_over = None  # (parameters, stepper, step) as last handed to the element
        self.parameters = dict(self.element.coefficients())
        self._init_noise()
        self._register()

    # ------------------------------------------------------------ variables

    def _register(self):
        """The FMU's variables (``description.element_variables``), each read and set here."""
        element = lambda: self.element  # noqa: E731
        accessors = {
            "F": (lambda: self.F, lambda value: setattr(self, "F", value)),
            "x": (lambda: element().x, None),
            "v": (lambda: element().v, None),
            "reaction": (lambda: element().reaction_under(self.F, bool(self.scene_load)), None),
            "stiffness": (lambda: element().stiffness(), None),
            "step": (lambda: self.step, lambda value: setattr(self, "step", value)),
            "scene_load": (lambda: self.scene_load, lambda value: setattr(self, "scene_load", value)),
            "stepper": (lambda: self.stepper, lambda value: setattr(self, "stepper", value)),
            "n": (lambda: self.n, None),
            **self._noise_accessors(),
        }
        for name in ENERGIES:
            accessors[name] = (lambda name=name: element().energy_of(name), None)
        for name in self.parameters:
            accessors[name] = (lambda name=name: self.parameters[name],
                               lambda value, name=name: self._set_parameter(name, value))
        self._fixed = register_variables(self, accessors)

    # ------------------------------------------------------------ stepping

    def exit_initialization_mode(self):
        problem = self._settings_problem()
        if problem is None and not finite_number(self.F):
            problem = f"F = {self.F!r} refused: the force must be finite"
        if problem is None:
            if not self._hand_over_settings():  # e.g. a stepper that does not apply (logged)
                problem = self.log_queue[-1].msg if self.log_queue else "a parameter does not fit the scene"
            else:
                try:  # a massless element starts in equilibrium with the force at the start
                    self.element.reset(self._force_at_start())
                except (ElementError, ValueError) as exc:
                    problem = str(exc)
        if problem is not None:
            self._fail(f"initialization refused: {problem}")
        self.element.time = self.start_time
        self._handed_over = None  # the next step compares the settings again
        self.initialized = True
        self._warn_if_unstable()
        if self.scene_load:  # a master that connects F is told that the scene's load is added (whatever loggingOn)
            self.log(scene_load_notice(self.scene, "the element"), Fmi2Status.warning, category="logStatusWarning")

    def _force_at_start(self) -> float:
        if self.scene_load:
            return self.F + float(force_at(self.scene.load.compile(), self.start_time))
        return self.F

    def _set_parameter(self, name, value):
        """Setter of an effect's parameter: a fixed one (x0, v0) cannot change after initialization."""
        if self.initialized and name in self._fixed and value != self.parameters[name]:
            self._fail(f"parameter {name} = {value!r} refused: {name} is fixed (the initial state, or an effect "
                       "with memory) and cannot change after initialization; the element is unchanged")
        self.parameters[name] = value

    def _settings_problem(self):
        """Why a parameter the master set cannot be used, or None."""
        return settings_problem(self.parameters, self.stepper, self.step, self.scene_load)

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
        except ElementError as exc:  # the step cannot be taken (budget, a non-finite result): fmi2Discard
            element.rollback(saved)
            return self._refuse(f"step from t = {current_time!r} with F = {force!r} refused: {exc}")
        except Exception as exc:  # a bad input the checks above missed: fmi2Error, the element as it was
            element.rollback(saved)
            self._fail(f"step from t = {current_time!r} with F = {force!r} refused ({exc.__class__.__name__}: "
                       f"{exc}); the instance is unchanged")
        return True  # Element.advance refuses (ElementError) a step that would leave any output non-finite

    def _apply_settings(self) -> bool:
        """Hand the parameters the master set to the element; False (logged) if one is refused. Nothing to do
        (the usual step) when they are those handed over last."""
        settings = (tuple(self.parameters.values()), self.stepper, self.step, self._noise_settings())
        if settings == self._handed_over:
            return True
        element = self.element
        before = (element.coefficients(), element.stepper, element.h)
        accepted = self._hand_over_settings()
        if accepted and (element.coefficients(), element.stepper, element.h) != before:
            self._warn_if_unstable()
        self._handed_over = settings if accepted else None
        return accepted

    def _warn_if_unstable(self):
        problem = self.element.stability_problem()
        if problem:
            self.log(problem, Fmi2Status.warning)

    def _hand_over_settings(self) -> bool:
        element = self.element
        # a noise turned off goes first and one turned on last: the stepper's check sees the noise that will
        # be there (some steppers take none)
        noise_first = not self.noise_intensity
        if noise_first and not self._hand_over_noise(element):
            return False
        current = element.coefficients()
        changed = {name: value for name, value in self.parameters.items() if value != current[name]}
        if changed:
            try:
                element.set_coefficients(**changed)
            except ValueError as exc:
                return self._refuse(f"parameter {exc}; steps are refused until it is set right")
        if self.stepper != element.stepper:
            if self.stepper not in STEPPERS:
                return self._refuse(f"parameter stepper = {self.stepper!r} refused: must be one of "
                                    f"{', '.join(STEPPERS)}; steps are refused until it is set right")
            try:
                element.set_stepper(self.stepper)
            except ValueError as exc:
                return self._refuse(f"parameter stepper = {self.stepper!r} refused: {exc}")
        if self.step != element.h:
            step = self.step
            if not (finite_number(step) and step > 0):
                return self._refuse(f"parameter step = {step!r} refused: must be finite and > 0; "
                                    "steps are refused until it is set right")
            try:
                element.set_step(step)
            except ValueError as exc:  # a white noise's unit too coarse for it
                return self._refuse(f"parameter {exc}; steps are refused until it is set right")
        return noise_first or self._hand_over_noise(element)

    # ------------------------------------------------------------ FMU state

    def _get_fmu_state(self):
        """The whole state as plain data (PythonFMU serializes it as JSON: no code can hide in it)."""
        return {
            "element": self.element.get_state(),
            "settings": {"F": self.F, "step": self.step, "stepper": self.stepper, "scene_load": bool(self.scene_load),
                         "parameters": dict(self.parameters), "start_time": self.start_time, **self._noise_state()},
        }

    def _set_fmu_state(self, state):
        try:
            if not isinstance(state, dict) or "invalid" in state:
                raise ValueError(state.get("invalid") if isinstance(state, dict) else "not a state of this FMU")
            settings = state["settings"]
            parameters = dict(settings["parameters"])
            if set(parameters) != set(self.parameters):
                raise ValueError("its parameters are not this FMU's")
            values = (settings["F"], settings["step"], settings["stepper"], settings["start_time"])
            problem = settings_problem(parameters, settings["stepper"], settings["step"], settings["scene_load"])
            if problem is None and not (finite_number(settings["F"]) and finite_number(settings["start_time"])):
                problem = f"F = {settings['F']!r}, start time {settings['start_time']!r}: must be finite numbers"
            if problem:
                raise ValueError(problem)
            noise = self._check_noise_state(settings)
            # checks everything (the stepper with the state's noise) before changing anything
            self.element.set_state(state["element"], noise=noise)
        except Exception as exc:  # any malformed or forged content (IndexError, OverflowError, ...): a reason
            self._fail(f"FMU state refused ({exc.__class__.__name__}: {exc}); the instance is unchanged")
        self.F, self.step, self.stepper, self.start_time = values
        self.scene_load = settings["scene_load"]
        self.parameters = parameters
        self._set_noise_values(settings)
        self._handed_over = None
