"""The value references of the native FMUs (issue 44.1): in an FMI 3.0 model description every variable's value
reference is its 1-based position in ModelVariables, so a master that reads FMI 3.0's ``dependencies`` (value
references) as FMI 2.0's positions (OMSimulator 2.x) names the same variable; FMI 2.0 keeps PythonFMU's numbering
(0, 1, 2, ... in order). Every kind of FMU (element, connector, network, network connector), with and without
``--arrays``; and the C layer's table of variables (``assemble.c_variables``, scene.h's VARS) is the description's.
Fast: no FMU is built (the built FMUs' C layer is driven by these value references in tests/test_native*.py)."""
from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from prandtl_fmu.fmu import description
from prandtl_fmu.fmu.archive import built_scene
from prandtl_fmu.fmu.native.assemble import c_variables

from tests.paths import ROOT

SCENES = ROOT / "scenes"
# (scene, causality): the four kinds; delay-oscillator's [friction] makes its reaction depend directly on F
KINDS = {
    "element, friction": ("delay-oscillator.toml", None),
    "element, dahl": ("belt-tensioner.toml", None),
    "element, branches": ("paper-section-8.toml", None),
    "connector": (ROOT / "examples/cosim/connector/bushing.toml", "displacement"),
    "network": ("networks/two-masses-slider.toml", None),
    "network connector": ("networks/chain-massless.toml", "displacement"),
}


def _scene(kind):
    path, causality = KINDS[kind]
    return built_scene(SCENES / path, causality)[0]


def _arrays_apply(scene) -> bool:
    return description.is_network(scene) or description.elongation_count(scene) > 0


@pytest.mark.parametrize("arrays", [False, True])
@pytest.mark.parametrize("kind", list(KINDS))
def test_an_fmi3_value_reference_is_the_variable_s_position(kind, arrays):
    scene = _scene(kind)
    if arrays and not _arrays_apply(scene):
        pytest.skip("no arrays to offer (--arrays is refused for this scene)")
    root = ET.fromstring(description.model_description(scene, 3, "token", arrays=arrays))
    variables = list(root.find("ModelVariables"))
    positions = {v.get("name"): position for position, v in enumerate(variables, start=1)}
    assert [int(v.get("valueReference")) for v in variables] == list(range(1, len(variables) + 1))
    assert variables[0].get("name") == "time" and variables[0].get("causality") == "independent"
    # OMSimulator's reading (positions) and FMI 3.0's (value references) of every dependency: the same variable
    by_vr = {int(v.get("valueReference")): v.get("name") for v in variables}
    by_position = {position: name for name, position in positions.items()}
    outputs = [v for v in variables if v.get("causality") == "output"]
    assert outputs
    if kind == "element, friction":  # the case OMSimulator refused: reaction depends on F, once value reference 0
        reaction = root.find(f"ModelStructure/Output[@valueReference='{positions['reaction']}']")
        assert reaction.get("dependencies") == str(positions["F"]) == "2"
    for tag in ("Output", "InitialUnknown"):
        for unknown in root.find("ModelStructure").findall(tag):
            for reference in [unknown.get("valueReference")] + unknown.get("dependencies").split():
                assert by_vr[int(reference)] == by_position[int(reference)]
    # a Dimension names its structural parameter by value reference, which is its position too
    for v in variables:
        dimension = v.find("Dimension")
        if dimension is not None:
            size = by_vr[int(dimension.get("valueReference"))]
            assert variables[positions[size] - 1].get("causality") == "structuralParameter"
    # what the scene's dependencies name: the FMI 2.0 inputs (F; the connector's x, v) under their FMI 3.0 position
    two = description.variables(scene)
    depends = {row.name: row.depends for row in two if row.causality == "output"}
    for unknown in root.find("ModelStructure").findall("Output"):
        name = by_vr[int(unknown.get("valueReference"))]
        if name in depends:
            assert sorted(by_position[int(d)] for d in unknown.get("dependencies").split()) == sorted(depends[name])


@pytest.mark.parametrize("kind", list(KINDS))
def test_fmi2_keeps_pythonfmu_s_numbering_and_the_c_table_is_the_description(kind):
    scene = _scene(kind)
    two = description.variables(scene)
    assert [row.value_reference for row in two] == list(range(len(two)))
    root = ET.fromstring(description.model_description(scene, 2, "guid"))
    assert [int(v.get("valueReference")) for v in root.iter("ScalarVariable")] == list(range(len(two)))
    for arrays in (False, True) if _arrays_apply(scene) else (False,):
        three = {row.name: row.value_reference for row in description.variables(scene, 3, arrays)}
        table = c_variables(scene, 3, arrays)
        assert [row.name for row in table] == [row.name for row in two]  # the C layer's variables, FMI 2.0's types
        assert [row.type for row in table] == [row.type for row in two]
        assert all(row.value_reference == three[row.name] for row in table)
        references = description.fmi3_references(scene)
        assert references["time"] == three["time"] == 1
        assert all(three[row.name] == row.value_reference + references["offset"] for row in two)
        if description.is_network(scene):
            arrays_names = ("x_nodes", "v_nodes") if scene.causality == "displacement" else ("x", "v")
            if arrays:
                assert (references["n_nodes"], references["x_nodes"], references["v_nodes"]) == (
                    three["n_nodes"], three[arrays_names[0]], three[arrays_names[1]])
        else:
            n = description.elongation_count(scene)
            assert [three[f"u_{i}"] for i in range(1, n + 1)] == [references["u_1"] + i for i in range(n)]
            if arrays:
                assert references["u"] == three["u"]
    assert c_variables(scene, 2) == two


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("kind", list(KINDS) + ["element, massless"])
def test_the_initial_unknowns_name_the_knowns_they_depend_on(kind, fmi, tmp_path):
    """ModelStructure's InitialUnknowns list their dependencies (none listed: a master takes every known, and
    OMSimulator then reports an algebraic loop through F at initialization): every parameter, and of the inputs F
    only where the initial value follows it (a massless element's equilibrium, a network's, a reaction with friction
    on the mass), the connector's x and v where its output is their function. FMPy reads the description with
    its validation on."""
    from fmpy import read_model_description

    if kind == "element, massless":
        path = tmp_path / "massless.toml"
        path.write_text('name = "massless"\n[spring]\nk0 = 1.0\n[branches]\nk = [1.0]\neta = [0.1]\n'
                        '[solver]\nstepper = "implicit"\nstep = 0.01\nstop_time = 1.0\noutput_interval = 0.01\n')
        scene = built_scene(path, None)[0]
    else:
        scene = _scene(kind)
    root = ET.fromstring(description.model_description(scene, fmi=fmi, guid="{0}"))
    rows = description.variables(scene, fmi=fmi)
    parameters = {row.name for row in rows if row.causality == "parameter"}
    inputs = {row.name for row in rows if row.causality == "input"}
    depends = {row.name: set(row.depends) for row in rows if row.causality == "output"}
    if fmi == 2:
        names = {str(i): v.get("name") for i, v in enumerate(root.iter("ScalarVariable"), start=1)}
        unknowns = [(names[u.get("index")], u.get("dependencies")) for u in root.find("ModelStructure/InitialUnknowns")]
    else:
        names = {v.get("valueReference"): v.get("name") for v in root.find("ModelVariables")}
        unknowns = [(names[u.get("valueReference")], u.get("dependencies"))
                    for u in root.find("ModelStructure").findall("InitialUnknown")]
    assert [name for name, _ in unknowns] == [row.name for row in rows if row.causality == "output"]
    for name, listed in unknowns:
        assert listed is not None, name
        named = {names[reference] for reference in listed.split()}
        assert parameters <= named, name
        if kind in ("element, massless", "network", "network connector"):
            assert inputs <= named, name
        else:
            assert named & inputs == depends[name] & inputs, name
    if kind == "element, branches":
        assert "F" in inputs and not any("F" in {names[r] for r in listed.split()} for _, listed in unknowns)
    (tmp_path / "modelDescription.xml").write_text(ET.tostring(root, encoding="unicode"))
    read_model_description(str(tmp_path / "modelDescription.xml"), validate=True)
