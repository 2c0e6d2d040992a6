"""Input checks, association and result assembly shared by the baselines."""
from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from .. import se2
from ..result import MatchResult


def as_boxes(name: str, boxes: np.ndarray) -> np.ndarray:
    """``boxes`` as a finite ``(N, 7)`` float64 array, or ValueError naming the argument."""
    arr = np.asarray(boxes, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 7:
        raise ValueError(f"{name} must have shape (N, 7), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


def as_transform(name: str, T: np.ndarray) -> np.ndarray:
    """``T`` as a finite rigid ``(3, 3)`` SE(2) matrix, or ValueError naming the argument."""
    arr = np.asarray(T, dtype=float)
    if arr.shape != (3, 3):
        raise ValueError(f"{name} must have shape (3, 3), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    R = arr[:2, :2]
    if not (np.allclose(arr[2], [0.0, 0.0, 1.0]) and np.allclose(R.T @ R, np.eye(2), atol=1e-6)
            and np.linalg.det(R) > 0):
        raise ValueError(f"{name} must be a rigid SE(2) transform (rotation block, last row 0 0 1)")
    return arr


def as_labels(name: str, labels: np.ndarray | None, n: int) -> np.ndarray | None:
    """``labels`` as a length-``n`` 1-D array (or None), or ValueError naming the argument."""
    if labels is None:
        return None
    arr = np.asarray(labels)
    if arr.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},) like its boxes, got {arr.shape}")
    return arr


def check_positive(owner: object, *names: str) -> None:
    """ValueError unless each named field of ``owner`` is a positive finite number."""
    for name in names:
        value = getattr(owner, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise ValueError(f"{type(owner).__name__}.{name} must be a positive finite number, got {value!r}")


def check_count(owner: object, name: str, minimum: int) -> None:
    """ValueError unless the named field of ``owner`` is an int of at least ``minimum``."""
    value = getattr(owner, name)
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ValueError(f"{type(owner).__name__}.{name} must be an integer >= {minimum}, got {value!r}")


def check_params(params, cls: type):
    """``params`` or the defaults of ``cls``; TypeError for a parameter object of another method."""
    if params is None:
        return cls()
    if not isinstance(params, cls):
        raise TypeError(f"params must be {cls.__name__}, got {type(params).__name__}")
    return params


def mutual_nearest_pairs(ego_xy: np.ndarray, cav_xy_in_ego: np.ndarray, gate: float) -> np.ndarray:
    """(K, 2) pairs (i, j) where ego i and CAV j are each other's nearest neighbour within ``gate``."""
    if len(ego_xy) == 0 or len(cav_xy_in_ego) == 0:
        return np.empty((0, 2), dtype=int)
    d_ce, ego_of_cav = cKDTree(ego_xy).query(cav_xy_in_ego, distance_upper_bound=gate)
    _, cav_of_ego = cKDTree(cav_xy_in_ego).query(ego_xy)
    cav = np.flatnonzero(np.isfinite(d_ce))
    ego = ego_of_cav[cav]
    keep = cav_of_ego[ego] == cav
    return sort_pairs(np.column_stack([ego[keep], cav[keep]]))


def sort_pairs(pairs: np.ndarray) -> np.ndarray:
    """Pairs as a (K, 2) int array sorted by ego index."""
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    return pairs[np.argsort(pairs[:, 0], kind="stable")]


def make_result(ego_boxes: np.ndarray, cav_boxes: np.ndarray, pairs: np.ndarray, transform: np.ndarray,
                init: np.ndarray, timings: dict[str, float]) -> MatchResult:
    """The MatchResult of a baseline: ``transform`` falls back to ``init`` below two pairs.

    Baselines have no anchor and no consensus stage: ``anchor`` is None, both counts are the
    number of pairs and ``runner_up_count`` is 0.
    """
    pairs = sort_pairs(pairs)
    estimated = len(pairs) >= 2
    final = np.array(transform if estimated else init, dtype=float)
    moved = se2.apply_points(final, cav_boxes[pairs[:, 1], :2])
    residuals = np.linalg.norm(ego_boxes[pairs[:, 0], :2] - moved, axis=1)
    return MatchResult(pairs=pairs, transform=final, init=np.array(init, dtype=float), estimated=estimated,
                       anchor=None, candidate_count=len(pairs), consensus_count=len(pairs), runner_up_count=0,
                       residuals=residuals, timings=timings)
