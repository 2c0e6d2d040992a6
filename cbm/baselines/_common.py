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


COINCIDENT_M = 1.0
"""Metres. Paired objects whose centres all lie within this (root mean square) of their mean fix no
rotation: any turn about that point explains them as well (20 boxes at one spot: 40 m errors)."""
SYMMETRY_M = 1.0
"""Metres. A layout of paired centres that, turned about its mean, lands every centre within this
of another one's place looks the same turned: a method that finds the pairs from the layout alone
cannot tell the two poses apart (evenly spaced boxes on a line and a half turn: 129 m off)."""
TURNS_DEG = (180.0, 120.0, 90.0)
"""The turns checked: any layout symmetric about a point (a line, a rectangle), three- and four-fold ones."""
HEADING_TOLERANCE = np.radians(15.0)
"""Two headings (known up to a half turn) closer than this count as the same."""


def unresolved(boxes: np.ndarray, layout: bool = True) -> str:
    """Why the paired objects ``boxes`` (their ego-side rows) cannot tell the pose, or "": their
    centres at one point (``COINCIDENT_M``); with ``layout`` (a method that pairs objects by their
    layout, with no prior to choose), a layout that looks the same turned by one of ``TURNS_DEG``
    (``SYMMETRY_M``), headings (up to a half turn) included."""
    xy = boxes[:, :2] - boxes[:, :2].mean(axis=0) if len(boxes) else boxes[:, :2]
    if len(boxes) >= 2 and np.sqrt(np.mean(np.sum(xy ** 2, axis=1))) < COINCIDENT_M:
        return (f"the {len(boxes)} paired objects lie at one point (within {COINCIDENT_M:g} m): their "
                f"positions fix no rotation")
    if not layout or len(boxes) < 2:
        return ""
    for turn in TURNS_DEG:
        if _looks_the_same(xy, boxes[:, 6], np.radians(turn)):
            return (f"the paired objects' layout looks the same turned by {turn:g}° about its centre: a pose "
                    f"turned so explains them as well")
    return ""


def _looks_the_same(xy: np.ndarray, headings: np.ndarray, turn: float) -> bool:
    """Whether ``xy`` (centred) turned by ``turn`` puts each point on another's place, one to one,
    with its heading (up to a half turn) there too."""
    turned = xy @ se2.make(0.0, 0.0, turn)[:2, :2].T
    distance, nearest = cKDTree(xy).query(turned)
    if np.any(distance > SYMMETRY_M) or len(set(nearest.tolist())) < len(xy):
        return False
    gap = np.abs((headings + turn - headings[nearest] + np.pi / 2) % np.pi - np.pi / 2)
    return bool(np.all(gap < HEADING_TOLERANCE))


def make_result(ego_boxes: np.ndarray, cav_boxes: np.ndarray, pairs: np.ndarray, transform: np.ndarray,
                init: np.ndarray, timings: dict[str, float], minimum_pairs: int = 2,
                layout: bool = False) -> MatchResult:
    """The MatchResult of a baseline: ``transform`` falls back to ``init`` below ``minimum_pairs``
    (two centres fix a pose; one box's corners do too, for the methods that fit corners). An
    estimate its pairs cannot tell (``unresolved``; ``layout``: the method pairs objects by their
    layout alone) is kept but abstained, with the reason.

    Baselines have no anchor and no consensus stage: ``anchor`` is None, both counts are the
    number of pairs and ``runner_up_count`` is 0.
    """
    pairs = sort_pairs(pairs)
    estimated = len(pairs) >= minimum_pairs
    final = np.array(transform if estimated else init, dtype=float)
    moved = se2.apply_points(final, cav_boxes[pairs[:, 1], :2])
    residuals = np.linalg.norm(ego_boxes[pairs[:, 0], :2] - moved, axis=1)
    why = unresolved(ego_boxes[pairs[:, 0]], layout) if estimated else ""
    return MatchResult(pairs=pairs, transform=final, init=np.array(init, dtype=float), estimated=estimated,
                       anchor=None, candidate_count=len(pairs), consensus_count=len(pairs), runner_up_count=0,
                       residuals=residuals, timings=timings, abstained=bool(why), reason=why)


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
