"""The exact stepper against a high-order ODE solver, and every other stepper's order against it."""
import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from prandtl_fmu import STEPPERS, load_scene, simulate
from prandtl_fmu.steppers import get_stepper

from tests.conftest import SCENES, make_scene

EVENT_FREE = {
    # undamped resonance: K = m omega^2, c = 0 (the particular solution grows like t sin t)
    "resonance": dict(mass={"m": 2.0, "x0": 0.1, "v0": 0.0}, spring={"k0": 0.5}, cubic=None, damper=None,
                      branches=None, load={"kind": "harmonic", "amplitude": 1.0, "omega": 0.5, "offset": 0.2}),
    # critical damping: c^2 = 4 m K
    "critical": dict(mass={"m": 1.0, "x0": -0.3, "v0": 0.7}, spring={"k0": 1.0}, cubic=None, damper={"c": 2.0},
                     branches=None, load={"kind": "harmonic", "amplitude": 0.5, "omega": 1.3, "offset": 0.3}),
    # K = 0: no spring, every branch sliding from the start (u0 = eta, v0 > 0, load pushing on)
    "no-stiffness": dict(mass={"m": 1.0, "x0": 0.0, "v0": 0.5}, spring=None, cubic=None, damper={"c": 0.1},
                         branches={"k": [1.0, 2.0], "eta": [0.1, 0.2], "u0": [0.1, 0.2]},
                         load={"kind": "constant", "value": 0.9}),
    # sticking branches (thresholds out of reach) under a table load with kinks
    "table": dict(mass={"m": 1.5, "x0": 0.0, "v0": 0.0}, spring={"k0": 0.3}, cubic=None, damper={"c": 0.05},
                  branches={"k": [1.0, 0.5], "eta": [50.0, 80.0], "u0": [0.0, 0.0]},
                  load={"kind": "table", "time": [0.0, 2.0, 3.0, 6.0], "force": [0.0, 1.0, -0.5, 0.25]}),
}


def dop853(scene, stop, rows):
    """The same linear ODE by DOP853 at rtol 1e-13 (no event may happen: checked by the caller)."""
    m, c = scene.mass.m, scene.damper.c if scene.damper else 0.0
    k0 = scene.spring.k0 if scene.spring else 0.0
    branches = scene.branches
    sliding = np.zeros(0, bool) if branches is None else (np.abs(branches.u0) == branches.yield_displacement) & (
        branches.u0 * scene.mass.v0 > 0)
    k = np.zeros(0) if branches is None else branches.stiffness
    u0 = np.zeros(0) if branches is None else branches.u0
    from prandtl_fmu.loads import force_at

    load = scene.load.compile()

    def rhs(t, y):
        x, v = y
        u = np.where(sliding, u0, u0 + x - scene.mass.x0)
        return [v, (force_at(load, t) - k0 * x - c * v - k @ u) / m]

    times = np.linspace(0, stop, rows)
    breaks = getattr(scene.load, "time", None)
    t_eval, y = times, [scene.mass.x0, scene.mass.v0]
    pieces = [0.0] + ([b for b in breaks if 0 < b < stop] if breaks is not None else []) + [stop]
    out = np.empty((rows, 2))
    for lo, hi in zip(pieces[:-1], pieces[1:]):  # integrate piece by piece across the table's kinks
        mask = (t_eval >= lo) & (t_eval <= hi)
        sol = solve_ivp(rhs, (lo, hi), y, method="DOP853", rtol=1e-13, atol=1e-15, t_eval=t_eval[mask])
        out[mask] = sol.y.T
        y = solve_ivp(rhs, (lo, hi), y, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
    return times, out


@pytest.mark.parametrize("case", list(EVENT_FREE))
def test_exact_agrees_with_dop853_without_events(case):
    stop = 10.0
    scene = make_scene(**EVENT_FREE[case], solver={"stepper": "exact", "step": 0.05, "stop_time": stop,
                                                   "output_interval": 0.05})
    result = simulate(scene, states=True)
    times, reference = dop853(scene, stop, len(result.time))
    np.testing.assert_allclose(result.time, times, atol=1e-12)
    scale = np.abs(reference).max(axis=0)
    assert np.abs(result.x - reference[:, 0]).max() <= 1e-10 * scale[0]
    assert np.abs(result.v - reference[:, 1]).max() <= 1e-10 * scale[1]
    if scene.branches is not None:
        assert np.all(np.abs(result.u) <= scene.branches.yield_displacement)


def test_exact_agrees_with_dop853_on_the_papers_first_stretch():
    """Before the first branch slips (x < min eta = 0.11) the paper's element is a linear oscillator."""
    scene = load_scene(SCENES / "paper-section-8.toml").with_solver(
        stepper="exact", stop_time=0.5, output_interval=0.01)
    result = simulate(scene)
    assert result.x.max() < 0.11
    exact_linear = 0.45 / (1 - 0.25) * (np.cos(0.5 * result.time) - np.cos(result.time))
    np.testing.assert_allclose(result.x, exact_linear, rtol=0, atol=1e-14)


@pytest.fixture(scope="module")
def paper_exact():
    scene = load_scene(SCENES / "paper-section-8.toml").with_solver(stop_time=12.0, output_interval=0.04)
    return scene, simulate(scene, "exact", states=True)


def test_exact_is_consistent_with_the_extrapolated_projected_scheme(paper_exact):
    """`projected` extrapolated to h -> 0 (Richardson, h = 2e-6 and 1e-6) lands on `exact`."""
    scene, exact = paper_exact
    runs = [simulate(scene.with_solver(step=h), "projected").x for h in (2e-6, 1e-6)]
    extrapolated = 2 * runs[1] - runs[0]
    assert np.abs(extrapolated - exact.x).max() < 1e-9
    assert np.abs(runs[1] - exact.x).max() > 1e-7  # the raw runs are not that close: the test can fail


@pytest.mark.parametrize("stepper", [name for name in STEPPERS if name != "exact"])
def test_measured_order_against_exact(stepper, paper_exact):
    scene, exact = paper_exact
    hs = np.array([0.01, 0.005, 0.0025, 0.00125, 0.000625])
    # (with the energy account, as the element's and the FMUs' tests run these loops: one compiled loop each)
    errors = [np.abs(simulate(scene.with_solver(step=h), stepper, energy=True).x - exact.x).max() for h in hs]
    order = np.polyfit(np.log(hs), np.log(errors), 1)[0]
    declared = get_stepper(stepper).ORDER
    assert abs(order - declared) < 0.05 * declared, (order, errors)


def test_exact_handles_every_branch_event_of_the_paper_scene(paper_exact):
    scene, exact = paper_exact
    eta = scene.branches.yield_displacement
    assert np.all(np.abs(exact.u) <= eta)
    assert np.any(np.abs(exact.u[:, -1]) == eta[-1])  # even the largest threshold is reached
    # reaction = k . u (k0 = 0): the branch force computed from the elongations
    np.testing.assert_allclose(exact.reaction, exact.u @ scene.branches.stiffness, atol=1e-15)


def test_exact_s_event_search_is_compiled_once_not_once_more_per_constant_argument(paper_exact):
    """The search reads x and v of y as int64 components, not as the constants 0 and 1 numba compiled _refine
    once more for each (a literal is a signature of its own): the cache of this run holds no kernel signature
    with a literal (tests/compiled_copies.py) once the paper scene's events were found (levels up and down, and
    reversals: every branch's threshold is reached, above)."""
    from tests.compiled_copies import literal_signatures

    assert np.any(np.diff(np.sign(paper_exact[1].v)) != 0)
    assert literal_signatures("exact._refine", "exact._row_times") == []


def test_exact_refuses_what_it_cannot_do():
    with pytest.raises(ValueError, match="no \\[cubic\\]"):
        get_stepper("exact").loop_for(make_scene())
    assert math.isinf(get_stepper("exact").ORDER)


def test_exact_keeps_an_energy_account():
    """exact books its energies (issue 31 item 11; tests/steppers/test_exact_bounded_work.py checks them): never NaN."""
    result = simulate(make_scene(cubic=None, solver={"stepper": "exact", "step": 0.1, "stop_time": 2.0,
                                                     "output_interval": 0.1}), energy=True)
    table = np.column_stack(list(result.energy.values()))
    assert np.all(np.isfinite(table)) and result.energy["work"][-1] != 0.0


@pytest.mark.parametrize("series", [False, True])
def test_the_element_s_energy_account_is_booked_by_exact_and_survives_a_state_round_trip(series):
    """exact books work and dissipation like every stepper (no NaN any more): an element's account continues
    through a switch to exact and back, survives plain JSON (get_state / set_state), and a reset zeroes it."""
    from prandtl_fmu.element import Element

    branches = {"k": [0.5, 0.3], "eta": [0.1, 0.3], "c": [0.4, 2.0]} if series else None
    element = Element(make_scene(cubic=None, **({"branches": branches} if branches else {})), stepper="implicit")
    element.advance(0.5, 0.8)
    work = element.energy_of("work")
    assert math.isfinite(work) and work != 0.0
    element.set_stepper("exact")
    element.advance(0.5, 0.8)
    for name in ("work", "dissipated_sliders", "dissipated_damper", "energy_residual"):
        assert math.isfinite(element.energy_of(name)), name
    assert element.energy_of("work") > work
    element.set_stepper("implicit")
    element.advance(0.5, 0.8)
    state = json.loads(json.dumps(element.get_state(), allow_nan=False))
    other = Element(element.scene)
    other.set_state(state)
    assert other.energy_of("work") == element.energy_of("work") and other.x == element.x
    element.reset()
    assert element.energy_of("work") == 0.0 and element.energy_of("energy_residual") == 0.0


# Run in a child process with a time limit: a regression of the event loop would spin for ever in compiled code
# (SIGINT does not reach it), and a test must fail, not hang the suite.
_REST_FUZZ = r'''
import sys
import numpy as np
from prandtl_fmu import parse_scene, simulate
from tests.conftest import scene_text

rng = np.random.default_rng(int(sys.argv[1]))
cases = 0
for case in range(int(sys.argv[2])):
    n = int(rng.integers(0, 4))
    k = rng.uniform(0.2, 2.0, n)
    eta = rng.uniform(0.05, 0.5, n)
    u0 = rng.uniform(-1, 1, n) * eta * (rng.random(n) < 0.7)
    u0 = np.where(rng.random(n) < 0.3, np.sign(rng.standard_normal(n)) * eta, u0)  # some on their threshold
    k0 = float(rng.choice([0.0, rng.uniform(0.1, 2.0)]))
    x0 = float(rng.choice([0.0, rng.uniform(-1, 1)]))
    rest = k0 * x0 + float(k @ u0)  # the force of equilibrium at the initial state
    kind = rng.choice(["equilibrium", "none", "harmonic", "table"])
    load = {"equilibrium": {"kind": "constant", "value": rest},
            "none": {"kind": "constant", "value": 0.0},
            "harmonic": {"kind": "harmonic", "amplitude": float(rng.uniform(0.1, 1)), "omega": 1.0,
                         "offset": rest, "phase": float(rng.choice([0.0, np.pi / 2]))},
            "table": {"kind": "table", "time": [0.0, 0.3, 0.7, 2.0], "force": [rest, rest, rest + 0.4, rest]}}[kind]
    if kind == "harmonic":  # a harmonic load starting at a peak or a zero of its rate
        load.pop("phase")
    zeros = int(rng.integers(1, 3))  # branches of elastic range 0: they never carry a force
    tables = {"name": "rest", "mass": {"m": float(rng.uniform(0.5, 2)), "x0": x0, "v0": 0.0},
              "spring": {"k0": k0} if k0 else None,
              "damper": {"c": float(rng.choice([0.0, 0.3]))},
              "load": load,
              "solver": {"stepper": "exact", "step": 0.1, "stop_time": 2.0, "output_interval": 0.1}}
    with_zeros = dict(tables, branches={"k": list(k) + [1.0] * zeros, "eta": list(eta) + [0.0] * zeros,
                                        "u0": list(u0) + [0.0] * zeros})
    without = dict(tables, branches={"k": list(k), "eta": list(eta), "u0": list(u0)} if n else None)
    clean = lambda t: {key: value for key, value in t.items() if value is not None}
    a = simulate(parse_scene(scene_text(clean(with_zeros)), "a.toml"))
    b = simulate(parse_scene(scene_text(clean(without)), "b.toml"))
    scale = 1.0 + np.abs(b.x).max()
    assert np.all(np.isfinite(a.x)), (case, with_zeros)
    assert np.abs(a.x - b.x).max() <= 1e-12 * scale, (case, np.abs(a.x - b.x).max(), with_zeros)
    assert np.abs(a.v - b.v).max() <= 1e-12 * scale, (case, with_zeros)
    if kind in ("equilibrium",) or (kind == "none" and rest == 0.0):
        assert np.all(a.x == x0) and np.all(a.v == 0.0), (case, "an equilibrium moved", with_zeros)
    cases += 1
print("cases", cases)
'''


@pytest.mark.parametrize("seed", [1, 2])
def test_exact_at_rest_with_zero_elastic_ranges_never_spins_and_zero_ranges_carry_nothing(seed):
    """Issue 23, item 7: at rest in equilibrium with a branch of elastic range 0, ``exact`` spun for ever (a
    level at distance 0 fired an event at tau = 5e-324 again and again). Random rest states, equilibria and
    loads starting at rest: every run ends (within the child's time limit), a branch of range 0 changes nothing
    (the same scene without it, to 1e-12), and an equilibrium stays exactly where it is."""
    import subprocess
    import sys

    from tests.conftest import ROOT

    done = subprocess.run([sys.executable, "-c", _REST_FUZZ, str(seed), "25"], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "cases 25" in done.stdout


def test_the_element_at_rest_with_a_zero_elastic_range_is_a_fixed_point_of_exact():
    """The issue's scene, in process: 10 exact steps of the element at rest in equilibrium."""
    scene = make_scene(mass={"m": 1.0, "x0": 0.5, "v0": 0.0}, spring={"k0": 1.0}, cubic=None, damper=None,
                       branches={"k": [1.0], "eta": [0.0]}, load={"kind": "constant", "value": 0.5},
                       solver={"stepper": "exact", "step": 0.1, "stop_time": 1.0, "output_interval": 0.1})
    result = simulate(scene)
    assert np.all(result.x == 0.5) and np.all(result.v == 0.0) and np.all(result.reaction == 0.5)


def test_a_start_at_rest_to_rounding_under_a_large_force_finds_its_level_in_one_long_step():
    """v0 = 5e-93 against a net force of -3.9 N: the first zero of v is ~1e-93 s after the start, the next one
    within rounding of half a period later (now v0 = 5e-43: the scene reader refuses magnitudes below 1e-50), where the sign test alone found no zero; the branch's level was
    then missed (x = -1.4612 in one step of 1.262 s, -1.5616 in 1262 steps). Found by the property test of
    the output interval."""
    scene = make_scene(mass={"m": 0.7745983084962722, "x0": 0.0, "v0": 5.263085279548564e-43}, spring=None,
                       cubic=None, damper=None,
                       branches={"k": [2.5378744241832147, 2.809112197623408],
                                 "eta": [0.99999, 0.9385506565966586],
                                 "u0": [0.6538038510445731, 0.10032773834488834]},
                       load={"kind": "constant", "value": -1.9951778712575408},
                       solver={"stepper": "exact", "step": 1.262, "stop_time": 1.262, "output_interval": 1.262})
    one = simulate(scene)
    fine = simulate(scene.with_solver(step=1e-3, output_interval=1e-3))
    assert abs(one.x[-1] - fine.x[-1]) <= 1e-12 and abs(one.v[-1] - fine.v[-1]) <= 1e-12
