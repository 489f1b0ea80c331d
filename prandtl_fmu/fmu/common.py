"""What both slaves (the element with its force input, the connector) share: refusals and FMU states.

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
import sys

from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from ..scene import load_scene

DBL_MAX = sys.float_info.max
SMALLEST = 5e-324  # the smallest positive double: FMI's min is inclusive, and 0 is refused


class Refused(Exception):
    """A call refused by the slave (logged first): fmi2Error (fmi2Fatal under PythonFMU's stock loader)."""


def finite_number(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)


class SlaveBase(Fmi2Slave):
    """The scene of the FMU, logging refusals, failing a call without freeing the instance, reading a
    serialized state."""

    def __init__(self, **kwargs):
        # absent under PythonFMU's stock loader (and when PythonFMU's builder instantiates the class)
        self.loader = kwargs.pop("pythonfmu_loader", None)
        super().__init__(**kwargs)
        self.scene = load_scene(os.path.join(self.resources, "scene.toml"))
        solver = self.scene.solver
        self.default_experiment = DefaultExperiment(start_time=0.0, stop_time=solver.stop_time,
                                                    step_size=solver.output_interval)
        self.start_time = 0.0
        branches = self.scene.branches
        # the variable n: the number of branches, -1 for the continuous element
        self.n = 0 if branches is None else -1 if branches.continuum else branches.n

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self.start_time = float(start_time)

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
