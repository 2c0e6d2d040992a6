import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from cbm import se2
from cbm.result import MatchResult
from evaluation.metric_registry import aggregate
from evaluation.metrics import (
    TrialMetrics,
    average_distance,
    count_correct,
    evaluate,
    precision,
    recall,
    rre,
    rte,
)
from evaluation.scenario import ScenarioParams, make_trial

GT = np.array([[0, 0], [1, 2], [2, 1], [4, 3]])
OUT = np.array([[0, 0], [1, 1], [2, 1], [3, 3]])


def test_precision_and_recall_by_hand():
    assert count_correct(OUT, GT) == 2
    assert precision(OUT, GT) == pytest.approx(2 / 4)
    assert recall(OUT, GT) == pytest.approx(2 / 4)
    assert precision(OUT[:1], GT) == 1.0
    assert recall(OUT[:1], GT) == pytest.approx(1 / 4)
    assert precision(np.array([[0, 1]]), GT) == 0.0


def test_nan_when_there_is_nothing_to_measure():
    empty = np.empty((0, 2), dtype=int)
    assert math.isnan(precision(empty, GT))
    assert math.isnan(recall(OUT, empty))
    assert recall(empty, GT) == 0.0
    assert precision(OUT, empty) == 0.0
    assert math.isnan(average_distance(empty, np.zeros((3, 2)), np.zeros((3, 2))))


def test_average_distance_uses_the_true_positions_of_each_pair():
    ego_xy = np.array([[0.0, 0.0], [10.0, 0.0]])
    cav_xy = np.array([[0.0, 0.0], [13.0, 4.0], [10.0, 1.0]])
    assert average_distance(np.array([[0, 0], [1, 1]]), ego_xy, cav_xy) == pytest.approx((0 + 5) / 2)
    assert average_distance(np.array([[1, 2], [0, 1]]), ego_xy, cav_xy) == pytest.approx((1 + math.hypot(13, 4)) / 2)


def test_rre_wraps_across_plus_minus_180_degrees_and_rte_is_euclidean():
    T_true = se2.make(1.0, 2.0, math.radians(-179.0))
    T_est = se2.make(4.0, 6.0, math.radians(179.0))
    assert rre(T_est, T_true) == pytest.approx(2.0)
    assert rre(T_true, T_est) == pytest.approx(2.0)
    assert rre(se2.make(0, 0, math.radians(30)), se2.make(0, 0, math.radians(-20))) == pytest.approx(50.0)
    assert rte(T_est, T_true) == pytest.approx(5.0)


def _trial():
    boxes = np.zeros((6, 7))
    boxes[:, 0] = np.arange(6) * 10.0
    params = ScenarioParams(eta=0.5, flip_prob=0.0, loc_x=0, loc_y=0, loc_yaw=0)
    return make_trial(boxes, np.arange(6), params)


def test_evaluate_a_match_result():
    trial = _trial()
    T_est = trial.T_true @ se2.make(0.3, 0.4, math.radians(2.0))
    result = MatchResult(pairs=trial.gt_pairs[:2], transform=T_est, init=trial.init, estimated=True, anchor=None,
                         candidate_count=3, consensus_count=2, runner_up_count=1, residuals=np.zeros(2),
                         timings={"total": 0.25})
    m = evaluate(result, trial)
    assert (m.n_ego, m.n_cav, m.n_true, m.n_matched, m.n_correct) == (
        len(trial.ego_boxes), len(trial.cav_boxes), 3, 2, 2)
    assert (m.precision, m.recall, m.ad) == (1.0, pytest.approx(2 / 3), pytest.approx(0.0))
    assert m.rre == pytest.approx(2.0) and m.rte == pytest.approx(0.5)
    assert (m.runtime_s, m.margin, m.estimated) == (0.25, 1.0, True)


def test_evaluate_is_duck_typed_and_scores_no_pose_when_none_was_estimated():
    trial = _trial()
    wrong = np.array([[trial.gt_pairs[0, 0], trial.gt_pairs[1, 1]]])
    m = evaluate(SimpleNamespace(pairs=wrong, transform=trial.init, estimated=False), trial)
    assert (m.n_matched, m.n_correct, m.precision) == (1, 0, 0.0)
    assert m.ad == pytest.approx(10.0 * abs(trial.ego_ids[wrong[0, 0]] - trial.cav_ids[wrong[0, 1]]))
    assert math.isnan(m.rre) and math.isnan(m.rte) and math.isnan(m.runtime_s) and math.isnan(m.margin)


def _metrics(n_matched, n_correct, n_true, ad=0.0, rre=0.0, rte=0.0, runtime_s=0.1, estimated=True):
    return TrialMetrics(n_ego=10, n_cav=10, n_true=n_true, n_matched=n_matched, n_correct=n_correct,
                        precision=n_correct / n_matched if n_matched else math.nan,
                        recall=n_correct / n_true if n_true else math.nan, ad=ad, rre=rre, rte=rte,
                        runtime_s=runtime_s, margin=0.0, estimated=estimated)


def test_aggregate_is_a_micro_average_which_differs_from_the_macro_average():
    a = _metrics(n_matched=1, n_correct=1, n_true=2, ad=0.0, rre=0.5, rte=0.2, runtime_s=0.1)
    b = _metrics(n_matched=9, n_correct=0, n_true=8, ad=2.0, rre=3.0, rte=0.5, runtime_s=0.3)
    c = _metrics(n_matched=0, n_correct=0, n_true=0, ad=math.nan, rre=math.nan, rte=math.nan, runtime_s=0.2,
                 estimated=False)
    agg = aggregate([a, b, c])
    assert agg["precision"] == pytest.approx(1 / 10)
    assert np.nanmean([m.precision for m in (a, b, c)]) == pytest.approx(0.5)
    assert agg["recall"] == pytest.approx(1 / 10)
    assert agg["ad"] == pytest.approx((0 * 1 + 2.0 * 9) / 10)
    assert (agg["rre_mean"], agg["rre_median"]) == (pytest.approx(1.75), pytest.approx(1.75))
    assert (agg["rte_mean"], agg["rte_median"]) == (pytest.approx(0.35), pytest.approx(0.35))
    assert agg["success_rate"] == pytest.approx(1 / 3)
    assert aggregate([a, replace(b, rre=1.5), c])["success_rate_2"] == pytest.approx(2 / 3)
    assert (agg["n_trials"], agg["n_estimated"], agg["runtime_median_s"]) == (3, 2, pytest.approx(0.2))


def test_aggregate_of_nothing_is_nan_not_zero():
    agg = aggregate([])
    assert agg["n_trials"] == 0
    assert all(math.isnan(agg[k]) for k in ("precision", "recall", "ad", "rre_mean", "rte_median", "success_rate"))
    nothing_matched = aggregate([replace(_metrics(0, 0, 3, ad=math.nan), estimated=False)])
    assert math.isnan(nothing_matched["precision"]) and nothing_matched["recall"] == 0.0


@pytest.mark.parametrize("chosen", [[], [0], [0, 1], [1, 2, 3]])
def test_evaluate_counts_precision_and_recall_as_the_functions_do(chosen):
    """``evaluate`` counts the correct pairs once for both ratios: the same numbers as ``precision``
    and ``recall`` (NaN included), whatever the pairs."""
    trial = _trial()
    candidates = np.array([trial.gt_pairs[0], [trial.gt_pairs[0, 0], trial.gt_pairs[1, 1]], trial.gt_pairs[2],
                           [trial.gt_pairs[1, 0], trial.gt_pairs[2, 1]]])
    pairs = candidates[chosen].reshape(-1, 2)
    for truth in (trial.gt_pairs, np.zeros((0, 2), int)):
        result = SimpleNamespace(pairs=pairs, transform=trial.init, estimated=False)
        m = evaluate(result, replace(trial, gt_pairs=truth))
        expected = (precision(pairs, truth), recall(pairs, truth))
        assert np.array_equal((m.precision, m.recall), expected, equal_nan=True)
