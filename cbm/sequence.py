"""CBM over time (step 8, beyond the paper): calibrate a CAV frame after frame with a track of its
pose error, for localization errors that drift like GNSS.

    from cbm import CBMParams, SequenceCalibrator
    cal = SequenceCalibrator(CBMParams())              # one per CAV and sequence
    r = cal.step(ego_boxes, cav_boxes, init, time_s)   # frames in time order: a MatchResult

Each frame (the model and the filter: ``cbm.track``; equations: docs/algorithm.md, step 8):

1. **watch**: until the error is seen to persist -- ``TrackingParams.chain`` measurements in a
   row, each agreeing with the one before (``cbm.track.agree``) -- every frame is per-frame CBM,
   unchanged: an error drawn anew each frame (OpenCOOD's convention) costs nothing;
2. **predict** the error and run CBM from the predicted pose ``init G_pred``, with a distance
   limit as tight as the prediction allows: pairs that persist keep matching, coincidences far
   from the prediction are turned away;
3. **gate** the frame's measurement against the prediction (one whose pairs explain the frame hardly
   better than a coincidence, ``_weak``, is set aside at once): accepted, it joins the track and the
   answer pools it with the frames before; while the track is young, one CBM stands by firmly
   (``sure_margin``) moves the track onto itself (the track lagged behind a fast drift); any other
   is rejected, and the prediction, with its uncertainty, is the answer: through stretches where
   single frames are thin, the track holds;
4. **re-acquire** when ``reacquire_after`` rejected measurements in a row agree with one another
   (a real jump), or two when the first was sure against the null pose too (``_outweighs``): a
   wrong anchor can be sure too, so one frame never moves a settled track (such a frame answers its
   own measurement meanwhile); and call the track **lost** when its prediction grows too uncertain
   or ``lost_after`` frames in a row brought a measurement, not abstained, that it rejected: that
   frame answers per-frame CBM, never the stale prediction (abstained where CBM alone is not sure),
   and watching starts again.

Every frame, before its measurement is taken, the CAV's message's age is followed and moving
objects are moved back by it (``cbm.motion``): a late message's moving pairs pull the pose no more,
and ``MatchResult.latency_s`` says how old the messages are. Time going backwards, a gap of more
than ``max_gap_s`` or another ``agent`` starts it over.
"""
from __future__ import annotations

import copy
import dataclasses
import math
import numbers

import numpy as np

from . import se2
from .engine.assignment import gated_assignment
from .engine.fitting import WELSCH_EFFICIENT_SCALE
from .hypotheses import EVIDENCE_MARGIN, predicted, same_pose
from .inputs import is_number, shown
from .motion import LateMessages
from .params import CBMParams
from .pipeline import checked_inputs, match
from .result import MatchResult, TrackNote
from .smoothing import combined
from .track import (
    Measurement,
    Persistence,
    Track,
    TrackingParams,
    agree,
    as_matrix,
    measurement,
)


class SequenceCalibrator:
    """CBM over time for one CAV of one sequence (see the module)."""

    def __init__(self, params: CBMParams | None = None, tracking: TrackingParams | None = None, *,
                 late: bool = True) -> None:
        """``late``: follow the CAV's messages' age (``cbm.motion``); the smoother's backward pass,
        where time runs back, does not."""
        self.follows_late = late
        self.params = CBMParams() if params is None else _of_type("params", params, CBMParams)
        self.tracking = TrackingParams() if tracking is None else _of_type("tracking", tracking, TrackingParams)
        t = self.tracking
        self.rate = np.array([t.drift_m ** 2, t.drift_m ** 2, math.radians(t.drift_deg) ** 2])
        self.floor = self.params.welsch_floor / WELSCH_EFFICIENT_SCALE
        self.reset()

    def reset(self) -> None:
        """Forget the track and what persisted: the next frame starts over."""
        self.track: Track | None = None
        self.persistence = Persistence(self.tracking.window)
        self.rejected: list[Measurement] = []
        self.misses = 0
        self.last_time: float | None = None
        self.agent: object = None
        self.late = LateMessages() if self.follows_late else None
        self.measured: tuple[MatchResult, bool] | None = None

    def step(self, ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray | None, time_s: float,
             agent: object = None) -> MatchResult:
        """The calibrated result of the frame at ``time_s`` (seconds; frames in time order) of the
        CAV ``agent`` (a string or an integer; another one starts the calibration over). A step that
        does not complete (an error, or stopped: ``cbm.engine.threads.Cancelled``) leaves the
        calibrator as it was, so that the same step run again answers as if it never was."""
        ego, cav, init, params = checked_inputs(ego_boxes, cav_boxes, init, self.params)
        if not is_number(time_s) or not math.isfinite(time_s):
            raise ValueError(f"time_s must be a finite number of seconds, got {shown(time_s)}")
        if not (agent is None or isinstance(agent, (str, numbers.Integral))) or isinstance(agent, (bool, np.bool_)):
            raise ValueError(f"agent must be None, a string or an integer (a label of the CAV), got {shown(agent)}")
        kept = self._state()
        try:
            return self._step(ego, cav, init, params, float(time_s), agent)
        except BaseException:
            self._restore(kept)
            raise

    def _state(self) -> tuple:
        """What a step changes, copied (a track is updated in place)."""
        return (copy.copy(self.track), self.persistence.copy(), list(self.rejected), self.misses, self.last_time,
                self.agent, None if self.late is None else self.late.copy())

    def _restore(self, state: tuple) -> None:
        self.track, self.persistence, self.rejected, self.misses, self.last_time, self.agent, self.late = state

    def _step(self, ego: np.ndarray, cav: np.ndarray, init: np.ndarray, params: CBMParams, time_s: float,
              agent: object) -> MatchResult:
        event = self._reset_if_needed(time_s, agent)
        lost = self._lost(time_s)
        result = self._matched(ego, cav, init, params, self._trusted_prediction(time_s), time_s)
        found = measurement(result, init, cav, self.floor, time_s)
        chain = self.persistence.add(found, self.rate, self.tracking.drift_share, self.tracking.gate)
        self.last_time = time_s
        if lost is not None:
            noted = self._noted(result, event or "lost", found, result.transform, True, init @ as_matrix(lost))
            if not (result.abstained or not result.estimated):
                return noted
            why = result.reason or "this frame alone paired too few objects"
            return dataclasses.replace(noted, abstained=True, reason=f"lost: no frame agreed with the calibration "
                                                                     f"over time for too long, and {why}")
        if self.track is None:
            return self._watched(result, found, chain, event)
        return self._tracked(ego, cav, init, result, found, time_s, event)

    def _matched(self, ego: np.ndarray, cav: np.ndarray, init: np.ndarray, params: CBMParams,
                 prior: tuple[np.ndarray, np.ndarray] | None, time_s: float) -> MatchResult:
        """The frame's measurement: CBM from the trusted prediction ``prior`` (pooled with it) or, without
        one, per-frame CBM; its pose then fitted again for the message's age (``cbm.motion``).
        Kept as ``measured``, and whether a prediction guided it (``Smoother``'s backward pass reuses it)."""
        if prior is None:
            result = match(ego, cav, init, params)
        else:
            result = match(ego, cav, init @ as_matrix(prior[0]), self._tightened(params, prior[1], cav))
            result = self._pooled(ego, cav, init @ as_matrix(prior[0]), prior[1], result)
        result = result if self.late is None else self.late.corrected(ego, cav, result, time_s, params.welsch_floor)
        self.measured = (result, prior is not None)
        return result

    def _reset_if_needed(self, time_s: float, agent: object) -> str:
        """Starts over after time went backwards, a long gap or another agent; names why ("" if not)."""
        why = ""
        if self.last_time is not None and time_s < self.last_time:
            why = "time went backwards"
        elif self.last_time is not None and time_s - self.last_time > self.tracking.max_gap_s:
            why = f"a gap of {time_s - self.last_time:.1f} s"
        elif self.last_time is not None and agent != self.agent:
            why = "another CAV"
        if why:
            self.reset()
        self.agent = agent
        return f"reset: {why}" if why else ""

    def _lost(self, time_s: float) -> np.ndarray | None:
        """The track's last prediction (as a pose error) when it is lost at ``time_s`` -- too
        uncertain, or ``lost_after`` rejected measurements in a row -- and then dropped; else None."""
        if self.track is None:
            return None
        g, P = self.track.predicted(time_s)
        if self._trusted(P) and self.misses < self.tracking.lost_after:
            return None
        self.track, self.rejected, self.misses = None, [], 0
        return g

    def _trusted_prediction(self, time_s: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The track's prediction (b^-, P^-) at ``time_s`` while it is trusted, else None."""
        if self.track is None:
            return None
        g, P = self.track.predicted(time_s)
        return (g, P) if self._trusted(P) else None

    def _trusted(self, P: np.ndarray) -> bool:
        return (math.sqrt(P[0, 0] + P[1, 1]) <= self.tracking.lost_m
                and math.degrees(math.sqrt(P[2, 2])) <= self.tracking.lost_deg)

    def _pooled(self, ego: np.ndarray, cav: np.ndarray, pose: np.ndarray, P: np.ndarray,
                result: MatchResult) -> MatchResult:
        """CBM's answer, or the track's predicted ``pose`` refined on the pairs it finds, whichever
        explains the frame better (``cbm.hypotheses.predicted``): the frames before count in the
        matching too, not only in the pose, where a frame alone matches nothing sure. Where CBM is
        sure on the predicted pose itself (``same_pose``), refining from there finds its pairs again."""
        if result.estimated and not result.abstained and same_pose(result.transform, pose):
            return result
        W = self.track.W
        sigma = max(self.floor, math.sqrt((P[0, 0] + P[1, 1] + W[0] + W[1]) / 2.0))
        found = predicted(ego, se2.apply_boxes(pose, cav), sigma, self.floor, self.params.refine_gate)
        if found is None or (result.estimated and not result.abstained and not found.score > result.evidence):
            return result
        transform = found.correction @ pose
        moved = se2.apply_points(transform, cav[found.pairs[:, 1], :2])
        return dataclasses.replace(result, pairs=found.pairs, transform=transform, estimated=True, abstained=False,
                                   reason="", evidence=found.score,
                                   residuals=np.hypot(*(ego[found.pairs[:, 0], :2] - moved).T))

    def _tightened(self, params: CBMParams, P: np.ndarray, cav: np.ndarray) -> CBMParams:
        """CBM's distance limit as tight as the prediction allows: 3 m of detection noise and 3
        standard deviations of the predicted error and its white noise at the CAV boxes' typical range."""
        W = self.track.W
        reach = float(np.median(np.hypot(cav[:, 0], cav[:, 1]))) if len(cav) else 0.0
        spread = math.sqrt(P[0, 0] + P[1, 1] + W[0] + W[1]) + math.sqrt(P[2, 2] + W[2]) * reach
        return dataclasses.replace(params, distance_limit=min(params.distance_limit, 3.0 + 3.0 * spread))

    def _watched(self, result: MatchResult, found: Measurement | None, chain: list[Measurement],
                 event: str) -> MatchResult:
        """Per-frame CBM's answer; the measurement that completes a chain of ``TrackingParams.chain``
        starts the track."""
        persists = len(chain) >= self.tracking.chain
        if persists:
            self.track = Track.started(chain, self.rate)
            event = event or "started"
        return self._noted(result, event or "per frame", found, result.transform, persists)

    def _tracked(self, ego: np.ndarray, cav: np.ndarray, init: np.ndarray, result: MatchResult,
                 found: Measurement | None, time_s: float, event: str) -> MatchResult:
        """The track's answer: the measurement accepted into it, or rejected (the prediction stands;
        re-acquired after a real jump; lost: per-frame CBM's answer, abstained)."""
        g, _ = self.track.predicted(time_s)
        predicted = init @ as_matrix(g)
        answer = g
        if found is not None and self._weak(found):
            event = event or "weak measurement"
        elif found is not None and self.track.accepts(found, self.tracking.gate):
            answer = self.track.update(found, self.rate)
            self.rejected, self.misses = [], 0
            event = event or "accepted"
        elif found is not None and self._sure(found) and not self._settled():
            self.track = self.track.restarted(found)
            answer = self.track.g
            self.rejected, self.misses = [], 0
            event = event or "re-acquired"
        elif found is not None and self._jumped(found):
            self.track = Track.started(self.rejected, self.rate)
            answer = self.track.g
            self.rejected, self.misses = [], 0
            event = event or "re-acquired"
        elif found is not None and self._outweighs(found):
            answer = found.g
            event = event or "sure, not yet confirmed"
        else:
            self.misses += found is not None and not found.result.abstained
            event = event or ("rejected" if found is not None else "no measurement")
        spread = self.track.predicted(time_s)[1] + np.diag(self.track.W)
        return self._answer(ego, cav, init, result, init @ as_matrix(answer), found, event, predicted, spread)

    def _weak(self, found: Measurement) -> bool:
        """Whether the measurement's pairs explain the frame less than ``EVIDENCE_MARGIN`` better than a
        coincidence would (per-frame CBM abstains on such an answer): it neither joins the track nor counts against
        it, and the prediction answers. On the scenes table (every row at once) that gained 0.000 /
        0.008 of S@1 / S@2 over time on average on seeds 0-1 and 0.003 / 0.005 on seeds 2-5, which did
        not choose it (the shipped log, sparse drift-heavy: .506 -> .625 and .577 -> .647), no row
        lower on seeds 2-5 and none by more than 0.010 on seeds 0-1; an evidence of 4 gained less
        (0.000 / 0.005), 12 lost S@1 (-0.001, sparse range-50 -0.026), and setting aside every
        abstained measurement lost 0.002 of S@1 (sparse drift-heavy -0.042)."""
        return found.result.evidence < EVIDENCE_MARGIN

    def _sure(self, found: Measurement) -> bool:
        """Whether its answer explains the scene ``sure_margin`` (log-likelihood) better than any other pose."""
        return not found.result.abstained and found.result.evidence_margin >= self.tracking.sure_margin

    def _outweighs(self, found: Measurement) -> bool:
        """Whether the measurement may stand against a settled track: sure (``_sure``), and by as much
        against no pose at all (its pairs' own evidence): a handful of boxes forms no rival pose, and
        its margin of ∞ says no more than its 3-4 pairs (``TrackingParams.sure_margin``)."""
        return self._sure(found) and found.result.evidence >= self.tracking.sure_margin

    def _settled(self) -> bool:
        """Whether the track has pooled a chain's worth of measurements: then one frame, however
        sure, cannot move it (a wrong anchor can be sure too)."""
        return self.track is not None and self.track.pooled >= self.tracking.chain

    def _jumped(self, found: Measurement) -> bool:
        """Whether ``found`` and the rejected measurements before it agree with one another: the
        error jumped (``reacquire_after`` of them in a row; two, the first sure, ``sure_margin``)."""
        t = self.tracking
        self.rejected = [m for m in self.rejected if agree(found, m, self.rate, t.drift_share, t.gate)] + [found]
        needed = 2 if any(self._outweighs(m) for m in self.rejected[:-1]) else t.reacquire_after
        return len(self.rejected) >= needed

    def _answer(self, ego: np.ndarray, cav: np.ndarray, init: np.ndarray, result: MatchResult,
                transform: np.ndarray, found: Measurement | None, event: str, predicted: np.ndarray,
                spread: np.ndarray) -> MatchResult:
        """``result`` carrying the track's pose; its pairs those under that pose (a gated assignment)."""
        moved = se2.apply_boxes(transform, cav)
        noise = math.sqrt(float(np.mean(result.residuals ** 2)) / 2) if len(result.residuals) else 0.0
        sigma = max(self.floor, noise)
        pairs = gated_assignment(ego, moved, self.params.refine_gate * sigma, sigma)
        residuals = np.hypot(*(ego[pairs[:, 0], :2] - moved[pairs[:, 1], :2]).T) if len(pairs) else np.zeros(0)
        answered = dataclasses.replace(result, pairs=pairs, transform=transform, init=init, estimated=True,
                                       residuals=residuals, abstained=False, reason="")
        return self._noted(answered, event, found, transform, True, predicted, spread)

    def _noted(self, result: MatchResult, event: str, found: Measurement | None, transform: np.ndarray,
               persists: bool, predicted: np.ndarray | None = None, spread: np.ndarray | None = None) -> MatchResult:
        """``result`` with its ``TrackNote``; ``spread``: the answer's covariance (the track's, else
        the frame's own measurement's, None without either)."""
        track = self.track
        spread = spread if spread is not None else (None if found is None else found.R)
        note = TrackNote(event=event, persists=persists, since_s=math.nan if track is None else track.since_s,
                         pooled=0 if track is None else track.pooled, predicted=predicted,
                         measured=None if found is None else found.result.transform, answer=transform,
                         covariance=spread)
        return dataclasses.replace(result, track=note)


def _of_type(name: str, value: object, kind: type) -> object:
    if not isinstance(value, kind):
        raise ValueError(f"SequenceCalibrator's {name} must be a {kind.__name__}, got {shown(value)}")
    return value


def match_first_step(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
                     params: CBMParams | None = None) -> MatchResult:
    """CBM over time on a frame alone: a fresh calibrator's first step (per-frame CBM's answer)."""
    return SequenceCalibrator(params).step(ego_boxes, cav_boxes, init, 0.0)


class Smoother:
    """CBM over a whole recording (beyond the paper): the frames after a frame count too.

    CBM over time (``cbm.SequenceCalibrator``) answers each frame from the frames before it, as a car
    must on the road. Offline, with the whole recording at hand (the app's run over every frame,
    ``evaluate.py``), a frame can also lean on the frames after it: a stretch where single frames are
    thin is then bridged from both ends, and a track that lagged behind a jump catches up at once. So
    CBM over time runs twice, forward and backward (the frames in reverse order, time counted back),
    and each frame's two answers are combined by their covariances (``TrackNote.covariance``) -- the
    two-filter smoother of Fraser and Potter (1969): ``C = (C_f^-1 + C_b^-1)^-1``,
    ``g = C (C_f^-1 g_f + C_b^-1 g_b)``, in the pose error ``g = init^-1 T``. The backward pass
    matches anew only the frames its prediction guides and none guided forward; elsewhere it takes
    the forward pass's measurement (per-frame CBM is the same both ways, and from two predictions of
    one error CBM pairs alike), which keeps the smoother within twice per-frame CBM's time. Where the
    two answers disagree beyond ``cbm.smoothing.SMOOTHING_GATE`` standard deviations, or only one side has a
    covariance, the surer one stands.

        smoother = Smoother(CBMParams())
        for ego, cav, init, t in frames:          # in time order
            smoother.step(ego, cav, init, t)      # CBM over time's causal answer
        results = smoother.smoothed()             # one per frame, using every frame
    """

    def __init__(self, params: CBMParams | None = None, tracking: TrackingParams | None = None) -> None:
        self.forward = SequenceCalibrator(params, tracking)
        self.params, self.tracking = self.forward.params, self.forward.tracking
        self.frames: list[tuple[np.ndarray, np.ndarray, np.ndarray, float, object]] = []
        self.causal: list[MatchResult] = []
        self.measured: list[tuple[MatchResult, bool]] = []

    def step(self, ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, time_s: float,
             agent: object = None) -> MatchResult:
        """CBM over time's answer to the frame (``SequenceCalibrator.step``); the frame is kept."""
        result = self.forward.step(ego_boxes, cav_boxes, init, time_s, agent)
        self.frames.append((ego_boxes, cav_boxes, init, float(time_s), agent))
        self.causal.append(result)
        self.measured.append(self.forward.measured)
        return result

    def smoothed(self) -> list[MatchResult]:
        """Every frame's answer from the frames before it and after it (see the module)."""
        backward = _Backward(self.params, self.tracking, late=False)
        late_first = []
        for (ego, cav, init, t, agent), measured in zip(reversed(self.frames), reversed(self.measured)):
            backward.given = measured
            late_first.append(backward.step(ego, cav, init, -t, agent))
        return [combined(ahead, behind) for ahead, behind in zip(self.causal, reversed(late_first))]


class _Backward(SequenceCalibrator):
    """``Smoother``'s backward pass: the forward pass's measurement of a frame, ``given``, stands
    unless only the backward prediction can guide the matching there."""

    given: tuple[MatchResult, bool] | None = None

    def _matched(self, ego: np.ndarray, cav: np.ndarray, init: np.ndarray, params: CBMParams,
                 prior: tuple[np.ndarray, np.ndarray] | None, time_s: float) -> MatchResult:
        if self.given is None or (prior is not None and not self.given[1]):
            return super()._matched(ego, cav, init, params, prior, time_s)
        return self.given[0]
