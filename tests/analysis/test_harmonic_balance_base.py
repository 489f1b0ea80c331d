"""Harmonic balance under base excitation (the support moves, y = Y0 cos(omega t)) and many curves at once (one
per amplitude, on dask.distributed or in-process): the linear transmissibility in closed form, a Jenkins element
against the time integration of the equivalent force on the relative coordinate, the CSV of a parameter study
with and without a cluster, and bad input."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main
from prandtl_fmu.frequency import parse_scene

from tests.analysis.test_describe_cli import read_csv, write

M, K, C, Y0 = 2.0, 50.0, 0.7, 1e-3
LINEAR = {"mass": {"m": M}, "spring": {"k0": K}, "damper": {"c": C}}
ONE_NODE = f"""
name = "one-node"
[network]
nodes = ["a"]
mass = [{M}]
load_node = "a"
[[network.spring]]
between = ["a", "ground"]
k = {K}
[[network.dashpot]]
between = ["ground", "a"]
c = {C}
"""
JENKINS = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.02},
           "branches": {"k": [1.0], "alpha": [0.1]}}


def transmissibility(omega):
    """x / Y0 of m x'' + c (x' - y') + k (x - y) = 0, y = Y0 cos(omega t): (k + i c w) / (k - m w^2 + i c w)."""
    return (K + 1j * C * omega) / (K - M * omega**2 + 1j * C * omega)


@pytest.mark.parametrize("scene_of", [lambda tmp: write(tmp, LINEAR), lambda tmp: _one_node(tmp)],
                         ids=["element", "network of one node"])
def test_base_excitation_of_a_mass_spring_dashpot_is_its_transmissibility(tmp_path, scene_of):
    """H = 1 (the linear response has no other harmonic): |x| / Y0 and the phase of the absolute x against y in
    closed form to 1e-10, through the resonance (f_n = 0.80 Hz) and past it, where the base moves more than the
    mass."""
    from prandtl_fmu.frequency import harmonic_response, read_scene

    scene, _ = read_scene(scene_of(tmp_path), networks=True)
    frequencies = [0.1, 0.5, 0.8, 1.2, 3.0]
    curve = harmonic_response(scene, frequencies=frequencies, base_amplitude=Y0, harmonics=1, stability=False)
    exact = transmissibility(2 * math.pi * curve.frequency)
    assert curve.frequency[0] == 0.1 and curve.frequency[-1] == pytest.approx(3.0, rel=1e-12)
    assert np.max(np.abs(curve.amplitude / Y0 - np.abs(exact)) / np.abs(exact)) <= 1e-10
    assert np.max(np.abs(curve.phase - np.angle(exact))) <= 1e-10
    assert curve.amplitude.max() > 10 * Y0 and curve.amplitude[-1] < 0.1 * Y0  # it went through the resonance
    assert curve.base_amplitude == Y0 and curve.force_amplitude is None


def _one_node(tmp_path):
    path = tmp_path / "one-node.toml"
    path.write_text(ONE_NODE)
    return str(path)


def test_base_excitation_from_the_command_line_reports_the_absolute_motion(tmp_path):
    """The CSV's amplitude, phase and amplitude_<node> are those of x = z + y (the closed form), with today's
    columns."""
    out = tmp_path / "base.csv"
    assert main(["describe", _one_node(tmp_path), "--base-amplitude", str(Y0), "--frequencies", "0.5,1.2",
                 "--harmonics", "1", "--out", str(out)]) == 0
    table = read_csv(out)
    assert list(table) == ["frequency", "amplitude", "phase", "stable", "amplitude_a", "fold", "multiplier"]
    exact = transmissibility(2 * math.pi * np.array(table["frequency"], dtype=float))
    assert np.array(table["amplitude"], dtype=float) == pytest.approx(Y0 * np.abs(exact), rel=1e-10)
    assert np.array(table["amplitude_a"], dtype=float) == pytest.approx(Y0 * np.abs(exact), rel=1e-10)
    assert np.array(table["phase"], dtype=float) == pytest.approx(np.angle(exact), abs=1e-10)
    assert set(table["stable"]) == {"true"}  # a damped linear oscillator


@pytest.mark.slow
def test_base_excited_jenkins_element_agrees_with_the_time_integration():
    """A mass on a spring, a dashpot and a Jenkins branch, its support moving: in z = x - y the mass feels
    m omega^2 Y0 cos(omega t) and the elements see z. The time sweep (the element's own stepper, settled to
    1e-4) of that force at each frequency, plus Y0, is the absolute motion the harmonic balance (H = 7) reports."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.response import frequency_response

    from tests.analysis.test_harmonic_balance import element

    scene = element(JENKINS)
    Y = 0.08
    curve = harmonic_response(scene, frequencies=[0.15, 0.19], base_amplitude=Y, harmonics=7)
    assert np.all(curve.stable)
    picks = sorted({int(np.argmin(np.abs(curve.frequency - f))) for f in (0.16, 0.173, 0.18)})
    assert len(picks) == 3
    for index in picks:
        omega = 2 * math.pi * curve.frequency[index]
        relative = frequency_response(scene, 1.0 * omega**2 * Y, [curve.frequency[index]], sweep="up",
                                      tolerance=1e-4)
        X = relative.amplitude[0] * np.exp(1j * relative.phase[0]) + Y  # x = z + y
        assert abs(X) == pytest.approx(curve.amplitude[index], rel=3e-4)
        assert np.angle(X) == pytest.approx(curve.phase[index], abs=3e-4)
    # the branch slips: the response is not the linear one of the branch sticking nor of it slipping
    omega = 2 * math.pi * curve.frequency
    for k in (1.0, 2.0):
        linear = Y * np.abs((k + 0.02j * omega) / (k - omega**2 + 0.02j * omega))
        assert np.max(np.abs(curve.amplitude / linear - 1)) > 0.05


def test_several_force_amplitudes_are_one_curve_each_with_their_column(tmp_path):
    """--force-amplitude F1,F2: the rows of each curve as a single run writes them, one curve after the other,
    with force_amplitude after the contract's four columns."""
    two = tmp_path / "two.csv"
    arguments = ["describe", _one_node(tmp_path), "--frequencies", "0.5,1.2", "--harmonics", "1"]
    assert main([*arguments, "--force-amplitude", "0.01,0.02", "--out", str(two)]) == 0
    table = read_csv(two)
    assert list(table) == ["frequency", "amplitude", "phase", "stable", "force_amplitude", "amplitude_a", "fold",
                           "multiplier"]
    lines = two.read_text().splitlines()[1:]
    start = 0
    for F in ("0.01", "0.02"):
        single = tmp_path / f"{F}.csv"
        assert main([*arguments, "--force-amplitude", F, "--out", str(single)]) == 0
        rows = single.read_text().splitlines()[1:]
        for row, mine in zip(rows, lines[start:start + len(rows)]):
            cells = row.split(",")
            assert mine.split(",") == cells[:4] + [repr(float(F))] + cells[4:]
        start += len(rows)
    assert start == len(lines)
    # a linear scene: the response is proportional to F
    a = np.array(table["amplitude"], dtype=float)
    assert a[len(a) // 2:] == pytest.approx(2 * a[:len(a) // 2], rel=1e-10)


@pytest.mark.slow
def test_the_curves_of_a_parameter_study_do_not_depend_on_the_cluster(tmp_path):
    """The same CSV bytes with --workers 2 (a LocalCluster, one curve per task) as in-process, on the two-mass
    joint through its folds at H = 3, three amplitudes; and the figure draws them."""
    pytest.importorskip("distributed")
    pytest.importorskip("matplotlib")
    arguments = ["describe", "networks/two-mass-joint", "--force-amplitude", "0.05,0.1,0.2", "--frequencies",
                 "0.1,0.4", "--harmonics", "3"]
    local, cluster = tmp_path / "local.csv", tmp_path / "cluster.csv"
    assert main([*arguments, "--out", str(local), "--plot", str(tmp_path / "curves.png")]) == 0
    assert main([*arguments, "--workers", "2", "--out", str(cluster)]) == 0
    assert local.read_bytes() == cluster.read_bytes()
    table = read_csv(local)
    assert sorted(set(table["force_amplitude"])) == ["0.05", "0.1", "0.2"]
    assert table["fold"].count("true") >= 2
    assert (tmp_path / "curves.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
def test_a_curve_refused_on_the_cluster_is_one_line(tmp_path):
    """Of two curves on a LocalCluster, the one forced beyond Den Hartog's bound is refused in one line, as
    in-process, exit 2: the workers log nothing (a refusal raised in a task was logged there as a failed compute,
    with its traceback, on the user's terminal). Run as a user would, every process's stderr read."""
    import subprocess
    import sys

    pytest.importorskip("distributed")
    path = write(tmp_path, {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "friction": {"alpha": 0.1}})
    done = subprocess.run([sys.executable, "-m", "prandtl_fmu", "describe", str(path), "--force-amplitude",
                           "0.05,1", "--frequencies", "0.1,0.3", "--workers", "2"], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 2 and not done.stdout, done
    assert len(done.stderr.strip().splitlines()) == 1 and "Den Hartog" in done.stderr, done.stderr


@pytest.mark.parametrize("arguments, culprit", [
    (["--force-amplitude", "1", "--base-amplitude", "0.1", "--frequencies", "0.1"], "--base-amplitude"),
    (["--frequencies", "0.1"], "--force-amplitude"),
    (["--base-amplitude", "0", "--frequencies", "0.1"], "--base-amplitude"),
    (["--base-amplitude=-1e-3", "--frequencies", "0.1"], "--base-amplitude"),
    (["--base-amplitude", "0.1,nan", "--frequencies", "0.1"], "--base-amplitude"),
    (["--base-amplitude", "0.1"], "--frequencies"),
    (["--base-amplitude", "0.1", "--frequencies", "0.1", "--method", "time"], "--base-amplitude"),
    (["--base-amplitude", "0.1", "--frequencies", "0.1", "--load-node", "mass"], "--load-node"),
    (["--force-amplitude", "0.1,0.2", "--frequencies", "0.1", "--method", "time"], "--force-amplitude"),
    (["--force-amplitude", "0.1,0.2", "--frequencies", "0.1", "--workers", "0"], "--workers"),
    (["--force-amplitude", "0.1", "--frequencies", "0.1", "--workers", "2", "--scheduler", "tcp://x:1"],
     "--workers"),
    (["--amplitudes", "0.1", "--base-amplitude", "0.1"], "--base-amplitude"),
    (["--mode", "1", "--amplitudes", "0.1", "--base-amplitude", "0.1"], "--plot"),
])
def test_bad_input_is_one_line_and_exit_2_with_nothing_written(tmp_path, capsys, arguments, culprit):
    out = tmp_path / "out.csv"
    status = main(["describe", write(tmp_path, LINEAR), *arguments, "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2, err
    assert culprit in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not out.exists()


def test_the_library_refuses_both_or_neither_amplitude_and_a_bad_base():
    from prandtl_fmu.frequency import FrequencyError, harmonic_response, harmonic_responses

    scene = parse_scene(write_text(LINEAR))[0]
    for kwargs, culprit in (({}, "either"), ({"force_amplitude": 1.0, "base_amplitude": 0.1}, "not both"),
                            ({"base_amplitude": 0.0}, "base amplitude"),
                            ({"base_amplitude": 0.1, "load_node": "mass"}, "load node")):
        with pytest.raises(FrequencyError, match=culprit):
            harmonic_response(scene, frequencies=[0.5], harmonics=1, **kwargs)
    with pytest.raises(FrequencyError, match="base amplitudes"):
        harmonic_responses(scene, [0.5], base_amplitudes=[0.1, -1.0], harmonics=1)


def write_text(tables):
    from tests.conftest import scene_text

    return scene_text(tables)


TWO_MASSES_ON_A_BASE = """
name = "two masses on a moving base"
[network]
nodes = ["a", "b", "base"]
mass = [1.0, 1.0, 0.0]
load_node = "base"
[[network.spring]]
name = "ka"
between = ["a", "base"]
k = 1.0
[[network.spring]]
name = "kb"
between = ["b", "base"]
k = 1.0
[[network.cubic]]
name = "k3"
between = ["a", "base"]
k3 = 0.5
[[network.branch]]
name = "joint"
between = ["a", "b"]
k = 2.0
eta = 0.05
[[network.dashpot]]
name = "ca"
between = ["a", "base"]
c = 0.02
[[network.dashpot]]
name = "cb"
between = ["b", "base"]
c = 0.02
[solver]
stepper = "implicit"
step = 0.01
stop_time = 1.0
output_interval = 0.01
"""


@pytest.mark.slow
def test_base_excited_points_marked_unstable_leave_their_orbit_and_stable_ones_keep_it(tmp_path):
    """The two-mass joint with its support moving (the ground a node of its own whose motion the connector
    imposes, written out here: absolute coordinates) from the orbit of a point of the curve: the most unstable
    point's first harmonic leaves it within 60 periods, a stable one keeps it."""
    from prandtl_fmu.frequency import read_scene
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.frequency.floquet import orbit_start
    from prandtl_fmu.frequency.harmonic_balance import HarmonicBalance, periodic_system
    from prandtl_fmu.network.driver import NetworkConnector

    scene, _ = read_scene("networks/two-mass-joint", networks=True)
    Y = 0.1
    curve = harmonic_response(scene, frequencies=[0.1, 0.4], base_amplitude=Y, harmonics=3)
    unstable = np.flatnonzero(~curve.stable)
    assert curve.folds.size >= 2 and unstable.size
    system = periodic_system(scene)
    balance = HarmonicBalance(system, 3, None, None, Y)
    path = tmp_path / "base.toml"
    path.write_text(TWO_MASSES_ON_A_BASE)
    moving, _ = read_scene(str(path), networks=True)
    names = [e.name for e in moving.network.elements]
    steps, periods = 1024, 60
    worst = unstable[np.nanargmax(np.where(np.isnan(curve.multiplier[unstable]), -1, curve.multiplier[unstable]))]
    for index, leaves in ((worst, True), (10, False)):
        omega = 2 * math.pi * curve.frequency[index]
        h = 2 * math.pi / omega / steps
        connector = NetworkConnector(moving, "implicit", h)
        z, v, u = orbit_start(balance, (curve.coefficients[index] - _base(balance, Y)).reshape(-1)[balance.free],
                              omega)
        connector.reset()
        connector.x[:] = np.append(z + Y, Y)
        connector.v[:] = np.append(v, 0.0)
        connector.u[:] = [u[[e.name for e in system.network.elements].index(name)] if name == "joint" else 0.0
                          for name in names]
        connector.piece[:] = 0
        x_a = np.empty(steps)
        for step in range(1, periods * steps + 1):
            t = step * h
            connector.move_to(Y * math.cos(omega * t), -Y * omega * math.sin(omega * t), t)
            x_a[(step - 1) % steps] = connector.x[0]
        weights = np.exp(-1j * omega * h * np.arange(1, steps + 1)) * 2 / steps
        moved = abs(abs(x_a @ weights) - curve.amplitude[index]) / curve.amplitude[index]
        assert (moved > 0.1) if leaves else (moved < 1e-2), (index, moved)


def _base(balance, Y):
    """The base's motion y = Y cos(omega t) as harmonics of every node (n, L): what x = z + y adds to z."""
    out = np.zeros((balance.system.n, balance.L))
    out[:, 1] = Y
    return out
