"""What the walkthrough explains, gathered once per outcome: CBM's run and its explanation
(``cbm.Explanation``), the pair it follows, that pair's way through eq. 9-14, the robust fit of
CBM's own pairs (eq. 15-16) and the result after the guided re-association (step 7b, beyond the paper)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cbm import AnchorDetail, CBMParams, Explanation, Fit, MatchResult, se2
from evaluation.metrics import TrialMetrics, evaluate
from evaluation.scenario import Trial

from ..session.explorer import Outcome


@dataclass(frozen=True)
class Facts:
    """One outcome as the walkthrough tells it: CBM's run on the outcome's trial."""

    outcome: Outcome
    result: MatchResult
    """CBM's result: the outcome's own when its method is CBM, else CBM run on the same trial."""
    metrics: TrialMetrics
    pair: tuple[int, int] | None
    """(ego index, CAV index) followed: the winning anchor, else the first true pair."""
    detail: AnchorDetail | None
    """``pair`` through eq. 9-14."""

    @property
    def explanation(self) -> Explanation:
        """CBM's sets, fit and selection of the very run that gave ``result``."""
        return self.result.explanation

    @property
    def fit(self) -> Fit | None:
        """The robust fit of eq. 15 on CBM's own pairs (None when fewer than 2)."""
        return self.explanation.fit

    @property
    def trial(self) -> Trial:
        return self.outcome.trial

    @property
    def params(self) -> CBMParams:
        return self.explanation.params

    @property
    def ego_xy(self) -> np.ndarray:
        return self.explanation.sets.ego_xy

    @property
    def cav_xy(self) -> np.ndarray:
        """CAV centres where the wrong pose ``init`` puts them (step 1, eq. 5)."""
        return self.explanation.sets.cav_xy

    @property
    def own_pairs(self) -> np.ndarray:
        """CBM's own pairs (eq. 14), before the re-association."""
        own = self.result.context_pairs
        return (self.result.pairs if own is None else own).reshape(-1, 2)

    @property
    def fit_pose(self) -> np.ndarray:
        """CAV->ego pose after the robust fit of CBM's own pairs (eq. 16), before step 7b."""
        return self.result.init if self.fit is None else self.fit.transform @ self.result.init

    def is_anchor(self) -> bool:
        anchor = self.result.anchor
        return self.pair is not None and anchor is not None and tuple(map(int, anchor)) == self.pair

    def ego_name(self, index: int) -> str:
        return f"EGO {str(self.trial.ego_ids[index])[:8]}"

    def cav_name(self, index: int) -> str:
        return f"CAV {str(self.trial.cav_ids[index])[:8]}"

    def truth(self) -> set[tuple[int, int]]:
        return {tuple(p) for p in np.asarray(self.trial.gt_pairs).reshape(-1, 2).tolist()}


def pose_error(T: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """(metres, degrees) between a CAV->ego pose and the true one."""
    metres = float(np.linalg.norm(se2.translation_of(T) - se2.translation_of(truth)))
    return metres, abs(math.degrees(se2.wrap_angle(se2.yaw_of(T) - se2.yaw_of(truth))))


def followed_pair(result: MatchResult, gt_pairs: np.ndarray, n_ego: int, n_cav: int) -> tuple[int, int] | None:
    """The pair the walkthrough follows: the winning anchor, else the first true pair, else the
    first objects of both agents (None when an agent sees nothing)."""
    if result.anchor is not None:
        return int(result.anchor[0]), int(result.anchor[1])
    gt = np.asarray(gt_pairs).reshape(-1, 2)
    if len(gt):
        return int(gt[0, 0]), int(gt[0, 1])
    return (0, 0) if n_ego and n_cav else None


def gather(outcome: Outcome) -> Facts:
    """The facts of ``outcome``: CBM's run with the tab's thresholds and its explanation (the
    outcome's own run when its method is CBM), nothing computed a second time."""
    result = outcome.cbm()
    own = result is outcome.result
    metrics = outcome.metrics if own else evaluate(result, outcome.trial)
    trial = outcome.trial
    pair = followed_pair(result, trial.gt_pairs, len(trial.ego_boxes), len(trial.cav_boxes))
    detail = result.explanation.anchor(*pair) if pair is not None else None
    return Facts(outcome, result, metrics, pair, detail)
