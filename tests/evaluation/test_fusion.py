"""Late fusion and AP (evaluation.fusion, evaluation.ap): rotated BEV IoU against shapely, NMS, AP on hand-made
cases, the seeded score model, and the ordering none < cbm <= oracle on a small run."""
from __future__ import annotations

import json

import numpy as np
import pytest
from shapely.geometry import Polygon

import evaluation
from cbm import se2
from evaluation.aggregates import fused_ap
from evaluation.ap import average_precision, corners, iou_matrix, match_detections, pooled_ap, voc_ap
from evaluation.fusion import detection_scores, fuse, ground_truth, nms
from evaluation.scenario import ScenarioParams, make_trial
from evaluation.sweep import Sweep


def box(x: float, y: float, yaw: float = 0.0, length: float = 4.0, width: float = 2.0) -> list[float]:
    return [x, y, 0.0, length, width, 1.5, yaw]


def test_rotated_iou_agrees_with_shapely_on_random_boxes() -> None:
    rng = np.random.default_rng(0)
    a = np.column_stack([rng.uniform(-3, 3, (60, 2)), np.zeros(60), rng.uniform(0.5, 5, (60, 2)),
                         np.ones(60), rng.uniform(-np.pi, np.pi, 60)])
    b = a.copy()
    b[:, :2] += rng.normal(0, 1.0, (60, 2))
    b[:, 6] += rng.normal(0, 0.5, 60)
    ours = iou_matrix(a, b)
    pa, pb = [Polygon(c) for c in corners(a)], [Polygon(c) for c in corners(b)]
    expected = np.array([[p.intersection(q).area / p.union(q).area for q in pb] for p in pa])
    assert np.abs(ours - expected).max() < 1e-9
    assert (expected > 0.1).sum() > 40


def test_iou_of_a_box_with_itself_is_one_and_with_a_far_box_zero() -> None:
    boxes = np.array([box(0, 0, 0.3), box(20, 0)])
    assert iou_matrix(boxes, boxes) == pytest.approx(np.eye(2))
    assert iou_matrix(np.array([box(0, 0)]), np.array([box(2, 0)]))[0, 0] == pytest.approx(4 / 12)


def test_nms_keeps_the_best_of_overlapping_boxes_and_every_separate_one() -> None:
    boxes = np.array([box(0, 0), box(0.3, 0.1, 0.05), box(10, 0), box(3.5, 0)])
    kept = nms(boxes, np.array([0.6, 0.9, 0.5, 0.4]))
    assert kept.tolist() == [1, 2, 3]


def test_matching_claims_each_ground_truth_once_in_score_order() -> None:
    truth = np.array([box(0, 0), box(10, 0)])
    detections = np.array([box(0.1, 0), box(0, 0.05), box(30, 0)])
    hits = match_detections(detections, np.array([0.5, 0.9, 0.8]), truth, 0.7)
    assert hits.tolist() == [False, True, False]


def test_ap_is_one_for_perfect_detections_and_follows_the_all_point_envelope() -> None:
    assert average_precision([0.9, 0.8], [True, True], 2) == pytest.approx(1.0)
    # TP, FP, TP against 3 boxes: recall 1/3 at precision 1, 2/3 at 2/3.
    assert average_precision([0.9, 0.8, 0.7], [True, False, True], 3) == pytest.approx(1 / 3 + 2 / 9)
    assert voc_ap(np.array([0.5, 0.5, 1.0]), np.array([1.0, 0.5, 2 / 3])) == pytest.approx(0.5 + 0.5 * 2 / 3)
    assert np.isnan(average_precision([0.9], [False], 0))


def test_pooled_ap_sorts_detections_over_the_whole_run() -> None:
    frames = [([(0.9, True, True), (0.2, False, False)], 1), ([(0.8, True, False)], 1)]
    ap = pooled_ap(frames)
    assert ap[0.5] == pytest.approx(1.0)
    assert ap[0.7] == pytest.approx(0.5)


def make_range_trial(sigma_p: float = 0.2) -> tuple:
    rng = np.random.default_rng(4)
    grid = np.stack(np.meshgrid(np.arange(5), np.arange(5)), axis=-1).reshape(-1, 2) * 12.0
    world = np.column_stack([grid + rng.uniform(-2, 2, (25, 2)), np.zeros(25), np.full(25, 4.5), np.full(25, 1.9),
                             np.full(25, 1.6), rng.uniform(-np.pi, np.pi, 25)])
    ids = np.arange(25)
    params = ScenarioParams(protocol="range", sigma_p=sigma_p, sigma_theta=1.0, sensor_range=40.0)
    trial = make_trial(world, ids, params, ego_pose=se2.make(10, 20, 0.3), cav_pose=se2.make(40, 35, -1.0), rng=rng)
    return trial, se2.apply_boxes(se2.inverse(trial.ego_pose), world), ids


def test_scores_are_seeded_and_fall_with_the_detection_error() -> None:
    trial, _, _ = make_range_trial(sigma_p=0.5)
    ego, cav = detection_scores(trial, 3, 7)
    again = detection_scores(trial, 3, 7)
    assert np.array_equal(ego, again[0]) and np.array_equal(cav, again[1])
    assert not np.array_equal(ego, detection_scores(trial, 4, 7)[0])
    assert ((0 < ego) & (ego < 1)).all() and len(cav) == len(trial.cav_boxes)
    error = np.linalg.norm(trial.ego_boxes[:, :2] - trial.ego_true_xy, axis=1)
    assert np.corrcoef(error, ego)[0, 1] < 0


def test_fusion_at_the_true_pose_removes_the_duplicates_of_co_visible_objects() -> None:
    trial, boxes, ids = make_range_trial(sigma_p=0.0)
    scores = detection_scores(trial, 0, 0)
    truth = ground_truth(trial, boxes, ids)
    assert len(truth) == len(set(trial.ego_ids) | set(trial.cav_ids)) and len(trial.gt_pairs) > 2
    right = fuse(trial, trial.T_true, scores)
    assert len(right.boxes) == len(truth)
    assert match_detections(right.boxes, right.scores, truth, 0.7).all()
    wrong = fuse(trial, trial.init, scores)
    assert (~match_detections(wrong.boxes, wrong.scores, truth, 0.7)).sum() >= len(trial.gt_pairs)


def test_a_sweep_rejects_an_unknown_fusion() -> None:
    with pytest.raises(ValueError, match="fusion"):
        Sweep(methods=("cbm",), fusion="mean")


def test_fused_ap_orders_none_below_cbm_at_or_below_oracle() -> None:
    table = evaluation.run(["argoverse2"], methods=("none", "cbm", "oracle"), protocol="range", seed=0,
                           frames=lambda n: range(0, n, 40), grid={"sigma_p": (0.2,), "sigma_theta": (2.0,)},
                           fusion="nms")
    rows = table.to_dicts()
    assert all(isinstance(json.loads(row["fused"]), list) and row["n_gt"] > 0 for row in rows)
    ap = fused_ap(rows, [row["method"] for row in rows])
    assert 1.3 * ap["none"][0.7] < ap["cbm"][0.7] <= ap["oracle"][0.7] + 0.01
    assert 1.3 * ap["none"][0.5] < ap["cbm"][0.5] <= ap["oracle"][0.5] + 0.01
