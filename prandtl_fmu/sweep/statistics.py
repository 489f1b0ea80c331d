"""The statistics of a Monte Carlo sweep: intervals for the mean, the standard deviation and a histogram's bins,
and a chi-square test of the histogram against a law.

For n independent values y_1 .. y_n of one output (the runs of one group, :meth:`spec.SweepSpec.group`) and
a confidence 1 - a:

* the mean ybar with Student's interval ybar -+ t_{1 - a/2, n - 1} s / sqrt(n) (exact for normal values,
  asymptotically right for any law with a variance);
* the standard deviation s (the n - 1 estimate) with the chi-square interval
  [s sqrt((n - 1) / chi2_{1 - a/2, n - 1}), s sqrt((n - 1) / chi2_{a/2, n - 1})] (exact for normal values
  only: for a law with heavier tails than the normal's it is too narrow);
* a histogram: the count k_j of each bin, its fraction p_j = k_j / n with Wilson's score interval
  (p + z^2/2n -+ z sqrt(p(1 - p)/n + z^2/4n^2)) / (1 + z^2/n), z = z_{1 - a/2}, which keeps its coverage
  near p = 0 and 1 where the normal approximation fails, and the density p_j / width_j;
* against a law with CDF F: the cells (-inf, e_0), [e_0, e_1), ..., [e_m, inf) of the bin edges e, their
  expected counts n (F(e_{j+1}) - F(e_j)), adjacent cells merged until each expects >= 5, and Pearson's
  X^2 = sum (k - E)^2 / E with r - 1 degrees of freedom (r cells; no parameter is fitted) and its p-value
  P(chi2_{r-1} >= X^2).

A law (:data:`LAWS`) is a density known up to its constant: it is normalised by quadrature
(``scipy.integrate.quad`` on the pieces between the bin edges and the density's kinks, and on the two
tails), so that a law needs only its log-density. The stationary laws of issue 34 are built in, for
m x'' + c x' + k x + k3 x^3 + alpha sign(x') = sigma xi (xi a standard white noise, sigma in N s^(1/2)):

* ``oscillator_x``, ``oscillator_v``: the linear oscillator, x ~ N(0, sigma^2 / (2 c k)),
  v ~ N(0, sigma^2 / (2 c m));
* ``cubic_oscillator_x``: the Gibbs law with a cubic spring, p(x) ~ exp(-(2c/sigma^2)(k x^2/2 + k3 x^4/4))
  (v as ``oscillator_v``);
* ``coulomb_dashpot_v``: a free mass with a dashpot and Coulomb friction,
  p(v) ~ exp(-(2m/sigma^2)(c v^2/2 + alpha |v|));
* ``normal`` (mean, std) and ``uniform`` (low, high), for any output.

Needs scipy (the quantiles of t and chi2, the quadrature).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

# expected count below which adjacent cells are merged (Cochran's rule of thumb)
MIN_EXPECTED = 5.0


def mean_interval(values, confidence: float = 0.95) -> tuple:
    """``(mean, low, high)``: the sample mean and Student's interval (NaN for fewer than 2 values)."""
    from scipy import stats

    y = np.asarray(values, dtype=float)
    n = y.size
    if n < 2:
        return (float(y.mean()) if n else math.nan, math.nan, math.nan)
    mean, s = float(y.mean()), float(y.std(ddof=1))
    half = stats.t.ppf(0.5 + confidence / 2, n - 1) * s / math.sqrt(n)
    return mean, mean - half, mean + half


def std_interval(values, confidence: float = 0.95) -> tuple:
    """``(s, low, high)``: the standard deviation (ddof 1) and its chi-square interval (NaN for fewer than 2)."""
    from scipy import stats

    y = np.asarray(values, dtype=float)
    n = y.size
    if n < 2:
        return (math.nan, math.nan, math.nan)
    s = float(y.std(ddof=1))
    alpha = 1 - confidence
    low = s * math.sqrt((n - 1) / stats.chi2.ppf(1 - alpha / 2, n - 1))
    high = s * math.sqrt((n - 1) / stats.chi2.ppf(alpha / 2, n - 1))
    return s, low, high


def wilson_interval(count, n, confidence: float = 0.95) -> tuple:
    """``(low, high)`` arrays: Wilson's score interval of a binomial proportion, ``count`` successes in ``n``."""
    from scipy import stats

    k = np.asarray(count, dtype=float)
    z = stats.norm.ppf(0.5 + confidence / 2)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    # the bounds hold p (rounding could put the lower one 1e-18 above p = 0)
    return np.clip(np.minimum(centre - half, p), 0.0, 1.0), np.clip(np.maximum(centre + half, p), 0.0, 1.0)


def default_bins(n: int) -> int:
    """Rice's rule, ceil(2 n^(1/3)): about 20 bins for 1000 values, each bin expecting tens of them."""
    return max(1, math.ceil(2 * n ** (1 / 3)))


@dataclass
class Histogram:
    """Bins [edges[j], edges[j+1]) (the last one closed) of n values: their counts, fractions with Wilson's
    interval, and densities (fraction / width) with the same interval scaled."""

    edges: np.ndarray
    counts: np.ndarray
    n: int
    confidence: float
    fraction: np.ndarray = field(init=False)
    fraction_low: np.ndarray = field(init=False)
    fraction_high: np.ndarray = field(init=False)

    def __post_init__(self):
        self.fraction = self.counts / self.n
        self.fraction_low, self.fraction_high = wilson_interval(self.counts, self.n, self.confidence)

    @property
    def widths(self) -> np.ndarray:
        return np.diff(self.edges)

    @property
    def density(self) -> np.ndarray:
        return self.fraction / self.widths

    @property
    def density_low(self) -> np.ndarray:
        return self.fraction_low / self.widths

    @property
    def density_high(self) -> np.ndarray:
        return self.fraction_high / self.widths


def histogram(values, bins: Optional[int] = None, confidence: float = 0.95) -> Histogram:
    """The histogram of ``values`` over [min, max] (``bins`` equal bins; default :func:`default_bins`); a
    sample of equal values gets one bin of width 1 around them."""
    y = np.asarray(values, dtype=float)
    bins = bins or default_bins(y.size)
    low, high = float(y.min()), float(y.max())
    if low == high:
        low, high, bins = low - 0.5, high + 0.5, 1
    counts, edges = np.histogram(y, bins=bins, range=(low, high))
    return Histogram(edges, counts.astype(float), y.size, confidence)


@dataclass
class Fit:
    """Pearson's chi-square test of a histogram against a law (see the module docstring)."""

    chi2: float
    dof: int
    p_value: float
    cells: int              # after merging
    expected: np.ndarray    # the law's probability of each bin (without the tails)


def chi_square_test(values, edges: np.ndarray, law: "Density") -> Fit:
    """Pearson's test of ``values`` against ``law`` on the cells of ``edges`` and the two tails."""
    from scipy import stats

    y = np.asarray(values, dtype=float)
    n = y.size
    probabilities = law.probabilities(edges)  # len(edges) + 1 cells: the tails and the bins
    observed = np.histogram(y, bins=np.concatenate(([-np.inf], edges, [np.inf])))[0].astype(float)
    merged_observed, merged_expected = [], []
    k_sum = e_sum = 0.0
    for k, p in zip(observed, probabilities):
        k_sum += k
        e_sum += n * p
        if e_sum >= MIN_EXPECTED:
            merged_observed.append(k_sum)
            merged_expected.append(e_sum)
            k_sum = e_sum = 0.0
    if merged_expected:  # what is left joins the last cell
        merged_observed[-1] += k_sum
        merged_expected[-1] += e_sum
    else:
        merged_observed, merged_expected = [k_sum], [e_sum]
    k, e = np.array(merged_observed), np.array(merged_expected)
    cells = len(k)
    if cells < 2:
        return Fit(math.nan, 0, math.nan, cells, probabilities[1:-1])
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = np.where(e > 0, (k - e) ** 2 / e, np.where(k > 0, np.inf, 0.0))
    chi2 = float(terms.sum())
    return Fit(chi2, cells - 1, float(stats.chi2.sf(chi2, cells - 1)), cells, probabilities[1:-1])


class Density:
    """A law on the line from its log-density known up to a constant, normalised by quadrature.

    ``log_density(y)`` (vectorised), its largest value at ``mode`` (a shift that keeps exp() in range),
    ``kinks``: points where it is not smooth, ``scale``: its width (quadrature pieces end at the kinks and at
    mode -+ 1, 4, 16, 64 scales, so that a narrow law is never missed by the tails' change of variable);
    ``cdf``: a closed-form CDF that replaces the quadrature (the normal, the uniform); ``support``: outside it
    the density is 0."""

    def __init__(self, label: str, log_density: Callable, mode: float = 0.0, kinks=(), cdf: Optional[Callable] = None,
                 support=(-math.inf, math.inf), scale: float = 1.0):
        self.label, self.log_density, self.mode, self.kinks, self.cdf = label, log_density, mode, tuple(kinks), cdf
        self.support = support
        self.breaks = self.kinks + tuple(mode + sign * multiple * scale for sign in (-1, 1) for multiple in (1, 4, 16, 64))
        self._shift = float(log_density(np.array([mode]))[0])
        self._total = None

    def _mass(self, a: float, b: float) -> float:
        """int_a^b exp(log_density - shift) within the support (a < b, either may be infinite)."""
        from scipy import integrate

        a, b = max(a, self.support[0]), min(b, self.support[1])
        if not a < b:
            return 0.0
        inside = {point for point in self.breaks + (self.mode,) if a < point < b}
        points = [a, *sorted(inside), b]
        total = 0.0
        for lo, hi in zip(points[:-1], points[1:]):
            value, _ = integrate.quad(lambda y: math.exp(float(self.log_density(np.array([y]))[0]) - self._shift),
                                      lo, hi, epsabs=0.0, epsrel=1e-11, limit=200)
            total += value
        return total

    def probabilities(self, edges) -> np.ndarray:
        """The law's probability of (-inf, e_0), [e_0, e_1), ..., [e_m, inf): len(edges) + 1 values, sum 1."""
        edges = np.asarray(edges, dtype=float)
        if self.cdf is not None:
            cumulative = np.concatenate(([0.0], self.cdf(edges), [1.0]))
            return np.diff(cumulative)
        bounds = np.concatenate(([-math.inf], edges, [math.inf]))
        masses = np.array([self._mass(a, b) for a, b in zip(bounds[:-1], bounds[1:])])
        return masses / masses.sum()

    def pdf(self, y) -> np.ndarray:
        """The normalised density at ``y``."""
        y = np.asarray(y, dtype=float)
        if self._total is None:
            self._total = self._mass(-math.inf, math.inf)
        inside = (y >= self.support[0]) & (y <= self.support[1])
        with np.errstate(over="ignore", invalid="ignore"):
            values = np.exp(self.log_density(y) - self._shift) / self._total
        return np.where(inside, values, 0.0)


def normal(mean: float, std: float, label: Optional[str] = None) -> Density:
    from scipy import stats

    if not std > 0:
        raise ValueError(f"normal: std must be > 0, got {std!r}")
    return Density(label or f"N({mean:.6g}, {std:.6g}^2)", lambda y: -0.5 * ((y - mean) / std) ** 2, mode=mean,
                   cdf=lambda y: stats.norm.cdf(y, mean, std))


def uniform(low: float, high: float) -> Density:
    if not low < high:
        raise ValueError(f"uniform: needs low < high, got {low!r}, {high!r}")
    return Density(f"U({low:.6g}, {high:.6g})", lambda y: np.zeros_like(y, dtype=float), mode=0.5 * (low + high),
                   cdf=lambda y: np.clip((y - low) / (high - low), 0.0, 1.0), support=(low, high))


def _positive(law, **values):
    for name, value in values.items():
        if not value > 0:
            raise ValueError(f"{law}: {name} must be > 0, got {value!r}")


def oscillator_x(sigma, c, k) -> Density:
    _positive("oscillator_x", sigma=sigma, c=c, k=k)
    return normal(0.0, sigma / math.sqrt(2 * c * k), f"x ~ N(0, sigma^2/(2ck)), sd {sigma / math.sqrt(2 * c * k):.4g}")


def oscillator_v(sigma, c, m) -> Density:
    _positive("oscillator_v", sigma=sigma, c=c, m=m)
    return normal(0.0, sigma / math.sqrt(2 * c * m), f"v ~ N(0, sigma^2/(2cm)), sd {sigma / math.sqrt(2 * c * m):.4g}")


def cubic_oscillator_x(sigma, c, k, k3) -> Density:
    _positive("cubic_oscillator_x", sigma=sigma, c=c)
    if not (k >= 0 and k3 >= 0 and k + k3 > 0):
        raise ValueError(f"cubic_oscillator_x: needs k, k3 >= 0, not both 0, got {k!r}, {k3!r}")
    beta = 2 * c / sigma ** 2
    scale = min(math.sqrt(1 / (beta * k)) if k > 0 else math.inf, (1 / (beta * k3)) ** 0.25 if k3 > 0 else math.inf)
    return Density("p(x) ~ exp(-(2c/sigma^2)(k x^2/2 + k3 x^4/4))",
                   lambda y: -beta * (0.5 * k * y ** 2 + 0.25 * k3 * y ** 4), scale=scale)


def coulomb_dashpot_v(sigma, m, c, alpha) -> Density:
    _positive("coulomb_dashpot_v", sigma=sigma, m=m)
    if not (c >= 0 and alpha >= 0 and c + alpha > 0):
        raise ValueError(f"coulomb_dashpot_v: needs c, alpha >= 0, not both 0, got {c!r}, {alpha!r}")
    beta = 2 * m / sigma ** 2
    scale = min(math.sqrt(1 / (beta * c)) if c > 0 else math.inf, 1 / (beta * alpha) if alpha > 0 else math.inf)
    return Density("p(v) ~ exp(-(2m/sigma^2)(c v^2/2 + alpha |v|))",
                   lambda y: -beta * (0.5 * c * y ** 2 + alpha * np.abs(y)), kinks=(0.0,), scale=scale)


# Where a built-in law's parameter comes from when [law] does not give it: a scene key; NOISE is the scene's
# white-noise intensity (load.intensity of kind = "white_noise", else load.noise_intensity); None: required.
NOISE = "<noise intensity>"


@dataclass(frozen=True)
class LawKind:
    make: Callable
    parameters: dict        # name -> default source (a scene key, NOISE, or None: required in [law])
    description: str


LAWS = {
    "normal": LawKind(normal, {"mean": None, "std": None}, "N(mean, std^2)"),
    "uniform": LawKind(uniform, {"low": None, "high": None}, "uniform on [low, high]"),
    "oscillator_x": LawKind(oscillator_x, {"sigma": NOISE, "c": "damper.c", "k": "spring.k0"},
                            "x of m x'' + c x' + k x = sigma xi: N(0, sigma^2/(2ck))"),
    "oscillator_v": LawKind(oscillator_v, {"sigma": NOISE, "c": "damper.c", "m": "mass.m"},
                            "v of m x'' + c x' + k x (+ k3 x^3) = sigma xi: N(0, sigma^2/(2cm))"),
    "cubic_oscillator_x": LawKind(cubic_oscillator_x, {"sigma": NOISE, "c": "damper.c", "k": "spring.k0",
                                                       "k3": "cubic.k3"},
                                  "x of m x'' + c x' + k x + k3 x^3 = sigma xi: "
                                  "exp(-(2c/sigma^2)(k x^2/2 + k3 x^4/4))"),
    "coulomb_dashpot_v": LawKind(coulomb_dashpot_v, {"sigma": NOISE, "m": "mass.m", "c": "damper.c",
                                                     "alpha": "friction.alpha"},
                                 "v of m v' + c v + alpha sign(v) = sigma xi: "
                                 "exp(-(2m/sigma^2)(c v^2/2 + alpha |v|))"),
}
