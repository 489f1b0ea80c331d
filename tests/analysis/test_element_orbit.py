"""The orbit of an element with friction on its mass whose forces are not linear between events (a cubic
spring, Stribeck's drop) by Taylor series (``frequency/element_orbit.py``), and the forced response that shooting
solves for on it: the exact stepper's orbit where both apply, an independent integration written here (scipy's
DOP853 with its event location, phase by phase) on random scenes, and the Duffing oscillator with friction's
curve with both folds, whose unstable points leave their orbit."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main

from tests.analysis.test_describe_cli import read_csv, write
from prandtl_fmu.frequency import element_orbit
from tests.analysis.test_harmonic_balance import element

DUFFING_FRICTION = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "cubic": {"k3": 0.5}, "damper": {"c": 0.02},
                    "friction": {"alpha": 0.05}}
STRIBECK = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.05},
            "friction": {"alpha": 0.1, "alpha_kinetic": 0.06, "stribeck_velocity": 0.05}}


def reference(m, k0, c, k3, alpha, alpha_k, vs, bk, eta, F, omega, x, v, u, t_end, history=None, z=()):
    """The motion written straightforwardly: each slide an ODE for scipy's DOP853 (rtol 1e-12, steps of at most
    T / 50) stopped at its events (v = 0; a sticking branch's u at +-eta), each stick until |N(t)| > alpha,
    the mass at rest sticking where |N| <= alpha, else sliding the way N pushes; ``history`` (weights, rates,
    on_v): its z_j' = -rate_j z_j + y integrated along. Returns (x, v, u) at t_end, and z with a history."""
    from scipy.integrate import solve_ivp

    nb = len(bk)
    u = np.clip(np.array(u, float), -eta, eta)
    weights, rates, on_v = (np.zeros(0), np.zeros(0), False) if history is None else history
    z = np.array(z, float)
    bmode = np.zeros(nb, int)
    t = 0.0
    largest = 0.02 * 2.0 * math.pi / omega

    def branch_force(x, x0, u0):
        return sum(bk[i] * (u0[i] + x - x0 if bmode[i] == 0 else bmode[i] * eta[i]) for i in range(nb))

    def done():
        return (x, v, u) if history is None else (x, v, u, z)

    while t < t_end:
        if v == 0.0:
            bmode[:] = 0
            held = F * math.cos(omega * t) - k0 * x - k3 * x**3 - float(np.dot(bk, u)) - float(np.dot(weights, z))
            sigma = 1 if held > alpha else -1 if held < -alpha else 0
            if sigma == 0:
                constant = held - F * math.cos(omega * t) + float(np.dot(weights, z))
                y_held = 0.0 if on_v else x
                # (y[0] a clock: scipy needs a state, and a history may have none)
                ends = [lambda s, y, side=side: alpha + 1e-12 - side * (F * math.cos(omega * s) + constant
                                                                        - float(np.dot(weights, y[1:])))
                        for side in (1, -1)]
                for end in ends:
                    end.terminal, end.direction = True, -1
                solution = solve_ivp(lambda s, y: np.concatenate(([1.0], y_held - rates * y[1:])), (t, t_end),
                                     np.concatenate(([t], z)), events=ends, rtol=1e-12, atol=1e-15,
                                     method="DOP853", max_step=0.05 * largest)  # a short escape is not missed
                z = solution.y[1:, -1].copy()
                if solution.status != 1:
                    return done()
                sigma = 1 if len(solution.t_events[0]) else -1
                t = float(solution.t_events[0 if sigma == 1 else 1][0])
        else:
            sigma = 1 if v > 0 else -1
        for i in range(nb):
            if bmode[i] == 0 and sigma * u[i] >= eta[i]:
                bmode[i], u[i] = sigma, sigma * eta[i]
        x0, u0 = x, u.copy()
        while True:
            elastic = [i for i in range(nb) if bmode[i] == 0]

            def rhs(s, y):
                slide = alpha if vs == 0.0 else alpha_k + (alpha - alpha_k) * math.exp(min(-sigma * y[1] / vs, 0.0))
                force = F * math.cos(omega * s) - k0 * y[0] - k3 * y[0] ** 3 - c * y[1] - sigma * slide
                force -= float(np.dot(weights, y[2:]))
                rates_of_z = (y[1] if on_v else y[0]) - rates * y[2:]
                return np.concatenate(([y[1], (force - branch_force(y[0], x0, u0)) / m], rates_of_z))

            events = [lambda s, y: sigma * y[1] + 1e-13]
            events += [lambda s, y, i=i: eta[i] - sigma * (u0[i] + y[0] - x0) for i in elastic]
            for event in events:
                event.terminal, event.direction = True, -1
            solution = solve_ivp(rhs, (t, t_end), np.concatenate(([x, v], z)), events=events, rtol=1e-12,
                                 atol=1e-15, method="DOP853", max_step=largest)
            x, v, t = float(solution.y[0, -1]), float(solution.y[1, -1]), float(solution.t[-1])
            z = solution.y[2:, -1].copy()
            for i in elastic:
                u[i] = min(max(u0[i] + x - x0, -eta[i]), eta[i])
            if solution.status != 1:
                return done()
            which = next(j for j, times in enumerate(solution.t_events) if len(times))
            if which == 0:
                v = 0.0
                break
            i = elastic[which - 1]
            bmode[i], u[i] = sigma, sigma * eta[i]
            for j in range(nb):  # the branches at their level at the same moment slide too
                if bmode[j] == 0 and eta[j] - sigma * u[j] <= 1e-11 * max(1.0, abs(x)):
                    bmode[j], u[j] = sigma, sigma * eta[j]
            x0, u0 = x, u.copy()
    return done()


def _random_scene(rng, smooth=True):
    m, k0, c = rng.uniform(0.5, 2.0), rng.uniform(0.5, 3.0), rng.uniform(0.0, 0.2)
    k3 = rng.uniform(0.1, 3.0) if smooth and rng.random() < 0.6 else 0.0
    alpha = rng.uniform(0.1, 0.5)
    stribeck = smooth and (k3 == 0.0 or rng.random() < 0.5)
    alpha_k, vs = (alpha * rng.uniform(0.3, 0.9), rng.uniform(0.05, 0.5)) if stribeck else (alpha, 0.0)
    nb = int(rng.integers(0, 3))
    bk, eta = rng.uniform(0.3, 2.0, nb), rng.uniform(0.05, 0.3, nb)
    return m, k0, c, k3, alpha, alpha_k, vs, bk, eta, rng.uniform(0.3, 2.0), rng.uniform(0.5, 3.0)


NO_HISTORY = (np.zeros(0), np.zeros(0), False)


def _taylor(parameters, x, v, u, h, steps, history=NO_HISTORY, z=()):
    from prandtl_fmu.frequency.element_orbit import OK, run

    m, k0, c, k3, alpha, alpha_k, vs, bk, eta, F, omega = parameters
    state, u, out, z = np.array([x, v]), np.array(u, float).copy(), np.empty(steps), np.array(z, float)
    status, taken = run(m, k0, c, k3, alpha, alpha_k, vs, bk, eta, np.zeros(0), *history, F, omega, state, u, z, h,
                        steps, out, 0.0)
    assert status == OK and taken == steps
    return (state, u, out) if history is NO_HISTORY and not len(z) else (state, u, out, z)


def test_the_taylor_orbit_is_the_exact_stepper_s_where_both_apply(tmp_path):
    """Coulomb friction, a spring, a dashpot and branches (linear between events): the Taylor orbit over two
    periods, sticks, slips and the branches' events included, is the exact stepper's (through shooting's own
    map) to 1e-11 of the motion, at every sample."""
    from prandtl_fmu.frequency.shooting import ElementShooting, prepared

    tables = {"mass": {"m": 1.0}, "spring": {"k0": 2.0}, "damper": {"c": 0.05}, "friction": {"alpha": 0.3},
              "branches": {"k": [1.0, 0.5], "alpha": [0.1, 0.2]}}
    scene = prepared(element(tables))
    eta = np.array(scene.branches.yield_displacement, float)
    M = 128
    for F, omega in ((1.0, 1.3), (0.5, 0.7), (2.0, 3.0)):
        exact = ElementShooting(scene, F, None, M, 7, 1.0)
        for start in ([0.0, 0.0, 0.0, 0.0], [0.3, -0.2, 0.05, -0.1], [0.8, 0.5, 0.1, 0.4]):
            end, xs = exact.run(np.array(start), omega, 4)
            parameters = (1.0, 2.0, 0.05, 0.0, 0.3, 0.3, 0.0, np.array([1.0, 0.5]), eta, F, omega)
            state, u, out = _taylor(parameters, start[0], start[1], np.clip(start[2:], -eta, eta),
                                    2 * math.pi / omega / M, 2 * M)
            size = float(np.max(np.abs(xs)))
            assert np.max(np.abs(out - xs[:, 0])) <= 1e-11 * size
            assert np.max(np.abs(np.concatenate((state, u)) - end)) <= 1e-11 * max(size, float(np.max(np.abs(end))))


def test_the_taylor_orbit_is_an_independent_integration_s_on_random_scenes():
    """Random scenes with a cubic spring and/or Stribeck's drop, branches or none, a history (one or two terms,
    on x or on v, rates 0 among them) or none, from random states over two periods and a half: the end state
    is the one the straightforward integration above reaches, to 1e-9 (its tolerance 1e-12 and its events'
    1e-13 compound over the stick and slip events)."""
    rng = np.random.default_rng(20261203)
    worst = 0.0
    for _ in range(24):
        parameters = _random_scene(rng)
        m, k0, c, k3, alpha, alpha_k, vs, bk, eta, F, omega = parameters
        x, v, u = rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), np.clip(rng.uniform(-0.3, 0.3, len(bk)), -eta, eta)
        period, M = 2.0 * math.pi / omega, 64
        history, z = NO_HISTORY, np.zeros(0)
        if rng.random() < 0.5:  # a history of one or two terms, on x or on v, some of rate 0
            terms = int(rng.integers(1, 3))
            history = (rng.uniform(-0.3, 0.5, terms) * rng.choice([1.0, 0.0], terms, p=[0.8, 0.2]) + 0.1,
                       rng.choice([0.0, 0.3, 2.0], terms), bool(rng.random() < 0.5))
            z = rng.uniform(-0.2, 0.2, terms)
        state, u_end, _, z_end = _taylor(parameters, x, v, u, period / M, 5 * M // 2, history, z) \
            if history is not NO_HISTORY else (*_taylor(parameters, x, v, u, period / M, 5 * M // 2), z)
        if history is NO_HISTORY:
            rx, rv, ru = reference(*parameters, x, v, u, 2.5 * period)
            rz = z_end
        else:
            rx, rv, ru, rz = reference(*parameters, x, v, u, 2.5 * period, history, z)
        size = max(1.0, abs(rx), abs(rv))
        error = max(abs(state[0] - rx), abs(state[1] - rv), *np.abs(u_end - ru), *np.abs(z_end - rz)) / size
        worst = max(worst, error)
    assert worst <= 1e-9, worst


@pytest.fixture(scope="module")
def duffing_curve(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("duffing")
    out, plot = tmp_path / "curve.csv", tmp_path / "curve.png"
    assert main(["describe", write(tmp_path, DUFFING_FRICTION), "--force-amplitude", "0.3", "--frequencies",
                 "0.1,0.8", "--out", str(out), "--plot", str(plot)]) == 0
    return read_csv(out), plot


def test_a_duffing_oscillator_with_friction_has_both_folds_and_its_middle_unstable(duffing_curve):
    """A hardening spring with Coulomb friction (refused before: no exact stepper): from the command line the
    curve goes up the resonance to its upper fold, back along the unstable middle to the lower fold and on
    down: two folds, every point between them unstable, every other stable; the figure is drawn."""
    table, plot = duffing_curve
    frequency = np.array(table["frequency"], float)
    fold = np.array(table["fold"]) == "true"
    stable = np.array(table["stable"]) == "true"
    folds = np.flatnonzero(fold)
    assert len(folds) == 2 and frequency[folds[0]] > frequency[folds[1]]  # the upper fold first, at the higher f
    between = np.arange(folds[0] + 1, folds[1])
    assert len(between) >= 3 and not np.any(stable[between])
    outside = np.r_[np.arange(0, folds[0]), np.arange(folds[1] + 1, len(frequency))]
    assert np.all(stable[outside])
    assert plot.read_bytes()[:4] == b"\x89PNG"
    assert "nan" not in " ".join(table["amplitude"]).lower()


def test_the_duffing_curve_s_points_are_periodic_orbits_and_the_unstable_ones_leave(duffing_curve):
    """Shooting's states at the curve's rows are periodic orbits of the independent integration (back to
    themselves after a period, to 1e-8 of the motion); moved by 1e-6 of the motion and integrated on for 30
    periods, a stable point comes back towards its orbit while a point marked unstable leaves it (by more than
    10 % of the motion)."""
    from prandtl_fmu.frequency.shooting import ElementShooting, prepared

    table, _ = duffing_curve
    frequency = np.array(table["frequency"], float)
    stable = np.array(table["stable"]) == "true"
    unstable = np.flatnonzero(~stable)
    shooting = ElementShooting(prepared(element(DUFFING_FRICTION)), 0.3, None, 512, 7, 1.0)  # the rows' quadrature
    parameters = (1.0, 1.0, 0.02, 0.5, 0.05, 0.05, 0.0, np.zeros(0), np.zeros(0), 0.3)
    for pick in (0, int(unstable[len(unstable) // 2]), len(frequency) - 1):
        omega = 2.0 * math.pi * frequency[pick]
        # the point of the curve's branch the row is on: Newton from the row's first harmonic
        A, phase = float(table["amplitude"][pick]), float(table["phase"][pick])
        s = shooting._newton(omega, np.array([A * math.cos(phase), -A * omega * math.sin(phase)]))
        assert s is not None and abs(shooting.amplitude_at(s, omega) - A) <= 1e-6 * A
        x, v = s[0], s[1] * shooting.reference
        period = 2.0 * math.pi / omega
        rx, rv, _ = reference(*parameters, omega, x, v, [], period)
        assert max(abs(rx - x), abs(rv - v) / omega) <= 1e-8 * A
        rx, rv, _ = reference(*parameters, omega, x + 1e-6 * A, v, [], 30 * period)
        moved = max(abs(rx - x), abs(rv - v) / omega) / A
        assert (moved < 1e-6) if stable[pick] else (moved > 0.1), (pick, stable[pick], moved)


def test_stribeck_s_drop_has_its_curve_and_its_orbits(tmp_path):
    """Friction with Stribeck's drop (refused before): the curve runs through the resonance; its points are
    periodic orbits of the independent integration (back to themselves after a period, to 1e-8); and at the
    lowest frequencies, where the mass turns slowly through the drop's negative slope, the symmetric orbit is
    unstable (Coulomb friction's cannot be: docs/frequency.md), which that integration confirms (moved by 1e-6 of
    the motion it leaves over 30 periods; at the peak it comes back)."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.shooting import ElementShooting, prepared

    scene = element(STRIBECK)
    curve = harmonic_response(scene, 0.3, [0.08, 0.25])
    assert curve.method == "shooting" and curve.orbit == "Taylor series" and len(curve.frequency) > 10
    peak = int(np.argmax(curve.amplitude))
    assert 0.12 < curve.frequency[peak] < 0.2 and curve.amplitude[peak] > 3 * curve.amplitude[0]
    assert not curve.stable[0] and curve.stable[peak] and curve.stable[-1]
    shooting = ElementShooting(prepared(scene), 0.3, None, 512, 7, 1.0)
    parameters = (1.0, 1.0, 0.05, 0.0, 0.1, 0.06, 0.05, np.zeros(0), np.zeros(0), 0.3)
    for pick in (0, peak, len(curve.frequency) - 1):
        omega, A = 2.0 * math.pi * curve.frequency[pick], curve.amplitude[pick]
        s = shooting.solve_at(omega)
        # the curve's samples were doubled until its first harmonic changed by half its tolerance (1e-6)
        assert abs(shooting.amplitude_at(s, omega) - A) <= 3e-6 * A
        x, v = s[0], s[1] * shooting.reference
        period = 2.0 * math.pi / omega
        rx, rv, _ = reference(*parameters, omega, x, v, [], period)
        assert max(abs(rx - x), abs(rv - v) / omega) <= 1e-8 * A
        if pick != len(curve.frequency) - 1:
            rx, rv, _ = reference(*parameters, omega, x + 1e-6 * A, v, [], 30 * period)
            moved = max(abs(rx - x), abs(rv - v) / omega) / A
            assert (moved < 1e-6) if curve.stable[pick] else (moved > 0.1), (pick, moved)


def series_reference(m, k0, c, k3, alpha, alpha_k, vs, bk, eta, lam, F, omega, x, v, u, t_end):
    """The motion with branches behind series dashpots, written straightforwardly: a branch that sticks relaxes,
    u' = v - lam u, and slides at +-eta while its inflow v - lam u pushes outwards; the mass sticks while the
    other forces stay within alpha. Each phase an ODE for scipy's DOP853 stopped at its events (v = 0; a
    sticking branch's u at +-eta; a sliding branch's inflow at 0; a stuck mass's force at +-alpha).
    Returns (x, v, u) at t_end."""
    from scipy.integrate import solve_ivp

    nb = len(bk)
    u = np.clip(np.array(u, float), -eta, eta)
    mode = np.zeros(nb, int)
    t = 0.0
    largest = 0.02 * 2.0 * math.pi / omega
    while t < t_end:
        if v == 0.0:
            mode[:] = 0  # at rest every inflow, -lam u, turns inwards

            def held(s, y):
                return F * math.cos(omega * s) - k0 * x - k3 * x**3 - float(np.dot(bk, y))

            ends = [lambda s, y, side=side: alpha + 1e-12 - side * held(s, y) for side in (1, -1)]
            for end in ends:
                end.terminal, end.direction = True, -1
            if abs(held(t, u)) > alpha:
                sigma = 1 if held(t, u) > 0 else -1
            else:
                solution = solve_ivp(lambda s, y: -lam * y, (t, t_end), u, events=ends, rtol=1e-12, atol=1e-15,
                                     method="DOP853", max_step=0.05 * largest)
                u, t = solution.y[:, -1].copy(), float(solution.t[-1])
                if solution.status != 1:
                    return x, v, u
                sigma = 1 if len(solution.t_events[0]) else -1
        else:
            sigma = 1 if v > 0 else -1
        while True:
            sticking = [i for i in range(nb) if mode[i] == 0]
            sliding = [i for i in range(nb) if mode[i] != 0]

            def rhs(s, y):
                slide = alpha if vs == 0.0 else alpha_k + (alpha - alpha_k) * math.exp(min(-sigma * y[1] / vs, 0.0))
                force = F * math.cos(omega * s) - k0 * y[0] - k3 * y[0] ** 3 - c * y[1] - sigma * slide
                force -= float(np.dot(bk, y[2:]))
                rates = np.where(mode == 0, y[1] - lam * y[2:], 0.0)
                return np.concatenate(([y[1], force / m], rates))

            events = [lambda s, y: sigma * y[1] + 1e-13]
            events += [lambda s, y, i=i, side=side: eta[i] - side * y[2 + i] for i in sticking for side in (1, -1)]
            events += [lambda s, y, i=i: mode[i] * y[1] - lam[i] * eta[i] + 1e-13 for i in sliding]
            for event in events:
                event.terminal, event.direction = True, -1
            solution = solve_ivp(rhs, (t, t_end), np.concatenate(([x, v], u)), events=events, rtol=1e-12,
                                 atol=1e-15, method="DOP853", max_step=largest)
            x, v, t = float(solution.y[0, -1]), float(solution.y[1, -1]), float(solution.t[-1])
            u = np.clip(solution.y[2:, -1].copy(), -eta, eta)
            if solution.status != 1:
                return x, v, u
            which = next(j for j, times in enumerate(solution.t_events) if len(times))
            if which == 0:
                v = 0.0
                break
            if which <= 2 * len(sticking):
                i, side = sticking[(which - 1) // 2], (1, -1)[(which - 1) % 2]
                mode[i], u[i] = side, side * eta[i]
            else:
                mode[sliding[which - 1 - 2 * len(sticking)]] = 0
    return x, v, u


@pytest.mark.slow  # (compiles the exact stepper with series dashpots for shooting: 17 s on a cold cache)
def test_the_taylor_orbit_with_series_dashpots_is_the_exact_stepper_s_where_both_apply():
    """Branches behind series dashpots (the series model) with Coulomb friction, linear between events: the
    Taylor orbit over two periods (the branches relax while they stick, slide at their levels, stick again when
    their inflow stops; the mass sticks and slides) is the exact stepper's (``exact_series.py``, through
    shooting's own map) to 1e-11 of the motion at every sample."""
    from prandtl_fmu.frequency.shooting import ElementShooting, prepared

    tables = {"mass": {"m": 1.0}, "spring": {"k0": 2.0}, "damper": {"c": 0.05}, "friction": {"alpha": 0.3},
              "branches": {"k": [1.0, 0.5], "alpha": [0.1, 0.2], "c": [2.0, 0.5]}}
    scene = prepared(element(tables))
    assert scene.has_series_dashpots
    eta = np.array(scene.branches.yield_displacement, float)
    lam = np.array([1.0 / 2.0, 0.5 / 0.5])
    M = 128
    for F, omega in ((1.0, 1.3), (0.5, 0.7), (2.0, 3.0)):
        exact = ElementShooting(scene, F, None, M, 7, 1.0)
        assert not exact.smooth
        for start in ([0.0, 0.0, 0.0, 0.0], [0.3, -0.2, 0.05, -0.1], [0.8, 0.5, 0.1, 0.4]):
            end, xs = exact.run(np.array(start), omega, 4)
            state, u, out = np.array(start[:2]), np.clip(start[2:], -eta, eta), np.empty(2 * M)
            status, taken = element_orbit.run(1.0, 2.0, 0.05, 0.0, 0.3, 0.3, 0.0, np.array([1.0, 0.5]), eta, lam,
                                              *NO_HISTORY, F, omega, state, u, np.zeros(0), 2 * math.pi / omega / M,
                                              2 * M, out, 0.0)
            assert status == element_orbit.OK and taken == 2 * M
            size = float(np.max(np.abs(xs)))
            assert np.max(np.abs(out - xs[:, 0])) <= 1e-11 * size
            assert np.max(np.abs(np.concatenate((state, u)) - end)) <= 1e-11 * max(size, float(np.max(np.abs(end))))


def test_the_taylor_orbit_with_series_dashpots_is_the_independent_integration_s_on_random_scenes():
    """Random scenes with a cubic spring and/or Stribeck's drop and one to three branches behind series dashpots
    (relaxation rates 0.05 to 5 per second), from random states over two periods and a half: the end state is
    the straightforward integration's above to 1e-9."""
    rng = np.random.default_rng(20261204)
    worst = 0.0
    for _ in range(16):
        m, k0, c, k3, alpha, alpha_k, vs, _, _, F, omega = _random_scene(rng)
        nb = int(rng.integers(1, 4))
        bk, eta, lam = rng.uniform(0.3, 2.0, nb), rng.uniform(0.05, 0.3, nb), 10.0 ** rng.uniform(-1.3, 0.7, nb)
        x, v, u = rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), np.clip(rng.uniform(-0.3, 0.3, nb), -eta, eta)
        period, M = 2.0 * math.pi / omega, 64
        state, u_end, out = np.array([x, v]), u.copy(), np.empty(5 * M // 2)
        status, taken = element_orbit.run(m, k0, c, k3, alpha, alpha_k, vs, bk, eta, lam, *NO_HISTORY, F, omega,
                                          state, u_end, np.zeros(0), period / M, 5 * M // 2, out, 0.0)
        assert status == element_orbit.OK and taken == 5 * M // 2
        rx, rv, ru = series_reference(m, k0, c, k3, alpha, alpha_k, vs, bk, eta, lam, F, omega, x, v, u,
                                      2.5 * period)
        size = max(1.0, abs(rx), abs(rv))
        worst = max(worst, max(abs(state[0] - rx), abs(state[1] - rv), *np.abs(u_end - ru)) / size)
    assert worst <= 1e-9, worst


def test_series_dashpots_beside_a_smooth_force_have_their_curve_and_its_orbits(tmp_path):
    """A cubic spring and Coulomb friction beside a branch behind a series dashpot (refused before), from the
    command line: the curve bends over the resonance with its two folds, and its points where the orbit is the
    only one (below the lower fold, above the upper) are periodic orbits of the independent integration above
    (back to themselves after a period, to 1e-8 of the motion)."""
    from prandtl_fmu.frequency.shooting import ElementShooting, prepared

    tables = dict(DUFFING_FRICTION, branches={"k": [1.0], "alpha": [0.05], "c": [0.5]})
    out = tmp_path / "curve.csv"
    assert main(["describe", write(tmp_path, tables), "--force-amplitude", "0.3", "--frequencies", "0.1,0.5",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    frequency, amplitude = np.array(table["frequency"], float), np.array(table["amplitude"], float)
    fold = np.array(table["fold"]) == "true"
    assert len(frequency) > 10 and np.max(amplitude) > 3 * amplitude[0] and np.sum(fold) == 2
    shooting = ElementShooting(prepared(element(tables)), 0.3, None, 512, 7, 1.0)
    assert shooting.smooth and shooting.dimension == 3
    below = np.flatnonzero(frequency < 0.99 * np.min(frequency[fold]))
    for pick in (0, below[np.argmax(amplitude[below])], len(frequency) - 1):
        omega, A = 2.0 * math.pi * frequency[pick], amplitude[pick]
        s = shooting.solve_at(omega)
        assert abs(shooting.amplitude_at(s, omega) - A) <= 3e-6 * A
        x, v, u = s[0], s[1] * shooting.reference, s[2:]
        rx, rv, ru = series_reference(1.0, 1.0, 0.02, 0.5, 0.05, 0.05, 0.0, np.array([1.0]), np.array([0.05]),
                                      np.array([2.0]), 0.3, omega, x, v, u, 2.0 * math.pi / omega)
        assert max(abs(rx - x), abs(rv - v) / omega, *np.abs(ru - u)) <= 1e-8 * A


@pytest.mark.parametrize("k0, c, k3, x0, expected", [
    (1e10, 0.02, 0.0, 0.0, "PILED_UP"), (1.0, 0.02, 1e14, 1.0, "PILED_UP"), (1e12, 2e6, 0.0, 0.0, "TOO_STIFF")],
    ids=["stick-slip at 1e5 rad/s", "a stiff cubic at large amplitude", "overdamped at 1e6 1/s"])
def test_the_taylor_orbit_s_work_is_bounded(k0, c, k3, x0, expected):
    """Motions the samples cannot follow end with their status after a bounded amount of work, never a hang: a
    spring of 1e10 N/m with Coulomb friction sticks and slips at every fast period, as does a cubic spring of
    1e14 N/m^3 from 1 m (events that pile up); a dashpot that relaxes the stiff spring at 1e6 1/s takes steps
    of its time scale (more Taylor steps than the bound)."""
    import time

    from prandtl_fmu.frequency import element_orbit

    state, out = np.array([x0, 0.0]), np.empty(64)
    start = time.perf_counter()
    status, taken = element_orbit.run(1.0, k0, c, k3, 0.05, 0.05, 0.0, np.zeros(0), np.zeros(0), np.zeros(0),
                                      *NO_HISTORY, 0.3, 0.6, state, np.zeros(0), np.zeros(0), 2 * math.pi / 0.6 / 64,
                                      64, out, 0.0)
    assert status == getattr(element_orbit, expected) and taken < 64
    assert time.perf_counter() - start < 30.0
    assert element_orbit.explain(status) != f"status {status}"


@pytest.mark.parametrize("acts_on", ["x", "v"])
def test_friction_beside_a_history_is_the_linear_closed_form_where_the_friction_vanishes(acts_on):
    """[friction] with [history] (refused before: shooting had no state for the memory; the z_j of its
    exponential terms are now unknowns of the shooting): with a friction of 1e-9 N against a force of 1 N the
    curve is the linear oscillator's with the history's transfer function, X = F / (k - m w^2 + i c w +
    sum_j w_j g_j / (r_j + i w)) (g_j = 1 on x, i w on v; a rate 0 among them: a plain integral), to 1e-7 in
    amplitude and phase."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from tests.analysis.test_harmonic_balance import element

    weights, rates = [0.3, 0.1], [0.5, 0.0]
    scene = element({"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.05},
                     "friction": {"alpha": 1e-9}, "history": {"weight": weights, "rate": rates, "acts_on": acts_on}})
    curve = harmonic_response(scene, 1.0, [0.05, 0.4], tolerance=1e-9)
    assert curve.method == "shooting" and curve.orbit == "Taylor series" and len(curve.frequency) > 10
    omega = 2.0 * math.pi * curve.frequency
    gain = np.ones_like(omega) if acts_on == "x" else 1j * omega
    memory = sum(w * gain / (r + 1j * omega) for w, r in zip(weights, rates))
    X = 1.0 / (1.0 - omega**2 + 0.05j * omega + memory)
    assert np.allclose(curve.amplitude, np.abs(X), rtol=1e-7, atol=0)
    assert np.allclose(curve.phase, np.angle(X), rtol=0, atol=1e-7)


def test_friction_beside_a_history_has_its_periodic_orbits(tmp_path):
    """With a friction that matters (the mass sticks at low frequency), from the command line: the curve's
    states are periodic orbits of the independent integration (history included) to 1e-8."""
    from prandtl_fmu.frequency.shooting import ElementShooting, prepared
    from tests.analysis.test_harmonic_balance import element

    tables = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.05}, "friction": {"alpha": 0.1},
              "history": {"weight": [0.3], "rate": [0.5]}}
    out = tmp_path / "curve.csv"
    assert main(["describe", write(tmp_path, tables), "--force-amplitude", "0.3", "--frequencies", "0.05,0.4",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    shooting = ElementShooting(prepared(element(tables)), 0.3, None, 512, 7, 1.0)
    assert shooting.dimension == 3
    frequency = np.array(table["frequency"], float)
    for pick in (0, len(frequency) // 2, len(frequency) - 1):
        omega = 2.0 * math.pi * frequency[pick]
        s = shooting.solve_at(omega)
        A = float(table["amplitude"][pick])
        assert abs(shooting.amplitude_at(s, omega) - A) <= 3e-6 * A
        x, v, z = s[0], s[1] * shooting.reference, s[2:]
        rx, rv, _, rz = reference(1.0, 1.0, 0.05, 0.0, 0.1, 0.1, 0.0, np.zeros(0), np.zeros(0), 0.3, omega, x, v, [],
                                  2.0 * math.pi / omega, (np.array([0.3]), np.array([0.5]), False), z)
        assert max(abs(rx - x), abs(rv - v) / omega, *np.abs(rz - z) / omega) <= 1e-8 * A


@pytest.mark.parametrize("stepper, warned", [("verlet", True), ("exact", False)])
def test_the_time_sweep_warns_where_its_error_column_cannot_be_trusted(tmp_path, capsys, stepper, warned):
    """--method time on friction with a stepper other than exact: one warning line (measured: verlet's error on
    the Duffing oscillator with friction stays at 3.3e-5 from 2048 to 8192 steps a period while the changes it
    states are 6e-7 and 2e-7); with the exact stepper (Coulomb friction, a linear spring), none."""
    tables = dict(DUFFING_FRICTION) if stepper == "verlet" else {
        key: value for key, value in DUFFING_FRICTION.items() if key != "cubic"}
    out = tmp_path / "sweep.csv"
    assert main(["describe", write(tmp_path, tables), "--method", "time", "--stepper", stepper, "--force-amplitude",
                 "0.3", "--frequencies", "0.6", "--tolerance", "1e-3", "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert (len(err) == 1 and err[0].startswith("warning:") and repr(stepper) in err[0]) if warned else err == []
    assert out.exists()


@pytest.mark.parametrize("vs", [0.01, 0.003, 0.001])
def test_a_small_stribeck_velocity_is_crossed_in_steps_the_drop_can_follow(vs):
    """A fast slide that stops through a narrow drop (v_s of a few mm/s): the steps cross the drop in pieces its
    exponential's series can follow, so the orbit is the same whatever the samples (128 or 8192 a period, to
    1e-11) and the independent integration's (to 1e-8); before, 128 samples let one step jump the drop, the
    friction too small on the way, 3e-4 off (a review's find, invisible to the samples' doubling)."""
    parameters = (1.0, 1.0, 0.0, 0.0, 0.5, 0.1, vs, np.zeros(0), np.zeros(0), 2.0, 1.0)
    period = 2.0 * math.pi
    ends = [_taylor(parameters, 0.0, 0.0, [], period / n, 2 * n)[0] for n in (128, 8192)]
    assert np.max(np.abs(ends[0] - ends[1])) <= 1e-11 * np.max(np.abs(ends[1]))
    rx, rv, _ = reference(*parameters, 0.0, 0.0, [], 2.0 * period)
    assert abs(ends[1][0] - rx) <= 1e-8 * max(1.0, abs(rv)) and abs(ends[1][1] - rv) <= 1e-8 * max(1.0, abs(rv))


@pytest.mark.parametrize("F, k3", [(10.0, 100.0), (100.0, 1.0)])
def test_a_run_from_exact_rest_takes_its_steps(F, k3):
    """From x = v = 0 (shooting's first guess) the truncation test compares with the forces' length, not with 0:
    before, its steps were of length 0 until the run was refused as too stiff (a review's find)."""
    from prandtl_fmu.frequency import element_orbit

    omega = 2.0 * math.pi * 0.1
    state, out = np.zeros(2), np.empty(64)
    status, taken = element_orbit.run(1.0, 1.0, 0.1, k3, 0.5, 0.5, 0.0, np.zeros(0), np.zeros(0), np.zeros(0),
                                      *NO_HISTORY, F, omega, state, np.zeros(0), np.zeros(0),
                                      2 * math.pi / omega / 64, 64, out, 0.0)
    assert status == element_orbit.OK and taken == 64 and np.all(np.isfinite(out))
    rx, rv, _ = reference(1.0, 1.0, 0.1, k3, 0.5, 0.5, 0.0, np.zeros(0), np.zeros(0), F, omega, 0.0, 0.0, [],
                          2 * math.pi / omega)
    assert abs(state[0] - rx) <= 1e-8 * max(1.0, abs(rx)) and abs(state[1] - rv) <= 1e-8 * max(1.0, abs(rv))


def test_a_fast_slide_through_a_narrow_drop_is_the_independent_integration_s():
    """A slide at 1e9 Stribeck velocities (v_s = 1 mm/s, v = 1e6 m/s): the steps go at their own length to where
    the drop starts to show (40 v_s), then in pieces of 2 in its exponent (cut to those pieces from where a step
    would reach the stop, a slide took (its speed there) / (2 v_s) steps: 42 000 a half period at the 3e5 m of
    the packaged breakaway-ramp's climb, 80 ms a run, measured; this test checks the orbit, not the cost). The
    orbit is the independent integration's to 1e-9 of its swing."""
    parameters = (1.0, 1.0, 0.0, 0.0, 0.5, 0.1, 1e-3, np.zeros(0), np.zeros(0), 2.0, 1.0)
    period = 2.0 * math.pi
    state, _, _ = _taylor(parameters, 0.0, 1e6, [], period / 64, 64)
    rx, rv, _ = reference(*parameters, 0.0, 1e6, [], period)
    assert abs(state[0] - rx) <= 1e-9 * 1e6 and abs(state[1] - rv) <= 1e-9 * 1e6, (state, rx, rv)  # of the swing
