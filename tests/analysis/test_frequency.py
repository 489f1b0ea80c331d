"""The frequency domain (prandtl_fmu/frequency/, issue 47): K(A), D(A) and the loss factor against closed forms
written here (one elastic-perfectly-plastic branch, their sums over random parallel branches, the cubic spring,
the Maxwell element, a delay, a history, Segalman's micro-slip power law, the continuum's Masing form), and the
frequency response against the linear responses (nothing slips, everything slips) and the two branches of a
Duffing oscillator's jump."""
import math
import re

import numpy as np
import pytest

from prandtl_fmu.frequency import FrequencyError, describe_amplitudes, frequency_response, parse_scene

from tests.conftest import scene_text


def element(**tables):
    """A scene of ``tables`` (no [load], no [solver]: describe needs neither)."""
    return parse_scene(scene_text(tables))[0]


def epp(k, eta, A):
    """(K, D) of one elastic-perfectly-plastic branch on its steady cycle x = A sin(theta): the issue's forms."""
    if A <= eta:
        return k, 0.0
    beta = math.acos(1.0 - 2.0 * eta / A)
    return k / math.pi * (beta - math.sin(2.0 * beta) / 2.0), 4.0 * k * eta * (A - eta)


# ----------------------------------------------------------------- K(A), D(A): exact on piecewise-linear cycles

@pytest.mark.parametrize("A", [0.05, 0.1, 0.1000001, 0.13, 0.2, 1.0, 50.0])
def test_one_branch_gives_the_elastic_perfectly_plastic_closed_form(A):
    k, eta = 2.5, 0.1
    d = describe_amplitudes(element(branches={"k": [k], "eta": [eta]}), [A])
    K, D = epp(k, eta, A)
    assert d.method == ("exact",) and d.error[0] == 0.0
    assert d.stiffness[0] == pytest.approx(K, rel=1e-12)
    assert d.dissipation[0] == pytest.approx(D, rel=1e-11, abs=1e-15 * k * A * A)
    assert d.loss_factor[0] == pytest.approx(D / (math.pi * K * A * A), rel=1e-11, abs=1e-15)


@pytest.mark.parametrize("seed", range(6))
def test_random_parallel_branches_add_their_closed_forms(seed):
    """K and D add over parallel effects: random branches (some with u0 != 0, on the O(n) kernel and, with 80,
    on the memory stack), a spring and a cubic spring against the sum of the closed forms."""
    rng = np.random.default_rng(seed)
    n = [1, 3, 7, 12, 80, 80][seed]
    k = rng.uniform(0.1, 2.0, n)
    eta = rng.uniform(0.01, 1.0, n)
    u0 = rng.uniform(-1, 1, n) * eta if seed % 2 else np.zeros(n)
    k0, k3 = rng.uniform(0, 1), rng.uniform(0, 3)
    scene = element(spring={"k0": k0}, cubic={"k3": k3}, branches={"k": k, "eta": eta, "u0": u0})
    amplitudes = np.sort(rng.uniform(0.005, 1.5, 5))
    d = describe_amplitudes(scene, amplitudes)
    for A, K, D in zip(amplitudes, d.stiffness, d.dissipation):
        forms = np.array([epp(ki, ei, A) for ki, ei in zip(k, eta)])
        assert K == pytest.approx(k0 + 0.75 * k3 * A * A + forms[:, 0].sum(), rel=1e-13)
        assert D == pytest.approx(forms[:, 1].sum(), rel=1e-11, abs=1e-15)


def test_springs_alone_and_a_dashpot_at_a_frequency():
    scene = element(spring={"k0": 3.0}, cubic={"k3": 2.0}, damper={"c": 0.4})
    with pytest.raises(FrequencyError, match="rate"):
        describe_amplitudes(scene, [0.1])
    f = 2.0
    d = describe_amplitudes(scene, [0.1, 1.0], frequency=f)
    A = d.amplitude
    assert np.allclose(d.stiffness, 3.0 + 0.75 * 2.0 * A**2, rtol=1e-13)
    assert np.allclose(d.dissipation, math.pi * 0.4 * 2 * math.pi * f * A**2, rtol=1e-13)
    assert d.frequency == f


@pytest.mark.parametrize("A", [0.01, 0.1])
def test_a_masing_backbone_against_masings_rules_on_the_smooth_curve(A):
    """[masing] hyperbolic: 200 branches interpolating F_b(x) = k x / (1 + k x / f_u) (exact on them); against
    Masing's D = 8 int_0^A F_b - 4 A F_b(A) and the rising branch -F_b(A) + 2 F_b((A + x)/2) of the smooth curve,
    to the interpolation's error (below 1e-3 here; docs/masing.md bounds it)."""
    k, ultimate = 1000.0, 10.0
    scene = element(masing={"kind": "hyperbolic", "k": k, "f_u": ultimate, "count": 200, "x_max": 0.2})
    d = describe_amplitudes(scene, [A])

    def backbone(x):
        return k * x / (1 + k * np.abs(x) / ultimate)

    nodes, weights = np.polynomial.legendre.leggauss(400)
    D = 8 * 0.5 * A * np.sum(weights * backbone(0.5 * A * (nodes + 1))) - 4 * A * backbone(A)
    theta = 0.5 * math.pi * nodes
    a1 = np.sum(weights * (-backbone(A) + 2 * backbone((A + A * np.sin(theta)) / 2)) * np.sin(theta))
    assert d.method == ("exact",)
    assert d.stiffness[0] == pytest.approx(a1 / A, rel=1e-3)
    assert d.dissipation[0] == pytest.approx(D, rel=1e-3)


def test_coulomb_friction_on_the_mass_dissipates_4_alpha_A():
    scene = element(mass={"m": 1.0}, spring={"k0": 1.0}, friction={"alpha": 0.3})
    d = describe_amplitudes(scene, [0.2, 2.0])
    assert np.allclose(d.stiffness, 1.0, rtol=1e-13)
    assert np.allclose(d.dissipation, 4 * 0.3 * d.amplitude, rtol=1e-13)


# ----------------------------------------------------------------- the exact method at the edges of A / eta

def epp_precise(k, eta, A, digits=60):
    """(K, D) of one branch by the issue's forms with acos(1 - 2 eta / A) in ``digits`` decimal digits (mpmath):
    the truth where eta / A is below the rounding of 1 in double precision."""
    import mpmath

    with mpmath.workdps(digits):
        k, eta, A = mpmath.mpf(float(k)), mpmath.mpf(float(eta)), mpmath.mpf(float(A))
        if A <= eta:
            return k, mpmath.mpf(0)
        beta = mpmath.acos(1 - 2 * eta / A)
        return k / mpmath.pi * (beta - mpmath.sin(2 * beta) / 2), 4 * k * eta * (A - eta)


@pytest.mark.parametrize("tables, A", [
    ({"spring": {"k0": 1.0}, "branches": {"k": [1e18], "eta": [1e-18]}}, 1.0),  # was K = 2, D = 0
    ({"branches": {"k": [1.0], "eta": [1e-6]}}, 10.0),  # A / eta = 1e7: K was 1.4e-6 off
    ({"branches": {"k": [1.0], "eta": [1e-6]}}, 1e5),  # 1e11: 130 % off
    ({"branches": {"k": [1.0, 0.5], "eta": [0.1, 0.3]}}, 1e16),  # D was 0
    ({"branches": {"k": [1e16, 1e15], "alpha": [1.0, 1.0]}}, 0.01),  # K was 0.080 for 7.06e-5
    ({"spring": {"k0": 1.0}, "branches": {"k": [1.0, 0.5], "eta": [0.1, 0.3]}}, 1e-162),  # K was 3.145 for 2.5
    ({"spring": {"k0": 1.0}, "branches": {"k": [1.0], "eta": [0.1]}}, 1e154),  # was "no stiffness in phase"
])
def test_a_tiny_elastic_range_against_the_amplitude_keeps_its_digits(tables, A):
    """K and D of branches whose eta / A is below the rounding of 1 (or whose A^2 over- or underflows) against
    the closed forms in 60 digits."""
    scene = element(**tables)
    d = describe_amplitudes(scene, [A])
    branches = scene.branches
    forms = [epp_precise(k, eta, A) for k, eta in zip(branches.stiffness, branches.yield_displacement)]
    k0 = scene.spring.k0 if scene.spring is not None else 0.0
    K, D = k0 + sum(f[0] for f in forms), sum(f[1] for f in forms)
    assert d.method == ("exact",)
    assert d.stiffness[0] == pytest.approx(float(K), rel=1e-12)
    assert d.dissipation[0] == pytest.approx(float(D), rel=1e-12, abs=0.0)
    assert d.loss_factor[0] == pytest.approx(float(D / (math.pi * K * A * A)), rel=1e-12, abs=0.0)


def test_random_branches_at_random_extremes_of_eta_over_A():
    """40 random elements (1 to 4 branches, k in [1e-10, 1e10], eta in [1e-20, 1e5], a spring or none) at
    A in [1e-150, 1e150] against the closed forms in 400 digits: K, D and the loss factor to 2e-15 (the
    difference y - sin(y) of the stick angle lost up to 2.5e-13 just above a series switched at y = 1e-2)."""
    import mpmath

    rng = np.random.default_rng(1)
    for _ in range(40):
        n = int(rng.integers(1, 5))
        k, eta = 10.0 ** rng.uniform(-10, 10, n), 10.0 ** rng.uniform(-20, 5, n)
        k0 = 10.0 ** rng.uniform(-5, 5) if rng.random() < 0.5 else 0.0
        A = 10.0 ** rng.uniform(-150, 150)
        d = describe_amplitudes(element(spring={"k0": k0}, branches={"k": k, "eta": eta}), [A])
        with mpmath.workdps(400):
            forms = [epp_precise(ki, ei, A, 400) for ki, ei in zip(k, eta)]
            K, D = k0 + sum(f[0] for f in forms), sum(f[1] for f in forms)
            loss = D / (mpmath.pi * K * mpmath.mpf(A) ** 2)
            for computed, truth in ((d.stiffness[0], K), (d.dissipation[0], D), (d.loss_factor[0], loss)):
                assert abs(computed - truth) <= 2e-15 * abs(truth), (k, eta, k0, A, computed, truth)


def test_a_dashpot_or_coulomb_friction_alone_has_an_infinite_loss_factor():
    """K = 0 and D = pi c w A^2 or 4 alpha A: answered, the loss factor inf (an empty field in the CSV)."""
    f, A = 0.5, 0.5
    d = describe_amplitudes(element(damper={"c": 1.0}), [A], frequency=f)
    assert d.stiffness[0] == 0.0 and d.loss_factor[0] == math.inf
    assert d.dissipation[0] == pytest.approx(math.pi * 1.0 * 2 * math.pi * f * A * A, rel=1e-15)
    assert d.columns()["loss_factor"] == [None]
    d = describe_amplitudes(element(mass={"m": 1.0}, friction={"alpha": 0.5}), [A])
    assert d.stiffness[0] == 0.0 and d.loss_factor[0] == math.inf
    assert d.dissipation[0] == pytest.approx(4 * 0.5 * A, rel=1e-15)


def test_a_cubic_spring_at_a_huge_amplitude_and_the_numbers_that_overflow_or_underflow():
    """3/4 k3 A^2 is finite at A = 1e103 (its A^3 is not); what overflows (K at 1e200, a dashpot's D at 1e300)
    or underflows (a cubic spring's K alone, a dashpot's D at 1e-200, a slipping branch's K at 1e300, a
    spectrum's D at 1e-200) is refused naming the amplitude; a part that underflows beside a larger one is
    rounding."""
    d = describe_amplitudes(element(spring={"k0": 1.0}, cubic={"k3": 2.0}), [1e103])
    assert d.stiffness[0] == pytest.approx(1.0 + 0.75 * 2.0 * 1e206, rel=1e-15)
    assert d.dissipation[0] == 0.0 and d.loss_factor[0] == 0.0
    d = describe_amplitudes(element(spring={"k0": 1.0}, cubic={"k3": 2.0}), [1e-200])  # 3/4 k3 A^2 is lost in k0
    assert d.stiffness[0] == 1.0
    cases = [(element(cubic={"k3": 2.0}), 1e-200, None, "K underflows"),
             (element(spring={"k0": 1.0}, cubic={"k3": 2.0}), 1e200, None, "K overflows"),
             (element(spring={"k0": 1.0}, damper={"c": 1.0}), 1e300, 1.0, "D overflows"),
             (element(spring={"k0": 1.0}, damper={"c": 1.0}), 1e-200, 1.0, "D underflows"),
             (element(mass={"m": 1.0}, spring={"k0": 1.0}, friction={"alpha": 1.0}), 1e-320, None, "D underflows"),
             (element(branches={"k": [1.0], "eta": [0.1]}), 1e300, None, "K underflows"),  # was K = 0, loss inf
             (_iwan(-0.5), 1e-200, None, "D underflows")]  # was D = 0, loss factor 0
    for scene, A, f, message in cases:
        with pytest.raises(FrequencyError, match=re.escape(f"at A = {A!r} m, {message}")):
            describe_amplitudes(scene, [A], frequency=f)


def test_the_exact_method_against_an_event_driven_cycle_from_any_u0():
    """The closed forms hold on the steady cycle whatever u0 (branches sticking at the start, some pre-loaded
    to +-eta): an event-driven play operator written here, moved 0 -> A -> -A -> A -> -A, then the last
    cycle's a_1, b_1 by Gauss-Legendre between its slip events (F is linear in x there)."""
    rng = np.random.default_rng(7)
    n = 9
    k = rng.uniform(0.1, 2.0, n)
    eta = rng.uniform(0.01, 1.0, n)
    u0 = rng.choice([-1.0, 1.0, 0.3, -0.7], n) * eta
    k0 = 0.4
    scene = element(spring={"k0": k0}, branches={"k": k, "eta": eta, "u0": u0})
    nodes, weights = np.polynomial.legendre.leggauss(20)
    for A in (0.05, 0.4, 3.0):
        u = u0.copy()
        for x_from, x_to in ((0.0, A), (A, -A), (-A, A), (A, -A)):
            u = np.clip(u + (x_to - x_from), -eta, eta)
        a1 = b1 = 0.0
        for x_from, sign in ((-A, 1.0), (A, -1.0)):  # the rising half from -A, then the falling half from A
            start = u.copy()
            slips = np.abs(sign * eta - start) / A  # x travelled (over A) until each branch slips
            ends = sorted({0.0, 2.0, *(s for s in slips if 0 < s < 2)})
            for lo, hi in zip(ends[:-1], ends[1:]):  # x - x_from = A (1 + sin(theta)) sign: travelled in [lo, hi]
                t_lo, t_hi = (math.asin(v - 1.0) for v in (lo, hi))
                t = 0.5 * (t_hi - t_lo) * nodes + 0.5 * (t_hi + t_lo)
                travelled = A * (1.0 + np.sin(t))
                x = x_from + sign * travelled
                branch = np.clip(start[:, None] + sign * travelled[None, :], -eta[:, None], eta[:, None])
                force = k0 * x + k @ branch
                theta = t if sign > 0 else math.pi + t  # x = A sin(theta) on the falling half too
                jacobian = 0.5 * (t_hi - t_lo)
                a1 += jacobian * np.sum(weights * force * np.sin(theta)) / math.pi
                b1 += jacobian * np.sum(weights * force * np.cos(theta)) / math.pi
            u = np.clip(start + sign * 2 * A, -eta, eta)
        d = describe_amplitudes(scene, [A])
        assert d.stiffness[0] == pytest.approx(a1 / A, rel=1e-12)
        assert d.dissipation[0] == pytest.approx(math.pi * A * b1, rel=1e-11, abs=1e-14)


def friction_precise(alpha, alpha_kinetic, stribeck_velocity, belt_velocity, A, f, digits=30):
    """D = oint F dx of the friction force F = sign(w) a(|w|) (w = x' - v_b) under x = A sin(theta), by mpmath
    over [0, 2 pi] cut where w changes sign."""
    import mpmath

    with mpmath.workdps(digits):
        speed = mpmath.mpf(A) * 2 * mpmath.pi * f
        r = belt_velocity / speed

        def force(theta):
            w = speed * mpmath.cos(theta) - belt_velocity
            size = alpha if stribeck_velocity is None else \
                alpha_kinetic + (alpha - alpha_kinetic) * mpmath.exp(-abs(w) / stribeck_velocity)
            return mpmath.sign(w) * size * A * mpmath.cos(theta)  # F dx / d theta

        cuts = [0, mpmath.acos(r), 2 * mpmath.pi - mpmath.acos(r), 2 * mpmath.pi] if abs(r) < 1 else \
            [0, mpmath.pi, 2 * mpmath.pi]
        return float(mpmath.quad(force, cuts))


@pytest.mark.parametrize("friction", [
    {"alpha": 0.5, "belt_velocity": 0.3},
    {"alpha": 0.5, "belt_velocity": -5.0},  # the belt outruns the mass: F constant, D = 0
    {"alpha": 0.5, "alpha_kinetic": 0.2, "stribeck_velocity": 0.1},
    {"alpha": 0.5, "alpha_kinetic": 0.2, "stribeck_velocity": 0.1, "belt_velocity": 2.0},  # negative D
    {"alpha": 0.5, "alpha_kinetic": 0.2, "stribeck_velocity": 1e-4, "belt_velocity": 0.3},
])
def test_friction_with_a_stribeck_drop_or_on_a_belt(friction):
    """Friction of the mass with a Stribeck drop or on a moving belt (refused before, while the frequency
    response took it): nothing in phase with x, D against oint F dx in 30 digits, within the error column;
    it needs the frequency."""
    scene = element(mass={"m": 1.0}, spring={"k0": 1.0}, friction=friction)
    with pytest.raises(FrequencyError, match=re.escape("[friction] with a Stribeck drop or a moving belt")):
        describe_amplitudes(scene, [0.1])
    f, A = 0.5, np.array([0.1, 0.5, 1.0])
    d = describe_amplitudes(scene, A, frequency=f)
    assert np.all(d.stiffness == 1.0)
    for amplitude, D, error in zip(A, d.dissipation, d.error):
        truth = friction_precise(friction["alpha"], friction.get("alpha_kinetic", friction["alpha"]),
                                 friction.get("stribeck_velocity"), friction.get("belt_velocity", 0.0), amplitude, f)
        assert error <= 1e-3
        assert abs(D - truth) <= max(error, 1e-13) * abs(truth) + 1e-15 * friction["alpha"] * amplitude


# ----------------------------------------------------------------- the quadrature, with its stated accuracy

def test_the_maxwell_element_of_a_series_dashpot_that_never_slips():
    """A branch k, c in series whose slider never slips is the Maxwell element: K + i D / (pi A^2) = k i w c /
    (k + i w c), to the stated accuracy."""
    k, c, f, A = 2.0, 0.5, 0.7, 0.1
    w = 2 * math.pi * f
    d = describe_amplitudes(element(branches={"k": [k], "eta": [1000.0], "c": [c]}), [A], frequency=f)
    exact = k * 1j * w * c / (k + 1j * w * c)
    assert d.method == ("quadrature",)
    assert abs(complex(d.stiffness[0], d.dissipation[0] / (math.pi * A * A)) - exact) <= 1e-3 * abs(exact)


def test_a_delay_and_a_history_against_their_transfer_functions():
    """The reaction's delay term gain x(t - tau) and history term int w exp(-r (t - s)) x(s) ds: complex
    stiffnesses gain exp(-i w tau) and w / (r + i w)."""
    f, A = 0.7, 0.1
    w = 2 * math.pi * f
    cases = [({"delay": {"gain": 0.5, "tau": 0.4}}, 0.5 * np.exp(-1j * w * 0.4)),
             ({"history": {"weight": [0.3], "rate": [2.0]}}, 0.3 / (2.0 + 1j * w))]
    for tables, transfer in cases:
        d = describe_amplitudes(element(spring={"k0": 1.0}, **tables), [A], frequency=f)
        exact = 1.0 + transfer
        assert abs(complex(d.stiffness[0], d.dissipation[0] / (math.pi * A * A)) - exact) <= 1e-3 * abs(exact)
        assert d.error[0] <= 1e-3


def test_the_quadratures_error_column_bounds_its_error_where_a_slip_kinks_the_force():
    """Branches with series dashpots that slip (a kink in theta at each slip, an uneven convergence): K and D
    at the default tolerance against the same at 1e-7, within the error column (in deep slip, A = 20, the
    last change alone said 2.5e-5 for an error of 6.4e-5)."""
    scene = element(spring={"k0": 0.5}, branches={"k": [1.0, 2.0], "eta": [0.1, 0.3], "c": [0.5, 0.2]})
    A = [0.15, 20.0]
    d = describe_amplitudes(scene, A, frequency=0.7)
    reference = describe_amplitudes(scene, A, frequency=0.7, tolerance=1e-7)
    assert d.method == ("quadrature",) * 2 and np.all(d.error <= 1e-3)
    for name in ("stiffness", "dissipation"):
        error = np.abs(getattr(d, name) / getattr(reference, name) - 1)
        assert np.all(error + reference.error <= d.error), (name, error, d.error)


@pytest.mark.parametrize("A", [0.002, 0.01, 0.05])
def test_dahl_friction_against_its_steady_loop(A):
    """Dahl's law with exponent 1 is rate independent; on its steady cycle the reversal force is
    F_r = F_c tanh(sigma A / F_c), the rising branch F(x) = F_c (1 - (1 + F_r / F_c) exp(-sigma (x + A) / F_c)),
    so D = 2 int F dx in closed form and a_1 by a Gauss rule here."""
    sigma, force = 50.0, 0.4
    d = describe_amplitudes(element(spring={"k0": 1.0}, dahl={"sigma": sigma, "force": force}), [A])
    a = sigma * A / force
    ratio = math.tanh(a)
    D = 2 * force * (2 * A - (1 + ratio) * force / sigma * (1 - math.exp(-2 * a)))
    nodes, weights = np.polynomial.legendre.leggauss(200)
    theta = 0.5 * math.pi * nodes
    rising = force * (1 - (1 + ratio) * np.exp(-sigma * (A * np.sin(theta) + A) / force))
    a1 = 2 / math.pi * 0.5 * math.pi * np.sum(weights * rising * np.sin(theta))  # the falling half alike
    assert d.method == ("quadrature",)
    assert d.stiffness[0] == pytest.approx(1.0 + a1 / A, rel=1e-3)
    assert d.dissipation[0] == pytest.approx(D, rel=1e-3)


def _iwan(chi, beta=0.5):
    return element(branches={"continuum": True, "density": {"kind": "iwan", "F_S": 1.0, "K_T": 1e6, "chi": chi,
                                                              "beta": beta}})


@pytest.mark.parametrize("chi", [-0.5, -0.2])
def test_segalman_micro_slip_dissipation_grows_like_A_to_the_3_plus_chi(chi):
    from prandtl_fmu.effects import iwan_parameters

    params = iwan_parameters(1.0, 1e6, chi, 0.5)
    A = params["phi_max"] * np.array([0.01, 0.03, 0.1, 0.3])
    d = describe_amplitudes(_iwan(chi), A)
    slope = np.polyfit(np.log(A), np.log(d.dissipation), 1)[0]
    assert slope == pytest.approx(3 + chi, abs=1e-3)
    segalman = 4 * params["R"] * A ** (chi + 3) / ((chi + 2) * (chi + 3))
    assert np.allclose(d.dissipation, segalman, rtol=1e-3)
    assert np.all(d.error <= 1e-3)


def spectrum_precise(branches, A, digits=30):
    """(K, D) of a spectrum (``ContinuousBranches``: eta linear on each segment, k(s) = coefficient eta(s)^power)
    by mpmath's quadrature of the branch forms in ``digits`` digits (a flat segment is one branch)."""
    import mpmath

    with mpmath.workdps(digits):
        A = mpmath.mpf(float(A))
        K = D = mpmath.mpf(0)
        for j in range(branches.coefficient.shape[0]):
            s0, s1 = mpmath.mpf(float(branches.s[j])), mpmath.mpf(float(branches.s[j + 1]))
            e0, e1 = mpmath.mpf(float(branches.eta[j])), mpmath.mpf(float(branches.eta[j + 1]))
            c, p = mpmath.mpf(float(branches.coefficient[j])), mpmath.mpf(float(branches.power[j]))
            if e0 == e1:
                k, d = epp_precise(c * e0**p * (s1 - s0), e0, A, digits)
                K, D = K + k, D + d
                continue
            eta = lambda s: e0 + (e1 - e0) * (s - s0) / (s1 - s0)  # noqa: E731
            cuts = [s0, *([s0 + (A - e0) / (e1 - e0) * (s1 - s0)] if e0 < A < e1 else []), s1]
            K += mpmath.quad(lambda s: c * eta(s) ** p * epp_precise(1, eta(s), A, digits)[0], cuts)
            D += mpmath.quad(lambda s: c * eta(s) ** p * epp_precise(1, eta(s), A, digits)[1], cuts)
        return K, D


def test_segalmans_joint_in_macro_slip_within_its_stated_error():
    """Segalman's joint (F_S = 3, K_T = 2, chi = -0.1, beta = 0.1) deep in macro-slip, where the sampled cycle
    was off by 1.9e-3 with an error column of 8.1e-4: K and D against the spectrum's integral in 30 digits,
    within the error column. K falls like A^(-3/2) there: every branch slips, and one that sticks for the angle
    beta ~ 2 sqrt(eta / A) after a reversal keeps K ~ (2 / 3 pi) k beta^3 ~ A^(-3/2)."""
    scene = element(branches={"continuum": True, "density": {"kind": "iwan", "F_S": 3.0, "K_T": 2.0, "chi": -0.1,
                                                              "beta": 0.1}})
    A = np.array([86284.40366972478, 3477651.4376180465])
    d = describe_amplitudes(scene, A)
    for amplitude, K, D, error in zip(A, d.stiffness, d.dissipation, d.error):
        K_true, D_true = (float(value) for value in spectrum_precise(scene.branches, amplitude))
        assert error <= 1e-3
        assert abs(K - K_true) <= max(error, 1e-13) * K_true
        assert abs(D - D_true) <= max(error, 1e-13) * D_true
    slope = np.diff(np.log(d.stiffness)) / np.diff(np.log(A))
    assert slope[0] == pytest.approx(-1.5, abs=1e-3)
    assert d.method == ("spectrum",) * 2


def _masing_linear_continuum(A, k, a, b):
    """K, D of the paper's continuum k(s) = k, eta(s) = a + (b - a) s from its backbone alone (Masing's rules):
    F_b(x) = int_0^1 k min(x, eta(s)) ds in closed form, D = 8 int_0^A F_b - 4 A F_b(A) and the rising branch
    F(x) = -F_b(A) + 2 F_b((A + x)/2), integrated by Gauss-Legendre on the pieces between the kinks (where the
    argument of F_b crosses a or b: F_b is a polynomial of degree <= 2 on each)."""
    def backbone(x):
        x = np.asarray(x, dtype=float)
        s = np.clip((x - a) / (b - a), 0.0, 1.0)
        return k * (a * s + (b - a) * s * s / 2 + x * (1 - s))

    nodes, weights = np.polynomial.legendre.leggauss(60)

    def integral(function, ends):
        total = 0.0
        for lo, hi in zip(ends[:-1], ends[1:]):
            total += 0.5 * (hi - lo) * np.sum(weights * function(lo + 0.5 * (hi - lo) * (nodes + 1)))
        return total

    D = 8 * integral(backbone, sorted({0.0, A, *(e for e in (a, b) if e < A)})) - 4 * A * backbone(A)
    kinks = [math.asin(2 * e / A - 1) for e in (a, b) if e < A]  # (A + A sin(theta)) / 2 = a or b
    theta_ends = sorted({-math.pi / 2, math.pi / 2, *kinks})
    a1 = 2 / math.pi * integral(lambda t: (-backbone(A) + 2 * backbone((A + A * np.sin(t)) / 2)) * np.sin(t),
                                theta_ends)  # the falling half gives the same (odd): twice the rising one
    return a1 / A, D


def test_the_continuum_against_its_masing_closed_form():
    scene = element(branches={"continuum": True, "k_total": 1.0, "eta_range": [0.1, 1.1]})
    A = np.array([0.05, 0.3, 0.8, 1.5, 4.0])
    d = describe_amplitudes(scene, A)
    for amplitude, K, D, error in zip(A, d.stiffness, d.dissipation, d.error):
        K_masing, D_masing = _masing_linear_continuum(amplitude, 1.0, 0.1, 1.1)
        assert K == pytest.approx(K_masing, rel=1e-3)
        assert D == pytest.approx(D_masing, rel=1e-3, abs=1e-12)
        assert error <= 1e-3
    assert d.method == ("spectrum",) * 5


def test_the_library_closed_forms_for_the_plots_agree():
    """The closed forms drawn over the plots (closed_forms.py) against the computed K and D."""
    from prandtl_fmu.frequency.closed_forms import closed_form

    scenes = [element(spring={"k0": 0.3}, branches={"k": [1.0, 2.0], "eta": [0.1, 0.4]}),
              element(branches={"continuum": True, "k_total": 1.0, "eta_range": [0.1, 1.1]}), _iwan(-0.5)]
    for scene in scenes:
        A = np.geomspace(1e-7, 1e-4, 4) if scene.branches.continuum and scene.branches.power[0] else \
            np.array([0.05, 0.3, 1.0])
        d = describe_amplitudes(scene, A)
        K, D = closed_form(scene, A)
        assert np.allclose(K, d.stiffness, rtol=2e-3)
        assert np.allclose(D, d.dissipation, rtol=2e-3, atol=1e-12 * np.max(D))


# ----------------------------------------------------------------- the frequency response

def damper_scene(**changes):
    tables = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.1},
              "branches": {"k": [1.0, 0.5], "eta": [0.1, 0.3]}}
    tables.update(changes)
    return element(**tables)


def linear(F0, f, k, m=1.0, c=0.1):
    w = 2 * math.pi * np.asarray(f)
    return F0 / np.abs(k - m * w**2 + 1j * c * w), -np.angle(k - m * w**2 + 1j * c * w)


def test_a_tiny_force_gives_the_linear_response_with_every_branch_sticking():
    f = np.array([0.1, 0.22, 0.25, 0.4])
    r = frequency_response(damper_scene(), 1e-4, f, sweep="up")
    amplitude, phase = linear(1e-4, r.frequency, 1.0 + 1.5)
    assert r.stepper == "exact"
    assert np.allclose(r.amplitude, amplitude, rtol=1e-3)
    assert np.allclose(r.phase, phase, atol=1e-3)
    assert r.sweep == ("up",) * 4 and np.all(r.error <= 1e-3)


def test_the_error_column_of_the_response_bounds_its_error_at_a_lightly_damped_resonance():
    """docs/frequency.md's friction damper (c = 0.02) at a tiny F0, at and near its resonance: the first harmonic
    against the linear one within the error column, which counts what the settling test leaves (the change
    of X under a doubling of M alone said 3.8e-5 for an error of 1.6e-4)."""
    scene = element(mass={"m": 1.0}, spring={"k0": 1.0}, damper={"c": 0.02}, branches={"k": [1.0], "alpha": [0.1]})
    f = math.sqrt(2.0) / (2 * math.pi) * np.array([0.99, 1.0])
    r = frequency_response(scene, 1e-4, f, sweep="up")
    amplitude, phase = linear(1e-4, f, 2.0, c=0.02)
    computed, exact = r.amplitude * np.exp(1j * r.phase), amplitude * np.exp(1j * phase)
    assert np.all(np.abs(computed - exact) <= r.error * np.abs(exact)), (np.abs(computed / exact - 1), r.error)
    assert np.all(r.error <= 1e-3)


def test_a_large_force_gives_the_response_of_k0_and_c_alone():
    """Every branch slips: the branches add a Coulomb force sum alpha_i sgn(v) (0.25 N), of relative size
    2.5e-5 against F0 = 1e4 N: the response is k0's and c's to the stated accuracy."""
    f = np.array([0.1, 0.16, 0.3])
    r = frequency_response(damper_scene(), 1e4, f, sweep="down")
    amplitude, phase = linear(1e4, r.frequency, 1.0)
    assert np.allclose(r.amplitude, amplitude, rtol=1e-3)
    assert np.allclose(r.phase, phase, atol=1e-3)
    assert r.sweep == ("down",) * 3 and list(r.frequency) == [0.3, 0.16, 0.1]


def test_the_two_sweeps_of_a_duffing_oscillator_find_both_sides_of_the_jump():
    """m x'' + c x' + k x + k3 x^3 = F0 cos(w t): sweeping up stays on the upper branch past the linear
    resonance, sweeping down on the lower one; the harmonic balance X^2 ((k + 3/4 k3 X^2 - m w^2)^2 + (c w)^2)
    = F0^2 gives both (to its own error, a few per cent at these amplitudes)."""
    m, k, k3, c, F0 = 1.0, 1.0, 1.0, 0.1, 0.3
    scene = element(mass={"m": m}, spring={"k0": k}, cubic={"k3": k3}, damper={"c": c})
    f = np.array([0.14, 0.18, 0.22, 0.25, 0.28, 0.31])
    r = frequency_response(scene, F0, f)
    assert r.stepper == "verlet" and sorted(set(r.sweep)) == ["down", "up"]

    def balance(frequency):
        w = 2 * math.pi * frequency
        a, b = 0.75 * k3, k - m * w * w
        roots = np.roots([a * a, 2 * a * b, b * b + (c * w) ** 2, -F0**2])
        return np.sort(np.sqrt(roots[(abs(roots.imag) < 1e-9) & (roots.real > 0)].real))

    up = dict(zip(r.frequency[np.array(r.sweep) == "up"], r.amplitude[np.array(r.sweep) == "up"]))
    down = dict(zip(r.frequency[np.array(r.sweep) == "down"], r.amplitude[np.array(r.sweep) == "down"]))
    for frequency in (0.22, 0.25):
        roots = balance(frequency)
        assert len(roots) == 3
        assert up[frequency] == pytest.approx(roots[-1], rel=0.03)
        assert down[frequency] == pytest.approx(roots[0], rel=0.03)
    for frequency in (0.14, 0.18, 0.31):  # one branch only: both sweeps agree
        assert up[frequency] == pytest.approx(down[frequency], rel=2e-3)


def test_a_mass_with_a_history_against_its_transfer_function():
    """A linear scene with memory (implicit, order 1, refined until X settles to 1e-3): X = F0 / (k0 + w_1 /
    (r_1 + i w) - m w^2 + i c w); one sweep (a history is linear)."""
    scene = element(mass={"m": 1.0}, spring={"k0": 1.0}, damper={"c": 0.2}, history={"weight": [0.3],
                                                                                      "rate": [2.0]})
    f = np.array([0.1, 0.2])
    r = frequency_response(scene, 1.0, f)
    w = 2 * math.pi * f
    impedance = 1.0 + 0.3 / (2.0 + 1j * w) - w**2 + 0.2j * w
    assert r.stepper == "implicit" and r.sweep == ("up", "up")
    assert np.allclose(r.amplitude, 1 / np.abs(impedance), rtol=1e-3)
    assert np.allclose(r.phase, -np.angle(impedance), atol=1e-3)


def test_a_mass_that_friction_holds_does_not_move():
    scene = element(mass={"m": 1.0}, spring={"k0": 1.0}, friction={"alpha": 1.0})
    r = frequency_response(scene, 0.5, [0.2], sweep="up")
    assert r.amplitude[0] == 0.0 and r.phase[0] == 0.0


def test_far_above_resonance_the_phase_is_minus_pi_until_the_motion_underflows():
    """m x'' + c x' + k x = F0 cos(w t) at f = 1e20 and 1e100 Hz against the linear response (x lags by pi);
    at 1e200 Hz F0 / (m w^2) ~ 1e-401 m underflows: refused naming the frequency, not amplitude 0, phase 0."""
    scene = element(mass={"m": 1.0}, spring={"k0": 1.0}, damper={"c": 0.1})
    for f in (1e20, 1e100):  # each from rest: continued from 1e20 Hz, x's offset of 1e-42 m hides 1e-202 m
        r = frequency_response(scene, 1.0, [f], sweep="up", stepper="verlet")
        amplitude, phase = linear(1.0, f, 1.0)
        assert r.amplitude[0] == pytest.approx(amplitude, rel=1e-3)
        assert abs(np.exp(1j * r.phase[0]) - np.exp(1j * phase)) < 1e-3
        assert abs(np.exp(1j * r.phase[0]) + 1) < 1e-3  # -pi (or pi)
    with pytest.raises(FrequencyError, match=re.escape("at f = 1e+200 Hz the mass moves about")):
        frequency_response(scene, 1.0, [1e200], sweep="up")


def test_a_response_that_cannot_settle_says_so(monkeypatch):
    from prandtl_fmu.frequency import response

    monkeypatch.setattr(response, "MAX_PERIODS", 3)
    scene = element(mass={"m": 1.0}, spring={"k0": 1.0}, damper={"c": 0.001})
    with pytest.raises(response.NotSettled, match="did not settle within 3 periods"):
        # verlet: the refusal is the driver's, whatever the stepper; verlet's loop for this model is the Duffing test's
        frequency_response(scene, 1.0, [0.1], sweep="up", stepper="verlet")


def test_bad_input_to_the_python_functions():
    scene = damper_scene()
    for call, culprit in [(lambda: describe_amplitudes(scene, [0.1, -1]), "amplitudes"),
                          (lambda: describe_amplitudes(scene, ["a"]), "amplitudes"),
                          (lambda: describe_amplitudes(scene, []), "amplitudes"),
                          (lambda: describe_amplitudes(scene, [0.1], frequency=0), "frequency"),
                          (lambda: describe_amplitudes(scene, [0.1], tolerance=2), "tolerance"),
                          (lambda: frequency_response(scene, 1.0, [0.1, 0.0]), "frequencies"),
                          (lambda: frequency_response(scene, -1.0, [0.1]), "force amplitude"),
                          (lambda: frequency_response(scene, 1.0, [0.1], sweep="sideways"), "sweep"),
                          (lambda: frequency_response(element(spring={"k0": 1.0}), 1.0, [0.1]), r"\[mass\]")]:
        with pytest.raises(FrequencyError, match=culprit):
            call()


@pytest.mark.slow
def test_the_frequencies_on_dask_give_the_serial_rows():
    pytest.importorskip("distributed")
    scene = damper_scene()
    f = [0.1, 0.2, 0.25, 0.3]
    serial = frequency_response(scene, 0.05, f)
    parallel = frequency_response(scene, 0.05, f, workers=2)
    rows = sorted(zip(parallel.sweep, parallel.frequency, parallel.amplitude))
    expected = sorted(zip(serial.sweep, serial.frequency, serial.amplitude))
    assert [row[:2] for row in rows] == [row[:2] for row in expected]
    assert np.allclose([row[2] for row in rows], [row[2] for row in expected], rtol=2e-3)
