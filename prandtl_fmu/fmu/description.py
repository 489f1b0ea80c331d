"""What PythonFMU 0.7.0 leaves out of modelDescription.xml, put back.

PythonFMU writes no units, no min/max, no ``InitialUnknowns`` and no output
dependencies. :class:`RealVariable` carries unit, min, max and nominal, and
:func:`complete` adds the ``UnitDefinitions`` and rewrites the
``ModelStructure`` of the XML tree PythonFMU builds.
"""
from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Real

# SI base-unit exponents of the units the FMU uses.
UNITS = {
    "s": {"s": 1},
    "m": {"m": 1},
    "kg": {"kg": 1},
    "m/s": {"m": 1, "s": -1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N/m3": {"kg": 1, "m": -2, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "J": {"kg": 1, "m": 2, "s": -2},
    "1/s": {"s": -1},
    "N/(m.s)": {"kg": 1, "s": -3},
    "1": {},
    # a white noise's intensity, N sqrt(s): FMI's base-unit exponents are integers, so the name alone says it
    "N.s0.5": None,
}


class RealVariable(Real):
    """A PythonFMU Real that also writes ``unit``, ``min``, ``max`` and ``nominal``."""

    def __init__(self, name, *, unit, min=None, max=None, nominal=None, **kwargs):
        super().__init__(name, **kwargs)
        if unit not in UNITS:
            raise ValueError(f"{name}: unit {unit!r} has no definition")
        self.unit, self.min, self.max, self.nominal = unit, min, max, nominal

    def to_xml(self) -> Element:
        node = super().to_xml()
        real = node.find("Real")
        real.set("unit", self.unit)
        for key in ("min", "max", "nominal"):
            value = getattr(self, key)
            if value is not None:
                real.set(key, f"{value:.17g}")
        return node


def complete(root: Element, variables: list, output_dependencies: dict) -> Element:
    """Add UnitDefinitions and a full ModelStructure to PythonFMU's XML ``root``.

    ``variables`` are the registered variables in value-reference order (the
    XML index of each is its position + 1). ``output_dependencies`` maps an
    output's name to the names it depends on directly (empty: no direct
    feedthrough from any input).
    """
    used = sorted({v.unit for v in variables if isinstance(v, RealVariable)})
    units = Element("UnitDefinitions")
    for name in used:
        unit = SubElement(units, "Unit", name=name)
        if UNITS[name] is not None:
            SubElement(unit, "BaseUnit", {k: str(e) for k, e in UNITS[name].items()})
    # UnitDefinitions comes right after CoSimulation (FMI 2.0 schema order).
    position = list(root).index(root.find("CoSimulation")) + 1
    root.insert(position, units)

    index = {v.name: i + 1 for i, v in enumerate(variables)}
    old = root.find("ModelStructure")
    root.remove(old)
    structure = SubElement(root, "ModelStructure")
    outputs = [v for v in variables if v.causality is not None and v.causality.name == "output"]
    if outputs:
        node = SubElement(structure, "Outputs")
        for v in outputs:
            depends = " ".join(str(index[name]) for name in output_dependencies.get(v.name, ()))
            SubElement(node, "Unknown", index=str(index[v.name]), dependencies=depends)
        # Outputs are calculated from the initial state and parameters; no
        # `dependencies` attribute means: from any of them.
        initial = SubElement(structure, "InitialUnknowns")
        for v in outputs:
            SubElement(initial, "Unknown", index=str(index[v.name]))
    return root
