"""Friction of the mass on the ground (Coulomb, Stribeck, a moving belt) and series dashpots in the branches
(issue 25): closed forms, independent references, measured orders, the root rule, the energy account, the
scene's rules."""
import math
import subprocess
import sys
import warnings

import numpy as np
import pytest

from prandtl_fmu import Element, parse_scene, simulate
from prandtl_fmu.connector import Connector, displacement_response
from prandtl_fmu.scene import SceneError
from prandtl_fmu.stability import StabilityWarning

from tests.conftest import scene_text

STEPPING = ["projected", "implicit", "symplectic", "verlet"]


def make(tables: dict, source: str = "friction.toml"):
    tables = dict(tables)
    tables.setdefault("solver", {"stepper": "projected", "step": 1e-3, "stop_time": 10.0, "output_interval": 0.01})
    return parse_scene(scene_text(tables), source)


def run(scene, stepper, h=None, **options):
    overrides = {"stepper": stepper}
    if h is not None:
        overrides["step"] = h
    with warnings.catch_warnings():
        warnings.simplefilter("error", StabilityWarning)  # the scenes here are within every limit
        return simulate(scene.with_solver(**overrides), **options)


# ---------------------------------------------------------------- Coulomb friction: closed forms


def coulomb_oscillator(t, x0, m, k, alpha):
    """m x'' + k x + alpha sigma(x') ∋ 0 from rest at x0: half periods pi sqrt(m/k) about the centres
    +-alpha/k (the amplitude falls by 2 alpha/k each), stuck for good at the first stop with |x| <= alpha/k."""
    omega, reach = math.sqrt(k / m), alpha / k
    x = np.empty_like(t)
    start, position = 0.0, x0
    while abs(position) > reach:
        centre = math.copysign(reach, position)
        inside = (t >= start) & (t <= start + math.pi / omega)
        x[inside] = centre + (position - centre) * np.cos(omega * (t[inside] - start))
        start, position = start + math.pi / omega, 2.0 * centre - position
    x[t > start] = position
    return x, start


COULOMB = {"mass": {"m": 2.0, "x0": 0.95}, "spring": {"k0": 3.0}, "friction": {"alpha": 0.3},
           "solver": {"stepper": "projected", "step": 1e-3, "stop_time": 16.0, "output_interval": 0.01}}


@pytest.mark.parametrize("stepper", STEPPING + ["exact"])
def test_a_coulomb_oscillator_follows_its_closed_form_and_then_sticks_exactly(stepper):
    scene = make(COULOMB)
    result = run(scene, stepper)
    expected, stops_at = coulomb_oscillator(result.time, 0.95, 2.0, 3.0, 0.3)
    error = np.abs(result.x - expected).max()
    assert error <= (1e-9 if stepper == "exact" else 1e-2), error  # O(h), h = 1e-3
    assert 12.0 < stops_at < 13.0  # five half periods (0.95 -> -0.75 -> 0.55 -> -0.35 -> 0.15 -> 0.05)
    assert abs(expected[-1] - 0.05) < 1e-12
    # once stuck: v exactly 0 to the bit and x constant, at every row (a margin of a few steps for the schemes)
    stuck = result.time > stops_at + 0.05
    assert np.all(result.v[stuck] == 0.0)
    assert np.all(result.x[stuck] == result.x[stuck][0])
    # the friction holds the mass against the spring: reaction = F = 0 while it sticks
    assert np.all(result.reaction[stuck] == 0.0)


@pytest.mark.parametrize("stepper, order", [("projected", 1), ("implicit", 1), ("symplectic", 1), ("verlet", 1)])
def test_the_order_with_coulomb_friction_is_measured(stepper, order):
    scene = make(dict(COULOMB, solver={"stepper": stepper, "step": 1e-3, "stop_time": 6.0,
                                       "output_interval": 0.02}))
    errors = []
    steps = [4e-3, 2e-3, 1e-3, 5e-4]
    for h in steps:
        result = run(scene, stepper, h)
        expected, _ = coulomb_oscillator(result.time, 0.95, 2.0, 3.0, 0.3)
        errors.append(np.abs(result.x - expected).max())
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert slope > order - 0.25, (errors, slope)


# ---------------------------------------------------------------- the break-away under a slow ramp


def sliding_reference(m, k0, friction, rate, t_start, t_end, times):
    """The sliding phase after the break-away at t_start (x = v = 0), m v' = r t - k0 x - g(v), v > 0: scipy's
    DOP853 at rtol 1e-12 (an independent integrator), up to the first stop (an event)."""
    from scipy.integrate import solve_ivp

    alpha, kinetic, stribeck = friction

    def rhs(t, y):
        g = kinetic + (alpha - kinetic) * math.exp(-y[1] / stribeck)
        return [y[1], (rate * t - k0 * y[0] - g) / m]

    def stops(t, y):
        return y[1] if t > t_start + 1e-9 else 1.0

    stops.terminal, stops.direction = True, -1
    inside = times[(times >= t_start) & (times <= t_end)]
    solution = solve_ivp(rhs, (t_start, t_end), [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-15,
                         t_eval=inside, events=stops)
    return solution.t, solution.y[0]


@pytest.mark.parametrize("stepper", STEPPING + ["exact"])
def test_under_a_slow_ramp_the_mass_does_not_move_until_the_static_threshold_then_slides(stepper):
    rate, end = 0.5, 3.0
    friction = {"alpha": 0.6, "alpha_kinetic": 0.35, "stribeck_velocity": 0.2}
    if stepper == "exact":
        friction = {"alpha": 0.6}  # exact follows plain Coulomb friction only
    scene = make({"mass": {"m": 1.0}, "spring": {"k0": 0.4}, "friction": friction,
                  "load": {"kind": "table", "time": [0.0, 100.0], "force": [0.0, 100.0 * rate]},
                  "solver": {"stepper": stepper, "step": 1e-4, "stop_time": end, "output_interval": 0.01}})
    result = run(scene, stepper)
    breakaway = 0.6 / rate
    before = result.time < breakaway - 1e-3
    assert np.all(result.x[before] == 0.0) and np.all(result.v[before] == 0.0)  # exactly held
    np.testing.assert_allclose(result.reaction[before], rate * result.time[before], rtol=1e-12, atol=1e-15)
    assert result.x[-1] > 0.05  # it broke away
    values = (0.6, friction.get("alpha_kinetic", 0.6), friction.get("stribeck_velocity", 1.0))
    times, reference = sliding_reference(1.0, 0.4, values, rate, breakaway, end, result.time)
    got = np.interp(times, result.time, result.x)
    tolerance = 1e-9 if stepper == "exact" else 2e-4  # O(h) with h = 1e-4
    assert np.abs(got - reference).max() <= tolerance, np.abs(got - reference).max()


# ---------------------------------------------------------------- series dashpots


def maxwell_closed_form(m, k0, k, c, force, times):
    """x of m x'' = F - k0 x - k u, u' = x' - (k/c) u from rest (no slip): expm of the linear system."""
    from scipy.linalg import expm

    a = np.array([[0.0, 1.0, 0.0, 0.0], [-k0 / m, 0.0, -k / m, 1.0 / m], [0.0, 1.0, -k / c, 0.0],
                  [0.0, 0.0, 0.0, 0.0]])
    return np.array([(expm(a * t) @ np.array([0.0, 0.0, 0.0, force]))[0] for t in times])


@pytest.mark.parametrize("stepper, order", [("projected", 1), ("implicit", 1), ("symplectic", 1), ("verlet", 2)])
def test_a_mass_on_a_maxwell_branch_without_slip_follows_the_matrix_exponential(stepper, order):
    tables = {"mass": {"m": 1.5}, "spring": {"k0": 0.5},
              "branches": {"k": [2.0], "eta": [1e6], "c": [0.8]}, "load": {"kind": "constant", "value": 1.0},
              "solver": {"stepper": stepper, "step": 1e-3, "stop_time": 8.0, "output_interval": 0.1}}
    scene = make(tables)
    errors = []
    steps = [4e-3, 2e-3, 1e-3]
    for h in steps:
        result = run(scene, stepper, h)
        expected = maxwell_closed_form(1.5, 0.5, 2.0, 0.8, 1.0, result.time)
        errors.append(np.abs(result.x - expected).max())
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert slope > order - 0.2, (errors, slope)
    assert errors[-1] < 5e-3


def series_reference(m, k0, k, eta, c, amplitude, omega, times):
    """One series branch (spring k, dashpot c, slider k eta) on a mass under amplitude cos(omega t): an
    event-driven scipy reference. Free: u' = v - (k/c) u until |u| = eta; slipping (u = +-eta): the slider
    slips while (v - (k/c) u) sign(u) > 0."""
    from scipy.integrate import solve_ivp

    rate = k / c
    state, t, u_held, slipping = np.array([0.0, 0.0, 0.0]), 0.0, 0.0, False
    out_t, out_x = [], []
    end = times[-1]
    while t < end:
        if not slipping:
            def rhs(s, y):
                return [y[1], (amplitude * math.cos(omega * s) - k0 * y[0] - k * y[2]) / m, y[1] - rate * y[2]]

            def reach(s, y):
                return abs(y[2]) - eta
            reach.terminal, reach.direction = True, 1
            events = [reach]
        else:
            def rhs(s, y):
                return [y[1], (amplitude * math.cos(omega * s) - k0 * y[0] - k * u_held) / m, 0.0]

            def release(s, y):
                return (y[1] - rate * u_held) * math.copysign(1.0, u_held)
            release.terminal, release.direction = True, -1
            events = [release]
        grid = times[(times >= t) & (times <= end)]
        solution = solve_ivp(rhs, (t, end), state, method="DOP853", rtol=1e-12, atol=1e-14, t_eval=grid,
                             events=events)
        keep = solution.t < (solution.t_events[0][0] if solution.t_events[0].size else np.inf)
        out_t += list(solution.t[keep])
        out_x += list(solution.y[0][keep])
        if not solution.t_events[0].size:
            break
        t, state = solution.t_events[0][0], solution.y_events[0][0].copy()
        slipping = not slipping
        if slipping:
            u_held = math.copysign(eta, state[2])
            state[2] = u_held
    return np.array(out_t), np.array(out_x)


@pytest.mark.slow  # exact's series dashpots compile for it alone (the quick suite's cold budget, README)
def test_exact_follows_a_mass_on_a_maxwell_branch_to_rounding():
    tables = {"mass": {"m": 1.5}, "spring": {"k0": 0.5},
              "branches": {"k": [2.0], "eta": [1e6], "c": [0.8]}, "load": {"kind": "constant", "value": 1.0},
              "solver": {"stepper": "exact", "step": 1e-3, "stop_time": 8.0, "output_interval": 0.1}}
    result = run(make(tables), "exact", energy=True)  # (with the account: the loop the element's tests compile)
    assert np.abs(result.x - maxwell_closed_form(1.5, 0.5, 2.0, 0.8, 1.0, result.time)).max() < 1e-12
    energy = result.energy
    assert energy["dissipated_damper"][-1] > 0.1  # the branch's dashpot dissipates: its account balances
    assert np.abs(energy["energy_residual"]).max() < 1e-12 * energy["work"].max()


@pytest.mark.parametrize("stepper", STEPPING + ["exact"])
def test_a_series_branch_that_slips_follows_an_event_driven_reference(stepper):
    tables = {"mass": {"m": 1.0}, "spring": {"k0": 0.3}, "branches": {"k": [1.5], "eta": [0.2], "c": [1.2]},
              "load": {"kind": "harmonic", "amplitude": 0.8, "omega": 1.1},
              "solver": {"stepper": stepper, "step": 2e-4, "stop_time": 15.0, "output_interval": 0.05}}
    result = run(make(tables), stepper, energy=stepper == "exact")  # (exact: the loop test_exact.py compiles)
    times, reference = series_reference(1.0, 0.3, 1.5, 0.2, 1.2, 0.8, 1.1, result.time)
    assert times[-1] > 14.9  # the reference went all the way
    got = np.interp(times, result.time, result.x)
    assert np.abs(got - reference).max() < (1e-9 if stepper == "exact" else 3e-3), np.abs(got - reference).max()
    assert np.ptp(reference) > 0.5


@pytest.mark.parametrize("stepper", ["implicit", "verlet"])
def test_series_dashpots_converge_to_the_prandtl_branch_like_one_over_c(stepper):
    tables = {"mass": {"m": 1.0}, "spring": {"k0": 0.2}, "branches": {"k": [1.0, 0.5], "eta": [0.2, 0.5]},
              "load": {"kind": "harmonic", "amplitude": 0.9, "omega": 0.8},
              "solver": {"stepper": stepper, "step": 1e-3, "stop_time": 10.0, "output_interval": 0.05}}
    plain = run(make(tables), stepper)
    gaps = []
    for c in (1e2, 1e3, 1e4):
        series = dict(tables, branches=dict(tables["branches"], c=[c, c]))
        gaps.append(np.abs(run(make(series), stepper).x - plain.x).max())
    ratios = gaps[0] / gaps[1], gaps[1] / gaps[2]
    assert all(7.0 < ratio < 13.0 for ratio in ratios), (gaps, ratios)


def random_series_scene(rng, load_kind):
    """A random scene that exact takes: mass, maybe a spring and a dashpot, maybe plain Coulomb friction, 1-4
    branches with series dashpots, a harmonic, constant or table load."""
    n = int(rng.integers(1, 5))
    tables = {"mass": {"m": float(rng.uniform(0.5, 2.0))},
              "branches": {"k": rng.uniform(0.3, 2.0, n).tolist(), "eta": rng.uniform(0.05, 0.4, n).tolist(),
                           "c": rng.uniform(0.2, 5.0, n).tolist()}}
    if rng.random() < 0.7:
        tables["spring"] = {"k0": float(rng.uniform(0.1, 1.0))}
    if rng.random() < 0.5:
        tables["damper"] = {"c": float(rng.uniform(0.01, 0.3))}
    if rng.random() < 0.6:
        tables["friction"] = {"alpha": float(rng.uniform(0.05, 0.3))}
    if load_kind == "harmonic":
        tables["load"] = {"kind": "harmonic", "amplitude": float(rng.uniform(0.5, 1.5)),
                          "omega": float(rng.uniform(0.3, 2.0))}
    elif load_kind == "constant":
        tables["load"] = {"kind": "constant", "value": float(rng.uniform(0.2, 1.0))}
    else:
        tables["load"] = {"kind": "table", "time": [0.0, 2.0, 4.5, 7.0, 9.0],
                          "force": [0.0, float(rng.uniform(0.5, 1.2)), float(rng.uniform(-1.2, -0.3)), 0.4, 0.4]}
    tables["solver"] = {"stepper": "exact", "step": 1e-3, "stop_time": 10.0, "output_interval": 0.05}
    return make(tables)


@pytest.mark.slow
@pytest.mark.parametrize("seed, load_kind", [(1, "harmonic"), (2, "constant"), (3, "table"), (4, "harmonic"),
                                             (5, "table")])
def test_exact_with_series_dashpots_is_what_the_schemes_converge_to(seed, load_kind):
    """Random scenes with series dashpots (and Coulomb friction): implicit's error against exact halves with h
    (order 1 toward exact's answer, an independent scheme), exact's elongations stay within their ranges, a
    mass at rest over an output interval has not moved, and exact does not depend on the output grid."""
    scene = random_series_scene(np.random.default_rng(seed), load_kind)
    exact = run(scene, "exact", states=True)
    errors = [np.abs(run(scene, "implicit", h).x - exact.x).max() for h in (4e-4, 2e-4, 1e-4)]
    ratios = errors[0] / errors[1], errors[1] / errors[2]
    assert all(1.6 < ratio < 2.5 for ratio in ratios), (errors, ratios)
    assert np.ptp(exact.x) > 1e-2
    assert np.all(np.abs(exact.u) <= scene.branches.yield_displacement)
    held = (exact.v[:-1] == 0.0) & (exact.v[1:] == 0.0)  # at rest at two rows in a row: stuck, x frozen
    assert np.array_equal(exact.x[1:][held], exact.x[:-1][held])
    if scene.friction is not None and load_kind != "harmonic":
        assert held.any()  # the friction held the mass somewhere
    coarse = simulate(scene.with_solver(output_interval=0.1), "exact")
    np.testing.assert_allclose(coarse.x, exact.x[::2], rtol=0, atol=1e-10)


# ---------------------------------------------------------------- independent straightforward code


def stribeck(friction, w):
    alpha, kinetic, speed, _ = friction
    if w == 0.0 or kinetic == alpha:
        return 0.0
    return -math.copysign(1.0, w) * (alpha - kinetic) * (1.0 - math.exp(-abs(w) / speed))


def shrink(friction, inertia, v_free, v_old):
    if friction is None:
        return v_free
    alpha, _, _, belt = friction
    q = inertia * (v_free - belt) - stribeck(friction, v_old - belt)
    return belt + (math.copysign(max(abs(q) - alpha, 0.0), q) / inertia)


def reference_step(stepper, p, t, h, x, v, u):
    """One step of each scheme as its docstring writes it, in plain Python (no kernel of the library)."""
    m, k0, c, k, eta, cs, friction, force = p
    rate = k / cs if cs is not None else np.zeros_like(k)
    c_ = c or 0.0

    def flow(u, dx):
        z = h * rate
        gain = np.where(z > 0, -np.expm1(-z) / np.where(z > 0, z, 1.0), 1.0)
        return np.clip(u * np.exp(-z) + dx * gain, -eta, eta)

    if stepper == "projected":
        a = (force(t) - k0 * x - c_ * v - k @ u) / m
        v1 = shrink(friction, m / h, v + h * a, v)
        return x + h * v, v1, np.clip(u + h * v - h * rate * u, -eta, eta)
    if stepper == "symplectic":
        u1 = flow(u, h * v)
        x1 = x + h * v
        v_free = (v + h * (force(t + h) - k0 * x1 - k @ u1) / m) / (1 + h * c_ / m)
        return x1, shrink(friction, m / h + c_, v_free, v), u1
    if stepper == "verlet":
        half = shrink(friction, 2 * m / h, v + 0.5 * h * (force(t) - k0 * x - c_ * v - k @ u) / m, v)
        u1 = flow(u, h * half)
        x1 = x + h * half
        v_free = (half + 0.5 * h * (force(t + h) - k0 * x1 - k @ u1) / m) / (1 + 0.5 * h * c_ / m)
        return x1, shrink(friction, 2 * m / h + c_, v_free, half), u1
    # implicit: G(w) + A(w/h - v_b) ∋ 0, the root of least slip (brentq on a bracket found by a scan)
    from scipy.optimize import brentq

    scale = 1 + h * rate

    def g0(w):  # w: a number, or an array of them (the scan below)
        springs = sum(k[i] * np.clip((u[i] + w) / scale[i], -eta[i], eta[i]) for i in range(len(k)))
        return (m / h**2 + c_ / h) * w - m * v / h + k0 * (x + w) + springs - force(t + h)

    if friction is None:
        lo, hi = -1.0, 1.0
        while g0(lo) > 0:
            lo *= 2
        while g0(hi) < 0:
            hi *= 2
        w = brentq(g0, lo, hi, xtol=1e-300, rtol=1e-15, maxiter=500)
        return x + w, w / h, np.clip((u + w) / scale, -eta, eta)
    alpha, kinetic, speed, belt = friction
    held = h * belt
    if abs(g0(held)) <= alpha:
        return x + held, belt, np.clip((u + held) / scale, -eta, eta)
    d = -math.copysign(1.0, g0(held))

    def phi(r):
        return d * g0(held + d * r) + kinetic + (alpha - kinetic) * np.exp(-r / (h * speed))

    grid = np.concatenate([[0.0], np.geomspace(1e-12, 10.0, 4000)])
    j = int(np.argmax(phi(grid) >= 0))  # the first point of the scan at or above 0, all points at once ...
    while j > 1 and phi(grid[j - 1]) >= 0:  # ... confirmed one number at a time (an array's exp may round
        j -= 1  # otherwise than a number's)
    while phi(grid[j]) < 0:
        j += 1
    r = brentq(phi, grid[j - 1], grid[j], xtol=1e-300, rtol=1e-15, maxiter=500)
    w = held + d * r
    return x + w, w / h, np.clip((u + w) / scale, -eta, eta)


def random_scene(rng, stepper):
    n = int(rng.integers(1, 4))
    friction = None
    if rng.random() < 0.8:
        alpha = float(rng.uniform(0.05, 0.4))
        friction = {"alpha": alpha, "belt_velocity": float(rng.choice([0.0, rng.uniform(-0.2, 0.2)]))}
        if rng.random() < 0.6:
            friction.update(alpha_kinetic=float(alpha * rng.uniform(0.3, 1.0)),
                            stribeck_velocity=float(rng.uniform(0.05, 0.5)))
    branches = {"k": rng.uniform(0.2, 2.0, n).tolist(), "eta": rng.uniform(0.01, 0.4, n).tolist()}
    if rng.random() < 0.8:
        branches["c"] = rng.uniform(0.1, 20.0, n).tolist()
    tables = {"mass": {"m": float(rng.uniform(0.5, 2.0)), "x0": float(rng.uniform(-0.3, 0.3)),
                       "v0": float(rng.uniform(-0.3, 0.3))},
              "spring": {"k0": float(rng.uniform(0.0, 1.0))}, "branches": branches,
              "load": {"kind": "harmonic", "amplitude": float(rng.uniform(0.2, 1.5)),
                       "omega": float(rng.uniform(0.3, 3.0))},
              "solver": {"stepper": stepper, "step": 1e-2, "stop_time": 3.0, "output_interval": 0.01}}
    if rng.random() < 0.5:
        tables["damper"] = {"c": float(rng.uniform(0.0, 0.5))}
    if friction:
        tables["friction"] = friction
    return make(tables)


@pytest.mark.slow  # each stepper's loop for 9 or 10 sets of effects the quick suite does not all compile: 25 s cold
@pytest.mark.parametrize("stepper", STEPPING)
def test_random_scenes_with_friction_and_series_dashpots_against_straightforward_code(stepper):
    rng = np.random.default_rng(25 + STEPPING.index(stepper))
    for _ in range(12):
        scene = random_scene(rng, stepper)
        result = run(scene, stepper, states=True)
        m = scene.mass.m
        k0 = scene.spring.k0
        c = scene.damper.c if scene.has_dashpot else None
        b = scene.branches
        f = scene.friction
        friction = None if f is None else (f.alpha, f.alpha_kinetic, f.stribeck_velocity or 1.0, f.belt_velocity)
        amplitude, omega = scene.load.amplitude, scene.load.omega
        p = (m, k0, c, b.stiffness, b.yield_displacement, b.damping, friction,
             lambda t: amplitude * math.cos(omega * t))
        x, v, u = scene.mass.x0, scene.mass.v0, b.u0.copy()
        h = scene.solver.step
        for step in range(len(result.time) - 1):
            x, v, u = reference_step(stepper, p, step * h, h, x, v, u)
            scale = 1.0 + abs(x)
            assert abs(result.x[step + 1] - x) <= 1e-9 * scale, (step, result.x[step + 1], x)
            assert abs(result.v[step + 1] - v) <= 1e-9 * (1.0 + abs(v)), (step, result.v[step + 1], v)
            np.testing.assert_allclose(result.u[step + 1], u, rtol=0, atol=1e-9)
            if friction is not None and v == friction[3]:
                assert result.v[step + 1] == v  # sticks to the bit where the reference sticks
            x, v, u = result.x[step + 1], result.v[step + 1], result.u[step + 1].copy()  # no drift of rounding


def test_the_implicit_step_takes_the_root_of_least_slip_when_stribeck_is_steep():
    """A stiff branch that slips early makes G(w) + A(w / h) rise above 0, fall below it while the Stribeck
    drop goes on, and rise again: three roots. The rule takes the first."""
    from prandtl_fmu.kernels.increment import residual, solve_held_increment

    m, h = 1e-4, 1e-3
    linear = m / h**2
    k, eta, u = np.array([1e5]), np.array([1e-6]), np.zeros(1)
    friction = (1.0, 0.2, 1e-2, 0.0)  # the drop 80 N s/m against m/h = 0.1
    offset = -1.01  # F = 1.01 > alpha from rest: it breaks away

    def phi(r):
        g = residual(r, 0.0, linear, offset, None, None, k, eta, None, u, h, 1.0)[0]
        return g + 0.2 + 0.8 * math.exp(-r / (h * 1e-2))  # G(w) + A(w / h), sliding forwards

    grid = np.linspace(0.0, 0.02, 400001)
    signs = np.sign([phi(r) for r in grid])
    assert len(np.flatnonzero(np.diff(signs))) == 3  # the rule matters: three roots
    w, resisted, stuck = solve_held_increment(0.0, linear, offset, None, None, k, eta, None, u, h, friction)
    assert not stuck and 0.0 < w < 1e-6
    assert abs(phi(w)) <= 1e-12  # a root, to rounding
    assert all(phi(r) < 0.0 for r in np.linspace(0.0, w, 10001)[:-1])  # no root of less slip
    assert resisted == pytest.approx(0.2 + 0.8 * math.exp(-w / (h * 1e-2)), rel=1e-12)


def test_a_steep_stribeck_drop_for_the_step_warns_in_one_line():
    tables = {"mass": {"m": 0.01}, "friction": {"alpha": 1.0, "alpha_kinetic": 0.2, "stribeck_velocity": 4e-4},
              "spring": {"k0": 5.0}, "load": {"kind": "constant", "value": 1.3},
              "solver": {"stepper": "implicit", "step": 1e-3, "stop_time": 0.1, "output_interval": 0.01}}
    scene = make(tables)
    with pytest.warns(StabilityWarning, match=r"Stribeck drop .* exceeds m/h \+ c .* least slip\); use h < "):
        simulate(scene)
    with warnings.catch_warnings():
        warnings.simplefilter("error", StabilityWarning)
        simulate(scene.with_solver(step=1e-6, stop_time=1e-3, output_interval=1e-4))  # resolved: no warning


# ---------------------------------------------------------------- energy


@pytest.mark.parametrize("stepper", STEPPING)
def test_dissipations_never_decrease_and_the_balance_keeps_its_sign(stepper):
    tables = {"mass": {"m": 1.0, "x0": 0.3}, "spring": {"k0": 0.5}, "damper": {"c": 0.05},
              "friction": {"alpha": 0.2, "alpha_kinetic": 0.12, "stribeck_velocity": 0.1, "belt_velocity": 0.07},
              "branches": {"k": [1.0, 0.6], "eta": [0.1, 0.3], "c": [0.5, 4.0]},
              "load": {"kind": "harmonic", "amplitude": 0.7, "omega": 0.9},
              "solver": {"stepper": stepper, "step": 1e-3, "stop_time": 30.0, "output_interval": 1e-3}}
    result = run(make(tables), stepper, energy=True)
    energy = result.energy
    for column in ("dissipated_sliders", "dissipated_damper", "dissipated_friction"):
        assert np.all(np.diff(energy[column]) >= 0.0), column
        assert energy[column][-1] > 1e-3, column  # each effect did dissipate
    scale = energy["work"].max() + energy["dissipated_friction"][-1]
    residual = energy["energy_residual"]
    if stepper == "implicit":
        assert residual.min() >= -1e-12 * scale  # never creates energy
    assert np.abs(residual).max() <= 0.05 * scale  # within the scheme's own O(h)


# ---------------------------------------------------------------- the scene and its refusals


@pytest.mark.parametrize("tables, culprit", [
    ({"friction": {"alpha": 0.5}, "mass": None}, "[friction]: friction of the mass on the ground needs [mass]"),
    ({"friction": {"alpha": 0.0}}, "[friction] alpha: must be > 0"),
    ({"friction": {"alpha": 0.5, "alpha_kinetic": 0.6, "stribeck_velocity": 1.0}}, "[friction] alpha_kinetic: must be <="),
    ({"friction": {"alpha": 0.5, "alpha_kinetic": 0.3}}, "[friction] stribeck_velocity: missing"),
    ({"friction": {"alpha": 0.5, "mu": 0.3}}, "[friction] mu: unknown key"),
    ({"branches": {"k": [1.0], "eta": [0.1], "c": [0.0]}}, "[branches] c[1]: must be > 0"),
    ({"branches": {"k": [1.0, 2.0], "eta": [0.1, 0.2], "c": [1.0]}}, "[branches] c: must have 2 values"),
    ({"branches": {"count": 3, "k_total": 1.0, "eta_range": [0.0, 1.0], "c": [1.0, 1.0, 1.0]}},
     "[branches] c: give one value for every branch with count = n"),
    ({"branches": {"continuum": True, "k_total": 1.0, "eta_range": [0.0, 1.0], "c": 1.0}},
     "[branches] c: series dashpots are not available with continuum = true"),
])
def test_the_scene_refuses_in_one_line_naming_the_key(tables, culprit):
    base = {"mass": {"m": 1.0}, "solver": {"step": 1e-3, "stop_time": 1.0, "output_interval": 0.01}}
    base.update(tables)
    with pytest.raises(SceneError) as caught:
        parse_scene(scene_text({k: v for k, v in base.items() if v is not None}), "bad.toml")
    assert culprit in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.parametrize("friction, branches, what", [
    ({"alpha": 0.5, "alpha_kinetic": 0.3, "stribeck_velocity": 0.1}, None, "Stribeck"),
    ({"alpha": 0.5, "belt_velocity": 0.1}, None, "belt"),
])
def test_exact_refuses_what_is_not_linear_between_its_events(friction, branches, what, tmp_path):
    tables = {"mass": {"m": 1.0}, "friction": friction, "branches": branches,
              "solver": {"stepper": "exact", "step": 1e-3, "stop_time": 1.0, "output_interval": 0.01}}
    path = tmp_path / "scene.toml"
    path.write_text(scene_text({k: v for k, v in tables.items() if v is not None}))
    run_ = subprocess.run([sys.executable, "-m", "prandtl_fmu", "run", str(path)], capture_output=True, text=True)
    assert run_.returncode == 2 and run_.stdout == ""
    assert len(run_.stderr.strip().splitlines()) == 1 and what in run_.stderr and "exact" in run_.stderr


def test_the_csv_has_dissipated_friction_only_with_friction(tmp_path):
    with_friction = run(make(COULOMB), "symplectic", energy=True)
    assert list(with_friction.energy)[-2:] == ["dissipated_friction", "energy_residual"]
    without = run(make(dict(COULOMB, friction=None)), "symplectic", energy=True)
    assert "dissipated_friction" not in without.energy
    # the friction dissipates alpha times the path: 0.3 (1.7 + 1.3 + 0.9 + 0.5 + 0.1) = 1.35 J, all of the
    # spring's energy 3 (0.95^2 - 0.05^2) / 2
    assert with_friction.energy["dissipated_friction"][-1] == pytest.approx(1.35, rel=2e-3)


def test_coefficients_change_in_a_running_element_with_their_rules():
    tables = {"mass": {"m": 1.0}, "friction": {"alpha": 0.5, "alpha_kinetic": 0.3, "stribeck_velocity": 0.1},
              "branches": {"k": [1.0, 2.0], "eta": [0.1, 0.2], "c": [1.0, 3.0]}}
    element = Element(make(tables))
    assert {"alpha", "alpha_kinetic", "stribeck_velocity", "belt_velocity", "c_branch[1]", "c_branch[2]"} \
        <= set(element.coefficients())
    element.set_coefficients(alpha=0.7, **{"c_branch[2]": 5.0})
    assert element.coefficients()["alpha"] == 0.7 and element.coefficients()["c_branch[2]"] == 5.0
    assert element.model[7][0] == 0.7 and element.model[6][1] == 5.0  # the kernels see them
    for values, culprit in (({"alpha_kinetic": 0.8}, "alpha_kinetic must be <= alpha"),
                            ({"c_branch[1]": -1.0}, "c_branch[1]: must be > 0"),
                            ({"c_branch[3]": 1.0}, "c_branch[3]: not a coefficient of this scene")):
        with pytest.raises(ValueError, match=re_escape(culprit)):
            element.set_coefficients(**values)
    assert element.coefficients()["alpha"] == 0.7  # unchanged by the refusals


def re_escape(text):
    import re

    return re.escape(text)


def test_a_plain_coulomb_scene_has_no_stribeck_coefficients_and_alpha_kinetic_follows_alpha():
    element = Element(make(COULOMB))
    assert "alpha_kinetic" not in element.coefficients()
    element.set_coefficients(alpha=0.1)
    assert element.scene.friction.alpha_kinetic == 0.1


# ---------------------------------------------------------------- the connector


def test_the_connector_takes_series_branches_and_refuses_friction():
    tables = {"spring": {"k0": 0.5}, "branches": {"k": [2.0], "eta": [0.3], "c": [1.0]}, "fmu": {"causality": "displacement"},
              "solver": {"step": 1e-3, "stop_time": 1.0, "output_interval": 0.01}}
    scene = make(tables)
    with pytest.raises(ValueError, match="give the times"):
        displacement_response(scene, [0.1])
    # x ramps to 0.1 over the first 0.01 s (linear between samples), then is held: the branch (no slip:
    # u < eta) follows u' = v - lambda u, lambda = k / c = 2, in closed form
    times = np.linspace(0.0, 3.0, 301)
    xs = np.where(times > 0, 0.1, 0.0)
    forces = displacement_response(scene, xs, time=times)
    ramp = 0.1 / 0.01 / 2.0 * (1.0 - math.exp(-2.0 * 0.01))
    expected = 0.5 * xs + 2.0 * ramp * np.exp(-2.0 * (times - 0.01))
    np.testing.assert_allclose(forces[1:], expected[1:], rtol=1e-12)
    connector = Connector(scene)
    connector.move_to(0.1, 0.0, 0.0)
    connector.move_to(0.1, 0.0, 1.0)
    assert connector.force == pytest.approx(0.05 + 0.2 * math.exp(-2.0), rel=1e-12)
    assert connector.energy()["dissipated_damper"] == pytest.approx(0.5 * 2.0 * 0.01 * (1 - math.exp(-4.0)),
                                                                    rel=1e-9)
    with pytest.raises(SceneError, match=r"\[friction\]: .*needs \[mass\]"):
        make({"friction": {"alpha": 0.5}, "fmu": {"causality": "displacement"},
              "solver": {"step": 1e-3, "stop_time": 1.0, "output_interval": 0.01}})


def test_a_sweep_varies_the_friction_and_a_series_dashpot():
    from prandtl_fmu.summary import summarize_many

    tables = {"mass": {"m": 1.0}, "friction": {"alpha": 0.2}, "branches": {"k": [1.0, 0.5], "eta": [0.1, 0.3],
                                                                           "c": [1.0, 2.0]},
              "load": {"kind": "harmonic", "amplitude": 0.6, "omega": 1.0},
              "solver": {"stepper": "verlet", "step": 1e-3, "stop_time": 5.0, "output_interval": 0.1}}
    scenes = [make(dict(tables, friction={"alpha": alpha}, branches=dict(tables["branches"], c=[1.0, c])))
              for alpha, c in ((0.2, 2.0), (0.3, 2.0), (0.2, 7.0))]
    outcomes = summarize_many([(scene, "verlet") for scene in scenes], ["final_x", "dissipated_friction"])
    for scene, outcome in zip(scenes, outcomes):
        alone = simulate(scene, energy=True)
        assert outcome.values["final_x"] == alone.x[-1]  # bit for bit with the run alone
        assert outcome.values["dissipated_friction"] == alone.energy["dissipated_friction"][-1]
    assert len({o.values["final_x"] for o in outcomes}) == 3
