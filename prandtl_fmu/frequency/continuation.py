"""Arc-length continuation of a harmonic balance in (coefficients, omega), through folds.

The curve R(q, omega) = 0 is followed from omega_min to omega_max in scaled unknowns y = (q / q_ref,
(omega - omega_min) / (omega_max - omega_min)), q_ref the largest |q| met so far (2-norm; the scale is
updated as the curve grows, the tangent rescaled with it; at least the balance's ``length_scale`` where it has
one, for a curve that starts at rest):

* tangent: t solves [dR/dq  dR/domega; t_prev] t = [0; 1], normalised (the previous tangent's side kept: a
  fold is passed, not turned back on; past a corner, the chord's side). The sign of det [dR/dy; t^T] is kept
  along too: where the two disagree and the side would turn the curve back in omega, the determinant's is
  taken. Along a smooth curve they agree (at a fold both turn); at a kink (a slip that starts or stops: the
  Jacobians on its two sides differ) the tangent can turn by more than a right angle, where the side alone
  turned the curve back (a chain on a support), while the determinant alone can flip at a kink of the sampled
  forces without a fold (measured on two masses and a joint at H = 3), where the side goes on;
* predictor y + ds t; corrector: Newton on [R(y); t . (y - y_pred)] = 0 (the step's hyperplane), at most
  CORRECTOR_ITERATIONS iterations; a corrector that does not converge halves ds, down to MIN_STEP, then the
  curve is refused where it stopped (FrequencyError: the frequency, the amplitude and why); a corrector that
  moves further than DRIFT steps from its prediction (at a kink of the Jacobian, where a slip starts, Newton can
  leap to another part of the curve) counts as not converged;
* chord: where the Jacobian is costly (shooting: one run of the motion per unknown), the corrector first keeps
  the Jacobian of the last point (the chord method, one run an iteration, at most CHORD_ITERATIONS), then
  Newton's;
* kink: below CORNER of the largest step, a corrector that does not converge is tried again as a damped Newton
  (each step halved while the residual grows), with omega fixed, then the tangent's largest unknown fixed, then
  on the hyperplane (:func:`_damped`): at a kink Newton on the hyperplane can cycle between the Jacobians of the
  two sides, where the curve parametrised by its frequency goes on; then on a sphere around the last point (a
  fold on a kink, a corner);
* step: ds grows or shrinks by the corrector's iterations against TARGET_ITERATIONS (at most doubled, at
  least halved), within [MIN_STEP, max_step]; max_step is ARC_ESTIMATE over the count of listed frequencies
  less one, over FEWEST_STEPS at least (a curve through one resonance gets about as many points as
  frequencies asked, at least that many, more where it bends); a point where the tangent turned by more than
  60 degrees (TURN) from the last is taken again at half the step, down to CORNER of max_step: a tight fold
  gets its points, and a kink (where a node starts to slip, whose turn does not shrink with the step) is
  located to that (the base-excited friction element went from its stuck part to its slipping part in one
  step past the onset of slip, which the line between them hid);
  a loop narrower than the largest step can still be stepped over whole (both ends agree: tangents, determinant
  and secant cannot see it): with FEWEST_STEPS 8 a belt with a history at F0 = 0.5 N, 0.07 to 0.12 Hz, went
  from 0.07 to 0.103 Hz in one step over a fold pair 0.15 of scaled arc long (0.0895 to 0.0902 Hz); at 16 it
  is found, and the analysis tests take 7 % more points (5363 to 5747): list more frequencies to refine;
* fold: where the omega-component of the tangent changes sign between two points; located by the secant
  method on that component along the arc between them (at most FOLD_ITERATIONS correctors, to 1e-9 of the
  step) and kept as a point of its own, marked;
* end: the point past omega_max is replaced by the point at omega_max (the corrector with omega fixed). At
  most MAX_POINTS points; a curve that turns back below omega_min or takes more points is refused;
* loop: a curve whose points lie again, twice in a row, on a stretch it took before (within an eighth of that
  stretch's length or of the step, whichever is larger; not the last LOOP_GAP points, and an arc length of at
  least LOOP_ROUND times that since it) going the same way has closed on itself: it would go round for ever,
  and is refused at once, with where it came back (:class:`_Trail`).
  The packaged delay oscillator at 0.6 N went round a loop between 0.113 and 0.131 Hz until MAX_POINTS (five
  minutes); it is refused after 60 points, in about 2 s;
* behind: a corrector that lands back in omega while both tangents point ahead (no fold between) has landed
  on another part of the curve (a linear oscillator from just above its resonance: the predictor overshot
  past q = 0 and the corrector found the curve below the resonance, which was refused as turned back): the
  step is taken again at half the length, down to MIN_STEP.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from . import FrequencyError
from .harmonic_balance import solve_linear

CORRECTOR_ITERATIONS = 12
TARGET_ITERATIONS = 4
MIN_STEP = 1e-7
FOLD_ITERATIONS = 40
MAX_POINTS = 20000
CONVERGED = 1e-10  # a corrector step below this (scaled max norm) has converged
CORNER = 1e-2  # below this fraction of the largest step, a failing corrector tries a kink's, then a corner's
ARC_ESTIMATE = 6.0  # about the scaled arc length of a curve through one resonance and its folds
FEWEST_STEPS = 16  # the largest step is at most ARC_ESTIMATE / FEWEST_STEPS, however few frequencies are listed
DRIFT = 0.5  # a corrector may move at most this many arc-length steps from its prediction
CHORD_ITERATIONS = 24  # of the chord corrector (a costly Jacobian kept from the last point)
CHORD_TARGET = 16  # its iterations that count as TARGET_ITERATIONS of Newton's for the step's size
DAMPED_ITERATIONS = 30  # of each corrector over a kink (its steps halved while the residual grows)
HALVINGS = 8  # of a step of those correctors
DAMPED_REACH = 4.0  # their point is at most this many arc-length steps from the last point
TURN = 0.5  # a point whose tangent turned by more than 60 degrees from the last is taken again at half the step
MISSED = 0.2  # march_curve: a point whose prediction missed by more than this many steps is taken again at half
RESOLUTION = 1e-2  # march_curve: a miss below this (scaled: 1 % of the curve drawn) is not chased
BRIDGE_STEPS = 64  # bridge: the most arc-length steps between two points of a curve
DEFLATE_BELOW = 1e-5  # the corner's search deflates the way back at arc-length steps up to this (scaled)
DEFLATED_ITERATIONS = 64  # of the sphere's Newton with the way back deflated (measured: up to 37 at a corner)
FIXED_SHARE = 0.05  # an unknown is fixed by those correctors if its share of the unit tangent is at least this
LOOP_GAP = 4  # a loop: the stretches between the last this many points are not looked at
LOOP_NEAR = 0.125  # a loop: within this fraction of a stretch's length (or of the step) of it
LOOP_ALONG = 0.5  # a loop: the cosine between the new stretch and the old one, at least
LOOP_ROUND = 4.0  # a loop: the arc length since the old stretch, at least this many times its length (or the step)


def continue_curve(balance, omega_min: float, omega_max: float, count: int, progress=None,
                   node: Optional[int] = None, start: Optional[np.ndarray] = None) -> list:
    """``[(omega, q_free, is_fold)]`` along the curve of ``balance`` (:class:`HarmonicBalance`) from
    ``omega_min`` to ``omega_max`` (rad/s) (see the module); ``count``: the frequencies listed; ``node``: the
    index of the node whose amplitude a refusal names (the curve's ``amplitude``; default the load's node);
    ``start``: the point at ``omega_min`` where it is known (else solved for)."""
    span = omega_max - omega_min
    q = balance.solve_at(omega_min) if start is None else np.array(start, dtype=float)
    _isolated(balance, q, omega_min)
    points = [(omega_min, q, False)]
    if span <= 0:
        return points
    # a curve that starts at rest (a mass stuck to its moving support) has q = 0: its scale is then the motion's
    # natural size where the balance has one (``length_scale``), not the rounding floor that sent y to 1e286
    floor = balance.length_scale(omega_min) if hasattr(balance, "length_scale") else 0.0
    scale = max(_size(balance, q, omega_min), floor, 1e-300)
    max_step = ARC_ESTIMATE / max(count - 1, FEWEST_STEPS)
    step = max_step
    omega = omega_min
    start = _oriented(balance, q, omega, None, scale, span)
    tangent, orientation, chord = (None, None, None) if start is None else start
    trail = _Trail(omega_min, q)
    if tangent is None or orientation == 0:
        raise FrequencyError(f"{balance.system.source}: the curve cannot start at f = {_hz(omega)!r} Hz: the "
                             "Jacobian is singular there")
    while True:
        if len(points) > MAX_POINTS:
            raise FrequencyError(f"{balance.system.source}: the curve did not reach f = {_hz(omega_max)!r} Hz "
                                 f"within {MAX_POINTS} points (at f = {_hz(omega)!r} Hz, "
                                 f"{_where(balance, q, omega, node)}: if it grew without bound there, a resonance "
                                 "that nothing limits)")
        new = None
        cornered = False
        while new is None:
            predicted = _scaled(q, omega, scale, omega_min, span) + step * tangent
            new = _correct(balance, predicted, tangent, scale, omega_min, span, step, chord)
            if new is None and step < CORNER * max_step:  # a kink, then a corner (a fold on a kink)
                new = _damped(balance, q, omega, tangent, scale, omega_min, span, step)
                if new is None:
                    # deflated only at the smallest steps: at a larger one the corner, the fold, is placed that
                    # much less exactly (the delay oscillator's slip onset at 0.1 N, at 0.20041 m for its 0.2 m
                    # with a step of 2e-3, where the plain guesses find the way on at 1.4e-6)
                    new = _around_corner(balance, q, omega, tangent, scale, omega_min, span, step,
                                         _behind(points, q, omega, scale, omega_min, span),
                                         deflate=step <= DEFLATE_BELOW)
                    cornered = new is not None  # a fold met there is at this point (not located by the secant)
            if new is None:
                step *= 0.5
                if step < MIN_STEP:
                    raise FrequencyError(
                        f"{balance.system.source}: the curve cannot continue past f = {_hz(omega)!r} Hz ("
                        f"{_where(balance, q, omega, node)}): the corrector does not "
                        f"converge even with an arc-length step of {MIN_STEP:g} (a bifurcation or a kink of the "
                        "curve)")
        q_new, omega_new, iterations = new
        scale_new = max(scale, _size(balance, q_new, omega_new))
        heading = tangent
        if cornered:  # the way on is the chord from the corner, not the tangent before it
            heading = _scaled(q_new, omega_new, scale, omega_min, span) - _scaled(q, omega, scale, omega_min, span)
            heading /= np.linalg.norm(heading)
        heading = _rescaled(heading, scale, scale_new)
        found = _oriented(balance, q_new, omega_new, heading, scale_new, span)
        if found is None:
            raise FrequencyError(f"{balance.system.source}: the curve cannot continue at f = {_hz(omega_new)!r} Hz: "
                                 "the Jacobian of the augmented system is singular there (a branch point)")
        tangent_new, sign, chord_new = found
        if not cornered and sign != orientation and tangent_new[-1] * heading[-1] < 0:
            # the side of the heading and the determinant's orientation disagree, and the side would turn the curve
            # back in omega: a kink where the tangent turned by more than a right angle (a fold passes both)
            tangent_new, sign = -tangent_new, -sign
        if not cornered and (omega_new - omega) * heading[-1] < 0 and tangent_new[-1] * heading[-1] > 0:
            # back in omega though both tangents point ahead (no fold between): the corrector landed on another
            # part of the curve (past a resonance the predictor overshot: a linear oscillator from 0.17 Hz, just
            # above its 0.159 Hz, went from q = -1.8e-12 at 0.199 Hz to +3.6e-12 at 0.135 Hz): a shorter step
            step *= 0.5
            if step < MIN_STEP:
                raise FrequencyError(f"{balance.system.source}: the curve cannot continue past f = {_hz(omega)!r} "
                                     f"Hz ({_where(balance, q, omega, node)}): every step lands behind it")
            continue
        if omega_new < omega_min - 1e-9 * span:
            raise FrequencyError(f"{balance.system.source}: the curve turned back below f = {_hz(omega_min)!r} Hz "
                                 f"({_where(balance, q_new, omega_new, node)}): it does not reach "
                                 f"{_hz(omega_max)!r} Hz from there (it folds below the range: a superharmonic "
                                 "resonance's loop, or a curve bent over the start): start the frequencies lower")
        if not cornered and step > CORNER * max_step and \
                tangent_new @ _rescaled(tangent, scale, scale_new) < TURN:
            step *= 0.5  # the tangent turned too far in one step (a kink, a tight fold): a shorter step shows it
            continue
        orientation = sign
        if omega_new >= omega_max:
            q_end = _fixed_frequency(balance, q, q_new, omega, omega_new, omega_max)
            if q_end is not None:
                _isolated(balance, q_end, omega_max)
                points.append((omega_max, q_end, False))
                if progress is not None:
                    progress.update(1)
                return points
            step *= 0.5
            continue
        if tangent_new[-1] * _rescaled(tangent, scale, scale_new)[-1] < 0:
            fold = None if cornered else _locate_fold(balance, q, omega, tangent, scale, omega_min, span, step)
            if fold is not None:
                points.append((fold[1], fold[0], True))
            else:  # a corner: the fold is the point the curve turns at
                points[-1] = (points[-1][0], points[-1][1], True)
        _isolated(balance, q_new, omega_new)
        points.append((omega_new, q_new, False))
        if progress is not None:
            progress.update(1)
        again = trail.add(omega_new, q_new, scale_new, omega_min, span, step)
        if again is not None:
            raise FrequencyError(f"{balance.system.source}: the curve closed on itself: at f = {_hz(omega_new)!r} "
                                 f"Hz ({_where(balance, q_new, omega_new, node)}) it came back, going the same way, "
                                 f"to the stretch it took at f = {_hz(again)!r} Hz, and goes round a loop from "
                                 f"there without reaching f = {_hz(omega_max)!r} Hz (the way in, a corner or a "
                                 "branch point, not found again)")
        tangent, scale, q, omega, chord = tangent_new, scale_new, q_new, omega_new, chord_new
        factor = min(2.0, max(0.5, TARGET_ITERATIONS / max(iterations, 1)))
        step = min(max_step, max(MIN_STEP, step * factor))


class _Trail:
    """The points a curve took (every one, the located folds left out), to see it come back on itself: a curve
    that passes again along a stretch it took, the same way, goes round a loop."""

    def __init__(self, omega, q):
        self.count = 1
        # (q, omega) of every point, grown by doubling: the stretches near a point are looked at in one pass
        self.points = np.empty((64, np.size(q) + 1))
        self.points[0] = np.append(q, omega)
        self.sizes = np.empty(64)  # |q| of each point: a stretch too small to reach the point is not looked at
        self.sizes[0] = float(np.linalg.norm(q))
        # of each stretch (i to i + 1), scaled when it was taken: at least as long in any later scale
        self.lengths = np.empty(64)
        self.arcs = np.zeros(64)  # the arc length to each point, of those lengths
        self.hits = 0

    def add(self, omega, q, scale, omega_min, span, step) -> Optional[float]:
        """Add the point; the frequency of the stretch it came back to (the second point in a row on an earlier
        stretch, going the same way), else None. Work: a vectorised pass over the points, then over the
        stretches whose frequencies are within their reach."""
        if self.count == self.lengths.size:
            self.points = np.resize(self.points, (2 * self.lengths.size, self.points.shape[1]))
            self.lengths, self.arcs, self.sizes = (np.resize(a, 2 * a.size) for a in
                                                   (self.lengths, self.arcs, self.sizes))
        last = self.count - 1
        self.points[self.count] = np.append(q, omega)
        self.sizes[self.count] = float(np.linalg.norm(q))
        scaled = self._scaled(slice(last, self.count + 1), scale, omega_min, span)
        self.lengths[last] = float(np.linalg.norm(scaled[1] - scaled[0]))
        self.arcs[self.count] = self.arcs[last] + self.lengths[last]
        self.count += 1
        hit = self._on_earlier(scale, omega_min, span, step)
        self.hits = self.hits + 1 if hit is not None else 0
        return hit if self.hits >= 2 else None

    def _scaled(self, which, scale, omega_min, span) -> np.ndarray:
        out = self.points[which].copy()
        out[..., :-1] /= scale
        out[..., -1] = (out[..., -1] - omega_min) / span
        return out

    def _on_earlier(self, scale, omega_min, span, step) -> Optional[float]:
        count = self.count - LOOP_GAP  # stretches i -> i + 1 for i + 1 < count
        if count < 2:
            return None
        end, here = self._scaled(slice(self.count - 2, self.count), scale, omega_min, span)
        came = here - end
        moved = float(np.linalg.norm(came))
        if moved == 0.0:
            return None
        omegas = (self.points[:count, -1] - omega_min) / span
        low, high = np.minimum(omegas[:-1], omegas[1:]), np.maximum(omegas[:-1], omegas[1:])
        reach = LOOP_NEAR * np.maximum(step, self.lengths[:count - 1])  # farther in omega alone: not near
        # nor where the point is farther out than either end, past the reach (the norm along a stretch is at
        # most its ends': a curve that climbs a resonance is past all its earlier stretches, looked at no more)
        sizes = self.sizes[:count] / scale
        beyond = self.sizes[self.count - 1] / scale - np.maximum(sizes[:-1], sizes[1:])
        near = np.flatnonzero((low - reach <= here[-1]) & (here[-1] <= high + reach) & (beyond <= reach))
        if near.size == 0:
            return None
        a = self._scaled(near, scale, omega_min, span)
        stretch = self._scaled(near + 1, scale, omega_min, span) - a
        length = np.linalg.norm(stretch, axis=1)
        size = np.maximum(length, step)
        along = np.clip(np.einsum("ij,ij->i", here - a, stretch) / np.maximum(length, 1e-300) ** 2, 0.0, 1.0)
        distance = np.linalg.norm(here - a - along[:, None] * stretch, axis=1)
        # the same way, within an eighth of it, and come back to it: round a way LOOP_ROUND times as long as the
        # stretch, not just past its end (steps shrinking towards a corner put a point within an eighth of a
        # stretch four points back)
        found = (length > 0.0) & (stretch @ came >= LOOP_ALONG * moved * length) & (distance <= LOOP_NEAR * size) \
            & (self.arcs[self.count - 1] - self.arcs[near + 1] >= LOOP_ROUND * size)
        return float(self.points[near[np.argmax(found)], -1]) if np.any(found) else None


def _isolated(balance, q, omega) -> None:
    """FrequencyError where the point (q, omega) is one of a family of periodic states (``balance.family``, where
    it has one: a free offset the unknowns do not fix), which no continuation follows: said, not continued."""
    family = getattr(balance, "family", None)
    why = None if family is None else family(q, omega)
    if why is not None:
        raise FrequencyError(f"{balance.system.source}: at f = {_hz(omega)!r} Hz {why}: the curve is not a curve "
                             "there; use --method time (the state the motion reaches from the scene's)")


def _size(balance, q, omega) -> float:
    """The size of the unknowns q that scales the arc length: their norm, or the balance's ``size_of`` where
    their norm is not the motion's (on a belt the drag's offset of the mean can dwarf the oscillation: a curve
    scaled by it stepped from 0.05 Hz over the resonance to 0.31 Hz in one step)."""
    size_of = getattr(balance, "size_of", None)
    return float(np.linalg.norm(q)) if size_of is None else float(size_of(q, omega))


def _where(balance, q, omega, node) -> str:
    """Where a curve stopped, as its CSV says it: the first harmonic's amplitude at the curve's node."""
    index = balance.system.load_node if node is None else node
    return (f"first-harmonic amplitude {balance.amplitude_at(q, omega, index)!r} m at node "
            f"{getattr(balance, 'names', balance.system.nodes)[index]}")


def across(balance, finer, lift, q, omega, omega_min: float, omega_max: float) -> Optional[tuple]:
    """The point of ``finer``'s curve across the point (q, omega) of ``balance``'s: Newton's method on
    [R_finer(y); t . (y - y0)] = 0 from y0, the point lifted into ``finer``'s unknowns (``lift``), t
    ``balance``'s unit tangent there lifted alike: the other curve's point on the normal through it, well
    posed at a fold (where the point at the same frequency may not exist). (q_finer, omega) or None (no tangent,
    or no convergence in CORRECTOR_ITERATIONS)."""
    span = omega_max - omega_min
    scale = max(np.linalg.norm(q), 1e-300)
    tangent = _tangent(balance, q, omega, None, scale, span)
    if tangent is None:
        return None
    start = _scaled(lift(q), omega, scale, omega_min, span)
    t = np.concatenate((lift(tangent[:-1]), tangent[-1:]))
    t /= np.linalg.norm(t)
    y = start.copy()
    for _ in range(CORRECTOR_ITERATIONS):
        q_y, omega_y = _unscaled(y, scale, omega_min, span)
        residual, matrix = _augmented(finer, q_y, omega_y, scale, span)
        delta = solve_linear(np.vstack((matrix, t)), -np.concatenate((residual, [t @ (y - start)])))
        if delta is None or not np.all(np.isfinite(delta)):
            return None
        y = y + delta
        if _converged(finer, delta, residual, omega_y):
            return _unscaled(y, scale, omega_min, span)
    return None


def bridge(balance, start: tuple, end: tuple, heading: np.ndarray, omega_min: float, omega_max: float):
    """The points of ``balance``'s curve from ``start`` to ``end`` (each (omega, q)), both on it, through what
    lies between (a fold that a finer resolution moved past the coarser curve's points, which then exist at no
    frequency of theirs): arc-length steps of an eighth of the chord from ``start`` along its tangent on the side
    of ``heading`` (scaled as the chord: q over the larger |q| of the two, omega over the range), halved where
    the corrector fails and doubled again after each point taken (up to an eighth), a fold located where the
    tangent's frequency component turns (:func:`_locate_fold`), until the point is within a step of ``end``,
    the stretch to ``end`` checked alike (a review's find: an end just past the fold left it unmarked). A fold
    pair within one step is not seen (as in the continuation).
    ``[(omega, q, is_fold)]`` without the ends, or None (a step below 1e-6 of the chord, or more than
    BRIDGE_STEPS steps, or a point farther from ``end`` than twice the chord: not the way there)."""
    span = omega_max - omega_min
    (omega, q), (omega_end, q_end) = start, end
    scale = max(float(np.linalg.norm(q)), float(np.linalg.norm(q_end)), 1e-300)
    target = _scaled(q_end, omega_end, scale, omega_min, span)
    chord = float(np.linalg.norm(target - _scaled(q, omega, scale, omega_min, span)))
    if chord == 0.0:
        return []
    tangent = _tangent(balance, q, omega, heading, scale, span)
    if tangent is None:
        return None
    step = chord / 8.0
    points = []
    for _ in range(BRIDGE_STEPS):
        y = _scaled(q, omega, scale, omega_min, span)
        remaining = float(np.linalg.norm(target - y))
        if remaining <= step:  # the last stretch, to ``end`` itself: a fold there too is located
            arrived = _tangent(balance, q_end, omega_end, tangent, scale, span)
            if arrived is None or not _folded(balance, q, omega, tangent, arrived, scale, omega_min, span,
                                              remaining, points):
                return None
            return points
        new = _correct(balance, y + step * tangent, tangent, scale, omega_min, span, step)
        if new is None:
            step *= 0.5
            if step < 1e-6 * chord:
                return None
            continue
        q_new, omega_new, _ = new
        if np.linalg.norm(target - _scaled(q_new, omega_new, scale, omega_min, span)) > 2.0 * chord:
            return None
        turned = _tangent(balance, q_new, omega_new, tangent, scale, span)
        if turned is None or not _folded(balance, q, omega, tangent, turned, scale, omega_min, span, step, points):
            return None
        points.append((omega_new, q_new, False))
        q, omega, tangent = q_new, omega_new, turned
        # the step grows back after a short one, up to an eighth of the chord (a kink halved it to a 128th, and
        # 64 steps went half way: the delay oscillator at 0.3 N from 0.05 to 1 Hz, refused near 0.1063 Hz)
        step = min(chord / 8.0, 2.0 * step)
    return None


def _folded(balance, q, omega, tangent, turned, scale, omega_min, span, step, points) -> bool:
    """For :func:`bridge`: where the tangent's frequency component turns from ``tangent`` (at (q, omega)) to
    ``turned`` (``step`` further), the fold between, located and appended to ``points``; False where it is not
    found."""
    if turned[-1] * tangent[-1] >= 0:
        return True
    fold = _locate_fold(balance, q, omega, tangent, scale, omega_min, span, step)
    if fold is None:
        return False
    points.append((fold[1], fold[0], True))
    return True


def _hz(omega: float) -> float:
    return float(omega) / (2.0 * math.pi)


def _scaled(q, omega, scale, omega_min, span) -> np.ndarray:
    return np.concatenate((q / scale, [(omega - omega_min) / span]))


def _unscaled(y, scale, omega_min, span) -> tuple:
    return y[:-1] * scale, omega_min + y[-1] * span


def _rescaled(tangent, old, new) -> np.ndarray:
    out = tangent.copy()
    out[:-1] *= old / new
    return out / np.linalg.norm(out)


def _augmented(balance, q, omega, scale, span):
    residual, jacobian, by_omega, _ = balance.evaluate(q, omega)
    return residual, np.hstack((jacobian * scale, by_omega[:, None] * span))


def _residual(balance, q, omega) -> np.ndarray:
    """R alone at (q, omega): one run of the motion for shooting (``residual_at``), where :func:`_augmented`
    costs a Jacobian (2 n + 2 runs); the harmonic balance's from its evaluation."""
    if hasattr(balance, "residual_at"):
        return balance.residual_at(q, omega)
    return balance.evaluate(q, omega)[0]


def _tangent(balance, q, omega, previous, scale, span):
    """The unit tangent at (q, omega), on the side of ``previous`` (t . previous > 0), else ahead in omega."""
    found = _oriented(balance, q, omega, previous, scale, span)
    return None if found is None else found[0]


def _oriented(balance, q, omega, previous, scale, span):
    """(t, sign of det [dR/dy; t], the scaled Jacobian) at (q, omega), t as :func:`_tangent`; or None."""
    _, matrix = _augmented(balance, q, omega, scale, span)
    row = previous if previous is not None else np.eye(matrix.shape[1])[-1]
    t = solve_linear(np.vstack((matrix, row)), np.eye(matrix.shape[1])[-1])
    if t is None:
        return None
    t = t / np.linalg.norm(t)
    sign, _ = np.linalg.slogdet(np.vstack((matrix, t)))
    return t, float(sign), matrix


def _correct(balance, predicted, tangent, scale, omega_min, span, step, chord=None):
    """Newton on [R; t . (y - y_pred)] from the prediction ``step`` along the tangent: (q, omega, iterations),
    or None (no convergence, or a corrector that went further than DRIFT steps from the prediction). Where the
    balance's Jacobian is costly (``costly_jacobian``: shooting, a run of the motion per unknown) and ``chord``
    (the scaled Jacobian at the last point) is given, the chord method first (:func:`_chord`)."""
    if chord is not None and getattr(balance, "costly_jacobian", False):
        new = _chord(balance, predicted, tangent, scale, omega_min, span, step, chord)
        if new is not None:
            return new
    y = predicted.copy()
    for iteration in range(1, CORRECTOR_ITERATIONS + 1):
        q, omega = _unscaled(y, scale, omega_min, span)
        residual, matrix = _augmented(balance, q, omega, scale, span)
        system = np.vstack((matrix, tangent))
        right = -np.concatenate((residual, [tangent @ (y - predicted)]))
        delta = solve_linear(system, right)
        if delta is None:
            return None
        y = y + delta
        if np.linalg.norm(y - predicted) > DRIFT * max(step, 1e-300) or _unscaled(y, scale, omega_min, span)[1] <= 0:
            return None  # gone far from the prediction: another part of the curve, or none; a shorter step
        if _converged(balance, delta, residual, omega):
            q, omega = _unscaled(y, scale, omega_min, span)
            return q, omega, iteration
    return None


def _converged(balance, delta, residual, omega) -> bool:
    """Whether a corrector's step ``delta`` (scaled) from a point of residual ``residual`` ends it: below
    CONVERGED, or the residual at rounding (1e-12 of the force's scale) and the step below 1e-6."""
    size = float(np.max(np.abs(delta)))
    return size <= CONVERGED or np.max(np.abs(residual)) <= 1e-12 * balance.force_scale(omega) and size <= 1e-6


def _chord(balance, predicted, tangent, scale, omega_min, span, step, chord):
    """The corrector of :func:`_correct` with the Jacobian of the last point kept (the chord method: one run of
    the motion an iteration, not one per unknown), made true along each step by Broyden's rank-one update (see
    :func:`_at_frequency`), at most CHORD_ITERATIONS iterations, the same convergence and drift; its iterations
    counted as Newton's would be for the step's size (TARGET_ITERATIONS for CHORD_TARGET)."""
    system = np.vstack((chord, tangent))
    y = predicted.copy()
    previous = math.inf
    last = delta = None
    for iteration in range(1, CHORD_ITERATIONS + 1):
        q, omega = _unscaled(y, scale, omega_min, span)
        residual = balance.residual_at(q, omega)
        if not np.all(np.isfinite(residual)):
            return None
        if last is not None:  # Broyden's update of the kept rows: true along the last step
            system[:-1] += np.outer(residual - last - system[:-1] @ delta, delta) / (delta @ delta)
        last = residual
        delta = solve_linear(system, -np.concatenate((residual, [tangent @ (y - predicted)])))
        if delta is None:
            return None
        y = y + delta
        if np.linalg.norm(y - predicted) > DRIFT * max(step, 1e-300) or _unscaled(y, scale, omega_min, span)[1] <= 0:
            return None
        size = float(np.max(np.abs(delta)))
        # converged as Newton's, and contracting by half at least (the chord converges linearly: its error is
        # below its last step then)
        if _converged(balance, delta, residual, omega) and size <= 0.5 * previous:
            q, omega = _unscaled(y, scale, omega_min, span)
            return q, omega, max(1, math.ceil(iteration * TARGET_ITERATIONS / CHORD_TARGET))
        previous = size
    return None


def _damped(balance, q, omega, tangent, scale, omega_min, span, step):
    """The point ahead of (q, omega) past a kink of the curve (a node that starts or stops slipping): there the
    Jacobians on the two sides differ and Newton on the arc-length hyperplane can cycle between them. Tried in
    turn, each a Newton's method whose steps are halved while max |R| grows (at most HALVINGS times, at most
    DAMPED_ITERATIONS steps): with omega fixed at the prediction's (the curve parametrised by the frequency,
    away from a fold: where a slip's onset flips the slope of the curve, the step ahead in omega is still
    there); with the tangent's largest scaled unknown fixed at the prediction's; on the step's hyperplane. An
    unknown is fixed only if its share of the tangent is at least FIXED_SHARE (so it moves ahead). The point
    must lie within DAMPED_REACH steps of the last point (on the hyperplane: within 60 degrees of the tangent).
    (q, omega, iterations) or None."""
    start = _scaled(q, omega, scale, omega_min, span)
    predicted = start + step * tangent
    rows = []
    for k in (tangent.size - 1, int(np.argmax(np.abs(tangent)))):
        if abs(tangent[k]) >= FIXED_SHARE and not any(row[k] == 1.0 for row in rows):
            rows.append(np.eye(tangent.size)[k])
    for row in rows + [tangent]:
        new = _damped_newton(balance, start, predicted, row, tangent, scale, omega_min, span, step)
        if new is not None:
            return new
    return None


def _damped_newton(balance, start, predicted, row, tangent, scale, omega_min, span, step):
    """Newton on [R(y); row . (y - predicted)] = 0 from ``predicted``, steps halved while max |R| grows (see
    :func:`_damped`): (q, omega, iterations) or None."""
    y = predicted.copy()
    q_y, omega_y = _unscaled(y, scale, omega_min, span)
    residual, matrix = _augmented(balance, q_y, omega_y, scale, span)
    for iteration in range(1, DAMPED_ITERATIONS + 1):
        if not np.all(np.isfinite(residual)):
            return None
        delta = solve_linear(np.vstack((matrix, row)), -np.concatenate((residual, [row @ (y - predicted)])))
        if delta is None:
            return None
        # each trial by its residual alone, the Jacobian at the step taken: a Jacobian at every trial cost a
        # network's shooting up to 11 000 runs of its motion (220 s) for one call (networks/chain-dynamic at 5 N
        # near 0.1 Hz, where the curve has a kink every 4e-5 Hz: a helper's measurement)
        for _ in range(HALVINGS + 1):
            moved = y + delta
            q_y, omega_y = _unscaled(moved, scale, omega_min, span)
            if omega_y <= 0:
                return None
            residual_moved = _residual(balance, q_y, omega_y)
            if np.max(np.abs(residual_moved)) <= np.max(np.abs(residual)):
                break
            delta = 0.5 * delta
        else:
            return None  # no descent even at 1 / 2^HALVINGS of the step: a stall (the other ways are tried next)
        y, residual = moved, residual_moved
        matrix = _augmented(balance, q_y, omega_y, scale, span)[1]
        # within reach, and ahead: the fixed unknown is (the prediction's); on the hyperplane, the chord within 60
        # degrees of the tangent (the hyperplane alone would take a point far to the side, even behind in omega)
        chord = y - start
        length = np.linalg.norm(chord)
        if length > DAMPED_REACH * step or (row is tangent and chord @ tangent < 0.5 * length):
            return None
        if _converged(balance, delta, residual, omega_y):
            return q_y, omega_y, iteration
    return None


def _around_corner(balance, q, omega, tangent, scale, omega_min, span, step, behind=None, deflate=True):
    """The point at arc length ``step`` from (q, omega) on the sphere |y - y_0| = step: the way on past a corner
    of the curve (the sampled forces make the curve piecewise smooth; where a fold falls on a kink, no
    hyperplane ahead meets the curve). Newton on the sphere from the prediction along ``tangent``, along it with
    its frequency component turned back, and against it: at a corner the tangent at the last point can be the
    far side's, pointing where the curve does not go (the delay oscillator at 0.1 N: the first branch starts to
    slip at 0.3705 Hz, the curve turns back by 131 degrees, and its way on is along minus that tangent). Not the
    way back: ``behind`` (unit, scaled) points to the previous point; the sphere's point that way is solved for
    too, and a point within a quarter of the step of it is refused (where it is not found, a chord within 45
    degrees of ``behind``). Where every guess lands on the way back and ``deflate``, the way on is sought from
    ``behind``, against the tangent and along it, with that point deflated (Newton's step scaled so that it
    is pushed away from it, :func:`_deflated`): at a corner as sharp as the delay oscillator's at 0.5 N (the mass
    starts to stick at 0.1190 Hz, the curve turns back by 153 degrees) the far side's point is nearer to the way
    back than to any of the guesses along the tangent. (q, omega, iterations) or None."""
    start = _scaled(q, omega, scale, omega_min, span)
    behind = -tangent if behind is None else behind

    def on_sphere(direction, deflated=None):
        y = start + step * direction
        for iteration in range(1, (CORRECTOR_ITERATIONS if deflated is None else DEFLATED_ITERATIONS) + 1):
            q_y, omega_y = _unscaled(y, scale, omega_min, span)
            if omega_y <= 0:
                return None
            residual, matrix = _augmented(balance, q_y, omega_y, scale, span)
            chord = y - start
            delta = solve_linear(np.vstack((matrix, 2.0 * chord)),
                                 -np.concatenate((residual, [chord @ chord - step * step])))
            if delta is None or not np.all(np.isfinite(delta)):
                return None
            if deflated is not None:
                delta = _deflated(delta, y, deflated, step)
                if delta is None:
                    return None
            y = y + delta
            if np.max(np.abs(delta)) <= CONVERGED:
                return y, iteration
        return None

    back = None
    for guess in (tangent, _turned(tangent, 0.5), _turned(tangent, 1.0), -tangent):
        found = on_sphere(guess)
        if found is None:
            continue
        y, iteration = found
        if back is None:
            back = on_sphere(behind) or (None,)
        if back[0] is not None:
            ahead = np.linalg.norm(y - back[0]) > 0.25 * step
        else:
            ahead = (y - start) @ behind < 0.7 * step
        if ahead:
            q_y, omega_y = _unscaled(y, scale, omega_min, span)
            return q_y, omega_y, iteration
    if not deflate:
        return None
    if back is None:
        back = on_sphere(behind) or (None,)
    if back[0] is None:
        return None
    for guess in (behind, -tangent, tangent):
        found = on_sphere(guess, back[0])
        if found is not None and np.linalg.norm(found[0] - back[0]) > 0.25 * step:
            q_y, omega_y = _unscaled(found[0], scale, omega_min, span)
            return q_y, omega_y, found[1]
    return None


def _deflated(delta, y, root, size) -> Optional[np.ndarray]:
    """Newton's step ``delta`` at ``y`` for F turned into the deflated problem's, M(y) F(y) = 0 with M = 1 /
    |y - root|^2 + 1 / size^2 (Farrell, Birkisson & Funke 2015): M grows without bound at ``root`` and tends to
    1 / size^2 far from it (other roots are kept). By Sherman-Morrison the deflated step is the plain one over
    1 - grad M . delta / M; None at ``root`` itself (M undefined) or where that divisor vanishes. Very near
    ``root`` the deflated step is about as small as y - root, so an iteration started there stops at once beside
    it: the caller refuses a point within a quarter of the step of the way back whichever way it was found."""
    away = y - root
    distance = float(away @ away)
    if distance <= 0.0:
        return None
    divisor = 1.0 + 2.0 * float(away @ delta) / distance**2 / (1.0 / distance + 1.0 / (size * size))
    if divisor == 0.0 or not math.isfinite(divisor):
        return None
    return delta / divisor


def _behind(points, q, omega, scale, omega_min, span) -> Optional[np.ndarray]:
    """The unit chord (scaled) from (q, omega) to the point before it on the curve, or None (none before)."""
    if len(points) < 2:
        return None
    omega_0, q_0, _ = points[-2]
    chord = _scaled(q_0, omega_0, scale, omega_min, span) - _scaled(q, omega, scale, omega_min, span)
    size = np.linalg.norm(chord)
    return chord / size if size > 0 else None


def _turned(tangent, amount):
    """The tangent with its frequency component reversed in part (a guess past a fold's corner)."""
    out = tangent.copy()
    out[-1] *= 1.0 - 2.0 * amount
    norm = np.linalg.norm(out)
    return out / norm if norm > 0 else tangent


def _fixed_frequency(balance, q0, q1, omega0, omega1, omega_end):
    """The point at omega_end between two points (linear interpolation, then Newton at omega fixed)."""
    weight = (omega_end - omega0) / (omega1 - omega0) if omega1 != omega0 else 1.0
    guess = q0 + weight * (q1 - q0)
    return balance._newton(omega_end, guess)


def _locate_fold(balance, q, omega, tangent, scale, omega_min, span, step):
    """The fold between the point (q, omega) and the one ``step`` further along ``tangent``: (q, omega) where
    the omega-component of the tangent is 0 (secant on it, bracketed), or None if the correctors fail."""
    start = _scaled(q, omega, scale, omega_min, span)

    def at(s):
        point = _correct(balance, start + s * tangent, tangent, scale, omega_min, span, max(s, 1e-3 * step))
        if point is None:
            return None
        t = _tangent(balance, point[0], point[1], tangent, scale, span)
        return None if t is None else (point[0], point[1], t[-1])

    low, high = 0.0, step
    f_low = tangent[-1]
    end = at(high)
    if end is None:
        return None
    f_high = end[2]
    best = end
    for iteration in range(FOLD_ITERATIONS):
        if high - low <= 1e-9 * step:
            break
        s = high - f_high * (high - low) / (f_high - f_low) if f_high != f_low else 0.5 * (low + high)
        if not low < s < high or iteration % 3 == 2:  # a bisection now and then: the bracket shrinks
            s = 0.5 * (low + high)
        point = at(s)
        if point is None:
            return None
        best = point
        if abs(point[2]) <= 1e-12:
            break
        if point[2] * f_low > 0:
            low, f_low = s, point[2]
        else:
            high, f_high = s, point[2]
    return best[0], best[1]


# ----------------------------------------------------------------- a curve that is a function of omega

def march_curve(balance, omega_min: float, omega_max: float, count: int, progress=None,
                node: Optional[int] = None) -> list:
    """``[(omega, q_free, False)]`` as :func:`continue_curve`, for a shooting whose periodic states are a function
    of the frequency (``balance.monotone``: a scene monotone in the sense of ``floquet.monotone`` has no fold):
    stepped in omega, each point by Newton's method at its frequency from the last two points' secant (the first
    step: the tangent). The steps are measured on the curve as drawn, the first harmonics of every node
    (``balance.coefficients``) scaled by their largest norm met, and omega over the range: at most
    ``ARC_ESTIMATE / max(count - 1, FEWEST_STEPS)`` of that arc, adapted to the corrector's iterations; a point
    whose step went more than twice as far as asked, or turned the drawn curve by more than 60 degrees, is taken
    again at half the step, down to CORNER of the largest (a kink of the curve is located to that), and so is a
    point that missed its prediction by more than MISSED of the step on the drawn curve (about half its curvature
    times the step squared: the wiggles of a friction damper's curve at low frequency, where a stick-slip pattern
    changes, were stepped over) or one in motion after a point at rest (s = 0: the onset of slip, a kink the
    drawn curve hardly shows). Why not the
    arc length of the unknowns: on a chain on a support at 5 N near 0.1 Hz the nodes next to the load start and
    stop micro-slipping every 4e-5 Hz or so; the velocities at t = 0 jump at each (their secant turned by 60 to
    150 degrees from one point to the next) while the harmonics change by 1e-5 relative, and the arc length of
    the unknowns, with the hyperplane's Newton cycling between the Jacobians on a kink's two sides, fell to 5e-4
    of its bound (hours from 0.1 to 3 Hz). Where the corrector does not converge even at MIN_STEP, the whole
    curve is :func:`continue_curve`'s (from a point of the march, its arc length turned back at such a kink:
    one node on a spring and a slider just below Den Hartog's bound, at 0.1559 Hz)."""
    span = omega_max - omega_min
    q = balance.solve_at(omega_min)
    _isolated(balance, q, omega_min)
    points = [(omega_min, q, False)]
    if span <= 0:
        return points
    drawn = _drawn(balance, q, omega_min)
    floor = balance.length_scale(omega_min) if hasattr(balance, "length_scale") else 0.0
    scale = max(float(np.linalg.norm(drawn)), floor, 1e-300)
    max_step = ARC_ESTIMATE / max(count - 1, FEWEST_STEPS)
    step = max_step
    omega = omega_min
    residual, chord, by_omega, _ = balance.evaluate(q, omega)
    slope = solve_linear(chord, -by_omega)  # dq / d omega at the start; then the secant's
    if slope is None or not np.all(np.isfinite(residual)):
        return continue_curve(balance, omega_min, omega_max, count, progress, node, start=q)
    ahead = 0.0  # the drawn curve's unit secant's omega component (0: not known yet, a first step of step * span)
    heading = rate = None  # the drawn curve's unit secant (scaled) and its d drawn / d omega
    beyond = None  # (omega, q) of the point just taken again at a shorter step: the next guesses interpolate to it
    while omega < omega_max:
        if len(points) > MAX_POINTS:
            raise FrequencyError(f"{balance.system.source}: the curve did not reach f = {_hz(omega_max)!r} Hz "
                                 f"within {MAX_POINTS} points (at f = {_hz(omega)!r} Hz, "
                                 f"{_where(balance, q, omega, node)})")
        omega_new = min(omega + step * (ahead if ahead > 0.0 else 1.0) * span, omega_max)
        guess = q + slope * (omega_new - omega)
        if beyond is not None and omega < omega_new < beyond[0]:  # within a point taken again: between the two
            guess = q + (beyond[1] - q) * ((omega_new - omega) / (beyond[0] - omega))
        found = _at_frequency(balance, guess, omega_new, scale, chord)
        if found is None:
            step *= 0.5
            if step < MIN_STEP:  # a kink Newton's method at a fixed frequency does not pass: the arc length's
                return continue_curve(balance, omega_min, omega_max, count, progress, node, start=points[0][1])
            continue
        q_new, iterations, chord_new = found
        drawn_new = _drawn(balance, q_new, omega_new)
        moved = np.concatenate(((drawn_new - drawn) / scale, [(omega_new - omega) / span]))
        length = float(np.linalg.norm(moved))
        secant = moved / max(length, 1e-300)
        # the prediction's miss on the drawn curve, along its last secant (about half its curvature times the step
        # squared); the first step's from the tangent's guess run (not a periodic state, but the tangent's)
        predicted = _drawn(balance, guess, omega_new) if rate is None else drawn + rate * (omega_new - omega)
        missed = float(np.linalg.norm(drawn_new - predicted)) / scale
        # from rest (every node stuck all period: s = 0) into motion, the onset of slip is a kink the drawn curve
        # hardly shows (the base-excited friction element: 2.4 % of its amplitude over 0.03 Hz past it, where
        # one step from rest landed) and the curve's user reads: located to CORNER of the largest step
        leaves_rest = not np.any(q) and np.any(q_new)
        if step > CORNER * max_step and (length > 2.0 * step or missed > max(MISSED * step, RESOLUTION) or
                                         leaves_rest or
                                         (heading is not None and secant @ heading < TURN)):
            step *= 0.5  # steeper than predicted, bent, a kink of the drawn curve: a shorter step shows it
            beyond = (omega_new, q_new)
            continue
        beyond = None
        _isolated(balance, q_new, omega_new)
        points.append((omega_new, q_new, False))
        if progress is not None:
            progress.update(1)
        scale_new = max(scale, float(np.linalg.norm(drawn_new)))
        heading = _rescaled(secant, scale, scale_new)
        ahead = float(heading[-1])
        slope = (q_new - q) / (omega_new - omega)
        rate = (drawn_new - drawn) / (omega_new - omega)
        q, omega, drawn, scale, chord = q_new, omega_new, drawn_new, scale_new, chord_new
        # longer where the corrector converged within twice its target; never shorter for its iterations alone:
        # they do not fall with the step where every step crosses kinks (their count shrank the step to 1 / 250
        # of its bound on the chain, 2205 points from 0.1 to 0.5 Hz); the drawn curve's miss and turn above
        # size the step
        step = min(max_step, step * (2.0 if iterations <= TARGET_ITERATIONS // 2 else
                                     1.5 if iterations <= 2 * TARGET_ITERATIONS else 1.0))
    return points


def _drawn(balance, q, omega) -> np.ndarray:
    """The curve as drawn at a point: the first harmonic (a_1, b_1) of every node."""
    return np.asarray(balance.coefficients(q, omega))[:, 1:3].ravel()


def _unit(slope) -> np.ndarray:
    """The unit vector along (slope, 1) (a scaled dq / d omega: ahead in omega)."""
    out = np.concatenate((slope, [1.0]))
    return out / np.linalg.norm(out)


def _at_frequency(balance, guess, omega, scale, chord):
    """The point at ``omega`` from ``guess``: where the balance's Jacobian is costly (``costly_jacobian``), the
    chord method first with the last point's Jacobian ``chord``, made true along each step by Broyden's rank-one
    update J += (dR - J d) d^T / d^T d (at most CHORD_ITERATIONS, converged and contracting by half); then
    Newton's method, each step halved while max |R| grows (at most HALVINGS times, at most CORRECTOR_ITERATIONS
    steps). ``(q, iterations as Newton's, the Jacobian to keep)`` or None. Broyden's update, measured on chains
    of 6 and 8 nodes (benchmarks/network_shooting.py): the kept Jacobian alone converged at 17 of 63 points
    and the march took 6263 and 9565 runs of the motion; updated, at 52 of 62 and 3251 and 5032 runs."""
    if getattr(balance, "costly_jacobian", False):
        q = np.array(guess, dtype=float)
        previous = math.inf
        jacobian = np.array(chord, dtype=float)
        last = delta = None
        for iteration in range(1, CHORD_ITERATIONS + 1):
            residual = _residual(balance, q, omega)
            if not np.all(np.isfinite(residual)):
                break
            if last is not None:  # Broyden's update: the kept Jacobian made true along the last step
                jacobian = jacobian + np.outer(residual - last - jacobian @ delta, delta) / (delta @ delta)
            delta = solve_linear(jacobian, -residual)
            if delta is None:
                break
            q = q + delta
            last = residual
            size = float(np.max(np.abs(delta))) / scale
            if _converged(balance, np.array([size]), residual, omega) and size <= 0.5 * previous:
                return q, max(1, math.ceil(iteration * TARGET_ITERATIONS / CHORD_TARGET)), chord
            previous = size
    q = np.array(guess, dtype=float)
    residual, jacobian, _, _ = balance.evaluate(q, omega)
    for iteration in range(1, CORRECTOR_ITERATIONS + 1):
        if not (np.all(np.isfinite(residual)) and np.all(np.isfinite(jacobian))):
            return None
        delta = solve_linear(jacobian, -residual)
        if delta is None:
            return None
        for _ in range(HALVINGS + 1):
            moved = q + delta
            residual_moved = _residual(balance, moved, omega)
            if np.max(np.abs(residual_moved)) <= np.max(np.abs(residual)):
                break
            delta = 0.5 * delta
        else:
            return None
        q = moved
        if _converged(balance, delta / scale, residual, omega):
            return q, iteration, jacobian
        residual, jacobian, _, _ = balance.evaluate(q, omega)
    return None
