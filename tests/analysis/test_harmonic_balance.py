"""Harmonic balance (``prandtl_fmu/frequency/harmonic_balance.py``, ``continuation.py``, ``floquet.py``,
``modes.py``): the Duffing oscillator's single-harmonic closed form, the nonlinear mode of a mass on a Jenkins
element against the describing function, the time sweep at stable points, unstable points integrated, a network
from the command line, and bad input."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main
from prandtl_fmu.frequency import parse_scene, read_scene

from tests.analysis.test_describe_cli import read_csv, write
from tests.conftest import scene_text
from tests.analysis.test_frequency import epp

DUFFING = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "cubic": {"k3": 0.5}, "damper": {"c": 0.05}}
DAMPER = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.02},
          "branches": {"k": [1.0], "alpha": [0.1]}}


def element(tables):
    from tests.conftest import scene_text

    return parse_scene(scene_text(tables))[0]


def duffing_frequencies(a, m=1.0, k=1.0, k3=0.5, c=0.05, F=0.2):
    """The two omega (rad/s) of the single-term Duffing curve a^2 [(k + 3/4 k3 a^2 - m w^2)^2 + (c w)^2] = F^2 at
    each amplitude a (NaN past the peak): a quadratic in w^2."""
    stiff = k + 0.75 * k3 * a * a
    b = 2 * m * stiff - c * c
    disc = b * b - 4 * m * m * (stiff * stiff - F * F / (a * a))
    root = np.sqrt(np.where(disc >= 0, disc, np.nan))
    with np.errstate(invalid="ignore"):  # past the peak: NaN
        return np.sqrt((b - root) / (2 * m * m)), np.sqrt((b + root) / (2 * m * m))


@pytest.mark.slow
def test_duffing_with_one_harmonic_is_the_single_term_curve_its_folds_and_peak():
    from prandtl_fmu.frequency.curve import harmonic_response

    curve = harmonic_response(element(DUFFING), 0.2, [0.5 / (2 * math.pi), 2.0 / (2 * math.pi)], harmonics=1,
                              stability=False)
    w, a = 2 * math.pi * curve.frequency, curve.amplitude
    residual = a * a * ((1.0 + 0.375 * a * a - w * w) ** 2 + (0.05 * w) ** 2) - 0.04
    assert np.max(np.abs(residual)) <= 1e-10
    # the closed form's folds: the extrema of omega along the curve, parametrised by a (low branch up, high down)
    fine = np.linspace(1e-3, 3.0, 400001)
    low, high = duffing_frequencies(fine)
    keep = np.isfinite(low)
    path = np.concatenate((low[keep], high[keep][::-1]))
    inner = np.flatnonzero((np.diff(np.sign(np.diff(path))) != 0)) + 1
    folds = np.sort(path[inner])
    assert folds.size == 2 and curve.folds.size == 2
    assert np.sort(w[curve.folds]) == pytest.approx(folds, rel=1e-7)
    peak = fine[keep][-1]
    assert a.max() <= peak * (1 + 1e-9) and a.max() == pytest.approx(peak, rel=2e-3)
    # the curve passes both folds in order: up to the higher one, back to the lower, up to the end
    assert w[curve.folds[0]] > w[curve.folds[1]] and curve.frequency[-1] == pytest.approx(2.0 / (2 * math.pi))


@pytest.mark.slow
@pytest.mark.parametrize("c", [0.0, 0.05])
def test_one_harmonic_nonlinear_mode_of_a_jenkins_element_is_its_describing_function(c):
    """m x'' + c x' + k0 x + Jenkins(k, eta): m omega^2 = K(A), damping ratio D(A) / (2 pi K A^2) + c / (2 m omega),
    with K and D the elastic-perfectly-plastic closed forms; the AFT's quadrature converges to them."""
    from prandtl_fmu.frequency.modes import nonlinear_mode

    m, k0, k, eta = 2.0, 1.0, 3.0, 0.1
    tables = {"mass": {"m": m}, "spring": {"k0": k0}, "branches": {"k": [k], "eta": [eta]}}
    if c:
        tables["damper"] = {"c": c}
    amplitudes = [0.05, 0.15, 0.3, 1.0, 5.0]
    errors = []
    for samples in (256, 4096):
        backbone = nonlinear_mode(element(tables), 1, amplitudes, harmonics=1, samples=samples)
        error = 0.0
        for A, f, zeta in zip(amplitudes, backbone.frequency, backbone.damping_ratio):
            K, D = epp(k, eta, A)
            K += k0
            omega = math.sqrt(K / m)
            expected = D / (2 * math.pi * K * A * A) + c / (2 * m * omega)
            error = max(error, abs(f - omega / (2 * math.pi)) / f, abs(zeta - expected) / max(expected, 1e-3))
        errors.append(error)
    assert errors[1] <= 1e-4 and errors[1] < errors[0] / 4  # the trapezoid rule over a kinked cycle: ~ 1 / N^2


def test_a_backbone_whose_family_turns_back_at_the_node_is_refused_not_continued_on_another_mode(tmp_path):
    """The packaged two-mass joint's first mode (in phase) at node a: as the joint slips and the cubic spring
    on a stiffens, the family's motion moves to b, and a's first harmonic turns back at about 0.853 m. The
    backbone stepped the amplitude at a and, past the turn, Newton landed on the second mode's family: from
    0.885 m mode 1 and mode 2 gave the same rows to 4 digits, silently (a review's find). Now each step must
    stay on the family (the mass-weighted MAC of the first harmonics of two points at least 0.5), and past the
    turn the backbone is refused in one line that says how far the family was followed: to within 1e-3 of the
    turn that shooting on the exact motion finds (a slider of 1e-6 N in the joint sends the scene there: it
    follows the family by arc length). At node b the same family goes on (rows unlike those of mode 2 at a, the
    family the old backbone went on along)."""
    from prandtl_fmu.frequency import FrequencyError
    from prandtl_fmu.frequency.modes import nonlinear_mode
    import re

    joint, _ = read_scene("networks/two-mass-joint", networks=True)
    with pytest.raises(FrequencyError, match="does not reach A = 1.0 m at node a") as refusal:
        nonlinear_mode(joint, 1, [0.3, 1.0], harmonics=5)
    reached = float(re.search(r"followed to ([0-9.e+-]+) m", str(refusal.value)).group(1))
    path = tmp_path / "slider.toml"
    with open(joint.source) as written:
        path.write_text(written.read() + '\n[[network.slider]]\nbetween = ["a", "b"]\nalpha = 1e-6\n')
    slider, _ = read_scene(str(path), networks=True)
    with pytest.raises(FrequencyError, match="does not reach A = 1.0 m at node a") as exact:
        nonlinear_mode(slider, 1, [0.3, 1.0])
    top = float(re.search(r"at most ([0-9.e+-]+) m", str(exact.value)).group(1))
    assert reached == pytest.approx(top, rel=1e-3) and reached < 0.9
    first = nonlinear_mode(joint, 1, [0.5, 1.0, 2.0], harmonics=5, node="b")
    second = nonlinear_mode(joint, 2, [1.0, 2.0], harmonics=5)  # the family the old backbone went on along
    assert np.all(np.isfinite(first.frequency)) and np.all(np.isfinite(first.damping_ratio))
    assert np.all(np.abs(first.frequency[1:] - second.frequency) > 1e-3 * second.frequency)


def test_a_backbone_s_value_does_not_depend_on_the_amplitudes_listed(tmp_path):
    """Three unit masses, springs and three branches (no slider: harmonic balance): mode 2's family at node a
    rises to 0.0594 m and turns back (a fold of the backbone). At 0.05 m it passes twice, with alike shapes:
    one step from the linear mode, or from 0.005 m, landed on the way back (0.2918 Hz, damping ratio 0.1005),
    a listing from 0.01 m on the way up (0.2981 Hz, 0.0517): the value depended on the amplitudes listed (a
    review's find). Each step must now also keep the frequency within 5 % and the damping ratio within 0.02 of
    the last point's, halved where it does not: every listing gives the way up, and past the fold the backbone
    is refused in one line."""
    from prandtl_fmu.frequency import FrequencyError
    from prandtl_fmu.frequency.modes import nonlinear_mode
    from tests.analysis.test_harmonic_balance_network_friction import network, network_text

    scene = network(tmp_path, network_text(["a", "b", "c"], [1.0, 1.0, 1.0], [
        ("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "a"], {"k": 1.0}), ("spring", ["b", "c"], {"k": 1.0}),
        ("branch", ["a", "b"], {"k": 2.0, "eta": 0.01}), ("branch", ["c", "ground"], {"k": 5.0, "eta": 0.03}),
        ("branch", ["b", "ground"], {"k": 1.0, "eta": 0.1})], load_node="a"))
    values = []
    # the last listing steps up the family by 3 % a time from where nothing slips: the way up by construction
    for listed in ([0.05], [0.005, 0.05], [0.01, 0.05], list(np.geomspace(1e-4, 0.05, 200))):
        backbone = nonlinear_mode(scene, 2, listed, harmonics=3, node="a")
        values.append((backbone.frequency[-1], backbone.damping_ratio[-1]))
    assert np.allclose(values, values[-1], rtol=1e-8, atol=0), values
    with pytest.raises(FrequencyError, match="does not reach A = 0.07 m at node a"):
        nonlinear_mode(scene, 2, [0.07], harmonics=3, node="a")


def test_the_mode_of_branches_without_a_spring_starts_from_one_harmonic(tmp_path):
    """Branches alone (k0 = 0, as the paper's section 8: no mean among the unknowns) at one harmonic, where the
    amplitude fixes both of the node's unknowns: Newton's step over the others is empty (it stopped on numpy's
    "zero-size array" for 14 of the packaged scenes). Below every threshold the mode is the linear one,
    sqrt(sum k / m), undamped; above the lowest, K(A) of the elastic-perfectly-plastic closed form."""
    m, k, eta = 2.0, [1.0, 3.0], [0.1, 0.2]
    path = write(tmp_path, {"mass": {"m": m}, "branches": {"k": k, "eta": eta}})
    out = tmp_path / "mode.csv"
    assert main(["describe", path, "--mode", "1", "--amplitudes", "0.05,0.15", "--out", str(out)]) == 0
    rows = read_csv(out)
    assert float(rows["frequency"][0]) == pytest.approx(math.sqrt(sum(k) / m) / (2 * math.pi), rel=1e-9)
    assert abs(float(rows["damping_ratio"][0])) <= 1e-9
    K = k[1] + epp(k[0], eta[0], 0.15)[0]
    assert float(rows["frequency"][1]) == pytest.approx(math.sqrt(K / m) / (2 * math.pi), rel=2e-3)


@pytest.mark.slow
def test_stable_points_agree_with_the_time_sweep_on_a_friction_damper():
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.response import frequency_response

    scene = element(DAMPER)
    curve = harmonic_response(scene, 0.1, [0.15, 0.19], harmonics=7)
    assert np.all(curve.stable)
    picks = [np.argmin(np.abs(curve.frequency - f)) for f in (0.16, 0.17, 0.18)]
    response = frequency_response(scene, 0.1, curve.frequency[picks], sweep="up", tolerance=1e-4)
    assert response.amplitude == pytest.approx(curve.amplitude[picks], rel=3e-4)
    assert response.phase == pytest.approx(curve.phase[picks], abs=3e-4)


def _first_harmonic_after(balance, q, omega, periods):
    """The first-harmonic amplitude of x at the load's node over the last of ``periods`` periods integrated with
    the implicit network stepper from the orbit's start (2048 steps per period: backward Euler's damping per
    period, about (2 pi)^2 / (2 steps), is 1 % here)."""
    from prandtl_fmu.frequency.floquet import orbit_start, run_periods

    steps = 2048
    x, _ = run_periods(balance, omega, orbit_start(balance, q, omega), periods, steps)
    weights = np.exp(-1j * 2 * math.pi * np.arange(1, steps + 1) / steps) * 2 / steps
    return abs(x[:, balance.system.load_node] @ weights)


@pytest.mark.slow
def test_points_marked_unstable_leave_their_orbit_and_stable_ones_keep_it():
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    scene, _ = read_scene("networks/two-mass-joint", networks=True)
    curve = harmonic_response(scene, 0.2, [0.1, 0.4], harmonics=5)
    assert curve.folds.size == 2
    first, second = curve.folds
    unstable = np.flatnonzero(~curve.stable)
    assert unstable.size and first <= unstable.min() and unstable.max() <= second  # between the folds only
    balance = HarmonicBalance(periodic_system(scene), 5, 0.2)
    for index, leaves in ((unstable[unstable.size // 2], True), (first // 2, False)):
        omega = 2 * math.pi * curve.frequency[index]
        q = curve.coefficients[index].reshape(-1)[balance.free]
        after = _first_harmonic_after(balance, q, omega, 60)
        moved = abs(after - curve.amplitude[index]) / curve.amplitude[index]
        assert (moved > 0.1) if leaves else (moved < 1e-2), (index, moved)


@pytest.mark.slow
def test_a_network_with_a_joint_end_to_end_from_the_command_line(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "curve.csv"
    plot = tmp_path / "curve.png"
    assert main(["describe", "networks/two-mass-joint", "--force-amplitude", "0.2", "--frequencies", "0.1,0.4",
                 "--harmonics", "3", "--out", str(out), "--plot", str(plot), "--mode", "2", "--amplitudes",
                 "0.1,0.5,1,2"]) == 0  # (the second mode's family carries a's large motion; the first turns back)
    table = read_csv(out)
    assert list(table)[:6] == ["frequency", "amplitude", "phase", "stable", "amplitude_a", "amplitude_b"]
    f = np.array(table["frequency"], dtype=float)
    assert f[0] == 0.1 and f[-1] == pytest.approx(0.4, rel=1e-12)
    assert set(table["stable"]) == {"true", "false"} and table["fold"].count("true") == 2
    assert np.allclose(np.array(table["amplitude"], dtype=float), np.array(table["amplitude_a"], dtype=float),
                       rtol=1e-14, atol=0)
    # every point's multiplier (all nodes have a mass: the variational equation), never nan
    computed = [cell for cell in table["multiplier"] if cell != ""]
    assert len(computed) == len(table["multiplier"])
    assert all(np.isfinite(float(cell)) and float(cell) > 0 for cell in computed)
    assert "nan" not in out.read_text().lower() and "inf" not in out.read_text().lower()
    assert plot.read_bytes()[:4] == b"\x89PNG"
    backbone = tmp_path / "backbone.csv"
    assert main(["describe", "networks/two-mass-joint", "--mode", "2", "--amplitudes", "0.01,0.5,2", "--harmonics",
                 "3", "--out", str(backbone), "--plot", str(tmp_path / "backbone.png")]) == 0
    assert (tmp_path / "backbone.png").read_bytes()[:4] == b"\x89PNG"
    modes = read_csv(backbone)
    assert list(modes) == ["amplitude", "frequency", "damping_ratio"]
    zeta = np.array(modes["damping_ratio"], dtype=float)
    assert zeta[1] > 2 * zeta[0] > 0  # the out-of-phase mode: the joint slips at 0.5 m; at 0.01 m it sticks


@pytest.mark.parametrize("arguments, culprit", [
    (["--force-amplitude", "1", "--frequencies", "0.1", "--harmonics", "0"], "--harmonics"),
    (["--force-amplitude", "1", "--frequencies", "0.1", "--harmonics", "two"], "--harmonics"),
    (["--force-amplitude", "1", "--frequencies", "0.1", "--sweep", "up"], "--sweep"),
    (["--force-amplitude", "1", "--frequencies", "0.1", "--method", "time", "--harmonics", "3"], "--harmonics"),
    (["--force-amplitude", "1", "--frequencies", "0.1", "--node", "nowhere"], "--node"),
    (["--mode", "1"], "--amplitudes"),
    (["--mode", "0", "--amplitudes", "0.1"], "--mode"),
    (["--mode", "2", "--amplitudes", "0.1"], "--mode"),
    (["--mode", "1", "--amplitudes", "0.1", "--frequencies", "0.1"], "--frequencies"),
    (["--mode", "1", "--amplitudes", "0.1", "--force-amplitude", "1", "--frequencies", "0.1"], "--plot"),
])
def test_bad_input_is_one_line_and_exit_2_with_nothing_written(tmp_path, capsys, arguments, culprit):
    out = tmp_path / "out.csv"
    status = main(["describe", write(tmp_path, DAMPER), *arguments, "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2, err
    assert culprit in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not out.exists()


def test_what_harmonic_balance_does_not_take_is_named(tmp_path, capsys):
    out = tmp_path / "out.csv"
    # (sliders and [friction] on the mass: the forced response by shooting, their own tests; massless nodes on
    # sliders: levers there, or refused, test_series.py; here every node is massless)
    scene = "networks/chain-massless"
    assert main(["describe", scene, "--force-amplitude", "1", "--frequencies", "0.1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    # it names what does work: the time integration of the network (describe's --method time takes element
    # scenes only)
    assert "massless" in err and "prandtl-fmu run" in err and len(err.strip().splitlines()) == 1
    assert main(["describe", scene, "--force-amplitude", "1", "--frequencies", "0.1", "--method", "time"]) == 2
    assert "element scene" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.slow
def test_the_harmonics_chosen_by_the_tolerance_reach_it():
    """Without H, the curve's first harmonic at its peak is within the tolerance of H = 21's there."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    scene = element(DAMPER)
    curve = harmonic_response(scene, 0.1, [0.15, 0.19], tolerance=1e-3, stability=False)
    assert curve.harmonics > 1 and curve.change <= 1e-3
    peak = int(np.argmax(curve.amplitude))
    reference = HarmonicBalance(periodic_system(scene), 21, 0.1)
    q = reference.solve_at(2 * math.pi * curve.frequency[peak])
    X = complex(reference.full(q)[1], -reference.full(q)[2])
    assert abs(abs(X) - curve.amplitude[peak]) <= 1e-3 * abs(X)


@pytest.mark.slow
def test_a_curve_that_cannot_continue_says_where_and_exits_2(tmp_path, capsys, monkeypatch):
    from prandtl_fmu.frequency import continuation

    monkeypatch.setattr(continuation, "_correct", lambda *args: None)
    monkeypatch.setattr(continuation, "_around_corner", lambda *args, **options: None)
    monkeypatch.setattr(continuation, "_damped", lambda *args: None)
    out = tmp_path / "out.csv"
    status = main(["describe", write(tmp_path, DAMPER), "--force-amplitude", "0.1", "--frequencies", "0.15,0.19",
                   "--harmonics", "3", "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2 and "cannot continue past f = 0.15 Hz" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_a_kink_of_the_sampled_forces_does_not_turn_the_curve_back(tmp_path):
    """networks/two-mass-joint at F0 = 0.5 N, H = 3: near 0.146 Hz a branch's slip puts a kink between two
    samples, where det [dR/dy; t] changes sign without a fold (a rank-one change of the Jacobian; the tangent's
    frequency share stays about +0.13 on both sides, and Newton at 0.1467 Hz from three guesses finds one
    solution). Orienting the tangent by that determinant alone sent the curve back and forth (481 points, 196
    false folds); kept on the side of the tangent before, it goes on: frequencies increasing, no fold, and the
    points there are the balance's solution at their frequency alone."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    scene, _ = read_scene("networks/two-mass-joint", networks=True)
    curve = harmonic_response(scene, 0.5, [0.05, 0.5], harmonics=3, stability=False)
    assert np.all(np.diff(curve.frequency) > 0) and curve.folds.size == 0
    balance = HarmonicBalance(periodic_system(scene), 3, 0.5)
    near = np.flatnonzero(np.abs(curve.frequency - 0.146) < 0.003)
    assert near.size >= 2
    for index in near:
        q = balance._newton(2 * math.pi * curve.frequency[index], curve.coefficients[index].reshape(-1)[balance.free]
                            * 1.2)
        assert q is not None
        assert math.hypot(balance.full(q)[1], balance.full(q)[2]) == pytest.approx(curve.amplitude[index], rel=1e-9)


def test_where_a_network_s_curve_stops_is_said_at_the_node_its_csv_reports(tmp_path, capsys, monkeypatch):
    """A curve that cannot continue names the amplitude the CSV's ``amplitude`` column would hold: at --node
    (here b, not the load's node a), absolute under base excitation."""
    import re

    from prandtl_fmu.frequency import continuation

    for extra in ([], ["--base-amplitude", "0.01"]):
        load = ["--force-amplitude", "1.0"] if not extra else extra
        common = ["describe", "networks/two-mass-joint", *load, "--harmonics", "3", "--node", "b"]
        out = tmp_path / "one.csv"
        assert main(common + ["--frequencies", "0.5", "--out", str(out)]) == 0
        expected = float(read_csv(out)["amplitude"][0])
        with monkeypatch.context() as patch:
            for name in ("_correct", "_around_corner", "_damped"):
                patch.setattr(continuation, name, lambda *args, **options: None)
            capsys.readouterr()
            assert main(common + ["--frequencies", "0.5,1.0", "--out", str(tmp_path / "two.csv")]) == 2
        err = capsys.readouterr().err
        said = re.search(r"first-harmonic amplitude (\S+) m at node (\w+)", err)
        assert said and said.group(2) == "b", err
        assert abs(float(said.group(1)) - expected) <= 1e-9 * expected, (said.group(1), expected)


def test_a_network_joint_s_describing_function_is_its_elements_closed_forms(tmp_path, capsys):
    """--between: the elements joining two nodes driven in the relative displacement; the two-mass joint's
    Jenkins branch (k = 2, eta = 0.05) gives the elastic-perfectly-plastic K and D; a slider beside a branch adds
    4 alpha A to D."""
    out = tmp_path / "joint.csv"
    amplitudes = [0.01, 0.05, 0.1, 1.0]
    assert main(["describe", "networks/two-mass-joint", "--amplitudes", ",".join(map(str, amplitudes)),
                 "--between", "b,a", "--out", str(out)]) == 0
    table = read_csv(out)
    for A, K, D in zip(amplitudes, table["stiffness"], table["dissipation"]):
        assert (float(K), float(D)) == pytest.approx(epp(2.0, 0.05, A), rel=1e-12, abs=1e-15)
    assert main(["describe", "networks/two-masses-slider", "--amplitudes", "0.01,1", "--between", "a,b", "--out",
                 str(out)]) == 0
    table = read_csv(out)
    for A, K, D in zip([0.01, 1.0], table["stiffness"], table["dissipation"]):
        K_b, D_b = epp(50.0, 0.02, A)
        assert (float(K), float(D)) == pytest.approx((K_b, D_b + 4 * 2.0 * A), rel=1e-12)
    for arguments, culprit in ((["--between", "a,nowhere"], "--between"), (["--between", "a,a"], "--between")):
        assert main(["describe", "networks/two-mass-joint", "--amplitudes", "0.1", *arguments]) == 2
        err = capsys.readouterr().err
        assert culprit in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_single_mode_synthesis_of_duffing_with_one_harmonic_is_the_single_term_curve():
    """EPMC of m x'' + c x' + k x + k3 x^3 with one harmonic: omega^2 = (k + 3/4 k3 a^2) / m, 2 zeta omega m = c; the
    synthesis then satisfies a^2 [(k + 3/4 k3 a^2 - m W^2)^2 + (c W)^2] = F^2 exactly, on both sides."""
    from prandtl_fmu.frequency.modes import nonlinear_mode, synthesis

    backbone = nonlinear_mode(element(DUFFING), 1, np.linspace(0.05, 2.5, 60), harmonics=1)
    f, a = synthesis(backbone, 0.2)
    W = 2 * math.pi * f
    assert f.size > 60  # both sides where the force reaches
    residual = a * a * ((1.0 + 0.375 * a * a - W * W) ** 2 + (0.05 * W) ** 2) - 0.04
    assert np.max(np.abs(residual)) <= 1e-9


def test_a_csv_cell_is_a_number_or_empty_never_nan(tmp_path):
    """The frequency domain's CSV writer: None is an empty field, a non-finite float a refusal (a defect), never
    a 'nan' or 'inf' cell that a reader takes for a number."""
    from prandtl_fmu.frequency.cli import csv_text

    assert csv_text({"a": [1.5, None], "b": ["true", "false"]}) == "a,b\n1.5,true\n,false\n"
    for bad in (float("nan"), float("inf"), np.float64(-np.inf)):
        with pytest.raises(ValueError, match="defect"):
            csv_text({"a": [bad]})


SPECTRA = {"linear": {"continuum": True, "k_total": 2.0, "eta_range": [0.05, 0.5]},
           "iwan": {"continuum": True, "density": {"kind": "iwan", "F_S": 1.0, "K_T": 5.0, "chi": -0.5, "beta": 0.1}}}


@pytest.mark.parametrize("spectrum", sorted(SPECTRA))
def test_one_harmonic_nonlinear_mode_on_a_spectrum_is_describe_s_spectrum_integral(spectrum):
    """A mass on k0 and a spectrum of branches (the continuum): harmonic balance takes the spectrum as branches at
    quadrature nodes, so with one harmonic the EPMC frequency is sqrt(K(A) / m) and the damping ratio
    D(A) / (2 pi K A^2), K and D describe's spectrum integral (Gauss-Legendre cut where eta(s) = A)."""
    from prandtl_fmu.frequency.describing import describe_amplitudes
    from prandtl_fmu.frequency.modes import nonlinear_mode

    m, tolerance = 2.0, 1e-4
    scene = element({"mass": {"m": m}, "spring": {"k0": 1.0}, "branches": SPECTRA[spectrum]})
    amplitudes = [0.02, 0.1, 0.3, 1.0]
    backbone = nonlinear_mode(scene, 1, amplitudes, harmonics=1, tolerance=tolerance, samples=2048)
    described = describe_amplitudes(scene, amplitudes, tolerance=tolerance / 10)
    assert set(described.method) == {"spectrum"}
    K, D, A = np.asarray(described.stiffness), np.asarray(described.dissipation), np.asarray(amplitudes)
    assert backbone.frequency == pytest.approx(np.sqrt(K / m) / (2 * math.pi), rel=tolerance)
    zeta = D / (2 * math.pi * K * A * A)
    assert np.all(zeta[1:] > 1e-3)
    assert backbone.damping_ratio == pytest.approx(zeta, rel=tolerance, abs=tolerance * zeta.max())


def test_one_harmonic_forced_response_on_a_spectrum_is_describe_s_spectrum_integral():
    """F0 cos(omega t) on m x'' + c x' + k0 x + spectrum: with one harmonic each point's amplitude A and phase
    satisfy (K(A) - m omega^2 + i (c omega + D(A) / (pi A^2))) A e^(i phase) = F0, K and D describe's, to the
    tolerance of the restoring force's first harmonic (what the spectrum's quadrature is held to)."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.describing import describe_amplitudes

    m, c, F0, tolerance = 1.0, 0.02, 0.1, 1e-4
    tables = {"mass": {"m": m}, "spring": {"k0": 1.0}, "branches": SPECTRA["linear"]}
    curve = harmonic_response(element({**tables, "damper": {"c": c}}), F0, [0.15, 0.3], harmonics=1,
                              tolerance=tolerance, stability=False, samples=2048)
    assert curve.frequency.size > 5
    described = describe_amplitudes(element(tables), curve.amplitude, tolerance=tolerance / 10)
    K, D, A = np.asarray(described.stiffness), np.asarray(described.dissipation), curve.amplitude
    omega = 2 * math.pi * curve.frequency
    force = (K - m * omega**2 + 1j * (c * omega + D / (math.pi * A * A))) * A * np.exp(1j * curve.phase)
    restoring = np.abs((K + 1j * D / (math.pi * A * A)) * A)
    assert np.all(np.abs(force - F0) <= tolerance * restoring)


def test_a_spectrum_whose_quadrature_cannot_reach_the_tolerance_is_one_line(tmp_path, capsys):
    out = tmp_path / "out.csv"
    scene = write(tmp_path, {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "branches": SPECTRA["linear"]})
    status = main(["describe", scene, "--force-amplitude", "0.1", "--frequencies", "0.15,0.3", "--tolerance",
                   "1e-12", "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2 and "spectrum of branches" in err and "--tolerance" in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


MAXWELL = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.02},
           "branches": {"k": [1.0], "alpha": [0.1], "c": [0.5]}}


@pytest.mark.slow
def test_stable_points_agree_with_the_time_sweep_on_a_mass_on_a_maxwell_branch():
    """A branch with a series dashpot (spring, slider and dashpot in series: relaxing at k / c = 2 / s, so its
    cycle depends on the period) driven by the compiled kernels over periods until its cycle repeats: with H = 5
    the curve's points agree with the time sweep's (--method time) to its tolerance, slip and stick alike."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.response import frequency_response

    scene = element(MAXWELL)
    curve = harmonic_response(scene, 0.1, [0.12, 0.25], harmonics=5)
    assert np.all(curve.stable)
    picks = [np.argmin(np.abs(curve.frequency - f)) for f in (0.14, 0.18, 0.22)]
    response = frequency_response(scene, 0.1, curve.frequency[picks], sweep="up", tolerance=1e-4)
    assert response.amplitude == pytest.approx(curve.amplitude[picks], rel=1e-4)
    assert response.phase == pytest.approx(curve.phase[picks], abs=1e-4)
    # the dashpot matters here: the same branch without it (the play operator's exact AFT) is another curve
    plain = harmonic_response(element({**MAXWELL, "branches": {"k": [1.0], "alpha": [0.1]}}), 0.1,
                              curve.frequency[picks][[0, -1]], harmonics=5, stability=False)
    assert abs(plain.amplitude[-1] / curve.amplitude[picks[-1]] - 1) > 1e-2


def test_a_maxwell_branch_that_never_slips_is_its_complex_stiffness():
    """A branch with a series dashpot and an elastic range of 5e5 m (it never slips: a spring and a dashpot in
    series, of complex stiffness k i omega c / (k + i omega c)): the curve is the linear closed form to the AFT's
    stated quadrature, and it reaches the end in a few dozen points. Its cycle was converged to 1e-13 of the
    elastic range (5e-8 m), the finite differences of its forces were 10 % off, and the continuation crept at
    steps of 5e-7 for minutes (a fuzz run's find)."""
    from prandtl_fmu.frequency.curve import harmonic_response

    m, k0, k, c, F0 = 2.947, 3.072, 0.1865, 0.1109, 0.1232
    scene = element({"mass": {"m": m}, "spring": {"k0": k0}, "branches": {"k": [k], "alpha": [1e5], "c": [c]}})
    curve = harmonic_response(scene, F0, [0.0549, 0.5175], harmonics=2)
    assert curve.frequency[-1] == 0.5175 and len(curve.frequency) < 100 and np.all(curve.stable)
    omega = 2 * math.pi * curve.frequency
    X = F0 / (k0 - m * omega**2 + k * 1j * omega * c / (k + 1j * omega * c))
    assert curve.amplitude == pytest.approx(np.abs(X), rel=2e-4)
    assert curve.phase == pytest.approx(np.angle(X), abs=2e-4)


@pytest.mark.slow
def test_a_stiff_series_dashpot_is_the_plain_branch():
    """c -> infinity: the Maxwell branch (driven over periods, finite-difference Jacobian) is the Jenkins branch
    (the play operator's exact AFT and Jacobian): the same solution to the dashpot's relaxation over a period."""
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    omega = 2 * math.pi * 0.17
    stiff = HarmonicBalance(periodic_system(element({**MAXWELL, "branches": {**MAXWELL["branches"],
                                                                                "c": [1e9]}})), 5, 0.1)
    plain = HarmonicBalance(periodic_system(element({**MAXWELL, "branches": {"k": [1.0], "alpha": [0.1]}})), 5, 0.1)
    assert stiff.system.series and not plain.system.series
    expected = plain.full(plain.solve_at(omega))
    assert np.max(np.abs(stiff.full(stiff.solve_at(omega)) - expected)) <= 1e-7 * np.max(np.abs(expected))


@pytest.mark.slow
def test_a_network_joint_with_a_series_dashpot_keeps_its_orbit_when_integrated(tmp_path):
    """Two masses joined by a Maxwell joint (the two-mass joint's branch with c = 3 N s/m in series): the orbit
    of the balance (H = 5), integrated by the network stepper from its state at t = 0 (the joint's u from its
    driven cycle), keeps its first harmonic; without the joint's force in the balance (as if it were cut) it
    would not."""
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    from importlib import resources

    source = resources.files("prandtl_fmu").joinpath("scenes/networks/two-mass-joint.toml").read_text()
    path = tmp_path / "maxwell-joint.toml"
    path.write_text(source.replace("eta = 0.05\n", "eta = 0.05\nc = 3.0\n", 1))
    scene, _ = read_scene(str(path), networks=True)
    balance = HarmonicBalance(periodic_system(scene), 5, 0.1)
    assert balance.system.series and balance.system.series[0].ends == (0, 1)
    for frequency in (0.12, 0.2):
        omega = 2 * math.pi * frequency
        q = balance.solve_at(omega)
        amplitude = abs(complex(balance.full(q)[1], -balance.full(q)[2]))
        after = _first_harmonic_after(balance, q, omega, 30)
        assert abs(after - amplitude) <= 2e-3 * amplitude, (frequency, after, amplitude)


def _full_finite_monodromy(balance, q, omega, steps):
    """The monodromy over (x, v, u) of the element (one node, its branches to the ground), by central finite
    differences of one period of the network's implicit stepper at ``steps`` steps, written out here: each of x,
    v and every branch's u perturbed in turn (no state left out, none moved with another)."""
    from prandtl_fmu.frequency.floquet import orbit_start, run_periods

    x, v, u = orbit_start(balance, q, omega)
    branches = np.flatnonzero([e.kind == "branch" for e in balance.system.network.elements])
    start = np.concatenate((x, v, u[branches]))
    scale = 1e-7

    def period(state):
        u_all = u.copy()
        u_all[branches] = state[2:]
        _, (x_end, v_end, u_end) = run_periods(balance, omega, (state[:1], state[1:2], u_all), 1, steps)
        return np.concatenate((x_end, v_end, u_end[branches]))

    columns = []
    for k in range(start.size):
        delta = np.zeros(start.size)
        delta[k] = scale
        columns.append((period(start + delta) - period(start - delta)) / (2 * scale))
    return np.array(columns).T


def test_the_variational_monodromy_of_a_stuck_branch_is_the_linear_oscillator_s():
    """floquet.variational_monodromy (every point's multipliers where the nodes all have a mass): on the friction
    damper under a force too small to slip its branch, the linear oscillator's exp(A T) (A of m, k0 + k, c: its
    eigenvalues to 1e-8, RK4's error at 512 steps a period; the stuck branch's neutral offset left out, its u
    moving with x)."""
    from scipy.linalg import expm

    from prandtl_fmu.frequency import floquet
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    system = periodic_system(element(DAMPER))
    assert floquet.variational(system)
    omega = 2 * math.pi * 0.2
    stuck = HarmonicBalance(system, 5, 0.01)  # |x| ~ 0.01 / |2 - omega^2|: the branch never reaches 0.1
    q = stuck.solve_at(omega)
    A = np.array([[0.0, 1.0], [-2.0, -0.02]])
    wanted = np.sort_complex(np.linalg.eigvals(expm(A * 2 * math.pi / omega)))
    got = np.sort_complex(np.linalg.eigvals(floquet.variational_monodromy(stuck, q, omega)))
    assert np.max(np.abs(got - wanted)) <= 1e-8, (got, wanted)


def test_a_stiff_stuck_branch_far_above_the_forcing_has_the_linear_oscillator_s_multipliers():
    """A branch of 1e6 N/m on 1 kg stuck under 0.1 Hz (the packaged hard/stiff-branches: the stuck network rings
    at 1000 rad/s, 10 000 radians a period): the variational equation's RK4 takes as many steps as that rate asks
    (one a sample was unstable: NaN multipliers), so |mu| is the linear oscillator's exp(-c T / 2 m) to 2e-4
    (variational.ACCURACY is 1e-4)."""
    from prandtl_fmu.frequency import floquet
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    c = 1e-3
    system = periodic_system(element({"mass": {"m": 1.0}, "damper": {"c": c},
                                      "branches": {"k": [1.0e6], "eta": [1.0e-4]}}))
    omega = 2 * math.pi * 0.1
    stuck = HarmonicBalance(system, 3, 0.01)  # |x| ~ 1e-8: the branch never reaches 1e-4
    q = stuck.solve_at(omega)
    got = np.abs(np.linalg.eigvals(floquet.variational_monodromy(stuck, q, omega)))
    wanted = math.exp(-c / 2 * 2 * math.pi / omega)
    assert np.all(np.isfinite(got))
    assert np.max(np.abs(got - wanted)) <= 2e-4, (got, wanted)


def test_a_monodromy_past_its_work_bound_is_not_computed_and_a_monotone_scene_is_stable_by_its_energy(
        tmp_path, monkeypatch):
    """Past floquet.WORK_LIMIT (0 here; 100 000 branches reach it) no multiplier is computed: a friction damper
    (linear spring, dashpot, branch: monotone) is stable at every point by the energy of the difference (its
    multiplier cell empty), a Duffing oscillator's stability is unknown (empty cells, never a guess); with the
    bound in place the damper's points are stable by their multipliers, which are written."""
    from prandtl_fmu.frequency import floquet
    from prandtl_fmu.frequency.harmonic_balance import periodic_system

    assert floquet.monotone(periodic_system(element(DAMPER)))
    assert not floquet.monotone(periodic_system(element(DUFFING)))
    arguments = ["--force-amplitude", "0.2", "--frequencies", "0.1,0.3", "--harmonics", "3"]
    damper, duffing = write(tmp_path, DAMPER, "damper.toml"), write(tmp_path, DUFFING, "duffing.toml")
    assert main(["describe", damper, *arguments, "--out", str(tmp_path / "measured.csv")]) == 0
    measured = read_csv(tmp_path / "measured.csv")
    assert set(measured["stable"]) == {"true"} and all(float(m) <= 1.0 for m in measured["multiplier"])
    monkeypatch.setattr(floquet, "WORK_LIMIT", 0.0)
    assert main(["describe", damper, *arguments, "--out", str(tmp_path / "proven.csv")]) == 0
    proven = read_csv(tmp_path / "proven.csv")
    assert set(proven["stable"]) == {"true"} and set(proven["multiplier"]) == {""}
    assert main(["describe", duffing, *arguments, "--out", str(tmp_path / "unknown.csv")]) == 0
    unknown = read_csv(tmp_path / "unknown.csv")
    assert set(unknown["stable"]) == {""} and set(unknown["multiplier"]) == {""}


@pytest.mark.slow
def test_the_variational_monodromy_of_a_sliding_branch_is_the_full_finite_differences():
    """Under a force that slips the friction damper's branch: the eigenvalues of floquet.variational_monodromy
    against those of the monodromy over (x, v, u) by finite differences of the implicit stepper written in the
    test, at 2048 and 4096 steps extrapolated (backward Euler, first order), to 5e-3; and the module's own finite
    differences (``_monodromy``, the path of the scenes the variational equation does not take) agree too."""
    from prandtl_fmu.frequency import floquet
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    system = periodic_system(element(DAMPER))
    omega = 2 * math.pi * 0.2
    slipping = HarmonicBalance(system, 7, 0.3)
    q = slipping.solve_at(omega)
    assert np.ptp(slipping.samples(slipping.full(q))[0]) > 0.2  # the branch slides
    got = np.sort(np.abs(np.linalg.eigvals(floquet.variational_monodromy(slipping, q, omega))))
    coarse, fine = (_full_finite_monodromy(slipping, q, omega, steps) for steps in (2048, 4096))
    finite = np.sort(np.abs(np.linalg.eigvals(2.0 * fine - coarse)))
    assert got == pytest.approx(finite, abs=5e-3), (got, finite)
    coarse, fine = (floquet._monodromy(slipping, q, omega, steps) for steps in (1024, 2048))
    assert np.sort(np.abs(np.linalg.eigvals(2.0 * fine - coarse))) == pytest.approx(got, abs=5e-3)


MASSLESS_JOINT = """
name = "massless-joint"

[network]
nodes = ["a", "j", "b"]
mass = [1.0, 0.0, 1.0]
load_node = "a"

[[network.spring]]
between = ["a", "ground"]
k = 1.0

[[network.spring]]
between = ["b", "ground"]
k = 1.0

[[network.spring]]
between = ["a", "j"]
k = 5.0

[[network.branch]]
name = "joint"
between = ["j", "b"]
k = 2.0
eta = 0.05

# a third element on j: a massless node between two elements would be joined into one (frequency/series.py)
[[network.spring]]
between = ["j", "ground"]
k = 0.5

[[network.dashpot]]
between = ["a", "ground"]
c = 0.02

[[network.dashpot]]
between = ["b", "ground"]
c = 0.02
"""


def test_every_point_of_a_finite_difference_curve_has_its_own_multipliers():
    """A joint behind a massless node (the finite differences of floquet.py, not the variational equation): every
    point's multipliers are computed (none inferred from its neighbours), and the largest agrees with the
    monodromy at 8 and 16 times the steps where the verdict could turn. At the resonance peak, extrapolating
    the matrices (2 Phi_2M - Phi_M) instead of the multipliers gave |mu| = 1.12 where both resolutions say 0.87
    and 0.90 (a stable point called unstable)."""
    from prandtl_fmu.frequency import floquet
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    scene = parse_scene(MASSLESS_JOINT, networks=True)[0]
    curve = harmonic_response(scene, 0.2, [0.05, 0.4], harmonics=5)
    assert np.all(np.isfinite(curve.multiplier)) and np.all(curve.stable)
    balance = HarmonicBalance(periodic_system(scene), 5, 0.2)
    for index in (int(np.argmax(curve.amplitude)), 0, len(curve.frequency) - 1):
        omega = 2 * math.pi * curve.frequency[index]
        q = curve.coefficients[index].reshape(-1)[balance.free]
        fine = np.linalg.eigvals(floquet._monodromy(balance, q, omega, 16 * floquet.STEPS))
        coarse = np.linalg.eigvals(floquet._monodromy(balance, q, omega, 8 * floquet.STEPS))
        reference = np.max(np.abs(floquet.extrapolated(fine, coarse)))
        # to 5e-3, or within a quarter of its distance from 1 (what floquet.refined asks before it stops refining)
        assert abs(curve.multiplier[index] - reference) <= max(5e-3, 0.25 * abs(reference - 1.0)), index


NEAR_RIGID = {"mass": {"m": 2.132}, "spring": {"k0": 0.247}, "damper": {"c": 0.04272},
              "branches": {"k": [1e5, 1e-6], "alpha": [0.298, 0.05719]}}


def test_a_given_number_of_harmonics_reports_its_truncation(tmp_path, capsys):
    """With --harmonics H the curve is the H-harmonic balance asked for, and ``change`` says how far it is from
    the next H: at the curve's ends, at least the change between the two balances solved there from scratch
    (written out here). A near-rigid branch (eta = 3e-6 m: a slider) at H = 9 is 3 % off the time sweep (a fuzz
    run's find, written without a word): the command line now prints one warning line with the change, and
    still writes the curve; a smooth curve (Duffing's at H = 15) gets no warning."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    scene = element(NEAR_RIGID)
    curve = harmonic_response(scene, 0.6246, [0.243439, 0.365158], harmonics=9, stability=False)
    system = periodic_system(scene)
    ends = []
    for H in (9, 11):
        balance = HarmonicBalance(system, H, 0.6246)
        ends.append([complex(*balance.full(balance.solve_at(2 * math.pi * f))[1:3] * [1, -1])
                     for f in (0.243439, 0.365158)])
    apart = max(abs(b - a) / abs(b) for a, b in zip(*ends))
    assert 1e-3 < apart <= curve.change * (1 + 1e-6), (apart, curve.change)
    path, out = write(tmp_path, NEAR_RIGID), tmp_path / "curve.csv"
    assert main(["describe", path, "--force-amplitude", "0.6246", "--frequencies", "0.243439,0.365158",
                 "--harmonics", "9", "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("warning: with --harmonics 9") and f"{curve.change:.3g}" in err[0]
    assert len(read_csv(out)["frequency"]) > 2
    duffing = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "cubic": {"k3": 0.5}, "damper": {"c": 0.05}}
    assert main(["describe", write(tmp_path, duffing), "--force-amplitude", "0.2", "--frequencies", "0.1,0.3",
                 "--harmonics", "15", "--out", str(out)]) == 0
    assert capsys.readouterr().err == ""
    # found at its peak, which is its fold: by the next H's point on the normal there
    smooth = harmonic_response(element(duffing), 0.2, [0.1, 0.3], harmonics=15, stability=False)
    assert smooth.folds.size == 2 and smooth.change is not None and smooth.change < 1e-6


def test_a_curve_that_starts_just_above_a_resonance_goes_on(tmp_path):
    """A linear oscillator from 0.17 Hz, just above its 0.159 Hz: the first steps' predictor overshoots past
    q = 0 and its corrector landed on the other side of the resonance (at 0.135 Hz, within its drift), which
    was refused as "turned back below 0.17 Hz"; a step that goes back in omega while both tangents point ahead
    is now taken again shorter. Every point is the closed form F0 / (k - m omega^2 + i c omega)."""
    m, k, c, F0 = 1.0, 1.0, 0.01, 0.5
    path = write(tmp_path, {"mass": {"m": m}, "spring": {"k0": k}, "damper": {"c": c}})
    out = tmp_path / "curve.csv"
    assert main(["describe", path, "--force-amplitude", repr(F0), "--frequencies", "0.17,2", "--harmonics", "1",
                 "--out", str(out)]) == 0
    rows = read_csv(out)
    omega = 2 * math.pi * np.array([float(f) for f in rows["frequency"]])
    assert omega[0] == pytest.approx(2 * math.pi * 0.17) and omega[-1] == pytest.approx(2 * math.pi * 2)
    assert np.all(np.diff(omega) > 0)
    wanted = F0 / np.abs(k - m * omega**2 + 1j * c * omega)
    got = np.array([float(a) for a in rows["amplitude"]])
    assert np.max(np.abs(got - wanted) / wanted) <= 1e-9


def test_newton_cycling_between_two_slip_patterns_is_damped():
    """The packaged masing-bilinear (one branch k = 90, eta = 0.01 beside k0 = 10) at its own force, 2 N, with 7
    harmonics at 0.1 Hz: full Newton steps flip between two states (max |R| 2.161, 2.162, 2.161, ... for 40
    iterations: "did not converge"); where the full iteration fails, a step that would raise the residual is
    halved, and the balance is solved to its tolerance."""
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    scene, _ = read_scene("masing-bilinear")
    balance = HarmonicBalance(periodic_system(scene), 7, 2.0)
    omega = 2 * math.pi * 0.1
    q = balance.solve_at(omega)
    residual = balance.evaluate(q, omega)[0]
    assert np.max(np.abs(residual)) <= 1e-9 * balance.force_scale(omega)
    assert 0.13 < balance.amplitude_at(q, omega, 0) < 0.15  # time integration: 0.1385


def test_a_resonance_held_only_by_a_first_slip_too_flat_to_resolve_is_refused_with_its_band(tmp_path, capsys):
    """Branches without a spring or a dashpot (as hard/large-forces, at unit scale): stuck, they resonate
    undamped at sqrt(sum k / m), held only by the first branch's slip, whose plateau (relative height
    h = pi F0 eta_1 / (4 k_1 eta_1^2)) is finer than the sampled slip resolves: the curve stopped at its corner
    or folded hundreds of times. Refused in one line that gives the band to leave out; either side of it the
    curve is the stuck, linear response F0 / |K - m omega^2|."""
    m, k, eta, F0 = 1.0, [0.5, 0.5], [0.1, 0.2], 1e-4
    path = write(tmp_path, {"mass": {"m": m}, "branches": {"k": k, "eta": eta}})
    out = tmp_path / "curve.csv"
    natural = math.sqrt(sum(k) / m) / (2 * math.pi)
    assert main(["describe", path, "--force-amplitude", repr(F0), "--frequencies",
                 f"{0.5 * natural!r},{2 * natural!r}", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "plateau" in err[0] and not out.exists(), err
    below, above = (float(word) for word in err[0].split("leave ")[1].split(" Hz")[0].split(" to "))
    assert below < natural < above
    # the force it suggests passes the check (rounded up, not to the nearest: a review's find)
    from prandtl_fmu.frequency.harmonic_balance import periodic_system
    from prandtl_fmu.frequency.unbounded import refuse_slip_limited

    enough = float(err[0].split("of at least ")[1].split(",")[0])
    system = periodic_system(parse_scene(open(path).read())[0])
    refuse_slip_limited(system, enough, None, 2 * math.pi * 0.6 * natural, 2 * math.pi * 2 * natural)
    # (not from exactly half the resonance: undamped, the second harmonic's operator is singular there)
    for low, high in ((0.6 * natural, 0.999 * below), (1.001 * above, 2 * natural)):
        assert main(["describe", path, "--force-amplitude", repr(F0), "--frequencies", f"{low!r},{high!r}",
                     "--out", str(out)]) == 0
        rows = read_csv(out)
        omega = 2 * math.pi * np.array([float(f) for f in rows["frequency"]])
        wanted = F0 / np.abs(sum(k) - m * omega**2)
        got = np.array([float(a) for a in rows["amplitude"]])
        assert np.max(np.abs(got - wanted) / wanted) <= 1e-6


@pytest.mark.slow
def test_the_harmonics_are_chosen_by_the_change_at_the_same_points():
    """The packaged masing-bilinear at 1 N: the chooser compared the two curves' own peaks, which fall at
    different frequencies where the phase turns fast (H = 21 at 0.775 Hz, 31 at 0.755 Hz: 0.0515 apart, "still
    changed" and refused); the same point solved with more harmonics changes by 1e-4. Now the last curve's ends
    and peak are solved again at the next H: the curve is chosen, and agrees with the time sweep where both
    are computed (to the tolerance)."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.response import frequency_response

    scene, _ = read_scene("masing-bilinear")
    curve = harmonic_response(scene, 1.0, [0.1, 2.0])
    assert curve.change <= 1e-3
    swept = frequency_response(scene, 1.0, [0.1, 2.0], sweep="up", progress=False)
    for f, amplitude in zip(swept.frequency.tolist(), swept.amplitude.tolist()):
        index = int(np.argmin(np.abs(curve.frequency - f)))
        assert abs(curve.frequency[index] - f) <= 1e-9 * f
        assert curve.amplitude[index] == pytest.approx(amplitude, rel=1e-3)


def test_a_force_below_the_static_friction_leaves_a_stribeck_mass_at_rest(tmp_path):
    """Stribeck's drop, F0 between 4 / pi alpha_k and alpha: the force never breaks the mass away, so it stays
    at rest at every frequency (amplitude 0), the kinetic level's bound notwithstanding (a review's find: refused
    as climbing without bound)."""
    from prandtl_fmu.frequency.unbounded import refuse_unbounded

    scene = element({"mass": {"m": 1.0}, "spring": {"k0": 1.0},
                     "friction": {"alpha": 1.0, "alpha_kinetic": 0.2, "stribeck_velocity": 0.2}})
    refuse_unbounded(scene, 0.5, None, 2 * math.pi * 0.1, 2 * math.pi * 0.3)  # no refusal
    path = write(tmp_path, {"mass": {"m": 1.0}, "spring": {"k0": 1.0},
                            "friction": {"alpha": 1.0, "alpha_kinetic": 0.2, "stribeck_velocity": 0.2}})
    out = tmp_path / "curve.csv"
    assert main(["describe", path, "--force-amplitude", "0.5", "--frequencies", "0.1,0.3", "--out", str(out)]) == 0
    assert {float(a) for a in read_csv(out)["amplitude"]} == {0.0}


def test_a_start_newton_misses_from_the_linear_response_is_found_from_fewer_harmonics(tmp_path):
    """masing-bilinear (a stiff Jenkins element, k = 100 N/m) at F0 = 3 N and 0.05 Hz with 31 harmonics: Newton
    from the linear response does not converge (full or damped steps, nor with the force raised in steps), and
    the point was refused; from the state with fewer harmonics (1, 3, ... 21, each lifted to the next) it is
    found, and its first harmonic is the one with 61 harmonics (where they have converged: 41, 61 and 91 agree
    to 5e-4) to the change the command reports at 31 (2.8e-3)."""
    from prandtl_fmu.frequency import read_scene
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system

    scene, _ = read_scene("masing-bilinear")
    balance = HarmonicBalance(periodic_system(scene), 31, 3.0)
    omega = 2 * math.pi * 0.05
    guess = balance.linear_guess(omega)
    assert balance._newton(omega, guess) is None and balance._newton(omega, guess, damped=True) is None
    amplitudes = {}
    for harmonics in ("31", "61"):
        out = tmp_path / f"h{harmonics}.csv"
        assert main(["describe", "masing-bilinear", "--force-amplitude", "3", "--frequencies", "0.05",
                     "--harmonics", harmonics, "--out", str(out)]) == 0
        amplitudes[harmonics] = float(read_csv(out)["amplitude"][0])
    assert amplitudes["31"] == pytest.approx(amplitudes["61"], rel=3e-3)


def test_the_harmonics_the_tolerance_climbs_stop_at_31_only_where_the_balance_is_large():
    """H = 45 and 63 are climbed while n (2 H + 1) stays within MOST_CHOSEN_UNKNOWNS; a harmonic asked for as a
    column starts the climb one step below it (compared with, never chosen) and none past the last is refused."""
    from prandtl_fmu.frequency.harmonic_balance import HARMONIC_STEPS, MOST_CHOSEN_UNKNOWNS, harmonic_steps

    assert harmonic_steps(1) == HARMONIC_STEPS and HARMONIC_STEPS[-2:] == (45, 63)
    for nodes in (1, 5, 15, 16, 21, 22, 40):
        steps = harmonic_steps(nodes)
        assert steps[:9] == (1, 3, 5, 7, 9, 11, 15, 21, 31)  # a large network keeps the steps it had
        assert all(nodes * (2 * H + 1) <= MOST_CHOSEN_UNKNOWNS for H in steps[9:])
        assert len(steps) == 9 + sum(nodes * (2 * H + 1) <= MOST_CHOSEN_UNKNOWNS for H in (45, 63))
    assert harmonic_steps(1, lowest=25) == (21, 31, 45, 63)
    assert harmonic_steps(1, lowest=3) == (1, 3, 5, 7, 9, 11, 15, 21, 31, 45, 63)
    assert harmonic_steps(40, lowest=45) == ()


def test_harmonic_amplitudes_above_the_steps_a_large_network_climbs_are_refused_in_one_line(tmp_path, capsys):
    """A chain of 40 masses climbs to H = 31 only (40 x 91 unknowns would be past MOST_CHOSEN_UNKNOWNS): the
    amplitude of harmonic 45 asked for without --harmonics is refused, naming the highest."""
    nodes = [f"n{i}" for i in range(40)]
    springs = [{"between": ["ground" if i == 0 else nodes[i - 1], nodes[i]], "k": 1.0} for i in range(40)]
    path = write(tmp_path, {"name": "chain", "network": {"nodes": nodes, "mass": [1.0] * 40, "load_node": "n39",
                                                         "spring": springs,
                                                         "dashpot": [{"between": [node, "ground"], "c": 0.1}
                                                                     for node in nodes],
                                                         "branch": [{"between": ["n0", "ground"], "k": 1.0,
                                                                     "eta": 0.1}]}})
    assert main(["describe", path, "--force-amplitude", "1", "--frequencies", "0.1,0.2",
                 "--harmonic-amplitudes", "45", "--out", str(tmp_path / "out.csv")]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and "harmonic 45 is above the 31 harmonics" in error
    assert not (tmp_path / "out.csv").exists()


@pytest.mark.slow
def test_a_curve_whose_first_harmonic_needs_more_than_31_harmonics_gets_them_and_agrees_with_time(tmp_path):
    """masing-bilinear at F0 = 3 N from 0.05 Hz: after each yield the stuck mass rings at its elastic 1.59 Hz
    (harmonic 32) with 1 % damping, and the first harmonic still changes by 1.3e-2 from H = 21 to 31 (it was
    refused there). The tolerance now climbs to 45 and 63; the curve's first point agrees with the exact
    stepper's time sweep to the tolerance."""
    from prandtl_fmu.frequency.curve import harmonic_response

    scene, _ = read_scene("masing-bilinear")
    curve = harmonic_response(scene, 3.0, [0.05, 0.1], stability=False)
    assert curve.harmonics > 31 and curve.change <= 1e-3
    out = tmp_path / "time.csv"
    assert main(["describe", "masing-bilinear", "--force-amplitude", "3", "--frequencies", "0.05",
                 "--method", "time", "--stepper", "exact", "--sweep", "up", "--out", str(out)]) == 0
    swept = float(read_csv(out)["amplitude"][0])
    assert curve.frequency[0] == pytest.approx(0.05, rel=1e-12)
    assert curve.amplitude[0] == pytest.approx(swept, rel=1e-3)


def test_a_harmonic_asked_for_between_two_steps_is_chosen_by_the_tolerance(tmp_path):
    """--harmonic-amplitudes 25 without --harmonics: the climb starts at 21 (compared with only), and the curve
    written has at least 25 harmonics (it was refused, "changed by inf from H = 21 to 31")."""
    from prandtl_fmu.frequency.curve import harmonic_response

    scene, _ = read_scene("networks/two-mass-joint", networks=True)
    curve = harmonic_response(scene, 0.5, [0.1, 0.12], orders=(25,), stability=False)
    assert curve.harmonics >= 31 and curve.change <= 1e-3
    out = tmp_path / "curve.csv"
    assert main(["describe", "networks/two-mass-joint", "--force-amplitude", "0.5", "--frequencies", "0.1,0.12",
                 "--harmonic-amplitudes", "25", "--out", str(out)]) == 0
    assert float(read_csv(out)["amplitude_a_h25"][0]) > 0.0


def test_the_most_harmonics_have_no_truncation_to_measure_and_say_so():
    """H = MOST_HARMONICS (256) is compared with nothing (the next, 513, is past what a balance takes: every
    --harmonics from 128 up was refused after its whole curve); its ``change`` is None."""
    from prandtl_fmu.frequency.curve import _truncation
    from prandtl_fmu.frequency.harmonic_balance import MOST_HARMONICS, HarmonicBalance, periodic_system

    scene, _ = parse_scene(scene_text({"name": "jenkins", "mass": {"m": 1.0}, "spring": {"k0": 1.0},
                                       "damper": {"c": 0.1}, "branches": {"k": [1.0], "eta": [0.1]}}))
    balance = HarmonicBalance(periodic_system(scene), MOST_HARMONICS, 0.1)
    assert _truncation(balance, [], 0, None) is None


@pytest.mark.slow
def test_harmonics_past_127_are_compared_with_the_most_and_written(tmp_path, capsys):
    """--harmonics 128: its truncation is measured against 256 harmonics (2 H + 1 = 257 was refused after the
    curve: "must be a whole number in [1, 256], got 257"); the point is written."""
    path = write(tmp_path, {"name": "jenkins", "mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.1},
                            "branches": {"k": [1.0], "eta": [0.1]}})
    out = tmp_path / "curve.csv"
    assert main(["describe", path, "--force-amplitude", "0.1", "--frequencies", "0.2", "--harmonics", "128",
                 "--out", str(out)]) == 0
    assert "warning" not in capsys.readouterr().err  # the change to 256 measured, within the tolerance
    assert float(read_csv(out)["amplitude"][0]) > 0.0


def test_a_start_past_the_folds_of_more_harmonics_is_found_where_one_harmonic_is_on_a_branch_they_lack():
    """A Duffing oscillator with three branches at F0 = 0.813 N: its folds are at 0.2060 and 0.2165 Hz, and
    with one harmonic the upper branch reaches past 0.2279 Hz, where three harmonics have none: the ladder from
    fewer harmonics, lifted from that branch, did not converge with 3, and 21 and 63 harmonics were refused at
    the lowest frequency listed (a review's find). A rung that fails from its lift is solved from its own linear
    response: the point is the curve's that starts below the folds, to the tolerance."""
    from prandtl_fmu.frequency.curve import harmonic_response

    scene, _ = parse_scene(scene_text({"name": "duffing-branches", "mass": {"m": 1.467}, "spring": {"k0": 0.932},
                                       "damper": {"c": 0.056}, "cubic": {"k3": 1.416},
                                       "branches": {"k": [2.614, 1.427, 2.698], "alpha": [0.192, 0.252, 0.159]}}))
    end = 0.2281
    started = harmonic_response(scene, 0.813, [0.22787, end], harmonics=21, stability=False)
    through = harmonic_response(scene, 0.813, [0.19, end], harmonics=21, stability=False)
    assert np.sum(through.fold) == 2  # the curve from below passes both folds
    assert started.frequency[-1] == through.frequency[-1] == pytest.approx(end, rel=1e-12)
    assert started.amplitude[-1] == pytest.approx(through.amplitude[-1], rel=1e-9)
