"""A small force source for the co-simulation example: F(t) = offset + amplitude cos(omega t).

A PythonFMU slave (FMI 2.0 co-simulation); its output F is the force at the
current communication point, computed whenever it is read from the parameters
as they are then: a master that reads F during initialization (to start a
massless element from the equilibrium with F(0)) gets F(0) of the amplitude
it set, not of the default. Its module name is unique on purpose (PythonFMU
FMUs cannot share a module name with anything the host imports).
"""
import math

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real

# PythonFMU 0.7.0 executes this file again at each instantiation and then
# releases a reference to the module's dict it never took: keep one more.
globals().setdefault("_DICT_REFERENCES", []).append(globals())


class HarmonicForce(Fmi2Slave):
    author = "prandtl_fmu examples"
    description = "Harmonic force F(t) = offset + amplitude cos(omega t)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.amplitude = 0.45
        self.omega = 0.5
        self.offset = 0.0
        self.time = 0.0
        for name, text in (("amplitude", "amplitude (N)"), ("omega", "angular frequency (rad/s)"),
                           ("offset", "constant part (N)")):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.tunable, description=text))
        self.register_variable(Real("F", causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                                    description="force at the current communication point (N)",
                                    getter=self.force))

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self.time = start_time

    def do_step(self, current_time, step_size):
        self.time = current_time + step_size
        return True

    def force(self):
        """F at the current time, from the parameters as they are now (N)."""
        return self.offset + self.amplitude * math.cos(self.omega * self.time)
