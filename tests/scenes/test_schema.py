"""The scene format's schema (prandtl_fmu/schema.py) is what the readers read and what the reference says.

* every key of every form of every table is read, through the readers, by a scene of the corpus below, and no
  reader reads a key the schema lacks (SchemaError, a bug);
* the example scenes (packaged and under examples/) and the scene blocks of docs/scene-format.md use only keys
  the schema knows;
* the scene reference the documentation site generates (docs/gen_pages.py) lists every key of the schema.
"""
import importlib.util
import pathlib
import re

import numpy as np
import pytest

from prandtl_fmu import parse_scene, schema
from prandtl_fmu.scene import PACKAGED_SCENES, VALUES, SceneError, _Reader, read_toml, toml_document

from tests.paths import ROOT

SOLVER = '\n[solver]\nstepper = "implicit"\nstep = 0.01\nstop_time = 0.1\noutput_interval = 0.1\n'

# One scene per form of every table: together they hold every key of the schema (checked below).
CORPUS = {
    "element, every plain table": """
        name = "every-table"
        [mass]
        m = 1.0
        x0 = 0.01
        v0 = 0.0
        [friction]
        alpha = 0.5
        alpha_kinetic = 0.3
        stribeck_velocity = 0.05
        belt_velocity = 0.1
        [spring]
        k0 = 1.0
        [cubic]
        k3 = 0.1
        [damper]
        c = 0.1
        [branches]
        k = [1.0, 2.0]
        eta = [0.1, 0.2]
        u0 = [0.0, 0.05]
        c = [1.0, 2.0]
        [load]
        kind = "harmonic"
        amplitude = 0.4
        omega = 0.5
        offset = 0.1
        noise_intensity = 0.1
        noise_seed = 3
        noise_unit = 0.01
        [fmu]
        causality = "force"
    """,
    "branches by alpha": """
        [mass]
        m = 1.0
        [branches]
        k = [1.0]
        alpha = [0.2]
        [load]
        kind = "constant"
        value = 0.1
    """,
    "branches sampled, a shared series dashpot": """
        [mass]
        m = 1.0
        [branches]
        count = 4
        k_total = 1.0
        eta_range = [0.1, 0.5]
        sampling = "midpoint"
        u0 = [0.0, 0.0, 0.0, 0.0]
        c = 2.0
        [load]
        kind = "table"
        time = [0.0, 1.0]
        force = [0.0, 1.0]
    """,
    "the continuum": """
        [mass]
        m = 1.0
        [branches]
        continuum = true
        k_total = 1.0
        eta_range = [0.1, 0.5]
        [load]
        kind = "random"
        seed = 7
        rms = 0.3
        band = [0.2, 2.0]
        components = 10
        offset = 0.0
    """,
    "an Iwan continuum": """
        [mass]
        m = 1.0
        [branches]
        continuum = true
        density = { kind = "iwan", F_S = 1.0, K_T = 10.0, chi = -0.5, beta = 0.1 }
        [load]
        kind = "white_noise"
        intensity = 0.1
        seed = 1
        offset = 0.0
        noise_unit = 0.01
    """,
    "a sampled piecewise density": """
        [mass]
        m = 1.0
        [branches]
        count = 5
        density = { kind = "piecewise", s = [0.0, 0.5, 1.0], k = [2.0, 0.5], eta = [0.0, 0.1, 0.1] }
        sampling = "mean"
        c = 1.0
    """,
    "a bilinear backbone": """
        [masing]
        kind = "bilinear"
        k = 100.0
        f_y = 1.0
        alpha = 0.1
        [damper]
        c = 1.0
    """,
    "a hyperbolic backbone": """
        [masing]
        kind = "hyperbolic"
        k = 100.0
        f_u = 1.0
        x_max = 0.1
        count = 10
        spacing = "displacement"
        [damper]
        c = 1.0
    """,
    "a Ramberg-Osgood backbone": """
        [masing]
        kind = "ramberg_osgood"
        k = 100.0
        f_y = 1.0
        a = 0.5
        r = 5.0
        x_max = 0.1
        [damper]
        c = 1.0
    """,
    "effects with memory": """
        [mass]
        m = 1.0
        [spring]
        k0 = 1.0
        [delay]
        gain = 0.5
        tau = 0.3
        acts_on = "v"
        [history]
        weight = [0.4, -0.1]
        rate = [1.3, 0.0]
        acts_on = "x"
        [dahl]
        sigma = 30.0
        force = 0.2
        exponent = 1.0
        kind = "dahl"
    """,
    "a network": """
        name = "net"
        [network]
        nodes = ["a", "b"]
        mass = [1.0, 1.0]
        x0 = [0.0, 0.0]
        v0 = [0.0, 0.0]
        load_node = "b"
        [[network.spring]]
        between = ["a", "ground"]
        k = 100.0
        name = "mount"
        [[network.dashpot]]
        between = ["b", "ground"]
        c = 0.5
        name = "dashpot_x"
        [[network.slider]]
        between = ["a", "b"]
        alpha = 2.0
        name = "slider_x"
        [[network.branch]]
        between = ["a", "b"]
        k = 50.0
        eta = 0.02
        u0 = 0.0
        c = 10.0
        name = "branch_x"
        [[network.cubic]]
        between = ["a", "ground"]
        k3 = 1e3
        name = "cubic_x"
        [fmu]
        causality = "force"
    """,
    "a chain": """
        [chain]
        n = 3
        m = [1.0, 1.0, 1.0]
        k = 1000.0
        alpha = 1.0
        c = 0.01
        k_wall = 1000.0
    """,
}


def _text(body: str) -> str:
    return "\n".join(line.strip() for line in body.strip().splitlines()) + SOLVER


@pytest.fixture
def keys_read(monkeypatch):
    """The (schema table, form, key) of every key the readers look up, recorded."""
    seen = set()
    lookup = _Reader.key

    def recording(self, name, method):
        key = lookup(self, name, method)
        forms = [self.form] if self.form is not None else [f for f, k in self.schema.all_keys() if k == key]
        seen.update((self.schema.name, form, name) for form in forms)
        return key

    monkeypatch.setattr(_Reader, "key", recording)
    return seen


def test_the_corpus_reads_every_key_of_every_form(keys_read, monkeypatch):
    from prandtl_fmu.effects import ContinuousBranches

    # the keys are read, not the spectrum computed: Segalman's takes half a second to compile (tests/models/test_spectra.py)
    monkeypatch.setattr(ContinuousBranches, "iwan", staticmethod(lambda *_: ContinuousBranches.linear(1.0, 0.1, 0.5)))
    for name, body in CORPUS.items():
        parse_scene(_text(body), source=name, check_stepper=False)
    # what the readers never look up through _Reader.key: the top level, a network's names and sub-tables
    by_code = {("scene", form, key.name) for form, key in schema.SCHEMA["scene"].all_keys()}
    by_code |= {(table.name, form, key.name) for table in schema.SCHEMA.values() for form, key in table.all_keys()
                if schema.TYPES[key.type] is None}
    every = {(table.name, form, key.name) for table in schema.SCHEMA.values() for form, key in table.all_keys()}
    assert every - keys_read - by_code == set()


def test_the_corpus_holds_every_key_of_the_schema():
    """Each key of each form appears in some scene of the corpus (the test above then reads it)."""
    present = set()

    def walk(table_name, data):
        table = schema.table(table_name)
        for key, value in data.items():
            present.add((table_name, key))
            if isinstance(value, dict) and f"{table_name}.{key}" in schema.SCHEMA:
                walk(f"{table_name}.{key}", value)
            if isinstance(value, list) and value and isinstance(value[0], dict):
                for item in value:
                    walk(f"{table_name}.{key}", item)
        assert table

    for body in CORPUS.values():
        document = toml_document(_text(body), "corpus")
        for key, value in document.items():
            present.add(("scene", key))
            if isinstance(value, dict):
                walk(key, value)
    every = {(table.name, key.name) for table in schema.SCHEMA.values() for _, key in table.all_keys()}
    assert every - present == set()


def test_a_key_the_schema_lacks_is_a_bug_not_a_refusal():
    r = _Reader("t.toml", "mass", {"m": 1.0})
    with pytest.raises(schema.SchemaError, match="not a key of the schema"):
        r.number("mass")
    with pytest.raises(schema.SchemaError, match="not read by number"):
        _Reader("t.toml", "solver", {"stepper": "implicit"}).number("stepper")
    with pytest.raises(schema.SchemaError, match="is not the schema's"):
        r.number("m", positive=False)  # a reader that states a bound must state the schema's
    with pytest.raises(schema.SchemaError, match="no form"):
        r.only({"m", "x0"})
    with pytest.raises(schema.SchemaError, match="not a table"):
        _Reader("t.toml", "masses", {})
    with pytest.raises(schema.SchemaError, match="name one"):
        _Reader("t.toml", "load", {}).only()
    assert not issubclass(schema.SchemaError, ValueError)  # never caught as a bad scene by the CLI


def test_defaults_and_bounds_come_from_the_schema(monkeypatch):
    text = _text(CORPUS["branches by alpha"])
    assert parse_scene(text).mass.x0 == 0.0
    mass = schema.SCHEMA["mass"]
    keys = dict(mass.keys())
    keys["x0"] = schema.Key("x0", "number", "initial displacement", "m", default=0.25, value=True)
    keys["m"] = schema.Key("m", "number", "mass", "kg", minimum=2.0)
    changed = schema.Table("mass", mass.meaning, {"": tuple(keys.values())})
    monkeypatch.setitem(schema.SCHEMA, "mass", changed)
    assert parse_scene(text.replace("m = 1.0", "m = 3.0")).mass.x0 == 0.25
    with pytest.raises(SceneError, match=r"\[mass\] m: must be >= 2.0, got 1.0"):
        parse_scene(text)


def test_the_value_keys_are_the_scenes_values():
    """The keys with only the upper magnitude bound are scene.VALUES, the FMU parameters' rule too."""
    values = {key.name for table in schema.SCHEMA.values() for _, key in table.all_keys() if key.value}
    assert values == set(VALUES)


def test_the_choices_of_the_registries_resolve():
    from prandtl_fmu.steppers import STEPPERS

    assert schema.SCHEMA["solver"].key("stepper").choice_names() == tuple(STEPPERS)
    assert "mean" in schema.SCHEMA["branches"].key("sampling", "density count").choice_names()


def test_the_network_keys_name_the_elements_coefficients():
    from prandtl_fmu.network.model import KEYS, KINDS

    network = schema.SCHEMA["network"].keys()
    for kind in KINDS:
        assert network[kind].type == "list of tables"
        assert set(KEYS[kind]) <= set(schema.SCHEMA[f"network.{kind}"].keys())


# ---------------------------------------------------------------------------------- the scenes we ship and show

def unknown_keys(document: dict) -> list:
    """The keys of a scene document that the schema does not know, as "[table] key"."""
    network = "network" in document or "chain" in document
    top = schema.SCHEMA["scene"].keys("network" if network else "element")
    unknown = []

    def walk(name, data):
        table = schema.SCHEMA[name]
        known = {key.name for _, key in table.all_keys()}
        for key, value in data.items():
            if key not in known:
                unknown.append(f"[{name}] {key}")
            elif isinstance(value, dict) and f"{name}.{key}" in schema.SCHEMA:
                walk(f"{name}.{key}", value)
            elif isinstance(value, list) and f"{name}.{key}" in schema.SCHEMA:
                for item in value:
                    walk(f"{name}.{key}", item)

    for key, value in document.items():
        if key not in top:
            unknown.append(key)
        elif isinstance(value, dict):
            walk(key, value)
    return unknown


def example_scenes() -> list:
    """Every scene file we ship or show: the packaged scenes and the examples (not the sweep files)."""
    paths = sorted(PACKAGED_SCENES.rglob("*.toml")) + sorted((ROOT / "examples").rglob("*.toml"))
    return [path for path in paths if "solver" in read_toml(path, "a scene")]


def test_the_example_scenes_use_only_keys_of_the_schema():
    scenes = example_scenes()
    assert len(scenes) >= 20
    for path in scenes:
        assert unknown_keys(read_toml(path, "a scene")) == [], path


def test_the_unknown_key_finder_finds_them():
    assert unknown_keys({"mass": {"m": 1, "mass": 2}, "springs": {}}) == ["[mass] mass", "springs"]
    assert unknown_keys({"network": {"spring": [{"k": 1, "k0": 2}]}}) == ["[network.spring] k0"]
    assert unknown_keys({"branches": {"density": {"kind": "iwan", "F_s": 1}}}) == ["[branches.density] F_s"]


def toml_blocks(path: pathlib.Path) -> list:
    """The ```toml blocks of a Markdown file."""
    return re.findall(r"^```toml\n(.*?)^```", path.read_text(encoding="utf-8"), flags=re.M | re.S)


COMMENTED_KEY = re.compile(r"^#\s*([A-Za-z_][A-Za-z0-9_]*)\s*=")
TABLE_LINE = re.compile(r"^\s*\[\[?([A-Za-z_.]+)\]\]?")


def commented_keys(block: str) -> list:
    """``(table, key)`` of the keys a block shows in comments (``# alpha = [...]``: the alternatives), the table
    being the last one opened above."""
    found, current = [], "scene"
    for line in block.splitlines():
        header = TABLE_LINE.match(line)
        if header:
            current = header.group(1)
            continue
        for part in line.split(";"):
            match = COMMENTED_KEY.match(part.strip())
            if match:
                found.append((current, match.group(1)))
            inline = re.search(r"density = \{(.*)\}", part)
            if inline:
                found += [("branches.density", key) for key in re.findall(r"(\w+) =", inline.group(1))]
    return found


def test_the_scene_format_page_uses_only_keys_of_the_schema():
    blocks = toml_blocks(ROOT / "docs" / "scene-format.md")
    assert len(blocks) >= 4
    for block in blocks:
        assert unknown_keys(toml_document(block, "docs/scene-format.md")) == [], block[:200]
        for table, key in commented_keys(block):
            known = {k.name for _, k in schema.table(table if table in schema.SCHEMA else "scene").all_keys()}
            assert key in known, f"docs/scene-format.md shows [{table}] {key}, which the schema does not know"


def _generator():
    spec = importlib.util.spec_from_file_location("gen_pages", ROOT / "docs" / "gen_pages.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_scene_reference_lists_every_key_of_the_schema():
    page = _generator().scene_reference()
    sections = dict(re.findall(r"^## `\[+([\w.]+)\]+`\n(.*?)(?=^## |\Z)", page, flags=re.M | re.S))
    for table in schema.SCHEMA.values():
        if table.name == "scene":
            continue
        assert table.name in sections, table.name
        for _, key in table.all_keys():
            assert f"| `{key.name}` |" in sections[table.name], (table.name, key.name)
    top = page.split("\n## ", 1)[0]
    for _, key in schema.SCHEMA["scene"].all_keys():
        assert f"`{key.name}`" in top, key.name


def test_the_default_lists_have_the_length_asked():
    r = _Reader("t.toml", "network", {"nodes": ["a"], "mass": [1.0]})
    r.only()
    np.testing.assert_array_equal(r.numbers("x0", length=3), np.zeros(3))
    with pytest.raises(schema.SchemaError, match="needs its length"):
        r.numbers("v0")
