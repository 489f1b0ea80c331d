"""The effects with memory (``prandtl_fmu/memory/``): [delay], [history], [dahl].

Each against an independent solution written here: the delay's stability boundary g tau / c = pi / 2 and the
rightmost root of the delayed oscillator's characteristic equation, a Runge-Kutta solution of the delay
equation (measured order 1); the history against the exact solution of the equivalent linear ODE (matrix
exponential) and against the convolution summed directly over the run's own path (O(N^2)); Dahl's friction
against its closed forms under monotone motion and against scipy's Radau. Then the energy balance, the state
(pieces, save and restore, rollback) and the refusals.
"""
import json
import math

import numpy as np
import pytest

from prandtl_fmu.driver import simulate
from prandtl_fmu.element import Element
from prandtl_fmu.scene import SceneError, parse_scene

slow = pytest.mark.slow


def scene(text, stepper="implicit", step=1e-3, stop=10.0, interval=None):
    return parse_scene(text + f"""
[solver]
stepper = "{stepper}"
step = {step!r}
stop_time = {stop!r}
output_interval = {interval or step!r}
""")


FIRST_ORDER = """
[damper]
c = 1.0
[delay]
gain = 1.0
tau = {tau}
[load]
kind = "constant"
value = 1.0
"""


@slow
@pytest.mark.parametrize("stepper", ["implicit", "projected"])
def test_a_first_order_delay_decays_below_pi_over_2_and_grows_beyond(stepper):
    """c x' = F - g x(t - tau) (massless, a dashpot): the deviation from x* = F / g decays iff g tau / c < pi/2."""
    amplitudes = {}
    for ratio in (1.3, 1.85):
        r = simulate(scene(FIRST_ORDER.format(tau=ratio), stepper, step=ratio / 400, stop=80.0,
                           interval=ratio / 400)).columns()
        t, e = r["time"], np.abs(r["x"] - 1.0)
        amplitudes[ratio] = (e[(t > 20) & (t < 30)].max(), e[t > 70].max())
    early, late = amplitudes[1.3]
    assert late < 0.05 * early
    early, late = amplitudes[1.85]
    assert late > 5.0 * early


OSCILLATOR = """
[mass]
m = 1.0
x0 = 1.0
[spring]
k0 = 4.0
[damper]
c = 0.2
[delay]
gain = {gain}
tau = {tau}
acts_on = "{on}"
"""


def rightmost_root(m, c, k, g, tau, on):
    """The root of m s^2 + c s + k + g s^q e^(-s tau) = 0 (q = 0 on x, 1 on v) of largest real part: Newton
    from a grid of starting points."""
    q = 1 if on == "v" else 0
    roots = []
    for re in np.linspace(-2, 1, 7):
        for im in np.linspace(0.1, 6, 13):
            s = complex(re, im)
            for _ in range(100):
                e = g * np.exp(-s * tau)
                f = m * s * s + c * s + k + (s if q else 1) * e
                df = 2 * m * s + c + (e if q else 0) - tau * (s if q else 1) * e
                step = f / df
                s -= step
                if abs(step) < 1e-14 * max(1, abs(s)):
                    break
            if abs(m * s * s + c * s + k + (s if q else 1) * g * np.exp(-s * tau)) < 1e-9 and s.imag > 0:
                roots.append(s)
    return max(roots, key=lambda s: s.real)


def decay_rate(t, x, start):
    """The slope of log|x| at its peaks after ``start``."""
    inner = (np.abs(x[1:-1]) > np.abs(x[:-2])) & (np.abs(x[1:-1]) >= np.abs(x[2:])) & (t[1:-1] > start)
    peaks_t, peaks = t[1:-1][inner], np.abs(x[1:-1][inner])
    return np.polyfit(peaks_t, np.log(peaks), 1)[0]


@slow
@pytest.mark.parametrize("gain, tau, on", [(0.5, 0.7, "x"), (-0.8, 0.4, "x"), (0.3, 0.5, "v"), (1.5, 1.2, "x")])
def test_the_delayed_oscillator_decays_at_its_rightmost_root(gain, tau, on):
    root = rightmost_root(1.0, 0.2, 4.0, gain, tau, on)
    r = simulate(scene(OSCILLATOR.format(gain=gain, tau=tau, on=on), step=5e-4, stop=40.0)).columns()
    measured = decay_rate(r["time"], r["x"], 15.0)
    # backward Euler's own damping of a mode of frequency w: about h w^2 / 2
    assert measured == pytest.approx(root.real, abs=0.02 * abs(root.real) + 5e-4 * root.imag ** 2 + 2e-3)


def rk4_delay(gain, tau, on, h, stop):
    """m x'' = -k x - c x' - g y(t - tau) by classical RK4 with the delayed value from cubic Hermite
    interpolation of the stored path (history: the initial state): an independent solution, O(h^4)."""
    n = int(round(stop / h))
    xs, vs = np.empty(n + 1), np.empty(n + 1)
    xs[0], vs[0] = 1.0, 0.0

    def acc(x, v):
        return -4.0 * x - 0.2 * v

    def delayed(s, p):  # y(s) from the first p + 1 stored points
        if s <= 0:
            return 1.0 if on == "x" else 0.0
        j = min(int(s / h), p - 1)
        theta = s / h - j
        x0, x1, v0, v1 = xs[j], xs[j + 1], vs[j], vs[j + 1]
        if on == "x":
            h00, h10, h01, h11 = (2 * theta**3 - 3 * theta**2 + 1, theta**3 - 2 * theta**2 + theta,
                                  -2 * theta**3 + 3 * theta**2, theta**3 - theta**2)
            return h00 * x0 + h10 * h * v0 + h01 * x1 + h11 * h * v1
        a0, a1 = acc(x0, v0) - gain * delayed(j * h - tau, p), acc(x1, v1) - gain * delayed((j + 1) * h - tau, p)
        h00, h10, h01, h11 = (2 * theta**3 - 3 * theta**2 + 1, theta**3 - 2 * theta**2 + theta,
                              -2 * theta**3 + 3 * theta**2, theta**3 - theta**2)
        return h00 * v0 + h10 * h * a0 + h01 * v1 + h11 * h * a1

    for p in range(n):
        t, x, v = p * h, xs[p], vs[p]

        def f(s, x, v):
            return v, acc(x, v) - gain * delayed(s - tau, p)

        k1 = f(t, x, v)
        k2 = f(t + h / 2, x + h / 2 * k1[0], v + h / 2 * k1[1])
        k3 = f(t + h / 2, x + h / 2 * k2[0], v + h / 2 * k2[1])
        k4 = f(t + h, x + h * k3[0], v + h * k3[1])
        xs[p + 1] = x + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        vs[p + 1] = v + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    return xs


@slow
@pytest.mark.parametrize("stepper", ["implicit", "projected"])
def test_the_delay_converges_at_order_one_to_an_independent_solution(stepper):
    """tau = 0.55 is no multiple of the steps: the buffer's interpolation is exercised."""
    stop = 4.0
    reference = rk4_delay(0.9, 0.55, "x", 1e-3, stop)
    errors = []
    for h in (8e-3, 4e-3, 2e-3):
        r = simulate(scene(OSCILLATOR.format(gain=0.9, tau=0.55, on="x"), stepper, step=h, stop=stop,
                           interval=8e-3)).columns()
        errors.append(np.max(np.abs(r["x"] - reference[::8])))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 0.85) & (orders < 1.2)), (errors, orders)


HISTORY = """
[damper]
c = 2.0
[spring]
k0 = 1.5
[history]
weight = [0.8, 0.3]
rate = [0.5, 4.0]
[load]
kind = "constant"
value = 1.0
"""


def history_exact(times):
    """c x' = F - k x - sum_j w_j z_j, z_j' = -r_j z_j + x: a linear ODE, solved by its matrix exponential."""
    c, k, force = 2.0, 1.5, 1.0
    w, r = np.array([0.8, 0.3]), np.array([0.5, 4.0])
    a = np.zeros((3, 3))
    a[0, 0], a[0, 1:] = -k / c, -w / c
    a[1:, 0] = 1.0
    a[1:, 1:] = -np.diag(r)
    b = np.array([force / c, 0.0, 0.0])
    steady = -np.linalg.solve(a, b)
    values, vectors = np.linalg.eig(a)
    coefficients = np.linalg.solve(vectors, -steady)  # y(0) = 0
    return np.array([(steady + (vectors @ (coefficients * np.exp(values * t)))).real[0] for t in times])


@slow
@pytest.mark.parametrize("stepper", ["implicit", "projected"])
def test_the_history_term_converges_at_order_one_to_the_exact_solution(stepper):
    errors = []
    for h in (0.02, 0.01, 0.005):
        r = simulate(scene(HISTORY, stepper, step=h, stop=8.0, interval=0.04)).columns()
        errors.append(np.max(np.abs(r["x"] - history_exact(r["time"]))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] < 5e-3
    assert np.all((orders > 0.9) & (orders < 1.15)), (errors, orders)


@slow
@pytest.mark.parametrize("on", ["x", "v"])
def test_the_history_force_is_the_convolution_summed_directly_over_the_path(on):
    """The force -int_0^t kappa(t - s) y(s) ds with the run's own path y (linear between steps), summed interval
    by interval in O(N^2), equals the element's: the internal variables integrate it exactly."""
    text = f"""
[mass]
m = 1.0
x0 = 0.3
v0 = -1.0
[spring]
k0 = 3.0
[history]
weight = [0.7, -0.2, 0.4]
rate = [0.0, 1.5, 7.0]
acts_on = "{on}"
[load]
kind = "harmonic"
amplitude = 1.0
omega = 2.5
"""
    h = 0.01
    r = simulate(scene(text, step=h, stop=3.0)).columns()
    t, x, v = r["time"], r["x"], r["v"]
    y = x if on == "x" else v
    force = r["reaction"] - 3.0 * r["x"]
    for p in range(1, len(t), 37):
        total = 0.0
        for weight, rate in ((0.7, 0.0), (-0.2, 1.5), (0.4, 7.0)):
            for i in range(p):  # int over [t_i, t_i+1] of exp(-rate (t_p - s)) (linear y) ds, exactly
                a, b = t[p] - t[i + 1], t[p] - t[i]  # the kernel's arguments at the ends
                if rate == 0.0:
                    total += weight * 0.5 * (b - a) * (y[i] + y[i + 1])
                    continue
                # int_a^b exp(-rate q) (y_i+1 (b - q) + y_i (q - a)) / (b - a) dq
                e_a, e_b = math.exp(-rate * a), math.exp(-rate * b)
                i0 = (e_a - e_b) / rate
                i1 = (e_a * (rate * a + 1) - e_b * (rate * b + 1)) / rate**2  # int q exp(-rate q)
                total += weight * (y[i] * (i1 - a * i0) + y[i + 1] * (b * i0 - i1)) / (b - a)
        assert force[p] == pytest.approx(total, rel=1e-9, abs=1e-12)


DAHL_RAMP = """
[spring]
k0 = 2.0
[damper]
c = 1.0
[dahl]
sigma = 50.0
force = 0.5
exponent = {exponent}
[load]
kind = "table"
time = [0.0, 10.0]
force = [0.0, 10.0]
"""


@slow
@pytest.mark.parametrize("exponent", [1.0, 2.0, 0.5])
def test_dahl_follows_its_closed_form_under_monotone_motion(exponent):
    """x increases: F_d(x) = F_c (1 - y(x)), y = exp(-sigma x / F_c) (exponent 1), (1 + sigma x / F_c)^-1 (2),
    max(0, 1 - sigma x / (2 F_c))^2 (1/2): exact whatever the step, since the step applies Dahl's operator."""
    r = simulate(scene(DAHL_RAMP.format(exponent=exponent), step=2e-3, stop=1.0, interval=2e-2)).columns()
    x = r["x"]
    assert np.all(np.diff(x) > 0)
    d = 50.0 * x / 0.5
    y = {1.0: np.exp(-d), 2.0: 1.0 / (1.0 + d), 0.5: np.maximum(0.0, 1.0 - d / 2) ** 2}[exponent]
    np.testing.assert_allclose(r["reaction"] - 2.0 * x - r["v"], 0.5 * (1.0 - y), rtol=0, atol=2e-14)


@pytest.mark.parametrize("exponent", [1.0, 2.0, 0.5])
def test_dahl_s_move_keeps_the_digits_of_a_small_force(exponent):
    """A thousand moves of 1e-9 F_c / sigma from F_d = 1e-6 F_c, composed: F_d as the closed form of the monotone
    motion (exponent 1: y = y0 exp(-d); 2: y0 / (1 + d y0); 1/2: (sqrt(y0) - d / 2)^2) in 40 digits, to 1e-13
    relative. 1 - y1 computed after y1 kept F_c's rounding each move (1e-16 F_c, 1e-10 of this F_d, a thousand
    times): the harmonic balance's Dahl cycle jumped by 1e-12 between Newton iterations."""
    import mpmath

    from prandtl_fmu.memory.dahl import after

    sigma, level = 400.0, 1.5
    part = ((sigma, level, exponent), np.zeros(1))
    f0, dx, moves = 1e-6 * level, 1e-9 * level / sigma, 1000
    f = f0
    for _ in range(moves):
        f, _slope = after(part, f, dx)
    mpmath.mp.dps = 40
    y0 = 1 - mpmath.mpf(f0) / level
    d = mpmath.mpf(sigma) * mpmath.mpf(dx) * moves / level
    y = {1.0: y0 * mpmath.exp(-d), 2.0: y0 / (1 + d * y0), 0.5: (mpmath.sqrt(y0) - d / 2) ** 2}[exponent]
    wanted = float(level * (1 - y))
    assert abs(f - wanted) <= 1e-13 * abs(wanted), (f, wanted)


def test_dahl_s_force_never_leaves_its_level():
    """Random moves, large and small, from anywhere in [-F_c, F_c]: F_d stays within [-F_c, F_c] to the bit (the
    sum F + s F_c y (1 - y1 / y) rounded one ulp past F_c in 8 % of large moves, a state set_state refuses)."""
    from prandtl_fmu.memory.dahl import after

    rng = np.random.default_rng(7)
    for exponent in (0.5, 1.0, 2.0):
        part = ((400.0, 1.5, exponent), np.zeros(1))
        f = 0.0
        for dx in rng.normal(0.0, 1.0, 4000) * 10.0 ** rng.uniform(-8, 0, 4000):
            f, _slope = after(part, f, float(dx))
            assert -1.5 <= f <= 1.5, (exponent, f)


DAHL_OSCILLATOR = """
[mass]
m = 1.0
x0 = 0.05
[spring]
k0 = 10.0
[dahl]
sigma = 40.0
force = 0.3
exponent = {exponent}
[load]
kind = "harmonic"
amplitude = 0.6
omega = 2.0
"""


@slow
@pytest.mark.parametrize("exponent", [1.0, 2.0])
@pytest.mark.parametrize("stepper", ["implicit", "projected"])
def test_dahl_converges_at_order_one_to_a_stiff_ode_solver(stepper, exponent):
    from scipy.integrate import solve_ivp

    def rhs(t, y):
        x, v, f = y
        slope = 40.0 * max(1.0 - f / 0.3 * np.sign(v), 0.0) ** exponent
        return [v, 0.6 * np.cos(2.0 * t) - 10.0 * x - f, slope * v]

    stop = 6.0
    times = np.arange(0, 151) * 0.04
    exact = solve_ivp(rhs, (0, stop), [0.05, 0.0, 0.0], method="Radau", rtol=1e-11, atol=1e-13, t_eval=times,
                      max_step=1e-3)
    errors = []
    for h in (2e-3, 1e-3, 5e-4):
        r = simulate(scene(DAHL_OSCILLATOR.format(exponent=exponent), stepper, step=h, stop=stop,
                           interval=0.04)).columns()
        errors.append(np.max(np.abs(r["x"] - exact.y[0])))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] < 2e-3
    assert np.all((orders > 0.8) & (orders < 1.25)), (errors, orders)


ALL = """
[mass]
m = 0.8
x0 = 0.1
[spring]
k0 = 5.0
[branches]
k = [2.0, 1.0]
alpha = [0.1, 0.3]
[delay]
gain = 0.7
tau = 0.23
[history]
weight = [0.4]
rate = [1.3]
acts_on = "v"
[dahl]
sigma = 30.0
force = 0.2
[load]
kind = "harmonic"
amplitude = 1.0
omega = 3.0
"""


@slow
def test_the_implicit_energy_residual_stays_the_schemes_own_dissipation():
    """The memory forces' work is booked with the load's: the implicit step's residual is what the scheme
    dissipates (>= 0) and falls like h."""
    residuals = []
    for h in (2e-3, 1e-3):
        r = simulate(scene(ALL, step=h, stop=5.0, interval=0.01), energy=True).columns()
        assert r["energy_residual"].min() >= -1e-12
        assert np.all(np.diff(r["dissipated_sliders"]) >= 0)
        residuals.append(r["energy_residual"][-1])
    assert residuals[1] == pytest.approx(residuals[0] / 2, rel=0.1)


@slow
@pytest.mark.parametrize("stepper", ["implicit", "projected"])
def test_an_element_advanced_in_pieces_saved_and_restored_is_the_run_bit_for_bit(stepper):
    s = scene(ALL, stepper, step=1e-3, stop=2.0, interval=1e-3)
    whole = simulate(s).columns()
    rng = np.random.default_rng(5)
    element = Element(s)
    xs, saved, t = [], None, 0.0
    for _ in range(400):
        steps = int(rng.integers(1, 12))
        if t + steps * 1e-3 > 2.0 + 1e-9:
            break
        checkpoint = element.checkpoint()
        element.advance(steps * 1e-3, 0.0, scene_load=True)
        if rng.random() < 0.2:  # a rejected step: rolled back and taken again
            element.rollback(checkpoint)
            element.advance(steps * 1e-3, 0.0, scene_load=True)
        t += steps * 1e-3
        if saved is None and t > 0.9:
            saved = (json.dumps(element.get_state()), len(xs))
        xs.append((element.time, element.x, element.reaction))
    times = np.round(whole["time"] / 1e-3).astype(int)
    for time, x, reaction in xs:
        j = int(round(time / 1e-3))
        assert times[j] == j
        assert x == whole["x"][j] and reaction == whole["reaction"][j]
    state, count = saved
    other = Element(s)
    other.set_state(json.loads(state))
    for time, x, reaction in xs[count:count + 30]:
        other.advance(time - other.time, 0.0, scene_load=True)
        assert (other.x, other.reaction) == (x, reaction)


@slow
def test_a_state_that_does_not_fit_the_memory_is_refused_and_changes_nothing():
    s = scene(ALL, step=1e-3, stop=1.0)
    element = Element(s)
    element.advance(0.05, 0.0, scene_load=True)
    state = element.get_state()
    before = json.dumps(element.get_state())
    for broken, words in (({**state, "memory": {"delay": state["memory"]["delay"][:-1],
                                                  "history": state["memory"]["history"],
                                                  "dahl": state["memory"]["dahl"]}}, "delay buffer"),
                          ({**state, "memory": {**state["memory"], "dahl": [0.5]}}, "beyond its level"),
                          ({**state, "memory": {"delay": state["memory"]["delay"]}}, "memory of"),
                          ({k: v for k, v in state.items() if k != "memory"}, "not a table")):
        with pytest.raises(ValueError, match=words):
            element.set_state(broken)
        assert json.dumps(element.get_state()) == before


@pytest.mark.parametrize("text, words", [
    ("[mass]\nm = 1.0\n[dahl]\nsigma = 1.0\nforce = 1.0\n[friction]\nalpha = 0.1\n", "keep one"),
    ("[damper]\nc = 1.0\n[delay]\ngain = 1.0\ntau = 0.1\nacts_on = \"v\"\n", "needs \\[mass\\]"),
    ("[spring]\nk0 = 1.0\n[delay]\ngain = -1.0\ntau = 0.1\n", "non-monotone"),
    # with a mass the remedy is the step (a mass does not make that step's equation monotone), not "add [mass]"
    ("[mass]\nm = 1.0\n[delay]\ngain = -1.0\ntau = 1e-4\n", "below the step .*: a \\[solver\\] step no longer than tau"),
    ("[spring]\nk0 = 1.0\n[history]\nweight = [-1.0]\nrate = [1.0]\n", "non-monotone"),
    ("[mass]\nm = 1.0\n[history]\nweight = [1.0, 2.0]\nrate = [1.0]\n", "rate"),
    ("[mass]\nm = 1.0\n[delay]\ngain = 1.0\ntau = 0.0\n", "tau"),
    ("[mass]\nm = 1.0\n[delay]\ngain = 1.0\ntau = 1e300\n", "tau"),
    ("[mass]\nm = 1.0\n[delay]\ngain = 1.0\ntau = 0.1\nlag = 2\n", "unknown key"),
    ("[mass]\nm = 1.0\n[dahl]\nsigma = 1.0\nforce = 1.0\nexponent = 0.0\n", "exponent"),
    ("[mass]\nm = 1.0\n[dahl]\nsigma = 1.0\nforce = 1.0\nkind = \"envelope\"\n", "envelope"),
])
def test_a_scene_that_breaks_a_memory_rule_is_refused_in_one_line(text, words):
    with pytest.raises(SceneError, match=words) as caught:
        scene(text)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize("stepper", ["exact", "verlet", "symplectic"])
def test_the_steppers_without_memory_refuse_it_by_name(stepper):
    with pytest.raises(SceneError, match=r"\[dahl\].*'implicit'"):
        scene("[mass]\nm = 1.0\n[dahl]\nsigma = 1.0\nforce = 1.0\n", stepper)


CONNECTOR = """
[spring]
k0 = 2.0
[dahl]
sigma = 50.0
force = 0.5
exponent = {exponent}
[delay]
gain = 0.4
tau = 0.05
[history]
weight = [0.3, -0.2]
rate = [2.0, 0.0]
[fmu]
causality = "displacement"
"""


@slow
@pytest.mark.parametrize("exponent", [1.0, 2.0])
def test_the_connector_with_memory_is_its_equations_along_a_given_path(exponent):
    """The motion is given: the delayed term is gain x(t - tau) on the path (linear between samples, tau a
    multiple of the sampling: exact), the history the exact convolution of the piecewise linear path, Dahl's force
    the operator of its closed form run reversal to reversal; the stateful Connector equals the whole history
    bit for bit, and its saved state continues bit for bit."""
    from prandtl_fmu.connector import Connector, displacement_response

    s = scene(CONNECTOR.format(exponent=exponent), step=1e-3, stop=1.0)
    h = 0.005
    t = np.arange(1, 401) * h
    x = 0.08 * np.sin(6.0 * t) + 0.03 * np.sin(17.0 * t)
    v = 0.48 * np.cos(6.0 * t) + 0.51 * np.cos(17.0 * t)
    forces = displacement_response(s, x, v, time=t)
    path_t, path_x = np.concatenate([[0.0], t]), np.concatenate([[0.0], x])
    delayed = 0.4 * np.interp(t - 0.05, path_t, path_x, left=0.0)
    history = np.zeros_like(t)
    for p in range(len(t)):
        for weight, rate in ((0.3, 2.0), (-0.2, 0.0)):
            for i in range(p + 1):
                a, b = path_t[p + 1] - path_t[i + 1], path_t[p + 1] - path_t[i]
                y0, y1 = path_x[i], path_x[i + 1]
                if rate == 0.0:
                    history[p] += weight * 0.5 * (b - a) * (y0 + y1)
                    continue
                e_a, e_b = math.exp(-rate * a), math.exp(-rate * b)
                i0, i1 = (e_a - e_b) / rate, (e_a * (rate * a + 1) - e_b * (rate * b + 1)) / rate**2
                history[p] += weight * (y0 * (i1 - a * i0) + y1 * (b * i0 - i1)) / (b - a)
    fd, dahl = 0.0, np.empty_like(t)
    previous = 0.0
    for p in range(len(t)):  # Dahl's closed form over each monotone piece of the path
        dx = path_x[p + 1] - previous
        sign = 1.0 if dx > 0 else -1.0
        y = 1.0 - sign * fd / 0.5
        d = 50.0 * abs(dx) / 0.5
        y1 = y * math.exp(-d) if exponent == 1.0 else y / (1.0 + d * y)
        fd = sign * 0.5 * (1.0 - y1)
        dahl[p], previous = fd, path_x[p + 1]
    np.testing.assert_allclose(forces, 2.0 * x + delayed + history + dahl, rtol=1e-10, atol=1e-13)
    connector = Connector(s)
    for j in range(len(t)):
        connector.move_to(x[j], v[j], t[j])
        assert connector.force == forces[j]
        if j == 150:
            saved = json.dumps(connector.get_state())
    other = Connector(s)
    other.set_state(json.loads(saved))
    for j in range(151, len(t)):
        other.move_to(x[j], v[j], t[j])
        assert other.force == forces[j]
    s_up = 2.0 + 50.0 * max(1.0 - fd / 0.5, 0.0) ** exponent  # the tangent: the spring and Dahl's slope
    assert connector.stiffness(1.0) == pytest.approx(s_up, rel=1e-12)


QUASI_STATIC = """
[spring]
k0 = 1.0
[branches]
k = [2.0, 1.0]
eta = [0.05, 0.2]
[dahl]
sigma = {sigma}
force = 0.5
exponent = 2.0
[delay]
gain = 0.3
tau = 0.0105
[load]
kind = "harmonic"
amplitude = 1.5
omega = 3.0
"""


@slow
def test_the_adversarial_reviews_cases_stay_fixed():
    """Found by a review (each reproduced before its fix): a delay buffer restored with a grid index that does
    not match its time; a connector's history after a restored state and an instant move; times the delay's
    grid cannot carry (negative, beyond 2^52 steps, going back); the Dahl force moved by x1 - x instead of the
    solved increment (with a stiff Dahl law the equilibrium missed by sigma ulp(x)); memory coefficients set on a
    massless element at its start that kept the old equilibrium."""
    from prandtl_fmu.connector import Connector
    from prandtl_fmu.stepping import ElementError

    s = scene(QUASI_STATIC.format(sigma=50.0), step=1e-3, stop=3.0)
    element = Element(s)
    element.advance(2.0, 0.0, scene_load=True)
    state = element.get_state()
    for index in (0.0, 1e6, 1e300):
        forged = json.loads(json.dumps(state))
        forged["memory"]["delay"][0] = index
        with pytest.raises(ValueError, match="grid index"):
            Element(s).set_state(forged)
    # the stiff Dahl law: F = reaction at every step of the quasi-static element, to the springs' rounding
    stiff = simulate(scene(QUASI_STATIC.format(sigma=1e12), step=1e-3, stop=2.0)).columns()
    force = 1.5 * np.cos(3.0 * stiff["time"])
    assert np.max(np.abs(stiff["reaction"] - force)) < 1e-9
    # memory coefficients at the start: the new initial equilibrium, as a fresh element's
    changed = Element(s)
    changed.reset(2.0)
    changed.set_coefficients(dahl_sigma=200.0, delay_gain=0.5)
    fresh = Element(parse_scene(QUASI_STATIC.format(sigma=200.0).replace("gain = 0.3", "gain = 0.5") + """
[solver]
stepper = "implicit"
step = 0.001
stop_time = 3.0
output_interval = 0.001
"""))
    fresh.reset(2.0)
    assert (changed.x, changed.get_state()["memory"]) == (fresh.x, fresh.get_state()["memory"])
    # times the delay cannot carry
    for start, words in ((-5.0, "negative"), (1e16, "2\\^52")):
        late = Element(s)
        late.time = start
        with pytest.raises(ElementError, match=words):
            late.advance(0.01, 0.0)
    back = Element(s)
    back.advance(1.0, 0.0)
    back.time = 0.5
    with pytest.raises(ElementError, match="goes back"):
        back.advance(0.01, 0.0)
    # the connector's history after a restored state and an instant move
    c = scene(CONNECTOR.format(exponent=1.0), step=1e-3, stop=1.0)
    first = Connector(c)
    first.move_to(0.01, 0.1, 0.01)
    first.move_to(0.02, 0.1, 0.02)
    second = Connector(c)
    second.set_state(json.loads(json.dumps(first.get_state())))
    for connector in (first, second):
        connector.move_to(0.03, 0.1, 0.02)
        connector.move_to(0.035, 0.1, 0.03)
    assert second.force == first.force and second.get_state() == first.get_state()
