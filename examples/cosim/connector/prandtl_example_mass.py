"""A point mass for the connector example: m x'' = amplitude cos(omega t) - force.

A PythonFMU slave (FMI 2.0 co-simulation). Input ``force`` (N): the force
the connector exerts against the mass's motion (its ``force`` output: k0 x +
... for x the mass's displacement relative to the ground); outputs ``x`` (m)
and ``v`` (m/s). Over a communication step the input is held and the harmonic
force is integrated in closed form, so the only error of a coupled run is the
coupling's. Its module name is unique on purpose (PythonFMU FMUs cannot share
a module name with anything the host imports).
"""
import math
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real

# The unit of each variable and the SI base units of each unit (PythonFMU 0.7.0 writes none; OMSimulator
# refuses to connect a variable with a unit to one without).
VARIABLE_UNITS = {"m": "kg", "amplitude": "N", "omega": "rad/s", "x0": "m", "v0": "m/s", "force": "N", "x": "m",
                  "v": "m/s"}
BASE_UNITS = {"kg": {"kg": "1"}, "N": {"kg": "1", "m": "1", "s": "-2"}, "rad/s": {"rad": "1", "s": "-1"},
              "m": {"m": "1"}, "m/s": {"m": "1", "s": "-1"}}

# PythonFMU 0.7.0 executes this file again at each instantiation and then
# releases a reference to the module's dict it never took: keep one more.
globals().setdefault("_DICT_REFERENCES", []).append(globals())


class PointMass(Fmi2Slave):
    author = "prandtl_fmu examples"
    description = "Point mass under a harmonic force and the force of a connector: m x'' = A cos(omega t) - force"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.m, self.amplitude, self.omega = 1.0, 0.45, 0.5
        self.x0 = self.v0 = 0.0
        self.x = self.v = 0.0
        self.force = 0.0
        for name, text in (("m", "mass (kg)"), ("amplitude", "amplitude A of the external force (N)"),
                           ("omega", "angular frequency of the external force (rad/s)")):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.tunable, description=text))
        for name, text in (("x0", "initial displacement (m)"), ("v0", "initial velocity (m/s)")):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.fixed, description=text))
        self.register_variable(Real("force", causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
                                    start=0.0, description="force of the connector against the motion (N)"))
        for name, text in (("x", "displacement (m)"), ("v", "velocity (m/s)")):
            self.register_variable(Real(name, causality=Fmi2Causality.output,
                                        variability=Fmi2Variability.continuous, description=text))

    def to_xml(self, model_options=dict()):
        """PythonFMU's modelDescription.xml with the units, the outputs' (absent) direct dependencies and the
        initial unknowns put in (without their dependencies, OMSimulator sees an algebraic loop through the
        connector at initialization)."""
        root = super().to_xml(model_options)
        units = Element("UnitDefinitions")
        for name, exponents in BASE_UNITS.items():
            SubElement(SubElement(units, "Unit", name=name), "BaseUnit", exponents)
        root.insert(list(root).index(root.find("CoSimulation")) + 1, units)  # the FMI 2.0 schema's order
        for variable in root.find("ModelVariables"):
            variable.find("Real").set("unit", VARIABLE_UNITS[variable.get("name")])
        structure = root.find("ModelStructure")
        initial = SubElement(structure, "InitialUnknowns")
        index = {variable.get("name"): str(i + 1) for i, variable in enumerate(root.find("ModelVariables"))}
        for output in structure.find("Outputs"):
            output.set("dependencies", "")  # x and v are states: no direct feedthrough from the force
            SubElement(initial, "Unknown", index=output.get("index"),  # computed from x0 and v0 alone
                       dependencies=f"{index['x0']} {index['v0']}")
        return root

    def exit_initialization_mode(self):
        self.x, self.v = self.x0, self.v0

    def do_step(self, current_time, step_size):
        t0, h, w = current_time, step_size, self.omega
        t1 = t0 + h
        push = self.amplitude / self.m  # the harmonic force per unit mass, integrated exactly
        dv = push * (math.sin(w * t1) - math.sin(w * t0)) / w - self.force / self.m * h
        dx = (self.v * h + push * ((math.cos(w * t0) - math.cos(w * t1)) / w - math.sin(w * t0) * h) / w
              - 0.5 * self.force / self.m * h * h)
        self.x, self.v = self.x + dx, self.v + dv
        return True
