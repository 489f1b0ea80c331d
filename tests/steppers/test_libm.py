"""prandtl_fmu.libm: accuracy against mpmath in ulps, C99 Annex F special values, symmetries, and the same bits
from the compiled code and from CPython running the same source (the proxy for "the same bits on every
platform": CPython's floats are IEEE doubles with nothing fused and nothing from libm in these functions).

An error in ulps is |computed - exact| / 2^(max(E, -1022) - 52) with E the binade of the exact value
(2^E <= |exact| < 2^(E + 1)): below 1/2 is correct rounding, below 1 a faithful result. The quick tests sample
a few hundred arguments per function; the slow ones (``-m slow``) 20,000 and every exponent's hardest
arguments for the reduction of sin and cos; ``docs/libm.md`` quotes the slow figures.
"""
import importlib.util
import math
import re

import mpmath
import numpy as np
import pytest

from prandtl_fmu import _jit, libm

# overflow to inf is a result here (exp(710), hypot(MAX, MAX)): numpy's scalars warn about it in the Python run
pytestmark = pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")

PRECISION = 256  # bits of mpmath's exact values (it raises its own for the reduction of large trigonometric ones)

MAX = 1.7976931348623157e308
TINY = 5e-324  # the smallest subnormal
with mpmath.workprec(PRECISION):
    OVERFLOW_EDGE = mpmath.ldexp(2 ** 54 - 1, 1024 - 54)  # the exact values from here on round to inf


@pytest.fixture(autouse=True)
def _exact_precision():
    """mpmath's working precision for this module's tests only (other modules keep theirs)."""
    with mpmath.workprec(PRECISION):
        yield


# --- measuring -------------------------------------------------------------------------------------------------

def ulps(computed, exact):
    """|computed - exact| in units of the last place of the exact value (see the module docstring)."""
    with mpmath.workprec(PRECISION):
        return _ulps(computed, mpmath.mpf(exact))


def _ulps(computed, exact):
    if math.isinf(computed):
        return 0.0 if abs(exact) >= OVERFLOW_EDGE and (computed > 0) == (exact > 0) else math.inf
    if math.isnan(computed):
        return math.inf
    if exact == 0:
        return 0.0 if computed == 0 else math.inf
    _, binade = mpmath.frexp(exact)  # |exact| = mantissa 2^binade, mantissa in [1/2, 1)
    return float(abs(mpmath.mpf(computed) - exact) / mpmath.ldexp(1, max(binade - 1, -1022) - 52))


def bits(value):
    return int(np.float64(value).view(np.int64))


def exact_cbrt(x):
    return mpmath.sign(x) * mpmath.cbrt(abs(x))


def exact_hypot(x, y):
    return mpmath.sqrt(mpmath.mpf(x) ** 2 + mpmath.mpf(y) ** 2)


def exact_pow(x, y):
    return mpmath.power(mpmath.mpf(x), mpmath.mpf(y))


EXACT = {
    "sin": mpmath.sin, "cos": mpmath.cos, "exp": mpmath.exp, "expm1": mpmath.expm1, "log": mpmath.log,
    "log1p": mpmath.log1p, "acos": mpmath.acos, "cbrt": exact_cbrt, "hypot": exact_hypot,
    "log2": lambda x: mpmath.log(x, 2), "pow": exact_pow,
}

# the largest errors measured (docs/libm.md: 10^6 random arguments each), rounded up: all below 1 ulp
BOUND = {"sin": 0.80, "cos": 0.80, "exp": 0.90, "expm1": 0.80, "log": 0.80, "log1p": 0.80, "acos": 0.90,
         "cbrt": 0.70, "hypot": 0.95, "log2": 0.501, "pow": 0.90}


# --- arguments -------------------------------------------------------------------------------------------------

def log_uniform(rng, count, low_exponent=-1074, high_exponent=1023, signed=True):
    """Doubles whose binade is uniform in [low_exponent, high_exponent] and mantissa uniform: every range
    alike, subnormals included."""
    values = np.ldexp(rng.uniform(1.0, 2.0, count), rng.integers(low_exponent, high_exponent + 1, count))
    if signed:
        values *= rng.choice([-1.0, 1.0], count)
    return values


def near(value, count=3):
    """value and its ``count`` neighbours on each side."""
    out = [value]
    up = down = value
    with np.errstate(over="ignore"):
        for _ in range(count):
            up, down = np.nextafter(up, math.inf), np.nextafter(down, -math.inf)
            out += [up, down]
    return [v for v in out if np.isfinite(v)]


def hardest_for_reduction(exponent, count=2):
    """Doubles m 2^exponent (m a 53-bit integer) closest to a multiple of pi/2: multiples of the largest
    denominators of the continued fraction of 2^exponent 2/pi mod 1 below 2^53."""
    with mpmath.workprec(1200 + max(exponent, 0)):
        alpha = mpmath.frac(mpmath.ldexp(2 / mpmath.pi, exponent))
        denominators = []
        previous, current = 0, 1
        rest = alpha
        for _ in range(100):
            whole = int(mpmath.floor(rest))
            previous, current = current, whole * current + previous
            if current >= 2 ** 53:
                break
            denominators.append(current)
            if rest == whole:
                break
            rest = 1 / (rest - whole)
    out = []
    for q in denominators[-count:]:
        m = q * -(-2 ** 52 // q)
        if m < 2 ** 53:
            out.append(math.ldexp(m, exponent))
    return out


FAMOUS = 6381956970095103 * 2.0 ** 797  # the double closest to a multiple of pi/2 (2^-60.9 away)


def hard_arguments(name):
    """The arguments where each function is most likely to go wrong: thresholds of its algorithm, overflow and
    underflow, subnormals, and for sin and cos the neighbourhoods of multiples of pi/2."""
    if name in ("sin", "cos"):
        values = [FAMOUS, 5261692873635770 * 2.0 ** 499, 2.0 ** 20 * math.pi / 2, math.pi / 4, 2.0 ** -26,
                  2.0 ** -27, 1e6, 2.0 ** 30, 2.0 ** 60, MAX, TINY, 2.2250738585072014e-308]
        values += [float(mpmath.mpf(k) * mpmath.pi / 2) for k in (1, 2, 3, 4, 5, 10, 100, 1000, 2 ** 19 + 1,
                                                                  2 ** 20 - 1, 2 ** 20 + 1, 10 ** 9)]
        values += hardest_for_reduction(-52) + hardest_for_reduction(-35) + hardest_for_reduction(100)
        return [w for v in values for w in near(v, 1)]
    if name in ("exp", "expm1"):
        values = [709.782712893384, -708.3964185322641, -745.1332191019411, -745.1332191019412, 0.5 * math.log(2),
                  1.5 * math.log(2), 2.0 ** -28, 2.0 ** -54, 56 * math.log(2), 1e-300, TINY, -1e-300, 1.0, -1.0,
                  20 * math.log(2), 57 * math.log(2), -37.5]
        return [w for v in values for w in near(v, 2)]
    if name in ("log", "log1p", "log2"):
        values = [1.0, 2.0, 0.5, math.sqrt(2.0), math.sqrt(0.5), MAX, TINY, 2.2250738585072014e-308, 1 + 2.0 ** -20,
                  1 - 2.0 ** -20, 2.0 ** 53, 2.0 ** -29, 2.0 ** -54, math.e]
        if name == "log1p":
            values += [-0.2928932188134524, -0.5, -1.0 + 2.0 ** -53, math.sqrt(2.0) - 1.0, 1e-300]
        if name == "log2":
            values += [2.0 ** k for k in range(-1074, 1024, 37)]
        return [w for v in values for w in near(v, 2) if w > (-1.0 if name == "log1p" else 0.0)]
    if name == "acos":
        values = [1.0, -1.0, 0.5, -0.5, 2.0 ** -57, -(2.0 ** -57), 1e-300, 0.0, 0.9999999999999999]
        return [w for v in values for w in near(v, 2) if abs(w) <= 1.0]
    if name == "cbrt":
        values = [1.0, 8.0, -27.0, 2.0 ** 1023, MAX, TINY, 2.2250738585072014e-308, 1e-310, 0.125]
        return [w for v in values for w in near(v, 2)]
    raise KeyError(name)


def arguments(name, rng, count):
    """``count`` random arguments over the function's whole domain and its hard arguments."""
    if name in ("sin", "cos", "cbrt"):
        values = log_uniform(rng, count)
    elif name == "exp":
        values = np.concatenate([rng.uniform(-745.2, 709.8, count // 2), log_uniform(rng, count // 2, -60, 0)])
    elif name == "expm1":
        values = np.concatenate([rng.uniform(-40.0, 709.8, count // 2), log_uniform(rng, count // 2, -1074, 0)])
    elif name in ("log", "log2"):
        values = np.concatenate([log_uniform(rng, count // 2, signed=False),
                                 1.0 + log_uniform(rng, count // 2, -60, -1)])
    elif name == "log1p":
        values = np.concatenate([log_uniform(rng, count // 2, signed=False),
                                 -log_uniform(rng, count // 2, -1074, -1, signed=False)])
    elif name == "acos":
        values = np.concatenate([rng.uniform(-1.0, 1.0, count // 2),
                                 rng.choice([-1.0, 1.0], count // 4)
                                 * (1.0 - log_uniform(rng, count // 4, -53, -2, signed=False)),
                                 log_uniform(rng, count - count // 2 - count // 4, -1074, -1)])
    else:
        raise KeyError(name)
    return [float(v) for v in values] + hard_arguments(name)


def hypot_arguments(rng, count):
    """Pairs over every range (the result below the overflow threshold), the ratio from 1 to 2^-70 and beyond."""
    a = log_uniform(rng, count, -1074, 1022)
    b = a * log_uniform(rng, count, -70, 0)
    pairs = list(zip(a.tolist(), b.tolist()))
    pairs += [(3.0, 4.0), (5.0, 12.0), (MAX / 2, MAX / 2), (MAX, 1.0), (TINY, TINY), (TINY, 3 * TINY),
              (2.0 ** 500, 2.0 ** 500), (2.0 ** -500, 2.0 ** -500), (1e-310, 1e-300), (2.0 ** 60, 1.0),
              (2.0 ** 61, 1.0), (1.0, 1.0), (1.0, 2.0 ** -27), (2.2250738585072014e-308, 1e-320)]
    return pairs


def pow_arguments(rng, count):
    """Pairs (x, y): x over every binade, y ln x uniform over [-750, 750] (overflow, gradual underflow), small
    real and integer exponents, x near 1 with large y, negative x with integer y."""
    x = log_uniform(rng, count, signed=False)
    x[x == 1.0] = 3.0
    log_x = np.log(x)
    kind = rng.integers(0, 4, count)
    y = np.where(kind == 0, rng.uniform(-750.0, 750.0, count) / log_x, rng.uniform(-3.0, 3.0, count))
    y = np.where(kind == 2, rng.integers(-40, 41, count).astype(float), y)
    near_one = kind == 3
    x[near_one] = 1.0 + rng.uniform(-1e-10, 1e-10, near_one.sum())
    y[near_one] = rng.uniform(-1e12, 1e12, near_one.sum())
    odd = (kind == 2) & (rng.random(count) < 0.5)
    x[odd] = -x[odd]
    pairs = list(zip(x.tolist(), y.tolist()))
    pairs += [(2.0, 3.0), (10.0, 2.0), (-2.0, 3.0), (2.0, -1074.0), (2.0, 1023.0), (0.5, 1074.0), (0.5, 1075.0),
              (2.0, 1023.9999999999999), (1.0000000000000002, 2.0 ** 60), (0.9999999999999999, -(2.0 ** 62)),
              (MAX, 0.5), (TINY, 0.5), (TINY, -0.5), (math.e, 709.782712893384), (math.e, -745.1332191019411),
              (10.0, -323.3), (10.0, 308.25), (-0.5, 3.0), (1.5, -1800.0), (3.0, 0.5)]
    return pairs


FUNCTIONS = ("sin", "cos", "exp", "expm1", "log", "log1p", "acos", "cbrt", "log2")
PAIRS = {"hypot": hypot_arguments, "pow": pow_arguments}


def worst(name, rng, count):
    """(largest error in ulps, its argument, number of arguments) of libm's ``name``."""
    with mpmath.workprec(PRECISION):
        return _worst(name, rng, count)


def _worst(name, rng, count):
    if name in PAIRS:
        function, exact = getattr(libm, name), EXACT[name]
        cases = PAIRS[name](rng, count)
        errors = [(ulps(function(x, y), exact(x, y)), (x, y)) for x, y in cases]
    else:
        function, exact = getattr(libm, name), EXACT[name]
        cases = arguments(name, rng, count)
        errors = [(ulps(function(x), exact(mpmath.mpf(x))), x) for x in cases]
    error, argument = max(errors)
    return error, argument, len(cases)


# --- the same source run by CPython ----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def in_python():
    """A second copy of prandtl_fmu/libm.py whose kernels are left plain Python functions, calls between them
    included (``.py_func`` alone would call the compiled callees)."""
    spec = importlib.util.spec_from_file_location("prandtl_fmu._libm_in_python", libm.__file__)
    module = importlib.util.module_from_spec(spec)
    kernel, inline_kernel = _jit.kernel, _jit.inline_kernel
    _jit.kernel = _jit.inline_kernel = lambda fn: fn
    try:
        spec.loader.exec_module(module)
    finally:
        _jit.kernel, _jit.inline_kernel = kernel, inline_kernel
    assert not hasattr(module.cos, "py_func")
    return module


# --- tests -----------------------------------------------------------------------------------------------------

def test_two_over_pi_table_is_two_over_pi():
    table = libm._TWO_OVER_PI
    assert table.dtype == np.int64 and np.all((0 <= table) & (table < 2 ** 24))
    assert np.all(table[:3] == 0)  # the 72 padding bits
    with mpmath.workprec(1500):
        digits = int(mpmath.floor(mpmath.ldexp(2 / mpmath.pi, 24 * (len(table) - 3))))
    assert int("".join(f"{int(limb):06x}" for limb in table[3:]), 16) == digits
    # the largest double's window, and one more limb for the shift, lie inside the table
    start = 1023 - 52 - 2 + libm._PAD_BITS
    assert start // 24 + 9 <= len(table)


# fdlibm's coefficients by the bit patterns its sources give beside them (a decimal typo would still pass the
# accuracy tests when it only costs a fraction of an ulp)
FDLIBM_BITS = {
    "_S1": "BFC5555555555549", "_S2": "3F8111111110F8A6", "_S3": "BF2A01A019C161D5", "_S4": "3EC71DE357B1FE7D",
    "_S5": "BE5AE5E68A2B9CEB", "_S6": "3DE5D93A5ACFD57C", "_C1": "3FA555555555554C", "_C2": "BF56C16C16C15177",
    "_C3": "3EFA01A019CB1590", "_C4": "BE927E4F809C52AD", "_C5": "3E21EE9EBDB4B1C4", "_C6": "BDA8FAE9BE8838D4",
    "_INV_PIO2": "3FE45F306DC9C883", "_PIO2_1": "3FF921FB54400000", "_PIO2_1T": "3DD0B4611A626331",
    "_PIO2_2": "3DD0B4611A600000", "_PIO2_2T": "3BA3198A2E037073", "_PIO2_3": "3BA3198A2E000000",
    "_PIO2_3T": "397B839A252049C1", "_P1": "3FC555555555553E", "_P2": "BF66C16C16BEBD93", "_P3": "3F11566AAF25DE2C",
    "_P4": "BEBBBD41C5D26BF1", "_P5": "3E66376972BEA4D0", "_LN2_HI": "3FE62E42FEE00000", "_LN2_LO": "3DEA39EF35793C76",
    "_INV_LN2": "3FF71547652B82FE", "_EXP_OVERFLOW": "40862E42FEFA39EF", "_EXP_UNDERFLOW": "C0874910D52D3051",
    "_Q1": "BFA11111111110F4", "_Q2": "3F5A01A019FE5585", "_Q3": "BF14CE199EAADBB7", "_Q4": "3ED0CFCA86E65239",
    "_Q5": "BE8AFDB76E09C32D", "_LG1": "3FE5555555555593", "_LG2": "3FD999999997FA04", "_LG3": "3FD2492494229359",
    "_LG4": "3FCC71C51D8E78AF", "_LG5": "3FC7466496CB03DE", "_LG6": "3FC39A09D078C69F", "_LG7": "3FC2F112DF3E5244",
    "_PI": "400921FB54442D18", "_PIO2_HI": "3FF921FB54442D18", "_PIO2_LO": "3C91A62633145C07",
    "_PS0": "3FC5555555555555", "_PS1": "BFD4D61203EB6F7D", "_PS2": "3FC9C1550E884455", "_PS3": "BFA48228B5688F3B",
    "_PS4": "3F49EFE07501B288", "_PS5": "3F023DE10DFDF709", "_QS1": "C0033A271C8A2D4B", "_QS2": "40002AE59C598AC8",
    "_QS3": "BFE6066C1B8D0159", "_QS4": "3FB3B8C5B12E9282", "_CB0": "3FFE03E60F61E692", "_CB1": "BFFE28E092F02420",
    "_CB2": "3FF9F1604A49D6C2", "_CB3": "BFE844CBBEE751D9", "_CB4": "3FC2B000D4E4EDD7",
}


def test_constants_are_fdlibms():
    for name, pattern in FDLIBM_BITS.items():
        assert f"{bits(getattr(libm, name)) & (2 ** 64 - 1):016X}" == pattern, name
    with mpmath.workprec(PRECISION):  # and the double-double constants written here
        for hi, lo, exact in ((libm._LN2_DD_HI, libm._LN2_DD_LO, mpmath.log(2)),
                              (libm._INV_LN2_HI, libm._INV_LN2_LO, 1 / mpmath.log(2))):
            assert hi == float(exact) and lo == float(exact - hi)


def test_log_table_is_ln_j_over_64():
    for i, (hi, lo) in enumerate(zip(libm._LOG_B_HI, libm._LOG_B_LO)):
        exact = mpmath.log(mpmath.mpf(i + libm._LOG_B_FIRST) / 64)
        assert hi == float(exact) and lo == float(exact - hi), i
    last = libm._LOG_B_FIRST + len(libm._LOG_B_HI) - 1
    assert libm._LOG_B_FIRST / 64 <= math.sqrt(0.5) and last / 64 >= math.sqrt(2)


@pytest.mark.parametrize("name", FUNCTIONS + tuple(PAIRS))
def test_accuracy(name):
    error, argument, count = worst(name, np.random.default_rng(33), 600)
    assert error <= BOUND[name], (name, argument, error, count)


@pytest.mark.slow
@pytest.mark.parametrize("name", FUNCTIONS + tuple(PAIRS))
def test_accuracy_many(name):
    """The figures of docs/libm.md (printed with -s)."""
    error, argument, count = worst(name, np.random.default_rng(2026), 20000)
    print(f"\n{name}: max {error:.3f} ulp over {count} arguments (at {argument!r})")
    assert error <= BOUND[name], (name, argument, error, count)


@pytest.mark.slow
def test_reduction_at_every_exponents_hardest_arguments():
    """sin and cos at the doubles closest to multiples of pi/2, for every exponent: the reduced argument loses
    up to 61 leading bits there and must still carry the 53 after them."""
    largest = 0.0
    for exponent in range(-52, 972):
        for x in hardest_for_reduction(exponent, count=1):
            for name in ("sin", "cos"):
                largest = max(largest, ulps(getattr(libm, name)(x), EXACT[name](mpmath.mpf(x))))
    print(f"\nsin, cos at the hardest argument of each exponent: max {largest:.3f} ulp")
    assert largest <= BOUND["sin"]


def test_the_famous_hardest_case():
    """6381956970095103 2^797 is 4.69e-19 from a multiple of pi/2 (Kahan, McDonald): cos x is that distance."""
    assert ulps(libm.cos(FAMOUS), mpmath.cos(mpmath.mpf(FAMOUS))) < 0.5
    assert ulps(libm.sin(FAMOUS), mpmath.sin(mpmath.mpf(FAMOUS))) < 0.5
    assert libm.cos(FAMOUS) == pytest.approx(-4.687165924254628e-19, rel=1e-15)


def test_exact_cases():
    assert libm.exp(0.0) == 1.0 and libm.exp(-0.0) == 1.0
    assert libm.log(1.0) == 0.0 and bits(libm.log(1.0)) == 0
    assert libm.log1p(0.0) == 0.0
    for x, root in ((-8.0, -2.0), (27.0, 3.0), (0.125, 0.5), (-64.0, -4.0), (1000.0, 10.0), (2.0 ** 300, 2.0 ** 100),
                    (2.0 ** -999, 2.0 ** -333), (-(2.0 ** -1071), -(2.0 ** -357)), (3.0 ** 33, 3.0 ** 11)):
        assert libm.cbrt(x) == root, x
    assert libm.hypot(3.0, 4.0) == 5.0 and libm.hypot(-5.0, 12.0) == 13.0 and libm.hypot(0.0, -7.5) == 7.5
    assert libm.hypot(2.0 ** 1000 * 3, 2.0 ** 1000 * 4) == 2.0 ** 1000 * 5
    assert libm.hypot(TINY * 3, TINY * 4) == TINY * 5
    assert libm.acos(1.0) == 0.0 and libm.acos(0.0) == math.pi / 2 and libm.acos(-1.0) == math.pi
    assert libm.sin(0.0) == 0.0 and libm.cos(0.0) == 1.0
    for n in range(-1074, 1024, 7):  # n ln 2, rounded once (k ln2_hi is exact, a sum of two roundings)
        assert ulps(libm.log(2.0 ** n), n * mpmath.log(2)) < 0.5, n
    for n in range(-1074, 1024):
        assert libm.log2(2.0 ** n) == n
        if n >= -1022:
            assert libm.pow(2.0, float(n)) == 2.0 ** n and libm.pow(0.5, float(-n)) == 2.0 ** n
    assert libm.pow(2.0, -1074.0) == TINY and libm.pow(2.0, -1075.0) == 0.0 and libm.pow(2.0, 1024.0) == INF
    assert libm.pow(10.0, 2.0) == 100.0 and libm.pow(-2.0, 3.0) == -8.0 and libm.pow(3.0, 4.0) == 81.0
    assert libm.pow(10.0, 22.0) == 1e22 and libm.pow(4.0, 0.5) == 2.0 and libm.pow(0.25, -1.5) == 8.0
    for x in np.random.default_rng(3).uniform(-1e3, 1e3, 300):  # an exact result: less than 1/2 ulp before rounding
        assert libm.pow(x, 1.0) == x and libm.pow(x, 2.0) == pytest.approx(x * x, rel=2.3e-16), x


NAN = math.nan
INF = math.inf
SPECIALS = [  # (function, arguments, C99 Annex F's value)
    ("sin", (0.0,), 0.0), ("sin", (-0.0,), -0.0), ("sin", (INF,), NAN), ("sin", (-INF,), NAN), ("sin", (NAN,), NAN),
    ("sin", (TINY,), TINY), ("sin", (-TINY,), -TINY),
    ("cos", (0.0,), 1.0), ("cos", (-0.0,), 1.0), ("cos", (INF,), NAN), ("cos", (-INF,), NAN), ("cos", (NAN,), NAN),
    ("exp", (0.0,), 1.0), ("exp", (-0.0,), 1.0), ("exp", (INF,), INF), ("exp", (-INF,), 0.0), ("exp", (NAN,), NAN),
    ("exp", (710.0,), INF), ("exp", (MAX,), INF), ("exp", (-746.0,), 0.0), ("exp", (-MAX,), 0.0),
    ("exp", (-745.0,), TINY), ("exp", (TINY,), 1.0), ("exp", (-TINY,), 1.0),
    ("expm1", (0.0,), 0.0), ("expm1", (-0.0,), -0.0), ("expm1", (INF,), INF), ("expm1", (-INF,), -1.0),
    ("expm1", (NAN,), NAN), ("expm1", (710.0,), INF), ("expm1", (-40.0,), -1.0), ("expm1", (-MAX,), -1.0),
    ("expm1", (TINY,), TINY), ("expm1", (-TINY,), -TINY),
    ("log", (0.0,), -INF), ("log", (-0.0,), -INF), ("log", (1.0,), 0.0), ("log", (INF,), INF), ("log", (-1.0,), NAN),
    ("log", (-INF,), NAN), ("log", (NAN,), NAN), ("log", (-TINY,), NAN), ("log", (TINY,), -744.4400719213812),
    ("log1p", (0.0,), 0.0), ("log1p", (-0.0,), -0.0), ("log1p", (-1.0,), -INF), ("log1p", (-2.0,), NAN),
    ("log1p", (INF,), INF), ("log1p", (-INF,), NAN), ("log1p", (NAN,), NAN), ("log1p", (TINY,), TINY),
    ("log1p", (-TINY,), -TINY),
    ("acos", (1.0,), 0.0), ("acos", (-1.0,), math.pi), ("acos", (1.0000000000000002,), NAN), ("acos", (INF,), NAN),
    ("acos", (-INF,), NAN), ("acos", (NAN,), NAN), ("acos", (0.0,), math.pi / 2), ("acos", (-0.0,), math.pi / 2),
    ("cbrt", (0.0,), 0.0), ("cbrt", (-0.0,), -0.0), ("cbrt", (INF,), INF), ("cbrt", (-INF,), -INF),
    ("cbrt", (NAN,), NAN),
    ("hypot", (INF, NAN), INF), ("hypot", (NAN, -INF), INF), ("hypot", (NAN, 1.0), NAN), ("hypot", (1.0, NAN), NAN),
    ("hypot", (0.0, 0.0), 0.0), ("hypot", (-0.0, -0.0), 0.0), ("hypot", (-3.0, 0.0), 3.0), ("hypot", (MAX, MAX), INF),
    ("hypot", (MAX, 1.0), MAX), ("hypot", (-INF, 0.0), INF), ("hypot", (TINY, 0.0), TINY),
    ("log2", (0.0,), -INF), ("log2", (-0.0,), -INF), ("log2", (1.0,), 0.0), ("log2", (INF,), INF),
    ("log2", (-1.0,), NAN), ("log2", (NAN,), NAN), ("log2", (TINY,), -1074.0),
    ("pow", (NAN, 0.0), 1.0), ("pow", (NAN, -0.0), 1.0), ("pow", (1.0, NAN), 1.0), ("pow", (1.0, INF), 1.0),
    ("pow", (-1.0, INF), 1.0), ("pow", (-1.0, -INF), 1.0), ("pow", (NAN, 1.0), NAN), ("pow", (2.0, NAN), NAN),
    ("pow", (0.0, -3.0), INF), ("pow", (-0.0, -3.0), -INF), ("pow", (-0.0, -2.0), INF), ("pow", (-0.0, -0.5), INF),
    ("pow", (0.0, -INF), INF), ("pow", (-0.0, -INF), INF), ("pow", (0.0, 3.0), 0.0), ("pow", (-0.0, 3.0), -0.0),
    ("pow", (-0.0, 2.0), 0.0), ("pow", (-0.0, 0.5), 0.0), ("pow", (-0.0, INF), 0.0),
    ("pow", (0.5, -INF), INF), ("pow", (-0.5, -INF), INF), ("pow", (2.0, -INF), 0.0), ("pow", (-2.0, -INF), 0.0),
    ("pow", (0.5, INF), 0.0), ("pow", (-0.5, INF), 0.0), ("pow", (2.0, INF), INF), ("pow", (-2.0, INF), INF),
    ("pow", (-INF, -3.0), -0.0), ("pow", (-INF, -2.0), 0.0), ("pow", (-INF, -0.5), 0.0), ("pow", (-INF, 3.0), -INF),
    ("pow", (-INF, 2.0), INF), ("pow", (-INF, 0.5), INF), ("pow", (INF, -1.0), 0.0), ("pow", (INF, 0.5), INF),
    ("pow", (-2.0, 0.5), NAN), ("pow", (-8.0, 1.0 / 3.0), NAN), ("pow", (-2.0, 2.0 ** 60), INF),
    ("pow", (-0.5, 2.0 ** 53 + 1 + 1), 0.0), ("pow", (-0.5, 3.0), -0.125), ("pow", (-2.0, 1025.0), -INF),
    ("pow", (-2.0, -1075.0), -0.0), ("pow", (MAX, 2.0), INF), ("pow", (TINY, 2.0), 0.0), ("pow", (2.0, 0.5 ** 60), 1.0),
]


@pytest.mark.parametrize("name, args, expected", SPECIALS)
def test_special_values(name, args, expected, in_python):
    for module in (libm, in_python):
        value = getattr(module, name)(*args)
        if math.isnan(expected):
            assert math.isnan(value), (name, args, value)
        else:
            assert bits(value) == bits(expected), (name, args, value, expected)
    if name in ("sin", "cos"):
        value = libm.sincos(*args)[0 if name == "sin" else 1]
        assert (math.isnan(value) and math.isnan(expected)) or bits(value) == bits(expected)


def test_symmetries_bit_for_bit():
    rng = np.random.default_rng(7)
    xs = [float(x) for x in log_uniform(rng, 1500, signed=False)] + hard_arguments("sin")[:60]
    for x in xs:
        assert bits(libm.cos(-x)) == bits(libm.cos(x)), x
        assert bits(libm.sin(-x)) == bits(-libm.sin(x)), x
        s, c = libm.sincos(-x)
        assert (bits(s), bits(c)) == (bits(-libm.sin(x)), bits(libm.cos(x))), x
        assert bits(libm.cbrt(-x)) == bits(-libm.cbrt(x)), x
        y = x * 0.37
        assert bits(libm.hypot(x, y)) == bits(libm.hypot(-y, -x)), x
    for x in rng.uniform(0.0, 1.0, 500):  # acos(-x) = pi - acos(x), to the roundings of both
        assert abs(libm.acos(-x) + libm.acos(x) - math.pi) <= 4.5e-16


def _compare_compiled_with_python(in_python, rng, count):
    for name in FUNCTIONS:
        compiled, python = getattr(libm, name), getattr(in_python, name)
        for x in arguments(name, rng, count):
            assert bits(compiled(x)) == bits(python(x)), (name, x)
    for x in arguments("sin", rng, count):
        assert [bits(v) for v in libm.sincos(x)] == [bits(v) for v in in_python.sincos(x)], x
    for name, pairs in PAIRS.items():
        compiled, python = getattr(libm, name), getattr(in_python, name)
        for x, y in pairs(rng, count):
            assert bits(compiled(x, y)) == bits(python(x, y)), (name, x, y)


def test_compiled_equals_python_bit_for_bit(in_python):
    _compare_compiled_with_python(in_python, np.random.default_rng(11), 120)


@pytest.mark.slow
def test_compiled_equals_python_bit_for_bit_many(in_python):
    _compare_compiled_with_python(in_python, np.random.default_rng(12), 20000)


def test_scalbn_is_ldexp(in_python):
    """x 2^n rounded once: C's ldexp (CPython's math.ldexp) to the bit, overflow to +-inf, the subnormals
    rounded to nearest even; n beyond any exponent range too."""
    rng = np.random.default_rng(13)
    xs = log_uniform(rng, 3000).tolist() + [0.0, -0.0, TINY, -TINY, MAX, 1.5, 3.0, INF, -INF]
    for x in xs:
        for n in [int(rng.integers(-2200, 2200)), -1074, -1075, -1076, 1023, 1024, -2098, 2098, -(10 ** 6), 10 ** 6, 0]:
            try:
                expected = math.ldexp(x, n)
            except OverflowError:
                expected = math.copysign(INF, x)
            assert bits(libm.scalbn(x, n)) == bits(expected) == bits(in_python.scalbn(x, n)), (x, n)
    assert math.isnan(libm.scalbn(NAN, 3)) and libm.scalbn(3.0, -1075) == 2 * TINY


def test_pow3_is_pow_three_times(in_python):
    """pow3 shares the logarithm of x between its three powers and gives pow's bits, compiled and in Python,
    for every kind of x and y (special values and the ones pow3 leaves to pow included)."""
    rng = np.random.default_rng(7)
    specials = [0.0, -0.0, 1.0, -1.0, INF, -INF, NAN, 0.5, 2.0, -3.0]
    pairs = pow_arguments(rng, 400)
    xs = [x for x, _ in pairs] + specials + [TINY, MAX]
    ys = [y for _, y in pairs] + specials
    for i, x in enumerate(xs):
        three = [ys[(3 * i + j) % len(ys)] for j in range(3)]
        expected = [bits(libm.pow(x, y)) for y in three]
        assert [bits(v) for v in libm.pow3(x, *three)] == expected, (x, three)
        assert [bits(v) for v in in_python.pow3(x, *three)] == expected, (x, three)


def test_sincos_is_sin_and_cos():
    rng = np.random.default_rng(5)
    for x in [float(v) for v in log_uniform(rng, 500)] + hard_arguments("cos"):
        assert [bits(v) for v in libm.sincos(x)] == [bits(libm.sin(x)), bits(libm.cos(x))], x


# what the compiled code may name: our own functions (_Z...), numba's runtime and the CPython wrapper around the
# entry point (NRT_, numba_, Py...), LLVM's intrinsics that are exact (fabs, copysign, fpclass, ...) and sqrt,
# correctly rounded by IEEE 754 in every libm (and one instruction on x86_64 and aarch64: checked below)
_ALLOWED = ("_Z", "NRT_", "numba_", "Py", "_Py", "llvm.fabs.", "llvm.copysign.", "llvm.is.fpclass.", "llvm.sqrt.",
            "llvm.lifetime.", "llvm.assume", "llvm.memset.", "llvm.memcpy.", "llvm.ctpop.", "llvm.ctlz.", "llvm.cttz.",
            "llvm.umax.", "llvm.umin.", "llvm.smax.", "llvm.smin.", "llvm.abs.", "llvm.umul.with.overflow.",
            "llvm.smul.with.overflow.", "llvm.sadd.with.overflow.", "llvm.ssub.with.overflow.")


def _compiled_afresh():
    """A copy of libm compiled without the cache (numba cannot show cached code), every kernel called once:
    {name: dispatcher} of every compiled function, the private ones included."""
    from numba import njit
    from numba.core.registry import CPUDispatcher
    spec = importlib.util.spec_from_file_location("prandtl_fmu._libm_uncached", libm.__file__)
    module = importlib.util.module_from_spec(spec)
    kernel, inline_kernel = _jit.kernel, _jit.inline_kernel
    _jit.kernel = lambda fn: njit(cache=False)(fn)
    _jit.inline_kernel = lambda fn: njit(cache=False, inline="always")(fn)
    try:
        spec.loader.exec_module(module)
    finally:
        _jit.kernel, _jit.inline_kernel = kernel, inline_kernel
    for name in FUNCTIONS + ("sincos",):
        getattr(module, name)(0.5)
        getattr(module, name)(3e9)  # the Payne-Hanek path
    for name in PAIRS:
        getattr(module, name)(0.5, 0.25)
    module.scalbn(0.5, -3)
    module.pow3(0.5, 1.5, 2.5, 3.5)
    compiled = {name: value for name, value in vars(module).items()
                if isinstance(value, CPUDispatcher) and value.signatures and not value.targetoptions.get("inline")}
    assert {"_reduce_large", "_log_dd", "_exp_dd", "cos", "pow", "scalbn"} <= set(compiled)
    return compiled


@pytest.mark.slow
def test_machine_code_has_no_libm_call_and_no_fused_operation():
    """The IR names no function outside _ALLOWED, no floating-point operation carries a fast-math or contract
    flag, and the machine code LLVM makes of it for three targets with fused multiply-add instructions (aarch64,
    x86_64 Haswell on Linux and Windows) has none, nor a call to sqrt: nothing is fused on any target."""
    import llvmlite.binding as llvm
    llvm.initialize_all_targets()
    llvm.initialize_all_asmprinters()
    machines = {triple: llvm.Target.from_triple(triple).create_target_machine(cpu=cpu, opt=3)
                for triple, cpu in (("aarch64-unknown-linux-gnu", "generic"), ("x86_64-unknown-linux-gnu", "haswell"),
                                    ("x86_64-pc-windows-msvc", "haswell"))}
    for name, function in _compiled_afresh().items():
        for ir in function.inspect_llvm().values():
            named = set(re.findall(r"^declare [^@]*@\"?([\w.$]+)", ir, re.M))
            named |= set(re.findall(r"call [^@]*@\"?([\w.$]+)", ir))
            foreign = {f for f in named if not f.startswith(_ALLOWED) and f != "sqrt"}
            assert not foreign, (name, foreign)
            assert not re.search(r"\bf(add|sub|mul|div|neg) (fast|contract|reassoc|afn|nnan|ninf|nsz|arcp)", ir), name
            for triple, machine in machines.items():
                module = llvm.parse_assembly(ir)
                module.triple = triple
                module.data_layout = str(machine.target_data)
                asm = machine.emit_assembly(module)
                assert not re.search(r"\bv?f(n)?m(add|sub)", asm), (name, triple)
                assert not re.search(r"\b(bl|call\w*|jmp)\s+\S*sqrt", asm), (name, triple)
