"""The network's compiled kernels as C functions of one network scene (no Python inside): the native FMU of a
``[network]`` or ``[chain]`` scene (issue 32).

As :mod:`prandtl_fmu.fmu.native.kernels` does for the element: small Python functions, generated here with the
scene's sizes written into them, unpack C pointers (``numba.carray``) into the library's model tuple
``(mass, kind, ends, coef, load_node, has_cubic)``, its load tuple and its workspace, and call the library's own
compiled kernels (:mod:`prandtl_fmu.network.kernels`): the time loops ``run_implicit`` and ``run_projected``,
``move_node``, ``jump_node`` and ``node_force`` (the connector), ``initial_state`` and ``initial_reaction`` (the
equilibrium at t = 0), ``kinetic``, ``stored``, and ``loads.force_at``. numba compiles each into a ``cfunc``, llvmlite emits it as an object; the numbers are the
library's, bit for bit (tests/networks/test_native.py).

The C signatures (``P`` a pointer to doubles, ``I`` a pointer to int64; ``net`` = mass, coef, kind, ends,
load_node, has_cubic; ``work`` = the workspace's 11 arrays, kernels.workspace's order; ``load`` = kind, lk, lt,
lf, nl as the element's):

* ``advance_<stepper>(net, x, v, u, piece, account, dissipated, out, work, load, t_base, first, h, steps,
  status)`` -> steps taken (``out``: the row of write_row, 2 n + 2; ``status[0]``: the last step's status);
* ``noisy_<stepper>(..., status, sigma, seed, unit, cache)``: the same under the load plus a white noise on the
  load's node, the load tuple's seventh entry ``(sigma, seed, unit, cache)`` (``loads.WhiteNoise``; ``cache``: the
  Brownian tree's int64 cache, ``kernels.NOISE_CACHE_SIZE``);
* ``load_force(load, t)`` -> F(t) of the load (``loads.force_at``);
* ``energies(net, x, v, u, out)``: out[0] the kinetic, out[1] the stored energy;
* ``initial(net, x, v, u, piece, force, reaction)``: the equilibrium at t = 0 in place (x, v, u, piece hold the
  scene's x0, v0, u0 and zeros), reaction[0] the reaction -> 0, or the status of the equilibrium that failed;
* ``move(net, x, v, u, piece, account, dissipated, work, target, whole, h, rest, force)``: ``kernels.move_node``
  (the load's node to ``target`` in ``whole`` steps of h and one of ``rest``) -> its status; force[0] the force
  of the elements on the load's node (``kernels.node_force``);
* ``jump(net, x, v, u, piece, account, dissipated, target, force)``: ``kernels.jump_node`` (the load's node to
  ``target`` in an instant) -> its status; force[0] the force that holds the node;
* ``reaction_check(net, x, v, u, piece, stepped, reaction, range)`` (the element's): ``kernels.reaction_fits``
  of a restored state's reaction -> 1 when it fits; range[0], range[1] what x, v, u fix of it and how far the
  stuck sliders let it lie (``kernels.reaction_range``).
"""
from __future__ import annotations

from .kernels import NOISE_CACHE_SIZE

_P = "types.CPointer(types.float64)"
_I = "types.CPointer(types.int64)"
_NET = f"{_P}, {_P}, {_I}, {_I}, types.int64, types.int64"
_WORK = ", ".join([_P, _P, _P, _I, _I, _P, _P, _I, _I, _I, _P])
_LOAD = f"types.int64, {_P}, {_P}, {_P}, types.int64"
_NOISE = f"types.float64, types.int64, types.float64, {_I}"
SIGNATURES = {
    "advance": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_I}, {_P}, {_P}, {_P}, {_WORK}, {_LOAD}, types.float64, "
               f"types.int64, types.float64, types.int64, {_I})",
    "advance_noisy": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_I}, {_P}, {_P}, {_P}, {_WORK}, {_LOAD}, types.float64, "
                     f"types.int64, types.float64, types.int64, {_I}, {_NOISE})",
    "energies": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_P})",
    "initial": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_I}, types.float64, {_P})",
    "move": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_I}, {_P}, {_P}, {_WORK}, types.float64, types.int64, "
            f"types.float64, types.float64, {_P})",
    "load_force": f"types.float64({_LOAD}, types.float64)",
    "jump": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_I}, {_P}, {_P}, types.float64, {_P})",
    "reaction_check": f"types.int64({_NET}, {_P}, {_P}, {_P}, {_I}, types.int64, types.float64, {_P})",
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


def _noisy_load(kind, lk, lt, lf, nl, sigma, seed, unit, cachep):
    return (kind, lk[0], lk[1], lk[2], carray(lt, (nl,)), carray(lf, (nl,)),
            (sigma, seed, unit, carray(cachep, ({noise_cache},))))


def advance(massp, coefp, kindp, endsp, load_node, has_cubic, xp, vp, up, piecep, accountp, dissipatedp, outp,
            dp, gp, pp, parp, clp, tp, sp, qp, degp, lp, scp, kind, lk, lt, lf, nl, t_base, first, h, steps,
            statusp):
    taken, status = run(_net(massp, coefp, kindp, endsp, load_node, has_cubic), _load(kind, lk, lt, lf, nl),
                        carray(xp, ({n},)), carray(vp, ({n},)), carray(up, ({e},)), carray(piecep, ({e},)),
                        t_base, first, h, steps, carray(outp, (1, {row})), carray(outp, (1, 0)), carray(accountp, (3,)),
                        carray(outp, (1, 0)), carray(dissipatedp, ({e},)), carray(outp, (1, 0)),
                        _work(dp, gp, pp, parp, clp, tp, sp, qp, degp, lp, scp))
    statusp[0] = status
    return taken


def advance_noisy(massp, coefp, kindp, endsp, load_node, has_cubic, xp, vp, up, piecep, accountp, dissipatedp,
                  outp, dp, gp, pp, parp, clp, tp, sp, qp, degp, lp, scp, kind, lk, lt, lf, nl, t_base, first, h,
                  steps, statusp, sigma, seed, unit, cachep):
    taken, status = run(_net(massp, coefp, kindp, endsp, load_node, has_cubic),
                        _noisy_load(kind, lk, lt, lf, nl, sigma, seed, unit, cachep),
                        carray(xp, ({n},)), carray(vp, ({n},)), carray(up, ({e},)), carray(piecep, ({e},)),
                        t_base, first, h, steps, carray(outp, (1, {row})), carray(outp, (1, 0)), carray(accountp, (3,)),
                        carray(outp, (1, 0)), carray(dissipatedp, ({e},)), carray(outp, (1, 0)),
                        _work(dp, gp, pp, parp, clp, tp, sp, qp, degp, lp, scp))
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
    model = _net(massp, coefp, kindp, endsp, load_node, has_cubic)
    x, v, u = carray(xp, ({n},)), carray(vp, ({n},)), carray(up, ({e},))
    status = initial_state(model, x, v, u, carray(piecep, ({e},)), force)
    if status < 0:
        return status
    reactionp[0] = initial_reaction(model, x, v, u, force)
    return 0


def reaction_check(massp, coefp, kindp, endsp, load_node, has_cubic, xp, vp, up, piecep, stepped, reaction,
                   rangep):
    model = _net(massp, coefp, kindp, endsp, load_node, has_cubic)
    x, v, u, piece = carray(xp, ({n},)), carray(vp, ({n},)), carray(up, ({e},)), carray(piecep, ({e},))
    fixed, free, scale = reaction_range(model, x, v, u, piece, stepped != 0)
    rangep[0] = fixed
    rangep[1] = free
    return 1 if reaction_fits(model, x, v, u, piece, stepped != 0, reaction) else 0


def jump(massp, coefp, kindp, endsp, load_node, has_cubic, xp, vp, up, piecep, accountp, dissipatedp, target,
         forcep):
    status, held = jump_node(_net(massp, coefp, kindp, endsp, load_node, has_cubic), carray(xp, ({n},)),
                             carray(vp, ({n},)), carray(up, ({e},)), carray(piecep, ({e},)), carray(accountp, (3,)),
                             carray(dissipatedp, ({e},)), load_node, target)
    forcep[0] = held
    return status


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

def compile_network(scene, steppers, connector: bool) -> list:
    """The scene's C functions: ``[(c_name, cfunc), ...]`` (``advance_<stepper>`` and, but for a connector (motion
    in: no noise), ``noisy_<stepper>`` for ``steppers``, ``energies``, ``initial``, and ``move`` for a connector).
    Whether a noise applies (``stepper_problem``: a massless load node needs a dashpot) depends on a mass the FMU
    may change: the C layer checks it (network.h)."""
    import numpy as np
    from numba import carray, cfunc, njit, types

    from ...network import kernels as nk
    from ...network.driver import loop_for

    network = scene.network
    n, e = network.n, len(network.elements)
    shape = dict(n=n, e=e, n1=n + 1, row=2 * n + 2, noise_cache=NOISE_CACHE_SIZE)
    source = _TEMPLATE.format(**shape)
    from ...loads import force_at

    names = ["energies", "initial", "load_force"] + (["move", "jump"] if connector else ["reaction_check"])
    compiled = []
    for stepper in [None] + list(steppers):
        namespace = dict(carray=carray, np=np, kinetic=nk.kinetic, stored=nk.stored, force_at=force_at,
                         move_node=nk.move_node, node_force=nk.node_force, jump_node=nk.jump_node,
                         initial_state=nk.initial_state, initial_reaction=nk.initial_reaction,
                         reaction_range=nk.reaction_range, reaction_fits=nk.reaction_fits,
                         run=loop_for(stepper) if stepper else None)
        exec(compile(source, f"<prandtl_fmu native network kernels of {scene.source}>", "exec"), namespace)
        for helper in ("_net", "_work", "_load", "_noisy_load"):  # inlined into each C function
            namespace[helper] = njit(inline="always")(namespace[helper])
        for name in ((["advance"] + ([] if connector else ["advance_noisy"])) if stepper else names):
            signature = eval(SIGNATURES[name], {"types": types})
            function = cfunc(signature, error_model="numpy")(namespace[name])
            compiled.append((f"noisy_{stepper}" if name == "advance_noisy" else f"advance_{stepper}" if stepper
                             else name, function))
    return compiled
