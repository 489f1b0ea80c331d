"""The continuous Prandtl element (infinitely many branches) and the sampled spectrum converging to it."""
import numpy as np
import pytest

from prandtl_fmu import simulate
from prandtl_fmu.effects import sample_spectrum
from prandtl_fmu.kernels import stack
from prandtl_fmu.scene import SceneError

from tests.conftest import make_scene

KAPPA, A, B = 1.0, 0.1, 1.1  # the paper's section 8: k(s) = 1, eta(s) = s + 0.1


def virgin(x, kappa=KAPPA, a=A, b=B):
    """Closed form of the continuum's force on its virgin curve: kappa * integral_0^1 min(x, eta(s)) ds."""
    x = np.abs(x)
    s = np.clip((x - a) / (b - a), 0.0, 1.0)
    return kappa * (a * s + 0.5 * (b - a) * s * s + x * (1.0 - s))


def drive(params, state, xs, energy):
    from numba import njit

    @njit
    def go(params, state, xs, energy, out):
        out[0] = stack.force(params, state)
        for p in range(1, xs.shape[0]):
            out[p] = stack.move(params, state, xs[p] - xs[p - 1], energy)

    out = np.empty(len(xs))
    go(params, state, xs, energy, out)
    return out


def test_virgin_curve_and_masing_branches_in_closed_form():
    """Loading from the virgin state follows integral min(x, eta); after a reversal at X the force is
    F(X) - 2 F_virgin((X - x) / 2) (Masing's rule, which the Prandtl continuum obeys exactly)."""
    params = stack.continuum(KAPPA, A, B)
    state = stack.fresh_state(params, 0.0)
    up = np.linspace(0.0, 0.8, 4001)
    down = np.linspace(0.8, -0.5, 6001)
    forces_up = drive(params, state, up, None)
    np.testing.assert_allclose(forces_up, virgin(up), rtol=0, atol=1e-13)
    state_at_top = state.copy()
    forces_down = drive(params, state, down, None)
    np.testing.assert_allclose(forces_down, virgin(0.8) - 2 * virgin((0.8 - down) / 2), rtol=0, atol=1e-13)
    # back up to 0.8: the minor loop closes and the memory of -0.5 is wiped out (return point memory)
    forces_back = drive(params, state, np.linspace(-0.5, 0.8, 100), None)
    assert forces_back[-1] == pytest.approx(virgin(0.8), abs=1e-13)
    assert int(state[stack.COUNT]) == int(state_at_top[stack.COUNT])


def test_energy_account_of_the_continuum_equals_the_loop_area():
    """Over closed cycles the work put in (the loop area, integral F dx) is what the sliders dissipated,
    and the stored energy integral k u^2 / 2 comes back to its value."""
    params = stack.continuum(KAPPA, A, B)
    state = stack.fresh_state(params, 0.0)
    drive(params, state, np.linspace(0.0, 0.9, 1000), None)  # to the first turning point
    stored0 = stack.stored_energy(params, state)
    cycle = 0.9 * np.cos(np.linspace(0.0, 6 * np.pi, 300_001))  # three cycles
    energy = np.zeros(3)
    forces = drive(params, state, cycle, energy)
    work = np.sum(0.5 * (forces[1:] + forces[:-1]) * np.diff(cycle))  # trapezoid: O(dx^2)
    assert energy[1] > 0.1
    assert energy[1] == pytest.approx(work, rel=1e-8)
    assert stack.stored_energy(params, state) == pytest.approx(stored0, rel=1e-12)
    # stored energy from its own integral of the profile u(s)
    s = (np.arange(200_000) + 0.5) / 200_000
    u = np.empty_like(s)
    stack.profile(params, state, s, u)
    assert stack.stored_energy(params, state) == pytest.approx(np.mean(0.5 * KAPPA * u * u), rel=1e-9)


def test_the_continuum_is_the_limit_of_the_sampled_kernels():
    """Move for move, the sampled branches' force tends to the continuum's: right end points like 1/n,
    midpoints like 1/n^2 (kernels only, on a random history)."""
    rng = np.random.default_rng(7)
    xs = np.cumsum(rng.normal(0, 0.02, 20_000))
    xs = 1.2 * xs / np.abs(xs).max()
    params = stack.continuum(KAPPA, A, B)
    exact = drive(params, stack.fresh_state(params, 0.0), xs, None)
    for rule, order in (("right", 1), ("midpoint", 2)):
        errors = []
        ns = [16, 64, 256, 1024]
        for n in ns:
            branches = sample_spectrum(n, KAPPA, (A, B), rule)
            sampled, _ = stack.prepare(branches.stiffness, branches.yield_displacement, branches.u0)
            errors.append(np.abs(drive(sampled, stack.fresh_state(sampled, 0.0), xs, None) - exact).max())
        slope = -np.polyfit(np.log(ns), np.log(errors), 1)[0]
        assert order - 0.15 < slope < order + 0.3, (rule, errors)


def continuum_scene(branches, stop_time=100.0, stepper="verlet"):
    return make_scene(spring={"k0": 0.0}, cubic=None, damper=None, branches=branches,
                      load={"kind": "harmonic", "amplitude": 0.45, "omega": 0.5},
                      solver={"stepper": stepper, "step": 1e-3, "stop_time": stop_time, "output_interval": 0.1})


@pytest.fixture(scope="module")
def continuum_run():
    return simulate(continuum_scene({"continuum": True, "k_total": KAPPA, "eta_range": [A, B]}), energy=True)


@pytest.mark.parametrize("rule, order", [("right", 1), ("midpoint", 2)])
def test_x_of_T_converges_to_the_continuum_as_n_grows(continuum_run, rule, order):
    """The paper's section 8 element, with the same stepper and step: x(T) of n sampled branches tends to
    the continuum's like 1/n (right end points, eq. 7.19, the default) or 1/n^2 (midpoints)."""
    ns = [10, 20, 40, 80, 160, 320]
    errors_end, errors_max = [], []
    for n in ns:
        scene = continuum_scene({"count": n, "k_total": KAPPA, "eta_range": [A, B], "sampling": rule})
        result = simulate(scene)
        errors_end.append(abs(result.x[-1] - continuum_run.x[-1]))
        errors_max.append(np.abs(result.x - continuum_run.x).max())
    for errors in (errors_end, errors_max):
        slope = -np.polyfit(np.log(ns), np.log(errors), 1)[0]
        assert order - 0.2 < slope < order + 0.3, (rule, errors)
    assert errors_max[-1] < (5e-2 if rule == "right" else 3e-5)


def test_continuum_run_keeps_its_energy_balance(continuum_run):
    energy = continuum_run.energy
    assert energy["dissipated_sliders"][-1] > 1.0
    # verlet's residual is O(h^2): tiny against what the sliders dissipated
    assert np.abs(energy["energy_residual"]).max() < 1e-5 * energy["dissipated_sliders"][-1]
    assert np.all(np.diff(energy["dissipated_sliders"]) >= 0)


def test_memory_of_the_continuum_stays_bounded():
    """A free decay from eta_min = 0 reverses for ever without wiping out its turning points: past
    CONTINUUM_PIECES pieces the narrowest is merged, and the force stays that of fine sampling."""
    params = stack.continuum(1.0, 0.0, 1.0)
    state = stack.fresh_state(params, 0.0)
    turns = 0.8 * (-1.0) ** np.arange(3 * stack.CONTINUUM_PIECES) / (1 + 0.01 * np.arange(3 * stack.CONTINUUM_PIECES))
    xs = np.concatenate([[0.0], turns])
    forces = drive(params, state, xs, None)
    assert int(state[stack.COUNT]) < stack.CONTINUUM_PIECES + 1
    branches = sample_spectrum(20_000, 1.0, (0.0, 1.0), "midpoint")
    sampled, _ = stack.prepare(branches.stiffness, branches.yield_displacement, branches.u0)
    reference = drive(sampled, stack.fresh_state(sampled, 0.0), xs, None)
    assert np.abs(forces - reference).max() < 1e-7
    assert len(state) == stack.HEADER + stack.ROW * (stack.CONTINUUM_PIECES + 1)  # no growth


def test_scene_keys_of_the_spectrum():
    scene = continuum_scene({"continuum": True, "k_total": 2.0, "eta_range": [0.0, 0.5]})
    assert scene.branches.continuum and scene.branches.stiffness_sum == 2.0 and scene.branches.is_linear
    assert scene.branches.strength == pytest.approx(0.5)
    mid = continuum_scene({"count": 4, "k_total": 2.0, "eta_range": [0.0, 1.0], "sampling": "midpoint"})
    np.testing.assert_allclose(mid.branches.yield_displacement, [0.125, 0.375, 0.625, 0.875])
    right = continuum_scene({"count": 4, "k_total": 2.0, "eta_range": [0.0, 1.0]})  # the default: eq. (7.19)
    np.testing.assert_allclose(right.branches.yield_displacement, [0.25, 0.5, 0.75, 1.0])
    np.testing.assert_allclose(right.branches.stiffness, 0.5)
    off = continuum_scene({"continuum": False, "count": 4, "k_total": 2.0, "eta_range": [0.0, 1.0]})
    assert not off.branches.continuum and off.branches.n == 4


@pytest.mark.parametrize("branches, culprit", [
    ({"continuum": True, "count": 10, "k_total": 1.0, "eta_range": [0.1, 1.1]}, "count: unknown key"),
    ({"continuum": True, "k_total": 1.0, "eta_range": [0.1, 1.1], "u0": [0.0]}, "u0: unknown key"),
    ({"continuum": True, "k_total": 1.0, "eta_range": [0.5, 0.5]}, "eta_range: the continuum needs a < b"),
    ({"continuum": True, "k_total": 1.0}, "eta_range: missing"),
    ({"continuum": "yes", "k_total": 1.0, "eta_range": [0.1, 1.1]}, "continuum: must be true or false"),
    ({"count": 3, "k_total": 1.0, "eta_range": [0.1, 1.1], "sampling": "left"}, "sampling: must be one of"),
    ({"k": [1.0], "eta": [0.1], "sampling": "midpoint"}, "sampling: unknown key"),
])
def test_spectrum_errors_name_the_key(branches, culprit):
    with pytest.raises(SceneError, match=culprit):
        continuum_scene(branches)


@pytest.mark.parametrize("stepper", ["implicit", "exact"])
def test_steppers_that_cannot_take_the_continuum_say_so(stepper):
    with pytest.raises(SceneError, match=f"stepper: '{stepper}'.*continuum"):
        continuum_scene({"continuum": True, "k_total": 1.0, "eta_range": [0.1, 1.1]}, stepper=stepper)


def test_states_of_the_continuum_are_refused_clearly():
    scene = continuum_scene({"continuum": True, "k_total": 1.0, "eta_range": [0.1, 1.1]}, stop_time=1.0)
    with pytest.raises(ValueError, match="continuum has no list of elongations"):
        simulate(scene, states=True)


@pytest.mark.parametrize("stepper", ["projected", "symplectic", "verlet"])
def test_every_stepper_that_takes_the_continuum_agrees_with_fine_sampling(stepper):
    # (both with the energy account, as the FMUs' tests run these loops: one compiled loop each)
    continuum = simulate(continuum_scene({"continuum": True, "k_total": KAPPA, "eta_range": [A, B]},
                                         stop_time=30.0, stepper=stepper), energy=True)
    sampled = simulate(continuum_scene({"count": 2000, "k_total": KAPPA, "eta_range": [A, B],
                                        "sampling": "midpoint"}, stop_time=30.0, stepper=stepper), energy=True)
    assert np.abs(continuum.x - sampled.x).max() < 1e-6
    assert np.abs(continuum.reaction - sampled.reaction).max() < 1e-6


def test_an_element_of_the_continuum_cannot_be_forced_onto_the_per_branch_kernel():
    from prandtl_fmu import Element

    scene = continuum_scene({"continuum": True, "k_total": 1.0, "eta_range": [0.1, 1.1]}, stop_time=1.0)
    with pytest.raises(ValueError, match="no O\\(n\\) kernel"):
        Element(scene, branch_kernel="play")
    element = Element(scene, stepper="projected")
    element.set_stepper("verlet")
    element.advance(1.0, 0.3)
    assert element.branch_kernel == "stack" and element.elongations() is None and element.x > 0
