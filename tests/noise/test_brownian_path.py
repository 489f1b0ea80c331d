"""The Brownian path of ``prandtl_fmu.noise``: a function of (seed, time) only, additive bit for bit, Brownian in
law, from a generator with Random123's known answers, at a bounded and amortized O(1) cost.

The statistical checks are seeded (the seeds are the sample), with bounds at 5 standard deviations of the
sampling distribution (or a p-value of 1e-6 for Kolmogorov-Smirnov and chi-square): a correct path fails
one of them with a probability below 1e-4; with 4000 seeds a variance wrong by 15 % or more fails.
"""
import math

import numpy as np
import pytest
from numba import njit

from prandtl_fmu import noise
from prandtl_fmu.noise import brownian, increment, new_cache

try:
    from scipy import stats
except ImportError:  # the moments and the chi-square statistic's own bound still hold
    stats = None

P_MIN = 1e-6
SEEDS = np.arange(4000, dtype=np.int64) * 7919 + 12345  # distinct, spread: no neighbouring-key luck

# times of every kind: 0, dyadic, non-dyadic, below 1 unit, across units, large, tiny gaps, near the horizon
TIMES = np.array([0.0, 1e-300, 2.0 ** -60, 1e-9, 0.1, 0.25, 0.3, 0.5, 0.5 + 1e-9, 0.7, 0.999999, 1.0, 1.5,
                  2.7, 3.4, 7.0 + 2.0 ** -40, 123.456, 1e6, 1e6 + 0.123, 1e6 + 0.123 + 1e-9, 2.0 ** 40 + 0.5,
                  2.0 ** 52 - 0.5])


def _across_seeds(seeds, a, b):
    """W(b) - W(a) for each seed, each from a new cache."""
    return np.array([increment(seed, a, b, new_cache()) for seed in seeds])


def _values_across_seeds(seeds, times):
    """W(times[j]) for each seed (rows), one cache per seed, the times in the given order."""
    return np.array([noise.brownian_path(seed, times, new_cache()) for seed in seeds])


def _forward(seed, t0, h, n, cache):
    """The increments over [t0 + i h, t0 + (i + 1) h], i < n, stepping forward with one cache."""
    times = t0 + np.arange(n + 1) * h
    return np.array([increment(seed, times[i], times[i + 1], cache) for i in range(n)])


def _normal_sample(sample, variance):
    """A sample of N(0, variance): Kolmogorov-Smirnov, and the mean and variance within 5 sigma."""
    n = sample.size
    if stats is not None:
        assert stats.kstest(sample / math.sqrt(variance), "norm").pvalue > P_MIN
    assert abs(sample.mean()) < 5.0 * math.sqrt(variance / n)
    assert abs(sample.var() / variance - 1.0) < 5.0 * math.sqrt(2.0 / n)


def _evenly_filled(counts):
    """Equally likely bins: chi-square p-value above P_MIN (scipy), else the statistic within 5 sigma of its
    mean (df, variance 2 df)."""
    if stats is not None:
        return stats.chisquare(counts).pvalue > P_MIN
    expected = counts.sum() / counts.size
    statistic = float(np.sum((counts - expected) ** 2) / expected)
    return statistic < counts.size - 1 + 5.0 * math.sqrt(2.0 * (counts.size - 1))


def _uncorrelated(x, y):
    assert abs(np.corrcoef(x, y)[0, 1]) < 5.0 / math.sqrt(x.size)


# --- the generator ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("counter, key, expected", [  # Random123's kat_vectors
    ((0, 0, 0, 0), (0, 0), (0x6627E8D5, 0xE169C58D, 0xBC57AC4C, 0x9B00DBD8)),
    ((0xFFFFFFFF,) * 4, (0xFFFFFFFF,) * 2, (0x408F276D, 0x41C83B0E, 0xA20BC7C6, 0x6D5451FD)),
    ((0x243F6A88, 0x85A308D3, 0x13198A2E, 0x03707344), (0xA4093822, 0x299F31D0),
     (0xD16CFE09, 0x94FDCCEB, 0x5001E420, 0x24126EA1)),
])
def test_philox_known_answers(counter, key, expected):
    out = noise.philox4x32_10(*[np.uint64(word) for word in counter + key])
    assert tuple(int(word) for word in out) == expected


@njit
def _uniforms(seed, stream, n):
    out = np.empty(n)
    for i in range(n):
        out[i] = noise.uniform(seed, stream, i)
    return out


@njit
def _normals(seed, stream, n):
    out = np.empty(n)
    for i in range(n):
        out[i] = noise.normal(seed, stream, i)
    return out


@pytest.mark.parametrize("seed, stream", [(0, 0), (1, 1 << 52), (-1, -(1 << 63)), (2 ** 62 + 3, 12345)])
def test_uniforms_fill_the_bins(seed, stream):
    bins = 64
    u = _uniforms(seed, stream, 1 << 17)
    assert u.min() >= 0.0 and u.max() < 1.0
    counts = np.bincount((u * bins).astype(np.int64), minlength=bins)
    assert _evenly_filled(counts)
    # consecutive counters are not correlated (the lag-1 pairs fill a 16 x 16 grid evenly)
    pairs = np.bincount((u[:-1] * 16).astype(np.int64) * 16 + (u[1:] * 16).astype(np.int64), minlength=256)
    assert _evenly_filled(pairs)


def test_normals_are_standard_in_the_core_the_wedges_and_the_tail():
    """The ziggurat's three paths: Kolmogorov-Smirnov, the fourth moment, and the mass beyond thresholds
    inside the layers, at the base layer's edge R = 3.44 (the tail algorithm) and beyond."""
    n = 1 << 20
    z = _normals(7, 3, n)
    _normal_sample(z, 1.0)
    assert abs(np.mean(z ** 4) - 3.0) < 5.0 * math.sqrt(96.0 / n)  # Var z^4 = 105 - 9
    for threshold in (0.2723, 1.0, 2.5, noise._ZIG_R, 4.0):
        p = math.erfc(threshold / math.sqrt(2.0))
        count = np.count_nonzero(np.abs(z) > threshold)
        assert abs(count - n * p) < 5.0 * math.sqrt(n * p * (1.0 - p)) + 1.0, threshold
    assert np.count_nonzero(z > noise._ZIG_R) > 0 and np.count_nonzero(z < -noise._ZIG_R) > 0


def test_exp_and_log_without_libm():
    x = np.linspace(-40.0, 40.0, 2001)
    assert np.max(np.abs([noise._exp(v) / math.exp(v) - 1.0 for v in x])) < 4e-16
    rng = np.random.default_rng(3)
    for bits in list(rng.integers(0, 1 << 53, 2000)) + [0, 1, 2, (1 << 53) - 1]:
        assert abs(noise._log_uniform(np.uint64(bits)) - math.log((int(bits) + 1) * 2.0 ** -53)) < 8e-15


def test_distinct_seeds_give_uncorrelated_paths():
    grid = np.arange(1, 2001) * 0.37  # increments over [0.37 i, 0.37 (i + 1)], within and across units
    for seed in (0, 1, 2, 1 << 32, -5):
        one = np.diff(_values_across_seeds(np.array([seed], dtype=np.int64), grid)[0])
        other = np.diff(_values_across_seeds(np.array([seed + 1], dtype=np.int64), grid)[0])
        _uncorrelated(one, other)
        assert not np.array_equal(one, other)


# --- a function of (seed, time) only ----------------------------------------------------------------------------

@pytest.mark.parametrize("seed", [0, 1, 42, -7, 2 ** 63 - 1])
def test_the_same_seed_gives_the_same_path_in_any_order_with_any_cache(seed):
    reference = np.array([brownian(seed, t, new_cache()) for t in TIMES])
    rng = np.random.default_rng(seed & 0xFFFF)
    used = new_cache()
    for t in rng.uniform(0, 50, 100):  # a cache that held other paths (a rolled-back FMU's, later in time)
        brownian(seed, t, used)
    for order in [np.arange(TIMES.size), np.arange(TIMES.size)[::-1]] + [rng.permutation(TIMES.size)
                                                                            for _ in range(5)]:
        values = np.empty(TIMES.size)
        for i in order:
            values[i] = brownian(seed, TIMES[i], used)
        assert np.array_equal(values, reference)
    other_seed = new_cache()
    brownian(seed ^ 1, 0.3, other_seed)  # a cache of another seed is reset, not trusted
    assert np.array_equal([brownian(seed, t, other_seed) for t in TIMES], reference)
    assert np.array_equal(noise.brownian_path(seed, TIMES[::-1].copy(), new_cache()), reference[::-1])
    zeros = np.zeros(noise.CACHE_SIZE, dtype=np.int64)  # an all-zero array is a new cache
    assert np.array_equal([brownian(seed, t, zeros) for t in TIMES], reference)


def test_a_rolled_back_run_redraws_nothing():
    """A co-simulation steps to t = 3, is rolled back to t = 1 (its cache now holds later paths) and steps again,
    with another step size: the same increments as a fresh run over the same steps."""
    h = 2.0 ** -7
    cache = new_cache()
    first = _forward(21, 1.0, h, 256, cache)
    again = _forward(21, 1.0, h, 256, cache)  # the stale cache of the first pass
    assert np.array_equal(first, again)
    assert np.array_equal(_forward(21, 1.0, 0.37 * h, 100, cache), _forward(21, 1.0, 0.37 * h, 100, new_cache()))
    halves = _forward(21, 1.0, 0.5 * h, 512, cache)
    assert np.array_equal(first, halves[0::2] + halves[1::2])


def test_the_path_is_continuous_in_time_and_defined_everywhere():
    cache = new_cache()
    assert brownian(3, 0.0, cache) == 0.0 and brownian(3, -1.0, cache) == 0.0 and brownian(3, math.nan, cache) == 0.0
    assert brownian(3, 2.0 ** 52, cache) == brownian(3, 1e300, cache) == brownian(3, math.inf, cache)
    for k in (1.0, 2.0, 1000.0, 2.0 ** 20):  # a unit's end: the fine path meets the next unit's start
        assert abs(increment(3, k - 2.0 ** -30, k, cache)) < 1e-3
        assert abs(increment(3, k, k + 2.0 ** -30, cache)) < 1e-3
        assert brownian(3, k, cache) == brownian(3, k, new_cache())
    # an increment beyond 2^15 units is the difference rounded once (not in fine quanta)
    assert increment(3, 0.0, 2.0 ** 50, cache) == pytest.approx(brownian(3, 2.0 ** 50, cache), rel=1e-15, abs=0)
    assert abs(brownian(3, 2.0 ** 50, cache)) > 2.0 ** 15
    # below the grid of 2^-52 units the path is constant; at the grid it moves
    assert brownian(3, 2.0 ** -53, cache) == brownian(3, 0.0, cache)
    assert brownian(3, 2.0 ** -52, cache) != 0.0


# --- increments add up bit for bit -------------------------------------------------------------------------------

def test_an_increment_is_the_sum_of_its_halves_bit_for_bit():
    rng = np.random.default_rng(2)
    cache = new_cache()
    for _ in range(3000):
        seed = int(rng.integers(-2 ** 63, 2 ** 63 - 1))
        a = float(rng.choice([rng.uniform(0, 2), rng.uniform(0, 1e6), rng.uniform(0, 1e-6)]))
        b = a + float(rng.choice([1e-9, 1e-3, rng.uniform(0, 1), rng.uniform(0, 10)]))
        m = float(rng.choice([0.5 * (a + b), rng.uniform(a, b)]))
        whole = increment(seed, a, b, cache)
        assert whole == increment(seed, a, m, cache) + increment(seed, m, b, cache)
        assert whole == -increment(seed, b, a, cache)
        assert whole == increment(seed, a, b, new_cache())


@pytest.mark.parametrize("h", [2.0 ** -10, 1e-3, 0.37])
def test_steps_h_and_half_h_see_the_same_path(h):
    """Stepping forward by h/2 and by h: each step's increment is the sum of its two halves exactly, and the
    sum over any run of steps is the increment over the run."""
    n = 2000
    coarse = _forward(11, 0.25, h, n, new_cache())
    fine = _forward(11, 0.25, 0.5 * h, 2 * n, new_cache())
    times = 0.25 + np.arange(n + 1) * h
    assert np.array_equal(times, 0.25 + np.arange(0, 2 * n + 1, 2) * (0.5 * h))  # the two grids meet
    assert np.array_equal(coarse, fine[0::2] + fine[1::2])
    total = 0.0
    for step in coarse[:200]:  # partial sums stay exact while below 32 units
        total += step
    assert total == increment(11, times[0], times[200], new_cache())


# --- the law -----------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("a, b", [(0.3, 0.7), (0.0, 0.1), (2.7, 3.4), (0.5, 0.5 + 1e-9),
                                  (1e6 + 0.123, 1e6 + 0.123 + 1e-9), (5.0, 5.0 + 2.0 ** -20), (17.25, 4113.9),
                                  (0.0, 1e6), (2.0 ** 40 + 0.5, 2.0 ** 40 + 1.75)])
def test_increments_are_centred_normals_of_variance_b_minus_a(a, b):
    _normal_sample(_across_seeds(SEEDS, a, b), b - a)  # b - a: the doubles' own difference (exact here)


def test_increments_over_disjoint_intervals_are_uncorrelated():
    for first, second in [((0.2, 0.5), (0.5, 0.9)), ((3.1, 3.3), (7.25, 8.0)), ((0.0, 1e-9), (1e-9, 0.5)),
                          ((1e6, 1e6 + 1e-3), (1e6 + 1e-3, 1e6 + 2e-3)), ((0.0, 1.0), (1.0, 1e6))]:
        _uncorrelated(_across_seeds(SEEDS, *first), _across_seeds(SEEDS, *second))


@pytest.mark.parametrize("a, b", [(0.3, 0.7), (0.0, 3.0), (2.9, 3.15), (1e6 + 0.1, 1e6 + 0.1 + 3e-9), (10.0, 1e5)])
def test_the_midpoint_follows_the_bridge(a, b):
    """Given W(a) and W(b), W((a + b) / 2) is normal with mean (W(a) + W(b)) / 2 and variance (b - a) / 4,
    at times that are not the tree's own points as well."""
    m = 0.5 * (a + b)
    values = _values_across_seeds(SEEDS, np.array([a, b, m]))
    residual = values[:, 2] - (values[:, 0] + (m - a) / (b - a) * (values[:, 1] - values[:, 0]))
    _normal_sample(residual, (m - a) * (b - m) / (b - a))
    _uncorrelated(residual, values[:, 1] - values[:, 0])
    if a > 0:
        _uncorrelated(residual, values[:, 0])


def test_the_value_at_a_large_time_has_its_variance():
    _normal_sample(_values_across_seeds(SEEDS, np.array([1e6 + 0.5]))[:, 0], 1e6 + 0.5)


# --- the cost, counted (the times are in benchmarks/noise_cost.py) -------------------------------------------------

def _draws_per_call(seed, times, cache):
    worst = 0
    for t in times:
        before = cache[noise.DRAWS]
        brownian(seed, t, cache)
        worst = max(worst, cache[noise.DRAWS] - before)
    return worst


def test_the_work_of_one_call_is_bounded():
    rng = np.random.default_rng(5)
    times = np.concatenate([rng.uniform(0, 2.0 ** 52, 2000), rng.uniform(0, 1, 2000), TIMES,
                            1e6 + rng.uniform(0, 1e-9, 100)])
    assert _draws_per_call(9, times, new_cache()) <= 2 * noise.LEVELS + 1
    cache = new_cache()
    brownian(9, 1e6 + 0.123, cache)
    assert _draws_per_call(9, np.array([1e6 + 0.123]), cache) == 0  # the same point again: nothing drawn


@pytest.mark.parametrize("h, most", [(2.0 ** -10, 1.01), (2.0 ** -20, 1.01), (1e-3, noise.LEVELS - 10 + 1.0)])
def test_stepping_forward_costs_amortized_o1_draws(h, most):
    """Dyadic step times cost one draw per step (each midpoint of the tree is drawn once: the held path's
    known midpoint is reused); step times with all their fraction bits cost the levels below the step's."""
    n = 20_000
    cache = new_cache()
    _forward(4, 1e6, h, 10, cache)
    before = cache[noise.DRAWS]
    _forward(4, 1e6 + 10 * h, h, n, cache)
    assert (cache[noise.DRAWS] - before) / n <= most


# --- a C function ----------------------------------------------------------------------------------------------------

def test_the_increment_compiles_as_a_cfunc_without_python_nor_libm():
    """The native runtime emits kernels as C functions: no Python object, no exception on the way. And no
    transcendental function of the platform's libm (whose last bits differ between machines): the FMU's path
    is the library's bit for bit."""
    import ctypes
    import re

    from numba import carray, cfunc, types

    @cfunc(types.float64(types.int64, types.float64, types.float64, types.CPointer(types.int64)), error_model="numpy")
    def c_increment(seed, a, b, cache_pointer):
        return increment(seed, a, b, carray(cache_pointer, noise.CACHE_SIZE))

    cache = new_cache()
    pointer = cache.ctypes.data_as(ctypes.POINTER(ctypes.c_int64))
    for a, b in [(0.3, 0.7), (1e6 + 0.1, 1e6 + 0.1 + 1e-9), (2.5, 2.75), (0.0, 2.0 ** 45)]:
        assert c_increment.ctypes(5, a, b, pointer) == increment(5, a, b, new_cache())
    declared = set(re.findall(r"declare [^@]*@([\w.]+)", str(c_increment._library._final_module)))
    assert not {name for name in declared if re.match(r"(llvm\.)?(log|exp|pow|sin|cos|tan|atan|erf)", name)}
    assert "llvm.floor.f64" in declared  # the pattern sees the module's declarations


def test_the_path_s_kernels_are_compiled_once_not_once_more_per_constant_argument():
    """The root of the path draws its normal with the stream and index as int64, not as the constants numba
    compiled normal() and its block once more for (a literal is a signature of its own): the cache of this run
    holds no kernel signature with a literal (tests/compiled_copies.py) once a path has been drawn."""
    from tests.compiled_copies import literal_signatures

    assert math.isfinite(brownian(3, 0.5, new_cache()))
    assert literal_signatures("noise.normal", "noise._root") == []
