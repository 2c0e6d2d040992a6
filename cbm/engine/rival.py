"""The runner-up search (``cbm.reference.runner_up``): the largest filtered set that shares no pair
with the winner's, the strongest rival answer, which the consensus margin compares with.

Anchors are visited one by one by decreasing card(L_ij), from where eq. 13's visit stopped, and the
search stops at the first whose card(L_ij) is no larger than the best rival so far (every later
one's is no larger either). An anchor that is one of the winner's pairs cannot be a rival with the
released rule or without consensus: its own pair survives in its set. Chunks of anchors are shared
out between the threads in interleaved parts that read and raise one largest size found; on a
mid-sized scene without a listing the whole search instead runs beside the verification of the
winner (``runner_up_beside``).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

import numba
import numpy as np

from . import tuning
from .filtered import PAPER, Filtering, listing_held, rival_free_size, work_room
from .listing import CandidateSets, in_parts
from .threads import check_stop, parts, shared_out, stop_flag

T = TypeVar("T")


@dataclass(frozen=True)
class RivalSearch:
    """Where the runner-up search starts: the anchors in ``by_count_descending`` order, the first
    one eq. 13's visit did not filter, the largest rival among those it did, and the winner's pairs
    (``in_winner``, by pair id)."""

    order: np.ndarray
    first: int
    found: int
    in_winner: np.ndarray
    L: CandidateSets
    filtering: Filtering


@numba.njit(cache=True, nogil=True)
def _largest_rival(anchors, span, count, best, shared, width, excluded, f, listing, stop):
    """The largest of ``best`` and the filtered sizes of ``anchors[part::parts]`` (``span``: part,
    parts; by decreasing card(L_ij) ``count``) whose sets hold no ``excluded`` pair
    (``rival_free_size``), visiting them in order and stopping at the first whose count is at most
    the largest so far. ``shared[0]`` is the largest size the other parts have found: read before
    each anchor, raised when this part finds a larger one. Same answer as the maximum over every
    anchor: every value read there is a size some anchor reaches, an anchor whose count is at most it
    cannot raise the maximum (filtering never grows a set), and every later anchor's count is no
    larger. Stops before the next anchor once ``stop[0]`` is set (``threads.stop_flag``: the caller
    then raises ``Cancelled``)."""
    part, parts = span
    lister, _, judge, n_ego = f
    work = work_room(width, n_ego, lister.lookup.n_cav, len(excluded))
    for n in range(part, len(anchors), parts):
        best = max(best, shared[0])
        if count[anchors[n]] <= best or stop[0]:
            break
        size = rival_free_size(anchors[n], best, excluded, lister, listing, judge, work)
        if size > best:
            best = size
            shared[0] = max(shared[0], size)
    return best


def runner_up(search: RivalSearch | None) -> int:
    """The largest filtered set sharing no pair with the winner (0 without a search: no winner).
    The anchors go in chunks (the first ``RIVAL_FIRST``, then ``RIVAL_CHUNK`` at a time), each
    visited on the calling thread or, from ``RIVAL_PAIRS_FROM`` candidate pairs, in interleaved parts
    on the threads; with a listing each part keeps what it lists in a part of the room of its own
    (``in_parts``)."""
    if search is None:
        return 0
    L, f, best, stop = search.L, search.filtering, search.found, stop_flag()
    ends = range(search.first + tuning.RIVAL_FIRST, len(search.order) + tuning.RIVAL_CHUNK, tuning.RIVAL_CHUNK)
    with listing_held(L):
        for chunk, end in zip([search.first, *ends], ends):
            anchors = search.order[chunk:end]
            anchors = anchors[L.count[anchors] > best]
            if len(anchors) == 0:
                break
            if f.judge.rule != PAPER:
                anchors = anchors[~search.in_winner[anchors]]
            shared = np.array([best], np.int64)
            n_parts = parts(int(L.count[anchors].sum()), tuning.RIVAL_PAIRS_FROM)
            if n_parts == 1:
                best = int(_largest_rival(anchors, (0, 1), L.count, best, shared, L.width, search.in_winner, f,
                                          f.listing, stop))
                check_stop()
                continue
            found = in_parts(L.listing, lambda k, n, listing, anchors=anchors, shared=shared, best=best: _largest_rival(
                anchors, (k, n), L.count, best, shared, L.width, search.in_winner, f, listing, stop), n_parts)
            best = int(max(found))
    return best


def runner_up_beside(search: RivalSearch | None, meanwhile: Callable[[], T]) -> tuple[int, T]:
    """(``runner_up(search)``, ``meanwhile()``): at once, the search on a thread of its own, where
    it pays for the hand-over and would not be shared out itself (from ``RIVAL_BESIDE_FROM`` to
    ``RIVAL_BESIDE_BELOW`` ego x CAV pairs) and lists into no listing (``meanwhile`` may read the
    candidate sets); else one after the other. ``meanwhile`` goes first, so that the calling thread
    starts it at once while a pool thread wakes for the search."""
    if search is None or search.L.listing is not None or not (
            tuning.RIVAL_BESIDE_FROM <= len(search.L.count) < tuning.RIVAL_BESIDE_BELOW):
        return runner_up(search), meanwhile()
    result, count = shared_out([meanwhile, lambda: runner_up(search)])
    return count, result
