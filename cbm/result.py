"""What ``cbm.match`` returns, and the rigid fit it is made of."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import se2


@dataclass(frozen=True)
class Fit:
    """A rigid fit of matched centres and the noise it assumes (``cbm.estimate``)."""

    transform: np.ndarray
    """(3, 3) T minimising eq. 15 (``dst ~ T src``)."""
    weights: np.ndarray
    """(K,) final weight of each pair in [0, 1] (all 1 for least squares)."""
    scale: float
    """Metres. The final Welsch scale nu (infinite for least squares)."""
    sigma: float
    """Metres. Per-axis std-dev of a pair's residual read from the inliers (``cbm.engine.fitting.inlier_sigma``),
    at least ``nu_floor / WELSCH_EFFICIENT_SCALE``: the noise the detections are assumed to carry."""


@dataclass(frozen=True)
class TrackNote:
    """How CBM over time (``cbm.SequenceCalibrator``) reached a frame's answer."""

    event: str
    """``per frame`` (the error does not persist: per-frame CBM's answer), ``started``,
    ``accepted`` (the frame's measurement joined the track), ``rejected`` (it disagreed: the
    prediction stands), ``no measurement``, ``weak measurement`` (its pairs explain the frame hardly
    better than a coincidence: set aside), ``re-acquired`` (after a real jump), ``sure, not yet
    confirmed`` (CBM was sure of a measurement the settled track rejected: the frame answers it, the
    track waits for the next frame to agree), ``lost`` (per-frame CBM's answer, abstained), or
    ``reset: ...`` (time went backwards, a gap, another CAV)."""
    persists: bool
    """The error was seen to persist from frame to frame (else every frame stands alone)."""
    since_s: float
    """Seconds: when the track the answer comes from started (NaN without a track)."""
    pooled: int
    """Frames whose measurements the track has pooled since then."""
    predicted: np.ndarray | None
    """(3, 3) the CAV->ego transform the track predicted for this frame (None without a track)."""
    measured: np.ndarray | None
    """(3, 3) the frame's own measurement (CBM's answer), None when CBM found too few pairs."""
    answer: np.ndarray
    """(3, 3) the transform answered."""
    covariance: np.ndarray | None = None
    """(3, 3) covariance of the answer's pose error (x, y in m^2, yaw in rad^2): the track's, or the
    frame's own measurement's; None without either (``cbm.sequence.Smoother`` weighs answers by it)."""


@dataclass(frozen=True)
class MatchResult:
    """The matched pairs, the refined pose, and what the app needs to explain them."""

    pairs: np.ndarray
    """(K, 2) int: (ego index, CAV index), one-to-one, sorted by ego index."""
    transform: np.ndarray
    """(3, 3) refined CAV->ego transform (= correction @ init); equals ``init`` when not ``estimated``."""
    init: np.ndarray
    """(3, 3) the CAV->ego transform CBM started from."""
    estimated: bool
    """False when no pose estimate was made: too few pairs (two centres; one box's corners for a
    method that fits corners, V2X-Reg++)."""
    anchor: tuple[int, int] | None
    """The winning anchor pair (ego index, CAV index), or None when no anchor had a set."""
    candidate_count: int
    """Size of the winning anchor's candidate set L_ij before consensus (eq. 9)."""
    consensus_count: int
    """Size of the winning set after consensus and the one-to-one rule (eq. 10-12): CBM's own pairs."""
    runner_up_count: int
    """Largest set of an anchor that shares no pair with the winner (0 when there is none)."""
    residuals: np.ndarray
    """(K,) metres: distance of each pair's centres after ``transform``."""
    timings: dict[str, float] = field(default_factory=dict)
    """Seconds per stage."""
    context_pairs: np.ndarray | None = None
    """(K0, 2) CBM's own pairs, the winning set of eq. 14, before the guided re-association that
    may add to them (``cbm.reassociate``); None for methods that are not CBM."""
    abstained: bool = False
    """"Not enough evidence": fewer than 3 pairs, or a different pose explains the scene almost as
    well (``cbm.hypotheses.Verdict.reason``). ``transform`` is still the best estimate found."""
    reason: str = ""
    """Why CBM abstained ("" when it did not)."""
    evidence: float = math.nan
    """Log-likelihood ratio with which the answer explains the scene (``cbm.hypotheses``); NaN
    without verified hypotheses."""
    runner_up_evidence: float = math.nan
    """The same for the best hypothesis with a different pose; -inf when every hypothesis agreed."""
    runner_up_transform: np.ndarray | None = None
    """(3, 3) the runner-up's CAV->ego transform (the best different answer), None without one."""
    hypotheses: int = 0
    """Hypotheses refined and verified (0 without the guided re-association)."""
    answer_anchor: tuple[int, int] | None = None
    """The anchor whose refined answer explained the scene best (``cbm.hypotheses``): ``anchor``
    unless another anchor's hypothesis won the verification."""
    track: TrackNote | None = None
    """How CBM over time reached this answer (``cbm.SequenceCalibrator``); None for a single frame."""
    latency_s: float | None = None
    """Seconds: how old CBM over time finds the CAV's message (``cbm.motion``: moving objects' offsets
    against their speeds); None where it cannot tell (a single frame, nothing moving yet)."""
    explanation: Any = field(default=None, repr=False, compare=False)
    """``cbm.Explanation`` of this very run (its sets, fit and selection: why each anchor scored as
    it did), when ``cbm.match`` was asked to ``explain``; None otherwise."""

    @property
    def margin(self) -> int:
        """Consensus margin: how many more pairs the winner holds than its strongest rival."""
        return self.consensus_count - self.runner_up_count

    @property
    def evidence_margin(self) -> float:
        """How much better the answer explains the scene than the runner-up pose (natural-log
        likelihood ratio: 8 is 3000 times better); inf when no other answer was found, NaN when not verified."""
        return self.evidence - self.runner_up_evidence

    @property
    def correction(self) -> np.ndarray:
        """The ego-frame correction (R*, t*) of eq. 16: ``transform = correction @ init``."""
        return self.transform @ se2.inverse(self.init)
