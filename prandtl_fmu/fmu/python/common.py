"""The FMI plumbing of the slave (``slave.py``): the scene, refusals, the checked getters and setters, FMU states.

A refused call logs its reason and raises :class:`Refused`. Under the FMU's own loader (``loader/``,
PythonFMU 0.7.0 patched; Linux x86-64) the call then fails with fmi2Error and the instance stays as it was.
Under PythonFMU's stock loader (its Windows binary, or an FMU built with ``loader="pythonfmu"``) every
Python exception is fmi2Fatal, and that loader releases its references to the slave when a call fails and
again when the instance is freed: :meth:`SlaveBase._fail` then takes one more reference first, so that the
instance stays intact there too (the refused call changed nothing, later calls still work) and the host
never touches freed memory. The loader says which it is by the ``pythonfmu_loader`` argument.
"""
import ctypes
import json
import math
import os

from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu import __version__ as pythonfmu_version
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from ...scene import load_scene
from ..description import fmi2_root, variables


class Refused(Exception):
    """A call refused by the slave (logged first): fmi2Error (fmi2Fatal under PythonFMU's stock loader)."""


def finite_number(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)


def register_variables(slave, accessors: dict) -> set:
    """Register the FMU's variables (``description.variables`` of the slave's scene, in value-reference order)
    with PythonFMU, each with its getter and setter, ``accessors[name] = (getter, setter)`` (setter None: the
    variable cannot be set). Returns the names of the fixed variables (a setter refuses them after
    initialization)."""
    kinds = {"Float64": Real, "Int32": Integer, "Boolean": Boolean, "String": String}
    for row in variables(slave.scene):
        getter, setter = accessors[row.name]
        variable = kinds[row.type](row.name, causality=Fmi2Causality[row.causality],
                                   variability=Fmi2Variability[row.variability], description=row.description,
                                   getter=getter, setter=setter)
        slave.register_variable(variable)
        if variable.value_reference != row.value_reference:
            raise RuntimeError(f"{row.name}: value reference {variable.value_reference}, the description's is "
                               f"{row.value_reference}")
    return {row.name for row in variables(slave.scene) if row.variability == "fixed"}


class SlaveBase(Fmi2Slave):
    """The scene of the FMU, logging refusals, failing a call without freeing the instance, reading a
    serialized state."""

    def __init__(self, **kwargs):
        # absent under PythonFMU's stock loader (and when PythonFMU's builder instantiates the class)
        self.loader = kwargs.pop("pythonfmu_loader", None)
        super().__init__(**kwargs)
        path = os.path.join(self.resources, "scene.toml")
        self.scene = load_scene(path, check_stepper=False)
        if self.scene.causality == "force":  # its own stepper must apply (a connector takes the library's steps)
            self.scene = load_scene(path)
        solver = self.scene.solver
        self.default_experiment = DefaultExperiment(start_time=0.0, stop_time=solver.stop_time,
                                                    step_size=solver.output_interval)
        self.start_time = 0.0
        branches = getattr(self.scene, "branches", None)  # a network scene has none: its slaves have no n
        # the variable n: the number of branches, -1 for the continuous element
        self.n = 0 if branches is None else -1 if branches.continuum else branches.n

    def to_xml(self, model_options=dict()):
        """The model description PythonFMU's builder writes: ``description.fmi2_root`` of the scene (the native
        FMU's too)."""
        return fmi2_root(self.scene, guid=str(self.guid), generation_tool=f"PythonFMU {pythonfmu_version}")

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        if not finite_number(start_time):
            self._fail(f"fmi2SetupExperiment refused: start time {start_time!r} must be finite")
        self.start_time = float(start_time)

    def _communication_problem(self, current_time, step_size):
        """Why a doStep from ``current_time`` by ``step_size`` is refused (fmi2Error: illegal arguments, FMI 2.0
        2.1.3), or None. The FMU's own loader refuses these before the slave sees them; PythonFMU's does not."""
        if not finite_number(current_time):
            return f"fmi2DoStep refused: communication point {current_time!r} must be finite"
        if not (finite_number(step_size) and step_size >= 0 and math.isfinite(current_time + step_size)):
            return (f"fmi2DoStep refused: communication step {step_size!r} must be finite and >= 0 "
                    f"(from t = {current_time!r})")
        return None

    # ------------------------------------------------------------ getters and setters
    #
    # PythonFMU's own raise a bare exception for an unknown value reference or a wrong type (the stock loader then
    # freed the instance's objects: no ``_fail``), set the variables before the bad one, and hand out whatever a
    # getter returns. These check every reference before anything changes, fail through ``_fail`` with the
    # reason, and never hand out a non-finite Real with fmi2OK (an output that is not a number is refused).

    def _variables(self, vrs, kind, function):
        variables = []
        for vr in vrs:
            var = self.vars.get(vr)
            if var is None:
                self._fail(f"{function} refused: no variable has value reference {vr}")
            if not isinstance(var, kind):
                self._fail(f"{function} refused: {var.name} (value reference {vr}) is not a {kind.__name__}")
            variables.append(var)
        return variables

    def _read(self, var, function):
        try:
            return var.getter()
        except Refused:
            raise
        except Exception as exc:  # e.g. the library's ElementError: a reason, never a bare exception
            self._fail(f"{function} refused: {var.name} cannot be read ({exc.__class__.__name__}: {exc})")

    def _write(self, var, value, function):
        if var.setter is None:
            causality, variability = (getattr(kind, "name", None) for kind in (var.causality, var.variability))
            self._fail(f"{function} refused: {var.name} cannot be set (causality {causality}, variability "
                       f"{variability})")
        try:
            var.setter(value)
        except Refused:
            raise
        except Exception as exc:
            self._fail(f"{function} refused: {var.name} = {value!r} ({exc.__class__.__name__}: {exc})")

    def get_real(self, vrs):
        values = []
        for var in self._variables(vrs, Real, "fmi2GetReal"):
            value = self._read(var, "fmi2GetReal")
            try:
                value = float(value)
            except (TypeError, ValueError, OverflowError):
                value = math.nan
            if not math.isfinite(value):
                self._fail(f"fmi2GetReal refused: {var.name} = {value!r} is not a finite number (no value is handed "
                           "out as valid that is not one)")
            values.append(value)
        return values

    def get_integer(self, vrs):
        return [int(self._read(var, "fmi2GetInteger")) for var in self._variables(vrs, Integer, "fmi2GetInteger")]

    def get_boolean(self, vrs):
        return [bool(self._read(var, "fmi2GetBoolean")) for var in self._variables(vrs, Boolean, "fmi2GetBoolean")]

    def get_string(self, vrs):
        return [str(self._read(var, "fmi2GetString")) for var in self._variables(vrs, String, "fmi2GetString")]

    def _set(self, vrs, values, kind, function):
        variables = self._variables(vrs, kind, function)
        values = list(values)
        if len(values) != len(variables):
            self._fail(f"{function} refused: {len(variables)} value references, {len(values)} values")
        for var, value in zip(variables, values):
            self._write(var, value, function)

    def set_real(self, vrs, values):
        self._set(vrs, values, Real, "fmi2SetReal")

    def set_integer(self, vrs, values):
        self._set(vrs, values, Integer, "fmi2SetInteger")

    def set_boolean(self, vrs, values):
        self._set(vrs, values, Boolean, "fmi2SetBoolean")

    def set_string(self, vrs, values):
        if not all(isinstance(value, str) for value in values):  # PythonFMU's loader hands None for NULL
            self._fail("fmi2SetString refused: a value is not a string (NULL)")
        self._set(vrs, values, String, "fmi2SetString")

    def _fail(self, message):
        """Log ``message`` and fail the current call (fmi2Error; fmi2Fatal under PythonFMU's stock loader, see
        the module docstring), keeping the instance alive and unchanged."""
        self.log(message, Fmi2Status.error)
        if self.loader is None:
            # PythonFMU's stock loader releases its references to the class, the instance and the log queue
            # once more than it took when a call raises: take one more of each, never to be given back
            # (balanced by that extra release), so that nothing the host still points to is freed.
            for owned in (type(self), self, self.log_queue):
                ctypes.pythonapi.Py_IncRef(ctypes.py_object(owned))
        raise Refused(message)

    def _refuse(self, message) -> bool:
        """Log ``message`` as a Discard and return False (``do_step`` returns it: fmi2Discard)."""
        self.log(message, Fmi2Status.discard)
        return False

    @staticmethod
    def _fmu_state_from_bytes(state: bytes):
        """A serialized state, never an exception here (PythonFMU has no instance to survive one with): what
        cannot be read becomes a state that ``_set_fmu_state`` refuses with the reason."""
        try:
            return json.loads(bytes(state).decode("utf-8"))
        except Exception as exc:  # any garbage: refused later, with its reason
            return {"invalid": f"not a serialized state of this FMU ({exc.__class__.__name__})"}
