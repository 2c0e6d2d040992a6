"""Eq. 13's visit (``cbm.reference.select_anchor``): anchors by decreasing card(L_ij), each one's
filtered set L^(2)_ij, until no remaining candidate set can reach the largest filtered set found.

Filtering never grows a set, so card(L_ij) bounds card(L^(2)_ij): the visit stops at the first
anchor whose candidate set is smaller than the best size found (branch and bound). On a large
scene the anchors after the first ``VISIT_FIRST`` are visited by the threads in interleaved parts
that share the best size found; the merge keeps exactly the anchors one pass visits, in its order,
so the answer, and every size and member the hypotheses and the diagnosis read, is the same.
"""
from __future__ import annotations

import bisect
from dataclasses import dataclass

import numba
import numpy as np

from . import tuning
from .filtered import Filtering, final_size, list_set, listing_held, work_room
from .listing import CandidateSets, in_parts
from .threads import NEVER, check_stop, parts, stop_flag


@dataclass(frozen=True)
class Visit:
    """What eq. 13's visit computed, for the hypotheses to reuse (``anchor_sets``): the anchors in
    ``by_count_descending`` order, the filtered sizes and members (flat, with offsets) of the first
    ``len(sizes)`` of them, and what they were filtered with."""

    order: np.ndarray
    sizes: np.ndarray
    offsets: np.ndarray
    members: np.ndarray
    filtering: Filtering

    def members_of(self, anchor: int, L: CandidateSets) -> np.ndarray:
        """Pair ids of one anchor's filtered set, increasing: the visit's when it filtered the anchor
        (the same kernel, so the same members), else filtered now."""
        at = np.flatnonzero(self.order[:len(self.sizes)] == anchor)
        return self.members_at(int(at[0])) if len(at) else filtered_members(anchor, L, self.filtering)

    def members_at(self, position: int) -> np.ndarray:
        """Pair ids of the filtered set of the anchor at ``position`` of the visit, increasing."""
        return np.sort(self.members[self.offsets[position]:self.offsets[position + 1]])


@numba.njit(cache=True, nogil=True)
def _visited_part(order, span, count, best, shared, width, f, listing, stop):
    """Eq. 13's visit of ``order``'s positions ``begin + part``, ``begin + part + parts``, ... below
    ``end`` (``span``), while an anchor's card(L_ij) (``count``) is not 0 and at least the largest
    size found: ``best``, this part's, and ``shared[0]``, the other parts' (read before each anchor,
    raised on a larger one). Lists with ``listing`` (this thread's part of it). Stops before the next
    anchor once ``stop[0]`` is set (``threads.stop_flag``: the caller then raises ``Cancelled``).

    Returns the visited positions' filtered sizes and members (flat, with offsets), in order. Every
    position the visit of all of ``order`` in one pass reaches is visited: a size read is one some
    anchor reaches, no larger than its card(L_ij), so an anchor is passed over only when an earlier
    anchor's set is larger than its candidate set (``_interleaved``)."""
    begin, end, part, parts = span
    lister, _, judge, n_ego = f
    work = work_room(width, n_ego, lister.lookup.n_cav, len(count))
    steps = max((end - begin - part + parts - 1) // parts, 0)
    sizes = np.empty(steps, np.int64)
    offsets = np.zeros(steps + 1, np.int64)
    members = np.empty(16 * width, np.int64)
    n = 0
    for position in range(begin + part, end, parts):
        anchor = order[position]
        best = max(best, shared[0])
        if count[anchor] == 0 or count[anchor] < best or stop[0]:
            break
        size = final_size(list_set(anchor, lister, listing, work.listed), judge, work)
        if offsets[n] + size > len(members):
            grown = np.empty(2 * len(members) + size, np.int64)
            grown[:offsets[n]] = members[:offsets[n]]
            members = grown
        members[offsets[n]:offsets[n] + size] = work.out[:size]
        sizes[n] = size
        offsets[n + 1] = offsets[n] + size
        if size > best:
            best = size
            shared[0] = max(shared[0], size)
        n += 1
    return sizes[:n], offsets[: n + 1], members[: offsets[n]]


def eq13_visit(order: np.ndarray, L: CandidateSets, f: Filtering) -> tuple[np.ndarray, ...]:
    """Eq. 13's visit of ``order`` (``by_count_descending``): (visited anchors, their filtered sizes,
    their members flat with offsets, where it stopped). The first ``VISIT_FIRST`` anchors are
    visited on the calling thread; on a scene and a visit large enough (``VISIT_APART_FROM``,
    ``VISIT_AHEAD_FROM``) the rest are shared out between the threads, in interleaved parts that
    list into parts of the listing of their own (``in_parts``), else it visits them too."""
    shared, first, stop = np.zeros(1, np.int64), min(tuning.VISIT_FIRST, len(order)), stop_flag()
    pieces = [_visited_part(order, (0, first, 0, 1), L.count, 0, shared, L.width, f, f.listing, stop)]
    if len(pieces[0][0]) == first < len(order):
        best = int(pieces[0][0].max(initial=0))
        n_parts = parts(f.n_ego * f.lister.lookup.n_cav, tuning.VISIT_APART_FROM)
        if (n_parts == 1
                or _work_ahead(order, first, best, L.count, tuning.VISIT_AHEAD_FROM) < tuning.VISIT_AHEAD_FROM):
            pieces.append(_visited_part(order, (first, len(order), 0, 1), L.count, best, shared, L.width, f,
                                        f.listing, stop))
        else:
            visited = in_parts(L.listing, lambda k, n, listing: _visited_part(
                order, (first, len(order), k, n), L.count, best, shared, L.width, f, listing, stop), n_parts)
            pieces.append(_interleaved(order[first:], L.count, best, visited))
    check_stop()
    sizes = np.concatenate([piece[0] for piece in pieces])
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    return order[:len(sizes)], sizes, offsets, np.concatenate([piece[-1] for piece in pieces]), len(sizes)


def _work_ahead(order: np.ndarray, first: int, best: int, count: np.ndarray, enough: float) -> int:
    """The candidate pairs of the anchors from ``order[first]`` on whose card(L_ij) is at least
    ``best``: the most the rest of the visit can filter (``order`` is by decreasing count); summed
    over ``enough`` anchors at most (each holds one pair or more, so more reach ``enough`` anyway)."""
    reach = bisect.bisect_right(order, -best, first, len(order), key=lambda anchor: -count[anchor])
    return int(count[order[first:min(reach, first + int(min(enough, len(order))))]].sum())


def _interleaved(anchors: np.ndarray, count: np.ndarray, best: int,
                 parts: list[tuple]) -> tuple[np.ndarray, np.ndarray]:
    """The parts' results (part k visited ``anchors`` k, k + len(parts), ...; ``count`` their
    card(L_ij)) merged in order up to where the visit in one pass stops: the first position whose
    count is 0 or below the largest size before it (``best`` and the sizes of the positions before)."""
    n = len(parts)
    reached = max((k + n * (len(part[0]) - 1) + 1 for k, part in enumerate(parts) if len(part[0])), default=0)
    counts = count[anchors[:reached]]
    size_at, start_at = np.zeros(reached, np.int64), np.zeros(reached, np.int64)
    base = 0
    for k, (sizes, offsets, members) in enumerate(parts):
        size_at[k::n][:len(sizes)] = sizes
        start_at[k::n][:len(sizes)] = base + offsets[:-1]
        base += len(members)
    before = np.maximum.accumulate(np.concatenate([[best], size_at[:-1]]))
    passed = (counts == 0) | (counts < before)
    stop = int(np.argmax(passed)) if passed.any() else reached
    sizes, starts = size_at[:stop], start_at[:stop]
    total = int(sizes.sum())
    gather = np.repeat(starts - np.cumsum(sizes) + sizes, sizes) + np.arange(total)
    return sizes, np.concatenate([part[2] for part in parts])[gather]


def filtered_members(anchor: int, L: CandidateSets, f: Filtering) -> np.ndarray:
    """Pair ids of one anchor's filtered set L^(2) (``cbm.reference.filtered_set``), increasing (a
    one-to-one set: in increasing ego index too)."""
    with listing_held(L):
        members = _visited_part(np.array([anchor], np.int64), (0, 1, 0, 1), L.count, 0, np.zeros(1, np.int64),
                                L.width, f, f.listing, NEVER)[2]
    return np.sort(members)
