"""V2X-Reg++ (V2I-Calib): object-level registration without a prior, from single box correspondences.

Qu et al., "V2I-Calib: A novel calibration approach for collaborative vehicle and road infrastructure
LiDAR" (IROS 2024) and its extension V2X-Reg++ (T-ITS 2025). Written from the papers and checked
against the behaviour of the public code (MassimoQu/v2i-calib: ``calib/filters/pipeline.py``,
``v2x_calib/corresponding/BoxesMatch.py``, ``CorrespondingDetector.py``), whose
``configs/pipeline.yaml`` defaults we follow where code and paper differ: the affinity from centre
and vertex distances (the paper's oIoU is an option here), ``top_k = 10``, ``filter_threshold = 4``
and no prior (``prior_weight = 0``).

Everything is in the bird's-eye view, as for every method here: a pose is SE(2), a box's corners
are its footprint's four. The code's 3-D SVD of one box's eight corners onto another's reduces, on
the footprint, to the difference of the two boxes' yaws and centres (the corners' centroid is the
centre; their cross-covariance turns by the yaw difference whatever the sizes). Box confidences
are 1 (the boxes reaching a method carry no score).
"""
from __future__ import annotations

from dataclasses import dataclass
from time import perf_counter
from typing import Literal

import numpy as np
from scipy.optimize import linear_sum_assignment

from .. import se2
from ..estimate import weighted_procrustes
from ..inputs import check_at_most, check_positive, checked_boxes, checked_transform
from ..result import MatchResult
from ._common import as_labels, check_count, check_params, make_result

Affinity = Literal["distance", "oiou"]

PRIORITY = ("bus", "truck", "car")
"""``priority_categories``: boxes of these kinds, in this order, are kept first (then the others)."""
KIND_WORDS = {
    "bus": ("bus",),
    "truck": ("truck", "trailer", "van", "large_vehicle"),
    "car": ("car", "vehicle", "suv", "pickup", "sedan"),
    "small": ("pedestrian", "person", "walker", "cyclist", "bicycl", "motorcycl", "tricycl", "scooter", "rider",
              "cone", "barrow", "barrier", "bollard"),
}
"""Words by which a dataset's category name is read as one of the code's kinds (first match wins, in
this order; a name with none of them is ``detected``, the code's kind for a class-less detector)."""
MATCH_DISTANCE = {"bus": 1.5, "truck": 1.5, "car": 1.0, "small": 0.5, "detected": 1.0}
"""Metres, ``distance_thresholds`` by kind: two boxes closer than this match under a hypothesis."""


@dataclass(frozen=True)
class V2XRegParams:
    """Parameters of V2X-Reg++; defaults are the public code's ``configs/pipeline.yaml``."""

    top_k: int = 10
    """Boxes kept per agent: the first ``top_k`` by kind (bus, truck, car, then others), then volume;
    at most 100 (every pair is a hypothesis scored against all: top_k^4 work)."""
    max_range: float = 120.0
    """Metres. Boxes farther than this from their own agent are left out first (``distance_m``)."""
    affinity: Affinity = "distance"
    """``distance``: a hypothesis scores the boxes it brings within the kind's match distance, by
    centre and by vertices (the code's default). ``oiou``: the boxes it makes overlap (V2I-Calib)."""
    distance_scale: float = 1.0
    """Multiplies every kind's match distance (1.5 m bus/truck/van, 1.0 m car, 0.5 m small objects)."""
    filter_threshold: int = 4
    """Matches scoring at least this are kept when the best scores above 5; else only the best-scoring
    ones (``thresholdRetained``)."""

    def __post_init__(self) -> None:
        check_count(self, "top_k", 1)
        check_count(self, "filter_threshold", 0)
        check_positive(self, "max_range", "distance_scale")
        check_at_most(self, {"top_k": 100, "filter_threshold": 100, "max_range": 500.0, "distance_scale": 10.0})
        if self.affinity not in ("distance", "oiou"):
            raise ValueError(f"V2XRegParams.affinity must be 'distance' or 'oiou', got {self.affinity!r}")


def match_v2xregpp(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
                   params: V2XRegParams | None = None, *, ego_labels: np.ndarray | None = None,
                   cav_labels: np.ndarray | None = None) -> MatchResult:
    """Register the CAV's boxes onto the ego's without using ``init`` (its fallback only).

    1. Filter each agent's boxes: within ``max_range``, sorted by kind priority then volume, first ``top_k``.
    2. Every same-kind pair (i, j) is a pose hypothesis T_ij: box j's corners onto box i's (SVD).
    3. Affinity KP_ij: under T_ij, count the one-to-one same-kind matches within the kind's
       distance, n_c by centres and n_v by vertices (||V_i - V_j||_F / 8 over the eight corners);
       KP_ij = round(((n_c - 1) + (n_v - 1)) / 2). With ``oiou``, KP_ij = (overlapping pairs) - 1.
    4. Hungarian assignment maximising KP; pairs of zero affinity dropped; the retained threshold.
    5. Pose: SVD on the kept pairs' corners, each pair weighted by its KP.
    A single kept pair gives a pose (its corners fix the yaw); none falls back to ``init``.
    """
    params = check_params(params, V2XRegParams)
    ego_boxes, cav_boxes = checked_boxes("ego_boxes", ego_boxes), checked_boxes("cav_boxes", cav_boxes)
    init = checked_transform("init", init)
    ego_kinds = kinds_of(as_labels("ego_labels", ego_labels, len(ego_boxes)), len(ego_boxes))
    cav_kinds = kinds_of(as_labels("cav_labels", cav_labels, len(cav_boxes)), len(cav_boxes))
    t0 = perf_counter()
    ego_kept = kept_boxes(ego_boxes, ego_kinds, params)
    cav_kept = kept_boxes(cav_boxes, cav_kinds, params)
    ego, cav = ego_boxes[ego_kept], cav_boxes[cav_kept]
    t1 = perf_counter()
    KP = affinities(ego, cav, ego_kinds[ego_kept], cav_kinds[cav_kept], params)
    t2 = perf_counter()
    rows, cols, scores = retained_matches(KP, params.filter_threshold)
    T = weighted_corner_fit(ego[rows], cav[cols], scores) if len(rows) else init
    t3 = perf_counter()
    pairs = np.column_stack([ego_kept[rows], cav_kept[cols]])
    timings = {"filter": t1 - t0, "affinity": t2 - t1, "assign_fit": t3 - t2, "total": t3 - t0}
    return make_result(ego_boxes, cav_boxes, pairs, T, init, timings, minimum_pairs=1)


def kinds_of(labels: np.ndarray | None, n: int) -> np.ndarray:
    """Each box's kind (``bus``, ``truck``, ``car``, ``small`` or ``detected``) from its category name."""
    if labels is None:
        return np.full(n, "detected", dtype=object)
    return np.array([kind_of(str(name)) for name in labels], dtype=object)


def kind_of(name: str) -> str:
    """The kind of one category name (``KIND_WORDS``), ``detected`` when no word of it matches."""
    lowered = name.strip().lower()
    for kind, words in KIND_WORDS.items():
        if any(word in lowered for word in words):
            return kind
    return "detected"


def kept_boxes(boxes: np.ndarray, kinds: np.ndarray, params: V2XRegParams) -> np.ndarray:
    """Indices of the boxes the filter keeps, in its order: within range, by kind priority, larger first."""
    near = np.flatnonzero(np.hypot(boxes[:, 0], boxes[:, 1]) <= params.max_range)
    priority = np.array([PRIORITY.index(k) if k in PRIORITY else len(PRIORITY) for k in kinds[near]])
    volume = np.prod(boxes[near, 3:6], axis=1)
    return near[np.lexsort((-volume, priority))][:params.top_k]


def footprint_corners(boxes: np.ndarray) -> np.ndarray:
    """(N, 4, 2) the footprint's corners: front-left, front-right, rear-right, rear-left."""
    signs = np.array([[1.0, 1.0], [1.0, -1.0], [-1.0, -1.0], [-1.0, 1.0]])
    half = signs[None] * boxes[:, None, 3:5] / 2.0
    c, s = np.cos(boxes[:, 6])[:, None], np.sin(boxes[:, 6])[:, None]
    x = c * half[..., 0] - s * half[..., 1] + boxes[:, None, 0]
    y = s * half[..., 0] + c * half[..., 1] + boxes[:, None, 1]
    return np.stack([x, y], axis=-1)


def hypothesis(ego_box: np.ndarray, cav_box: np.ndarray) -> np.ndarray:
    """T_ij: the CAV->ego pose that lays CAV box j's corners onto ego box i's (the corner SVD's answer)."""
    T = se2.make(0.0, 0.0, ego_box[6] - cav_box[6])
    T[:2, 2] = ego_box[:2] - T[:2, :2] @ cav_box[:2]
    return T


def affinities(ego: np.ndarray, cav: np.ndarray, ego_kinds: np.ndarray, cav_kinds: np.ndarray,
               params: V2XRegParams) -> np.ndarray:
    """(Ne, Nc) KP: each same-kind pair's hypothesis scored by the matches it brings about."""
    KP = np.zeros((len(ego), len(cav)))
    same = ego_kinds[:, None] == cav_kinds[None, :]
    limit = np.array([MATCH_DISTANCE[k] for k in cav_kinds]) * params.distance_scale
    ego_corners = footprint_corners(ego)
    for i, j in zip(*np.nonzero(same)):
        moved = se2.apply_boxes(hypothesis(ego[i], cav[j]), cav)
        if params.affinity == "oiou":
            KP[i, j] = int(np.count_nonzero(overlapping(ego, moved) & same)) - 1
            continue
        centre = np.linalg.norm(ego[:, None, :2] - moved[None, :, :2], axis=2)
        vertex = np.sqrt(2.0) * np.linalg.norm(ego_corners[:, None] - footprint_corners(moved)[None], axis=(2, 3)) / 8
        n_c = one_to_one_count(np.where(same & (centre < limit[None, :]), centre, np.inf))
        n_v = one_to_one_count(np.where(same & (vertex < limit[None, :]), vertex, np.inf))
        KP[i, j] = np.round(((n_c - 1) + (n_v - 1)) / 2)
    return KP


def one_to_one_count(distance: np.ndarray) -> int:
    """How many one-to-one pairs of finite distance a greedy pass takes, nearest first."""
    rows, cols = np.nonzero(np.isfinite(distance))
    order = np.argsort(distance[rows, cols], kind="stable")
    used_rows, used_cols = set(), set()
    for r, c in zip(rows[order], cols[order]):
        if r not in used_rows and c not in used_cols:
            used_rows.add(r)
            used_cols.add(c)
    return len(used_rows)


def overlapping(ego: np.ndarray, cav: np.ndarray) -> np.ndarray:
    """(Ne, Nc) whether two footprints overlap (separating-axis test on the rectangles' four axes)."""
    a, b = footprint_corners(ego)[:, None], footprint_corners(cav)[None]
    apart = np.zeros((len(ego), len(cav)), dtype=bool)
    for yaw in (ego[:, 6][:, None], cav[:, 6][None]):
        for turn in (0.0, np.pi / 2):
            axis = np.stack([np.cos(yaw + turn), np.sin(yaw + turn)], -1)[:, :, None, :]
            pa, pb = (a * axis).sum(-1), (b * axis).sum(-1)
            apart |= (pa.max(-1) < pb.min(-1)) | (pb.max(-1) < pa.min(-1))
    return ~apart


def retained_matches(KP: np.ndarray, filter_threshold: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows, columns and scores of the Hungarian matches on ``KP`` that ``thresholdRetained`` keeps:
    nonzero, then at least ``filter_threshold`` when the best exceeds 5, else at least the best."""
    rows, cols = linear_sum_assignment(KP, maximize=True)
    scores = KP[rows, cols]
    nonzero = scores > 0
    rows, cols, scores = rows[nonzero], cols[nonzero], scores[nonzero]
    if len(scores) == 0:
        return rows, cols, scores
    keep = scores >= (filter_threshold if scores.max() > 5 else scores.max())
    return rows[keep], cols[keep], scores[keep]


def weighted_corner_fit(ego: np.ndarray, cav: np.ndarray, scores: np.ndarray) -> np.ndarray:
    """The CAV->ego pose fitted to the matched boxes' corners, each box's corners weighted by its score."""
    src = footprint_corners(cav).reshape(-1, 2)
    dst = footprint_corners(ego).reshape(-1, 2)
    return weighted_procrustes(src, dst, np.repeat(scores, 4))
