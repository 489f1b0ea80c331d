"""``documentation/index.html`` of the FMU: the equations of *its* effects, its steppers, its variables."""
from __future__ import annotations

import html
import xml.etree.ElementTree as ET

from ..steppers import STEPPERS

_UNBOUNDED = 1e308  # a min or max beyond this is shown as no bound at all (the XML holds +-DBL_MAX)


def _terms(scene, spring, cubic, dashpot, branches, continuum):
    """The terms of the effects present, in the order spring, cubic, dashpot, branches."""
    pairs = [(scene.spring, spring), (scene.cubic, cubic), (scene.damper if scene.has_dashpot else None, dashpot),
             (scene.branches, continuum if scene.branches is not None and scene.branches.continuum else branches)]
    return [text for effect, text in pairs if effect is not None and text]


def reaction_formula(scene) -> str:
    """The reaction k0 x + k3 x^3 + c v + sum_i k_i u_i (+ the friction on the mass), with the terms of the
    effects present only."""
    terms = _terms(scene, "k0 x", "k3 x^3", "c v", "sum_i k_i u_i", "integral of k(s) u(s) ds")
    if scene.friction is not None:
        terms.append("A(v - v_b)")
    return " + ".join(terms) or "0"


def stiffness_formula(scene) -> str:
    """The tangent dF/dx, with the terms of the effects present only."""
    text = " + ".join(_terms(scene, "k0", "3 k3 x^2", None, "the k_i of the sticking branches",
                             "the integral of k(s) over the sticking branches")) or "0"
    if scene.friction is not None:
        text += " (the friction on the mass depends on v only: it adds no stiffness, stuck or sliding)"
    return text


def stored_energy_formula(scene) -> str:
    """The elastic energy, with the terms of the effects present only."""
    return " + ".join(_terms(scene, "k0 x^2/2", "k3 x^4/4", None, "sum_i k_i u_i^2/2",
                             "integral of k(s) u(s)^2/2 ds")) or "0"


def equations(scene) -> str:
    """The element's equations with the terms of the effects present only."""
    branches = scene.branches
    forces = _terms(scene, "k0 x", "k3 x^3", "c v", "sum_i k_i u_i", "integral of k(s) u(s) ds")
    reaction = reaction_formula(scene)
    lines = []
    if scene.mass is not None:
        lines += ["x' = v", f"m v' = F - ({reaction})"]
    elif scene.has_dashpot:
        elastic = " + ".join(f for f in forces if f != "c v") or "0"
        lines += [f"c x' = F - ({elastic})        (massless: the dashpot sets the rate)"]
    else:
        lines += [f"0 = F - ({reaction})        (massless, no dashpot: quasi-static equilibrium at every instant)"]
    lines += _branch_lines(branches)
    if scene.friction is not None:
        lines.append("A(w) = alpha sigma(w) + Psi(w), sigma the sign graph (the mass sticks, v = v_b, while "
                     "|F - the other forces| <= alpha)")
        if scene.friction.stribeck_velocity is not None:
            lines.append("A(w) = sign(w) (alpha_kinetic + (alpha - alpha_kinetic) exp(-|w| / stribeck_velocity))"
                         "  for w != 0 (Stribeck)")
    lines.append(f"reaction = {reaction}" + ("  (= F - m v')" if scene.mass is not None else ""))
    return "\n".join(lines)


def connector_equations(scene) -> str:
    """The connector's equations (x, v given), with the terms of the effects present only."""
    branches = scene.branches
    lines = [f"force = {reaction_formula(scene)}        (x, v: the inputs)"] + _branch_lines(branches)
    return "\n".join(lines)


def _branch_lines(branches) -> list:
    if branches is None:
        return []
    if branches.continuum:
        return ["u(s)' + d psi_[-eta(s), eta(s)](u(s)) ∋ x'   (|u(s)| <= eta(s), s in [0, 1])"]
    if branches.damping is not None:
        return [f"u_i' + d psi_[-eta_i, eta_i](u_i) ∋ x' - (k_i / c_i) u_i   (|u_i| <= eta_i, i = 1..{branches.n}; "
                "a dashpot c_i in series)"]
    return [f"u_i' + d psi_[-eta_i, eta_i](u_i) ∋ x'        (|u_i| <= eta_i, i = 1..{branches.n})"]


def _effect_text(scene) -> str:
    branches = scene.branches
    parts = []
    if scene.mass is not None:
        parts.append(f"a point of mass m = {scene.mass.m:.6g} kg")
    else:
        parts.append("no mass (the massless element)")
    if scene.spring is not None:
        parts.append(f"a linear spring k0 = {scene.spring.k0:.6g} N/m")
    if scene.cubic is not None:
        parts.append(f"a cubic spring k3 = {scene.cubic.k3:.6g} N/m3")
    if scene.has_dashpot:
        parts.append(f"a dashpot c = {scene.damper.c:.6g} N s/m")
    friction = scene.friction
    if friction is not None:
        law = (f"Stribeck's law down to alpha_kinetic = {friction.alpha_kinetic:.6g} N over "
               f"{friction.stribeck_velocity:.6g} m/s" if friction.stribeck_velocity is not None else "Coulomb's law")
        ground = f" moving at {friction.belt_velocity:.6g} m/s" if friction.belt_velocity else ""
        parts.append(f"friction on the ground{ground}: threshold alpha = {friction.alpha:.6g} N, {law}")
    if branches is None:
        parts.append("no friction branches")
    elif branches.continuum:
        parts.append(f"the continuous element: infinitely many branches s in [0, 1], {branches.description} "
                     f"(stiffness {branches.stiffness_sum:.6g} N/m, strength {branches.strength:.6g} N)")
    else:
        parts.append(f"{branches.n} Prandtl branches (a spring k_i in series with a Coulomb slider of threshold "
                     f"alpha_i = k_i eta_i): stiffness sum {branches.stiffness.sum():.6g} N/m, elastic ranges "
                     f"{branches.yield_displacement.min():.6g} to {branches.yield_displacement.max():.6g} m, "
                     f"strength sum alpha_i = {branches.strength:.6g} N"
                     + (", each with a dashpot in series" if branches.damping is not None else ""))
    return "; ".join(parts)


def _stepper_rows(scene, steppers=None) -> str:
    """The steppers' table: whether each applies to ``scene`` (``steppers``: the only ones the FMU holds)."""
    rows = []
    for name, module in STEPPERS.items():
        summary = module.__doc__.strip().split("\n\n")[0].replace("\n", " ").replace(f"``{name}``: ", "", 1)
        try:
            module.loop_for(scene)
            applies = "default" if name == scene.solver.stepper else "yes"
        except ValueError as exc:
            applies = f"no: {exc}"
        if steppers is not None and name not in steppers and not applies.startswith("no"):
            applies = "no: not in this FMU (built with --steppers " + ",".join(steppers) + ")"
        order = "exact (events located to rounding)" if module.ORDER == float("inf") else str(module.ORDER)
        rows.append("<tr>" + "".join(f"<td>{html.escape(cell)}</td>" for cell in (name, applies, order, summary))
                    + "</tr>")
    return "\n".join(rows)


def _bound(text: str) -> str:
    if not text:
        return ""
    try:
        return "" if abs(float(text)) >= _UNBOUNDED else text
    except ValueError:
        return text


def index_html(model_description: bytes, scene, runtime: str = "python", steppers=None) -> str:
    """The page, from the FMU's own modelDescription.xml (FMI 2.0 or 3.0) and its scene; ``runtime``: "python"
    (PythonFMU) or "native" (no Python in the host); ``steppers``: the only steppers a native FMU holds (None:
    every one that applies)."""
    root = ET.fromstring(model_description)
    fmi3 = root.get("fmiVersion", "").startswith("3")
    rows = []
    for var in root.find("ModelVariables"):
        typed = var if fmi3 else var[0]  # FMI 3.0: the type is the element; 2.0: its child
        start = typed.get("start", "")
        if fmi3 and typed.find("Start") is not None:
            start = typed.find("Start").get("value", "")
        rows.append("<tr>" + "".join(f"<td>{html.escape(str(cell))}</td>" for cell in (
            var.get("name"), var.get("causality", "local"), var.get("variability", "continuous"),
            typed.tag, typed.get("unit", ""), start, _bound(typed.get("min", "")),
            _bound(typed.get("max", "")), var.get("description", ""))) + "</tr>")
    name = html.escape(scene.name)
    version = "fmi3" if fmi3 else "fmi2"
    if runtime == "native":
        refusal = f"{version}Error"
        requirements = (_NATIVE_REQUIREMENTS.format(version="3.0" if fmi3 else "2.0")
                        + _derivatives_text(root.find("CoSimulation"),
                                            getattr(scene, "causality", None) == "displacement"))
    else:
        refusal = ("fmi2Error; fmi2Fatal where the FMU runs on PythonFMU's own binary: Windows, macOS")
        requirements = _PYTHON_REQUIREMENTS
    if hasattr(scene, "network"):
        body = network_body(scene, refusal, steppers)
        title = "Network of springs, dashpots, sliders and Prandtl branches"
    else:
        body = (_connector_body(scene, refusal) if scene.causality == "displacement"
                else _element_body(scene, refusal, steppers))
        title = "Generalized Prandtl element"
    return _page(name, rows, body.replace("fmi2Discard", f"{version}Discard"), requirements, title)


_PYTHON_REQUIREMENTS = """<p>A PythonFMU FMU runs in the host's Python: the host process needs Python 3 with numpy, numba and pythonfmu
(<code>pip install prandtl_fmu</code> installs them). A host that is not itself Python (OMSimulator's or ecos'
binaries) needs <code>LD_PRELOAD=&lt;libpython3.X.so&gt;</code> and <code>PYTHONPATH=&lt;the site-packages that
hold numpy and numba&gt;</code>: see the project's README.</p>"""

_NATIVE_REQUIREMENTS = """<p>This is the <b>native</b> FMU (FMI {version}): its binary holds the scene's kernels, compiled by numba
from the library's sources, and a C layer that only marshals values, validates calls and calls the kernels. It
needs no Python, no <code>LD_PRELOAD</code> and no <code>PYTHONPATH</code> in the host: any FMI {version}
co-simulation master loads it as it is. Its binary is built for Linux x86-64 (the libc and libm of the machine
that built it). Every refusal is logged with a declared category, whatever the logging setting.</p>"""


def _derivatives_text(capabilities, connector: bool = False) -> str:
    """What the model description declares of derivatives and intermediate update, in a paragraph ("" if none)."""
    said = []
    if capabilities.get("canInterpolateInputs") == "true" and connector:
        said.append("it takes the first and second derivatives of x and v (<code>fmi2SetRealInputDerivatives</code>): "
                    "over the next step its flanges follow x + x' (t - t0) + x'' (t - t0)^2 / 2, the branches by the "
                    "exact play update through the path's turning point")
    elif capabilities.get("canInterpolateInputs") == "true":
        said.append("it takes F's first and second derivatives (<code>fmi2SetRealInputDerivatives</code>): over the "
                    "next step its force is F + F' (t - t0) + F'' (t - t0)^2 / 2, evaluated at every internal step")
    if capabilities.get("providesIntermediateUpdate") == "true":
        said.append("with an intermediate update callback it asks the master for F at every internal step")
    if capabilities.get("maxOutputDerivativeOrder") and connector:
        said.append("it gives its force's first and second time derivatives (its output derivatives) along the path "
                    "its inputs' derivatives describe (x' = v where they are not set; one-sided, for the motion ahead)")
    elif capabilities.get("maxOutputDerivativeOrder"):
        said.append("it gives its outputs' time derivatives up to order "
                    f"{capabilities.get('maxOutputDerivativeOrder')} (x: v, a; v: a, a'; the reaction's rate; "
                    "one-sided, for the motion ahead)")
    if "true" in (capabilities.get("providesDirectionalDerivative"), capabilities.get("providesDirectionalDerivatives")):
        said.append("it gives the directional derivatives of its force in x (the tangent stiffness) and v (c)")
    return f"<p>For coupling at second order: {'; '.join(said)}.</p>" if said else ""


def _connector_body(scene, refusal: str) -> str:
    return f"""<p>This FMU is the element as a <b>connector</b> between two bodies that other FMUs hold: it takes the
relative displacement <code>x</code> and velocity <code>v</code> of its two flanges and returns the force
<code>force</code> it transmits. It holds {html.escape(_effect_text(scene))}. Effects the scene leaves out are
absent: they have no parameter and no term below. Model of Bastien &amp; Schatzman, M2AN 36 (2002), eq. (7.7),
with the dashpot and cubic spring of the related models; the scene is <code>resources/scene.toml</code>.</p>
<pre>{html.escape(connector_equations(scene))}</pre>
<h2>Stepping</h2>
<p>No time integration: the branches follow the exact play update along x, taken linear between the samples
the master sets (a master that gives only the end value of a step gets the linear interpolant; the play
operator is rate independent, so the time between samples does not matter). The outputs always show the element
at the inputs set last (<code>force</code> depends directly on <code>x</code> and <code>v</code>); only
<code>doStep</code> commits an input sample, so a master may set x several times at one communication point.
Initialization takes the element from x = 0 (elongations u0) to the first input x, monotonically.
<code>stiffness</code> is the tangent dF/dx for a motion in the direction of v (of the last motion when
v = 0): a master can choose a stable communication step from it, or build a coupling Jacobian.</p>
<p>A non-finite input at doStep is refused: fmi2Discard, a logged message, the state unchanged. A bad parameter
value is refused at initialization with a logged reason ({refusal}), or by a Discard during stepping. The instance stays usable. The
whole state can be saved, restored and serialized. OSP: <code>resources/PrandtlConnector_OspModelDescription.xml</code>
declares a LinearMechanicalPort (force out, v in) and a LinearMechanicalQuasiPort (force out, x in).</p>"""


def _element_body(scene, refusal: str, steppers=None) -> str:
    return f"""<p>This FMU holds {html.escape(_effect_text(scene))}, under the input force F. Effects the scene leaves out are
absent: they have no parameter and no term below. Model of Bastien &amp; Schatzman, M2AN 36 (2002), eq. (7.7),
with the dashpot and cubic spring of the related models; the scene is <code>resources/scene.toml</code>.</p>
<pre>{html.escape(equations(scene))}</pre>
<h2>Stepping</h2>
<p>The input F is held constant over each communication step (with the parameter <code>scene_load</code> true,
the scene's [load] F_scene(t) is added and evaluated at every internal step as in the library).
<code>doStep(t, H)</code> advances by whole internal
steps of the parameter <code>step</code> (default {scene.solver.step:g} s) and, when H is not a multiple of it, one
last shorter step for the remainder. The parameter <code>stepper</code> chooses the scheme:</p>
<table><tr><th>stepper</th><th>applies to this FMU</th><th>order</th><th>scheme</th></tr>
{_stepper_rows(scene, steppers)}
</table>
<p><code>projected</code> is the scheme (5.1) of the paper, which the paper calls "the implicit Euler scheme"
because it is implicit in the friction term only; our <code>implicit</code> is implicit in every term.</p>
<p>A non-finite F or a step that would leave a non-finite state is refused: fmi2Discard, a logged message naming
the culprit, the state unchanged. A bad parameter value is refused where it is set or at initialization with a
logged reason ({refusal}); the instance stays usable. The whole state can be saved, restored and serialized. OSP:
<code>resources/PrandtlElement_OspModelDescription.xml</code> declares a LinearMechanicalPort (F in, v out) and a
LinearMechanicalQuasiPort (F in, x out).</p>"""


def _page(name, rows, body, requirements, title="Generalized Prandtl element") -> str:
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{name}: {title}</title>
<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}} td,th{{border:1px solid #ccc;padding:2px 6px}}
table{{border-collapse:collapse}} pre{{background:#f4f4f4;padding:1em}}</style></head><body>
<h1>{title}: {name}</h1>
{body}
<h2>Variables</h2>
<p>An empty min or max means no bound.</p>
<table><tr><th>name</th><th>causality</th><th>variability</th><th>type</th><th>unit</th><th>start</th><th>min</th>
<th>max</th><th>description</th></tr>
{chr(10).join(rows)}
</table>
<h2>Requirements</h2>
{requirements}
</body></html>
"""


# ------------------------------------------------------------------ networks

_LAWS = {
    "spring": "f = k (x_i - x_j)",
    "dashpot": "f = c (v_i - v_j)",
    "slider": "f in alpha sign(v_i - v_j)  (any f in [-alpha, alpha] while it sticks)",
    "branch": "f = k u,  u' + d psi_[-eta, eta](u) ∋ v_i - v_j - (k / c) u  (no last term when c = 0)",
    "cubic": "f = k3 (x_i - x_j)^3",
}


def network_equations(scene) -> str:
    """The equations of the network: the balance of every node and the law of every kind of element present."""
    network = scene.network
    load = network.nodes[network.load_node]
    input_force = "F" if scene.causality == "force" else "0"
    lines = []
    if any(network.mass > 0):
        lines.append(f"m_j v_j' = {input_force} [j = {load}] - sum_e s_ej f_e,  x_j' = v_j    (nodes with a mass)")
    if not all(network.mass > 0):
        lines.append(f"0 = {input_force} [j = {load}] - sum_e s_ej f_e    (massless nodes: equilibrium at every "
                     "instant)")
    if scene.causality == "displacement":
        lines.append(f"x_{load}, v_{load} given (the inputs x, v);  force = sum_e s_e{load} f_e")
    lines.append("s_ej = +1 if j is the element's first end i, -1 if its second end j (the ground: x = v = 0)")
    for kind in scene.effects:
        lines.append(f"{kind:8s} {_LAWS[kind]}")
    lines.append("reaction = sum of f_e over the elements with an end at the ground")
    return "\n".join(lines)


def _network_tables(scene) -> str:
    network = scene.network
    nodes = []
    for j, node in enumerate(network.nodes):
        cells = (node, f"m_{node}", f"{network.mass[j]:.6g}", f"{network.x0[j]:.6g}", f"{network.v0[j]:.6g}",
                 "yes" if j == network.load_node else "")
        nodes.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in cells) + "</tr>")
    elements = []
    for e in network.elements:
        ends = " - ".join("ground" if j < 0 else network.nodes[j] for j in e.between)
        values = ", ".join(f"{key}_{e.name} = {value:.6g}" for key, value in e.coefficients().items())
        if e.kind == "branch" and e.u0:
            values += f" (u0 = {e.u0:.6g})"
        cells = (e.name, e.kind, ends, values)
        elements.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in cells) + "</tr>")
    return f"""<h2>Nodes</h2>
<table><tr><th>node</th><th>mass parameter</th><th>mass (kg)</th><th>x0 (m)</th><th>v0 (m/s)</th>
<th>load node</th></tr>
{chr(10).join(nodes)}
</table>
<h2>Elements</h2>
<p>Each coefficient is a tunable FMU parameter named &lt;key&gt;_&lt;element&gt;; a change is checked by the
library's rules (a refused value: fmi2Discard at the next step with the reason logged).</p>
<table><tr><th>element</th><th>kind</th><th>between (i - j)</th><th>parameters</th></tr>
{chr(10).join(elements)}
</table>"""


def _network_stepper_rows(scene, steppers=None) -> str:
    from ..network.model import NETWORK_STEPPERS, stepper_problem

    rows = []
    texts = {"implicit": "implicit Euler, every term implicit; each step one strictly convex problem solved "
                         "exactly by an active-set method (any network)",
             "projected": "the paper's scheme (5.1): explicit in the masses, the branches projected (all "
                          "plasticity in branches, a mass at every node)"}
    for name in NETWORK_STEPPERS:
        problem = stepper_problem(scene, name)
        applies = f"no: {problem}" if problem else "default" if name == scene.solver.stepper else "yes"
        if steppers is not None and name not in steppers and not problem:
            applies = "no: not in this FMU (built with --steppers " + ",".join(steppers) + ")"
        rows.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in (name, applies, "1", texts[name]))
                    + "</tr>")
    return "\n".join(rows)


def network_body(scene, refusal: str, steppers=None) -> str:
    """The page's body for a network's FMU (the element with the force F, or the connector)."""
    network = scene.network
    load = html.escape(network.nodes[network.load_node])
    counts = ", ".join(f"{len(network.of_kind(kind))} {kind}{'s' if len(network.of_kind(kind)) > 1 else ''}"
                       for kind in scene.effects) or "no elements"
    if scene.causality == "displacement":
        intro = f"""<p>This FMU is a network of {network.n} nodes ({counts}) as a <b>connector</b>: the motion of its
load node {load} is imposed by the inputs <code>x</code> and <code>v</code>, the rest of the network responds,
and <code>force</code> is the force of the network's elements on {load} (what holds the motion). The scene is
<code>resources/scene.toml</code>.</p>"""
        stepping = f"""<h2>Stepping</h2>
<p>The inputs set at a communication point belong to that time. <code>doStep(t, H)</code> commits the sample set
at t: the library moves {load} from the last committed sample to it along a line in implicit steps of the
parameter <code>step</code> (default {scene.solver.step:g} s). The outputs always show the network with the
inputs and parameters set last at the FMU's current time, without committing (<code>force</code> depends directly on
<code>x</code> and <code>v</code>): a master may set x several times at one communication point. The first
sample is taken as an instant move from the scene's x0. A non-finite input at doStep is refused (fmi2Discard,
a logged message, the state unchanged); a bad parameter is refused with its reason: at initialization
{refusal}, at a step fmi2Discard. The whole state can be saved, restored and serialized. OSP:
<code>resources/PrandtlNetworkConnector_OspModelDescription.xml</code> declares a LinearMechanicalPort (force
out, v in) and a LinearMechanicalQuasiPort (force out, x in).</p>"""
    else:
        intro = f"""<p>This FMU is a network of {network.n} nodes ({counts}) under the input force <code>F</code> at its
load node {load}. Its outputs are <code>x_&lt;node&gt;</code> and <code>v_&lt;node&gt;</code> of every node, the
<code>reaction</code> (the force of the elements on the ground) and the energy account. The scene is
<code>resources/scene.toml</code>.</p>"""
        stepping = f"""<h2>Stepping</h2>
<p>The input F is held constant over each communication step (with the parameter <code>scene_load</code> true,
the scene's [load] F_scene(t) is added and evaluated at every internal step as in the library: with no input
connected the FMU reproduces the library's run of its scene). <code>doStep(t, H)</code> advances by whole
internal steps of the parameter <code>step</code> (default {scene.solver.step:g} s) and, when H is not a multiple
of it, one last shorter step for the remainder. The outputs are those at the end of the last step (none depends
directly on F). The parameter <code>stepper</code> chooses the scheme:</p>
<table><tr><th>stepper</th><th>applies to this FMU</th><th>order</th><th>scheme</th></tr>
{_network_stepper_rows(scene, steppers)}
</table>
<p>A step the library cannot take (no equilibrium of a massless part, e.g. a massless chain pulled beyond the
total friction of its nodes; the step budget; an overflow) and a non-finite F are refused: fmi2Discard, the
library's reason logged, the state unchanged. A bad parameter value is refused with its reason: at
initialization {refusal}, at a step fmi2Discard. The instance stays usable. The whole state of the network can be saved,
restored and serialized. OSP: <code>resources/PrandtlNetwork_OspModelDescription.xml</code> declares a
LinearMechanicalPort (F in, v_{load} out) and a LinearMechanicalQuasiPort (F in, x_{load} out).</p>"""
    return f"""{intro}
<pre>{html.escape(network_equations(scene))}</pre>
{_network_tables(scene)}
{stepping}"""
