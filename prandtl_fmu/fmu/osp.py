"""The OSP interface description of an FMU: ``<name>_OspModelDescription.xml``.

The Open Simulation Platform's interface specification (OSP-IS; schema
OspModelDescription-1.0.1.xsd of osp-validator) names the two sides of a
mechanical coupling: a ``LinearMechanicalPort`` is one Force and one
LinearVelocity of opposite causality, a ``LinearMechanicalQuasiPort`` one
Force and one LinearDisplacement. libcosim reads the file from beside the FMU,
named after the FMU's ``modelName``, and then connects ports with one
``VariableGroupConnection`` (and ECCO's ``powerBond``).

* the element with its force input (``PrandtlElement``): F in; v, x out;
* the connector (``PrandtlConnector``): v, x in; force out;
* a network with its force input (``PrandtlNetwork``): F in; v_<load node>, x_<load node> out;
* a network as a connector (``PrandtlNetworkConnector``): v, x (of its load node) in; force out.

Units refer to the FMU's own UnitDefinitions (N, m/s, m).
"""
from __future__ import annotations

NAMESPACE = "https://open-simulation-platform.com/OspModelDescription/1.0.1"

# (force variable, velocity variable, displacement variable) per causality
PORT_VARIABLES = {"force": ("F", "v", "x"), "displacement": ("force", "v", "x")}


def port_variables(scene, causality: str = None) -> tuple:
    """(force, velocity, displacement) variable names of the FMU of a scene (with ``causality``, default the
    scene's): a network's element FMU shows the load node's motion as v_<node>, x_<node>."""
    causality = causality or scene.causality
    if hasattr(scene, "network") and causality == "force":
        node = scene.network.nodes[scene.network.load_node]
        return ("F", f"v_{node}", f"x_{node}")
    return PORT_VARIABLES[causality]


def osp_model_description(causality: str, variables: tuple = None) -> str:
    """The XML text for an FMU of ``causality`` ("force" or "displacement"); ``variables``: (force, velocity,
    displacement) names other than the element's (:func:`port_variables`)."""
    force, velocity, displacement = variables or PORT_VARIABLES[causality]
    return f"""<?xml version="1.0" encoding="utf-8"?>
<OspModelDescription xmlns="{NAMESPACE}" version="1.0">
  <VariableGroups>
    <LinearMechanicalPort name="mechanical_port">
      <Force name="port_force">
        <Variable ref="{force}" unit="N"/>
      </Force>
      <LinearVelocity name="port_velocity">
        <Variable ref="{velocity}" unit="m/s"/>
      </LinearVelocity>
    </LinearMechanicalPort>
    <LinearMechanicalQuasiPort name="mechanical_quasi_port">
      <Force name="quasi_port_force">
        <Variable ref="{force}" unit="N"/>
      </Force>
      <LinearDisplacement name="quasi_port_displacement">
        <Variable ref="{displacement}" unit="m"/>
      </LinearDisplacement>
    </LinearMechanicalQuasiPort>
  </VariableGroups>
</OspModelDescription>
"""


def file_name(model_name: str) -> str:
    """The name libcosim looks for beside the FMU."""
    return f"{model_name}_OspModelDescription.xml"
