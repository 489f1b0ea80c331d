"""A Brownian path that is a function of (seed, time) only: a virtual Brownian tree on a counter-based generator.

W is a standard Brownian motion in the caller's time unit (W(t) - W(s) ~ N(0, t - s)); a noise of intensity
sigma over a physical time T0 per unit is ``sigma * sqrt(T0) * increment(seed, a / T0, b / T0, cache)``.
Nothing here depends on a step, an output interval, a communication step or the order of calls: the same
(seed, t) gives the same W(t), bit for bit, whatever was asked before.

Construction (every normal is keyed by its place in the tree, never drawn from a stream):

* the generator is Philox4x32-10 (Salmon et al., SC'11; Random123's known answers in the tests), keyed by the
  64-bit seed, with a 128-bit counter (stream, index); a normal is Marsaglia and Tsang's ziggurat (128 layers,
  Doornik's ZIGNOR) on one Philox block per attempt (an attempt accepts with probability 98.8 %; 97.2 % end
  in a layer's core: a product and a comparison);
* the coarse tree: W(0) = 0, W(2^52) = 2^26 z_root, and the midpoint of every dyadic interval [l, r] of
  [0, 2^52] down to width 1 is the Brownian bridge (W(l) + W(r)) / 2 + sqrt(r - l) / 2 * z(level, index).
  This gives W(k) at every integer k (a random walk with N(0, 1) steps) in 52 bridge draws, not k;
* the fine tree: within the unit [k, k + 1), the same bridge halves [k, k + 1] down to width 2^-52, keyed by
  (k, level, index);
* W(t) for a double t: k = floor(t), and the fraction t - k (exact in doubles) is truncated to the grid of
  2^-52 units; the point is then an endpoint of the tree at level d = 52 - (its trailing zero bits), reached
  by d bridge draws from the unit's ends. A time on the grid 2^-j (j <= 52) needs at most j fine draws.

What is exact and what is not:

* the tree is an exact Brownian construction (Levy's): W restricted to the dyadic points of level <= 52 below
  2^52 units has exactly the law of Brownian motion, up to the two roundings below; a time t >= 1 unit IS such
  a point (its fraction has at most 52 bits), a time below 1 unit is truncated to the grid 2^-52 (2.2e-16
  units), so W is piecewise constant only at that scale;
* the values are fixed-point integers: W(k) in quanta of 2^-32 units, W(t) - W(k) in quanta of 2^-48 units
  (3.6e-15); each bridge draw is rounded to its quantum (a relative change of the variance below 1e-13 at the
  finest level). The arithmetic is on int64 (a difference of two values is exact; wraparound cancels out);
* increments are exact differences of those integers, converted once to a double: for |W(b) - W(a)| < 32
  units the conversion is exact, so an increment over [a, b] is BIT FOR BIT the sum of those over [a, m] and
  [m, b] (two half steps equal one step, in floating point, not only in law). Larger increments are rounded
  once (to 1 ulp);
* the domain is 0 <= t < 2^52 units (4.5e15); t <= 0 or NaN gives W(0) = 0, t >= 2^52 gives W(2^52).
* the normals are exact in law (rejection) up to the tables' rounding (1e-13) and a total variation below
  1e-15 (eight rejections in a row keep the last candidate);
* the same bits on every machine: only IEEE +, -, *, /, sqrt, floor and integer operations, no libm (exp and
  log are written here, for the ziggurat's wedges and tail and for its tables; the tables and the bridge's
  constants come from the same operations at import), so the native runtime's compiled path equals this one.

Cost, work per call bounded (only bounded loops, no allocation, no exception: compilable as a numba cfunc;
the state is plain int64):

* a call descends at most 52 coarse and 52 fine levels: at most 105 normals (the root's, then one per level;
  a normal is one Philox block 98.8 % of the time, at most 16), whatever t, h or the cache;
* the cache (:func:`new_cache`, a small int64 array the caller keeps; all zeros is a new cache) holds the two
  root-to-leaf paths last walked. A query reuses the levels it shares with them, so stepping forward by h costs
  the levels below the first bit where t and t + h differ: amortized O(1) draws per step (about one) when the
  step times are on a dyadic grid of the unit (h = 2^-j units), and at most 52 - log2(1/h) draws for step
  times with all 52 fraction bits (t = n * 1e-3). Moving to the next unit costs its own fine descent once.
* the cache is never needed for correctness: with a new cache, a stale one (a rolled-back FMU's) or one
  for another seed the values are the same integers (they are the same computations from the same parents);
  a cache whose header does not match the seed is reset. A cache is a new one or one these functions wrote.
  ``cache[DRAWS]`` counts the normals drawn (for the tests and benchmarks; it never enters a value).

Use in a stepper: keep one cache per path (seed) beside the loop's scratch, never in the saved state, and ask
for the increment over each step [t_p, t_p+1] at the tree's points of those times. The element's steppers do
it through :func:`prandtl_fmu.loads.impulse`: the point of time t is t / T0 rounded to 48 significant bits
(:func:`prandtl_fmu.loads.tree_time`), a function of t alone, so that step times p h within a few ulps of
p (h / T0) land on the tree's dyadic points when h / T0 is a power of two, for any unit T0 (the scene's
``noise_unit``; docs/white-noise.md). Choose T0 = the coarsest step of a refinement study: every query is then
a point of the tree, about one normal per step, and the steps h and h / 2 see the same path bit for bit. A
restored or rolled-back state needs only its time.

``benchmarks/noise_cost.py`` measures ns per increment stepping forward and at random times, beside the
deterministic step (2026-11, a shared 2-core x86_64, load 3.5, 10^6 steps): 57 ns per step with dyadic step
times (one normal); 830 ns with h = 1e-3 units from t = 0 (34 normals), 580 ns from t = 1e6 (23); 2.0 us at
random times (75); a normal 19 ns; the deterministic 7-branch step 191 ns implicit, 63 ns projected.
"""
import math

import numpy as np

from ._jit import inline_kernel, kernel

# --- Philox4x32-10 (Random123) -------------------------------------------------------------------------------

_MASK32 = np.uint64(0xFFFFFFFF)
_SHIFT32 = np.uint64(32)
_SHIFT11 = np.uint64(11)
_PHILOX_M0 = np.uint64(0xD2511F53)
_PHILOX_M1 = np.uint64(0xCD9E8D57)
_PHILOX_W0 = np.uint64(0x9E3779B9)
_PHILOX_W1 = np.uint64(0xBB67AE85)
_TWO_POW_M53 = 2.0 ** -53


@kernel
def philox4x32_10(c0, c1, c2, c3, k0, k1):
    """Philox4x32-10 of the counter (c0, c1, c2, c3) under the key (k0, k1): four 32-bit words in uint64s
    (inputs must be below 2^32), as Random123's ``philox4x32_R(10, ctr, key)``."""
    for _ in range(10):
        p0 = _PHILOX_M0 * c0
        p1 = _PHILOX_M1 * c2
        c0, c1, c2, c3 = ((p1 >> _SHIFT32) ^ c1 ^ k0, p1 & _MASK32,
                          (p0 >> _SHIFT32) ^ c3 ^ k1, p0 & _MASK32)
        k0 = (k0 + _PHILOX_W0) & _MASK32
        k1 = (k1 + _PHILOX_W1) & _MASK32
    return c0, c1, c2, c3


@kernel
def _block(seed, stream, index):
    """Philox of the 128-bit counter (stream, index) under the 64-bit seed: two 64-bit words."""
    key = np.uint64(seed)
    s = np.uint64(stream)
    i = np.uint64(index)
    x0, x1, x2, x3 = philox4x32_10(i & _MASK32, i >> _SHIFT32, s & _MASK32, s >> _SHIFT32,
                                   key & _MASK32, key >> _SHIFT32)
    return (x0 << _SHIFT32) | x1, (x2 << _SHIFT32) | x3


@kernel
def uniform(seed, stream, index):
    """A uniform double in [0, 1) (53 bits), a function of (seed, stream, index) only (int64s)."""
    a, _ = _block(seed, stream, index)
    return np.float64(a >> _SHIFT11) * _TWO_POW_M53


@kernel
def _bit_length(x):
    """The number of bits of 0 <= x < 2^63 (0 for 0)."""
    n = 0
    if x >= (1 << 32):
        x >>= 32
        n += 32
    if x >= (1 << 16):
        x >>= 16
        n += 16
    if x >= (1 << 8):
        x >>= 8
        n += 8
    if x >= (1 << 4):
        x >>= 4
        n += 4
    if x >= (1 << 2):
        x >>= 2
        n += 2
    if x >= (1 << 1):
        x >>= 1
        n += 1
    if x >= 1:
        n += 1
    return n


# --- exp and log in plain arithmetic: the same bits on every machine (no libm) ------------------------------------

_LN2_HI = 6.93147180369123816490e-01  # fdlibm's split of ln 2: n * _LN2_HI is exact for |n| < 2^20
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e+00
_SQRT2 = math.sqrt(2.0)  # IEEE square roots are correctly rounded: the same everywhere
_POW2 = np.array([math.ldexp(1.0, n) for n in range(-64, 65)])  # 2^n, |n| <= 64
_EXP_TAYLOR = np.array([1.0 / math.factorial(n) for n in range(14)])


@kernel
def _exp(x):
    """e^x for |x| <= 40, to about 1 ulp: x = n ln 2 + r, |r| <= ln 2 / 2, and Taylor to r^13 (below 1e-17)."""
    n = math.floor(x * _INV_LN2 + 0.5)
    r = (x - n * _LN2_HI) - n * _LN2_LO
    p = _EXP_TAYLOR[13]
    for k in range(12, -1, -1):
        p = p * r + _EXP_TAYLOR[k]
    return p * _POW2[np.int64(n) + 64]


@kernel
def _log_mantissa(m):
    """ln m for m in [sqrt(1/2), sqrt(2)]: 2 atanh((m - 1) / (m + 1)) to s^19 (below 1e-17)."""
    s = (m - 1.0) / (m + 1.0)
    s2 = s * s
    p = 1.0 / 19.0
    for k in range(17, 0, -2):
        p = p * s2 + 1.0 / k
    return 2.0 * s * p


@kernel
def _log_uniform(bits):
    """ln U for U = (bits + 1) 2^-53 in (0, 1], bits a 53-bit integer (uint64)."""
    m = np.int64(bits) + 1
    e = _bit_length(m) - 1  # m = 2^e * mantissa, mantissa in [1, 2)
    mantissa = np.float64(m) * _POW2[64 - e]
    if mantissa > _SQRT2:
        mantissa *= 0.5
        e += 1
    power = np.float64(e - 53)
    return _log_mantissa(mantissa) + power * _LN2_LO + power * _LN2_HI


def _log_table(x):
    """ln x for a positive double (for the tables, at import)."""
    mantissa, e = math.frexp(x)  # exact: x = mantissa 2^e, mantissa in [1/2, 1)
    mantissa, e = mantissa * 2.0, e - 1
    if mantissa > _SQRT2:
        mantissa, e = mantissa * 0.5, e + 1
    return _log_mantissa.py_func(mantissa) + e * _LN2_LO + e * _LN2_HI


# --- the standard normal: Marsaglia and Tsang's ziggurat (Doornik's ZIGNOR, 128 layers) -----------------------------

# R and V solve the ziggurat's two closing conditions to 40 digits (mpmath): the base layer R f(R) + the tail
# integral = V, and the 127th layer ends at the mode (Doornik's 13-digit R leaves it open by 1e-9)
_ZIG_R = 3.442619855896652
_ZIG_V = 0.009912563035336461


def _ziggurat_tables():
    f = _exp.py_func(-0.5 * _ZIG_R * _ZIG_R)
    x = [_ZIG_V / f, _ZIG_R]
    for _ in range(2, 128):
        x.append(math.sqrt(-2.0 * _log_table(_ZIG_V / x[-1] + f)))
        f = _exp.py_func(-0.5 * x[-1] * x[-1])
    x.append(0.0)
    x = np.array(x)
    return x, x[1:] / x[:-1]


_ZIG_X, _ZIG_RATIO = _ziggurat_tables()
_ZIG_ATTEMPTS = 8  # all eight rejected: probability below 1e-15
_LAYER = np.uint64(127)
_TWO_POW_M52 = 2.0 ** -52


@kernel
def normal(seed, stream, index):
    """A standard normal, a function of (seed, stream, index) only (bits 58-62 of the stream must be clear: the
    attempts use them). The ziggurat: one Philox block per attempt, a layer from 7 bits and a point from 53;
    97.2 % of attempts end in the layer's core (a product and a comparison), the rest take the wedge test (two
    exponentials) or the tail beyond R (Marsaglia's, two logarithms, a second block); 1.2 % are rejected.
    Exact in law up to the tables' rounding and a total variation below 1e-15 (eight rejections in a row return
    the last candidate)."""
    x = 0.0
    for attempt in range(_ZIG_ATTEMPTS):
        a, b = _block(seed, stream ^ (attempt << 58), index)
        layer = np.int64(a & _LAYER)
        u = np.float64(a >> _SHIFT11) * _TWO_POW_M52 - 1.0  # [-1, 1)
        x = u * _ZIG_X[layer]
        if abs(u) < _ZIG_RATIO[layer]:
            return x
        if layer == 0:  # beyond R: the tail, from a block of its own
            c, d = _block(seed, stream ^ ((attempt + 16) << 58), index)
            beyond = -_log_uniform(c >> _SHIFT11) / _ZIG_R
            if -2.0 * _log_uniform(d >> _SHIFT11) > beyond * beyond:
                return _ZIG_R + beyond if u > 0.0 else -_ZIG_R - beyond
            continue
        f0 = _exp(-0.5 * (_ZIG_X[layer] * _ZIG_X[layer] - x * x))
        f1 = _exp(-0.5 * (_ZIG_X[layer + 1] * _ZIG_X[layer + 1] - x * x))
        if f1 + np.float64(b >> _SHIFT11) * _TWO_POW_M53 * (f0 - f1) < 1.0:
            return x
    return x


# --- the virtual Brownian tree ---------------------------------------------------------------------------------

LEVELS = 52  # coarse levels: [0, 2^52] down to width 1; fine levels: [k, k + 1] down to width 2^-52
HORIZON = 2.0 ** LEVELS
_COARSE_Q = 32  # W(k) in quanta of 2^-32 units
_FINE_Q = 48  # W(t) - W(k) in quanta of 2^-48 units
_COARSE_TO_FINE = _FINE_Q - _COARSE_Q
_COARSE_QUANTUM = 2.0 ** -_COARSE_Q
_FINE_QUANTUM = 2.0 ** -_FINE_Q
_EXACT_DIFFERENCE = 1 << 46  # |W(kb) - W(ka)| in coarse quanta below which it fits in fine quanta in an int64
_FINE_SCALE = 2.0 ** LEVELS


def _half_sqrt_width(log2_width, quantum_bits):
    """sqrt(2^log2_width) / 2 in quanta of 2^-quantum_bits, from IEEE operations only (the same everywhere)."""
    return math.ldexp(_SQRT2 if log2_width % 2 else 1.0, quantum_bits + log2_width // 2 - 1)


# the bridge's standard deviation sqrt(r - l) / 2 in quanta, at the midpoint of an interval of each level
_COARSE_SD = np.array([_half_sqrt_width(LEVELS - level, _COARSE_Q) for level in range(LEVELS)])
_FINE_SD = np.array([_half_sqrt_width(-level, _FINE_Q) for level in range(LEVELS)])
_ROOT_SD = _half_sqrt_width(LEVELS, _COARSE_Q) * 2.0

# streams of the generator: bit 63 tells the coarse tree (level in bits 52-57) from the fine (level in bits
# 52-57, the unit k in bits 0-51); the index is the interval's rank on its level
_COARSE_STREAM = -(1 << 63)
_ROOT_STREAM = _COARSE_STREAM | (63 << 52)

# the cache: a header, then the left and right values of the intervals on the last coarse and fine paths
_TAG = 0
_SEED = 1
_COARSE_K = 2  # the unit whose coarse path is held (-1: none)
_FINE_K = 3  # the unit whose fine path is held (-1: none)
_FINE_BITS = 4  # the fraction (in 2^-52 units) whose fine path is held, to depth _FINE_DEPTH
_FINE_DEPTH = 5
DRAWS = 6  # normals drawn through this cache (statistics only)
_LAST_K = 7  # the last point asked (unit, fraction bits) and its value (-1: none)
_LAST_BITS = 8
_LAST_COARSE = 9
_LAST_FINE = 10
_CL = 12
_CR = _CL + LEVELS + 1
_FL = _CR + LEVELS + 1
_FR = _FL + LEVELS + 1
CACHE_SIZE = _FR + LEVELS + 1
_CACHE_TAG = 0x4E4F495345303031  # "NOISE001"


@kernel
def new_cache():
    """A new cache (any all-zero int64 array of CACHE_SIZE is one too)."""
    return np.zeros(CACHE_SIZE, np.int64)


@kernel
def _bridge(left, right, z, sd):
    """The midpoint of a Brownian bridge from ``left`` to ``right`` (int64 quanta), sd in quanta."""
    return left + ((right - left) >> 1) + np.int64(math.floor(sd * z + 0.5))


@kernel
def _root(seed):
    """W(2^52) in coarse quanta."""
    # the stream and index as int64, not constants: a constant argument would compile normal() again for it
    return np.int64(math.floor(_ROOT_SD * normal(seed, np.int64(_ROOT_STREAM), np.int64(0)) + 0.5))


@inline_kernel
def _reset_if_foreign(seed, cache):
    if cache[_TAG] != _CACHE_TAG or cache[_SEED] != seed:
        cache[_TAG] = _CACHE_TAG
        cache[_SEED] = seed
        cache[_COARSE_K] = -1
        cache[_FINE_K] = -1
        cache[_LAST_K] = -1


@inline_kernel
def _take_other_half(cache, left, right, level, held_went_right):
    """Step from the interval at ``level`` into the half the held path did not take, whose midpoint it holds."""
    if held_went_right:
        cache[right + level + 1] = cache[left + level + 1]
        cache[left + level + 1] = cache[left + level]
    else:
        cache[left + level + 1] = cache[right + level + 1]
        cache[right + level + 1] = cache[right + level]


@inline_kernel
def _coarse(seed, k, cache):
    """(W(k), W(k + 1)) in coarse quanta, 0 <= k < 2^52, through the cache's coarse path."""
    held = cache[_COARSE_K]
    if held < 0 or held >= (1 << LEVELS):
        cache[_CL] = 0
        cache[_CR] = _root(seed)
        cache[DRAWS] += 1
        shared = 0
    else:
        shared = LEVELS - _bit_length(k ^ held)
        if shared < LEVELS:  # k leaves the held path here: the other half of this interval is already known
            _take_other_half(cache, _CL, _CR, shared, (held >> (LEVELS - 1 - shared)) & 1)
            shared += 1
    for level in range(shared, LEVELS):
        mid = _bridge(cache[_CL + level], cache[_CR + level],
                      normal(seed, _COARSE_STREAM | (level << 52), k >> (LEVELS - level)), _COARSE_SD[level])
        if (k >> (LEVELS - 1 - level)) & 1:
            cache[_CL + level + 1] = mid
            cache[_CR + level + 1] = cache[_CR + level]
        else:
            cache[_CL + level + 1] = cache[_CL + level]
            cache[_CR + level + 1] = mid
    cache[DRAWS] += LEVELS - shared
    cache[_COARSE_K] = k
    return cache[_CL + LEVELS], cache[_CR + LEVELS]


@inline_kernel
def _fine(seed, k, bits, unit_increment, cache):
    """W(k + bits 2^-52) - W(k) in fine quanta, 0 < bits < 2^52, given W(k + 1) - W(k) (fine quanta), through
    the cache's fine path."""
    depth = LEVELS + 1 - _bit_length(bits & -bits)  # the level where the point is an interval's left end
    held_depth = cache[_FINE_DEPTH]
    held_bits = cache[_FINE_BITS]
    if (cache[_FINE_K] != k or held_depth < 0 or held_depth > LEVELS
            or held_bits < 0 or held_bits >= (1 << LEVELS)):
        cache[_FL] = 0
        cache[_FR] = unit_increment
        cache[_FINE_K] = k
        shared = 0
    else:
        shared = min(held_depth, LEVELS - _bit_length(bits ^ held_bits))
        if shared >= depth:
            return cache[_FL + depth]
        if shared < held_depth:  # the held path went on through this interval's midpoint
            _take_other_half(cache, _FL, _FR, shared, (held_bits >> (LEVELS - 1 - shared)) & 1)
            shared += 1
    stream = k  # the unit in bits 0-51, the level in bits 52-57
    for level in range(shared, depth):
        mid = _bridge(cache[_FL + level], cache[_FR + level],
                      normal(seed, stream | (level << 52), bits >> (LEVELS - level)), _FINE_SD[level])
        if (bits >> (LEVELS - 1 - level)) & 1:
            cache[_FL + level + 1] = mid
            cache[_FR + level + 1] = cache[_FR + level]
        else:
            cache[_FL + level + 1] = cache[_FL + level]
            cache[_FR + level + 1] = mid
    cache[DRAWS] += depth - shared
    cache[_FINE_BITS] = bits
    cache[_FINE_DEPTH] = depth
    return cache[_FL + depth]


@kernel
def point(seed, t, cache):
    """W(t) as the exact pair (W(k) in 2^-32 units, W(t) - W(k) in 2^-48 units), k = floor(t)."""
    if not t > 0.0:  # t <= 0 and NaN
        return np.int64(0), np.int64(0)
    if t >= HORIZON:
        return _root(seed), np.int64(0)
    _reset_if_foreign(seed, cache)
    whole = math.floor(t)
    k = np.int64(whole)
    bits = np.int64(math.floor((t - whole) * _FINE_SCALE))
    if k == cache[_LAST_K] and bits == cache[_LAST_BITS]:  # a step's start is the previous step's end
        return cache[_LAST_COARSE], cache[_LAST_FINE]
    left, right = _coarse(seed, k, cache)
    fine = np.int64(0)
    if bits != 0:
        fine = _fine(seed, k, bits, (right - left) << _COARSE_TO_FINE, cache)
    cache[_LAST_K] = k
    cache[_LAST_BITS] = bits
    cache[_LAST_COARSE] = left
    cache[_LAST_FINE] = fine
    return left, fine


@inline_kernel
def brownian(seed, t, cache):
    """W(t) in the caller's time unit (a double: rounded once from the exact pair of :func:`point`)."""
    coarse, fine = point(seed, t, cache)
    return np.float64(coarse) * _COARSE_QUANTUM + np.float64(fine) * _FINE_QUANTUM


@inline_kernel
def increment(seed, a, b, cache):
    """W(b) - W(a): the exact difference of the two values, converted once to a double (exact, and additive
    over adjacent intervals bit for bit, when |W(b) - W(a)| < 32 units). Cheapest with a = the previous b."""
    coarse_a, fine_a = point(seed, a, cache)
    coarse_b, fine_b = point(seed, b, cache)
    coarse = coarse_b - coarse_a
    fine = fine_b - fine_a
    if -_EXACT_DIFFERENCE < coarse < _EXACT_DIFFERENCE:
        return np.float64((coarse << _COARSE_TO_FINE) + fine) * _FINE_QUANTUM
    return np.float64(coarse) * _COARSE_QUANTUM + np.float64(fine) * _FINE_QUANTUM


@kernel
def brownian_path(seed, times, cache):
    """W at each of ``times`` (an array; any order)."""
    out = np.empty(times.shape[0])
    for i in range(times.shape[0]):
        out[i] = brownian(seed, times[i], cache)
    return out
