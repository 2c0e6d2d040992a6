"""Per-trial metrics of a matching result: the record of a trial (``TrialMetrics``) that the metric
registry (``evaluation.metric_registry``) reads, per trial and over a run.

Pairs are ``(K, 2)`` int arrays of (ego index, CAV index), one row per distinct pair. A metric that
has nothing to measure is NaN, never 0, so that it cannot pass for a real score.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cbm import se2

from .scenario import Trial


def _as_pairs(pairs: np.ndarray) -> np.ndarray:
    return np.asarray(pairs, dtype=np.int64).reshape(-1, 2)


def count_correct(pairs: np.ndarray, gt_pairs: np.ndarray) -> int:
    """|M_hat n M|: how many output pairs are true pairs."""
    pairs, gt_pairs = _as_pairs(pairs), _as_pairs(gt_pairs)
    if len(pairs) == 0 or len(gt_pairs) == 0:
        return 0
    width = int(max(pairs[:, 1].max(), gt_pairs[:, 1].max())) + 1
    return int(np.isin(pairs[:, 0] * width + pairs[:, 1], gt_pairs[:, 0] * width + gt_pairs[:, 1]).sum())


def _share(n_correct: int, total: int) -> float:
    return n_correct / total if total else math.nan


def precision(pairs: np.ndarray, gt_pairs: np.ndarray) -> float:
    """precision = |M_hat n M| / |M_hat| (paper sec. IV-A, V-B); NaN when nothing was matched."""
    return _share(count_correct(pairs, gt_pairs), len(_as_pairs(pairs)))


def recall(pairs: np.ndarray, gt_pairs: np.ndarray) -> float:
    """recall = |M_hat n M| / |M| (paper sec. V-B); NaN when there are no true pairs."""
    return _share(count_correct(pairs, gt_pairs), len(_as_pairs(gt_pairs)))


def average_distance(pairs: np.ndarray, ego_true_xy: np.ndarray, cav_true_xy: np.ndarray) -> float:
    """AD (paper sec. V-B): d = 1/|M_hat| sum_{(i,j) in M_hat} ||p_i - p_j||_2.

    ``p_i``, ``p_j`` are the true (noise-free) centres of the two objects of a pair, both in the ego
    frame, so a correct pair scores 0 and a wrong one scores how far apart the objects really are.
    NaN when no pairs.
    """
    pairs = _as_pairs(pairs)
    if len(pairs) == 0:
        return math.nan
    gaps = np.asarray(ego_true_xy)[pairs[:, 0]] - np.asarray(cav_true_xy)[pairs[:, 1]]
    return float(np.linalg.norm(gaps, axis=1).mean())


def rre(T_est: np.ndarray, T_true: np.ndarray) -> float:
    """Relative rotation error in degrees: RRE = |wrap(yaw(T_est) - yaw(T_true))|, wrapped to [-pi, pi)."""
    return math.degrees(abs(float(se2.wrap_angle(se2.yaw_of(T_est) - se2.yaw_of(T_true)))))


def rte(T_est: np.ndarray, T_true: np.ndarray) -> float:
    """Relative translation error in metres: RTE = ||t_est - t_true||_2."""
    return float(np.linalg.norm(se2.translation_of(T_est) - se2.translation_of(T_true)))


@dataclass(frozen=True)
class TrialMetrics:
    """The metrics of one result on one trial. ``rre``/``rte`` are NaN when no estimate was made."""

    n_ego: int
    n_cav: int
    n_true: int
    """Co-visible (ground-truth) pairs."""
    n_matched: int
    n_correct: int
    precision: float
    recall: float
    ad: float
    """Metres, paper sec. V-B."""
    rre: float
    """Degrees."""
    rte: float
    """Metres."""
    runtime_s: float
    """``result.timings["total"]``; NaN when the result has no timing."""
    margin: float
    """Consensus margin of CBM; NaN for results without one."""
    estimated: bool
    abstained: bool = False
    """The method said its pose has not enough evidence (``cbm.MatchResult.abstained``); its pose
    is still scored, and counted apart (``evaluation.metric_registry.AbstainRate``)."""
    latency_error_s: float = math.nan
    """Seconds between the message's age the method tells (``cbm.MatchResult.latency_s``) and the
    trial's (``Trial.message_age_s``); NaN where it tells none."""


def evaluate(result: Any, trial: Trial) -> TrialMetrics:
    """Score a result on a trial.

    Duck-typed: ``result`` needs ``pairs``, ``transform`` and ``estimated`` (as ``cbm.MatchResult``);
    ``margin`` and ``timings`` (with a ``"total"`` key, seconds) are read when present.
    """
    pairs = _as_pairs(result.pairs)
    estimated = bool(result.estimated)
    n_correct = count_correct(pairs, trial.gt_pairs)
    return TrialMetrics(
        n_ego=len(trial.ego_boxes),
        n_cav=len(trial.cav_boxes),
        n_true=len(trial.gt_pairs),
        n_matched=len(pairs),
        n_correct=n_correct,
        precision=_share(n_correct, len(pairs)),
        recall=_share(n_correct, len(_as_pairs(trial.gt_pairs))),
        ad=average_distance(pairs, trial.ego_true_xy, trial.cav_true_xy),
        rre=rre(result.transform, trial.T_true) if estimated else math.nan,
        rte=rte(result.transform, trial.T_true) if estimated else math.nan,
        runtime_s=float(getattr(result, "timings", {}).get("total", math.nan)),
        margin=float(getattr(result, "margin", math.nan)),
        estimated=estimated,
        abstained=bool(getattr(result, "abstained", False)),
        latency_error_s=_latency_error(getattr(result, "latency_s", None), trial.message_age_s),
    )


def _latency_error(told: float | None, age: float) -> float:
    return math.nan if told is None else abs(float(told) - float(age))


def is_success(m: TrialMetrics, *, rte_max: float = 1.0, rre_max: float = 1.0) -> bool:
    """A trial succeeds when a pose was estimated with RTE < rte_max (m) and RRE < rre_max (deg)."""
    return m.estimated and m.rte < rte_max and m.rre < rre_max
