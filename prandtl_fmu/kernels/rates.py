"""The time derivatives of the element's outputs at an instant: what a co-simulation master extrapolates with.

At the state (x, v, u) and time t, under the load F (held: F' = 0 from t on, the input as the master set it),
for a massive element m x'' = F - R(x, v, u):

    a  = x''     = (F - R) / m                          (R the reaction, friction and memory forces included)
    R' = dR/dt   = K_t v + c a                           (K_t the tangent stiffness for the motion ahead)
    a' = x'''    = (F' - R') / m = -R' / m

one-sided, for the motion ahead: K_t is that of the direction of v (of a when v = 0, of increasing x when both
are 0), so where a branch is on its threshold and the motion pushes it on, it slides and adds nothing (the
derivative from the right). R' and a' are exact for the smooth effects and plain branches; a friction on the mass
(stick and slip), series dashpots and the effects with memory have rates this does not give (``exact_rates``).

The connector (motion in, force out: :func:`connector_rates`) at (x, u) along the path its inputs describe:

    F'  = K_t x' + c v',   F'' = K_t x'' + 6 k3 x x'^2 + c v''

with x' and x'' the master's input derivatives of x where it set them, else x' = v (the input v is x's rate) and
x'' = v'; v' and v'' the input derivatives of v (0 where not set: held). K_t is that of the direction of x' (of x''
when x' = 0, of the last motion when both are 0): exact from the right between switches, like the element's.
"""
from .._jit import kernel
from .drive import tangent
from .friction import reaction
from .play import branch_force
from ..loads import force_at


def exact_rates(scene) -> bool:
    """Whether R' and a' are exact for ``scene`` (see the module): a mass, no friction on it, no series dashpot,
    no effect with memory."""
    return (scene.mass is not None and scene.friction is None and not scene.has_series_dashpots
            and scene.delay is None and scene.history is None and scene.dahl is None)


@kernel
def _per_mass(m, force):
    if m is None:  # (massless: compiled away; no acceleration is asked for)
        return 0.0
    return force / m


@kernel
def _cubic_curvature(k3, x):
    if k3 is None:
        return 0.0
    return 6.0 * k3 * x


@kernel
def _dashpot(c):
    if c is None:
        return 0.0
    return c


@kernel
def output_rates(model, load, t, x, v, u, out):
    """out[0] = a, out[1] = a', out[2] = R' (m/s^2, m/s^3, N/s) at (x, v, u) and time t under ``load``, held."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    a = _per_mass(m, force_at(load, t) - reaction(model, load, t, x, v, branch_force(k, u)))
    ahead = v if v != 0.0 else a
    direction = -1.0 if ahead < 0.0 else 1.0
    rate = tangent(model, x, u, direction) * v + _dashpot(c) * a
    out[0] = a
    out[1] = _per_mass(m, -rate)
    out[2] = rate


@kernel
def connector_rates(model, x, v, u, xd, vd, direction, out):
    """out[0] = F', out[1] = F'' (N/s, N/s^2) of the connector's force at (x, u) for the input v and the inputs'
    derivatives ``xd`` (x', x'': zeros when not set) and ``vd`` (v', v''), along the path they describe (see the
    module); ``direction``: of the last motion (+1 or -1), for a path that does not move."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    if xd[0] != 0.0 or xd[1] != 0.0:
        x1, x2 = xd[0], xd[1]
    else:
        x1, x2 = v, vd[0]
    ahead = x1 if x1 != 0.0 else x2
    if ahead != 0.0:
        direction = -1.0 if ahead < 0.0 else 1.0
    stiffness = tangent(model, x, u, direction)
    out[0] = stiffness * x1 + _dashpot(c) * vd[0]
    out[1] = stiffness * x2 + _cubic_curvature(k3, x) * x1 * x1 + _dashpot(c) * vd[1]
