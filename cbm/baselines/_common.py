"""Input checks, association and result assembly shared by the baselines."""
from __future__ import annotations

from collections.abc import Callable
from time import perf_counter
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from .. import se2
from ..inputs import checked_boxes, checked_transform
from ..result import MatchResult


def as_labels(name: str, labels: np.ndarray | None, n: int) -> np.ndarray | None:
    """``labels`` as a length-``n`` 1-D array (or None), or ValueError naming the argument."""
    if labels is None:
        return None
    arr = np.asarray(labels)
    if arr.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},) like its boxes, got {arr.shape}")
    return arr


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
                init: np.ndarray, timings: dict[str, float], minimum_pairs: int = 2) -> MatchResult:
    """The MatchResult of a baseline: ``transform`` falls back to ``init`` below ``minimum_pairs``
    (two centres fix a pose; one box's corners do too, for the methods that fit corners).

    Baselines have no anchor and no consensus stage: ``anchor`` is None, both counts are the
    number of pairs and ``runner_up_count`` is 0.
    """
    pairs = sort_pairs(pairs)
    estimated = len(pairs) >= minimum_pairs
    final = np.array(transform if estimated else init, dtype=float)
    moved = se2.apply_points(final, cav_boxes[pairs[:, 1], :2])
    residuals = np.linalg.norm(ego_boxes[pairs[:, 0], :2] - moved, axis=1)
    return MatchResult(pairs=pairs, transform=final, init=np.array(init, dtype=float), estimated=estimated,
                       anchor=None, candidate_count=len(pairs), consensus_count=len(pairs), runner_up_count=0,
                       residuals=residuals, timings=timings)


def closest_point_match(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, params: Any,
                        iterate: Callable[[np.ndarray, np.ndarray, np.ndarray, Any], np.ndarray]) -> MatchResult:
    """ICP-style methods: ``iterate`` the transform from ``init`` on the centres, then associate
    mutual nearest neighbours within ``params.max_correspondence_distance``."""
    ego_boxes = checked_boxes("ego_boxes", ego_boxes)
    cav_boxes = checked_boxes("cav_boxes", cav_boxes)
    init = checked_transform("init", init)
    t0 = perf_counter()
    ego_xy, cav_xy = ego_boxes[:, :2], cav_boxes[:, :2]
    T = iterate(ego_xy, cav_xy, init, params)
    t1 = perf_counter()
    pairs = mutual_nearest_pairs(ego_xy, se2.apply_points(T, cav_xy), params.max_correspondence_distance)
    t2 = perf_counter()
    return make_result(ego_boxes, cav_boxes, pairs, T, init,
                       {"iterate": t1 - t0, "associate": t2 - t1, "total": t2 - t0})
