"""VIPS baseline: object association by spectral graph matching (Shi et al., "VIPS: Real-time perception
fusion for infrastructure-assisted autonomous driving", MobiCom 2022), then a Procrustes pose fit."""
from __future__ import annotations

from dataclasses import dataclass
from time import perf_counter

import numpy as np
from scipy import sparse
from scipy.optimize import linear_sum_assignment
from scipy.sparse.linalg import eigsh
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from .. import se2
from ..estimate import weighted_procrustes
from ..inputs import check_at_most, check_positive, checked_boxes, checked_transform
from ..result import MatchResult
from ._common import as_labels, check_count, check_params, make_result, sort_pairs

_DENSE_EIGEN_LIMIT = 2
"""Up to this many candidate assignments the eigenvector comes from a dense solver (ARPACK needs more)."""
_BLOCK_ENTRIES = 1 << 18
"""Entries of the affinity matrix evaluated at once; bounds the memory of its construction."""


@dataclass(frozen=True)
class VIPSParams:
    """Parameters of VIPS. The affinity weights are the published ones (lambda1..4 = 0.5, 0.1, 0.5, 0.1;
    mu1..4 = 0.5); the pruning and the score threshold are ours (VIPS builds the full matrix)."""

    lambda_size: float = 0.5
    """1/m^2. Node term ``exp(-lambda1 ||s_i - s_i'||^2)`` on the sizes (length, width, height)."""
    lambda_position: float = 0.1
    """1/m. Node term ``exp(-lambda2 ||p_i - init p_i'||)`` on the centres under ``init``."""
    lambda_distance: float = 0.5
    """1/m^2. Edge term ``exp(-lambda3 (d_ij - d_i'j')^2)`` on the centre distances."""
    lambda_heading: float = 0.1
    """Edge term ``exp(-lambda4 |sin(theta_i - theta_j) - sin(theta_i' - theta_j')|)`` on relative headings."""
    mu_size: float = 0.5
    """mu1: weight of the size term in the node affinity."""
    mu_position: float = 0.5
    """mu2: weight of the position term in the node affinity."""
    mu_distance: float = 0.5
    """mu3: weight of the distance term in the edge affinity."""
    mu_heading: float = 0.5
    """mu4: weight of the relative-heading term in the edge affinity."""
    candidate_radius: float = 10.0
    """Metres, at most 200. An assignment (i, i') is a candidate only when the CAV centre lies this
    close to the ego centre under ``init``."""
    top_k: int = 10
    """Each ego object keeps its ``top_k`` candidates of largest node affinity, at most 100 (the
    affinity matrix grows with its square: 1,000,000 ran out of memory)."""
    edge_gate: float = 3.0
    """Metres. Two assignments whose centre distances differ by more than this have zero affinity
    (their distance term is then below exp(-lambda3 edge_gate^2) = 0.011 at the defaults)."""
    score_threshold: float = 0.2
    """A Hungarian assignment is kept when its eigenvector entry is at least this fraction of the largest."""

    def __post_init__(self) -> None:
        check_positive(self, "lambda_size", "lambda_position", "lambda_distance", "lambda_heading",
                       "mu_size", "mu_position", "mu_distance", "mu_heading", "candidate_radius", "edge_gate")
        check_count(self, "top_k", 1)
        check_at_most(self, {"top_k": 100, "candidate_radius": 200.0, "edge_gate": 50.0})
        if not isinstance(self.score_threshold, (int, float)) or not 0.0 < self.score_threshold <= 1.0:
            raise ValueError(f"VIPSParams.score_threshold must lie in (0, 1], got {self.score_threshold!r}")


def match_vips(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, params: VIPSParams | None = None,
               *, ego_labels: np.ndarray | None = None, cav_labels: np.ndarray | None = None) -> MatchResult:
    """Associate boxes by spectral graph matching (Leordeanu and Hebert, 2005) with VIPS's affinities.

    1. Candidates: assignments (i, i') of the same category (when labels are given) whose centres lie
       within ``candidate_radius`` under ``init``, at most ``top_k`` per ego object by node affinity
       ``M(a, a) = mu1 exp(-lambda1 ||s_i - s_i'||^2) + mu2 exp(-lambda2 ||p_i - init p_i'||)``.
       This pruning keeps the matrix at most ``(top_k Ne)^2`` instead of ``(Ne Nc)^2``.
    2. Affinity between candidates a = (i, i') and b = (j, j'):
       ``M(a, b) = mu3 exp(-lambda3 (d_ij - d_i'j')^2) + mu4 exp(-lambda4 |sin(theta_i - theta_j) -
       sin(theta_i' - theta_j')|)``; zero when a and b conflict (i = j or i' = j') or when
       ``|d_ij - d_i'j'| > edge_gate``, so M is sparse. The sine of the relative heading changes sign
       under a 180-degree flip of one heading: the fragility the CBM paper reports (sec. IV).
    3. x = leading eigenvector of M; Hungarian assignment maximising the sum of x over one-to-one pairs;
       pairs with ``x < score_threshold * max(x)`` dropped.
    4. Transform: unweighted Procrustes fit of the matched centres (``init`` below two pairs).
    """
    params = check_params(params, VIPSParams)
    ego_boxes = checked_boxes("ego_boxes", ego_boxes)
    cav_boxes = checked_boxes("cav_boxes", cav_boxes)
    init = checked_transform("init", init)
    ego_labels = as_labels("ego_labels", ego_labels, len(ego_boxes))
    cav_labels = as_labels("cav_labels", cav_labels, len(cav_boxes))
    t0 = perf_counter()
    ego_of, cav_of, node = candidate_assignments(ego_boxes, cav_boxes, init, ego_labels, cav_labels, params)
    t1 = perf_counter()
    M = affinity_matrix(ego_boxes, cav_boxes, ego_of, cav_of, node, params)
    t2 = perf_counter()
    x = leading_eigenvector(M)
    t3 = perf_counter()
    pairs = discretise(ego_of, cav_of, x, (len(ego_boxes), len(cav_boxes)), params.score_threshold)
    t4 = perf_counter()
    T = weighted_procrustes(cav_boxes[pairs[:, 1], :2], ego_boxes[pairs[:, 0], :2]) if len(pairs) >= 2 else init
    t5 = perf_counter()
    timings = {"candidates": t1 - t0, "affinity": t2 - t1, "eigenvector": t3 - t2, "assign": t4 - t3,
               "fit": t5 - t4, "total": t5 - t0}
    return make_result(ego_boxes, cav_boxes, pairs, T, init, timings)


def candidate_assignments(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
                          ego_labels: np.ndarray | None, cav_labels: np.ndarray | None,
                          params: VIPSParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate assignments (ego index, CAV index) and their node affinities, grouped by ego index."""
    empty = (np.empty(0, dtype=int), np.empty(0, dtype=int), np.empty(0))
    if len(ego_boxes) == 0 or len(cav_boxes) == 0:
        return empty
    cav_xy = se2.apply_points(init, cav_boxes[:, :2])
    near = cKDTree(cav_xy).query_ball_point(ego_boxes[:, :2], r=params.candidate_radius)
    ego_of = np.repeat(np.arange(len(ego_boxes)), [len(n) for n in near])
    if len(ego_of) == 0:
        return empty
    cav_of = np.concatenate([np.asarray(n, dtype=int) for n in near])
    if ego_labels is not None and cav_labels is not None:
        same = ego_labels[ego_of] == cav_labels[cav_of]
        ego_of, cav_of = ego_of[same], cav_of[same]
    size_d2 = np.sum((ego_boxes[ego_of, 3:6] - cav_boxes[cav_of, 3:6]) ** 2, axis=1)
    dist = np.linalg.norm(ego_boxes[ego_of, :2] - cav_xy[cav_of], axis=1)
    node = params.mu_size * np.exp(-params.lambda_size * size_d2) + params.mu_position * np.exp(
        -params.lambda_position * dist)
    keep = top_k_per_group(ego_of, node, params.top_k)
    return ego_of[keep], cav_of[keep], node[keep]


def top_k_per_group(group: np.ndarray, score: np.ndarray, k: int) -> np.ndarray:
    """Indices of the ``k`` largest scores within each group, ordered by group then decreasing score."""
    order = np.lexsort((-score, group))
    sorted_group = group[order]
    starts = np.flatnonzero(np.r_[True, sorted_group[1:] != sorted_group[:-1]])
    rank = np.arange(len(order)) - np.repeat(starts, np.diff(np.r_[starts, len(order)]))
    return order[rank < k]


def affinity_matrix(ego_boxes: np.ndarray, cav_boxes: np.ndarray, ego_of: np.ndarray, cav_of: np.ndarray,
                    node: np.ndarray, params: VIPSParams) -> sparse.csr_matrix:
    """The sparse symmetric VIPS affinity matrix over candidate assignments (node terms on the diagonal)."""
    K = len(ego_of)
    d_ego, d_cav = cdist(ego_boxes[:, :2], ego_boxes[:, :2]), cdist(cav_boxes[:, :2], cav_boxes[:, :2])
    sin_ego, sin_cav = relative_heading_sines(ego_boxes[:, 6]), relative_heading_sines(cav_boxes[:, 6])
    rows, cols, vals = [np.arange(K)], [np.arange(K)], [node]
    block = max(1, _BLOCK_ENTRIES // max(K, 1))
    for start in range(0, K, block):
        a = np.arange(start, min(start + block, K))
        dd = d_ego[ego_of[a, None], ego_of[None, :]] - d_cav[cav_of[a, None], cav_of[None, :]]
        ok = (np.abs(dd) <= params.edge_gate) & (ego_of[a, None] != ego_of[None, :]) & (
            cav_of[a, None] != cav_of[None, :])
        ai, b = np.nonzero(ok)
        a_ok = a[ai]
        dsin = sin_ego[ego_of[a_ok], ego_of[b]] - sin_cav[cav_of[a_ok], cav_of[b]]
        edge = params.mu_distance * np.exp(-params.lambda_distance * dd[ok] ** 2) + params.mu_heading * np.exp(
            -params.lambda_heading * np.abs(dsin))
        rows.append(a_ok)
        cols.append(b)
        vals.append(edge)
    return sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(K, K))


def relative_heading_sines(yaw: np.ndarray) -> np.ndarray:
    """``sin(theta_i - theta_j)`` for every pair of objects of one agent."""
    return np.sin(yaw[:, None] - yaw[None, :])


def leading_eigenvector(M: sparse.csr_matrix) -> np.ndarray:
    """The leading (Perron) eigenvector of the non-negative symmetric ``M``, non-negative, max entry 1."""
    K = M.shape[0]
    if K == 0:
        return np.empty(0)
    if K <= _DENSE_EIGEN_LIMIT:
        x = np.linalg.eigh(M.toarray())[1][:, -1]
    else:
        x = eigsh(M, k=1, which="LA", v0=np.ones(K))[1][:, 0]
    x = np.clip(x if x.sum() >= 0 else -x, 0.0, None)
    return x / x.max() if x.max() > 0 else x


def discretise(ego_of: np.ndarray, cav_of: np.ndarray, x: np.ndarray, shape: tuple[int, int],
               threshold: float) -> np.ndarray:
    """One-to-one pairs maximising the summed scores (Hungarian), keeping scores >= ``threshold``."""
    if len(x) == 0:
        return np.empty((0, 2), dtype=int)
    score = np.zeros(shape)
    score[ego_of, cav_of] = x
    rows, cols = linear_sum_assignment(score, maximize=True)
    keep = score[rows, cols] >= threshold
    return sort_pairs(np.column_stack([rows[keep], cols[keep]]))
