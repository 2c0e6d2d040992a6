"""FreeAlign: boxes matched as a common subgraph of the two agents' distance graphs, then an SE(2) fit.

Lu et al., "Robust collaborative perception without external localization and clock devices"
(ICRA 2024). Written from the paper and checked against the behaviour of the public code
(MediaBrain-SJTU/FreeAlign, ``freealign/match/match_v7_with_detection.py``, its box-only matcher);
the parameters are that code's: ``anchor_error = 0.3`` m, ``box_error = 0.5`` m and ``min_anchors =
3`` (its pose function's; its command line uses 5). The learned variant (a graph network on box
features) is left out: here the boxes alone decide, as in the public box matcher.

Each agent's graph has its boxes as nodes and the distances between their centres as edges: the
same for both agents whatever their poses, so no prior is needed. ``init`` is only the fallback
when no subgraph is found.
"""
from __future__ import annotations

from dataclasses import dataclass
from time import perf_counter

import numba
import numpy as np
from scipy.spatial.distance import cdist

from ..estimate import weighted_procrustes
from ..inputs import check_at_most, check_positive, checked_boxes, checked_transform
from ..result import MatchResult
from ._common import check_count, check_params, make_result

START_ERROR = 100.0
"""The public code's starting error of a match: its score is (100 + summed residuals) / size^2, so a
larger subgraph wins over any smaller one, and among equals the more consistent."""


@dataclass(frozen=True)
class FreeAlignParams:
    """Parameters of FreeAlign's box matcher; defaults are the public code's."""

    anchor_error: float = 0.3
    """Metres. A pair joins the anchors when its distances to the seed differ by less than this, and
    its edges to every anchor by less than twice this."""
    box_error: float = 0.5
    """Metres. After the anchors, a pair joins when its distances to the seed differ by less than
    this and its edges to every anchor by less than this."""
    min_anchors: int = 3
    """A seed needs at least this many anchors; the best subgraph must be larger than this."""
    max_boxes: int = 100
    """Each agent's nearest boxes matched (ours: the search compares every pair of boxes with every
    other, n^4 work: 1 s at 100 boxes per agent, 10-20 s at 200; the public code matches one
    detector's output, tens of boxes)."""

    def __post_init__(self) -> None:
        check_positive(self, "anchor_error", "box_error")
        check_count(self, "min_anchors", 2)
        check_count(self, "max_boxes", 3)
        check_at_most(self, {"anchor_error": 5.0, "box_error": 5.0, "min_anchors": 50, "max_boxes": 200})


def match_freealign(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
                    params: FreeAlignParams | None = None) -> MatchResult:
    """Match the boxes as the largest consistent common subgraph, then fit the pose to its centres.

    For every seed pair (i, j), ego box i and CAV box j, compare their distance rows:
    ``D[a, b] = |d(i, a) - d'(j, b)|``.
    1. Anchors: from the smallest entry, try each entry below ``anchor_error`` as the second anchor,
       then add, smallest first, every other such entry whose boxes are still free and whose edges to
       all anchors agree within ``2 anchor_error`` (``|d(a, a_k) - d'(b, b_k)|``); keep the largest
       set. (The public code takes the entries in index order; by size, the answer does not depend
       on the order in which the boxes are listed.) Every box is in one pair at most.
    2. Growth: with at least ``min_anchors`` anchors, take the smallest remaining entries below
       ``box_error`` one by one; each joins when its edges to every anchor agree within ``box_error``.
    3. Score (100 + summed growth residuals) / size^2; the best over all seeds, larger than ``min_anchors``.
    4. Pose: least-squares SE(2) fit of the matched centres (``init`` when nothing matched).
    Only each agent's ``max_boxes`` nearest boxes take part.
    """
    params = check_params(params, FreeAlignParams)
    ego_boxes, cav_boxes = checked_boxes("ego_boxes", ego_boxes), checked_boxes("cav_boxes", cav_boxes)
    init = checked_transform("init", init)
    t0 = perf_counter()
    ego_kept, cav_kept = nearest(ego_boxes, params.max_boxes), nearest(cav_boxes, params.max_boxes)
    pairs = common_subgraph(ego_boxes[ego_kept, :2], cav_boxes[cav_kept, :2], params)
    pairs = np.column_stack([ego_kept[pairs[:, 0]], cav_kept[pairs[:, 1]]])
    t1 = perf_counter()
    T = weighted_procrustes(cav_boxes[pairs[:, 1], :2], ego_boxes[pairs[:, 0], :2]) if len(pairs) >= 2 else init
    t2 = perf_counter()
    return make_result(ego_boxes, cav_boxes, pairs, T, init, {"subgraph": t1 - t0, "fit": t2 - t1, "total": t2 - t0},
                       layout=True)


def nearest(boxes: np.ndarray, count: int) -> np.ndarray:
    """Indices of the ``count`` boxes nearest their agent (its origin), nearest first."""
    return np.argsort(np.hypot(boxes[:, 0], boxes[:, 1]), kind="stable")[:count]


def common_subgraph(ego_xy: np.ndarray, cav_xy: np.ndarray, params: FreeAlignParams) -> np.ndarray:
    """(K, 2) pairs (ego index, CAV index) of the best common subgraph; empty when there is none."""
    if len(ego_xy) <= 2 or len(cav_xy) <= 2:
        return np.empty((0, 2), dtype=np.int64)
    return _best_subgraph(cdist(ego_xy, ego_xy), cdist(cav_xy, cav_xy), float(params.anchor_error),
                          float(params.box_error), int(params.min_anchors))


@numba.njit(cache=True, nogil=True)
def _best_subgraph(g1, g2, anchor_error, box_error, min_anchors):
    """Step 3 over every seed (i, j): for each ego box i the best j, then the best i."""
    best = np.empty((0, 2), dtype=np.int64)
    best_error = START_ERROR
    for i in range(g1.shape[0]):
        match, error = np.empty((0, 2), dtype=np.int64), START_ERROR
        for j in range(g2.shape[0]):
            found, found_error = _seed_match(g1, g2, i, j, anchor_error, box_error, min_anchors)
            if len(found) >= min_anchors and found_error <= error:
                match, error = found, found_error
        if len(match) > min_anchors and error <= best_error:
            best, best_error = match, error
    return best


@numba.njit(cache=True, nogil=True)
def _agrees(g1, g2, anchors, count, a, b, tolerance):
    """Whether the edges from (a, b) to each of the first ``count`` anchors agree within ``tolerance``."""
    for k in range(count):
        if abs(g1[anchors[k, 0], a] - g2[anchors[k, 1], b]) >= tolerance:
            return False
    return True


@numba.njit(cache=True, nogil=True)
def _anchors(D, g1, g2, anchor_error):
    """Step 1: the largest anchor set grown from the smallest entry of ``D`` (one-to-one)."""
    n1, n2 = D.shape
    flat = np.argmin(D)
    seed_a, seed_b = flat // n2, flat % n2
    candidates = np.argwhere(D < anchor_error)
    candidates = candidates[np.argsort(_entries(D, candidates), kind="mergesort")]
    best = np.empty((1, 2), dtype=np.int64)
    best[0, 0], best[0, 1] = seed_a, seed_b
    anchors = np.empty((min(n1, n2), 2), dtype=np.int64)
    for c in range(len(candidates)):
        second_a, second_b = candidates[c, 0], candidates[c, 1]
        if second_a == seed_a or second_b == seed_b:
            continue
        used_a, used_b = np.zeros(n1, dtype=np.bool_), np.zeros(n2, dtype=np.bool_)
        anchors[0, 0], anchors[0, 1], anchors[1, 0], anchors[1, 1] = seed_a, seed_b, second_a, second_b
        used_a[seed_a] = used_a[second_a] = True
        used_b[seed_b] = used_b[second_b] = True
        count = 2
        for k in range(len(candidates)):
            a, b = candidates[k, 0], candidates[k, 1]
            if not used_a[a] and not used_b[b] and _agrees(g1, g2, anchors, count, a, b, 2.0 * anchor_error):
                anchors[count, 0], anchors[count, 1] = a, b
                used_a[a], used_b[b] = True, True
                count += 1
        if count > len(best):
            best = anchors[:count].copy()
    return best


@numba.njit(cache=True, nogil=True)
def _entries(D, positions):
    """``D`` at each (row, column) of ``positions``."""
    out = np.empty(len(positions))
    for k in range(len(positions)):
        out[k] = D[positions[k, 0], positions[k, 1]]
    return out


@numba.njit(cache=True, nogil=True)
def _seed_match(g1, g2, i, j, anchor_error, box_error, min_anchors):
    """Steps 1-2 for the seed (i, j): the matched pairs and their score (``START_ERROR`` when too few anchors).

    Growth visits the entries below ``box_error`` smallest first, as the public code's repeated
    minimum does: an entry of a box already paired is never the minimum, a rejected one uses up one
    of the ``min(n1, n2) - anchors`` visits."""
    D = np.abs(g1[i][:, None] - g2[j][None, :])
    anchors = _anchors(D, g1, g2, anchor_error)
    if len(anchors) < min_anchors:
        return anchors, START_ERROR
    n1, n2 = D.shape
    used_a, used_b = np.zeros(n1, dtype=np.bool_), np.zeros(n2, dtype=np.bool_)
    for k in range(len(anchors)):
        used_a[anchors[k, 0]], used_b[anchors[k, 1]] = True, True
    entries = np.argwhere(D < box_error)
    entries = entries[np.argsort(_entries(D, entries), kind="mergesort")]
    grown = np.empty((min(n1, n2), 2), dtype=np.int64)
    grown[:len(anchors)] = anchors
    count, error, visits = len(anchors), START_ERROR, min(n1, n2) - len(anchors)
    for k in range(len(entries)):
        if visits == 0:
            break
        a, b = entries[k, 0], entries[k, 1]
        if used_a[a] or used_b[b]:
            continue
        visits -= 1
        if _agrees(g1, g2, anchors, len(anchors), a, b, box_error):
            grown[count, 0], grown[count, 1] = a, b
            count += 1
            error += D[a, b]
            used_a[a], used_b[b] = True, True
    return grown[:count].copy(), error / count ** 2
