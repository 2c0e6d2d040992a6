"""Eq. 13-14 (``cbm.reference.select_anchor``) with the distance limit, over sparse candidate sets.

Filtering never grows a set, so card(L_ij) bounds card(L^(2)_ij): anchors are visited from the
largest candidate set down and the visit stops once no remaining set can reach the best size
found (``visit``). The answer is the same as filtering every set; only the work differs. Ties are
broken as the reference breaks them (``cbm.reference.set_key``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from ..reference import set_key
from .filtered import filtered_sizes_of, filtering, listing_held
from .listing import CandidateSets
from .rival import RivalSearch
from .visit import Visit, eq13_visit, filtered_members
from .voting import PairSets


@dataclass(frozen=True)
class Selection:
    anchor: int | None
    """Winning anchor pair id, or None when every set is empty or rejected."""
    pairs: np.ndarray
    """(K, 2) (ego index, CAV index) of the winning set, sorted by ego index."""
    candidate_count: int
    """card(L_ij) of the winning anchor before filtering (eq. 9)."""
    rival: RivalSearch | None = None
    """Where the runner-up search starts (``cbm.engine.rival.runner_up``); None without a winner."""
    visit: Visit | None = None
    """The visit's filtered sets (None when every set is empty)."""


@numba.njit(cache=True)
def by_count_descending(count):
    """Pair ids of non-empty sets by decreasing set size, ties by increasing id (a counting sort)."""
    n_sizes = 1
    for a in range(len(count)):
        n_sizes = max(n_sizes, count[a] + 1)
    start = np.zeros(n_sizes + 1, np.int64)
    for a in range(len(count)):
        start[n_sizes - count[a]] += 1
    for k in range(n_sizes):
        start[k + 1] += start[k]
    order = np.empty(start[n_sizes - 1], np.int64)
    for a in range(len(count)):
        if count[a] > 0:
            order[start[n_sizes - 1 - count[a]]] = a
            start[n_sizes - 1 - count[a]] += 1
    return order


def _as_pairs(members: np.ndarray, n_cav: int) -> np.ndarray:
    return np.stack([members // n_cav, members % n_cav], axis=1)


def filtered_sizes(anchors: np.ndarray, L: CandidateSets, voted_by: PairSets, rule: str | None,
                   ego_xy: np.ndarray, cav_xy: np.ndarray, distance_limit: float) -> np.ndarray:
    """card(L^(2)) of each of ``anchors`` (eq. 13), 0 where the distance limit rejects it."""
    anchors = np.asarray(anchors, dtype=np.int64)
    if len(anchors) == 0:
        return np.zeros(0, np.int64)
    with listing_held(L):
        return filtered_sizes_of(anchors, L.width, filtering(L, voted_by, rule, ego_xy, cav_xy, distance_limit))


def select(L: CandidateSets, voted_by: PairSets, rule: str | None, ego_xy: np.ndarray, cav_xy: np.ndarray,
           distance_limit: float) -> Selection:
    """Eq. 13-14: the largest filtered set after rejecting anchors beyond the distance limit, and
    where the runner-up search starts."""
    n_ego, n_cav = len(ego_xy), len(cav_xy)
    empty = Selection(anchor=None, pairs=np.zeros((0, 2), dtype=np.intp), candidate_count=0)
    candidate_count = L.count
    if n_ego * n_cav == 0 or not candidate_count.any():
        return empty
    order = by_count_descending(candidate_count)
    f = filtering(L, voted_by, rule, ego_xy, cav_xy, distance_limit)
    with listing_held(L):
        visited, sizes, offsets, members, stop = eq13_visit(order, L, f)
    best = int(sizes.max(initial=0))
    if best == 0:
        return empty
    k_win = _tie_broken(np.flatnonzero(sizes == best), visited, members, offsets, ego_xy, cav_xy)
    winner = members[offsets[k_win]:offsets[k_win + 1]]
    in_winner = np.zeros(n_ego * n_cav, dtype=bool)
    in_winner[winner] = True
    set_of_member = np.repeat(np.arange(len(sizes)), sizes)
    shares = np.bincount(set_of_member, weights=in_winner[members], minlength=len(sizes)) > 0
    rival = RivalSearch(order, stop, int(sizes[~shares].max(initial=0)), in_winner, L, f)
    return Selection(anchor=int(visited[k_win]), pairs=_as_pairs(np.sort(winner), n_cav),
                     candidate_count=int(candidate_count[visited[k_win]]), rival=rival,
                     visit=Visit(order, sizes, offsets, members, f))


def _tie_broken(tied: np.ndarray, visited: np.ndarray, members: np.ndarray, offsets: np.ndarray,
                ego_xy: np.ndarray, cav_xy: np.ndarray) -> int:
    """Which of the ``tied`` visited sets (positions in ``visited``) wins: the one, or the least
    ``cbm.reference.set_key`` followed by the anchor's centres (a key per distinct set)."""
    if len(tied) == 1:
        return int(tied[0])
    n_cav = len(cav_xy)
    set_keys: dict[bytes, tuple[float, ...]] = {}
    keys = {}
    for k in tied:
        m = members[offsets[k]:offsets[k + 1]]
        fingerprint = np.sort(m).tobytes()
        if fingerprint not in set_keys:
            pairs = _as_pairs(m, n_cav)
            set_keys[fingerprint] = set_key(ego_xy[pairs[:, 0]], cav_xy[pairs[:, 1]])
        a = int(visited[k])
        keys[k] = set_keys[fingerprint] + (*ego_xy[a // n_cav], *cav_xy[a % n_cav])
    return int(min(keys, key=keys.__getitem__))


def anchor_sets(L: CandidateSets, voted_by: PairSets, rule: str | None, ego_xy: np.ndarray, cav_xy: np.ndarray,
                distance_limit: float, winner: int, k: int, pool: int,
                visit: Visit | None = None) -> list[tuple[int, np.ndarray]]:
    """(anchor, filtered set) of the eq. 13 ``winner`` and of the next ``k - 1`` anchors with the
    largest filtered sets among the ``pool`` largest candidate sets, each set once, largest first
    (ties by candidate-set order: ``by_count_descending``). The sets eq. 13's ``visit`` (of the same
    sets) filtered are taken from it; of the rest only those are filtered here whose card(L_ij)
    exceeds the last set taken from the visit's (when it gave ``k``): filtering never grows a set,
    and a tie goes to the visited anchor, which comes first in the order."""
    if visit is None:
        visit = Visit(by_count_descending(L.count), np.zeros(0, np.int64), np.zeros(1, np.int64),
                      np.zeros(0, np.int64), filtering(L, voted_by, rule, ego_xy, cav_xy, distance_limit))
    order = visit.order[:pool]
    known = min(len(visit.sizes), len(order))
    first = (winner, visit.members_of(winner, L))
    found = _distinct_largest(order[:known], visit.sizes[:known], first, k, visit.members_at)
    rest = order[known:]
    if len(found) == k:
        rest = rest[L.count[rest] > len(found[-1][1])]
    if len(rest) > 0:
        with listing_held(L):
            sizes = np.concatenate([visit.sizes[:known], filtered_sizes_of(rest, L.width, visit.filtering)])
        anchors = np.concatenate([order[:known], rest])
        found = _distinct_largest(anchors, sizes, first, k, lambda index: visit.members_at(index) if index < known
                                  else filtered_members(int(anchors[index]), L, visit.filtering))
    n_cav = visit.filtering.lister.lookup.n_cav
    return [(anchor, _as_pairs(members, n_cav)) for anchor, members in found]


def _distinct_largest(anchors: np.ndarray, sizes: np.ndarray, first: tuple[int, np.ndarray], k: int,
                      members_at) -> list[tuple[int, np.ndarray]]:
    """``first`` (anchor, pair ids increasing) and the next anchors by decreasing filtered size
    ``sizes`` (ties in the order of ``anchors``) whose sets differ from those taken, until ``k`` are
    taken or the sizes reach 0; ``members_at(index)``: the pair ids of ``anchors[index]``'s set, increasing."""
    found, seen = [first], {first[1].tobytes()}
    for index in np.argsort(-sizes, kind="stable"):
        if len(found) == k or sizes[index] == 0:
            break
        members = members_at(int(index))
        if members.tobytes() not in seen:
            seen.add(members.tobytes())
            found.append((int(anchors[index]), members))
    return found
