"""What moves, and how old the CAV's message is (beyond the paper: CBM over time, step 8).

A CAV's detections reach the ego some time d after capture: a parked car lies where the CAV saw
it, a moving one has moved on by v d, and a fit that pairs it pulls the pose that way. The ego's
own boxes, frame after frame, tell which objects move and how fast (``EgoTracks``):

1. the ego's motion between two frames is the robust rigid fit (``cbm.estimate.robust_fit``) of
   its boxes to the same boxes a frame before, paired by the gated assignment under the motion of
   the frame before (most objects stand still: the moving ones are its outliers);
2. a box's velocity is the least-squares slope of its positions over the ``WINDOW`` frames before,
   each carried into the current frame by the ego's motions since (one frame's detection noise
   over one frame period would swamp it; the frame's own would correlate with its residual).

Then a matched pair's residual ``r = p_ego - T p_cav`` is ``v d`` plus noise, so the message's age
is the least-squares slope of the residuals on the velocities (``message_age``). Pooled over
frames by a weighted median (``AgeEstimate``) it is the typical age; a frame's own slope, as sure as
its moving pairs make it, moves it towards the frame's age, which jitters with the network
(``AgeEstimate.of_frame``). The pose is then fitted again (eq. 15) with each ego box moved back by
``v d``: moving objects no longer pull it. (Shifting the pose by as much as a least-squares fit
moves, ``compensated``, is how the age itself is read; as the answer it kept the robust fit's pull
towards whichever group of pairs agreed best before: 0.58 of 1 m / 1° successes against 0.85 on
moving traffic, ``tests/evaluation/test_latency_estimate.py``.)
"""
from __future__ import annotations

import dataclasses
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from . import se2
from .engine.assignment import gated_assignment
from .engine.gaps import pose_gap
from .estimate import robust_fit, weighted_procrustes
from .result import MatchResult

WINDOW = 11
"""Frames whose positions give a box its velocity (1 s at 10 Hz: 0.3 m detection noise leaves
about 0.3 m/s of it)."""
LEAST_SPAN_S = 0.25
"""Seconds a box must have been followed before its velocity counts."""
LINK_GATE = 3.0
"""Metres between one object's boxes of two frames after the ego's motion: 30 m/s at 10 Hz."""
LINK_SIGMA = 0.5
"""Metres: the noise the frame-to-frame assignment's cost assumes."""
SETTLED_M = 0.2
SETTLED_DEG = 0.5
"""The ego's motion fitted within this of the motion its boxes were paired under is kept: pairing
again under so close a motion rarely changes a pair of the 3 m gate. One round instead of two on
most frames; the age's error and the successes on the shipped log and on moving traffic stayed as
with two, and the scenes table within a frame or two (``bench/bench_accuracy.py --scenes``)."""
MOVING = 1.0
"""Metres per second from which an object's motion counts towards the message's age."""
AGE_FRAMES = 30
"""Frames whose age estimates are pooled (3 s at 10 Hz)."""
LEAST_WEIGHT = 200.0
"""Least pooled sum of squared speeds (m^2/s^2) to tell the age: two cars at 10 m/s for a frame."""
MOST_AGE_S = 1.0
"""Seconds: the oldest message the estimate believes (an older one reads as no estimate)."""
AGE_ROUNDS = 1
"""Rounds of the pose and the age fitted in turn (``frame_age``): one told the age as well as two
(median error 31.0 ms on the shipped log's ``latency``, 34-38 ms on moving traffic, against 30.9 and
34-38) at less cost; none told it worse on moving traffic (36-48 ms, and fewer successes)."""
REFIT_FROM = 0.5
"""Metres: where a pair's object moved at least this far while the message travelled, the pose is
fitted again to the pairs moved back (below, such motion is within the detection noise, and the
pose is shifted as much as their least-squares fit moves: ``compensated``)."""
LEAST_PAIRS = 3
"""Fewest pairs of a frame whose residuals count towards the age."""
MOST_ERROR_S = 0.03
"""Seconds: the largest standard error of the pooled age that still tells it."""
LEAST_JITTER_S = 0.005
"""Seconds: the least jitter of the messages' age assumed (a frame's slope never counts alone)."""


@dataclass
class EgoTracks:
    """The ego's boxes over the last ``WINDOW`` frames, carried into its current frame."""

    times: deque = field(default_factory=lambda: deque(maxlen=WINDOW))
    """Seconds of the frames followed, oldest first."""
    positions: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 2)))
    """(frames, N, 2): where each current box was at each of ``times``, in the current ego frame (NaN: not seen)."""
    boxes: np.ndarray | None = None
    """(N, 7) the last frame's boxes."""
    motion: np.ndarray = field(default_factory=lambda: np.eye(3))
    """The ego's last motion, previous frame -> current (the next frame's prediction)."""

    def step(self, ego: np.ndarray, time_s: float) -> np.ndarray:
        """(N, 2) metres per second of each of ``ego`` (boxes of the frame at ``time_s``) in the
        ego's frame, from the frames before it (its own detection's noise would correlate with its
        residuals), NaN where not followed for ``LEAST_SPAN_S``; the frame joins the tracks."""
        ego = np.asarray(ego, dtype=float)
        current = ego[:, :2][None]
        if self.boxes is None or not self.times or time_s <= self.times[-1]:
            self.times.clear()
            self.positions, self.motion = current.copy(), np.eye(3)
        else:
            links, self.motion = ego_motion(self.boxes, ego, self.motion)
            carried = np.full((len(self.positions), len(ego), 2), np.nan)
            linked = links >= 0
            carried[:, linked] = self.positions[:, links[linked]] @ self.motion[:2, :2].T + self.motion[:2, 2]
            self.positions = np.concatenate([carried, current])[-WINDOW:]
        self.boxes = ego
        self.times.append(float(time_s))
        return velocities(np.asarray(self.times)[:-1], self.positions[:-1])


def ego_motion(previous: np.ndarray, current: np.ndarray, predicted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(links, motion): for each current box the previous box of the same object (-1: none), and
    the ego's motion, previous frame -> current (``predicted`` where fewer than 3 boxes pair): the
    boxes paired under ``predicted``, the motion fitted to them, and paired once more under it unless
    it lies within ``SETTLED_M`` / ``SETTLED_DEG`` of ``predicted``."""
    motion = predicted
    links = np.full(len(current), -1)
    for _ in range(2):
        pairs = gated_assignment(current, se2.apply_boxes(motion, previous), LINK_GATE, LINK_SIGMA)
        if len(pairs) < 3:
            return links, predicted
        fitted = robust_fit(previous[pairs[:, 1], :2], current[pairs[:, 0], :2], LINK_SIGMA).transform
        metres, degrees, _ = pose_gap(motion, fitted)
        motion = fitted
        if metres < SETTLED_M and degrees < SETTLED_DEG:
            break
    links[pairs[:, 0]] = pairs[:, 1]
    return links, motion


def velocities(times: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """(N, 2) the least-squares slope of each box's positions (frames, N, 2) over ``times``, NaN
    where they span less than ``LEAST_SPAN_S``."""
    seen = ~np.isnan(positions[..., 0])
    t = np.where(seen, times[:, None], np.nan)
    span = np.nanmax(t, axis=0, initial=-np.inf) - np.nanmin(t, axis=0, initial=np.inf)
    count = seen.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        t_mean = np.nansum(t, axis=0) / count
        dt = np.where(seen, times[:, None] - t_mean, 0.0)
        p_mean = np.nansum(positions, axis=0) / count[:, None]
        dp = np.where(seen[..., None], positions - p_mean, 0.0)
        slope = (dt[..., None] * dp).sum(axis=0) / (dt ** 2).sum(axis=0)[:, None]
    slope[~(span >= LEAST_SPAN_S)] = np.nan
    return slope


def message_age(residuals: np.ndarray, velocity: np.ndarray) -> tuple[float, float, float]:
    """(d, weight, noise): the least-squares age of a frame's message, ``sum v.r / sum |v|^2`` over
    the pairs whose speed is at least ``MOVING``, the weight ``sum |v|^2`` it stands on (0: none),
    and the residuals' variance per axis among the pairs standing still (m^2; NaN with none), so
    that the age's own variance is ``noise / weight``."""
    speed2 = np.einsum("ij,ij->i", velocity, velocity)
    moving = np.isfinite(speed2) & (speed2 >= MOVING ** 2)
    still = np.isfinite(speed2) & ~moving
    noise = float(np.mean(residuals[still] ** 2)) if still.any() else float("nan")
    weight = float(speed2[moving].sum())
    if weight == 0.0:
        return float("nan"), 0.0, noise
    return float(np.einsum("ij,ij->", velocity[moving], residuals[moving]) / weight), weight, noise


@dataclass
class AgeEstimate:
    """A message's age pooled over the last ``AGE_FRAMES`` frames: the weighted median of the
    frames' estimates (a frame whose pairs are wrong cannot drag it), once they weigh enough."""

    found: deque = field(default_factory=lambda: deque(maxlen=AGE_FRAMES))

    def add(self, age: float, weight: float, noise: float = float("nan")) -> None:
        if weight > 0.0 and np.isfinite(age) and np.isfinite(noise):
            self.found.append((age, weight, noise))

    def clear(self) -> None:
        self.found.clear()

    @property
    def seconds(self) -> float | None:
        """The pooled age, None while the frames' weights sum to less than ``LEAST_WEIGHT`` or its
        standard error, ``sqrt(mean noise / sum weight)``, exceeds ``MOST_ERROR_S``."""
        if not self.found:
            return None
        ages, weights, noises = np.array(self.found).T
        if weights.sum() < LEAST_WEIGHT or np.mean(noises) / weights.sum() > MOST_ERROR_S ** 2:
            return None
        order = np.argsort(ages)
        middle = np.searchsorted(np.cumsum(weights[order]), weights.sum() / 2.0)
        age = float(ages[order][middle])
        return age if 0.0 <= age <= MOST_AGE_S else None

    def of_frame(self, age: float, weight: float, noise: float) -> float | None:
        """The age of one frame's message: the pooled age (``seconds``) and the frame's own slope
        ``age`` weighed by their variances -- the frame's ``noise / weight``, the pooled one's the
        spread of the frames' slopes about it less their own noise (the network's jitter)."""
        pooled = self.seconds
        if pooled is None or weight == 0.0 or not np.isfinite(noise):
            return pooled
        ages, weights, _ = np.array(self.found).T
        spread = float(np.average((ages - pooled) ** 2, weights=weights))
        jitter = max(spread - noise * len(ages) / weights.sum(), LEAST_JITTER_S ** 2)
        own = noise / weight
        blended = (age / own + pooled / jitter) / (1.0 / own + 1.0 / jitter)
        return float(min(max(blended, 0.0), MOST_AGE_S))


def frame_age(transform: np.ndarray, ego_xy: np.ndarray, cav_xy: np.ndarray,
              velocity: np.ndarray) -> tuple[float, float, float]:
    """``message_age`` of one frame's pairs, the pose and the age fitted together: a pose fitted
    to every pair has taken up part of the moving pairs' offsets, so the age is read again from the
    residuals of the pose ``compensated`` by it, ``AGE_ROUNDS`` times (least squares in both)."""
    found = message_age(ego_xy - se2.apply_points(transform, cav_xy), velocity)
    for _ in range(AGE_ROUNDS):
        if found[1] == 0.0:
            break
        moved = compensated(transform, ego_xy, cav_xy, velocity, found[0])
        found = message_age(ego_xy - se2.apply_points(moved, cav_xy), velocity)
    return found


def compensated(transform: np.ndarray, ego_xy: np.ndarray, cav_xy: np.ndarray, velocity: np.ndarray,
                age: float) -> np.ndarray:
    """``transform`` (CAV->ego, fitted to the pairs ``cav_xy`` -> ``ego_xy``) moved as much as the
    pairs' least-squares fit moves once each ego centre is moved back by its object's motion over
    the message's ``age`` (no velocity: it stands still); ``transform`` itself at age 0."""
    if age == 0.0:
        return transform
    back = np.where(np.isfinite(velocity), velocity, 0.0) * age
    shift = weighted_procrustes(cav_xy, ego_xy - back) @ se2.inverse(weighted_procrustes(cav_xy, ego_xy))
    return shift @ transform


@dataclass
class LateMessages:
    """The message's age as CBM over time follows it: the ego's tracks, the pooled age."""

    tracks: EgoTracks = field(default_factory=EgoTracks)
    age: AgeEstimate = field(default_factory=AgeEstimate)

    def copy(self) -> LateMessages:
        """A copy that a step on this one leaves as it is (its arrays are replaced, never written)."""
        t = self.tracks
        return LateMessages(EgoTracks(deque(t.times, maxlen=WINDOW), t.positions, t.boxes, t.motion),
                            AgeEstimate(deque(self.age.found, maxlen=AGE_FRAMES)))

    def _pairs(self, ego: np.ndarray, cav: np.ndarray, result: MatchResult,
               velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pairs the age is read from: CBM's own, or -- once an age is known -- the one-to-one
        pairs of the ego's boxes moved back by their motion over it and the CAV's under CBM's pose,
        so that a fast object whose offset the age explains is not left out by the gate of CBM's
        pairs (which would leave only the moving pairs that moved least, and the age too short)."""
        pooled = self.age.seconds
        if pooled is None:
            return result.pairs[:, 0], result.pairs[:, 1]
        back = ego.copy()
        back[:, :2] -= np.where(np.isfinite(velocity), velocity, 0.0) * pooled
        sigma = max(float(np.sqrt(np.mean(result.residuals ** 2) / 2.0)), LINK_SIGMA / 2.0)
        pairs = gated_assignment(back, se2.apply_boxes(result.transform, cav), 3.0 * sigma, sigma)
        if len(pairs) < LEAST_PAIRS:
            return result.pairs[:, 0], result.pairs[:, 1]
        return pairs[:, 0], pairs[:, 1]

    def corrected(self, ego: np.ndarray, cav: np.ndarray, result: MatchResult, time_s: float,
                  floor: float) -> MatchResult:
        """``result`` (CBM's on the frame at ``time_s``) with the message's age (``latency_s``, None
        while it cannot tell) and, once known, its pose fitted again (eq. 15, ``robust_fit`` with
        the Welsch ``floor``) to its pairs with the ego's boxes moved back by their objects' motion
        over it: moving pairs then agree with the still ones, and the robust fit no longer follows
        one lane of traffic or the parked cars alone; the ego's boxes join the tracks."""
        velocity = self.tracks.step(ego, time_s)
        if not result.estimated or len(result.pairs) < LEAST_PAIRS:
            return dataclasses.replace(result, latency_s=self.age.seconds)
        e, c = self._pairs(ego, cav, result, velocity)
        frame = frame_age(result.transform, ego[e, :2], cav[c, :2], velocity[e])
        self.age.add(*frame)
        age = self.age.of_frame(*frame)
        if age is None:
            return dataclasses.replace(result, latency_s=None)
        back = np.where(np.isfinite(velocity[e]), velocity[e], 0.0) * age
        if np.max(np.hypot(*back.T), initial=0.0) >= REFIT_FROM:
            transform = robust_fit(cav[c, :2], ego[e, :2] - back, floor).transform
        else:
            transform = compensated(result.transform, ego[e, :2], cav[c, :2], velocity[e], age)
        residuals = np.hypot(*(ego[e, :2] - back - se2.apply_points(transform, cav[c, :2])).T)
        return dataclasses.replace(result, transform=transform, residuals=residuals, latency_s=age)
