"""The memory-stack kernel equals the O(n) play kernel: moves, force, energy account, peeks, steppers."""
import numpy as np
import pytest

from prandtl_fmu.kernels import play, stack


def random_branches(rng, n):
    eta = np.sort(rng.uniform(0.0, 1.0, n))
    eta[rng.random(n) < 0.1] = 0.0  # some zero ranges
    eta = np.sort(eta)
    if n > 3:
        eta[2] = eta[1]  # a tie
    k = rng.uniform(0.1, 2.0, n)
    # an admissible profile: 1-Lipschitz in eta, then clipped to [-eta, eta]
    steps = rng.uniform(-1, 1, n) * np.diff(np.concatenate([[0.0], eta]))
    u0 = np.clip(np.cumsum(steps) + rng.uniform(-0.2, 0.2), -eta, eta)
    shuffle = rng.permutation(n)  # the scene's order is not sorted
    return k[shuffle], eta[shuffle], u0[shuffle]


@pytest.mark.parametrize("seed", range(6))
def test_stack_equals_the_play_kernel_over_a_million_moves(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 300))
    k, eta, u0 = random_branches(rng, n)
    x0 = rng.normal()
    params, order = stack.prepare(k, eta, u0)
    state = stack.fresh_state(params, x0)
    u = u0.copy()
    # a random load history: bursts of monotone motion of random lengths and sizes, 10^6 moves
    increments = rng.normal(size=10**6) * 10.0 ** rng.uniform(-4, 0, size=10**6)
    flips = np.cumsum(rng.random(10**6) < 0.01) % 2 * 2 - 1
    increments = np.abs(increments) * flips
    energy_stack, energy_play = np.zeros(3), np.zeros(3)
    forces_stack, forces_play = run_both(params, state, k, eta, u, increments, energy_stack, energy_play)
    scale = max(1.0, np.abs(forces_play).max())
    assert np.abs(forces_stack - forces_play).max() <= 1e-10 * scale
    # the sliders' dissipation and the stored energy, from prefix sums: the same
    assert energy_play[1] > 0
    assert abs(energy_stack[1] - energy_play[1]) <= 1e-10 * energy_play[1]
    assert stack.stored_energy(params, state) == pytest.approx(play.stored_energy(k, u), rel=1e-10, abs=1e-12)
    expanded = np.empty(n)
    stack.elongations(params, state, expanded)
    np.testing.assert_allclose(expanded, u, rtol=0, atol=1e-10)


def run_both(params, state, k, eta, u, increments, energy_stack, energy_play):
    from numba import njit

    @njit
    def drive(params, state, k, eta, u, increments, out_stack, out_play, energy_stack, energy_play):
        for p in range(increments.shape[0]):
            out_stack[p] = stack.move(params, state, increments[p], energy_stack)
            out_play[p] = play.move(k, eta, u, increments[p], energy_play)

    out_stack = np.empty(len(increments))
    out_play = np.empty(len(increments))
    drive(params, state, k, eta, u, increments, out_stack, out_play, energy_stack, energy_play)
    return out_stack, out_play


@pytest.mark.parametrize("seed", range(4))
def test_peek_equals_the_play_kernel_piece(seed):
    """What `implicit` asks of the branches at a trial increment: force, sticking stiffness, room to the
    next kink; the stack answers without moving."""
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(2, 200))
    k, eta, u0 = random_branches(rng, n)
    params, _ = stack.prepare(k, eta, u0)
    state = stack.fresh_state(params, 0.3)
    u = u0.copy()
    checked = 0
    for _ in range(300):
        dx = rng.normal() * 10.0 ** rng.uniform(-3, 0)
        stack.move(params, state, dx, None)
        play.shift(k, eta, u, dx)
        before = state[:stack.used(state)].copy()
        for direction in (1.0, -1.0):
            for trial in (0.0, direction * 10.0 ** rng.uniform(-4, 0)):
                got = stack.peek(params, state, trial, direction)
                want = play.piece(k, eta, u, trial, direction)
                assert got[0] == pytest.approx(want[0], abs=1e-10)
                assert got[1] == pytest.approx(want[1], rel=1e-10, abs=1e-12)
                assert got[2] == pytest.approx(want[2], rel=1e-9, abs=1e-12)
                checked += 1
        np.testing.assert_array_equal(state[:len(before)], before)  # peeking moves nothing (free rows are scratch)
        assert stack.used(state) == len(before)
    assert checked == 1200


def test_inadmissible_initial_states_are_refused():
    eta = np.array([0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="1-Lipschitz"):
        stack.prepare(np.ones(3), eta, np.array([0.1, -0.2, 0.3]))  # jumps by 0.3 over 0.1


def test_memory_holds_only_the_turning_points_not_wiped_out():
    """A periodic history leaves a bounded stack whatever n (the cost is measured by benchmarks/stack_cost.py)."""
    for n in (10, 100_000):
        eta = np.linspace(0.01, 1.0, n)
        xs = 0.9 * np.cos(0.5 * np.arange(200_001) * 1e-3)
        params, _ = stack.prepare(np.full(n, 1.0 / n), eta, np.zeros(n))
        state = stack.fresh_state(params, xs[0])
        total = drive_only(params, state, xs)
        assert np.isfinite(total)
        assert int(state[stack.COUNT]) <= 3
        u = np.empty(n)
        stack.elongations(params, state, u)
        assert np.all(np.abs(u) <= eta)


def drive_only(params, state, xs):
    from numba import njit

    @njit
    def go(params, state, xs):
        total = 0.0
        for p in range(1, xs.shape[0]):
            total += stack.move(params, state, xs[p] - xs[p - 1], None)
        return total

    return go(params, state, xs)


@pytest.mark.parametrize("stepper", ["projected", "implicit", "symplectic", "verlet"])
def test_steppers_give_the_same_motion_with_the_stack_over_a_million_steps(stepper):
    from prandtl_fmu import simulate

    from tests.conftest import make_scene

    rng = np.random.default_rng(hash(stepper) % 2**32)
    n = 300
    k, eta, u0 = random_branches(rng, n)
    times = np.sort(rng.uniform(0, 1000, 40))
    scene = make_scene(
        mass={"m": 1.0, "x0": float(rng.normal(0, 0.1)), "v0": 0.0}, cubic=None, damper={"c": 0.02},
        spring={"k0": 0.05}, branches={"k": k / n * 50, "eta": eta, "u0": u0},
        load={"kind": "table", "time": np.concatenate([[0.0], times]),
              "force": rng.uniform(-1.5, 1.5, len(times) + 1)},
        solver={"stepper": stepper, "step": 1e-3, "stop_time": 1000.0, "output_interval": 1.0})
    from prandtl_fmu.compiled import choose_branch_kernel

    assert choose_branch_kernel(scene, stepper) == "stack"
    fast = simulate(scene, states=True, energy=True)  # chosen automatically: the stack
    slow = simulate(scene, states=True, energy=True, branch_kernel="play")
    for name in ("x", "v", "reaction", "u"):
        a, b = getattr(fast, name), getattr(slow, name)
        assert np.abs(a - b).max() <= 1e-10 * max(1.0, np.abs(b).max()), name
    for name, b in slow.energy.items():
        a = fast.energy[name]
        assert np.abs(a - b).max() <= 1e-10 * max(1.0, np.abs(b).max()), name
    assert np.any((np.abs(slow.u) == eta) & (eta > 0))  # branches slipped


def test_element_moves_between_the_kernels_when_the_stepper_changes():
    """An Element holds n = 100 branches in the stack; `exact` needs one elongation per branch, so switching
    to it expands the stack, and switching back folds them again: the motion is the one of the O(n) kernel."""
    from prandtl_fmu import Element, load_scene

    from tests.conftest import SCENES

    scene = load_scene(SCENES / "paper-section-8.toml")
    fast = Element(scene, stepper="projected")
    slow = Element(scene, stepper="projected", branch_kernel="play")
    assert (fast.branch_kernel, slow.branch_kernel) == ("stack", "play")
    for stepper in ("projected", "exact", "implicit", "verlet"):
        fast.set_stepper(stepper)
        slow.set_stepper(stepper)
        assert fast.branch_kernel == ("play" if stepper == "exact" else "stack")
        for k in range(40):
            force = 0.45 * np.cos(0.5 * fast.time)
            fast.advance(0.5, force)
            slow.advance(0.5, force)
        assert fast.x == pytest.approx(slow.x, abs=1e-10) and fast.reaction == pytest.approx(slow.reaction, abs=1e-10)
        for name, value in slow.energy().items():  # exact books no energy: NaN from then on, in both
            assert fast.energy()[name] == pytest.approx(value, rel=1e-9, abs=1e-10, nan_ok=True), name
    # plain-data state of the stack: restored into another element, the same continuation bit for bit
    state = fast.get_state()
    other = Element(scene, stepper="verlet")
    other.set_state(state)
    for element in (fast, other):
        element.advance(3.7, 0.2)
    assert (fast.x, fast.v, fast.reaction) == (other.x, other.v, other.reaction)
    broken = dict(state, u=state["u"][:-1])
    with pytest.raises(ValueError, match="memory-stack state"):
        other.set_state(broken)
