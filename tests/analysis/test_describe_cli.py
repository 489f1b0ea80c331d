"""``prandtl-fmu describe`` (issue 47): its CSVs, its figures, and one line with exit status 2 and nothing
written for every kind of bad input."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main

from tests.conftest import scene_text

JOINT = {"spring": {"k0": 1.0}, "branches": {"k": [1.0, 2.0], "eta": [0.1, 0.3]}}
DAMPER = {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.1}, "branches": {"k": [1.0], "eta": [0.1]}}


def write(tmp_path, tables, name="scene.toml"):
    path = tmp_path / name
    path.write_text(scene_text(tables))
    return str(path)


def read_csv(path):
    lines = open(path).read().splitlines()
    header = lines[0].split(",")
    rows = [line.split(",") for line in lines[1:]]
    return {name: [row[j] for row in rows] for j, name in enumerate(header)}


def test_amplitudes_write_the_describing_function(tmp_path, capsys):
    """A scene with no [load] and no [solver]: the contract columns first, one row per amplitude."""
    out = tmp_path / "d.csv"
    assert main(["describe", write(tmp_path, JOINT), "--amplitudes", "0.05, 0.2,1", "--out", str(out)]) == 0
    table = read_csv(out)
    assert list(table)[:4] == ["amplitude", "stiffness", "dissipation", "loss_factor"]
    assert [float(a) for a in table["amplitude"]] == [0.05, 0.2, 1.0]
    K = np.array(table["stiffness"], dtype=float)
    D = np.array(table["dissipation"], dtype=float)
    assert K[0] == pytest.approx(4.0, rel=1e-13)  # nothing slips at 0.05: k0 + k1 + k2
    assert D[2] == pytest.approx(4 * 1.0 * 0.1 * 0.9 + 4 * 2.0 * 0.3 * 0.7, rel=1e-12)
    assert np.allclose(np.array(table["loss_factor"], dtype=float), D / (math.pi * K * np.array([0.05, 0.2, 1.0]) ** 2))
    assert table["method"] == ["exact"] * 3
    assert capsys.readouterr().err == ""


def test_a_frequency_response_to_standard_output(tmp_path, capsys):
    status = main(["describe", write(tmp_path, DAMPER), "--force-amplitude", "1e-4", "--frequencies", "0.1,0.3",
                   "--method", "time", "--sweep", "up"])
    assert status == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("frequency,amplitude,phase,sweep")
    frequency, amplitude, phase = (float(v) for v in lines[1].split(",")[:3])
    w = 2 * math.pi * frequency
    assert amplitude == pytest.approx(1e-4 / abs(2.0 - w * w + 0.1j * w), rel=1e-3)
    assert phase == pytest.approx(-np.angle(2.0 - w * w + 0.1j * w), abs=1e-3)
    assert len(lines) == 3 and lines[2].split(",")[3] == "up"


@pytest.mark.parametrize("arguments, culprit", [
    (["--amplitudes", "0.1,-2"], "--amplitudes"),
    (["--amplitudes", "0.1,abc"], "--amplitudes"),
    (["--amplitudes", "0"], "--amplitudes"),
    (["--amplitudes", "nan"], "--amplitudes"),
    ([], "either --amplitudes"),
    (["--amplitudes", "0.1", "--force-amplitude", "1"], "not both"),
    (["--force-amplitude", "1"], "--frequencies"),
    (["--force-amplitude", "1", "--frequencies", "0.1,-0.2"], "--frequencies"),
    (["--force-amplitude", "-1", "--frequencies", "0.1"], "--force-amplitude"),
    # beyond a scene's range of magnitudes [1e-50, 1e50] (1e-300 Hz overflowed the stability's step count)
    (["--force-amplitude", "1", "--frequencies", "1e-300"], "--frequencies"),
    (["--force-amplitude", "1e-320", "--frequencies", "0.1"], "--force-amplitude"),
    (["--force-amplitude", "1", "--frequencies", "0.1", "--method", "time", "--workers", "0"], "--workers"),
    (["--amplitudes", "0.1", "--frequencies", "0.1"], "--frequencies"),
    (["--amplitudes", "0.1", "--tolerance", "2"], "--tolerance"),
    (["--amplitudes", "0.1", "--plot", "figure.nope"], "--plot"),
])
def test_bad_options_are_one_line_and_exit_2_with_nothing_written(tmp_path, capsys, arguments, culprit):
    out = tmp_path / "out.csv"
    status = main(["describe", write(tmp_path, DAMPER), *arguments, "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2
    assert culprit in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not out.exists()


def test_scenes_the_command_refuses(tmp_path, capsys):
    out = tmp_path / "out.csv"
    cases = [
        (write(tmp_path, JOINT, "massless.toml"), ["--force-amplitude", "1", "--frequencies", "0.1"], "[mass]"),
        (write(tmp_path, {"spring": {"k0": 1.0}, "damper": {"c": 0.2}}, "dashpot.toml"), ["--amplitudes", "0.1"],
         "--frequency"),
        (write(tmp_path, {"spring": {"k0": 1.0}, "delay": {"gain": 0.1, "tau": 0.5}}, "delay.toml"),
         ["--amplitudes", "0.1"], "[delay]"),
        (write(tmp_path, {"spring": {"k0": -1.0}}, "broken.toml"), ["--amplitudes", "0.1"], "k0"),
        (str(tmp_path / "missing.toml"), ["--amplitudes", "0.1"], "missing.toml"),
        ("networks/two-masses-slider", ["--amplitudes", "0.1"], "[network]"),
    ]
    for scene, arguments, culprit in cases:
        status = main(["describe", scene, *arguments, "--out", str(out)])
        err = capsys.readouterr().err
        assert status == 2, err
        assert culprit in err and len(err.strip().splitlines()) == 1
        assert not out.exists()


def test_a_rate_dependent_scene_with_its_frequency(tmp_path):
    out = tmp_path / "d.csv"
    scene = write(tmp_path, {"spring": {"k0": 1.0}, "damper": {"c": 0.2}})
    assert main(["describe", scene, "--amplitudes", "0.5", "--frequency", "2", "--out", str(out)]) == 0
    table = read_csv(out)
    assert float(table["dissipation"][0]) == pytest.approx(math.pi * 0.2 * 2 * math.pi * 2 * 0.25, rel=1e-13)


def test_an_infinite_loss_factor_is_an_empty_field(tmp_path):
    """A dashpot alone: K = 0, D = pi c w A^2, the loss factor infinite: written as an empty field, exit 0."""
    out = tmp_path / "d.csv"
    scene = write(tmp_path, {"damper": {"c": 1.0}})
    assert main(["describe", scene, "--amplitudes", "0.5", "--frequency", "0.5", "--out", str(out)]) == 0
    table = read_csv(out)
    assert float(table["stiffness"][0]) == 0.0 and table["loss_factor"] == [""]
    assert float(table["dissipation"][0]) == pytest.approx(math.pi * 2 * math.pi * 0.5 * 0.25, rel=1e-15)


def test_an_amplitude_whose_numbers_overflow_is_named(tmp_path, capsys):
    out = tmp_path / "d.csv"
    scene = write(tmp_path, {"spring": {"k0": 1.0}, "damper": {"c": 1.0}})
    assert main(["describe", scene, "--amplitudes", "0.5,1e300", "--frequency", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "at A = 1e+300 m, D overflows" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_friction_on_a_belt_in_both_modes(tmp_path):
    """Friction with a Stribeck drop on a moving belt: the describing function (at --frequency) and the
    frequency response by time integration both take it (--amplitudes refused it, --force-amplitude did not); a dashpot damps
    the stick-slip that the drop would excite."""
    out = tmp_path / "d.csv"
    scene = write(tmp_path, {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.5},
                             "friction": {"alpha": 0.3, "alpha_kinetic": 0.2, "stribeck_velocity": 0.1,
                                          "belt_velocity": 0.5}})
    assert main(["describe", scene, "--amplitudes", "0.5", "--frequency", "0.5", "--out", str(out)]) == 0
    assert float(read_csv(out)["stiffness"][0]) == 1.0 and float(read_csv(out)["dissipation"][0]) > 0
    out.unlink()
    assert main(["describe", scene, "--force-amplitude", "1", "--frequencies", "0.1", "--method", "time", "--out",
                 str(out)]) == 0
    assert float(read_csv(out)["amplitude"][0]) > 0


def test_a_result_that_cannot_reach_its_accuracy_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch):
    from prandtl_fmu.frequency import response

    monkeypatch.setattr(response, "MAX_PERIODS", 3)
    out = tmp_path / "r.csv"
    scene = write(tmp_path, {"mass": {"m": 1.0}, "spring": {"k0": 1.0}, "damper": {"c": 0.001}})
    assert main(["describe", scene, "--force-amplitude", "1", "--frequencies", "0.1", "--method", "time", "--out",
                 str(out)]) == 2
    err = capsys.readouterr().err
    assert "did not settle" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_plot_without_matplotlib_names_the_extra(tmp_path, capsys, monkeypatch):
    from prandtl_fmu.frequency import cli

    monkeypatch.setattr(cli, "_missing", lambda *names: [name for name in names if name == "matplotlib"])
    status = main(["describe", write(tmp_path, JOINT), "--amplitudes", "0.1", "--plot", str(tmp_path / "k.png")])
    err = capsys.readouterr().err
    assert status == 2 and "prandtl_fmu[plot]" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "k.png").exists()


def test_the_figures_are_written(tmp_path):
    pytest.importorskip("matplotlib")
    for arguments in (["--amplitudes", "0.05,0.1,0.3,1"],
                      ["--force-amplitude", "0.05", "--frequencies", "0.1,0.2,0.3", "--method", "time"]):
        plot = tmp_path / "figure.png"
        scene = write(tmp_path, DAMPER if "--force-amplitude" in arguments else JOINT)
        assert main(["describe", scene, *arguments, "--plot", str(plot), "--out", str(tmp_path / "o.csv")]) == 0
        assert plot.read_bytes()[:4] == b"\x89PNG"
        plot.unlink()


def test_a_negative_delay_gain_with_a_short_tau_is_described_without_a_solver_table(tmp_path):
    # the scene has no [solver]: the step a time run would need is not the user's, and must not refuse the scene
    # (it did: "tau = 1e-06 s below the step 0.001 s"); the response is the linear closed form
    # F0 / |k0 + g e^(-i w tau) - m w^2 + i c w|
    path = tmp_path / "delay.toml"
    path.write_text("[mass]\nm = 1.0\n[spring]\nk0 = 1.0\n[damper]\nc = 0.1\n[delay]\ngain = -0.2\ntau = 1e-6\n")
    out = tmp_path / "curve.csv"
    assert main(["describe", str(path), "--force-amplitude", "0.1", "--frequencies", "0.1,0.2", "--out",
                 str(out)]) == 0
    rows = np.genfromtxt(out, delimiter=",", names=True, dtype=None, encoding="utf-8")
    w = 2 * math.pi * rows["frequency"]
    closed = 0.1 / np.abs(1.0 - 0.2 * np.exp(-1j * w * 1e-6) - w * w + 0.1j * w)
    assert np.allclose(rows["amplitude"], closed, rtol=1e-6)


def test_a_single_frequency_is_written_as_listed(tmp_path):
    """The points are taken in omega = 2 pi f; the ends come back as the frequencies listed, not 2 pi f / 2 pi
    (0.17 was written 0.17000000000000004)."""
    out = tmp_path / "one.csv"
    assert main(["describe", write(tmp_path, DAMPER), "--force-amplitude", "0.1", "--frequencies", "0.17",
                 "--out", str(out)]) == 0
    assert read_csv(out)["frequency"] == ["0.17"]
    assert main(["describe", write(tmp_path, DAMPER), "--force-amplitude", "0.1", "--frequencies", "0.19,0.17",
                 "--out", str(out)]) == 0
    frequencies = read_csv(out)["frequency"]
    assert frequencies[0] == "0.17" and frequencies[-1] == "0.19"


DUFFING_BRANCHES = {"mass": {"m": 0.5}, "spring": {"k0": 2.0}, "cubic": {"k3": 3.0}, "damper": {"c": 0.05},
                    "branches": {"k": [1.0, 3.0], "alpha": [0.05, 0.3]}}


@pytest.mark.parametrize("frequencies", [[0.12], [0.12, 0.15]])
def test_the_harmonics_chosen_are_within_the_tolerance_of_many(frequencies):
    """Without --harmonics, H grows until the first harmonic changes by at most the tolerance twice in a row:
    here it changes by 9.7e-4 from H = 1 to 3 (within 1e-3), and H = 3 is 2.4e-3 off H = 63; the point at
    0.12 Hz is within the tolerance of the balance with 63 harmonics, whatever else is listed."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from tests.analysis.test_harmonic_balance import element

    scene = element(DUFFING_BRANCHES)
    chosen = harmonic_response(scene, 0.3, frequencies, stability=False)
    many = harmonic_response(scene, 0.3, [0.12], harmonics=63, stability=False)
    assert chosen.harmonics > 3
    X = chosen.amplitude[0] * np.exp(1j * chosen.phase[0])
    X_many = many.amplitude[0] * np.exp(1j * many.phase[0])
    assert abs(X - X_many) <= 1e-3 * abs(X_many)


def test_a_harmonic_balance_curve_shows_its_progress_on_a_terminal(tmp_path, capsys, monkeypatch):
    """On a terminal (stderr a tty, not CI) the curve says how far it is: the points taken under the number of
    harmonics being tried, then the stability of each point; the CSV is the one written without it. Off a
    terminal nothing is printed (the same run in a pipe, as every other test runs)."""
    import sys

    args = ["describe", "networks/two-mass-joint", "--force-amplitude", "0.2", "--frequencies", "0.1,0.4"]
    quiet = tmp_path / "quiet.csv"
    assert main(args + ["--out", str(quiet)]) == 0
    assert capsys.readouterr().err == ""
    monkeypatch.delenv("CI", raising=False)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    shown = tmp_path / "shown.csv"
    assert main(args + ["--out", str(shown)]) == 0
    err = capsys.readouterr().err
    assert "harmonic balance, H = 1 (chosen by the tolerance)" in err and "stability of each point, H = " in err
    assert shown.read_text() == quiet.read_text()
