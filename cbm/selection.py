"""Selection of the answer among all anchors (paper eq. 12-13) with the released code's distance limit.

The answer is the anchor whose filtered set L^(2)_ij is largest (eq. 12). Anchors whose pairs lie on
average farther apart than ``distance_limit`` after the pre-transform are rejected (released code).
Ties are broken by what the sets are, never by input order: first the smaller residual of a
least-squares rigid fit of the set, then the set's centroids (see ``tie_break_key``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.distance import cdist

from .consensus import FilteredSets
from .estimate import residuals, weighted_procrustes


@dataclass(frozen=True)
class Selection:
    anchor: int | None
    """Winning anchor pair id, or None when every set is empty or rejected."""
    pairs: np.ndarray
    """(K, 2) (ego index, CAV index) of the winning set, sorted by ego index."""
    runner_up_count: int
    """Largest set among anchors that share no pair with the winner."""


def mean_pair_distance(sets: FilteredSets, ego_xy: np.ndarray, cav_xy: np.ndarray, n_cav: int,
                       n_pairs: int) -> np.ndarray:
    """(Ne * Nc,) mean centre distance of each set's pairs (CAV centres pre-transformed), 0 if empty."""
    distance = cdist(ego_xy, cav_xy).ravel()[sets.member]
    total = np.bincount(sets.anchor, weights=distance, minlength=n_pairs)
    count = np.bincount(sets.anchor, minlength=n_pairs)
    return np.divide(total, count, out=np.zeros(n_pairs), where=count > 0)


def tie_break_key(pairs: np.ndarray, ego_xy: np.ndarray, cav_xy: np.ndarray) -> tuple[float, ...]:
    """Order-free key of a set: (rigid-fit RMS residual, ego centroid, CAV centroid), rounded to 1e-9.

    The pairs are put in an order given by their coordinates first, so the same set gives the same
    floating-point key whatever the order of the input boxes.
    """
    src, dst = cav_xy[pairs[:, 1]], ego_xy[pairs[:, 0]]
    order = np.lexsort((src[:, 1], src[:, 0], dst[:, 1], dst[:, 0]))
    src, dst = src[order], dst[order]
    rms = float(np.sqrt(np.mean(residuals(weighted_procrustes(src, dst), src, dst) ** 2))) if len(pairs) > 1 else 0.0
    key = (rms, *dst.mean(axis=0), *src.mean(axis=0))
    return tuple(round(float(value), 9) for value in key)


def select(sets: FilteredSets, ego_xy: np.ndarray, cav_xy: np.ndarray, distance_limit: float) -> Selection:
    """Eq. 12-13: the largest set after rejecting anchors beyond the distance limit."""
    n_cav = len(cav_xy)
    n_pairs = len(ego_xy) * n_cav
    empty = np.zeros((0, 2), dtype=np.intp)
    if n_pairs == 0 or len(sets.anchor) == 0:
        return Selection(anchor=None, pairs=empty, runner_up_count=0)
    count = np.bincount(sets.anchor, minlength=n_pairs)
    count[mean_pair_distance(sets, ego_xy, cav_xy, n_cav, n_pairs) > distance_limit] = 0
    best = int(count.max())
    if best == 0:
        return Selection(anchor=None, pairs=empty, runner_up_count=0)
    starts = np.searchsorted(sets.anchor, np.arange(n_pairs + 1))
    members = {int(a): sets.member[starts[a]:starts[a + 1]] for a in np.flatnonzero(count == best)}
    set_keys: dict[bytes, tuple[float, ...]] = {}
    keys = {}
    for a, m in members.items():
        fingerprint = np.sort(m).tobytes()
        if fingerprint not in set_keys:
            set_keys[fingerprint] = tie_break_key(np.stack([m // n_cav, m % n_cav], axis=1), ego_xy, cav_xy)
        keys[a] = set_keys[fingerprint] + (*ego_xy[a // n_cav], *cav_xy[a % n_cav])
    winner = min(keys, key=keys.__getitem__)
    in_winner = np.zeros(n_pairs, dtype=bool)
    in_winner[members[winner]] = True
    shares = np.bincount(sets.anchor, weights=in_winner[sets.member], minlength=n_pairs) > 0
    rivals = count[~shares]
    pairs = np.stack([members[winner] // n_cav, members[winner] % n_cav], axis=1)
    return Selection(anchor=winner, pairs=pairs[np.argsort(pairs[:, 0], kind="stable")],
                     runner_up_count=int(rivals.max(initial=0)))
