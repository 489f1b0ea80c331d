"""The library's compiled kernels as C functions of one scene, in one object file (no Python inside).

For a scene, :func:`compile_kernels` writes a few small Python functions (their source is generated here,
with the scene's structure written into it: which effects are present, the number of branches) that
unpack C pointers into arrays (``numba.carray``) and the model tuple of the library
(``driver.compile_model``), and call the library's own compiled kernels: each stepper's time loop
``run``, ``reaction``, ``kinetic``, ``stored``, ``tangent``, the massless equilibrium. numba compiles each
into a ``cfunc``; their LLVM modules are emitted as object files by llvmlite, for each target
(``platforms.py``). The numerics in the native FMU are therefore the library's, not a copy: the same source
compiled by the same compiler for the same types, bit for bit (tests/fmu/native/test_against_library.py).

What the objects need besides libm is numba's error path (a kernel that raises: Python's C API with the GIL)
and ``numba_nextafter``: ``stubs.c`` provides them; the error path sets a flag that the FMI layer reads
(the step is refused), it never touches Python.

The C signatures (every pointer to doubles; ``kind`` the load's kind, ``lk`` = offset, amplitude, omega of
the load, ``lt``/``lf``/``nl`` its table):

* ``advance(p, k, eta, cs, u, mp, ms, nd, xv, account, out, kind, lk, lt, lf, nl, t_base, first, h, steps)``
  -> steps taken (``kernels/loop.py``: out = x, v, reaction; the elongations and the energy row are not recorded,
  handed as arrays with no column, as ``stepping.integrate`` hands them: the same types, so the library's compiled
  loop; ``row`` computes the energy row when an output reads it);
* ``advance_noisy(..., steps, sigma, seed, unit, cache)``: the same under the load plus a white noise, the load
  tuple's seventh entry ``(sigma, seed, unit, cache)`` (``loads.WhiteNoise``; ``cache``: the Brownian tree's
  int64 cache of :data:`NOISE_CACHE_SIZE`, any content valid), for the steppers that take a noise
  (:func:`noise_refusal`);
* ``record(p, k, eta, cs, u, mp, ms, nd, xv, account, out, erow, kind, lk, lt, lf, nl, t)``: the outputs of the
  state;
* ``row(p, k, eta, cs, u, mp, ms, nd, xv, account, erow)``: the energy row of the state (kinetic, stored, the
  account), what ``record`` writes into erow;
* ``stiffness(p, k, eta, cs, u, mp, ms, nd, xv)`` -> the tangent stiffness;
* ``rates(p, k, eta, cs, u, mp, ms, nd, xv, kind, lk, lt, lf, nl, t, out)``: a, a' and the reaction's rate at the
  state under the load held (``kernels/rates.output_rates``: the outputs' derivatives a master reads);
* ``limits(p, k, eta, cs, u, mp, ms, nd, out)``: the magnitudes of x, v and the account's entries below which
  every output is surely a number (``kernels/showable.limits``): a doStep then computes none of them to show
  only numbers;
* ``initial(p, k, eta, cs, u, mp, ms, nd, xv, kind, lk, lt, lf, nl)`` -> 1, or 0 when a massless element has no
  equilibrium (``driver.initial_state``); it also makes the memory fresh (``driver._memory_model``, and
  ``driver._initial_with_memory`` for a massless element without a dashpot);
* ``force_at(kind, lk, lt, lf, nl, t, unused)`` -> F(t) of the load (``loads.force_at``);
* ``elongations(p, k, eta, cs, u, mp, ms, nd, out)``: the n elongations u_i into ``out`` (the FMI 3.0 array ``u``);
* ``state_check(k, state, scratch)`` (memory-stack scenes): why a restored stack state is not one, or 0
  (:func:`compile_state_check`);
* ``stability(p, cs, x, h, kind, out)`` (the element): ``stability.check``'s finding for the step in use, its
  numbers in ``out`` (:func:`compile_stability`).

The connector's (``_CONNECTOR_SIGNATURES``: the element's arrays, then): ``move(..., x_start, v_start, t_start, x,
v, duration, force, account)``, one sample of ``connector.Connector.move_to`` (``drive_with_memory`` with effects
with memory, else ``drive``; the dashpot's dissipation over the sample added to the account); ``cpath(..., x, v,
xd, vd, duration, account, out)``, the motion along the inputs' Taylor polynomial of ``Connector.advance``
(``drive.drive_polynomial``); ``cforce(..., x, v, t)``, ``ctangent(..., x, direction)`` (the memory's force and
slope added), ``cdirectional(..., x, direction, dx, dv)``
(d force = (tangent + the memory's slope) dx + c dv: the directional derivative a master asks for; the memory's
forces do not move with v at an instant), ``crates(..., x, v, xd, vd, direction, out)`` (the force's first and
second time derivatives along the inputs' path: ``Connector.output_derivatives``), ``cstored(..., x)``; ``cinitial(...)``
(a fresh memory stack and memory); ``elongations(p, k, eta, cs, u, out)`` (the branches' arrays alone).

``p`` holds the coefficients in :data:`PARAMETERS` order. ``mp``, ``ms``, ``nd``: the effects with memory
(``memory/``), laid out by :func:`memory_layout`: their parameters, their state (the history's variables and
cache, the Dahl force, then the delay's buffer of ``nd`` values, sized by the FMU at its initialization from the
delay's tau in use), rebuilt into the library's tuple ``(delay, history, dahl)`` (``compile_memory``). A
connector with ``[damper]`` gets every function twice, with c and without (its dashpot's dissipation is booked
only with one); an element once (:func:`variants`). The model tuple is the library's
(``compiled.compile_model``), an absent spring or dashpot a zero, so the variants and the library's own runs
share each stepper's compiled loop.
"""
from __future__ import annotations

import functools

import numpy as np

from ...noise import CACHE_SIZE

PARAMETERS = ("m", "x0", "v0", "k0", "k3", "c", "alpha", "alpha_kinetic", "stribeck_velocity", "belt_velocity")
NATIVE_STEPPERS = ("projected", "implicit", "symplectic", "verlet", "exact")
NOISE_CACHE_SIZE = CACHE_SIZE  # the int64s of the Brownian tree's cache (noise.new_cache): one per FMU instance

_PTR = "types.CPointer(types.float64)"
# a white noise's entry of the load tuple, (sigma, seed, unit, cache) (loads.WhiteNoise.compile)
_NOISE = "types.float64, types.int64, types.float64, types.CPointer(types.int64)"
# the element's arrays: p, k, eta, cs, u, then the memory's parameters, state and delay buffer length (mp, ms, nd)
_ELEMENT = f"{', '.join([_PTR] * 7)}, types.int64"
_SIGNATURES = {
    "advance": f"types.int64({_ELEMENT}, {', '.join([_PTR] * 3)}, types.int64, {_PTR}, {_PTR}, {_PTR}, types.int64, "
               "types.float64, types.int64, types.float64, types.int64)",
    "advance_noisy": f"types.int64({_ELEMENT}, {', '.join([_PTR] * 3)}, types.int64, {_PTR}, {_PTR}, {_PTR}, "
                     f"types.int64, types.float64, types.int64, types.float64, types.int64, {_NOISE})",
    "record": f"types.int64({_ELEMENT}, {', '.join([_PTR] * 4)}, types.int64, {_PTR}, {_PTR}, {_PTR}, types.int64, "
              "types.float64)",
    "stiffness": f"types.float64({_ELEMENT}, {_PTR})",
    "limits": f"types.int64({_ELEMENT}, {_PTR})",
    "row": f"types.int64({_ELEMENT}, {', '.join([_PTR] * 3)})",
    "initial": f"types.int64({_ELEMENT}, {_PTR}, types.int64, {_PTR}, {_PTR}, {_PTR}, types.int64)",
    "force_at": f"types.float64(types.int64, {_PTR}, {_PTR}, {_PTR}, types.int64, types.float64, {_PTR})",
    "elongations": f"types.int64({_ELEMENT}, {_PTR})",
    "rates": f"types.int64({_ELEMENT}, {_PTR}, types.int64, {_PTR}, {_PTR}, {_PTR}, types.int64, types.float64, "
             f"{_PTR})",
}

_TEMPLATE = '''
def _model(p, kp, etap, csp, mp, msp, nd):
    return ({m}, {k0}, {k3}, {c}, {k}, {eta}, {cs}, {friction}, {memory})


def _load(kind, lk, lt, lf, nl):
    return (kind, lk[0], lk[1], lk[2], carray(lt, (nl,)), carray(lf, (nl,)))


def _noisy_load(kind, lk, lt, lf, nl, sigma, seed, unit, cachep):
    return (kind, lk[0], lk[1], lk[2], carray(lt, (nl,)), carray(lf, (nl,)),
            (sigma, seed, unit, carray(cachep, ({noise_cache},))))


def advance(p, kp, etap, csp, up, mp, msp, nd, xv, accountp, outp, kind, lk, lt, lf, nl, t_base, first, h, steps):
    x, v, taken = run(_model(p, kp, etap, csp, mp, msp, nd), _load(kind, lk, lt, lf, nl), xv[0], xv[1], {u}, t_base,
                      first, h, steps, carray(outp, (1, 3)), carray(outp, (1, 0)), carray(accountp, (4,)),
                      carray(outp, (1, 0)))
    xv[0] = x
    xv[1] = v
    return taken


def advance_noisy(p, kp, etap, csp, up, mp, msp, nd, xv, accountp, outp, kind, lk, lt, lf, nl, t_base, first, h,
                  steps, sigma, seed, unit, cachep):
    load = _noisy_load(kind, lk, lt, lf, nl, sigma, seed, unit, cachep)
    x, v, taken = run_noisy(_model(p, kp, etap, csp, mp, msp, nd), load, xv[0], xv[1], {u}, t_base, first, h, steps,
                            carray(outp, (1, 3)), carray(outp, (1, 0)), carray(accountp, (4,)), carray(outp, (1, 0)))
    xv[0] = x
    xv[1] = v
    return taken


def record(p, kp, etap, csp, up, mp, msp, nd, xv, accountp, outp, erowp, kind, lk, lt, lf, nl, t):
    model = _model(p, kp, etap, csp, mp, msp, nd)
    m, k0, k3, c, k, eta, cs, friction, memory = model
    u = {u}
    x = xv[0]
    v = xv[1]
    outp[0] = x
    outp[1] = v
    outp[2] = reaction(model, _load(kind, lk, lt, lf, nl), t, x, v, branch_force(k, u))
    erowp[0] = kinetic(m, v)
    erowp[1] = stored(x, k0, k3, k, u)
    for j in range(4):
        erowp[2 + j] = accountp[j]
    return 0


def row(p, kp, etap, csp, up, mp, msp, nd, xv, accountp, erowp):
    m, k0, k3, c, k, eta, cs, friction, memory = _model(p, kp, etap, csp, mp, msp, nd)
    erowp[0] = kinetic(m, xv[1])
    erowp[1] = stored(xv[0], k0, k3, k, {u})
    for j in range(4):
        erowp[2 + j] = accountp[j]
    return 0


def stiffness(p, kp, etap, csp, up, mp, msp, nd, xv):
    direction = -1.0 if xv[1] < 0 else 1.0
    return tangent(_model(p, kp, etap, csp, mp, msp, nd), xv[0], {u}, direction)


def rates(p, kp, etap, csp, up, mp, msp, nd, xv, kind, lk, lt, lf, nl, t, outp):
    output_rates(_model(p, kp, etap, csp, mp, msp, nd), _load(kind, lk, lt, lf, nl), t, xv[0], xv[1], {u},
                 carray(outp, (3,)))
    return 0


def limits(p, kp, etap, csp, up, mp, msp, nd, outp):
    showable_limits(_model(p, kp, etap, csp, mp, msp, nd), carray(outp, (3,)))
    return 0


def elongations(p, kp, etap, csp, up, mp, msp, nd, outp):
    if {has_branches}:
        write_elongations(_model(p, kp, etap, csp, mp, msp, nd)[4], {u}, carray(outp, ({n},)))
    return 0


def force_at_c(kind, lk, lt, lf, nl, t, unused):
    return force_at(_load(kind, lk, lt, lf, nl), t)


def initial(p, kp, etap, csp, up, mp, msp, nd, xv, kind, lk, lt, lf, nl):
    model = _model(p, kp, etap, csp, mp, msp, nd)
    m, k0, k3, c, k, eta, cs, friction, memory = model
    u = {u}
    if {stack}:  # stack.fresh_state(params, x0) in place: one sticking piece, u_i = x - x0 + u0_i
        start(k, p[1] if {massive} else 0.0, u)
{fresh}
    if {massive}:
        xv[0] = p[1]
        xv[1] = p[2]
        return 1
    force = force_at(_load(kind, lk, lt, lf, nl), 0.0)
    if {damped}:
        xv[0] = 0.0
        xv[1] = (force - elastic_force(0.0, k0, k3) - branch_force(k, u) - force_now(memory, 0.0, 0.0, 0.0)) / p[5]
        return 1
{quasi_static}
    w = solve_increment(0.0, 0.0, -force, k0, k3, k, eta, None, u, 0.0)
    if not (abs(w) < np.inf):
        return 0
    move(k, eta, u, w, None)
    xv[0] = w
    xv[1] = 0.0
    return 1
'''


_CONNECTOR_TEMPLATE = '''
def _model(p, kp, etap, csp, mp, msp, nd):
    return ({m}, {k0}, {k3}, {c}, {k}, {eta}, {cs}, {friction}, {memory})


def move(p, kp, etap, csp, up, mp, msp, nd, x_start, v_start, t_start, xp, vp, dp, fp, accountp):
    model = _model(p, kp, etap, csp, mp, msp, nd)
    v_end, duration = vp[0], dp[0]
    if {has_memory}:  # connector.Connector.move_to: the memory moves along the path too
        drive_with_memory(model, {u}, x_start, v_start, t_start, carray(xp, (1,)), carray(vp, (1,)),
                          carray(dp, (1,)), carray(fp, (1,)), carray(accountp, (3,)))
    else:
        drive(model, {u}, x_start, carray(xp, (1,)), carray(vp, (1,)), carray(dp, (1,)), carray(fp, (1,)),
              carray(accountp, (3,)))
    if {damped}:  # Connector.move_to: the dashpot's dissipation, v linear over the sample
        accountp[2] += p[5] * (v_start * v_start + v_start * v_end + v_end * v_end) * duration / 3.0
    return 0


def cpath(p, kp, etap, csp, up, mp, msp, nd, x, v, xdp, vdp, duration, accountp, outp):
    model = _model(p, kp, etap, csp, mp, msp, nd)  # Connector.advance with the inputs' derivatives
    drive_polynomial(model, {u}, x, v, carray(xdp, (2,)), carray(vdp, (2,)), duration, carray(accountp, (3,)),
                     carray(outp, (4,)))
    return 0


def cforce(p, kp, etap, csp, up, mp, msp, nd, x, v, t):
    m, k0, k3, c, k, eta, cs, friction, memory = _model(p, kp, etap, csp, mp, msp, nd)
    return smooth_force(x, v, k0, k3, c) + branch_force(k, {u}) + force_now(memory, t, x, v)


def ctangent(p, kp, etap, csp, up, mp, msp, nd, x, direction):
    model = _model(p, kp, etap, csp, mp, msp, nd)
    return tangent(model, x, {u}, direction) + tangent_now(model[8], direction)


def cdirectional(p, kp, etap, csp, up, mp, msp, nd, x, direction, dx, dv):
    model = _model(p, kp, etap, csp, mp, msp, nd)
    return (tangent(model, x, {u}, direction) + tangent_now(model[8], direction)) * dx + model[3] * dv


def crates(p, kp, etap, csp, up, mp, msp, nd, x, v, xdp, vdp, direction, outp):
    model = _model(p, kp, etap, csp, mp, msp, nd)  # Connector.output_derivatives: F', F'' along the inputs' path
    connector_rates(model, x, v, {u}, carray(xdp, (2,)), carray(vdp, (2,)), direction, carray(outp, (2,)))
    return 0


def cstored(p, kp, etap, csp, up, mp, msp, nd, x):
    m, k0, k3, c, k, eta, cs, friction, memory = _model(p, kp, etap, csp, mp, msp, nd)
    return stored(x, k0, k3, k, {u})


def cinitial(p, kp, etap, csp, up, mp, msp, nd):
    model = _model(p, kp, etap, csp, mp, msp, nd)
    k = model[4]
    u = {u}
    if {stack}:  # stack.fresh_state(params, 0.0) in place
        start(k, 0.0, u)
{fresh}
    return 1


def elongations(p, kp, etap, csp, up, outp):
    if {has_branches}:
        write_elongations({k}, {u}, carray(outp, ({n},)))
    return 0
'''
# the connector's arrays are the element's (p, k, eta, cs, u, mp, ms, nd); its elongations take none of the memory
# (the FMI 3.0 layer calls them with the branches' arrays alone)
_CONNECTOR_SIGNATURES = {
    "move": f"types.int64({_ELEMENT}, types.float64, types.float64, types.float64, {', '.join([_PTR] * 5)})",
    "cpath": f"types.int64({_ELEMENT}, types.float64, types.float64, {', '.join([_PTR] * 2)}, types.float64, "
             f"{', '.join([_PTR] * 2)})",
    "cforce": f"types.float64({_ELEMENT}, types.float64, types.float64, types.float64)",
    "ctangent": f"types.float64({_ELEMENT}, types.float64, types.float64)",
    "cdirectional": f"types.float64({_ELEMENT}, types.float64, types.float64, types.float64, types.float64)",
    "crates": f"types.int64({_ELEMENT}, types.float64, types.float64, {', '.join([_PTR] * 2)}, types.float64, {_PTR})",
    "cstored": f"types.float64({_ELEMENT}, types.float64)",
    "cinitial": f"types.int64({_ELEMENT})",
    "elongations": f"types.int64({', '.join([_PTR] * 6)})",
}


def structure(scene, unfolded=False) -> dict:
    """The scene's structure as the generated source needs it (which effects, how many branches); ``unfolded``:
    the O(n) kernel of a scene whose branches are on the memory stack (see :func:`folds`)."""
    branches = scene.branches
    continuum = branches is not None and branches.continuum
    n = 0 if branches is None or continuum else branches.n
    on_stack = is_stack_scene(scene) and not unfolded
    friction = scene.friction
    if friction is None:
        friction_source = "None"
    else:
        stribeck = "p[8]" if friction.stribeck_velocity is not None else "1.0"
        kinetic = "p[7]" if friction.stribeck_velocity is not None else "p[6]"
        friction_source = f"(p[6], {kinetic}, {stribeck}, p[9])"
    return {
        "n": n,
        "m": "p[0]" if scene.mass is not None else "None",
        "k0": "p[3]" if scene.spring is not None else "0.0",  # the library's model: compiled.compile_model
        "k3": "p[4]" if scene.cubic is not None else "0.0",
        # the branches' coefficients read-only, as the library's model holds them (compiled._read_only): the
        # same types, so the FMU's kernels are the library's compiled loops, not copies compiled for writable ones
        "k": (f"(carray(kp, {branches.params[0].shape}),)" if continuum else f"carray(kp, (10, {n + 1}))"
              if on_stack else f"read_only(carray(kp, ({n},)))" if n else "None"),
        "eta": "None" if on_stack else f"read_only(carray(etap, ({n},)))" if n else "None",
        "cs": f"read_only(carray(csp, ({n},)))" if scene.has_series_dashpots else "None",
        "u": f"carray(up, ({state_size(scene)},))" if on_stack else f"carray(up, ({n},))" if n else "None",
        "stack": "True" if on_stack else "False",
        "has_branches": "True" if n else "False",
        "friction": friction_source,
        "massive": "True" if scene.mass is not None else "False",
        **memory_source(scene),
    }


_MARK_X0, _MARK_V0 = 1.0 + 1000 / 1024, 1.0 + 1001 / 1024  # the initial state's marks (memory_layout)


def _literal(value: float) -> str:
    """A float as generated source (NaN and the infinities as numpy's names)."""
    value = float(value)
    if value != value:
        return "np.nan"
    if abs(value) == float("inf"):
        return "np.inf" if value > 0 else "-np.inf"
    return repr(value)


def memory_layout(scene) -> dict:
    """Where the effects with memory sit in the kernels' ``mp`` (parameters) and ``ms`` (state) arrays, found in
    the library's own kernel form (``memory.compile_memory``) of the scene with each parameter and x0, v0 set to a
    distinct mark: a mark in a part's parameter tuple is read from ``mp``, one in its arrays is written there by
    the fresh memory (``initial``); every other entry is the library's constant.

    ``mp``: the FMU's memory parameters (``names``: delay_gain, delay_tau, history_weight[j], history_rate[j],
    dahl_sigma, dahl_force, dahl_exponent, those of the effects present). ``ms``: every part's arrays in kernel
    order, the delay's buffer last (``fixed`` values before it; its ``nd`` values are ``memory.delay.size`` at the
    tau in use). Returns the names, ``parts`` (per effect: None, or (params' sources, [(offset, length or None
    for the buffer, {index: source of its fresh value})])), ``fixed``, ``nh``, and the offsets the C layer checks
    a state with (``dahl_state``: the Dahl force; ``delay``, ``dahl``: whether present)."""
    from ...memory import EFFECTS, compile_memory
    from ...scene import MEMORY_COEFFICIENTS, _coefficient_key, coefficients_of, with_coefficients

    names = [name for name in coefficients_of(scene) if _coefficient_key(name) in MEMORY_COEFFICIENTS]
    layout = {"names": names, "parts": [None, None, None], "fixed": 0, "dahl_state": 0,
              "nh": len(scene.history.weight) if scene.history is not None else 0,
              "delay": scene.delay is not None, "dahl": scene.dahl is not None}
    if not names:
        return layout
    marks = {1.0 + (j + 1) / 1024: f"mp[{j}]" for j in range(len(names))}
    marked = with_coefficients(scene, **{name: value for value, name in zip(marks, names)})
    massive = scene.mass is not None
    marks[_MARK_X0] = "p[1]" if massive else "0.0"  # driver._memory_model: x0, v0 of a massless element are 0
    marks[_MARK_V0] = "p[2]" if massive else "0.0"
    memory = compile_memory(marked, _MARK_X0, _MARK_V0)

    def source(value):
        if isinstance(value, float) and value in marks:
            return marks[value]
        if isinstance(value, np.ndarray):  # an array of parameters (history's weights or rates): a slice of mp
            first = marks.get(float(value[0]), "")
            start = int(first[3:-1]) if first.startswith("mp[") else -1
            if start < 0 or [marks.get(float(v)) for v in value] != [f"mp[{start + i}]" for i in range(len(value))]:
                raise ValueError("the native runtime cannot pass a memory parameter array that is not the FMU's")
            return f"carray(mp, ({len(names)},))[{start}:{start + len(value)}]"
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise ValueError(f"the native runtime cannot pass a memory parameter {value!r}")
        # an integer as np.int64, not a constant: numba types a constant as a literal of its own, and would compile
        # the library's loop and every kernel under it once more for it (tests/compiled_copies.py)
        return f"np.int64({int(value)})" if isinstance(value, (int, np.integer)) else repr(float(value))

    offset = 0
    arrays_of = {}
    for index, (name, part) in enumerate(zip(EFFECTS, memory)):
        if part is None:
            continue
        params = [source(value) for value in part[0]]
        arrays = []
        for array in part[1:]:
            if name == "delay":  # its buffer, sized at run time: placed last
                arrays.append([None, None, array])
                continue
            arrays.append([offset, array.shape[0], array])
            offset += array.shape[0]
        layout["parts"][index] = (params, arrays)
        arrays_of[name] = arrays
    layout["fixed"] = offset
    for index, (name, part) in enumerate(zip(EFFECTS, memory)):
        if part is None:
            continue
        for entry in layout["parts"][index][1]:
            offset_, length, array = entry
            if offset_ is None:
                entry[0] = offset
            entry[2] = {i: marks[value] if value in marks else _literal(value)
                        for i, value in enumerate(array.tolist()) if value != 0.0}  # (a NaN marker too)
    if layout["dahl"]:
        layout["dahl_state"] = arrays_of["dahl"][0][0]
    return layout


def memory_source(scene) -> dict:
    """The generated source of the memory: the tuple of ``driver.compile_model`` (``memory``), the fresh memory
    at t = 0 (``fresh``: ``compile_memory``'s values) and the massless element's start without a dashpot
    (``quasi_static``: ``driver._initial_with_memory``), as lines of the ``initial`` kernel."""
    layout = memory_layout(scene)
    if not layout["names"]:
        return {"memory": "(None, None, None)", "fresh": "", "quasi_static": ""}
    fixed = layout["fixed"]
    parts = []
    fresh = ["    # the fresh memory (memory.compile_memory): its constants, the parameters in use, x0 and v0",
             f"    state = carray(msp, ({fixed} + nd,))",
             f"    for j in range({fixed} + nd):",
             "        state[j] = 0.0"]
    buffer_marks = {}
    for index, part in enumerate(layout["parts"]):
        if part is None:
            parts.append("None")
            continue
        params, arrays = part
        views = []
        for offset, length, values in arrays:
            if length is None:  # the delay's buffer
                views.append(f"carray(msp, ({fixed} + nd,))[{fixed}:{fixed} + nd]")
                buffer_marks = values
            else:
                views.append(f"carray(msp, ({fixed},))[{offset}:{offset + length}]")
            fresh += [f"    state[{offset + i}] = {value}" for i, value in values.items()]
        parts.append(f"(({', '.join(params)}{',' if len(params) == 1 else ''}), {', '.join(views)})")
    quasi = []
    if scene.mass is None and scene.damper is None:  # driver._initial_with_memory
        gain = "mp[0]" if layout["delay"] else "0.0"  # delay_gain: the first name
        quasi = [f"    linear = {gain}",
                 ("    w = solve_dahl_increment(memory[2], 0.0, linear, -force, k0, k3, k, eta, None, u, 0.0)"
                  if layout["dahl"] else
                  "    w = solve_increment(0.0, linear, -force, k0, k3, k, eta, None, u, 0.0)"),
                 "    if not (abs(w) < np.inf):",
                 "        return 0",
                 "    move(k, eta, u, w, None)"]
        if layout["delay"]:  # the history y(0) is the equilibrium: where compile_memory put x0
            quasi += ["    buffer = memory[0][1]"] + [f"    buffer[{i}] = w" for i in buffer_marks]
        if layout["dahl"]:
            quasi.append("    memory[2][1][0] = dahl_after(memory[2], 0.0, w)[0]")
        quasi += ["    xv[0] = w", "    xv[1] = 0.0", "    return 1"]
    return {"memory": "(" + ", ".join(parts) + ")", "fresh": "\n".join(fresh), "quasi_static": "\n".join(quasi)}


def is_stack_scene(scene) -> bool:
    """Whether the scene's branches run on the memory stack (``driver.choose_branch_kernel``: many branches with an
    admissible initial state, or the continuum)."""
    from ...driver import choose_branch_kernel

    return scene.branches is not None and choose_branch_kernel(scene, "projected") == "stack"


def takes_stack(stepper) -> bool:
    """Whether the stepper runs on the memory stack (every one but ``exact``)."""
    from ...steppers import get_stepper

    return bool(getattr(get_stepper(stepper), "BRANCH_STACK", False))


def folds(scene) -> bool:
    """Whether the scene's n branches are on the memory stack, which ``exact`` does not take: as
    ``driver.Element`` does, the native FMU then unfolds them to n elongations for exact (the O(n) kernel's
    functions, suffix ``p``) and folds them back for another stepper when they are admissible
    (``fold``: ``stack.refer`` and ``stack.start``)."""
    return is_stack_scene(scene) and not scene.branches.continuum


def state_size(scene) -> int:
    """The length of the branches' state: n elongations, or the memory stack's state (``stack.fresh_state``)."""
    from ...kernels import stack

    branches = scene.branches
    if branches is not None and branches.continuum:
        return stack.HEADER + stack.ROW * (stack.CONTINUUM_PIECES + 1)
    n = 0 if branches is None else branches.n
    return stack.HEADER + stack.ROW * (n + 1) if is_stack_scene(scene) else n


def variants(scene) -> list:
    """("c" | "n", with_dashpot): the dashpot variants of the scene's functions (see the module docstring).

    An element's functions are compiled once: the dashpot of a massless element sets its rate (c stays > 0:
    common.h), and a mass's dashpot of c = 0 is no dashpot, the same library loop with c = 0.0 (the C layer's
    ``_n`` names are then the ``_c`` functions: build.py). The connector's take c = 0 apart (its own template)."""
    if scene.damper is None:
        return [("n", False)]
    if scene.causality != "displacement":
        return [("c", True)]
    return [("c", True), ("n", False)]


def applicable(scene) -> list:
    """The native steppers that apply to ``scene`` without its white noise (``loop_for`` accepts it): the FMU's
    parameters turn a noise on and off, and a stepper that takes none refuses it then (:func:`noise_refusal`)."""
    from ...steppers import get_stepper

    names = []
    for name in NATIVE_STEPPERS:
        try:
            get_stepper(name).loop_for(with_noise(scene, None))
        except ValueError:
            continue
        names.append(name)
    return names


def with_noise(scene, noise):
    """The scene (an element's or a network's) with the white noise ``noise`` (None: none) on its load."""
    import dataclasses

    if getattr(scene.load, "noise", None) is noise:
        return scene
    return dataclasses.replace(scene, load=dataclasses.replace(scene.load, noise=noise))


def with_a_noise(scene):
    """The scene with a white noise on its load (the steppers' rules read only that there is one)."""
    from ...loads import WhiteNoise

    return with_noise(scene, WhiteNoise(1.0, 0))


def noise_refusal(scene, stepper) -> "str | None":
    """Why ``stepper`` takes no white noise on ``scene``: the library's own refusal (``loop_for`` of the scene
    with a noise, what ``Element.set_noise`` and ``set_stepper`` call), or None when it takes one. A rule of the
    scene's structure (which effects), never of a coefficient the FMU may change: a massless element keeps its
    dashpot in the native runtime (c > 0, common.h)."""
    from ...steppers import get_stepper

    try:
        get_stepper(stepper).loop_for(with_a_noise(scene))
    except ValueError as exc:
        return str(exc)
    return None


@functools.lru_cache(maxsize=None)
def read_only():
    """The compiled function ``read_only(array)``: the same array (data, shape, owner), typed read-only. A
    ``carray`` is writable; the library's model holds the branches' coefficients read-only, and numba compiles a
    loop for each. Only the type changes (numba lays both out alike), so nothing is copied. Made once."""
    from numba.core import types
    from numba.core.imputils import impl_ret_borrowed
    from numba.extending import intrinsic

    @intrinsic
    def read_only(typingctx, array):
        if not isinstance(array, types.Array):
            return None
        result = array.copy(readonly=True)

        def codegen(context, builder, signature, args):
            return impl_ret_borrowed(context, builder, result, args[0])

        return result(array), codegen

    return read_only


def compile_kernels(scene, steppers) -> list:
    """Compile the scene's C functions for ``steppers`` (:func:`applicable`); returns ``[(c_name, cfunc), ...]``:
    ``advance_<stepper>_<variant>``, ``noisy_<stepper>_<variant>`` (``advance_noisy``, for the steppers that take
    a white noise), ``record_<variant>``, ``row_<variant>``, ``stiffness_<variant>``, ``limits_<variant>``,
    ``initial_<variant>``,
    ``elongations_<variant>``, ``rates_<variant>``, ``force_at``; for a scene that :func:`folds`, the same on the O(n) kernel
    (``<variant>p``) and ``fold``."""
    from numba import carray, cfunc, njit, types  # noqa: F401  (the generated source uses them)

    from ...kernels.drive import tangent
    from ...kernels.energy import kinetic, stored
    from ...kernels.friction import reaction
    from ...kernels.rates import output_rates
    from ...kernels.increment import solve_increment
    from ...kernels.play import branch_force, move, write_elongations
    from ...kernels.showable import limits as showable_limits
    from ...kernels.smooth import elastic_force
    from ...kernels.stack import start
    from ...loads import force_at
    from ...memory import force_now
    from ...memory.dahl import after as dahl_after
    from ...kernels.dahl_increment import solve_dahl_increment
    from ...steppers import get_stepper

    checks = [("state_check", compile_state_check(scene))] if is_stack_scene(scene) else []
    if scene.causality == "displacement":
        return _compile_connector(scene, structure(scene)) + checks
    checks.append(("stability", compile_stability(scene)))
    compiled = []
    compiled_force = False
    quiet, noisy = with_noise(scene, None), with_a_noise(scene)  # the two loads a stepper's loop is compiled for
    kernels = [("", structure(scene))] + ([("p", structure(scene, unfolded=True))] if folds(scene) else [])
    for suffix, damped in variants(scene):
        for unfolded, shape in kernels:
            # c as compiled.compile_model hands it: c > 0, else 0.0 (a master's -0.0 too, as the library's)
            source = _TEMPLATE.format(c="(p[5] if p[5] > 0.0 else 0.0)" if damped else "0.0",
                                      damped="True" if damped else "False",
                                      noise_cache=NOISE_CACHE_SIZE, **shape)
            for stepper in list(steppers) + [None]:
                if stepper and shape["stack"] == "True" and not takes_stack(stepper):
                    continue  # on the O(n) kernel only (the element unfolds the stack for it)
                takes_noise = stepper is not None and noise_refusal(scene, stepper) is None
                namespace = dict(carray=carray, read_only=read_only(), np=np, reaction=reaction, kinetic=kinetic,
                                 stored=stored,
                                 tangent=tangent, showable_limits=showable_limits,
                                 branch_force=branch_force, move=move,
                                 solve_increment=solve_increment, write_elongations=write_elongations,
                                 elastic_force=elastic_force, force_at=force_at, start=start,
                                 force_now=force_now, solve_dahl_increment=solve_dahl_increment,
                                 dahl_after=dahl_after, output_rates=output_rates,
                                 run=get_stepper(stepper).loop_for(quiet) if stepper else None,
                                 run_noisy=get_stepper(stepper).loop_for(noisy) if takes_noise else None)
                exec(compile(source, f"<prandtl_fmu native kernels of {scene.source}>", "exec"), namespace)
                for helper in ("_model", "_load", "_noisy_load"):  # inlined into each C function
                    namespace[helper] = njit(inline="always")(namespace[helper])
                names = (["advance"] + (["advance_noisy"] if takes_noise else []) if stepper
                         else ["record", "row", "stiffness", "limits", "initial", "elongations", "rates"])
                if stepper is None and not compiled_force:
                    names.append("force_at")  # the scene's load alone: once
                    compiled_force = True
                for name in names:
                    signature = eval(_SIGNATURES[name], {"types": types})
                    function = cfunc(signature, error_model="numpy")(
                        namespace["force_at_c" if name == "force_at" else name])
                    c_name = (f"advance_{stepper}_{suffix}{unfolded}" if name == "advance" else
                              f"noisy_{stepper}_{suffix}{unfolded}" if name == "advance_noisy" else
                              "force_at" if name == "force_at" else f"{name}_{suffix}{unfolded}")
                    compiled.append((c_name, function))
    if folds(scene):
        compiled.append(("fold", _compile_fold(scene)))
    return compiled + checks


def compile_stability(scene):
    """``stability(p, cs, x, h, kind, out)`` -> what ``stability.check`` finds for the element's coefficients ``p``
    (:data:`PARAMETERS` order), series dashpots ``cs``, displacement ``x``, step ``h`` and stepper ``kind``
    (``stability.stepper_kind``), its numbers in ``out`` (4 doubles): the library's own check, whose findings the
    C layer words as ``stability.explain`` does. The scene's structure (which effects are present, the branches'
    stiffness) is fixed here, as the library reads it from the scene."""
    from numba import carray, cfunc, types

    from ...stability import check

    # a np.bool_, not True or False: one compiled check() for every element, not a copy for each constant (it is
    # not the library's: this closure's k_branch is a read-only constant, the library's a writable array)
    massive = np.bool_(scene.mass is not None)
    has_spring, has_cubic, has_damper = (scene.spring is not None, scene.cubic is not None,
                                         scene.damper is not None)
    stribeck = scene.friction is not None and scene.friction.stribeck_velocity is not None
    k_sum = float(scene.branches.stiffness_sum) if scene.branches is not None else 0.0
    k_branch = (np.asarray(scene.branches.stiffness, dtype=np.float64) if scene.has_series_dashpots
                else np.zeros(0))
    n = k_branch.size

    def stability(p, csp, x, h, kind, outp):
        m = p[0] if massive else 0.0
        c = p[5] if has_damper else 0.0
        k0 = p[3] if has_spring else 0.0
        k3 = p[4] if has_cubic else 0.0
        drop = (p[6] - p[7]) / p[8] if stribeck else 0.0  # effects.Friction.drop_slope
        return check(kind, massive, m, c, k0, k3, x, k_sum, drop, k_branch, carray(csp, (n,)), h, carray(outp, (4,)))

    pointer = types.CPointer(types.float64)
    return cfunc(types.int64(pointer, pointer, types.float64, types.float64, types.int64, pointer),
                 error_model="numpy")(stability)


def _compile_fold(scene):
    """``fold(kp, u, x, state)`` -> 1, or 0 when the n elongations ``u`` are not admissible: the stack's
    parameters ``kp`` refer to ``u`` and ``state`` is the fresh stack at x (``driver.Element._use_branch_kernel``:
    ``stack.prepare`` then ``stack.fresh_state``)."""
    from numba import carray, cfunc, types

    from ...kernels.stack import refer, start

    n, size = scene.branches.n, state_size(scene)

    def fold(kp, up, x, statep):
        params = carray(kp, (10, n + 1))
        if not refer(params, carray(up, (n,))):
            return 0
        start(params, x, carray(statep, (size,)))
        return 1

    signature = types.int64(types.CPointer(types.float64), types.CPointer(types.float64), types.float64,
                            types.CPointer(types.float64))
    return cfunc(signature, error_model="numpy")(fold)


def _compile_connector(scene, shape) -> list:
    """The connector's C functions (``_CONNECTOR_TEMPLATE``): ``move``, ``cpath``, ``cforce``, ``ctangent``,
    ``cdirectional``, ``crates``, ``cstored``, ``cinitial``, ``elongations``, each ``_<variant>``. With effects with memory, ``move`` is
    ``drive_with_memory``, the force and the tangent add the memory's (``memory.force_now``, ``tangent_now``) and
    ``cinitial`` makes the memory fresh, as ``connector.Connector`` does."""
    from numba import carray, cfunc, njit, types

    from ...kernels.drive import drive, drive_polynomial, drive_with_memory, tangent
    from ...kernels.energy import stored
    from ...kernels.play import branch_force, write_elongations
    from ...kernels.rates import connector_rates
    from ...kernels.smooth import smooth_force
    from ...kernels.stack import start
    from ...memory import force_now, tangent_now

    compiled = []
    has_memory = "True" if memory_layout(scene)["names"] else "False"
    for suffix, damped in variants(scene):
        source = _CONNECTOR_TEMPLATE.format(c="p[5]" if damped else "0.0", damped="True" if damped else "False",
                                            has_memory=has_memory, **shape)
        namespace = dict(carray=carray, read_only=read_only(), np=np, drive=drive, drive_with_memory=drive_with_memory,
                         drive_polynomial=drive_polynomial, tangent=tangent,
                         stored=stored, branch_force=branch_force, write_elongations=write_elongations,
                         smooth_force=smooth_force, start=start, force_now=force_now, tangent_now=tangent_now,
                         connector_rates=connector_rates)
        exec(compile(source, f"<prandtl_fmu native connector of {scene.source}>", "exec"), namespace)
        namespace["_model"] = njit(inline="always")(namespace["_model"])
        for name, signature in _CONNECTOR_SIGNATURES.items():
            function = cfunc(eval(signature, {"types": types}), error_model="numpy")(namespace[name])
            compiled.append((f"{name}_{suffix}", function))
    return compiled


# why a memory-stack state cannot be restored (stack.restore's ValueError, in order), by the code state_check returns
STATE_CHECK_REASONS = (
    None,
    "not a memory-stack state (a header or piece is not finite)",
    "memory-stack state: wrong count of pieces",
    "memory-stack state: the pieces do not tile the branches",
    "memory-stack state: branches slid in no direction",
    "memory-stack state: an elongation outside its elastic range",
    "memory-stack state: the elongations are not admissible (|u_i - u_j| > |eta_i - eta_j|)",
    "memory-stack state: the running totals do not match the pieces",
    "its memory-stack parameters are not this scene's",
    "memory-stack state: a piece's weight of the initial elongations is not one the stack makes",  # stack.restore's
)


def compile_state_check(scene):
    """``state_check(kp, state, scratch)`` -> 0, or the index in :data:`STATE_CHECK_REASONS` of why the memory-stack
    ``state`` (its full array, ``state_size``) over the stack's parameters ``kp`` is not one the library would restore
    (``stack.restore`` and ``_check_admissible``, the same rules and tolerances; with n branches also that ``kp``'s
    rows of the elongations referred to are what ``stack.refer`` makes of them). ``scratch``: ``state_size + n``
    doubles. The FMU state a master hands back is checked with it before anything runs on it."""
    import math

    from numba import carray, cfunc, njit, types

    from ...kernels import stack

    branches = scene.branches
    continuum = branches.continuum
    size = state_size(scene)
    n = 0 if continuum else branches.n
    shape = branches.params[0].shape if continuum else (10, n + 1)
    header, row_len, resync_every = stack.HEADER, stack.ROW, stack.RESYNC
    COUNT, TOP, DIRECTION, SK, S0, MOVES, X = range(header)
    end = 1.0 if continuum else float(n)
    limit = (stack.CONTINUUM_PIECES + 1 - 2) if continuum else n
    eta_at, refer, resync = stack._eta_at, stack.refer, stack.resync
    ETA_ROW, C_ROW, ORDER_ROW = stack.ETA_ROW, stack.C_ROW, stack.ORDER_ROW

    @njit
    def tiles(state, count):
        if not (state[DIRECTION] == -1.0 or state[DIRECTION] == 0.0 or state[DIRECTION] == 1.0):
            return False
        if not (0.0 <= state[TOP] <= end):
            return False
        bound = end
        for j in range(count):
            row = header + row_len * j
            lo, hi = state[row], state[row + 1]
            if hi != bound or lo > hi or abs(state[row + 3]) > 1.0:
                return False
            if not continuum and lo != math.floor(lo):  # n branches: positions are branch indices
                return False
            bound = lo
        return bound == state[TOP]  # the last piece ends at the top (no piece: the top is the end)

    @njit
    def admissible(params, state, count, u):
        x = state[X]
        size_ = abs(x)
        for j in range(count):
            size_ = max(size_, abs(x) + abs(state[header + row_len * j + 2]))
        if continuum:
            table = params[0]
            for j in range(count):
                row = header + row_len * j
                for position in (state[row], state[row + 1]):
                    eta = eta_at(table, position)
                    if abs(state[row + 2] + x + state[row + 3] * eta) > eta + 1e-12 * max(1.0, eta, size_):
                        return 5
            return 0
        largest = 0.0
        for i in range(n):
            largest = max(largest, params[ETA_ROW, i])
        top = int(state[TOP])
        for i in range(top):
            u[i] = state[DIRECTION] * params[ETA_ROW, i]
        for j in range(count):
            row = header + row_len * j
            a, beta, gamma = state[row + 2], state[row + 3], state[row + 4]
            for i in range(int(state[row]), int(state[row + 1])):
                u[i] = a + x + beta * params[ETA_ROW, i] + gamma * params[C_ROW, i]
        tolerance = 1e-12 * max(1.0, largest, size_)
        for i in range(n):
            if abs(u[i]) > params[ETA_ROW, i] + tolerance:
                return 5
        for i in range(n - 1):
            if not abs(u[i + 1] - u[i]) <= (params[ETA_ROW, i + 1] - params[ETA_ROW, i]) + tolerance:
                return 6
        return 0

    @njit
    def referred(params, u0):
        """stack.refer makes of kp's own rows of u0 exactly kp (bit for bit)."""
        work = np.empty((10, n + 1))  # numba's runtime (stubs.c): a reshape of the scratch would need numba's helper
        for i in range(n):
            u0[int(params[ORDER_ROW, i])] = params[C_ROW, i]
        for r in range(10):
            for i in range(n + 1):
                work[r, i] = params[r, i]
        if not refer(work, u0):
            return False
        for r in range(10):
            for i in range(n + 1):
                if not work[r, i] == params[r, i]:
                    return False
        return True

    def state_check(kp, statep, scratchp):
        table = carray(kp, shape)
        params = (table,) if continuum else table
        state = carray(statep, (size,))
        scratch = carray(scratchp, (size + n,))
        if not continuum:
            for r in range(10):
                for i in range(n + 1):
                    if not math.isfinite(table[r, i]):
                        return 8
            if not referred(table, scratch[size:size + n]):
                return 8
        for i in range(header):
            if not math.isfinite(state[i]):
                return 1
        count = int(state[COUNT]) if 0.0 <= state[COUNT] <= limit else -1
        if count < 0 or state[COUNT] != count:
            return 2
        for i in range(header, header + row_len * count):
            if not math.isfinite(state[i]):
                return 1
        if not tiles(state, count):
            return 3
        if state[DIRECTION] == 0.0 and state[TOP] != 0.0:
            return 4
        for j in range(count):  # gamma: 1 on the piece referring to the initial elongations, else 0
            gamma = state[header + row_len * j + 4]
            if not (gamma == 0.0 or (gamma == 1.0 and not continuum)):
                return 9
        problem = admissible(params, state, count, scratch)
        if problem:
            return problem
        for i in range(header + row_len * count):
            scratch[i] = state[i]
        resync(params, scratch)  # the totals are those of the pieces (to rounding)
        scale = 1.0 + abs(scratch[SK]) + abs(scratch[S0])
        if (abs(scratch[SK] - state[SK]) + abs(scratch[S0] - state[S0]) > 1e-9 * scale
                or not 0.0 <= state[MOVES] < resync_every):
            return 7
        return 0

    pointer = types.CPointer(types.float64)
    return cfunc(types.int64(pointer, pointer, pointer), error_model="numpy")(state_check)
