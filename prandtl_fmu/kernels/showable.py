"""Outputs that are surely numbers, without computing them: bounds from the coefficients.

A caller that must never show an output that is not a number (the native FMU after every doStep: a step that
would show one is refused and rolled back) would compute every output after every step, and two of them walk
the branches: the tangent stiffness (the branches that stick) and the stored energy. Both are bounded by the
coefficients alone, whatever the state the kernels reach (every branch keeps |u_i| <= eta_i), and the rest are
polynomials in x and v. :func:`limits` turns that into three magnitudes: below them every output of the element
(its stiffness, kinetic and stored energy, and with them the energy account's residual) is surely a finite
number. The caller still computes the reaction (O(1)) and falls back to computing every output where a magnitude
is exceeded, so the verdict is always the exact one; the bounds only spare the work.

The bounds, with cap = SHOWABLE / 8 (DBL_MAX is 1.8e308; a sum of seven terms below cap is a number):

* stiffness: |k0| + 3 |k3| x^2 + the sticking k_i, at most sum |k_i| (the memory stack keeps it as a running
  total that drifts by rounding only: counted twice);
* stored energy: |k0| x^2 / 2 + |k3| x^4 / 4 + the branches'. On the n elongations, sum k_i u_i^2 / 2 with
  |u_i| <= eta_i exactly (the clip). On the memory stack, each piece's closed form (``stack.stored_energy``)
  expands (a + x + beta eta_i + gamma c_i)^2 with |beta| <= 1, gamma in {0, 1}, |c_i| <= eta_i (an admissible
  u0), and |a + x| <= 3 max eta plus the rounding of a + x, which the state's checks allow up to 1e-12 of
  |x| + max |a| (``stack._check_admissible``): counted as SLACK (4 |x| + 2 max eta + 2), a thousand times
  that. Every term of the expansion is then at most sum |k_i| (A + 2 max eta)^2, A that bound of |a + x|;
* kinetic energy m v^2 / 2; the account's entries and the initial energy are compared with cap as they are.

Each limit is halved once more for the rounding of these formulas. tests/fmu/native/test_showable_bounds.py checks
the bounds against the outputs computed at states pushed to them."""
import numpy as np

from .._jit import kernel
from .play import branch_bounds

SHOWABLE = 1e300
SLACK = 1e-9


@kernel
def limits(model, out):
    """Write (the largest |x|, the largest |v|, the largest magnitude of an energy account's entry and of the
    initial energy) at or below which every output of ``model``'s element is surely a finite number into
    ``out[0:3]``; 0.0 where no value is (coefficients too large)."""
    m, k0, k3, c, k, eta, cs, friction, memory = model
    mass, spring, cubic = _magnitude(m), _magnitude(k0), _magnitude(k3)
    total, largest = branch_bounds(k, eta)
    cap = SHOWABLE / 8.0
    x = np.inf
    if not spring + 2.0 * total <= 0.5 * cap:
        x = 0.0
    x = min(x, _square_below(0.5 * cap, 3.0 * cubic))  # the stiffness: 3 |k3| x^2
    x = min(x, _square_below(0.25 * cap, 0.5 * spring))  # the stored energy: |k0| x^2 / 2 ...
    x = min(x, np.sqrt(_square_below(0.25 * cap, 0.25 * cubic)))  # ... |k3| x^4 / 4 ...
    if total > 0.0:  # ... and the branches': 2 sum|k| (A + 2 max eta)^2 <= cap / 2, A = 3 max eta + SLACK (...)
        room = _square_below(cap, 4.0 * total) - 5.0 * largest
        x = min(x, max((room / SLACK - 2.0 * largest - 2.0) / 4.0, 0.0))
    out[0] = 0.5 * x
    out[1] = 0.5 * _square_below(cap, 0.5 * mass)
    out[2] = cap
    if not (out[0] >= 0.0 and out[1] >= 0.0):  # a NaN coefficient: nothing is sure
        out[0] = 0.0
        out[1] = 0.0


@kernel
def _magnitude(value):
    """|value|, 0 for an absent coefficient (None)."""
    if value is None:
        return 0.0
    return abs(value)


@kernel
def _square_below(budget, coefficient):
    """The largest z >= 0 with coefficient z^2 <= budget (inf for a zero coefficient), as a quotient of square
    roots: budget / coefficient overflows for a small coefficient, and a kernel calls no libm (sqrt is IEEE's)."""
    if coefficient == 0.0:
        return np.inf
    return np.sqrt(budget) / np.sqrt(coefficient)
