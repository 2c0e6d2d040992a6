"""CBM's parameters, with their defaults in one place."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from .inputs import check_at_most, check_positive

HeadingMode = Literal["fold", "align"]
ConsensusRule = Literal["paper", "released"]
Estimator = Literal["welsch", "least_squares"]


MOST = {"sigma1": 45.0, "sigma2": 10.0, "sigma3": 10.0, "distance_limit": 60.0, "welsch_floor": 5.0,
        "refine_gate": 8.0}
"""Each threshold's largest value, wherever it is given (the app's sliders end there): beyond them
every pair of objects matches and a frame takes minutes (``distance_limit`` may also be ``math.inf``)."""


@dataclass(frozen=True)
class CBMParams:
    """Thresholds of CBM (Song et al., RA-L 2024, sec. III-B) and of the pose estimate (sec. III-C).

    Angles are in degrees here, at the interface; the algorithm uses radians (``sigma1_rad``).
    The thresholds are the authors' released code's (its consensus rule with sigma3 = 1 m gave the
    best recall and success rate under the SIND protocol and on Argoverse 2, docs/benchmarks.md).
    Three defaults go beyond the paper because they measured better (docs/results.md): ``heading``
    ``align`` rather than the released code's ``fold``; a Welsch scale that follows the residuals
    (``cbm.estimate.robust_fit``); and the guided re-association ``refine``. The paper's method is
    ``refine=False``; the released code's is also ``heading="fold", estimator="least_squares"``.
    """

    sigma1: float = 10.0
    """Degrees. Largest angle between two context vectors that still match (eq. 8, first term)."""
    sigma2: float = 3.0
    """Metres. Largest L1 distance between two context vectors that still match (eq. 8, second term)."""
    sigma3: float = 1.0
    """Metres. L1 distance for the voting sets of the global consensus (with the paper's rule,
    sigma3 = sigma2 makes eq. 10 exact; sigma3 itself is the released code's, beyond the paper)."""
    distance_limit: float = 20.0
    """Metres. An anchor whose pairs are on average farther apart than this after ``init`` is rejected;
    ``math.inf``: no limit (CBM without a prior, ``cbm.prior_free``)."""
    consensus: bool = True
    """Global consensus (eq. 10-11) on or off (off is the paper's ablation)."""
    consensus_rule: ConsensusRule = "released"
    """``paper``: eq. 10-11, every candidate needs another member's vote. ``released``: the authors'
    code, only candidates sharing a row or column of their set need a vote (see ``cbm.reference.consensus``)."""
    heading: HeadingMode = "align"
    """``fold``: fold every heading into (-pi/2, pi/2] (released code). ``align``: turn each CAV
    object's heading by pi where that brings it closer to the ego object it is compared with."""
    estimator: Estimator = "welsch"
    """Pose estimate from the pairs: ``welsch`` the robust fit of eq. 15, ``least_squares`` the
    released code's SVD fit."""
    welsch_floor: float = 0.3
    """Metres. Smallest Welsch scale nu of the robust pose estimate: the least detection noise assumed."""
    refine: bool = True
    """Guided re-association after CBM (beyond the paper, ``cbm.reassociate``): pair all boxes
    one-to-one under the estimate, refit, repeat until the pairs stop changing; and the verified
    hypotheses with the noise-aware gate (``cbm.hypotheses``), which also say when CBM has not
    enough evidence. ``False`` is the paper's method."""
    refine_gate: float = 3.0
    """Gate of the re-association in std-devs of the pairs' noise (read from the residuals, at
    least welsch_floor / 2.1): a true pair falls outside 3 sigma with probability 1.1 %; a wider
    gate finds more true pairs and more coincidences in crowds (docs/results.md)."""

    def __post_init__(self) -> None:
        check_positive(self, "sigma1", "sigma2", "sigma3", "welsch_floor", "refine_gate")
        if self.distance_limit != math.inf:
            check_positive(self, "distance_limit")
        check_at_most(self, {name: most for name, most in MOST.items()
                             if not (name == "distance_limit" and self.distance_limit == math.inf)})
        if self.consensus_rule not in ("paper", "released"):
            raise ValueError(f"CBMParams.consensus_rule must be 'paper' or 'released', got {self.consensus_rule!r}")
        if self.heading not in ("fold", "align"):
            raise ValueError(f"CBMParams.heading must be 'fold' or 'align', got {self.heading!r}")
        if self.estimator not in ("welsch", "least_squares"):
            raise ValueError(f"CBMParams.estimator must be 'welsch' or 'least_squares', got {self.estimator!r}")
        for name in ("consensus", "refine"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"CBMParams.{name} must be True or False, got {getattr(self, name)!r}")

    @property
    def sigma1_rad(self) -> float:
        return math.radians(self.sigma1)
