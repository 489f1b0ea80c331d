"""The network's compiled kernels as C functions of one network scene (no Python inside): the native FMU of a
``[network]`` or ``[chain]`` scene (issue 32).

As :mod:`prandtl_fmu.native.kernels` does for the element: small Python functions, generated here with the
scene's sizes written into them, unpack C pointers (``numba.carray``) into the library's model tuple
``(mass, kind, ends, coef, load_node, has_cubic)``, its load tuple and its workspace, and call the library's own
compiled kernels (:mod:`prandtl_fmu.network.kernels`): the time loops ``run_implicit`` and ``run_projected``,
``move_node`` and ``node_force`` (the connector), ``solve_step`` and ``commit`` (the equilibrium at t = 0),
``kinetic``, ``stored``, ``forces_now``, and ``loads.force_at``. numba compiles each into a ``cfunc``, llvmlite emits it as an object; the numbers are the
library's, bit for bit (tests/test_native_network.py).

Two pieces of the library are plain Python (numpy) and cannot be called from a cfunc; they are written below as
compiled functions that do the same operations in the same order on the same arrays (tests hold them to the
library's numbers bit for bit): ``network.driver.initial_state`` (the instant model of ``driver.instant_model``,
built in place: the massive nodes held by sliders of infinite threshold listed first, rigid dashpots, no series
dashpot relaxing) and ``driver.initial_reaction``, both in :func:`instant_state`.

The C signatures (``P`` a pointer to doubles, ``I`` a pointer to int64; ``net`` = mass, coef, kind, ends,
load_node, has_cubic; ``work`` = the workspace's 11 arrays, kernels.workspace's order; ``load`` = kind, lk, lt,
lf, nl as the element's):

* ``advance_<stepper>(net, x, v, u, piece, account, dissipated, out, work, load, t_base, first, h, steps,
  status)`` -> steps taken (``out``: the row of write_row, 2 n + 2; ``status[0]``: the last step's status);
* ``load_force(load, t)`` -> F(t) of the load (``loads.force_at``);
* ``energies(net, x, v, u, out)``: out[0] the kinetic, out[1] the stored energy;
* ``initial(net, x, v, u, piece, force, reaction)``: the equilibrium at t = 0 in place (x, v, u, piece hold the
  scene's x0, v0, u0 and zeros), reaction[0] the reaction -> 0, or the status of the equilibrium that failed;
* ``move(net, x, v, u, piece, account, dissipated, work, target, whole, h, rest, force)``: ``kernels.move_node``
  (the load's node to ``target`` in ``whole`` steps of h and one of ``rest``) -> its status; force[0] the force
  of the elements on the load's node (``kernels.node_force``).
"""
from __future__ import annotations

_P = "types.CPointer(types.float64)"
_I = "types.CPointer(types.int64)"
_NET = f"{_P}, {_P}, {_I}, {_I}, types.int64, types.int64"
_WORK = ", ".join([_P, _P, _P, _I, _I, _P, _P, _I, _I, _I, _P])
_LOAD = f"types.int64, {_P}, {_P}, {_P}, types.int64"
SIGNATURES = {
    "advance": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_I}, {_P}, {_P}, {_P}, {_WORK}, {_LOAD}, types.float64, "
               f"types.int64, types.float64, types.int64, {_I})",
    "energies": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_P})",
    "initial": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_I}, types.float64, {_P})",
    "move": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_I}, {_P}, {_P}, {_WORK}, types.float64, types.int64, "
            f"types.float64, types.float64, {_P})",
    "load_force": f"types.float64({_LOAD}, types.float64)",
}

_TEMPLATE = '''
def _net(massp, coefp, kindp, endsp, load_node, has_cubic):
    return (carray(massp, ({n},)), carray(kindp, ({e},)), carray(endsp, ({e}, 2)), carray(coefp, ({e}, 3)),
            load_node, has_cubic != 0)


def _work(dp, gp, pp, parp, clp, tp, sp, qp, degp, lp, scp):
    return (carray(dp, ({n},)), carray(gp, ({n},)), carray(pp, ({n},)), carray(parp, ({n1},)),
            carray(clp, ({n1},)), carray(tp, ({e},)), carray(sp, ({n1},)), carray(qp, ({n1},)),
            carray(degp, ({n1},)), carray(lp, ({n1},)), carray(scp, ({n},)))


def _load(kind, lk, lt, lf, nl):
    return (kind, lk[0], lk[1], lk[2], carray(lt, (nl,)), carray(lf, (nl,)))


def advance(massp, coefp, kindp, endsp, load_node, has_cubic, xp, vp, up, piecep, accountp, dissipatedp, outp,
            dp, gp, pp, parp, clp, tp, sp, qp, degp, lp, scp, kind, lk, lt, lf, nl, t_base, first, h, steps,
            statusp):
    taken, status = run(_net(massp, coefp, kindp, endsp, load_node, has_cubic), _load(kind, lk, lt, lf, nl),
                        carray(xp, ({n},)), carray(vp, ({n},)), carray(up, ({e},)), carray(piecep, ({e},)),
                        t_base, first, h, steps, carray(outp, (1, {row})), None, carray(accountp, (3,)), None,
                        carray(dissipatedp, ({e},)), None, _work(dp, gp, pp, parp, clp, tp, sp, qp, degp, lp, scp))
    statusp[0] = status
    return taken


def load_force(kind, lk, lt, lf, nl, t):
    return force_at(_load(kind, lk, lt, lf, nl), t)


def energies(massp, coefp, kindp, endsp, load_node, has_cubic, xp, vp, up, outp):
    model = _net(massp, coefp, kindp, endsp, load_node, has_cubic)
    outp[0] = kinetic(model[0], carray(vp, ({n},)))
    outp[1] = stored(model, carray(xp, ({n},)), carray(up, ({e},)))
    return 0


def initial(massp, coefp, kindp, endsp, load_node, has_cubic, xp, vp, up, piecep, force, reactionp):
    return instant_state(_net(massp, coefp, kindp, endsp, load_node, has_cubic), carray(xp, ({n},)),
                         carray(vp, ({n},)), carray(up, ({e},)), carray(piecep, ({e},)), force,
                         carray(reactionp, (1,)))


def move(massp, coefp, kindp, endsp, load_node, has_cubic, xp, vp, up, piecep, accountp, dissipatedp,
         dp, gp, pp, parp, clp, tp, sp, qp, degp, lp, scp, target, whole, h, rest, forcep):
    model = _net(massp, coefp, kindp, endsp, load_node, has_cubic)
    work = _work(dp, gp, pp, parp, clp, tp, sp, qp, degp, lp, scp)
    status, taken = move_node(model, carray(xp, ({n},)), carray(vp, ({n},)), carray(up, ({e},)),
                              carray(piecep, ({e},)), work, carray(accountp, (3,)), carray(dissipatedp, ({e},)),
                              load_node, target, whole, h, rest)
    forcep[0] = node_force(model, work[5], load_node)
    return status
'''

def _library_pieces():
    """The compiled stand-ins of driver.initial_state, driver.initial_reaction, NetworkConnector.move_to (see the
    module docstring), defined on first use (numba is imported then)."""
    import math

    import numpy as np
    from numba import njit

    from ..network import kernels as nk

    SLIDER, DASHPOT, BRANCH, GROUND, KINK = nk.SLIDER, nk.DASHPOT, nk.BRANCH, nk.GROUND, nk.KINK

    @njit
    def instant_model(model):
        """driver.instant_model: (the instant's model, the number of held nodes listed first)."""
        mass, kind, ends, coef, load_node, has_cubic = model
        n = mass.shape[0]
        elements = kind.shape[0]
        extra = 0
        for j in range(n):
            if mass[j] > 0:
                extra += 1
        count = extra + elements
        kind2 = np.empty(count, np.int64)
        ends2 = np.empty((count, 2), np.int64)
        coef2 = np.empty((count, 3))
        m = 0
        for j in range(n):  # every massive node held: a stuck slider of infinite threshold, listed first
            if mass[j] > 0:
                kind2[m] = SLIDER
                ends2[m, 0] = j
                ends2[m, 1] = -1
                coef2[m, 0], coef2[m, 1], coef2[m, 2] = np.inf, 0.0, 0.0
                m += 1
        for e in range(elements):
            kind2[extra + e] = kind[e]
            ends2[extra + e, 0], ends2[extra + e, 1] = ends[e, 0], ends[e, 1]
            coef2[extra + e, 0], coef2[extra + e, 1], coef2[extra + e, 2] = coef[e, 0], coef[e, 1], coef[e, 2]
        for e in range(count):
            if kind2[e] == DASHPOT and coef2[e, 0] > 0:  # rigid (a dashpot with c = 0 is no dashpot)
                kind2[e] = SLIDER
                coef2[e, 0], coef2[e, 1], coef2[e, 2] = np.inf, 0.0, 0.0
        for e in range(count):
            if kind2[e] == DASHPOT:
                coef2[e, 0] = 0.0
            if kind2[e] == BRANCH:
                coef2[e, 2] = 0.0
        return (np.zeros(n), kind2, ends2, coef2, load_node, has_cubic), extra

    @njit
    def initial_state(model, x, v, u, piece, force):
        """driver.initial_state on (x, v, u, piece) holding the scene's x0, v0, u0 and zeros: every massless node
        in equilibrium with ``force``. Returns 0, or the failed equilibrium's status."""
        mass, kind, ends, coef, load_node, has_cubic = model
        n = mass.shape[0]
        elements = kind.shape[0]
        massless = False
        for j in range(n):
            if not mass[j] > 0:
                v[j] = 0.0
                massless = True
        if not massless:
            return 0
        instant, extra = instant_model(model)
        count = instant[1].shape[0]
        work = nk.workspace(n, count)
        piece2 = np.zeros(count, np.int64)
        u2 = np.zeros(count)
        for e in range(elements):
            u2[extra + e] = u[e]
        status = nk.solve_step(instant, x, np.zeros(n), u2, piece2, 1.0, force, -1, 0.0, work)
        if status < 0:
            return status
        nk.commit(instant, x, np.zeros(n), u2, piece2, 1.0, force, work, None, None)
        for e in range(elements):  # the pieces reached; a rigid dashpot is a dashpot again
            if kind[e] == SLIDER or kind[e] == BRANCH:
                p = piece2[extra + e]
                piece[e] = p if abs(p) != KINK else p // KINK
            u[e] = u2[extra + e]
        return 0

    @njit
    def initial_reaction(model, x, v, u, force):
        """driver.initial_reaction, in the same order of operations (Python's min and max included)."""
        mass, kind, ends, coef, load_node, has_cubic = model
        n = mass.shape[0]
        elements = kind.shape[0]
        term = np.zeros(elements)
        nk.forces_now(model, x, v, u, term)
        massless = False
        for j in range(n):
            if not mass[j] > 0:
                massless = True
        if massless:  # the instant's forces (its solve from the equilibrium found by initial_state)
            instant, extra = instant_model(model)
            count = instant[1].shape[0]
            work = nk.workspace(n, count)
            piece = np.zeros(count, np.int64)
            u2 = np.zeros(count)
            for e in range(elements):
                u2[extra + e] = u[e]
            status = nk.solve_step(instant, x.copy(), np.zeros(n), u2, piece, 1.0, force, -1, 0.0, work)
            if status >= 0:
                held = work[5]
                for e in range(elements):
                    if not mass[ends[e, 0]] > 0 or (ends[e, 1] >= 0 and not mass[ends[e, 1]] > 0):
                        term[e] = held[extra + e]
        net = np.zeros(n)
        net[load_node] += force
        for e in range(elements):
            if kind[e] != SLIDER:
                net[ends[e, 0]] -= term[e]
                if ends[e, 1] >= 0:
                    net[ends[e, 1]] += term[e]
        total = 0.0
        for e in range(elements):
            if ends[e, 1] != GROUND:
                continue
            i = ends[e, 0]
            if kind[e] == SLIDER and mass[i] > 0:
                alpha = coef[e, 0]
                if v[i] != 0:
                    total += alpha * math.copysign(1.0, v[i])
                else:
                    held_force = net[i]  # min(max(net, -alpha), alpha) as Python's builtins pick
                    if -alpha > held_force:
                        held_force = -alpha
                    if alpha < held_force:
                        held_force = alpha
                    total += held_force
            else:
                total += term[e]
        return total

    @njit
    def instant_state(model, x, v, u, piece, force, reaction):
        """initial_state, then reaction[0] = initial_reaction. Returns 0, or the failed equilibrium's status."""
        status = initial_state(model, x, v, u, piece, force)
        if status < 0:
            return status
        reaction[0] = initial_reaction(model, x, v, u, force)
        return 0

    return dict(instant_state=instant_state, initial_reaction=initial_reaction)


_PIECES = {}


def library_pieces() -> dict:
    if not _PIECES:
        _PIECES.update(_library_pieces())
    return _PIECES


def compile_network(scene, steppers, connector: bool) -> list:
    """The scene's C functions: ``[(c_name, cfunc), ...]`` (``advance_<stepper>`` for ``steppers``, ``energies``,
    ``initial``, and ``move`` for a connector)."""
    import numpy as np
    from numba import carray, cfunc, njit, types

    from ..network import kernels as nk
    from ..network.driver import loop_for

    network = scene.network
    n, e = network.n, len(network.elements)
    shape = dict(n=n, e=e, n1=n + 1, row=2 * n + 2)
    source = _TEMPLATE.format(**shape)
    from ..loads import force_at

    names = ["energies", "initial", "load_force"] + (["move"] if connector else [])
    compiled = []
    for stepper in [None] + list(steppers):
        namespace = dict(carray=carray, np=np, kinetic=nk.kinetic, stored=nk.stored, force_at=force_at,
                         move_node=nk.move_node, node_force=nk.node_force,
                         run=loop_for(stepper) if stepper else None, **library_pieces())
        exec(compile(source, f"<prandtl_fmu native network kernels of {scene.source}>", "exec"), namespace)
        for helper in ("_net", "_work", "_load"):  # inlined into each C function
            namespace[helper] = njit(inline="always")(namespace[helper])
        for name in (["advance"] if stepper else names):
            signature = eval(SIGNATURES[name], {"types": types})
            function = cfunc(signature, error_model="numpy")(namespace[name])
            compiled.append((f"advance_{stepper}" if stepper else name, function))
    return compiled
