"""Late fusion after calibration, as OpenCOOD's late fusion does it: the CAV's boxes are moved
into the ego frame with a method's CAV->ego transform, merged with the ego's, and duplicates
suppressed by non-maximum suppression on rotated BEV IoU (``NMS_IOU``, OpenCOOD's ``nms_thresh``).
The fused boxes are then scored against the ground truth either agent sees (``evaluation.ap``).

Scores. A detector's boxes carry their own; the simulated detections (noisy ground truth, sec.
IV-A) get them from a seeded score model (``detection_scores``): each detection's score is
``sigmoid(SCORE_BIAS - SCORE_SLOPE * e + SCORE_SPREAD * z)`` with ``e`` its centre error in metres
against its object (in its own agent's frame, so the score does not depend on the calibration)
and ``z`` a standard normal drawn from ``numpy.random.default_rng([seed, frame, SCORE_STREAM])``,
ego detections first, then the CAV's -- the trial's own draws (``evaluation.scenario``) are untouched.
Noisy ground truth has no false positives of its own: the fused false positives are misplaced or
duplicated boxes.
"""
from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from cbm import se2

from .ap import IOU_THRESHOLDS, iou_matrix, match_detections
from .scenario import FrameInputs, Trial

FUSIONS = ("nms",)
"""Late-fusion schemes (``--fusion``): ``nms``, the only one, OpenCOOD's."""
NMS_IOU = 0.15
"""BEV IoU above which a lower-scored box is suppressed (OpenCOOD's late-fusion ``nms_thresh``)."""
SCORE_BIAS = 2.0
SCORE_SLOPE = 2.0
"""Logit lost per metre of centre error."""
SCORE_SPREAD = 1.0
SCORE_STREAM = 1
"""Third word of the score model's seed: a stream apart from the trial's ``trial_rng(seed, frame)``."""
FUSION_COLUMNS = ("n_gt", "fused")
"""Per-trial columns of a run with late fusion: the ground-truth count and the fused detections as
JSON ``[[score, tp@0.5, tp@0.7], ...]`` (highest score first): what AP over a run is pooled from."""


@dataclass(frozen=True)
class Fused:
    """The fused boxes of one trial, in the ego frame, highest score first."""

    boxes: np.ndarray
    """(M, 7) kept boxes."""
    scores: np.ndarray
    """(M,) their scores."""
    agent: np.ndarray
    """(M,) ``"ego"`` or ``"cav"``: whose detection each box is."""


def nms(boxes: np.ndarray, scores: np.ndarray, threshold: float = NMS_IOU) -> np.ndarray:
    """Indices of the boxes kept by greedy NMS on rotated BEV IoU, highest score first."""
    order = np.argsort(-np.asarray(scores, dtype=float), kind="stable")
    ious = iou_matrix(boxes, boxes)
    kept: list[int] = []
    for k in order:
        if all(ious[k, j] <= threshold for j in kept):
            kept.append(int(k))
    return np.array(kept, dtype=np.int64)


def detection_scores(trial: Trial, seed: int, frame_index: int) -> tuple[np.ndarray, np.ndarray]:
    """Scores of the ego's and the CAV's detections under the seeded score model (module docstring)."""
    ego_error = np.linalg.norm(trial.ego_boxes[:, :2] - trial.ego_true_xy, axis=1)
    cav_error = np.linalg.norm(se2.apply_points(trial.T_true, trial.cav_boxes[:, :2]) - trial.cav_true_xy, axis=1)
    draws = np.random.default_rng([seed, frame_index, SCORE_STREAM]).standard_normal(len(ego_error) + len(cav_error))
    logits = SCORE_BIAS - SCORE_SLOPE * np.concatenate([ego_error, cav_error]) + SCORE_SPREAD * draws
    scores = 1.0 / (1.0 + np.exp(-logits))
    return scores[:len(ego_error)], scores[len(ego_error):]


def fuse(trial: Trial, transform: np.ndarray, scores: tuple[np.ndarray, np.ndarray],
         threshold: float = NMS_IOU) -> Fused:
    """Late fusion: the CAV's boxes placed by ``transform`` (CAV->ego), merged with the ego's,
    duplicates suppressed by ``nms``. ``scores``: (ego, CAV) detection scores."""
    boxes = np.concatenate([trial.ego_boxes, se2.apply_boxes(transform, trial.cav_boxes)]).reshape(-1, 7)
    merged = np.concatenate([np.asarray(scores[0], float), np.asarray(scores[1], float)])
    agent = np.array(["ego"] * len(trial.ego_boxes) + ["cav"] * len(trial.cav_boxes), dtype=object)
    kept = nms(boxes, merged, threshold)
    return Fused(boxes[kept], merged[kept], agent[kept])


def ground_truth(trial: Trial, boxes: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """(G, 7) true boxes of the objects either agent sees: ``boxes`` (every object of the frame,
    in the ego frame) whose ``ids`` one of the agents detected."""
    seen = np.concatenate([trial.ego_ids, trial.cav_ids]).astype(str)
    return np.asarray(boxes, dtype=float).reshape(-1, 7)[np.isin(np.asarray(ids).astype(str), seen)]


def true_positives(fused: Fused, truth: np.ndarray) -> dict[float, np.ndarray]:
    """Each fused box's true-positive flag at every IoU threshold of ``evaluation.ap``."""
    return {t: match_detections(fused.boxes, fused.scores, truth, t) for t in IOU_THRESHOLDS}


def fusion_pose(method: str, result: Any, trial: Trial) -> np.ndarray:
    """The CAV->ego transform a method's boxes are fused with: its estimate, except for ``oracle``,
    which fuses at the true pose (the ceiling of the paper's Table II; its estimate, a fit to the
    noisy true pairs, can fall a little short of it or beat it by chance)."""
    return trial.T_true if method == "oracle" else result.transform


def fusion_columns(trial: Trial, transform: np.ndarray, frame: FrameInputs, seed: int) -> dict[str, Any]:
    """The ``FUSION_COLUMNS`` of one trial: late fusion with ``transform`` (a method's estimate),
    scored against the frame's ground truth."""
    world = frame.trial
    truth = ground_truth(trial, se2.apply_boxes(se2.inverse(trial.ego_pose), np.asarray(world["boxes"], float)),
                         world["ids"])
    fused = fuse(trial, transform, detection_scores(trial, seed, frame.index))
    hits = true_positives(fused, truth)
    detections = [[round(float(s), 6), *(int(hits[t][k]) for t in IOU_THRESHOLDS)] for k, s in enumerate(fused.scores)]
    return {"n_gt": len(truth), "fused": json.dumps(detections, separators=(",", ":"))}


def decoded(row: Mapping[str, Any]) -> tuple[list[tuple[float, bool, bool]], int]:
    """A row's fused detections and ground-truth count, as ``evaluation.ap.pooled_ap`` takes them."""
    return [tuple(d) for d in json.loads(row["fused"])], int(row["n_gt"])


def fused_against_truth(trial: Trial, transform: np.ndarray, boxes: np.ndarray, ids: np.ndarray, seed: int,
                        frame_index: int, threshold: float = IOU_THRESHOLDS[-1]) -> tuple[Fused, np.ndarray]:
    """The fused boxes of ``trial`` under ``transform`` and whether each is a true positive at
    BEV IoU ``threshold`` against the objects either agent sees (``boxes``, ``ids``: every object
    of the frame, ego frame), the scores from the seeded score model: what the app draws."""
    fused = fuse(trial, transform, detection_scores(trial, seed, frame_index))
    return fused, match_detections(fused.boxes, fused.scores, ground_truth(trial, boxes, ids), threshold)
