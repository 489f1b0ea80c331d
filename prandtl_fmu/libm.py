"""The elementary functions the kernels call, in plain IEEE arithmetic: the same bits on every platform.

glibc's, Windows' and zig/musl's libm differ in the last bits of cos, sin, exp, log, ...; a kernel that calls
them gives a native FMU for each platform its own numbers (issue 33, "one number everywhere"). The functions
here use only IEEE +, -, *, /, sqrt and integer and bit operations on the doubles' representations, each
rounded to nearest as IEEE 754 prescribes, in a fixed order: no libm, no FMA (numba emits no ``contract``
flag without fastmath, so LLVM never fuses a*b + c; the tests check the machine code), no extended precision.
The library in process, the pure-Python execution of the same source (CPython's floats) and every FMU binary
therefore compute the same bits, which the tests check against the pure-Python run.

Algorithms (FreeBSD msun, i.e. Sun's fdlibm 5.3 with FreeBSD's fixes, whose sources bound exp, expm1, log,
log1p and hypot below 1 ulp and cbrt below 0.667; log2 and pow are written here; ``tests/steppers/test_libm.py``
measures every one against mpmath, ``docs/libm.md`` has the figures: at most 0.89 ulp):

* cos, sin, sincos: ``k_cos.c``, ``k_sin.c`` (degree 14 and 13 minimax polynomials on [-pi/4, pi/4], the
  reduced argument as a double-double y0 + y1) after an argument reduction x = n pi/2 + y:
  Cody-Waite with pi/2 in three 33-bit parts (``e_rem_pio2.c``) for |x| < 2^20 pi/2, and above an exact
  Payne-Hanek reduction in integer arithmetic: the 53-bit mantissa times the 192 bits of 2/pi that matter
  for its exponent (24-bit limbs from a 1440-bit table, products in int64), then the fraction times pi/2
  in double-double. The reduced argument keeps at least 70 correct bits for every finite double (the
  closest a double comes to a multiple of pi/2 is 2^-61 relative, 6381956970095103 2^797). cos(-x) = cos(x)
  and sin(-x) = -sin(x) bit for bit (the reduction runs on |x|);
* exp: ``e_exp.c`` (x = k ln2 + r, |r| <= ln2 / 2, a degree-5 minimax rational form of r);
* expm1: ``s_expm1.c`` (the same reduction, a correction term for the rounding of r, and 2^k (e^r - 1)
  recombined so that nothing cancels);
* log: ``e_log.c``; log1p: ``s_log1p.c`` (x = 2^k (1 + f), s = f / (2 + f), a degree-14 minimax
  polynomial in s; log1p adds the correction term of 1 + x's rounding);
* acos: ``e_acos.c`` (a rational form in x^2 below 1/2, acos x = 2 asin(sqrt((1 - x) / 2)) above, with the
  square root split in two);
* cbrt: ``s_cbrt.c`` (an exponent estimate, a polynomial to 23 bits, one Newton step in double);
* hypot: ``e_hypot.c`` (scaled by 2^+-600 or 2^1022 so that nothing overflows or underflows, the squares
  summed with their low parts so that the sum is good to about 1/2 ulp before the square root);
* scalbn: musl's ``scalbn.c`` (x 2^n by at most three exact scalings, one rounding into the subnormals);
* log2 and pow (written here): ln x in double-double to a relative 2^-68 (a table of ln(j/64) in
  double-double, then 2 atanh s with |s| <= 0.0056), log2 x = k + ln m / ln 2 rounded once (k exactly at
  2^k); pow x^y = e^(y ln|x|) with y ln|x| a double-double whose tail enters exp's reduction; pow3 three
  powers of one base, its logarithm computed once, each pow's bits.

Special values are those of C99 Annex F (signed zeros, infinities, NaN, overflow to inf, gradual underflow);
floating-point exceptions are not raised (nothing reads them). Every function takes and returns float64,
allocates nothing and raises nothing (callable from a numba cfunc).
"""
import numpy as np

from ._jit import inline_kernel, kernel

# --- the representation of a double -------------------------------------------------------------------------


@inline_kernel
def _bits(x):
    """The IEEE 754 representation of the double x as an int64."""
    return np.float64(x).view(np.int64)


@inline_kernel
def _double(bits):
    """The double whose IEEE 754 representation is the int64 ``bits``."""
    return np.int64(bits).view(np.float64)


@inline_kernel
def _high(x):
    """The high 32 bits of x's representation, signed (fdlibm's GET_HIGH_WORD as an int32)."""
    return np.float64(x).view(np.int64) >> 32


@inline_kernel
def _low(x):
    """The low 32 bits of x's representation (fdlibm's GET_LOW_WORD)."""
    return np.float64(x).view(np.int64) & 0xFFFFFFFF


@inline_kernel
def _with_high(x, high):
    """x with the high word replaced by ``high`` (0 <= high < 2^31: a non-negative double)."""
    return np.int64((np.int64(high) << 32) | (np.float64(x).view(np.int64) & 0xFFFFFFFF)).view(np.float64)


@inline_kernel
def _from_high(high):
    """The double of high word ``high`` (0 <= high < 2^31) and low word 0 (fdlibm's INSERT_WORDS(x, high, 0))."""
    return np.int64(np.int64(high) << 32).view(np.float64)


_NAN = float("nan")
_INF = float("inf")
_ROUND_TO_INTEGER = 6755399441055744.0  # 1.5 2^52: (x + it) - it is x rounded to the nearest integer, |x| < 2^51

# --- cos and sin: the kernels on [-pi/4, pi/4] (k_sin.c, k_cos.c) -------------------------------------------

_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10

_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11


@inline_kernel
def _sin_reduced(x, y):
    """sin(x + y) for |x + y| <= pi/4 (a little more is fine), |y| <= ulp(x) / 2: k_sin.c with iy = 1."""
    z = x * x
    w = z * z
    r = _S2 + z * (_S3 + z * _S4) + z * w * (_S5 + z * _S6)
    v = z * x
    return x - ((z * (0.5 * y - v * r) - y) - v * _S1)


@inline_kernel
def _cos_reduced(x, y):
    """cos(x + y) for |x + y| <= pi/4 (a little more is fine), |y| <= ulp(x) / 2: k_cos.c."""
    z = x * x
    w = z * z
    r = z * (_C1 + z * (_C2 + z * _C3)) + w * w * (_C4 + z * (_C5 + z * _C6))
    hz = 0.5 * z
    w = 1.0 - hz
    return w + (((1.0 - w) - hz) + (z * r - x * y))


# --- the argument reduction x = n pi/2 + y0 + y1 ------------------------------------------------------------

_INV_PIO2 = 6.36619772367581382433e-01  # 2/pi
_PIO2_1 = 1.57079632673412561417e+00  # the first 33 bits of pi/2
_PIO2_1T = 6.07710050650619224932e-11  # pi/2 - _PIO2_1
_PIO2_2 = 6.07710050630396597660e-11  # the next 33 bits
_PIO2_2T = 2.02226624879595063154e-21  # pi/2 - (_PIO2_1 + _PIO2_2)
_PIO2_3 = 2.02226624871116645580e-21  # the next 33 bits
_PIO2_3T = 8.47842766036889956997e-32  # pi/2 - (_PIO2_1 + _PIO2_2 + _PIO2_3)
_PIO2_HI = 1.57079632679489655800e+00  # pi/2 as a double-double
_PIO2_LO = 6.12323399573676603587e-17
_MEDIUM = 0x413921FB  # high word of 2^20 pi/2: Cody-Waite below, Payne-Hanek above

# 2/pi = sum_k _TWO_OVER_PI[k] 2^(-24 (k - 2)): its first 1440 bits in 24-bit limbs, after 72 zero bits (so
# that a window may start up to 72 bits before the binary point); checked against mpmath by the tests
_LIMB = 24
_LIMB_MASK = (1 << _LIMB) - 1
_PAD_BITS = 72
_TWO_OVER_PI = np.array([
    0x000000, 0x000000, 0x000000,
    0xA2F983, 0x6E4E44, 0x1529FC, 0x2757D1, 0xF534DD, 0xC0DB62, 0x95993C, 0x439041, 0xFE5163, 0xABDEBB,
    0xC561B7, 0x246E3A, 0x424DD2, 0xE00649, 0x2EEA09, 0xD1921C, 0xFE1DEB, 0x1CB129, 0xA73EE8, 0x8235F5,
    0x2EBB44, 0x84E99C, 0x7026B4, 0x5F7E41, 0x3991D6, 0x398353, 0x39F49C, 0x845F8B, 0xBDF928, 0x3B1FF8,
    0x97FFDE, 0x05980F, 0xEF2F11, 0x8B5A0A, 0x6D1F6D, 0x367ECF, 0x27CB09, 0xB74F46, 0x3F669E, 0x5FEA2D,
    0x7527BA, 0xC7EBE5, 0xF17B3D, 0x0739F7, 0x8A5292, 0xEA6BFB, 0x5FB11F, 0x8D5D08, 0x560330, 0x46FC7B,
    0x6BABF0, 0xCFBC20, 0x9AF436, 0x1DA9E3, 0x91615E, 0xE61B08, 0x659985, 0x5F14A0, 0x68408D, 0xFFD880,
], dtype=np.int64)


@inline_kernel
def _two_sum(a, b):
    """(s, e) with s = fl(a + b) and s + e = a + b exactly (Knuth)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


@inline_kernel
def _split(a):
    """(hi, lo) with a = hi + lo exactly and hi, lo of at most 26 bits (Veltkamp; |a| < 2^995)."""
    c = 134217729.0 * a  # 2^27 + 1
    hi = c - (c - a)
    return hi, a - hi


@inline_kernel
def _two_product(a, b):
    """(p, e) with p = fl(a b) and p + e = a b exactly (Dekker, without FMA)."""
    p = a * b
    a_hi, a_lo = _split(a)
    b_hi, b_lo = _split(b)
    return p, ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo


@inline_kernel
def _window(first, shift, j):
    """The j-th 24-bit limb of the bits of 2/pi from bit 24 first + shift of the padded table on."""
    return ((_TWO_OVER_PI[first + j] << shift) | (_TWO_OVER_PI[first + j + 1] >> (_LIMB - shift))) & _LIMB_MASK


@kernel
def _reduce_large(ax):
    """(n mod 4, y0, y1) with ax = n pi/2 + y0 + y1, |y0 + y1| <= pi/4, for a finite ax >= 2^20 (Payne-Hanek).

    ax = m 2^e, m < 2^53 an integer; the bits of 2/pi of weight above 2^(1-e) give multiples of 4 in
    ax 2/pi and are dropped; the next 192 bits W give ax 2/pi mod 4 = m W 2^(2 - 192) up to
    m 2^(e - 192 - (e - 2)) < 2^-137: two bits of quadrant and 190 of fraction, exact in integers."""
    bits = _bits(ax)
    e = ((bits >> 52) & 0x7FF) - 1075
    m = (bits & 0xFFFFFFFFFFFFF) | (1 << 52)
    start = e - 2 + _PAD_BITS  # >= 0 for ax >= 2^20 (e >= -32)
    first = start // _LIMB
    shift = start - _LIMB * first
    m0 = m & _LIMB_MASK
    m1 = (m >> _LIMB) & _LIMB_MASK
    m2 = m >> (2 * _LIMB)
    # the window's limbs, least significant first
    v0 = _window(first, shift, 7)
    v1 = _window(first, shift, 6)
    v2 = _window(first, shift, 5)
    v3 = _window(first, shift, 4)
    v4 = _window(first, shift, 3)
    v5 = _window(first, shift, 2)
    v6 = _window(first, shift, 1)
    v7 = _window(first, shift, 0)
    # m W mod 2^192 in limbs (each column < 3 2^48 + carry: no int64 overflows)
    c = m0 * v0
    y0 = c & _LIMB_MASK
    c = (c >> _LIMB) + m0 * v1 + m1 * v0
    y1 = c & _LIMB_MASK
    c = (c >> _LIMB) + m0 * v2 + m1 * v1 + m2 * v0
    y2 = c & _LIMB_MASK
    c = (c >> _LIMB) + m0 * v3 + m1 * v2 + m2 * v1
    y3 = c & _LIMB_MASK
    c = (c >> _LIMB) + m0 * v4 + m1 * v3 + m2 * v2
    y4 = c & _LIMB_MASK
    c = (c >> _LIMB) + m0 * v5 + m1 * v4 + m2 * v3
    y5 = c & _LIMB_MASK
    c = (c >> _LIMB) + m0 * v6 + m1 * v5 + m2 * v4
    y6 = c & _LIMB_MASK
    c = (c >> _LIMB) + m0 * v7 + m1 * v6 + m2 * v5
    y7 = c & _LIMB_MASK
    n = (y7 >> 22) & 3
    y7 &= 0x3FFFFF
    sign = 1.0
    if y7 >= 0x200000:  # fraction >= 1/2: the next quadrant, y = -(1 - fraction) pi/2 (two's complement)
        n = (n + 1) & 3
        sign = -1.0
        c = ((~y0) & _LIMB_MASK) + 1
        y0 = c & _LIMB_MASK
        c = (c >> _LIMB) + ((~y1) & _LIMB_MASK)
        y1 = c & _LIMB_MASK
        c = (c >> _LIMB) + ((~y2) & _LIMB_MASK)
        y2 = c & _LIMB_MASK
        c = (c >> _LIMB) + ((~y3) & _LIMB_MASK)
        y3 = c & _LIMB_MASK
        c = (c >> _LIMB) + ((~y4) & _LIMB_MASK)
        y4 = c & _LIMB_MASK
        c = (c >> _LIMB) + ((~y5) & _LIMB_MASK)
        y5 = c & _LIMB_MASK
        c = (c >> _LIMB) + ((~y6) & _LIMB_MASK)
        y6 = c & _LIMB_MASK
        y7 = ((c >> _LIMB) + ((~y7) & 0x3FFFFF)) & 0x3FFFFF
    # the fraction (< 1/2) as a double-double: each limb times its power of two is exact; sum them from the top
    hi = np.float64(y7) * 2.0 ** -22
    lo = 0.0
    hi, err = _two_sum(hi, np.float64(y6) * 2.0 ** -46)
    lo += err
    hi, err = _two_sum(hi, np.float64(y5) * 2.0 ** -70)
    lo += err
    hi, err = _two_sum(hi, np.float64(y4) * 2.0 ** -94)
    lo += err
    hi, err = _two_sum(hi, np.float64(y3) * 2.0 ** -118)
    lo += err
    hi, err = _two_sum(hi, np.float64(y2) * 2.0 ** -142)
    lo += err
    hi, err = _two_sum(hi, lo)
    # times pi/2, in double-double
    p, err2 = _two_product(hi, _PIO2_HI)
    tail = err2 + (hi * _PIO2_LO + err * _PIO2_HI)
    r0 = p + tail
    r1 = tail - (r0 - p)
    return n, sign * r0, sign * r1


@kernel
def _reduce(ax):
    """(n mod 4, y0, y1) with ax = n pi/2 + y0 + y1, |y0 + y1| <= pi/4 (a few ulps more by rounding), for a
    finite ax > pi/4: fdlibm's Cody-Waite below 2^20 pi/2 (e_rem_pio2.c), Payne-Hanek above."""
    hx = _high(ax)
    if hx >= _MEDIUM:  # fdlibm: ix < 0x413921fb is medium
        return _reduce_large(ax)
    fn = (ax * _INV_PIO2 + _ROUND_TO_INTEGER) - _ROUND_TO_INTEGER
    n = np.int64(fn)
    r = ax - fn * _PIO2_1
    w = fn * _PIO2_1T  # 85 bits of n pi/2 so far
    j = hx >> 20
    y0 = r - w
    if j - ((_high(y0) >> 20) & 0x7FF) > 16:  # r cancelled more than 16 bits: 118 bits
        t = r
        w = fn * _PIO2_2
        r = t - w
        w = fn * _PIO2_2T - ((t - r) - w)
        y0 = r - w
        if j - ((_high(y0) >> 20) & 0x7FF) > 49:  # more than 49: 151 bits, enough for every double here
            t = r
            w = fn * _PIO2_3
            r = t - w
            w = fn * _PIO2_3T - ((t - r) - w)
            y0 = r - w
    y1 = (r - y0) - w
    return n & 3, y0, y1


@kernel
def sincos(x):
    """(sin x, cos x) from one argument reduction. sin(+-0) = +-0, cos(+-0) = 1; inf and NaN give NaN."""
    x = np.float64(x)
    ax = abs(x)
    sign = -1.0 if x < 0.0 else 1.0
    hx = _high(ax)
    if hx <= 0x3FE921FB:  # |x| <= pi/4
        if hx < 0x3E400000:  # |x| < 2^-27: sin x = x, cos x = 1 to the last bit
            return x, 1.0
        return sign * _sin_reduced(ax, 0.0), _cos_reduced(ax, 0.0)
    if hx >= 0x7FF00000:
        return _NAN, _NAN
    n, y0, y1 = _reduce(ax)
    s = _sin_reduced(y0, y1)
    c = _cos_reduced(y0, y1)
    if n == 0:
        return sign * s, c
    if n == 1:
        return sign * c, -s
    if n == 2:
        return -sign * s, -c
    return -sign * c, s


@kernel
def sin(x):
    """sin x (x in radians). sin(+-0) = +-0; inf and NaN give NaN. sin(-x) = -sin(x) bit for bit."""
    x = np.float64(x)
    ax = abs(x)
    sign = -1.0 if x < 0.0 else 1.0
    hx = _high(ax)
    if hx <= 0x3FE921FB:
        if hx < 0x3E500000:  # |x| < 2^-26
            return x
        return sign * _sin_reduced(ax, 0.0)
    if hx >= 0x7FF00000:
        return _NAN
    n, y0, y1 = _reduce(ax)
    if n == 0:
        return sign * _sin_reduced(y0, y1)
    if n == 1:
        return sign * _cos_reduced(y0, y1)
    if n == 2:
        return -sign * _sin_reduced(y0, y1)
    return -sign * _cos_reduced(y0, y1)


@kernel
def cos(x):
    """cos x (x in radians). cos(+-0) = 1; inf and NaN give NaN. cos(-x) = cos(x) bit for bit."""
    ax = abs(np.float64(x))
    hx = _high(ax)
    if hx <= 0x3FE921FB:
        if hx < 0x3E400000:  # |x| < 2^-27
            return 1.0
        return _cos_reduced(ax, 0.0)
    if hx >= 0x7FF00000:
        return _NAN
    n, y0, y1 = _reduce(ax)
    if n == 0:
        return _cos_reduced(y0, y1)
    if n == 1:
        return -_sin_reduced(y0, y1)
    if n == 2:
        return -_cos_reduced(y0, y1)
    return _sin_reduced(y0, y1)


# --- exp and expm1 (e_exp.c, s_expm1.c) ---------------------------------------------------------------------

_LN2_HI = 6.93147180369123816490e-01  # ln 2 to 32 bits: k _LN2_HI is exact for |k| < 2^21
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e+00
_EXP_OVERFLOW = 7.09782712893383973096e+02  # ln(largest double)
_EXP_UNDERFLOW = -7.45133219101941108420e+02  # ln(2^-1075)
_P1 = 1.66666666666666019037e-01
_P2 = -2.77777777770155933842e-03
_P3 = 6.61375632143793436117e-05
_P4 = -1.65339022054652515390e-06
_P5 = 4.13813679705723846039e-08
_TWO_M1000 = 2.0 ** -1000
_TWO_1023 = 2.0 ** 1023


@kernel
def exp(x):
    """e^x. exp(+-0) = 1, exp(inf) = inf, exp(-inf) = +0, overflow above 709.78 to inf, gradual underflow
    below -708.4 and +0 below -745.13."""
    x = np.float64(x)
    hx = _high(x)
    negative = hx < 0
    hx &= 0x7FFFFFFF
    if hx >= 0x40862E42:  # |x| >= 709.78
        if hx >= 0x7FF00000:
            if x != x:
                return x
            return 0.0 if negative else x
        if x > _EXP_OVERFLOW:
            return _INF
        if x < _EXP_UNDERFLOW:
            return 0.0
    k = 0
    hi = 0.0
    lo = 0.0
    if hx > 0x3FD62E42:  # |x| > ln2 / 2: x = k ln2 + hi - lo
        if hx < 0x3FF0A2B2:  # and |x| < 1.5 ln2
            if negative:
                hi = x + _LN2_HI
                lo = -_LN2_LO
                k = -1
            else:
                hi = x - _LN2_HI
                lo = _LN2_LO
                k = 1
        else:
            k = np.int64(_INV_LN2 * x + (-0.5 if negative else 0.5))  # truncation toward zero, as C's (int)
            t = np.float64(k)
            hi = x - t * _LN2_HI
            lo = t * _LN2_LO
        x = hi - lo
    elif hx < 0x3E300000:  # |x| < 2^-28
        return 1.0 + x
    t = x * x
    c = x - t * (_P1 + t * (_P2 + t * (_P3 + t * (_P4 + t * _P5))))
    if k == 0:
        return 1.0 - ((x * c) / (c - 2.0) - x)
    y = 1.0 - ((lo - (x * c) / (2.0 - c)) - hi)
    if k >= -1021:
        if k == 1024:
            return y * 2.0 * _TWO_1023
        return y * _from_high((0x3FF + k) << 20)
    return y * _from_high((0x3FF + k + 1000) << 20) * _TWO_M1000


_Q1 = -3.33333333333331316428e-02
_Q2 = 1.58730158725481460165e-03
_Q3 = -7.93650757867487942473e-05
_Q4 = 4.00821782732936239552e-06
_Q5 = -2.01099218183624371326e-07


@kernel
def expm1(x):
    """e^x - 1, accurate for small x. expm1(+-0) = +-0, expm1(inf) = inf, expm1(-inf) = -1."""
    x = np.float64(x)
    hx = _high(x)
    negative = hx < 0
    hx &= 0x7FFFFFFF
    if hx >= 0x4043687A:  # |x| >= 56 ln2
        if hx >= 0x40862E42:  # |x| >= 709.78
            if hx >= 0x7FF00000:
                if x != x:
                    return x
                return -1.0 if negative else x
            if x > _EXP_OVERFLOW:
                return _INF
        if negative:  # e^x < 2^-56: -1 to the last bit
            return -1.0
    k = 0
    c = 0.0
    if hx > 0x3FD62E42:  # |x| > ln2 / 2
        if hx < 0x3FF0A2B2:  # and |x| < 1.5 ln2
            if negative:
                hi = x + _LN2_HI
                lo = -_LN2_LO
                k = -1
            else:
                hi = x - _LN2_HI
                lo = _LN2_LO
                k = 1
        else:
            k = np.int64(_INV_LN2 * x + (-0.5 if negative else 0.5))
            t = np.float64(k)
            hi = x - t * _LN2_HI
            lo = t * _LN2_LO
        x = hi - lo
        c = (hi - x) - lo  # the rounding of hi - lo
    elif hx < 0x3C900000:  # |x| < 2^-54: x to the last bit
        return x
    hfx = 0.5 * x
    hxs = x * hfx
    r1 = 1.0 + hxs * (_Q1 + hxs * (_Q2 + hxs * (_Q3 + hxs * (_Q4 + hxs * _Q5))))
    t = 3.0 - r1 * hfx
    e = hxs * ((r1 - t) / (6.0 - x * t))
    if k == 0:
        return x - (x * e - hxs)
    e = x * (e - c) - c
    e -= hxs
    if k == -1:
        return 0.5 * (x - e) - 0.5
    if k == 1:
        if x < -0.25:
            return -2.0 * (e - (x + 0.5))
        return 1.0 + 2.0 * (x - e)
    if k <= -2 or k > 56:  # e^x - 1 = e^x to the last bit
        y = 1.0 - (e - x)
        if k == 1024:
            y = y * 2.0 * _TWO_1023
        else:
            y = y * _from_high((0x3FF + k) << 20)
        return y - 1.0
    if k < 20:
        t = _from_high(0x3FF00000 - (0x200000 >> k))  # 1 - 2^-k
        y = t - (e - x)
        return y * _from_high((0x3FF + k) << 20)
    t = _from_high((0x3FF - k) << 20)  # 2^-k
    y = x - (e + t)
    y += 1.0
    return y * _from_high((0x3FF + k) << 20)


# --- log and log1p (e_log.c, s_log1p.c) ---------------------------------------------------------------------

_TWO54 = 1.80143985094819840000e+16
_LG1 = 6.666666666666735130e-01
_LG2 = 3.999999999940941908e-01
_LG3 = 2.857142874366239149e-01
_LG4 = 2.222219843214978396e-01
_LG5 = 1.818357216161805012e-01
_LG6 = 1.531383769920937332e-01
_LG7 = 1.479819860511658591e-01


@kernel
def log(x):
    """ln x. log(+-0) = -inf, log(1) = +0, log(inf) = inf, log(x < 0) = NaN."""
    x = np.float64(x)
    hx = _high(x)
    k = 0
    if hx < 0x00100000:  # x < 2^-1022
        if ((hx & 0x7FFFFFFF) | _low(x)) == 0:
            return -_INF
        if hx < 0:
            return _NAN
        k -= 54
        x *= _TWO54  # a subnormal, scaled up
        hx = _high(x)
    if hx >= 0x7FF00000:
        return x + x
    k += (hx >> 20) - 1023
    hx &= 0x000FFFFF
    i = (hx + 0x95F64) & 0x100000
    x = _with_high(x, hx | (i ^ 0x3FF00000))  # x or x / 2 in [sqrt(2) / 2, sqrt(2))
    k += i >> 20
    f = x - 1.0
    dk = np.float64(k)
    if (0x000FFFFF & (2 + hx)) < 3:  # -2^-20 <= f < 2^-20
        if f == 0.0:
            if k == 0:
                return 0.0
            return dk * _LN2_HI + dk * _LN2_LO
        r = f * f * (0.5 - 0.33333333333333333 * f)
        if k == 0:
            return f - r
        return dk * _LN2_HI - ((r - dk * _LN2_LO) - f)
    s = f / (2.0 + f)
    z = s * s
    i = hx - 0x6147A
    w = z * z
    j = 0x6B851 - hx
    t1 = w * (_LG2 + w * (_LG4 + w * _LG6))
    t2 = z * (_LG1 + w * (_LG3 + w * (_LG5 + w * _LG7)))
    i |= j
    r = t2 + t1
    if i > 0:
        hfsq = 0.5 * f * f
        if k == 0:
            return f - (hfsq - s * (hfsq + r))
        return dk * _LN2_HI - ((hfsq - (s * (hfsq + r) + dk * _LN2_LO)) - f)
    if k == 0:
        return f - s * (f - r)
    return dk * _LN2_HI - ((s * (f - r) - dk * _LN2_LO) - f)


@kernel
def log1p(x):
    """ln(1 + x), accurate for small x. log1p(+-0) = +-0, log1p(-1) = -inf, log1p(x < -1) = NaN,
    log1p(inf) = inf."""
    x = np.float64(x)
    hx = _high(x)
    ax = hx & 0x7FFFFFFF
    k = 1
    f = 0.0
    c = 0.0
    hu = 0
    if hx < 0x3FDA827A:  # 1 + x < sqrt(2)+
        if ax >= 0x3FF00000:  # x <= -1
            if x == -1.0:
                return -_INF
            return _NAN
        if ax < 0x3E200000:  # |x| < 2^-29
            if ax < 0x3C900000:  # |x| < 2^-54
                return x
            return x - x * x * 0.5
        if hx > 0 or hx <= -0x402D413C:  # sqrt(2)/2- <= 1 + x < sqrt(2)+ (hx <= (int32) 0xBFD2BEC4)
            k = 0
            f = x
            hu = 1
    if hx >= 0x7FF00000:
        return x + x
    if k != 0:
        if hx < 0x43400000:  # x < 2^53
            u = 1.0 + x
            hu = _high(u)
            k = (hu >> 20) - 1023
            c = (1.0 - (u - x)) if k > 0 else (x - (u - 1.0))  # the rounding of 1 + x
            c /= u
        else:
            u = x
            hu = _high(u)
            k = (hu >> 20) - 1023
            c = 0.0
        hu &= 0x000FFFFF
        if hu < 0x6A09E:  # u < sqrt(2)
            u = _with_high(u, hu | 0x3FF00000)
        else:
            k += 1
            u = _with_high(u, hu | 0x3FE00000)  # u / 2
            hu = (0x00100000 - hu) >> 2
        f = u - 1.0
    hfsq = 0.5 * f * f
    dk = np.float64(k)
    if hu == 0:  # |f| < 2^-20
        if f == 0.0:
            if k == 0:
                return 0.0
            c += dk * _LN2_LO
            return dk * _LN2_HI + c
        r = hfsq * (1.0 - 0.66666666666666666 * f)
        if k == 0:
            return f - r
        return dk * _LN2_HI - ((r - (dk * _LN2_LO + c)) - f)
    s = f / (2.0 + f)
    z = s * s
    r = z * (_LG1 + z * (_LG2 + z * (_LG3 + z * (_LG4 + z * (_LG5 + z * (_LG6 + z * _LG7))))))
    if k == 0:
        return f - (hfsq - s * (hfsq + r))
    return dk * _LN2_HI - ((hfsq - (s * (hfsq + r) + (dk * _LN2_LO + c))) - f)


# --- acos (e_acos.c) ----------------------------------------------------------------------------------------

_PI = 3.14159265358979311600e+00
_PS0 = 1.66666666666666657415e-01
_PS1 = -3.25565818622400915405e-01
_PS2 = 2.01212532134862925881e-01
_PS3 = -4.00555345006794114027e-02
_PS4 = 7.91534994289814532176e-04
_PS5 = 3.47933107596021167570e-05
_QS1 = -2.40339491173441421878e+00
_QS2 = 2.02094576023350569471e+00
_QS3 = -6.88283971605453293030e-01
_QS4 = 7.70381505559019352791e-02


@inline_kernel
def _asin_ratio(z):
    """fdlibm's rational R(z) = p(z) / q(z), asin(s) = s + s R(s^2) for 0 <= z = s^2 <= 1/2."""
    p = z * (_PS0 + z * (_PS1 + z * (_PS2 + z * (_PS3 + z * (_PS4 + z * _PS5)))))
    q = 1.0 + z * (_QS1 + z * (_QS2 + z * (_QS3 + z * _QS4)))
    return p / q


@kernel
def acos(x):
    """arccos x in [0, pi]. acos(1) = +0, acos(|x| > 1) = NaN."""
    x = np.float64(x)
    hx = _high(x)
    ix = hx & 0x7FFFFFFF
    if ix >= 0x3FF00000:  # |x| >= 1
        if ((ix - 0x3FF00000) | _low(x)) == 0:
            if hx > 0:
                return 0.0
            return _PI + 2.0 * _PIO2_LO
        return _NAN
    if ix < 0x3FE00000:  # |x| < 1/2
        if ix <= 0x3C600000:  # |x| <= 2^-57
            return _PIO2_HI + _PIO2_LO
        r = _asin_ratio(x * x)
        return _PIO2_HI - (x - (_PIO2_LO - x * r))
    if hx < 0:  # x < -1/2
        z = (1.0 + x) * 0.5
        s = np.sqrt(z)
        w = _asin_ratio(z) * s - _PIO2_LO
        return _PI - 2.0 * (s + w)
    z = (1.0 - x) * 0.5  # x > 1/2
    s = np.sqrt(z)
    df = _double(_bits(s) & -0x100000000)  # s with its low word cleared: df * df is exact
    c = (z - df * df) / (s + df)
    w = _asin_ratio(z) * s + c
    return 2.0 * (df + w)


# --- cbrt (s_cbrt.c) ----------------------------------------------------------------------------------------

_B1 = 715094163  # (1023 - 1023/3 - 0.03306235651) 2^20
_B2 = 696219795  # (1023 - 1023/3 - 54/3 - 0.03306235651) 2^20
_CB0 = 1.87595182427177009643
_CB1 = -1.88497979543377169875
_CB2 = 1.621429720105354466140
_CB3 = -0.758397934778766047437
_CB4 = 0.145996192886612446982


@kernel
def cbrt(x):
    """The real cube root of x. cbrt(+-0) = +-0, cbrt(+-inf) = +-inf, cbrt(-x) = -cbrt(x)."""
    x = np.float64(x)
    hx = _high(x) & 0x7FFFFFFF
    if hx >= 0x7FF00000:
        return x + x
    ax = abs(x)
    if hx < 0x00100000:  # zero or subnormal
        if (hx | _low(x)) == 0:
            return x
        t = ax * 18014398509481984.0  # 2^54
        t = _from_high(((_high(t) & 0x7FFFFFFF) // 3) + _B2)
    else:
        t = _from_high(hx // 3 + _B1)  # cbrt(|x|) to 5 bits from the exponent
    r = (t * t) * (t / ax)
    t = t * ((_CB0 + r * (_CB1 + r * _CB2)) + ((r * r) * r) * (_CB3 + r * _CB4))  # to 23 bits
    t = _double((_bits(t) + 0x80000000) & -0x40000000)  # rounded away from zero to 22 bits: t * t exact
    s = t * t
    r = ax / s
    w = t + t
    r = (r - t) / (w + r)  # one Newton step to 53 bits
    t = t + t * r
    return -t if x < 0.0 else t


# --- hypot (e_hypot.c) --------------------------------------------------------------------------------------


@kernel
def hypot(x, y):
    """sqrt(x^2 + y^2) without overflow or underflow on the way. hypot(+-inf, y) = inf even for a NaN y,
    else NaN if either is; hypot(x, +-0) = |x|."""
    a = abs(np.float64(x))
    b = abs(np.float64(y))
    if b > a:
        a, b = b, a
    ha = _high(a)
    hb = _high(b)
    if ha >= 0x7FF00000 or hb >= 0x7FF00000:  # inf or NaN
        if a == _INF or b == _INF:
            return _INF
        return a + b  # NaN
    if ha - hb > 0x3C00000:  # a / b > 2^60
        return a + b
    k = 0
    if ha > 0x5F300000:  # a > 2^500: both scaled by 2^-600
        ha -= 0x25800000
        hb -= 0x25800000
        k += 600
        a = _with_high(a, ha)
        b = _with_high(b, hb)
    if hb < 0x20B00000:  # b < 2^-500
        if hb <= 0x000FFFFF:  # subnormal b or 0
            if b == 0.0:
                return a
            a *= 4.49423283715578976932e+307  # 2^1022
            b *= 4.49423283715578976932e+307
            k -= 1022
            ha = _high(a)
            hb = _high(b)
        else:  # both scaled by 2^600
            ha += 0x25800000
            hb += 0x25800000
            k -= 600
            a = _with_high(a, ha)
            b = _with_high(b, hb)
    w = a - b
    if w > b:
        t1 = _from_high(ha)  # a's high word: t1 * t1 exact
        t2 = a - t1
        w = np.sqrt(t1 * t1 - (b * (-b) - t2 * (a + t1)))
    else:
        a = a + a
        y1 = _from_high(hb)
        y2 = b - y1
        t1 = _from_high(ha + 0x00100000)
        t2 = a - t1
        w = np.sqrt(t1 * y1 - (w * (-w) - (t1 * y2 + t2 * b)))
    if k != 0:
        return w * _from_high((1023 + k) << 20)
    return w


# --- scalbn (musl's scalbn.c) --------------------------------------------------------------------------------

_TWO_M969 = 2.0 ** -969  # 2^-1022 2^53


@kernel
def scalbn(x, n):
    """x 2^n for an integer n, rounded once (exact unless the result is subnormal; C99's scalbn and ldexp).
    For the kernels' powers of two: numba compiles ``2.0 ** n`` with an integer variable n into a call of
    libm's exp2."""
    y = np.float64(x)
    n = np.int64(n)
    if n > 1023:
        y *= _TWO_1023
        n -= 1023
        if n > 1023:
            y *= _TWO_1023
            n -= 1023
            if n > 1023:
                n = 1023
    elif n < -1022:  # the last factor leaves n < -53: one rounding into the subnormals, not two
        y *= _TWO_M969
        n += 1022 - 53
        if n < -1022:
            y *= _TWO_M969
            n += 1022 - 53
            if n < -1022:
                n = -1022
    return y * _double((0x3FF + n) << 52)


# --- a double-double logarithm, and log2 and pow on it ------------------------------------------------------

_LN2_DD_HI = 0.6931471805599453  # ln 2 = _LN2_DD_HI + _LN2_DD_LO to 2^-106
_LN2_DD_LO = 2.3190468138462996e-17
_INV_LN2_HI = 1.4426950408889634  # 1 / ln 2, likewise
_INV_LN2_LO = 2.0355273740931033e-17
_SQRT2 = 1.4142135623730951


@inline_kernel
def _fast_two_sum(a, b):
    """(s, e) with s = fl(a + b), s + e = a + b exactly, for |a| >= |b| (Dekker)."""
    s = a + b
    return s, b - (s - a)


# ln(j / 64) = _LOG_B_HI[j - 45] + _LOG_B_LO[j - 45] to 2^-106, j = 45 ... 91 (j / 64 spans [sqrt(1/2), sqrt(2)]);
# mpmath's values, checked by the tests
_LOG_B_FIRST = 45
_LOG_B_HI = np.array([
    -0.3522205935893521, -0.33024168687057687, -0.3087354816496133, -0.2876820724517809, -0.26706278524904525,
    -0.24686007793152578, -0.22705745063534608, -0.2076393647782445, -0.18859116980755003, -0.16989903679539747,
    -0.15154989812720093, -0.13353139262452263, -0.1158318155251217, -0.09844007281325252, -0.0813456394539524,
    -0.06453852113757118, -0.048009219186360606, -0.0317486983145803, -0.015748356968139168, 0.0,
    0.015504186535965254, 0.030771658666753687, 0.0458095360312942, 0.06062462181643484, 0.07522342123758753,
    0.08961215868968714, 0.10379679368164356, 0.11778303565638346, 0.13157635778871926, 0.1451820098444979,
    0.15860503017663857, 0.17185025692665923, 0.184922338494012, 0.19782574332991987, 0.21056476910734964,
    0.22314355131420976, 0.2355660713127669, 0.24783616390458127, 0.25995752443692605, 0.27193371548364176,
    0.2837681731306446, 0.2954642128938359, 0.3070250352949119, 0.3184537311185346, 0.329753286372468,
    0.3409265869705932, 0.3519764231571782,
])
_LOG_B_LO = np.array([
    -5.7233316949182485e-18, 1.0828321637483858e-17, 1.6199186085148102e-17, -2.607160616442564e-17,
    7.32891532732017e-18, -1.361743371748368e-17, -9.551415762738488e-18, -1.2053243216686129e-17,
    7.432164219196925e-18, 4.868008764439071e-19, -5.1669593684615594e-18, 3.664457663660085e-18,
    -4.338484369808096e-18, 4.439009633675136e-18, -5.07707635593117e-18, 6.470486661692933e-18,
    -1.4390903347292205e-18, -3.0382263084680858e-18, -1.0021578630528974e-18, 0.0, -3.278321022892429e-19,
    1.0431732029005968e-18, 1.902959866474257e-18, 2.6424025938726934e-18, -5.930604196293241e-18,
    -5.4268129336647135e-18, 5.47772415726659e-18, -1.1971685747593677e-18, 1.1123000879729588e-17,
    8.242418783022475e-18, 1.1257003872182592e-17, -6.0224538210113705e-18, 3.0236614153574064e-18,
    1.2821194372980142e-17, -4.249405314729895e-18, -9.091270597324799e-18, -2.3943371495187355e-18,
    -1.2432209578702523e-17, 2.069806938978935e-17, 7.83319637697442e-19, -2.032665581126656e-17,
    -2.16461086040599e-17, -1.2319916200101964e-17, 2.7114779367326236e-17, 2.122020616196946e-18,
    1.7467136443544747e-17, -1.2953893030191963e-17,
])


@kernel
def _log_dd(x):
    """(k, hi, lo) with ln x = k ln 2 + hi + lo to a relative 2^-68, for a positive finite x (subnormals too).

    x = 2^k m, m in [sqrt(1/2), sqrt(2)]; b = j / 64 the nearest such fraction (m - b exact, |m - b| <= 1/128);
    ln m = ln b + 2 atanh s = ln b + 2 s + 2 s^3 / 3 + ... + 2 s^9 / 9, s = (m - b) / (m + b), |s| <= 0.0056:
    ln b and s in double-double, the odd powers from s^3 (below 2^-16 of the sum) in double (the next term
    is below 2^-78)."""
    k = 0
    if x < 2.2250738585072014e-308:  # a subnormal: scaled into the normal range
        x *= _TWO54
        k = -54
    bits = _bits(x)
    k += (bits >> 52) - 1023
    m = _double((bits & 0xFFFFFFFFFFFFF) | 0x3FF0000000000000)
    if m > _SQRT2:
        m *= 0.5
        k += 1
    j64 = (m * 64.0 + _ROUND_TO_INTEGER) - _ROUND_TO_INTEGER
    b = j64 * 0.015625
    index = np.int64(j64) - _LOG_B_FIRST
    f = m - b  # exact (Sterbenz)
    u_hi, u_lo = _two_sum(m, b)
    s_hi = f / u_hi
    p, e = _two_product(s_hi, u_hi)
    s_lo = (((f - p) - e) - s_hi * u_lo) / u_hi
    z = s_hi * s_hi
    odd = s_hi * z * (2.0 / 3.0 + z * (2.0 / 5.0 + z * (2.0 / 7.0 + z * (2.0 / 9.0))))
    hi, lo = _two_sum(_LOG_B_HI[index], 2.0 * s_hi)
    lo += _LOG_B_LO[index] + (2.0 * s_lo + odd)
    hi, lo = _fast_two_sum(hi, lo)
    return k, hi, lo


@kernel
def log2(x):
    """log2 x (k exactly for x = 2^k). log2(+-0) = -inf, log2(1) = +0, log2(inf) = inf, log2(x < 0) = NaN."""
    x = np.float64(x)
    if not x > 0.0:
        if x == 0.0:
            return -_INF
        return _NAN  # x < 0 or NaN
    if x == _INF:
        return x
    k, hi, lo = _log_dd(x)
    t_hi, t_lo = _two_product(hi, _INV_LN2_HI)
    t_lo += hi * _INV_LN2_LO + lo * _INV_LN2_HI
    s, e = _two_sum(np.float64(k), t_hi)
    return s + (e + t_lo)


@kernel
def _exp_dd(x, tail):
    """e^(x + tail) for -745.2 <= x <= 709.8, |tail| <= ulp(x): e_exp.c's reduction with the tail in its
    low part (overflow to inf and gradual underflow as exp's)."""
    k = np.int64(_INV_LN2 * x + (-0.5 if x < 0.0 else 0.5))
    t = np.float64(k)
    hi = x - t * _LN2_HI
    lo = t * _LN2_LO - tail
    r = hi - lo
    t = r * r
    c = r - t * (_P1 + t * (_P2 + t * (_P3 + t * (_P4 + t * _P5))))
    y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi)
    if k >= -1021:
        if k == 1024:
            return y * 2.0 * _TWO_1023
        return y * _from_high((0x3FF + k) << 20)
    return y * _from_high((0x3FF + k + 1000) << 20) * _TWO_M1000


@inline_kernel
def _integer_kind(y):
    """0 if the finite nonzero y is not an integer, 1 if an odd one, 2 if an even one."""
    bits = _bits(y)
    e = ((bits >> 52) & 0x7FF) - 1023
    if e < 0:
        return 0
    if e > 52:
        return 2
    fraction_bits = 52 - e
    mantissa = (bits & 0xFFFFFFFFFFFFF) | (1 << 52)
    if mantissa & ((np.int64(1) << fraction_bits) - 1) != 0:
        return 0
    return 1 if (mantissa >> fraction_bits) & 1 else 2


@kernel
def pow(x, y):
    """x^y, with C99 Annex F's special values: pow(x, +-0) = 1 and pow(1, y) = 1 even for a NaN; pow(-1, +-inf)
    = 1; pow(+-0, y) = +-0 or +0 for y > 0, +-inf or +inf for y < 0 (the sign kept for an odd integer y);
    pow(x < 0, y) = NaN for a finite non-integer y, else (-1)^y |x|^y; the infinities by |x| <> 1.

    |x|^y = e^(y ln|x|), ln|x| in double-double (relative 2^-68) and y ln|x| as a double-double, whose tail
    enters exp's reduction."""
    x = np.float64(x)
    y = np.float64(y)
    if y == 0.0 or x == 1.0:
        return 1.0
    if x != x or y != y:
        return x + y
    ax = abs(x)
    ay = abs(y)
    kind = 2 if ay == _INF else _integer_kind(y)
    if ay == _INF:
        if ax == 1.0:
            return 1.0
        return _INF if (ax > 1.0) == (y > 0.0) else 0.0
    negative_odd = _bits(x) < 0 and kind == 1  # -0.0 too: its sign is kept
    if x == 0.0 or ax == _INF:
        if (x == 0.0) == (y < 0.0):
            return -_INF if negative_odd else _INF
        return -0.0 if negative_odd else 0.0
    if x < 0.0 and kind == 0:
        return _NAN
    sign = -1.0 if negative_odd else 1.0
    l_hi, l_lo = _ln_dd(ax)
    return _exp_of_product(y, l_hi, l_lo, sign)


@inline_kernel
def _ln_dd(ax):
    """ln ax as a double-double (l_hi, l_lo) for a positive finite ax: :func:`_log_dd` plus k ln 2."""
    k, m_hi, m_lo = _log_dd(ax)
    dk = np.float64(k)
    a, b = _two_product(dk, _LN2_DD_HI)
    l_hi, l_lo = _two_sum(a, m_hi)
    l_lo += b + dk * _LN2_DD_LO + m_lo
    return _fast_two_sum(l_hi, l_lo)


@inline_kernel
def _exp_of_product(y, l_hi, l_lo, sign):
    """sign e^(y (l_hi + l_lo)) for a finite nonzero y: the product as a double-double into exp's reduction."""
    z = y * l_hi
    if z > 709.8:
        return sign * _INF
    if z < -745.2:
        return sign * 0.0
    z, err = _two_product(y, l_hi)
    err += y * l_lo
    z, err = _fast_two_sum(z, err)
    return sign * _exp_dd(z, err)


@kernel
def pow3(x, y0, y1, y2):
    """(x^y0, x^y1, x^y2), each bit for bit :func:`pow`'s, with the logarithm of a positive finite x computed
    once (the continuum's closed forms take eta^(p+1), eta^(p+2), eta^(p+3) of one eta: the logarithm is most
    of pow's cost)."""
    x = np.float64(x)
    y0 = np.float64(y0)
    y1 = np.float64(y1)
    y2 = np.float64(y2)
    if not (x > 0.0 and x < _INF) or x == 1.0:
        return pow(x, y0), pow(x, y1), pow(x, y2)
    l_hi, l_lo = _ln_dd(x)
    # pow's path for x > 0 finite, x != 1 and y finite nonzero; the other y by pow itself
    r0 = _exp_of_product(y0, l_hi, l_lo, 1.0) if y0 != 0.0 and abs(y0) < _INF else pow(x, y0)
    r1 = _exp_of_product(y1, l_hi, l_lo, 1.0) if y1 != 0.0 and abs(y1) < _INF else pow(x, y1)
    r2 = _exp_of_product(y2, l_hi, l_lo, 1.0) if y2 != 0.0 and abs(y2) < _INF else pow(x, y2)
    return r0, r1, r2
