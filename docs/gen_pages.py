"""The generated parts of the documentation site, and the MkDocs hook that puts them in (``hooks:`` in mkdocs.yml).

A page asks for a generated part with a marker line ``<!-- generated: NAME -->``; at build time the hook replaces
it with ``GENERATED[NAME]()``, computed from the code itself so that the page cannot drift from it:

* ``scene_reference``: every table and key of a scene, from ``prandtl_fmu/schema.py``, the table the scene reader
  reads by;
* ``stepper_table``: each stepper's order (its ``ORDER``), its scheme (its docstring's first line) and which
  scenes it takes (its own ``loop_for`` asked on one scene per effect: the refusal it gives, word for word);
* ``fmu_variables``: every variable of the FMUs, from the model descriptions the builds write (FMI 2.0, both
  runtimes; FMI 3.0, the native runtime), for a scene of each effect;
* ``api_reference``: mkdocstrings blocks for the public names ``prandtl_fmu`` exports, found where they live now.

The hook also makes the README the site's home page (``index.md``) and turns a link to a file of the repository
outside ``docs/`` into a link to the repository (``repo_url``) or, without one, into plain text.

Run alone (``python docs/gen_pages.py NAME``) it prints one generated part.
"""
from __future__ import annotations

import importlib
import os
import pathlib
import re
import sys
import tempfile
import textwrap
import xml.etree.ElementTree as ET

DOCS = pathlib.Path(__file__).resolve().parent
ROOT = DOCS.parent
if str(ROOT) not in sys.path:  # the site documents this checkout's package, whatever else is installed
    sys.path.insert(0, str(ROOT))
MARKER = re.compile(r"^<!-- generated: (\w+) -->$", re.M)


def _cell(text) -> str:
    """Text for a Markdown table cell (``psi_[a, b](u)`` is not a link)."""
    return str(text).replace("|", "\\|").replace("\n", " ").replace("](", "]\\(")


# ----------------------------------------------------------------------------------------------- scene reference

def _default(key) -> str:
    from prandtl_fmu import schema

    if key.default is schema.REQUIRED:
        return "**required**"
    if key.default is schema.OPTIONAL:
        return f"absent: {key.absent}"
    if isinstance(key.default, schema.SameAs):
        return f"= `{key.default.key}`"
    if isinstance(key.default, bool):
        return f"`{str(key.default).lower()}`"
    if isinstance(key.default, str):
        return f'`"{key.default}"`'
    if key.type == "list of numbers":
        return f"`{key.default:g}` each"
    return f"`{key.default:g}`" if isinstance(key.default, float) else f"`{key.default}`"


def _rule(table, key) -> str:
    """What the reader checks of ``key``: the schema's bounds, the kind of number, and the key's own rule."""
    parts = []
    if key.positive:
        parts.append("> 0")
    if key.minimum is not None:
        parts.append(f">= {key.minimum:g}")
    if key.maximum is not None:
        parts.append(f"<= {key.maximum:g}")
    choices = key.choice_names()
    if choices:
        parts.append("one of " + ", ".join(f'`"{choice}"`' for choice in choices))
    numeric = key.type in ("number", "list of numbers", "number or list of numbers")
    if numeric and table.numbers != "times" and (key.value or table.numbers == "values"):
        parts.append("a value")
    if key.rule:
        parts.append(key.rule)
    return "; ".join(parts)


def _power(value: float) -> str:
    return f"{value:.0e}".replace("e+", "e")


def _heading(table) -> str:
    return f"`[[{table.name}]]`" if table.many else f"`[{table.name}]`"


def scene_reference() -> str:
    """Every table and key of a scene file, from the schema the reader reads by."""
    from prandtl_fmu import schema
    from prandtl_fmu.scene_tables import LARGEST_MAGNITUDE, SMALLEST_MAGNITUDE

    lines = [
        "Every key below is read by the scene reader with exactly this type, default and bound: the reader takes "
        "them from the same table (`prandtl_fmu/schema.py`), and a key it would read that the table lacks is a "
        "bug a test catches. A key of no table, or of another form of its table, is refused with the keys "
        "allowed there.",
        "",
        f"**Numbers.** A *coefficient* (every number of a physical table unless marked *a value*) is 0 or has "
        f"|value| in [{_power(SMALLEST_MAGNITUDE)}, {_power(LARGEST_MAGNITUDE)}]; *a value* (an initial state, a "
        f"belt's speed, every number of `[load]`) has |value| <= {_power(LARGEST_MAGNITUDE)}; the `[solver]` times "
        "have their own rules. Every number is finite. An integer is a number; a number is not an integer.",
        "",
        "**Rule** lists what the reader refuses: the bounds, then what the reader's code checks besides (what ties "
        "keys together). **Forms**: a table with several forms takes the keys of one of them, chosen as "
        "its line says.",
        "",
        "**Top level.** An element scene may hold "
        + ", ".join(f"`{key.name}`" for key in schema.SCHEMA["scene"].forms["element"])
        + "; a network scene (one with `[network]` or `[chain]`) "
        + ", ".join(f"`{key.name}`" for key in schema.SCHEMA["scene"].forms["network"])
        + ". `name` is free text (default: the file name without `.toml`); `[solver]` is required; an absent "
          "table is an absent effect.",
        "",
    ]
    for table in schema.SCHEMA.values():
        if table.name == "scene":
            continue
        lines += [f"## {_heading(table)}", "", _cell(table.meaning[0].upper() + table.meaning[1:]) + "."]
        if table.source:
            lines += ["", f"*Source:* {_cell(table.source)}."]
        if len(table.forms) > 1:
            lines += ["", f"**Forms** (chosen {table.choose}):", ""]
            lines += [f"* *{form}*: " + ", ".join(f"`{key.name}`" for key in keys)
                      for form, keys in table.forms.items()]
        rows = []  # one row per distinct key (a key may differ between forms: then one row for each)
        for form, key in table.all_keys():
            for row in rows:
                if row[0] == key:
                    row[1].append(form)
                    break
            else:
                rows.append((key, [form]))
        several = len(table.forms) > 1
        lines += ["", "| key | type | unit | default | rule | meaning |" + (" forms |" if several else ""),
                  "|---|---|---|---|---|---|" + ("---|" if several else "")]
        for key, forms in rows:
            cells = [f"`{key.name}`", key.type, key.unit, _default(key), _rule(table, key), key.meaning]
            if several:
                cells.append("all" if len(forms) == len(table.forms) else ", ".join(forms))
            lines.append("| " + " | ".join(_cell(cell) for cell in cells) + " |")
        lines.append("")
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------------- steppers

# One scene per effect, for the applicability table: the stepper's own loop_for says whether it takes it.
_SOLVER = "\n[solver]\nstep = 0.01\nstop_time = 1.0\noutput_interval = 0.1\n"
STEPPER_SCENES = {
    "mass, springs, dashpot, branches": "[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[damper]\nc = 0.1\n"
                                        "[branches]\nk = [1.0]\neta = [0.1]\n",
    "cubic spring": "[mass]\nm = 1.0\n[cubic]\nk3 = 1.0\n",
    "massless, with a dashpot": "[spring]\nk0 = 1.0\n[damper]\nc = 1.0\n[branches]\nk = [1.0]\neta = [0.1]\n",
    "massless, quasi-static": "[spring]\nk0 = 1.0\n[branches]\nk = [1.0]\neta = [0.1]\n",
    "many branches (n >= 64: the memory stack)": "[mass]\nm = 1.0\n[branches]\ncount = 100\nk_total = 1.0\n"
                                                 "eta_range = [0.1, 1.1]\n",
    "the continuum": "[mass]\nm = 1.0\n[branches]\ncontinuum = true\nk_total = 1.0\neta_range = [0.1, 1.1]\n",
    "series dashpots": "[mass]\nm = 1.0\n[branches]\nk = [1.0]\neta = [0.1]\nc = [1.0]\n",
    "Coulomb friction on the mass": "[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[friction]\nalpha = 0.1\n",
    "Stribeck friction": "[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[friction]\nalpha = 0.1\nalpha_kinetic = 0.05\n"
                         "stribeck_velocity = 0.1\n",
    "friction on a belt": "[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[friction]\nalpha = 0.1\nbelt_velocity = 0.1\n",
    "random load": "[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[load]\nkind = \"random\"\nseed = 1\nrms = 0.1\n"
                   "band = [0.1, 1.0]\n",
    "white noise": "[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[damper]\nc = 0.1\n[load]\nkind = \"white_noise\"\n"
                   "intensity = 0.1\nseed = 1\n",
    "delay": "[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[delay]\ngain = 0.1\ntau = 0.5\n",
    "history": "[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[history]\nweight = [0.1]\nrate = [1.0]\n",
    "Dahl friction": "[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[dahl]\nsigma = 10.0\nforce = 0.1\n",
    "a network with masses and branches": "[network]\nnodes = [\"a\"]\nmass = [1.0]\n[[network.branch]]\n"
                                          "between = [\"a\", \"ground\"]\nk = 1.0\neta = 0.1\n",
    "a network with a slider or a massless node": "[network]\nnodes = [\"a\"]\nmass = [0.0]\n[[network.spring]]\n"
                                                  "between = [\"a\", \"ground\"]\nk = 1.0\n[[network.slider]]\n"
                                                  "between = [\"a\", \"ground\"]\nalpha = 0.1\n",
}


def stepper_table() -> str:
    """Each stepper: its order and scheme, and which of STEPPER_SCENES it takes (its refusal where it does not)."""
    from prandtl_fmu import STEPPERS, parse_scene

    def first_line(module) -> str:
        return " ".join((module.__doc__ or "").strip().split("\n\n")[0].split())

    def order(module) -> str:
        value = getattr(module, "ORDER", None)
        return "exact" if value == float("inf") else str(value)

    lines = ["| stepper | order | scheme |", "|---|---|---|"]
    lines += [f"| `{name}` | {order(module)} | {_cell(first_line(module).replace('``', '`'))} |"
              for name, module in STEPPERS.items()]
    lines += ["", "Which scenes each stepper takes (✓), and why not where it does not (its own refusal, word for "
              "word: the scene reader refuses such a scene with it, and the CLI's `--stepper` may pick another):",
              "", "| scene | " + " | ".join(f"`{name}`" for name in STEPPERS) + " |", "|---|" + "---|" * len(STEPPERS)]
    reasons = []
    for label, body in STEPPER_SCENES.items():
        cells = []
        for name in STEPPERS:
            try:
                parse_scene(body + _SOLVER.replace("[solver]\n", f'[solver]\nstepper = "{name}"\n'),
                            source=label)
                cells.append("✓")
            except ValueError as exc:
                reason = str(exc).split("stepper: ", 1)[-1]
                if reason not in reasons:
                    reasons.append(reason)
                cells.append(f"✗ [{reasons.index(reason) + 1}](#refusal-{reasons.index(reason) + 1})")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    lines += ["", "Refusals:", ""]
    lines += [f'<span id="refusal-{i}"></span>{i}. {_cell(reason)}' for i, reason in enumerate(reasons, start=1)]
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------------------------------------ FMU variables

_S = "\n[solver]\nstepper = \"implicit\"\nstep = 0.001\nstop_time = 1.0\noutput_interval = 0.01\n"
_ELEMENT_BASE = "[mass]\nm = 1.0\n"
_CONNECTOR_BASE = "[fmu]\ncausality = \"displacement\"\n[spring]\nk0 = 1.0\n"
# The FMUs whose variables the page lists: a base scene and the base with one table more, so that the tables a
# variable comes with are the variants it appears in.
ELEMENT_VARIANTS = {
    "[mass]": _ELEMENT_BASE,
    "no [mass]": "[spring]\nk0 = 1.0\n",
    "[spring]": _ELEMENT_BASE + "[spring]\nk0 = 1.0\n",
    "[cubic]": _ELEMENT_BASE + "[cubic]\nk3 = 1.0\n",
    "[damper]": _ELEMENT_BASE + "[damper]\nc = 0.1\n",
    "[branches]": _ELEMENT_BASE + "[branches]\nk = [1.0, 2.0]\neta = [0.1, 0.2]\n",
    "[branches] c = [...]": _ELEMENT_BASE + "[branches]\nk = [1.0, 2.0]\neta = [0.1, 0.2]\nc = [1.0, 2.0]\n",
    "[branches] count, c": _ELEMENT_BASE + "[branches]\ncount = 3\nk_total = 1.0\neta_range = [0.1, 0.2]\nc = 1.0\n",
    "[branches] continuum": _ELEMENT_BASE + "[branches]\ncontinuum = true\nk_total = 1.0\neta_range = [0.1, 0.2]\n",
    "[friction]": _ELEMENT_BASE + "[friction]\nalpha = 0.1\n",
    "[friction] Stribeck": _ELEMENT_BASE + "[friction]\nalpha = 0.1\nalpha_kinetic = 0.05\n"
                           "stribeck_velocity = 0.1\n",
    "a white noise": _ELEMENT_BASE + "[load]\nkind = \"white_noise\"\nintensity = 0.1\nseed = 1\n",
    "[delay]": _ELEMENT_BASE + "[delay]\ngain = 0.1\ntau = 0.5\n",
    "[history]": _ELEMENT_BASE + "[history]\nweight = [0.1, 0.2]\nrate = [1.0, 2.0]\n",
    "[dahl]": _ELEMENT_BASE + "[dahl]\nsigma = 10.0\nforce = 0.1\n",
}
CONNECTOR_VARIANTS = {
    "[spring]": _CONNECTOR_BASE,
    "[cubic]": _CONNECTOR_BASE + "[cubic]\nk3 = 1.0\n",
    "[damper]": _CONNECTOR_BASE + "[damper]\nc = 0.1\n",
    "[branches]": _CONNECTOR_BASE + "[branches]\nk = [1.0, 2.0]\neta = [0.1, 0.2]\n",
    "[branches] continuum": _CONNECTOR_BASE + "[branches]\ncontinuum = true\nk_total = 1.0\neta_range = [0.1, 0.2]\n",
    "[delay]": _CONNECTOR_BASE + "[delay]\ngain = 0.1\ntau = 0.5\n",
    "[history]": _CONNECTOR_BASE + "[history]\nweight = [0.1]\nrate = [1.0]\n",
    "[dahl]": _CONNECTOR_BASE + "[dahl]\nsigma = 10.0\nforce = 0.1\n",
}
# The scenes whose descriptions the tables show: every effect at once, so that a formula (the reaction's, the
# stored energy's) names every term it can have.
DESCRIBED = {
    "force": _ELEMENT_BASE + "[spring]\nk0 = 1.0\n[cubic]\nk3 = 1.0\n[damper]\nc = 0.1\n[branches]\nk = [1.0, 2.0]\n"
                             "eta = [0.1, 0.2]\nc = [1.0, 2.0]\n[friction]\nalpha = 0.1\nalpha_kinetic = 0.05\n"
                             "stribeck_velocity = 0.1\n[delay]\ngain = 0.1\ntau = 0.5\n[history]\nweight = [0.1, 0.2]\n"
                             "rate = [1.0, 2.0]\n",
    "displacement": _CONNECTOR_BASE + "[cubic]\nk3 = 1.0\n[damper]\nc = 0.1\n[branches]\nk = [1.0, 2.0]\n"
                                      "eta = [0.1, 0.2]\n[delay]\ngain = 0.1\ntau = 0.5\n[history]\nweight = [0.1]\n"
                                      "rate = [1.0]\n[dahl]\nsigma = 10.0\nforce = 0.1\n",
}
# A network of every kind of element; its node and element names are replaced by placeholders in the table.
_NETWORK = """[network]
nodes = ["NodeA", "NodeB"]
mass = [1.0, MASS_B]
[[network.spring]]
between = ["NodeA", "ground"]
k = 1.0
name = "SpringX"
[[network.dashpot]]
between = ["NodeA", "NodeB"]
c = 0.1
name = "DashpotX"
[[network.slider]]
between = ["NodeA", "ground"]
alpha = 0.5
name = "SliderX"
[[network.branch]]
between = ["NodeA", "NodeB"]
k = 1.0
eta = 0.1
c = 1.0
name = "BranchX"
[[network.cubic]]
between = ["NodeB", "ground"]
k3 = 1.0
name = "CubicX"
"""
NETWORK_VARIANTS = {"force": _NETWORK.replace("MASS_B", "1.0"),
                    "displacement": _NETWORK.replace("MASS_B", "0.0") + "[fmu]\ncausality = \"displacement\"\n"}
PLACEHOLDERS = {"NodeA": "<node>", "NodeB": "<node>", "SpringX": "<spring>", "DashpotX": "<dashpot>",
                "SliderX": "<slider>", "BranchX": "<branch>", "CubicX": "<cubic>"}


def _descriptions(text: str, folder: pathlib.Path, label: str) -> dict:
    """``{"2.0": root, "3.0": root}``: the model descriptions of the FMUs of the scene ``text``, FMI 2.0 (both
    runtimes declare the same variables; the PythonFMU one is asked for) and 3.0 (the native runtime's).

    From ``prandtl_fmu.fmu.description.model_description``, the one source both runtimes' builds write their
    descriptions from; where it is not there yet, from the FMU ``build_fmu`` builds and the FMI 3.0 description the
    native build makes from it (without compiling kernels)."""
    from prandtl_fmu.scene import load_scene

    stem = re.sub(r"\W+", "_", label).strip("_") or "scene"
    path = folder / f"{stem}.toml"
    solver = _S.replace('"implicit"', '"projected"') if "continuum = true" in text else _S  # (implicit refuses it)
    path.write_text(f'name = "{stem}"\n' + text + solver, encoding="utf-8")
    scene = load_scene(path, check_stepper=False)
    try:
        from prandtl_fmu.fmu.description import model_description
    except ImportError:
        model_description = None
    if model_description is not None:
        return {"2.0": ET.fromstring(model_description(scene, fmi=2, runtime="python")),
                "3.0": ET.fromstring(model_description(scene, fmi=3))}
    import zipfile

    from prandtl_fmu.fmu.build import build_fmu

    with zipfile.ZipFile(build_fmu(path, folder / f"{stem}.fmu")) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
    count = max(int(v.get("valueReference")) for v in root.iter("ScalarVariable")) + 1
    if hasattr(scene, "network"):
        from prandtl_fmu.fmu.native.network_build import fmi3_network_description

        extra = {"time": count, "n_nodes": count + 1, "x_nodes": count + 2, "v_nodes": count + 3}
        fmi3 = fmi3_network_description(root, scene, extra, False, scene.causality == "displacement")
    else:
        from prandtl_fmu.fmu.native.build import fmi3_description

        fmi3 = fmi3_description(root, scene, count)
    return {"2.0": root, "3.0": ET.fromstring(fmi3)}


def _variables(root, fmi: str) -> dict:
    """name -> (type, causality, variability, unit, description) of a model description."""
    found = {}
    if fmi == "2.0":
        for variable in root.iter("ScalarVariable"):
            kind = next(child for child in variable if child.tag in ("Real", "Integer", "Boolean", "String"))
            found[variable.get("name")] = (kind.tag, variable.get("causality") or "local",
                                           variable.get("variability") or "continuous", kind.get("unit") or "",
                                           variable.get("description") or "")
    else:
        for variable in root.find("ModelVariables"):
            found[variable.get("name")] = (variable.tag, variable.get("causality") or "local",
                                           variable.get("variability") or "continuous",
                                           variable.get("unit") or "", variable.get("description") or "")
    return found


def _generalized(name: str, description: str) -> tuple:
    """The variable's name and description with the network's names as placeholders, and an index (u_2,
    c_branch[2], history_rate[2]) as <i>."""
    for token, placeholder in PLACEHOLDERS.items():
        name, description = name.replace(token, placeholder), description.replace(token, placeholder)
    index = re.search(r"(?:_(\d+)|\[(\d+)\])$", name)
    if index:
        number = index.group(1) or index.group(2)
        name = name[:index.start()] + ("_<i>" if index.group(1) else "[<i>]")
        description = re.sub(rf"(?<![\w.]){number}(?![\w.])|(?<=_){number}(?![\w.])", "<i>", description)
    return name, description


def _variable_table(variants: dict, folder: pathlib.Path, network: bool = False, described: str = "") -> list:
    """The rows of one kind of FMU: every variable of every variant, with the variants it appears in, described as
    the FMU of the scene ``described`` (every effect at once) describes it."""
    seen = {}  # generalized name -> {"2.0": info, "3.0": info, "in": [labels]}
    order = []
    richest = {}  # generalized name -> its description in the FMU of ``described``
    if described:
        for fmi, root in _descriptions(described, folder, "described").items():
            richest.update(_generalized(name, info[4]) for name, info in _variables(root, fmi).items())
    for label, text in variants.items():
        for fmi, root in _descriptions(text, folder, label).items():
            for name, info in _variables(root, fmi).items():
                general, description = _generalized(name, info[4])
                info = info[:4] + (richest.get(general, description),)
                if general not in seen:
                    seen[general] = {"in": []}
                    order.append(general)
                entry = seen[general]
                entry.setdefault(fmi, info)
                if label not in entry["in"]:
                    entry["in"].append(label)
    labels = list(variants)
    rows = ["| variable | causality | variability | unit | FMI 2.0 | FMI 3.0 | in | what |",
            "|---|---|---|---|---|---|---|---|"]
    for name in order:
        entry = seen[name]
        info = entry.get("2.0") or entry.get("3.0")
        present = entry["in"]
        if network or len(present) == len(labels):
            where = "always"
        elif len(present) > len(labels) / 2:
            where = "not with " + ", ".join(label for label in labels if label not in present)
        else:
            where = ", ".join(present)
        types = [entry[fmi][0] if fmi in entry else "—" for fmi in ("2.0", "3.0")]
        cells = [f"`{name}`", info[1], info[2], info[3], types[0], types[1], where, info[4]]
        rows.append("| " + " | ".join(_cell(cell) for cell in cells) + " |")
    return rows


def fmu_variables() -> str:
    """Every variable of the element, connector, network and network connector FMUs."""
    with tempfile.TemporaryDirectory(prefix="prandtl_docs_") as scratch:
        folder = pathlib.Path(scratch)
        lines = ["### The element (`PrandtlElement`, causality \"force\")", "",
                 "Built from the scene `[mass] m = 1` and from it with one table more each: **in** names the "
                 "scenes whose FMU has the variable (all of them: *always*). The descriptions are those of a scene "
                 "with every effect at once (a formula names every term it can have).", ""]
        lines += _variable_table(ELEMENT_VARIANTS, folder, described=DESCRIBED["force"])
        lines += ["", "### The connector (`PrandtlConnector`, causality \"displacement\")", "",
                  "Built from the massless scene `[spring] k0 = 1`, `[fmu] causality = \"displacement\"` and from "
                  "it with one table more each.", ""]
        lines += _variable_table(CONNECTOR_VARIANTS, folder, described=DESCRIBED["displacement"])
        lines += ["", "### A network (`PrandtlNetwork`)", "",
                  "Built from a network of two nodes with one element of each kind; `<node>` stands for each "
                  "node's name, `<spring>`, `<branch>`... for each element's.", ""]
        lines += _variable_table({"network": NETWORK_VARIANTS["force"]}, folder, network=True)
        lines += ["", "### A network connector (`PrandtlNetworkConnector`)", "",
                  "The same network with a massless load node and `[fmu] causality = \"displacement\"`.", ""]
        lines += _variable_table({"network connector": NETWORK_VARIANTS["displacement"]}, folder, network=True)
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------------------------- API reference

# Public entry points beside ``prandtl_fmu.__all__``, by the name a user imports them by.
MORE_ENTRY_POINTS = [
    "prandtl_fmu.connector.Connector", "prandtl_fmu.connector.displacement_response",
    "prandtl_fmu.sweep.sweep", "prandtl_fmu.fmu.build.build_fmu",
    "prandtl_fmu.identify.fit", "prandtl_fmu.identify.fit_continuum",
    "prandtl_fmu.frequency.describe_amplitudes", "prandtl_fmu.frequency.frequency_response",
]


def _resolve(dotted: str):
    module, _, name = dotted.rpartition(".")
    return getattr(importlib.import_module(module), name)


def api_reference() -> str:
    """mkdocstrings blocks for the names ``prandtl_fmu`` exports and the entry points above, each at the module
    that defines it now (the names survive a move of their module)."""
    import prandtl_fmu

    lines = []
    entries = [(f"prandtl_fmu.{name}", getattr(prandtl_fmu, name)) for name in prandtl_fmu.__all__]
    entries += [(dotted, _resolve(dotted)) for dotted in MORE_ENTRY_POINTS]
    for public, value in entries:
        home = getattr(value, "__module__", None)
        qualname = getattr(value, "__qualname__", None)
        if home is None or qualname is None:  # a registry (STEPPERS): say what it holds
            lines += [f"## `{public}`", "", f"`{public}` = `{{{', '.join(repr(k) for k in value)}}}`: "
                      "a mapping of names to modules", ""]
            continue
        lines += [f"## `{public}`", "", f"::: {home}.{qualname}", "    options:", "        show_root_heading: false",
                  ""]
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------- the code layout

def _first_paragraph(docstring: str) -> str:
    return " ".join(docstring.strip().split("\n\n")[0].split())


def code_layout() -> str:
    """The package's own account of its layers (its docstring), and every module with the first paragraph of its
    docstring, read from the sources (nothing imported)."""
    import ast

    package = ROOT / "prandtl_fmu"
    top = ast.get_docstring(ast.parse((package / "__init__.py").read_text(encoding="utf-8"))) or ""
    lines = ["From `prandtl_fmu/__init__.py`:", "", textwrap.indent(top.strip(), "> ", lambda line: True), "",
             "| module | what it holds |", "|---|---|"]
    for path in sorted(package.rglob("*.py")):
        if "loader" in path.relative_to(package).parts[:-1] and path.name != "__init__.py":
            continue  # the FMU loader's build helpers
        name = path.relative_to(ROOT).with_suffix("").as_posix().replace("/", ".").removesuffix(".__init__")
        docstring = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or "(no docstring)"
        lines.append(f"| `{name}` | {_cell(_first_paragraph(docstring).replace('``', '`'))} |")
    return "\n".join(lines) + "\n"


GENERATED = {"scene_reference": scene_reference, "stepper_table": stepper_table, "fmu_variables": fmu_variables,
             "api_reference": api_reference, "code_layout": code_layout}


def _digest_of(name: str) -> str:
    """A digest of everything ``GENERATED[name]`` depends on: the package's sources, its own section of this file,
    the versions of Python and of the package that writes model descriptions."""
    import hashlib
    from importlib.metadata import version

    digest = hashlib.sha256(f"{name} {version('pythonfmu')} {sys.version}".encode())
    for path in sorted((ROOT / "prandtl_fmu").rglob("*")):
        if path.is_file() and path.suffix in (".py", ".c", ".h", ".toml"):
            digest.update(path.relative_to(ROOT).as_posix().encode() + b"\0" + path.read_bytes())
    source = pathlib.Path(__file__).read_text(encoding="utf-8")
    section = source.split(f"# {'-' * 20}")  # the sections of this file, one per generated part
    digest.update("".join(part for part in section if f"def {name}(" in part).encode())
    return digest.hexdigest()[:16]


# The generated parts that take long enough (FMUs built) to be kept between builds, under their digest.
KEPT = ("fmu_variables",)


def generated(name: str) -> str:
    """``GENERATED[name]()``; a part of KEPT is kept in the temporary folder under its digest, so that ``mkdocs
    serve`` does not build FMUs again at every edit of a page (a change of what it depends on changes the
    digest)."""
    if name not in KEPT:
        return GENERATED[name]()
    kept = pathlib.Path(tempfile.gettempdir()) / "prandtl_fmu_docs" / f"{name}-{_digest_of(name)}.md"
    if kept.is_file():
        return kept.read_text(encoding="utf-8")
    text = GENERATED[name]()
    kept.parent.mkdir(parents=True, exist_ok=True)
    partial = kept.with_name(f"{kept.name}.{os.getpid()}")
    partial.write_text(text, encoding="utf-8")
    os.replace(partial, kept)
    return text


# ------------------------------------------------------------------------------------------------ the MkDocs hook

LINK = re.compile(r"(!?\[[^\]]*\])\(([^)\s]+)\)")


def _outside_links(markdown: str, page_path: str, repo_url: str | None) -> str:
    """Links of a page to files of the repository outside docs/ (``../prandtl_fmu/x.py``, the README's
    ``examples/...``) turned into links to the repository, or without ``repo_url`` into plain text."""
    folder = (DOCS / page_path).parent

    def fix(match):
        text, target = match.group(1), match.group(2)
        if re.match(r"^[a-z]+:|^#|^/", target):
            return match.group(0)
        path = (folder / target.split("#")[0]).resolve()
        try:
            path.relative_to(DOCS)
            return match.group(0)
        except ValueError:
            pass
        try:
            inside = path.relative_to(ROOT).as_posix()
        except ValueError:
            return match.group(0)
        if inside == "README.md":
            return f"{text}({os.path.relpath(DOCS / 'index.md', folder)})"
        if repo_url:
            return f"{text}({repo_url.rstrip('/')}/blob/main/{inside})"
        return text[1:-1] if not text.startswith("!") else match.group(0)

    return LINK.sub(fix, markdown)


def readme_as_index() -> str:
    """The README with its links made relative to docs/: the site's home page."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")

    def relative(match):
        text, target = match.group(1), match.group(2)
        if target.startswith("docs/"):
            return f"{text}({target[len('docs/'):]})"
        if target == "CHANGELOG.md":
            return f"{text}(changelog.md)"
        if re.match(r"^[a-z]+:|^#|^/", target):
            return match.group(0)
        return f"{text}(../{target})"  # a file of the repository: on_page_markdown links it there

    return LINK.sub(relative, text)


def on_files(files, config):
    from mkdocs.structure.files import File

    if files.get_file_from_path("index.md") is None:
        files.append(File.generated(config, "index.md", content=readme_as_index()))
    if files.get_file_from_path("changelog.md") is None:  # CHANGELOG.md, the one file that holds dates
        files.append(File.generated(config, "changelog.md",
                                    content=(ROOT / "CHANGELOG.md").read_text(encoding="utf-8")))
    return files


def on_page_markdown(markdown, page, config, files):
    markdown = MARKER.sub(lambda match: generated(match.group(1)), markdown)
    return _outside_links(markdown, page.file.src_uri, config.get("repo_url"))


if __name__ == "__main__":
    print(GENERATED[sys.argv[1]]())
