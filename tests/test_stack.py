"""The memory-stack kernel equals the O(n) play kernel (issue 6: the kernel, not yet in the steppers)."""
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
    params, state, order = stack.prepare(k, eta, u0, x0)
    u = u0.copy()
    # a random load history: bursts of monotone motion of random lengths and sizes, 10^6 moves
    increments = rng.normal(size=10**6) * 10.0 ** rng.uniform(-4, 0, size=10**6)
    flips = np.cumsum(rng.random(10**6) < 0.01) % 2 * 2 - 1
    increments = np.abs(increments) * flips
    forces_stack, forces_play = run_both(params, state, k, eta, u, x0, increments)
    scale = max(1.0, np.abs(forces_play).max())
    assert np.abs(forces_stack - forces_play).max() <= 1e-10 * scale
    expanded = np.empty(n)
    stack.elongations(params, state, expanded)
    np.testing.assert_allclose(expanded, u, rtol=0, atol=1e-10)


def run_both(params, state, k, eta, u, x0, increments):
    from numba import njit

    @njit
    def drive(params, state, k, eta, u, x0, increments, out_stack, out_play):
        for p in range(increments.shape[0]):
            out_stack[p] = stack.move(params, state, increments[p])
            out_play[p] = play.shift(k, eta, u, increments[p])

    out_stack = np.empty(len(increments))
    out_play = np.empty(len(increments))
    drive(params, state, k, eta, u, x0, increments, out_stack, out_play)
    return out_stack, out_play


def test_inadmissible_initial_states_are_refused():
    eta = np.array([0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="1-Lipschitz"):
        stack.prepare(np.ones(3), eta, np.array([0.1, -0.2, 0.3]), 0.0)  # jumps by 0.3 over 0.1


def test_memory_holds_only_the_turning_points_not_wiped_out():
    """A periodic history leaves a bounded stack whatever n (the cost is measured by benchmarks/stack_cost.py)."""
    for n in (10, 100_000):
        eta = np.linspace(0.01, 1.0, n)
        xs = 0.9 * np.cos(0.5 * np.arange(200_001) * 1e-3)
        params, state, _ = stack.prepare(np.full(n, 1.0 / n), eta, np.zeros(n), xs[0])
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
            total += stack.move(params, state, xs[p] - xs[p - 1])
        return total

    return go(params, state, xs)


@pytest.mark.parametrize("stepper", ["projected", "symplectic", "verlet"])
def test_steppers_give_the_same_motion_with_the_stack_over_a_million_steps(stepper):
    from prandtl_fmu import simulate

    from .conftest import make_scene

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
    from prandtl_fmu.driver import choose_branch_kernel

    assert choose_branch_kernel(scene, stepper, energy=False) == "stack"
    fast = simulate(scene, states=True)  # chosen automatically: the stack
    slow = simulate(scene, states=True, branch_kernel="play")
    for name in ("x", "v", "reaction", "u"):
        a, b = getattr(fast, name), getattr(slow, name)
        assert np.abs(a - b).max() <= 1e-10 * max(1.0, np.abs(b).max()), name
    assert np.any((np.abs(slow.u) == eta) & (eta > 0))  # branches slipped
