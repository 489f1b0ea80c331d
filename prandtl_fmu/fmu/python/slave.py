"""The FMU of a scene as an FMI 2.0 co-simulation slave (PythonFMU): one class for every kind of FMU.

Glue only: :class:`PrandtlSlave` maps the FMU's variables (``description.variables`` of its scene: the element,
the connector, a network or a network's connector, as the scene's kind and ``[fmu] causality`` say) to the
library's stepped object and back, through the kind's description (``kinds.py``: its library object, its
outputs' getters, how settings are handed over, the step call); every number is computed by the library. In an
FMU this module is part of the library copy in ``resources/prandtl_fmu``, imported under a private name by the
entry point (``entry.py``, see there).

The inputs and the settings (F or x, v; ``step``, ``stepper``, ``scene_load``, ``noise_*``) start at their
description's start values and are held in :attr:`PrandtlSlave.values`; the parameters of the effects (or the
network's coefficients) in :attr:`PrandtlSlave.parameters`. Both are checked and handed to the library at
initialization and at each step.

Driven by a force (the element, a network): ``do_step(t, H)`` advances by whole internal steps of ``step`` and,
when H is not a multiple of it, one shorter last step for the remainder (a remainder below 1e-9 h is a master's
clock's rounding: no step), with the input F held at the value set before the call. With the parameter
``scene_load`` true (its start when the scene names a load; leaving initialization with it logs a warning,
whatever loggingOn says) the force is F plus the scene's ``[load]`` F_scene(t), evaluated by the stepper at
every internal step exactly as the library does: with no input connected, the FMU then reproduces ``simulate``
of its scene. The parameters ``noise_intensity``, ``noise_seed`` and ``noise_unit`` add a white noise sigma xi(t)
that the FMU generates (start values: the scene's [load] noise, or none), with or without ``scene_load``: its
path is a function of (seed, time) alone, so a rolled-back step redraws the same increments.

Driven by a motion (a connector): the outputs always show the element or network moved to the inputs x, v set
last (without committing: a master may set them several times at one communication point); ``doStep`` commits
the sample (``kinds.py``).

Refusals: a non-finite input, a parameter outside its range or a step that would leave a non-finite state during
stepping is refused: a message naming the variable and the value is logged, ``do_step`` returns fmi2Discard,
and the state is exactly what it was before (a master may set a good value and step again; FMPy's
``simulate_fmu`` ends the run early on a Discard). A step the library cannot take (``ElementError``: its step
budget, a non-finite result) is a Discard with the library's reason.

A bad start value (set before or during initialization) is refused at ``fmi2ExitInitializationMode``, a fixed
parameter (x0, v0, an effect with memory) set after initialization where it is set, and a state of another FMU
or a tampered blob at ``fmi2SetFMUstate``/``fmi2DeSerializeFMUstate``: the reason is logged and the call fails,
so that a master such as FMPy raises with that reason. Such a call fails with fmi2Error under the FMU's own
loader (fmi2Fatal under PythonFMU's stock one, see ``common.py``); the instance stays intact. So does a
non-finite clock or a negative communication step (``fmi2DoStep``), an unknown value reference, a variable of
another type, and a getter whose value is not a finite number: no Real is handed out with fmi2OK unless it is
finite.
"""

from pythonfmu.enums import Fmi2Status

from ...stepping import ElementError
from ..description import (NOISE_SEED_LIMIT, check_noise_settings, is_network, model_identifier, scene_load_notice,
                           variables)
from .common import SlaveBase, finite_number, register_variables
from .kinds import KINDS

# the settings a master sets beside the inputs (the other parameters are the effects' or the network's)
SETTINGS = ("step", "stepper", "scene_load", "noise_intensity", "noise_seed", "noise_unit")
NOISE = ("noise_intensity", "noise_seed", "noise_unit")


class PrandtlSlave(SlaveBase):
    """The FMU of a scene (module docstring); its variables: ``description.variables``, its kind ``kinds.KINDS``
    (by the scene's kind and causality)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        scene = self.scene
        self.kind = KINDS[is_network(scene), scene.causality](scene)
        self.modelName = model_identifier(scene)  # (PythonFMU's builder names the binaries after it)
        self.parameters = self.kind.parameters()
        # what the master set: the inputs and the settings, from their start values; checked and handed to the
        # library at each step
        self.values = {row.name: row.start for row in variables(scene)
                       if row.causality == "input" or row.name in SETTINGS}
        if self.values.get("noise_seed", 0) >= NOISE_SEED_LIMIT:
            from ...scene import SceneError

            raise SceneError(f"{scene.source}: [load] seed {self.values['noise_seed']}: an FMU's noise_seed is an "
                             "FMI Integer (32 bits): it must be < 2^31")
        self.initialized = False  # after fmi2ExitInitializationMode: fixed parameters are frozen
        self._handed_over = None  # the settings as last handed to the library
        self._preview_key = self._preview = None  # a connector's outputs at the inputs set now (cached)
        self._register()

    def _register(self):
        """The FMU's variables, each read and set here."""
        accessors = {"n": (lambda: self.n, None)}
        for name in self.values:
            accessors[name] = (lambda name=name: self.values[name],
                               lambda value, name=name: self.values.__setitem__(name, value))
        for name in self.parameters:
            accessors[name] = (lambda name=name: self.parameters[name],
                               lambda value, name=name: self._set_parameter(name, value))
        for name, getter in self.kind.outputs(self).items():
            accessors[name] = (getter, None)
        self._fixed = register_variables(self, accessors)

    def _set_parameter(self, name, value):
        """Setter of a parameter: a fixed one (x0, v0, an effect with memory) cannot change after initialization."""
        if self.initialized and name in self._fixed and value != self.parameters[name]:
            self._fail(f"parameter {name} = {value!r} refused: {name} is fixed {self.kind.fixed} and cannot change "
                       f"after initialization; the {self.kind.noun} is unchanged")
        self.parameters[name] = value

    # ------------------------------------------------------------ initialization and steps

    def exit_initialization_mode(self):
        if self.kind.driven_by_force:
            problem = self._start_under_force()
        else:
            problem = self.kind.hand_over(self)
            if problem is None:
                problem = self._motion_problem(" refused: the motion must be finite") or self.kind.start(self)
        if problem is not None:
            self._fail(f"initialization refused: {problem}")
        if self.kind.driven_by_force:
            self.kind.stepped.time = self.start_time
            self._handed_over = None  # the next step compares the settings again
        self.initialized = True
        if self.values.get("scene_load"):  # a master that connects F is told the scene's load is added
            self.log(scene_load_notice(self.scene, self.kind.where), Fmi2Status.warning,
                     category="logStatusWarning")
        self._warn_if_unstable()

    def _start_under_force(self):
        """None, or why the element or network cannot start: its settings, then F, then the library (a massless
        part starts in equilibrium with the force at the start)."""
        force = self.values["F"]
        problem = self.kind.settings_problem(self)
        if problem is None and not finite_number(force):
            problem = f"F = {force!r} refused: the force must be finite"
        if problem is None:
            if not self._hand_over_settings():  # e.g. a stepper that does not apply (logged)
                return self.log_queue[-1].msg if self.log_queue else self.kind.misfit
            if self.values["scene_load"]:
                from ...loads import force_at

                force = force + float(force_at(self.scene.load.compile(), self.start_time))
            try:
                self.kind.stepped.reset(force)
            except (ElementError, ValueError) as exc:
                problem = str(exc)
        return problem

    def _motion_problem(self, refusal):
        x, v = self.values["x"], self.values["v"]
        return None if finite_number(x) and finite_number(v) else f"input x = {x!r}, v = {v!r}{refusal}"

    def do_step(self, current_time, step_size):
        problem = self._communication_problem(current_time, step_size)
        if problem:
            self._fail(f"{problem}; the instance is unchanged")
        if self.kind.driven_by_force:
            return self._advance(current_time, step_size)
        problem = self.kind.hand_over(self)
        if problem is not None:
            return self._refuse(f"{problem}; steps are refused until it is set right")
        problem = self._motion_problem(" refused: the motion must be finite; step not taken")
        if problem is not None:
            return self._refuse(problem)
        committed = self.kind.commit(self, current_time, step_size)
        if committed:
            self.forget_preview()
        return committed

    def _advance(self, current_time, step_size) -> bool:
        """The step of an element or a network under the force F held (plus the scene's load with scene_load)."""
        if not self._apply_settings():
            return False
        force = self.values["F"]
        if not finite_number(force):
            return self._refuse(f"F = {force!r} refused: the force must be finite; step not taken")
        element = self.kind.stepped
        saved = element.checkpoint()
        try:
            element.time = current_time
            element.advance(step_size, force, scene_load=bool(self.values["scene_load"]))
        except ElementError as exc:  # the step cannot be taken (budget, a non-finite result): fmi2Discard
            element.rollback(saved)
            return self._refuse(f"step from t = {current_time!r} with F = {force!r} refused: {exc}")
        except Exception as exc:  # a bad input the checks above missed: fmi2Error, the element as it was
            element.rollback(saved)
            self._fail(f"step from t = {current_time!r} with F = {force!r} refused ({exc.__class__.__name__}: "
                       f"{exc}); the instance is unchanged")
        return True  # the library refuses (ElementError) a step that would leave any output non-finite

    def _apply_settings(self) -> bool:
        """Hand the settings the master set to the library; False (logged) if one is refused. Nothing to do (the
        usual step) when they are those handed over last."""
        settings = (tuple(self.parameters.values()), self.values["stepper"], self.values["step"],
                    tuple(self.values[name] for name in NOISE))
        if settings == self._handed_over:
            return True
        before = self.kind.settings_in_use()
        accepted = self._hand_over_settings()
        if accepted and self.kind.settings_in_use() != before:
            self._warn_if_unstable()
        self._handed_over = settings if accepted else None
        return accepted

    def _hand_over_settings(self) -> bool:
        # a noise turned off goes first and one turned on last: the stepper's check sees the noise that will be
        # there (some steppers take none; a massless load node needs a dashpot under a noise)
        noise_first = not self.values["noise_intensity"]
        if noise_first and not self._hand_over_noise():
            return False
        return self.kind.hand_over(self) and (noise_first or self._hand_over_noise())

    def _hand_over_noise(self) -> bool:
        """Hand the white noise the master set to the library; False (logged: fmi2Discard) if refused."""
        from ...loads import white_noise

        seed = self.values["noise_seed"]
        try:
            if not (isinstance(seed, int) and 0 <= seed < NOISE_SEED_LIMIT):
                raise ValueError(f"noise_seed = {seed!r}: must be an integer, 0 <= seed < 2^31")
            noise = white_noise(*(self.values[name] for name in NOISE))
            if noise != self.kind.stepped.noise:
                self.kind.stepped.set_noise(noise)
        except ValueError as exc:
            return self._refuse(f"parameter {exc}; steps are refused until it is set right")
        return True

    def _warn_if_unstable(self):
        problem = self.kind.stability_problem()
        if problem:
            self.log(problem, Fmi2Status.warning)

    # ------------------------------------------------------------ a connector's outputs

    def preview(self, key, move, fresh):
        """A connector's stepped object moved to the inputs set now by ``move`` (on a ``fresh()`` copy, never
        committed), cached under ``key``; no output is handed out for a motion that is not finite."""
        if key != self._preview_key:
            problem = self._motion_problem(": the outputs at a motion that is not finite are not numbers (a doStep "
                                           "would be refused)")
            if problem is not None:
                self._fail(problem)
            preview = fresh()
            move(preview)
            self._preview_key, self._preview = key, preview
        return self._preview

    def forget_preview(self):
        self._preview_key = None

    # ------------------------------------------------------------ FMU state

    def _get_fmu_state(self):
        """The whole state as plain data (PythonFMU serializes it as JSON: no code can hide in it)."""
        settings = {**self.values, "parameters": dict(self.parameters), "start_time": self.start_time,
                    **self.kind.saved_clock()}
        if "scene_load" in settings:
            settings["scene_load"] = bool(settings["scene_load"])
        return {self.kind.state_key: self.kind.stepped.get_state(), "settings": settings}

    def _set_fmu_state(self, state):
        try:
            if not isinstance(state, dict) or "invalid" in state:
                raise ValueError(state.get("invalid") if isinstance(state, dict) else "not a state of this FMU")
            settings = state["settings"]
            parameters = dict(settings["parameters"])
            if set(parameters) != set(self.parameters):
                raise ValueError("its parameters are not this FMU's")
            values = {name: settings[name] for name in self.values}
            start_time = settings["start_time"]
            self.kind.check_state(self, settings, parameters)
            noise = check_noise_settings(*(settings[name] for name in NOISE)) if self.kind.driven_by_force else None
            # the library checks everything (the stepper with the state's noise) before changing anything
            self.kind.restore(state, settings, noise)
        except Exception as exc:  # any malformed or forged content (IndexError, OverflowError, ...): a reason
            self._fail(f"FMU state refused ({exc.__class__.__name__}: {exc}); the instance is unchanged")
        self.values.update(values)
        self.parameters, self.start_time = parameters, start_time
        self._handed_over = None
        self.forget_preview()
