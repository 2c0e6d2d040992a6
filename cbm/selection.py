"""Selection of the answer among all anchors (paper eq. 12-13) with the released code's distance limit.

The answer is the anchor whose filtered set L^(2)_ij is largest (eq. 12). Anchors whose pairs lie on
average farther apart than ``distance_limit`` after the pre-transform are rejected (released code).

Filtering never grows a set, so card(L_ij) bounds card(L^(2)_ij): anchors are visited from the
largest candidate set down and the search stops once no remaining set can reach the best size
found (branch and bound). The answer is the same as filtering every set; only the work differs.

Ties are broken by what the sets are, never by input order: first the smaller residual of a
least-squares rigid fit of the set, then the set's centroids (see ``tie_break_key``).
"""
from __future__ import annotations

from concurrent.futures import Future
from dataclasses import dataclass

import numba
import numpy as np

from .consensus import PairSets
from .estimate import residuals, weighted_procrustes
from .filtered import (
    N_CAV,
    PAPER,
    RULE,
    filtered_sizes_of,
    kernel_arguments,
    listing_held,
    rival_free_size,
    work_arrays,
)
from .local_matching import POOL, CandidateSets, Done
from .local_matching.listing import in_two_parts
from .visit import Visit, eq13_visit, filtered_members, with_listing

RIVAL_FIRST = 64
"""Anchors the runner-up search visits on the calling thread before it hands any to the threads:
most searches end within them."""
RIVAL_CHUNK = 512
"""Anchors handed to the threads at a time in the runner-up search."""
RIVAL_APART = (5_000, 40_000)
"""Ego x CAV pairs from and below which, without a listing, ``select`` starts the runner-up search
on ``POOL`` (on that one thread) and returns: the caller verifies the winner meanwhile. Below, the
hand-over costs more than it saves (and the warm-up's small scene never waits for ``POOL`` while it
compiles); from the upper end the search is better split over both threads."""
RIVAL_THREADS_FROM = 10_000
"""Candidate pairs (the chunk's card(L_ij) summed) from which a chunk's halves run on two threads;
below, handing them over costs more than it saves, and the calling thread runs the chunk."""


@dataclass(frozen=True)
class Selection:
    anchor: int | None
    """Winning anchor pair id, or None when every set is empty or rejected."""
    pairs: np.ndarray
    """(K, 2) (ego index, CAV index) of the winning set, sorted by ego index."""
    candidate_count: int
    """card(L_ij) of the winning anchor before filtering (eq. 8)."""
    rival: Future | Done
    """The runner-up search (``strongest_rival``): found, or running on ``POOL`` (``RIVAL_APART``)."""
    visit: Visit | None = None
    """The visit's filtered sets (None when every set is empty)."""

    @property
    def runner_up_count(self) -> int:
        """Largest set among anchors that share no pair with the winner (waits for the search)."""
        return self.rival.result()


@numba.njit(cache=True, nogil=True)
def _largest_rival(anchors, part, parts, count, best, shared, width, excluded, signs, lookup, listing, voted_start,
                   voted_by, rule, n_ego, n_cav, centres, limit):
    """The largest of ``best`` and the filtered sizes of ``anchors[part::parts]`` (by decreasing
    card(L_ij) ``count``) whose sets hold no ``excluded`` pair (``rival_free_size``), visiting them in
    order and stopping at the first whose count is at most the largest so far. ``shared[0]`` is the
    largest size the other parts have found: read before each anchor, raised when this part finds a
    larger one. Same answer as the maximum over every anchor: every value read there is a size some
    anchor reaches, an anchor whose count is at most it cannot raise the maximum (filtering never
    grows a set), and every later anchor's count is no larger. An anchor whose members cannot form a
    one-to-one set larger than the largest so far, or whose filtered set is sure to hold an excluded
    pair, is not filtered (``rival_free_size``): it cannot raise the maximum either."""
    work = work_arrays(width, n_ego, n_cav, len(excluded))
    for n in range(part, len(anchors), parts):
        best = max(best, shared[0])
        if count[anchors[n]] <= best:
            break
        size = rival_free_size(anchors[n], best, excluded, signs, lookup, listing, voted_start, voted_by, rule,
                               n_ego, n_cav, centres, limit, work)
        if size > best:
            best = size
            shared[0] = max(shared[0], size)
    return best


def strongest_rival(order: np.ndarray, first: int, L: CandidateSets, runner_up: int, in_winner: np.ndarray,
                    common: tuple, threads: bool = True) -> int:
    """Largest filtered set sharing no pair with the winner, among anchors from ``order[first]`` on
    whose candidate set could beat ``runner_up``.

    Without the paper's rule an anchor pair is alone in its row and column of its own set, so it
    survives into its filtered set: an anchor that is one of the winner's pairs shares it, unseen.
    The anchors go in chunks (the first ``RIVAL_FIRST`` anchors, then ``RIVAL_CHUNK`` at a time),
    each visited by ``_largest_rival`` on the calling thread or, from ``RIVAL_THREADS_FROM``
    candidate pairs and with ``threads``, in two interleaved parts at once (the second on ``POOL``)
    that share the largest size found; with a listing each part keeps what it lists in its half of
    the room (``in_two_parts``)."""
    rule = common[RULE]
    ends = range(first + RIVAL_FIRST, len(order) + RIVAL_CHUNK, RIVAL_CHUNK)
    for chunk, end in zip([first, *ends], ends):
        anchors = order[chunk:end]
        anchors = anchors[L.count[anchors] > runner_up]
        if len(anchors) == 0:
            break
        if rule != PAPER:
            anchors = anchors[~in_winner[anchors]]
        shared = np.array([runner_up], np.int64)
        if not threads or int(L.count[anchors].sum()) < RIVAL_THREADS_FROM:
            runner_up = int(_largest_rival(anchors, 0, 1, L.count, runner_up, shared, L.width, in_winner, *common))
            continue
        runner_up = int(max(in_two_parts(L.listing, _rival_part, anchors, runner_up, shared, L, in_winner, common)))
    return runner_up


def _rival_part(part: int, listing: tuple, anchors: np.ndarray, runner_up: int, shared: np.ndarray,
                L: CandidateSets, in_winner: np.ndarray, common: tuple) -> int:
    """``_largest_rival`` of one of two interleaved parts of ``anchors``, listing with ``listing``."""
    return _largest_rival(anchors, part, 2, L.count, runner_up, shared, L.width, in_winner,
                          *with_listing(common, listing))


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


def _as_pairs(members: np.ndarray, n_cav: int) -> np.ndarray:
    return np.stack([members // n_cav, members % n_cav], axis=1)


def filtered_sizes(anchors: np.ndarray, L: CandidateSets, voted_by: PairSets, rule: str | None,
                   ego_xy: np.ndarray, cav_xy: np.ndarray, distance_limit: float) -> np.ndarray:
    """card(L^(2)) of each of ``anchors`` (eq. 12), 0 where the distance limit rejects it."""
    anchors = np.asarray(anchors, dtype=np.int64)
    if len(anchors) == 0:
        return np.zeros(0, np.int64)
    with listing_held(L):
        return filtered_sizes_of(anchors, L.width, *kernel_arguments(L, voted_by, rule, ego_xy, cav_xy,
                                                                     distance_limit))


def select(L: CandidateSets, voted_by: PairSets, rule: str | None, ego_xy: np.ndarray, cav_xy: np.ndarray,
           distance_limit: float) -> Selection:
    """Eq. 12-13: the largest filtered set after rejecting anchors beyond the distance limit."""
    n_ego, n_cav = len(ego_xy), len(cav_xy)
    empty = Selection(anchor=None, pairs=np.zeros((0, 2), dtype=np.intp), candidate_count=0, rival=Done(0))
    candidate_count = L.count
    if n_ego * n_cav == 0 or not candidate_count.any():
        return empty
    order = by_count_descending(candidate_count)
    common = kernel_arguments(L, voted_by, rule, ego_xy, cav_xy, distance_limit)
    with listing_held(L):
        visited, sizes, offsets, members, stop = eq13_visit(order, L, common)
        best = int(sizes.max(initial=0))
        if best == 0:
            return empty
        k_win = _tie_broken(np.flatnonzero(sizes == best), visited, members, offsets, ego_xy, cav_xy)
        winner = members[offsets[k_win]:offsets[k_win + 1]]
        in_winner = np.zeros(n_ego * n_cav, dtype=bool)
        in_winner[winner] = True
        set_of_member = np.repeat(np.arange(len(sizes)), sizes)
        shares = np.bincount(set_of_member, weights=in_winner[members], minlength=len(sizes)) > 0
        search = (order, stop, L, int(sizes[~shares].max(initial=0)), in_winner, common)
        if L.listing is None and RIVAL_APART[0] <= n_ego * n_cav < RIVAL_APART[1]:
            rival = POOL.submit(strongest_rival, *search, threads=False)
        else:
            rival = Done(strongest_rival(*search))
    return Selection(anchor=int(visited[k_win]), pairs=_as_pairs(np.sort(winner), n_cav),
                     candidate_count=int(candidate_count[visited[k_win]]), rival=rival,
                     visit=Visit(order, sizes, offsets, members, common))


def _tie_broken(tied: np.ndarray, visited: np.ndarray, members: np.ndarray, offsets: np.ndarray,
                ego_xy: np.ndarray, cav_xy: np.ndarray) -> int:
    """Which of the ``tied`` visited sets (positions in ``visited``) wins: the one, or the least
    ``tie_break_key`` followed by the anchor's centres (a key per distinct set)."""
    if len(tied) == 1:
        return int(tied[0])
    n_cav = len(cav_xy)
    set_keys: dict[bytes, tuple[float, ...]] = {}
    keys = {}
    for k in tied:
        m = members[offsets[k]:offsets[k + 1]]
        fingerprint = np.sort(m).tobytes()
        if fingerprint not in set_keys:
            set_keys[fingerprint] = tie_break_key(_as_pairs(m, n_cav), ego_xy, cav_xy)
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
                      np.zeros(0, np.int64), kernel_arguments(L, voted_by, rule, ego_xy, cav_xy, distance_limit))
    order = visit.order[:pool]
    known = min(len(visit.sizes), len(order))
    first = (winner, visit.members_of(winner, L))
    found = _distinct_largest(order[:known], visit.sizes[:known], first, k, visit.members_at)
    rest = order[known:]
    if len(found) == k:
        rest = rest[L.count[rest] > len(found[-1][1])]
    if len(rest) > 0:
        with listing_held(L):
            sizes = np.concatenate([visit.sizes[:known], filtered_sizes_of(rest, L.width, *visit.common)])
        anchors = np.concatenate([order[:known], rest])
        found = _distinct_largest(anchors, sizes, first, k, lambda index: visit.members_at(index) if index < known
                                  else filtered_members(int(anchors[index]), L, visit.common))
    n_cav = visit.common[N_CAV]
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
