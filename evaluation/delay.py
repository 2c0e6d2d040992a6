"""Late messages: a CAV's detections and reported pose reach the ego some time after capture.

OpenCOOD's asynchronous settings delay the CAV's message by 100-300 ms; DAIR-V2X pairs vehicle and
roadside frames whose timestamps differ. On the road a message's age is the network's delay plus
the gap between the two agents' capture times, and it jitters from message to message. So a trial
of frame k at time t_k with a delay d takes the CAV's objects and pose from the sequence at the
capture time t_k - d (``History.at``: the real frames around it, interpolated where d is not a
multiple of the frame period), the ego's from frame k. Parked cars are where the CAV saw them;
moving ones have moved while the message travelled. The pose to estimate is the CAV's pose at
capture relative to the ego now.

The delay of a frame is ``delay_ms`` plus a uniform draw within +-``jitter_ms`` (never below 0),
drawn from a generator of its own (``delay_rng``), so that a delay changes no other draw of the trial.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cbm import se2

MOST_MS = 1000.0
"""Milliseconds: the oldest message a scenario may ask for (delay plus jitter)."""
STREAM = 0xDE1A7
"""The delay's own stream of the seed (``delay_rng``)."""


@dataclass(frozen=True)
class History:
    """The frames before one frame (and the frame itself), as the CAV of its trial would have seen
    them: the boxes of the frame's objects in each (rows as the frame's, NaN where an object was
    not there) and the CAV's pose, oldest first."""

    times: np.ndarray
    """(J,) seconds, increasing; the last is the frame's own."""
    boxes: np.ndarray
    """(J, N, 7) world boxes of the frame's N objects at each time (NaN rows: absent)."""
    cav_poses: np.ndarray
    """(J, 3, 3) the CAV's pose (CAV->world) at each time."""

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray, float]:
        """(boxes, CAV pose, capture time) at time ``t``, between the two frames around it: positions
        and headings linear in time (headings the short way round), sizes of the later frame; an
        object absent from either frame is absent. Before the oldest frame, the oldest frame."""
        t = float(min(max(t, self.times[0]), self.times[-1]))
        later = int(np.searchsorted(self.times, t, side="left"))
        if self.times[later] == t:
            return self.boxes[later].copy(), self.cav_poses[later].copy(), t
        earlier = later - 1
        w = (t - self.times[earlier]) / (self.times[later] - self.times[earlier])
        return (between(self.boxes[earlier], self.boxes[later], w),
                pose_between(self.cav_poses[earlier], self.cav_poses[later], w), t)


def between(a: np.ndarray, b: np.ndarray, w: float) -> np.ndarray:
    """(N, 7) boxes a fraction ``w`` of the way from ``a`` to ``b``, row by row (NaN where either is)."""
    out = b.copy()
    out[:, :3] = (1.0 - w) * a[:, :3] + w * b[:, :3]
    out[:, 6] = se2.wrap_angle(a[:, 6] + w * se2.wrap_angle(b[:, 6] - a[:, 6]))
    out[np.isnan(a).any(axis=1)] = np.nan
    return out


def pose_between(a: np.ndarray, b: np.ndarray, w: float) -> np.ndarray:
    """The pose a fraction ``w`` of the way from ``a`` to ``b`` (translation linear, yaw the short way)."""
    xy = (1.0 - w) * se2.translation_of(a) + w * se2.translation_of(b)
    yaw = se2.yaw_of(a) + w * se2.wrap_angle(se2.yaw_of(b) - se2.yaw_of(a))
    return se2.make(xy[0], xy[1], yaw)


def delay_rng(seed: int, frame_index: int, stream: int = 0) -> np.random.Generator:
    """The generator of a frame's delay draw: apart from the trial's own (``scenario.trial_rng``)."""
    return np.random.default_rng([seed, frame_index, stream, STREAM])


def message_delay(delay_ms: float, jitter_ms: float, rng: np.random.Generator) -> float:
    """Seconds: ``delay_ms`` plus a uniform draw within +-``jitter_ms``, at least 0."""
    return max(delay_ms + jitter_ms * (2.0 * rng.random() - 1.0), 0.0) / 1000.0


def history_of(times: np.ndarray, boxes: list[np.ndarray], cav_poses: list[np.ndarray]) -> History:
    """A ``History`` from its frames' times, aligned boxes and CAV poses, oldest first."""
    return History(np.asarray(times, dtype=float), np.stack(boxes), np.stack(cav_poses))
