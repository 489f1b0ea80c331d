"""``documentation/index.html`` of the FMU: equations, variables, units, the scene."""
from __future__ import annotations

import html
import xml.etree.ElementTree as ET

_EQUATIONS = """\
x' = v
m v' = F - k0 x - k3 x^3 - c v - sum_i k_i u_i
u_i' + d psi_[-eta_i, eta_i](u_i) ∋ v        (|u_i| <= eta_i, i = 1..n)
reaction = k0 x + k3 x^3 + c v + sum_i k_i u_i  (= F - m v')"""


def index_html(model_description: bytes, scene) -> str:
    """The page, from the FMU's own modelDescription.xml and its scene."""
    root = ET.fromstring(model_description)
    rows = []
    for var in root.find("ModelVariables"):
        typed = var[0]
        start = typed.get("start", "")
        rows.append("<tr>" + "".join(f"<td>{html.escape(str(cell))}</td>" for cell in (
            var.get("name"), var.get("causality", "local"), var.get("variability", "continuous"),
            typed.tag, typed.get("unit", ""), start, typed.get("min", ""), typed.get("max", ""),
            var.get("description", ""))) + "</tr>")
    effects = ", ".join(scene.effects)
    branches = scene.branches
    if branches is None:
        branch_text = "no branches"
    elif branches.continuum:
        branch_text = (f"the continuous element: branches s in [0, 1] with stiffness density {branches.k_total:.6g} "
                       f"N/m and elastic range eta(s) = {branches.eta_min:.6g} + "
                       f"{branches.eta_max - branches.eta_min:.6g} s m, strength {branches.strength:.6g} N")
    else:
        branch_text = (f"{branches.n} branches, stiffness sum {branches.stiffness.sum():.6g} N/m, "
                       f"elastic ranges {branches.yield_displacement.min():.6g} to "
                       f"{branches.yield_displacement.max():.6g} m, strength sum alpha_i = {branches.strength:.6g} N")
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{html.escape(scene.name)}: Prandtl element</title>
<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}} td,th{{border:1px solid #ccc;padding:2px 6px}}
table{{border-collapse:collapse}} pre{{background:#f4f4f4;padding:1em}}</style></head><body>
<h1>Generalized Prandtl element: {html.escape(scene.name)}</h1>
<p>A point of mass m at displacement x with velocity v under the input force F, held in parallel by a linear
spring k0, a cubic spring k3, a dashpot c and n Prandtl branches (a spring k_i in series with a Coulomb slider of
threshold alpha_i = k_i eta_i). Model of Bastien &amp; Schatzman, M2AN 36 (2002), eq. (7.7), with the dashpot and
cubic spring of the related models.</p>
<pre>{html.escape(_EQUATIONS)}</pre>
<p>Effects present in this FMU: {html.escape(effects)} ({html.escape(branch_text)}).
Absent effects have no parameter. The branch stiffnesses and elastic ranges come from the scene in
<code>resources/scene.toml</code>.</p>
<h2>Stepping</h2>
<p>The input F is held constant over each communication step. <code>doStep(t, H)</code> advances by whole internal
steps of the parameter <code>step</code> and, when H is not a multiple of it, one last shorter step for the
remainder. Steppers (parameter <code>stepper</code>): <code>projected</code> is the scheme (5.1) of the paper
(which the paper calls the implicit Euler scheme: implicit in the friction term only, explicit otherwise; order 1;
needs omega h &lt;&lt; 1); <code>implicit</code> is backward Euler in every term (order 1, unconditionally
stable). A non-finite F, a parameter out of range or a step that would leave a non-finite state is refused
(fmi2Discard, a logged message naming the culprit) with the state unchanged. The whole state can be saved,
restored and serialized (as JSON).</p>
<h2>Variables</h2>
<table><tr><th>name</th><th>causality</th><th>variability</th><th>type</th><th>unit</th><th>start</th><th>min</th>
<th>max</th><th>description</th></tr>
{chr(10).join(rows)}
</table>
<h2>Requirements</h2>
<p>A PythonFMU FMU runs in the host's Python: the host process needs Python 3 with numpy and numba. A host that
is not itself Python may need <code>LD_PRELOAD=libpython3.X.so</code> so that the Python extension modules find the
interpreter's symbols.</p>
</body></html>
"""
