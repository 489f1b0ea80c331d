"""A curve that closes on itself (``continuation._Trail``): seen on its second pass, never on a curve that only
comes near itself, crosses itself another way or turns back at a fold."""
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main
from prandtl_fmu.frequency import continuation


def _walk(points, step=0.1):
    """The trail of ``points`` ((q, omega) in the plane, omega in [0, 1], scale 1): the first frequency a point
    came back to, and the index of that point, or None."""
    trail = continuation._Trail(points[0][1], np.array([points[0][0]]))
    for index, (q, omega) in enumerate(points[1:], start=1):
        again = trail.add(omega, np.array([q]), 1.0, 0.0, 1.0, step)
        if again is not None:
            return again, index
    return None


def _circle(turns, count=40, radius=0.3):
    angles = np.linspace(0.0, 2 * math.pi * turns, int(count * turns), endpoint=False)
    return [(radius * math.sin(a), 0.5 - radius * math.cos(a)) for a in angles]


def test_a_loop_is_seen_on_its_second_pass_and_not_before():
    points = _circle(turns=3)
    found = _walk(points)
    assert found is not None
    _, index = found
    assert 40 < index <= 40 + continuation.LOOP_GAP + 3  # the second lap, within a few points of its start
    assert _walk(_circle(turns=0.97)) is None  # the first lap alone: nothing


def test_a_second_pass_with_other_points_on_the_same_loop_is_seen():
    """The second lap's points fall between the first's (another step size): still on its stretches."""
    first = _circle(turns=1, count=40)
    second = [(0.3 * math.sin(a), 0.5 - 0.3 * math.cos(a)) for a in np.linspace(0.07, 2 * math.pi, 33)]
    assert _walk(first + second) is not None


def test_a_curve_that_comes_near_itself_crosses_itself_or_turns_back_is_no_loop():
    # a spiral: each lap 0.1 (a stretch's length about 0.05) outside the last
    angles = np.linspace(0.0, 6 * math.pi, 120)
    spiral = [((0.1 + 0.1 * a / (2 * math.pi)) * math.sin(a), 0.5 - (0.1 + 0.1 * a / (2 * math.pi)) * math.cos(a))
              for a in angles]
    assert _walk(spiral, step=0.05) is None
    # a figure of eight: through its middle twice, the second time across the first
    eight = [(0.3 * math.sin(2 * a), 0.5 + 0.3 * math.sin(a)) for a in np.linspace(0.0, 2 * math.pi, 80)[:-2]]
    assert _walk(eight) is None
    # a fold: up in omega, then back down along a neighbouring branch (the way back, the other way)
    there = [(0.01 * i, 0.1 + 0.02 * i) for i in range(30)]
    back = [(0.3 + 0.005 * i, 0.1 + 0.02 * (29 - i)) for i in range(30)]
    assert _walk(there + back) is None
    assert _walk(there + [(q, omega) for q, omega in reversed(there)]) is None  # exactly back: the other way
    # steps shrinking fast towards a corner (the delay oscillator's slip onset at 0.1 N: 0.0117, 0.0058, 4e-4,
    # 2e-4, 1e-4, 1e-5, 7e-7): a point past the end of a stretch four points back, within an eighth of its length,
    # but only just past it; then the corner turns the curve back by 131 degrees
    steps = [0.3, 0.17, 0.046, 0.0117, 0.0058, 3.7e-4, 1.8e-4, 9e-5, 1.1e-5, 7e-7]
    line = [(0.0, 0.1)]
    for length in steps:
        line.append((line[-1][0] + 0.6 * length, line[-1][1] + 0.8 * length))
    turn = math.radians(180 - 131)
    out = [(line[-1][0] - 0.1 * i * math.cos(turn), line[-1][1] + 0.1 * i * math.sin(turn)) for i in range(1, 6)]
    assert _walk(line + out, step=7e-7) is None


def test_the_delay_oscillator_s_loop_is_refused_at_once_with_where(tmp_path, capsys, monkeypatch):
    """The packaged delay oscillator (linearly unstable: every time sweep diverges) at 0.6 N: past a corner at
    0.1255 Hz its curve goes round a loop between 0.113 and 0.131 Hz. It went round until 20000 points (five
    minutes); the second pass is refused within the first 100 points, in one line that says where."""
    monkeypatch.setattr(continuation, "MAX_POINTS", 100)
    out = tmp_path / "curve.csv"
    assert main(["describe", "delay-oscillator", "--force-amplitude", "0.6", "--frequencies", "0.05,0.6",
                 "--out", str(out)]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and "the curve closed on itself: at f = 0.12" in error
    assert "stretch it took at f = 0.12" in error and not out.exists()
