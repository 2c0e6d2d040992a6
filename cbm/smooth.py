"""CBM over a whole recording (beyond the paper): a smoother that uses the frames after a frame too.

CBM over time (``cbm.SequenceCalibrator``) answers each frame from the frames before it, as a car
must on the road. Offline, with the whole recording at hand (the app's run over every frame,
``evaluate.py``), a frame can also lean on the frames after it: a stretch where single frames are
thin is then bridged from both ends, and a track that lagged behind a jump catches up at once. So
CBM over time runs twice, forward and backward (the frames in reverse order, time counted back),
and each frame's two answers are combined by their covariances (``TrackNote.covariance``) -- the
two-filter smoother of Fraser and Potter (1969): ``C = (C_f^-1 + C_b^-1)^-1``,
``g = C (C_f^-1 g_f + C_b^-1 g_b)``, in the pose error ``g = init^-1 T``. Where the two answers
disagree beyond ``GATE`` standard deviations, or only one side has a covariance, the surer one stands.

    smoother = Smoother(CBMParams())
    for ego, cav, init, t in frames:          # in time order
        smoother.step(ego, cav, init, t)      # CBM over time's causal answer
    results = smoother.smoothed()             # one per frame, using every frame
"""
from __future__ import annotations

import dataclasses

import numpy as np

from . import se2
from .params import CBMParams
from .result import MatchResult
from .sequence import SequenceCalibrator, TrackingParams
from .track import as_matrix, as_vector, difference, mahalanobis2

GATE = 3.5
"""Standard deviations (3 degrees of freedom) within which the two directions' answers are one."""


class Smoother:
    """The frames of one CAV in time order, and CBM over time's answers to them both ways."""

    def __init__(self, params: CBMParams | None = None, tracking: TrackingParams | None = None) -> None:
        self.forward = SequenceCalibrator(params, tracking)
        self.params, self.tracking = self.forward.params, self.forward.tracking
        self.frames: list[tuple[np.ndarray, np.ndarray, np.ndarray, float, object]] = []
        self.causal: list[MatchResult] = []

    def step(self, ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, time_s: float,
             agent: object = None) -> MatchResult:
        """CBM over time's answer to the frame (``SequenceCalibrator.step``); the frame is kept."""
        result = self.forward.step(ego_boxes, cav_boxes, init, time_s, agent)
        self.frames.append((ego_boxes, cav_boxes, init, float(time_s), agent))
        self.causal.append(result)
        return result

    def smoothed(self) -> list[MatchResult]:
        """Every frame's answer from the frames before it and after it (see the module)."""
        backward = SequenceCalibrator(self.params, self.tracking)
        late_first = [backward.step(ego, cav, init, -t, agent) for ego, cav, init, t, agent in reversed(self.frames)]
        return [combined(ahead, behind) for ahead, behind in zip(self.causal, reversed(late_first))]


def combined(ahead: MatchResult, behind: MatchResult) -> MatchResult:
    """``ahead`` (the forward answer) with its pose the two answers' covariance-weighted mean."""
    if ahead.track is None or behind.track is None:
        return ahead
    C_f, C_b = ahead.track.covariance, behind.track.covariance
    if C_f is None or C_b is None:
        return ahead if C_b is None else _as(ahead, behind.transform)
    init = ahead.init
    g_f, g_b = as_vector(se2.inverse(init) @ ahead.transform), as_vector(se2.inverse(init) @ behind.transform)
    gap = difference(g_b, g_f)
    if mahalanobis2(gap, C_f + C_b) > GATE ** 2:
        return ahead if np.linalg.det(C_f) <= np.linalg.det(C_b) else _as(ahead, behind.transform)
    g = g_f + C_f @ np.linalg.solve(C_f + C_b, gap)
    return _as(ahead, init @ as_matrix(g))


def _as(result: MatchResult, transform: np.ndarray) -> MatchResult:
    return dataclasses.replace(result, transform=transform, estimated=True)
