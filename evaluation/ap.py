"""Detection average precision in the bird's-eye view, with OpenCOOD's conventions
(``opencood/utils/eval_utils.py``).

Per frame (``match_detections``, OpenCOOD's ``caluclate_tp_fp``): the detections, highest score
first, each take the unclaimed ground-truth box of highest BEV IoU; a detection is a true positive
when that IoU is at least the threshold (the box is then claimed), a false positive otherwise.
Over a run (``average_precision``, OpenCOOD's ``calculate_ap`` with ``global_sort_detections``):
every detection of every frame is sorted by score, precision and recall are accumulated down the
list against the total ground-truth count, and AP is the area under the precision envelope at
every recall step -- VOC 2010 all-point interpolation (``voc_ap``), not the 11-point VOC 2007 one.
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

IOU_THRESHOLDS = (0.5, 0.7)
"""BEV IoU thresholds reported (OpenCOOD also reports 0.3; the paper's Table II uses 0.7)."""


def corners(boxes: np.ndarray) -> np.ndarray:
    """(N, 4, 2) BEV corners, counter-clockwise, of ``(N, 7)`` boxes ``x, y, z, l, w, h, yaw``."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 7)
    half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=float) * 0.5
    local = half[None] * boxes[:, None, 3:5]
    c, s = np.cos(boxes[:, 6])[:, None], np.sin(boxes[:, 6])[:, None]
    x = c * local[..., 0] - s * local[..., 1] + boxes[:, None, 0]
    y = s * local[..., 0] + c * local[..., 1] + boxes[:, None, 1]
    return np.stack([x, y], axis=-1)


def _clip(subject: list[np.ndarray], a: np.ndarray, b: np.ndarray) -> list[np.ndarray]:
    """Sutherland-Hodgman: the part of polygon ``subject`` left of the directed edge ``a -> b``."""
    def side(p: np.ndarray) -> float:
        return float((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]))

    out: list[np.ndarray] = []
    for k, current in enumerate(subject):
        previous = subject[k - 1]
        s_cur, s_prev = side(current), side(previous)
        if (s_cur >= 0) != (s_prev >= 0):
            out.append(previous + (current - previous) * (s_prev / (s_prev - s_cur)))
        if s_cur >= 0:
            out.append(current)
    return out


def _area(polygon: Sequence[np.ndarray]) -> float:
    if len(polygon) < 3:
        return 0.0
    p = np.asarray(polygon)
    return 0.5 * abs(float(np.dot(p[:, 0], np.roll(p[:, 1], -1)) - np.dot(p[:, 1], np.roll(p[:, 0], -1))))


def intersection_area(p: np.ndarray, q: np.ndarray) -> float:
    """Area of the intersection of two convex counter-clockwise quads ``(4, 2)``."""
    polygon = list(p)
    for k in range(4):
        polygon = _clip(polygon, q[k], q[(k + 1) % 4])
        if not polygon:
            return 0.0
    return _area(polygon)


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(Na, Nb) rotated BEV IoU of two sets of ``(N, 7)`` boxes; pairs whose circumcircles are
    apart are 0 without clipping."""
    a, b = np.asarray(a, dtype=float).reshape(-1, 7), np.asarray(b, dtype=float).reshape(-1, 7)
    out = np.zeros((len(a), len(b)))
    if not len(a) or not len(b):
        return out
    ca, cb = corners(a), corners(b)
    area_a, area_b = a[:, 3] * a[:, 4], b[:, 3] * b[:, 4]
    reach = 0.5 * (np.hypot(a[:, 3], a[:, 4])[:, None] + np.hypot(b[:, 3], b[:, 4])[None])
    near = np.linalg.norm(a[:, None, :2] - b[None, :, :2], axis=2) < reach
    for i, j in zip(*np.nonzero(near)):
        inter = intersection_area(ca[i], cb[j])
        union = area_a[i] + area_b[j] - inter
        out[i, j] = inter / union if union > 0 else 0.0
    return out


def match_detections(boxes: np.ndarray, scores: np.ndarray, truth: np.ndarray, threshold: float) -> np.ndarray:
    """True-positive flag of each detection (input order) at BEV IoU ``threshold``: greedy in
    descending score, each ground-truth box claimed at most once."""
    hits = np.zeros(len(boxes), dtype=bool)
    if not len(boxes) or not len(truth):
        return hits
    ious = iou_matrix(boxes, truth)
    free = np.ones(len(truth), dtype=bool)
    for k in np.argsort(-np.asarray(scores), kind="stable"):
        candidates = np.where(free, ious[k], -1.0)
        best = int(np.argmax(candidates))
        if candidates[best] >= threshold:
            hits[k], free[best] = True, False
    return hits


def voc_ap(recall: np.ndarray, precision: np.ndarray) -> float:
    """VOC 2010 all-point AP: the area under the monotone envelope of precision over recall."""
    mrec = np.concatenate([[0.0], recall, [1.0]])
    mpre = np.concatenate([[0.0], precision, [0.0]])
    mpre = np.maximum.accumulate(mpre[::-1])[::-1]
    steps = np.flatnonzero(mrec[1:] != mrec[:-1]) + 1
    return float(np.sum((mrec[steps] - mrec[steps - 1]) * mpre[steps]))


def average_precision(scores: Sequence[float], hits: Sequence[bool], n_truth: int) -> float:
    """AP of detections pooled over a run (``scores``, true-positive flags ``hits``) against
    ``n_truth`` ground-truth boxes: sorted by score over the whole run, then ``voc_ap``. NaN
    without ground truth."""
    if n_truth <= 0:
        return float("nan")
    order = np.argsort(-np.asarray(scores, dtype=float), kind="stable")
    tp = np.cumsum(np.asarray(hits, dtype=float)[order])
    fp = np.cumsum(1.0 - np.asarray(hits, dtype=float)[order])
    recall = tp / n_truth
    precision = tp / np.maximum(tp + fp, 1e-12)
    return voc_ap(recall, precision)


def pooled_ap(frames: Iterable[tuple[Sequence[tuple[float, bool, bool]], int]]) -> dict[float, float]:
    """AP at each of ``IOU_THRESHOLDS`` over frames given as (detections ``(score, tp@0.5,
    tp@0.7)``, ground-truth count)."""
    scores: list[float] = []
    flags: list[tuple[bool, bool]] = []
    n_truth = 0
    for detections, count in frames:
        scores.extend(d[0] for d in detections)
        flags.extend((bool(d[1]), bool(d[2])) for d in detections)
        n_truth += int(count)
    return {t: average_precision(scores, [f[k] for f in flags], n_truth) for k, t in enumerate(IOU_THRESHOLDS)}
