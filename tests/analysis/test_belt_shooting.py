"""Friction on a moving belt (``[friction] belt_velocity``) in the frequency response: the Taylor orbit of
``frequency/element_orbit.py`` with the mass stuck to the belt (x moving with it, the branches it carries sliding
at their levels ahead) and the slides on the slip v - V, and shooting over the whole period (a belt breaks the
half period's symmetry). Checked against a straightforward hybrid integration written here (scipy's DOP853 with
its event location, mode by mode), on random scenes and at the points of a curve."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main
from prandtl_fmu.frequency import element_orbit

from tests.analysis.test_describe_cli import read_csv, write
from tests.analysis.test_element_orbit import NO_HISTORY
from tests.analysis.test_harmonic_balance import element

BELT = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.1}, "friction": {"alpha": 0.3,
                                                                                      "belt_velocity": 0.2}}


def belt_reference(m, k0, c, k3, alpha, alpha_k, vs, belt, bk, eta, F, omega, x, v, u, t_end, t=0.0, seen=None):
    """The motion from (x, v, u) at ``t`` to ``t_end``, written straightforwardly with the belt's speed ``belt``:
    modes (the mass sliding either way on the slip w = v - belt, or stuck to the belt: x' = belt; each branch
    sticking, u' = x', or sliding at +-eta), each an ODE for scipy's DOP853 (rtol 1e-12) stopped at the events of
    its mode (w = 0; |N - c belt| = alpha; u = +-eta; x' = 0 for a sliding branch), the mode that event ends
    changed. Returns (x, v, u) at t_end; ``seen`` (a Counter) counts the events by kind, and "ahead": the
    branches that slide while the mass sticks to the belt.)"""
    from scipy.integrate import solve_ivp

    nb = len(bk)
    u = np.clip(np.array(u, float), -eta, eta)
    bmode = np.zeros(nb, int)
    largest = 0.02 * 2.0 * math.pi / omega
    tiny = 1e-12

    def held(s, x, u):  # the force on the mass stuck to the belt, without the friction
        return F * math.cos(omega * s) - k0 * x - k3 * x**3 - c * belt - float(np.dot(bk, u))

    def mass_mode(s, x, v, u):
        if abs(v - belt) > tiny:
            return 1 if v > belt else -1
        pull = held(s, x, u)
        return 1 if pull > alpha else -1 if pull < -alpha else 0

    def branches_ahead(direction):  # the sticking branches at their level in the direction x moves slide
        for i in range(nb):
            if direction != 0 and bmode[i] == 0 and direction * u[i] >= eta[i] - tiny * max(1.0, eta[i]):
                bmode[i], u[i] = direction, direction * eta[i]

    def sign(value):
        return 1 if value > 0 else -1 if value < 0 else 0

    sigma = mass_mode(t, x, v, u)
    if sigma == 0:
        v = belt
    branches_ahead(sign(belt) if sigma == 0 else (sign(v) or sigma))
    for _ in range(100000):
        if t >= t_end:
            return x, v, u

        def speed(y):
            return belt if sigma == 0 else y[1]

        def rhs(s, y):
            force = F * math.cos(omega * s) - k0 * y[0] - k3 * y[0] ** 3 - float(np.dot(bk, y[2:]))
            if sigma == 0:
                acceleration = 0.0
            else:
                slip = abs(y[1] - belt)
                slide = alpha if vs == 0.0 else alpha_k + (alpha - alpha_k) * math.exp(-slip / vs)
                acceleration = (force - c * y[1] - sigma * slide) / m
            rate = speed(y)
            return np.concatenate(([rate, acceleration], [rate if bmode[i] == 0 else 0.0 for i in range(nb)]))

        events = []  # (function, what it ends)
        if sigma != 0:
            events.append((lambda s, y: sigma * (y[1] - belt), ("slide",)))
        else:
            events += [(lambda s, y, side=side: alpha - side * held(s, y[0], y[2:]), ("stick", side))
                       for side in (1, -1)]
        for i in range(nb):
            if bmode[i] == 0:
                events += [(lambda s, y, i=i, side=side: eta[i] - side * y[2 + i], ("level", i, side))
                           for side in (1, -1)]
            elif sigma != 0:
                events.append((lambda s, y, i=i: bmode[i] * y[1], ("turn",)))
        for function, _ in events:
            function.terminal, function.direction = True, -1
        solution = solve_ivp(rhs, (t, t_end), np.concatenate(([x, v], u)), events=[e for e, _ in events],
                             rtol=1e-12, atol=1e-15, method="DOP853", max_step=largest)
        x, v, t = float(solution.y[0, -1]), float(solution.y[1, -1]), float(solution.t[-1])
        u = np.clip(solution.y[2:, -1], -eta, eta)
        if sigma == 0:
            v = belt
        if solution.status != 1:
            return x, v, u
        ended = events[next(j for j, times in enumerate(solution.t_events) if len(times))][1]
        if seen is not None:
            seen[ended[0]] += 1
            seen["ahead"] += int(sigma == 0 and ended[0] == "level")
        if ended[0] == "slide":  # the slip ends: the mass sticks to the belt or turns back
            v = belt
            for i in range(nb):
                if bmode[i] != 0 and bmode[i] != sign(belt):
                    bmode[i] = 0
            sigma = mass_mode(t, x, v, u)
            branches_ahead(sign(belt))
        elif ended[0] == "stick":  # the friction lets go
            sigma = ended[1]
        elif ended[0] == "level":
            bmode[ended[1]], u[ended[1]] = ended[2], ended[2] * eta[ended[1]]
            branches_ahead(ended[2])  # (others at their level at the same moment)
        else:  # x' turns: the sliding branches stick at their levels
            v = 0.0
            bmode[:] = 0
    raise AssertionError("the reference integration took too many modes")


def orbit(scene_values, F, omega, x, v, u, steps):
    """element_orbit.run with the belt: (state, u, status)."""
    m, k0, c, k3, alpha, alpha_k, vs, belt, bk, eta = scene_values
    state, u_end, out = np.array([x, v]), np.array(u, float), np.empty(steps)
    status, taken = element_orbit.run(m, k0, c, k3, alpha, alpha_k, vs, bk, eta, np.zeros(0), *NO_HISTORY, F, omega,
                                      state, u_end, np.zeros(0), 2.0 * math.pi / omega / 64, steps, out, belt)
    assert status == element_orbit.OK and taken == steps, element_orbit.explain(status)
    return state, u_end


def test_the_taylor_orbit_on_a_belt_is_the_independent_integration_s_on_random_scenes():
    """Random scenes (a spring, a dashpot, maybe a cubic spring, maybe Stribeck's drop, zero to two branches, a
    belt either way), from random states over two periods and a half (64 samples a period): the end state is the
    straightforward integration's above to 1e-9 of the motion. The scenes stick to the belt and slide, and their
    branches slide ahead of the belt while the mass sticks and turn within a slide of one direction."""
    from collections import Counter

    rng = np.random.default_rng(20261203)
    worst = 0.0
    seen = Counter()
    for _ in range(12):
        m, k0, c = rng.uniform(0.5, 2.0), rng.uniform(0.5, 3.0), rng.uniform(0.0, 0.3)
        k3 = rng.uniform(0.1, 2.0) if rng.random() < 0.4 else 0.0
        alpha = rng.uniform(0.1, 0.5)
        alpha_k, vs = (alpha * rng.uniform(0.4, 0.9), rng.uniform(0.1, 0.5)) if rng.random() < 0.5 else (alpha, 0.0)
        belt = rng.choice([-1.0, 1.0]) * rng.uniform(0.05, 0.5)
        nb = int(rng.integers(0, 3))
        bk, eta = rng.uniform(0.3, 2.0, nb), rng.uniform(0.05, 0.3, nb)
        F, omega = rng.uniform(0.3, 2.0), rng.uniform(0.5, 3.0)
        x, v, u = rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), np.clip(rng.uniform(-0.3, 0.3, nb), -eta, eta)
        values = (m, k0, c, k3, alpha, alpha_k, vs, belt, bk, eta)
        state, u_end = orbit(values, F, omega, x, v, u, 5 * 64 // 2)
        rx, rv, ru = belt_reference(m, k0, c, k3, alpha, alpha_k, vs, belt, bk, eta, F, omega, x, v, u,
                                    2.5 * 2.0 * math.pi / omega, seen=seen)
        size = max(1.0, abs(rx), abs(rv))
        worst = max(worst, max(abs(state[0] - rx), abs(state[1] - rv), *np.abs(u_end - ru)) / size)
    assert worst <= 1e-9, worst
    # every kind of event happened (the scenes are drawn so: the test would lose its meaning otherwise)
    assert all(seen[kind] >= 3 for kind in ("slide", "stick", "level", "turn", "ahead")), seen


@pytest.mark.parametrize("tables, F, f", [
    (BELT, 0.5, 0.08),  # sticks to the belt half of the period, then slides back
    (dict(BELT, branches={"k": [0.5, 0.3], "alpha": [0.05, 0.12]}), 0.5, 0.08),
    (dict(BELT, friction={"alpha": 0.3, "alpha_kinetic": 0.2, "stribeck_velocity": 0.1, "belt_velocity": -0.1},
          damper={"c": 0.5}), 0.5, 0.08),
])
def test_the_periodic_state_on_a_belt_is_an_orbit_of_the_independent_integration(tables, F, f):
    """Shooting over the whole period on a belt: the state it finds comes back to itself after a period under the
    integration above (to 1e-8 of the motion), the mass moves with the belt over part of the period (x advancing
    by V h from sample to sample), its mean is not zero (the belt drags the mass), and, with a dashpot, Coulomb's
    friction on the belt is monotone: every multiplier is within the unit circle."""
    from prandtl_fmu.frequency.shooting import ElementShooting, prepared

    scene = prepared(element(tables))
    omega = 2.0 * math.pi * f
    shooting = ElementShooting(scene, F, None, 128, 7, omega)
    assert shooting.smooth and not shooting.symmetric
    s = shooting.solve_at(omega)
    friction = scene.friction
    bk = np.zeros(0) if scene.branches is None else np.array(scene.branches.stiffness, float)
    eta = np.zeros(0) if scene.branches is None else np.array(scene.branches.yield_displacement, float)
    c = float(scene.damper.c)
    vs = float(friction.stribeck_velocity) if friction.stribeck_velocity is not None else 0.0
    x, v, u = belt_reference(1.0, 1.0, c, 0.0, friction.alpha, friction.alpha_kinetic, vs, friction.belt_velocity,
                             bk, eta, F, omega, s[0], s[1] * omega, s[2:], 2.0 * math.pi / omega)
    samples = shooting.samples(s, omega)[0]
    size = float(np.max(np.abs(samples)))
    stuck = np.abs(np.diff(samples) - friction.belt_velocity * 2.0 * math.pi / omega / 128) <= 1e-12 * size
    assert 0.05 <= np.mean(stuck) <= 0.95
    assert max(abs(x - s[0]), abs(v / omega - s[1]), *np.abs(u - s[2:])) <= 1e-8 * size
    assert abs(shooting.coefficients(s, omega)[0, 0]) > 1e-3 * size
    if friction.stribeck_velocity is None:
        assert np.max(np.abs(shooting.multipliers(s, omega))) < 1.0


def test_the_curve_on_a_belt_from_the_command_line_is_the_settled_motion(tmp_path):
    """`describe` of a mass on a belt (refused before: "no periodic state symmetric over half a period"): every
    point is stable (Coulomb friction on the belt with a dashpot), and its amplitude is the first harmonic of the
    independent integration's last period after 60 periods from rest, to 1e-6."""
    out = tmp_path / "curve.csv"
    assert main(["describe", write(tmp_path, BELT), "--force-amplitude", "0.5", "--frequencies", "0.06,0.12",
                 "--out", str(out)]) == 0
    table = read_csv(out)
    assert set(table["stable"]) == {"true"} and len(table["frequency"]) >= 2
    for row in (0, len(table["frequency"]) // 2, len(table["frequency"]) - 1):
        f = float(table["frequency"][row])
        omega, periods, M = 2.0 * math.pi * f, 60, 256
        period = 2.0 * math.pi / omega
        x, v, u = belt_reference(1.0, 1.0, 0.1, 0.0, 0.3, 0.3, 0.0, 0.2, np.zeros(0), np.zeros(0), 0.5, omega,
                                 0.0, 0.0, np.zeros(0), (periods - 1) * period)
        samples = []
        for j in range(M):  # the last period, sample by sample (the reference integrates on from each)
            samples.append(x)
            start = (periods - 1) * period + j * period / M
            x, v, u = belt_reference(1.0, 1.0, 0.1, 0.0, 0.3, 0.3, 0.0, 0.2, np.zeros(0), np.zeros(0), 0.5, omega,
                                     x, v, u, start + period / M, start)
        first = 2.0 * abs(np.fft.rfft(samples)[1]) / M
        assert float(table["amplitude"][row]) == pytest.approx(first, rel=1e-6)


@pytest.mark.parametrize("tables, F, culprit", [
    # a branch far from its level: it never slides, any preload within its range is as periodic
    (dict(BELT, branches={"k": [0.5, 0.3], "alpha": [0.05, 5.0]}), 0.5, "branch 2 never slides over the period"),
    # no dashpot, a fast belt, a small force: the mass slides all along, a free oscillation added is as periodic
    ({"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "friction": {"alpha": 0.1, "belt_velocity": 1.0}}, 0.05,
     "never sticks to the belt and nothing damps"),
])
def test_a_family_of_periodic_states_on_a_belt_is_said_in_one_line(tmp_path, capsys, tables, F, culprit):
    """Where the periodic state on a belt is not isolated (its Jacobian singular: Newton lands on a member as the
    rounding falls, and the continuation went on to say the curve "turned back", which it had not), one line
    names why, and nothing is written."""
    out = tmp_path / "curve.csv"
    assert main(["describe", write(tmp_path, tables), "--force-amplitude", str(F), "--frequencies", "0.05,0.1",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert culprit in err and "at f = 0.05 Hz" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
