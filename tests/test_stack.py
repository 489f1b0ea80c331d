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
    x_end = x0 + increments.sum()
    expanded = np.empty(n)
    stack.elongations(params, state, x_end, expanded)
    np.testing.assert_allclose(expanded, u[order], rtol=0, atol=1e-10)


def run_both(params, state, k, eta, u, x0, increments):
    from numba import njit

    @njit
    def drive(params, state, k, eta, u, x0, increments, out_stack, out_play):
        x = x0
        for p in range(increments.shape[0]):
            x_new = x + increments[p]
            out_stack[p] = stack.move(params, state, x, x_new)
            out_play[p] = play.shift(k, eta, u, x_new - x)
            x = x_new

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
        params, state, _ = stack.prepare(np.full(n, 1.0 / n), eta, np.zeros(n), 0.0)
        xs = 0.9 * np.cos(0.5 * np.arange(200_001) * 1e-3)
        stack.move(params, state, 0.0, xs[0])
        total = drive_only(params, state, xs)
        assert np.isfinite(total)
        assert int(state[stack.COUNT]) <= 3
        u = np.empty(n)
        stack.elongations(params, state, xs[-1], u)
        assert np.all(np.abs(u) <= eta)


def drive_only(params, state, xs):
    from numba import njit

    @njit
    def go(params, state, xs):
        total = 0.0
        for p in range(1, xs.shape[0]):
            total += stack.move(params, state, xs[p - 1], xs[p])
        return total

    return go(params, state, xs)
