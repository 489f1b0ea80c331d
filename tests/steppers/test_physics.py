"""The physics of every stepper: invariants, closed forms, measured orders, energy.

The tests run over every stepper keep the energy account (``energy=True``): the same compiled loop as the
element's and the FMUs' tests of those effects, where a run without it compiles one of its own (the account never
changes the motion: tests/fmu/python/test_against_library.py)."""
import math

import numpy as np
import pytest

from prandtl_fmu import STEPPERS, load_scene, simulate
from prandtl_fmu.steppers import get_stepper

from tests.conftest import SCENES, make_scene

ALL = list(STEPPERS)
STEPPED = [name for name in ALL if math.isfinite(get_stepper(name).ORDER)]  # all but `exact`


def fits(stepper, **changes):
    """make_scene(**changes), without the cubic spring if the stepper refuses it (``exact``)."""
    try:
        scene = make_scene(**changes)
        get_stepper(stepper).loop_for(scene)
    except ValueError:  # SceneError is a ValueError
        scene = make_scene(**{**changes, "cubic": None})
    return scene


def energy(result):
    """m v^2/2 + k0 x^2/2 + k3 x^4/4 + sum k_i u_i^2/2 on the output grid."""
    scene = result.scene
    e = 0.5 * scene.mass.m * result.v**2
    if scene.spring:
        e += 0.5 * scene.spring.k0 * result.x**2
    if scene.cubic:
        e += 0.25 * scene.cubic.k3 * result.x**4
    if scene.branches:
        e += 0.5 * result.u**2 @ scene.branches.stiffness
    return e


def fitted_order(hs, errors):
    slope, intercept = np.polyfit(np.log(hs), np.log(errors), 1)
    return slope, np.exp(intercept)


@pytest.mark.parametrize("stepper", ALL)
def test_elongations_stay_in_their_elastic_range_at_every_step(stepper):
    rng = np.random.default_rng(1)
    n = 40
    eta = rng.uniform(0.0, 0.2, n)
    eta[:3] = [0.0, 1e-12, 0.0]
    branches = {"k": rng.uniform(0.1, 5.0, n), "eta": eta, "u0": rng.uniform(-1, 1, n) * eta}
    scene = fits(stepper, branches=branches,
                 load={"kind": "harmonic", "amplitude": 30.0, "omega": 3.0, "offset": 1.0},
                 solver={"stepper": stepper, "step": 2e-3, "stop_time": 10.0, "output_interval": 2e-3})
    result = simulate(scene, states=True, energy=True)
    assert result.u.shape == (5001, n)
    assert np.all(np.isfinite(result.u))
    assert np.all(np.abs(result.u) <= eta)  # exactly: no tolerance
    assert np.all(result.u[:, 0] == 0.0) and np.all(result.u[:, 2] == 0.0)
    assert np.abs(result.u).max() > 0.1  # the load did drive branches to slip


@pytest.mark.parametrize("stepper", ALL)
@pytest.mark.parametrize("table, zero", [("spring", {"k0": 0.0}), ("cubic", {"k3": 0.0}), ("damper", {"c": 0.0})])
def test_an_effect_with_zero_coefficient_is_the_absent_effect(stepper, table, zero):
    solver = {"stepper": stepper, "step": 1e-3, "stop_time": 5.0, "output_interval": 0.01}
    if stepper == "exact" and table == "cubic":
        with pytest.raises(ValueError, match="cubic"):  # any cubic spring, even k3 = 0
            get_stepper(stepper).loop_for(make_scene(solver=solver, cubic=zero))
        return
    others = {} if stepper != "exact" else {"cubic": None}
    present = simulate(make_scene(solver=solver, **{**others, table: zero}), states=True, energy=True)
    absent = simulate(make_scene(solver=solver, **{**others, table: None}), states=True, energy=True)
    for name in ("x", "v", "reaction", "u"):
        if (stepper == "implicit" and table == "cubic") or stepper == "exact":
            # another solve path (Newton with a cubic term; the phase matrix of `exact`): equal to rounding
            np.testing.assert_allclose(getattr(present, name), getattr(absent, name), rtol=1e-10, atol=1e-12)
        else:  # adding 0 * x is exact
            np.testing.assert_array_equal(getattr(present, name), getattr(absent, name))


def oscillator_scene(stepper, step, damped):
    """Thresholds far too large to yield: a linear oscillator of stiffness K = k0 + sum k_i."""
    return make_scene(
        mass={"m": 1.5, "x0": 0.2, "v0": -0.3},
        spring={"k0": 0.5},
        cubic=None,
        damper={"c": 0.3} if damped else None,
        branches={"k": [0.5, 1.0], "eta": [1e3, 1e3], "u0": [0.1, -0.2]},
        load={"kind": "constant", "value": 0.4},
        solver={"stepper": stepper, "step": step, "stop_time": 10.0, "output_interval": 0.04},
    )


def oscillator_exact(t, damped):
    m, x0, v0, c = 1.5, 0.2, -0.3, (0.3 if damped else 0.0)
    stiffness = 0.5 + 1.5
    offset = 0.5 * 0.1 + 1.0 * -0.2 - 1.5 * x0  # sum k_i (u0_i - x0): the branch force is K_b x + this
    x_eq = (0.4 - offset) / stiffness
    gamma = c / (2 * m)
    omega = np.sqrt(stiffness / m - gamma**2)
    a = x0 - x_eq
    b = (v0 + gamma * a) / omega
    return x_eq + np.exp(-gamma * t) * (a * np.cos(omega * t) + b * np.sin(omega * t))


@pytest.mark.parametrize("stepper", ALL)
@pytest.mark.parametrize("damped", [False, True])
def test_linear_oscillator_converges_to_closed_form_at_declared_order(stepper, damped):
    hs = np.array([0.02, 0.01, 0.005, 0.0025, 0.00125])
    errors = []
    for h in hs:
        result = simulate(oscillator_scene(stepper, h, damped), energy=True)
        errors.append(np.max(np.abs(result.x - oscillator_exact(result.time, damped))))
    declared = get_stepper(stepper).ORDER
    if math.isinf(declared):
        assert max(errors) < 1e-12, errors  # exact to rounding at any output grid
        return
    order, _ = fitted_order(hs, errors)
    assert abs(order - declared) < 0.05 * declared, (order, errors)
    assert errors[-1] < 5e-3


def paper_scene(n, stepper, h, stop_time):
    scene = load_scene(SCENES / "paper-section-8.toml")
    if n != 100:
        from prandtl_fmu.scene import parse_scene

        text = (SCENES / "paper-section-8.toml").read_text().replace("count = 100", f"count = {n}")
        scene = parse_scene(text, "paper.toml")
    return scene.with_solver(stepper=stepper, step=h, stop_time=stop_time, output_interval=0.04)


def all_components(result):
    """u = (x, v, u_1..u_n) on the output grid, shape (rows, n + 2)."""
    return np.column_stack([result.x, result.v, result.u])


@pytest.fixture(scope="module")
def paper_reference():
    """Reference for the paper's scene on [0, 12]: Richardson extrapolation of ``projected``.

    The scheme is of order 1 with a smooth error expansion (the paper's
    Table 1), so 2 u_{h/2} - u_h at h = 2e-6 removes the O(h) term. Its own
    error is estimated by the same extrapolation one level coarser.
    """
    runs = {h: all_components(simulate(paper_scene(100, "projected", h, 12.0), states=True))
            for h in (4e-6, 2e-6, 1e-6)}
    fine = 2 * runs[1e-6] - runs[2e-6]
    coarse = 2 * runs[2e-6] - runs[4e-6]
    return fine, np.max(np.abs(fine - coarse))


@pytest.mark.parametrize("stepper", ALL)
def test_order_with_friction_active_on_the_paper_scene(stepper, paper_reference):
    if stepper == "exact":
        reference, reference_error = paper_reference
        result = simulate(paper_scene(100, stepper, 0.04, 12.0), states=True, energy=True)
        assert np.abs(all_components(result) - reference).max() < 10 * reference_error
        return
    reference, reference_error = paper_reference
    assert reference_error < 1e-6
    hs = np.array([0.01, 0.005, 0.0025, 0.00125, 0.000625])
    errors = []
    for h in hs:
        result = simulate(paper_scene(100, stepper, h, 12.0), states=True, energy=True)
        errors.append(np.max(np.abs(all_components(result) - reference)))
    assert min(errors) > 100 * reference_error
    order, _ = fitted_order(hs, errors)
    declared = get_stepper(stepper).ORDER
    assert abs(order - declared) < 0.05 * declared, (order, errors)
    # Friction was active: the largest branches slipped.
    assert np.any(np.abs(result.u[:, -1]) == result.scene.branches.yield_displacement[-1]) or \
        np.any(np.abs(result.u[:, 0]) == result.scene.branches.yield_displacement[0])


def test_max_norm_constant_is_uniform_in_n_and_euclidean_one_is_not():
    """The paper's Table 1 pattern, with its method: eps(h) = |u_h - u_{h/2}| ~ 2 C h^alpha."""
    hs = np.array([0.02, 0.01, 0.005, 0.0025])
    constants = {}
    for n in (10, 100, 1000):
        runs = {h: all_components(simulate(paper_scene(n, "projected", h, 50.0), states=True))
                for h in np.append(hs, hs[-1] / 2)}
        for q in (np.inf, 2):
            eps = [np.max(np.linalg.norm(runs[h] - runs[h / 2], ord=q, axis=1)) for h in hs]
            alpha, two_c = fitted_order(hs, eps)
            assert abs(alpha - 1) < 0.1, (n, q, alpha)
            constants[n, q] = two_c / 2
    assert constants[1000, np.inf] / constants[10, np.inf] < 1.3, constants
    assert constants[1000, 2] / constants[10, 2] > 2.0, constants
    assert constants[1000, 2] > constants[100, 2] > constants[10, 2]


def straightforward_projected(scene, stop_time, h):
    """Scheme (5.1) written from the paper, with plain numpy: U <- proj_K(U + h f(t, U))."""
    m = scene.mass.m
    k0, k3, c = scene.spring.k0, scene.cubic.k3, scene.damper.c
    k, eta = scene.branches.stiffness, scene.branches.yield_displacement
    state = np.concatenate([[scene.mass.x0, scene.mass.v0], scene.branches.u0])
    lower = np.concatenate([[-np.inf, -np.inf], -eta])
    upper = np.concatenate([[np.inf, np.inf], eta])
    amplitude, omega = scene.load.amplitude, scene.load.omega
    out = [state.copy()]
    for p in range(int(round(stop_time / h))):
        x, y, u = state[0], state[1], state[2:]
        force = amplitude * np.cos(omega * p * h)
        f = np.concatenate([[y, (force - k0 * x - k3 * x**3 - c * y - k @ u) / m], np.full(len(u), y)])
        state = np.clip(state + h * f, lower, upper)
        out.append(state.copy())
    return np.array(out)


def test_projected_is_exactly_the_papers_scheme():
    scene = make_scene(solver={"stepper": "projected", "step": 1e-3, "stop_time": 3.0, "output_interval": 1e-3},
                       load={"kind": "harmonic", "amplitude": 2.0, "omega": 1.3, "offset": 0.0})
    result = simulate(scene, states=True)
    expected = straightforward_projected(scene, 3.0, 1e-3)
    np.testing.assert_allclose(all_components(result), expected, rtol=0, atol=1e-12)
    assert np.any(np.abs(expected[:, 2:]) == scene.branches.yield_displacement)  # it slipped


def test_implicit_energy_never_increases_without_load():
    rng = np.random.default_rng(7)
    n = 30
    eta = rng.uniform(0.0, 0.5, n)
    for step in (1e-3, 0.1, 2.0):  # up to omega h ~ 10: far beyond any explicit limit
        scene = make_scene(
            mass={"m": 0.5, "x0": 1.5, "v0": 4.0},
            spring={"k0": 3.0}, cubic={"k3": 2.0}, damper=None,
            branches={"k": rng.uniform(1.0, 20.0, n), "eta": eta, "u0": np.zeros(n)},
            load=None,
            solver={"stepper": "implicit", "step": step, "stop_time": 400 * step, "output_interval": step},
        )
        e = energy(simulate(scene, states=True))
        assert np.all(np.diff(e) <= 1e-13 * e[0]), np.diff(e).max()
        assert e[-1] < e[0]


def test_projected_multiplies_elastic_energy_by_one_plus_omega_h_squared():
    """Documented instability of the paper's scheme in the elastic regime, exactly as predicted."""
    h, steps = 0.01, 2000
    scene = oscillator_scene("projected", h, damped=False)
    scene = scene.with_solver(stop_time=steps * h, output_interval=h)
    from prandtl_fmu.loads import ConstantLoad
    import dataclasses

    scene = dataclasses.replace(scene, load=ConstantLoad(0.0))
    result = simulate(scene, states=True)
    omega2 = 2.0 / 1.5
    # the energy about the equilibrium x_eq (F = 0) grows by (1 + omega^2 h^2) per step
    x_eq = -(0.5 * 0.1 - 0.2 - 1.5 * 0.2) / 2.0
    e = 0.5 * 1.5 * result.v**2 + 0.5 * 2.0 * (result.x - x_eq) ** 2
    np.testing.assert_allclose(e[-1] / e[0], (1 + omega2 * h * h) ** steps, rtol=1e-9)


@pytest.mark.parametrize("stepper", ALL)
def test_output_grid_ends_at_stop_time_with_a_partial_last_interval(stepper):
    solver = {"stepper": stepper, "step": 0.01, "stop_time": 1.057, "output_interval": 0.1}
    coarse = simulate(fits(stepper, solver=solver), energy=True)
    assert coarse.time[-1] == 1.057 and coarse.time[-2] == 1.0 and len(coarse.time) == 12
    fine = simulate(fits(stepper, solver=dict(solver, output_interval=0.01, stop_time=1.0)), energy=True)
    if stepper == "exact":  # one exact step per output interval: other steps, same motion
        np.testing.assert_allclose(coarse.x[:-1], fine.x[::10], rtol=0, atol=1e-13)
    else:
        np.testing.assert_array_equal(coarse.x[:-1], fine.x[::10])
    assert np.isfinite(coarse.x[-1]) and coarse.x[-1] != coarse.x[-2]


# ------------------------------------------------ each stepper runs its own loop, whatever the cache holds

_RUN_STEPPERS = """
import sys
from prandtl_fmu import parse_scene, simulate
scene = parse_scene(sys.argv[1], "s.toml")
for name in sys.argv[2:]:
    print(name, repr(simulate(scene, name).x[-1].item()))
"""


def test_the_steppers_loops_have_names_of_their_own():
    """numba links a closure's machine code by module, qualified name, types and a per-process counter: the
    loops must differ by name (see kernels/loop.py), else a cached `run` can call another stepper's loop."""
    from prandtl_fmu.steppers import projected

    loops = [get_stepper(name)._loop for name in STEPPERS] + [projected._loop_massless]
    names = {loop.py_func.__qualname__ for loop in loops}
    assert len(names) == len(loops), names


@pytest.mark.slow
def test_each_stepper_compiled_alone_in_its_own_process_then_loaded_together_runs_its_own_scheme(tmp_path):
    """The CI failure this guards: `projected`, loaded from a cache that processes filled one stepper each, ran
    `implicit`. Every stepper is compiled alone in a fresh process, then all are loaded in one process from that
    cache, and each must give the numbers of the process that compiled it (its loop compiled there, not loaded:
    no other stepper's code in the cache can stand in for it)."""
    import os
    import subprocess
    import sys

    from tests.conftest import base_tables, scene_text

    text = scene_text(base_tables(cubic=None, load={"kind": "constant", "value": 0.9}))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))

    def run(names):
        done = subprocess.run([sys.executable, "-c", _RUN_STEPPERS, text, *names], capture_output=True, text=True,
                              env=env, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        return dict(line.split() for line in done.stdout.splitlines())

    compiled = {}
    for name in STEPPERS:
        compiled.update(run([name]))
    names = list(STEPPERS)
    assert len(set(compiled.values())) == len(names), compiled  # a number of its own for each scheme
    assert run(names) == run(names[::-1]) == compiled
