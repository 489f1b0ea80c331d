"""A fold on a corner of a curve, on curves whose corner is known exactly: the continuation's way on past it
(``continuation._around_corner``) and the finer resolution's points left out past it
(``shooting._solved_again``)."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from prandtl_fmu.frequency import FrequencyError, continuation, shooting


class Corner:
    """R(q, omega) = omega - omega_c + g(q - q_c), g(d) = -a d below the corner and b d above: the curve comes up
    in q with omega increasing (omega = omega_c - a (q_c - q)) and turns back at (q_c, omega_c) (omega = omega_c -
    b (q - q_c)), a fold on a kink."""

    def __init__(self, a=1.0, b=3.0, q_c=1.0, omega_c=2.0):
        self.a, self.b, self.q_c, self.omega_c = a, b, q_c, omega_c
        self.system = SimpleNamespace(source="corner.toml", load_node=0, nodes=("mass",))

    def slope(self, q):
        return self.b if q[0] > self.q_c else -self.a

    def evaluate(self, q, omega):
        d = q[0] - self.q_c
        residual = np.array([omega - self.omega_c + (self.b * d if d > 0 else -self.a * d)])
        return residual, np.array([[self.slope(q)]]), np.array([1.0]), None

    def residual_at(self, q, omega):
        return self.evaluate(q, omega)[0]

    def force_scale(self, omega):
        return 1.0


def test_the_way_on_past_a_corner_is_against_the_far_side_s_tangent():
    """The last point is a hair past the corner, on the far side's Jacobian; its tangent, taken ahead in omega,
    points along q < q_c where the curve is the way it came (omega falls there): the point at the step's distance
    ahead is on the far side (q > q_c, omega = omega_c - b (q - q_c)), found against that tangent, not the way
    back."""
    balance = Corner()
    q0 = np.array([balance.q_c + 1e-9])
    omega0 = balance.omega_c - balance.b * 1e-9
    tangent = np.array([-1.0, balance.b]) / math.hypot(1.0, balance.b)  # the far side's, ahead in omega
    behind = np.array([-1.0, -balance.a]) / math.hypot(1.0, balance.a)  # to the point before, on the way in
    step = 1e-3
    found = continuation._around_corner(balance, q0, omega0, tangent, 1.0, 0.0, 1.0, step, behind)
    assert found is not None
    q, omega, _ = found
    assert q[0] > balance.q_c
    assert omega == pytest.approx(balance.omega_c - balance.b * (q[0] - balance.q_c), abs=1e-12)
    assert math.hypot(q[0] - q0[0], omega - omega0) == pytest.approx(step, rel=1e-9)


def test_past_a_corner_the_way_back_is_never_taken():
    """Where only the way back lies on the sphere (the curve ends at the corner: g = -a d on both sides, a
    straight line that the search must not walk back along), no point is found."""
    balance = Corner(b=-1.0)  # omega = omega_c + (q - q_c) above: the same line as below, no corner
    q0 = np.array([balance.q_c])
    omega0 = balance.omega_c
    along = np.array([1.0, 1.0]) / math.sqrt(2.0)
    found = continuation._around_corner(balance, q0, omega0, along, 1.0, 0.0, 1.0, 1e-3, -along)
    assert found is not None and found[0][0] > balance.q_c  # ahead: the line goes on
    found = continuation._around_corner(balance, q0, omega0, -along, 1.0, 0.0, 1.0, 1e-3, -along)
    assert found is None or found[0][0] > balance.q_c  # never the point behind


class Shifted:
    """A finer resolution whose curve is the coarse one with its corner moved down in omega by ``shift``: Newton
    at a frequency past it finds nothing."""

    def __init__(self, corner, shift):
        self.corner, self.shift = corner, shift
        self.system = corner.system
        self.delay_harmonics, self.M = 3, 128

    def _newton(self, omega, guess):
        if omega > self.corner.omega_c - self.shift:
            return None
        return np.array(guess, dtype=float)

    def evaluate(self, q, omega):
        return self.corner.evaluate(q, omega + self.shift)

    def force_scale(self, omega):
        return 1.0


def points_near(corner, spacing):
    """(omega, s, fold) up the near side to the corner and down the far side, ``spacing`` apart in q."""
    up = [(corner.omega_c - corner.a * k * spacing, np.array([corner.q_c - k * spacing]), False)
          for k in (4, 3, 2, 1)]
    top = [(corner.omega_c, np.array([corner.q_c]), True)]
    down = [(corner.omega_c - corner.b * k * spacing, np.array([corner.q_c + k * spacing]), False)
            for k in (1, 2, 3, 4)]
    return up + top + down


def _coarse():
    return SimpleNamespace(padded=lambda s, finer: np.array(s, dtype=float))


def test_the_points_past_a_moved_corner_are_left_out_and_the_fold_moves_to_the_point_before(monkeypatch):
    monkeypatch.setattr(continuation, "across", lambda *args: None)
    corner = Corner()
    points = points_near(corner, 1e-6)
    finer = Shifted(corner, 1.5e-6)  # past the finer corner: the point up at k = 1 and the corner
    out, kept = shooting._solved_again(_coarse(), finer, points, 1.0, 3.0, 1e-4)
    assert list(kept) == [0, 1, 2, 5, 6, 7, 8]
    assert [fold for _, _, fold in out] == [False, False, True, False, False, False, False]
    assert [omega for omega, _, _ in out] == [points[index][0] for index in kept]


def test_a_point_not_found_far_from_a_fold_or_its_neighbours_is_refused(monkeypatch):
    monkeypatch.setattr(continuation, "across", lambda *args: None)
    corner = Corner()
    points = points_near(corner, 1e-6)
    with pytest.raises(FrequencyError, match="was not found from the coarser one's"):  # the run spans 2e-6 in q
        shooting._solved_again(_coarse(), Shifted(corner, 1.5e-6), points, 1.0, 3.0, 1e-6)
    no_fold = [(omega, s, False) for omega, s, _ in points]
    with pytest.raises(FrequencyError, match="at f = "):
        shooting._solved_again(_coarse(), Shifted(corner, 1.5e-6), no_fold, 1.0, 3.0, 1e-4)
    with pytest.raises(FrequencyError):  # the last point not found: no neighbour after it
        shooting._solved_again(_coarse(), Shifted(corner, 5e-6), points[:5], 1.0, 3.0, 1e-4)


def test_a_point_the_normal_moves_far_is_not_kept(monkeypatch):
    """The normal through a coarse point near a corner can meet the finer curve on its far side, far away (a
    review's find: kept, out of order, the fold 1e-3 past the corner): a point ``across`` moves by more than the
    spacing is not found; one it moves within the spacing is kept where it lands."""
    corner = Corner()
    points = points_near(corner, 1e-6)

    def moved(by):
        def across(balance, finer, lift, q, omega, low, high):
            return q + by, omega * (1.0 - by)
        return across

    monkeypatch.setattr(continuation, "across", moved(1e-3))
    with pytest.raises(FrequencyError, match="was not found from the coarser one's"):
        shooting._solved_again(_coarse(), Shifted(corner, 1e-3), points, 1.0, 3.0, 1e-4)
    monkeypatch.setattr(continuation, "across", moved(1e-7))
    out, kept = shooting._solved_again(_coarse(), Shifted(corner, 1.5e-6), points, 1.0, 3.0, 1e-4)
    assert list(kept) == list(range(len(points)))
    assert out[3][0] == pytest.approx(points[3][0] * (1.0 - 1e-7), rel=1e-15)


def folds_marked(points) -> int:
    return sum(1 for point in points if point[2])


class Parabola:
    """R(q, omega) = omega - omega_c + c (q - q_c)^2: a smooth fold at (q_c, omega_c), the curve turning back."""

    def __init__(self, c=2.0, q_c=1.0, omega_c=2.0):
        self.c, self.q_c, self.omega_c = c, q_c, omega_c
        self.system = SimpleNamespace(source="parabola.toml", load_node=0, nodes=("mass",))

    def evaluate(self, q, omega):
        d = q[0] - self.q_c
        return (np.array([omega - self.omega_c + self.c * d * d]), np.array([[2.0 * self.c * d]]), np.array([1.0]),
                None)

    def force_scale(self, omega):
        return 1.0


@pytest.mark.parametrize("past", [0.15, 0.003])
def test_a_bridge_follows_the_curve_through_its_fold_from_one_point_to_another(past):
    """``continuation.bridge``: from a point before a fold to one after it (the delay oscillator at 0.3 N, whose
    finer resolution moves a fold past the coarser fold point and its neighbour, so that neither exists at its
    frequency), the points between are on the curve, in order along it, one of them the fold, marked, at the
    parabola's vertex; also where the end is just past the fold, within the bridge's last step (a review's find:
    the fold went unmarked)."""
    balance = Parabola()
    start = (balance.omega_c - balance.c * 0.01, np.array([balance.q_c - 0.1]))
    end = (balance.omega_c - balance.c * past**2, np.array([balance.q_c + past]))
    heading = np.array([1.0, 1.0]) / math.sqrt(2.0)  # q and omega growing towards the fold
    between = continuation.bridge(balance, start, end, heading, 1.0, 3.0)
    assert between is not None and len(between) >= 4
    q = np.array([p[1][0] for p in between])
    assert folds_marked(between) == 1
    assert np.all(np.diff(q) > 0) and start[1][0] < q[0] and q[-1] < end[1][0]
    for omega, state, _ in between:
        assert abs(balance.evaluate(state, omega)[0][0]) <= 1e-10
    folds = [p for p in between if p[2]]
    assert folds[0][1][0] == pytest.approx(balance.q_c, abs=1e-6) and folds[0][0] == pytest.approx(balance.omega_c)


def test_a_resolution_that_bridged_points_is_never_the_last(monkeypatch):
    """A bridged point has no coarser twin, so its change is not measured at the level that bridged it: that
    level is never the last, whatever the change at the others (a review's find). On a delay with a vanishing
    friction one level suffices (the linear closed form, 1e-9); the same curve with its last point marked bridged
    at the first level goes on to a second, and its points are then the closed form's as before."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from tests.analysis.test_delay_friction import DELAYED
    from tests.analysis.test_harmonic_balance import element

    levels, solved_again = [], shooting._solved_again

    def marked(coarse, finer, points, *args):
        out, kept = solved_again(coarse, finer, points, *args)
        if not levels:
            kept = np.array(kept)
            kept[-1] = -1
        levels.append(finer.M)
        return out, kept

    tables = dict(DELAYED, friction={"alpha": 1e-9}, delay={"gain": -0.2, "tau": 0.5})
    plain = harmonic_response(element(tables), 1.0, [0.05, 0.4], tolerance=1e-9)
    monkeypatch.setattr(shooting, "_solved_again", marked)
    curve = harmonic_response(element(tables), 1.0, [0.05, 0.4], tolerance=1e-9)
    assert len(levels) == 2 and levels[1] == 2 * levels[0]
    assert plain.frequency.size == curve.frequency.size
    assert np.allclose(curve.amplitude, plain.amplitude, rtol=1e-8, atol=0)


def test_a_deflated_newton_finds_the_sphere_s_other_point_from_beside_the_first():
    """``continuation._deflated``: on the unit circle about the origin and the line y_1 = 1/2 (two points,
    (+-sqrt(3)/2, 1/2)), Newton from (0.8, 0.6) goes to the near point; with that point deflated, from the same
    guess, to the far one, as the corner's search goes from the way back to the way on."""
    def newton(y, root=None):
        for _ in range(continuation.DEFLATED_ITERATIONS):
            residual = np.array([y[1] - 0.5, y @ y - 1.0])
            jacobian = np.array([[0.0, 1.0], 2.0 * y])
            delta = np.linalg.solve(jacobian, -residual)
            if root is not None:
                delta = continuation._deflated(delta, y, root, 1.0)
            y = y + delta
            if np.max(np.abs(delta)) <= 1e-14:
                return y
        return None

    near = newton(np.array([0.8, 0.6]))
    assert near == pytest.approx([math.sqrt(3.0) / 2.0, 0.5], abs=1e-14)
    far = newton(np.array([0.8, 0.6]), near)
    assert far is not None and far == pytest.approx([-math.sqrt(3.0) / 2.0, 0.5], abs=1e-14)
    assert continuation._deflated(np.ones(2), near, near, 1.0) is None  # at the root itself: no step
