"""Candidate sets as the selection reads them (``CandidateSets``), and the members of those it
listed kept for the next sigma2 edit (``Listing``).

The selection lists the members of every anchor it visits (``members_into``), and a sigma2 edit
makes it visit them again. With sigma1 fixed, L_ij at a smaller sigma2 is L_ij at a larger one
without the members whose L1 distance (eq. 8) exceeds it, in the same order: the window only
shrinks and its test reads the same numbers. So per input and sigma1 the members of the anchors
visited so far are kept with their distances, listed at the largest sigma2 asked for, and a later
call at a sigma2 up to that one filters them instead of listing them again (``listed_into``); a
larger sigma2 starts a new listing there. Threads that list disjoint anchors at once each keep
their rows in a part of the room left (``writers``), closed up after (``closed_up``).
"""
from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple, TypeVar

import numba
import numpy as np

from . import tuning
from .candidates import Lookup, SortedBlocks, members_into, members_room, sorted_blocks
from .context import Prepared
from .threads import parts, shared_out

T = TypeVar("T")

CAPACITY = 1 << 20
"""Members a listing keeps (16 MB); anchors listed once it is full are listed again when asked."""


class ListingArrays(NamedTuple):
    """A listing as its kernels read it: anchor a's members are rows ``at[a]:at[a] + length[a]`` of
    ``ego``, ``cav`` (their objects) and ``distance`` (their L1 distance of eq. 8), without the
    anchor pair; ``at[a]`` is -1 for an anchor not listed. ``fill[0]`` is the first row not in use.
    ``bound[a]``: min(distinct ego objects, distinct CAV objects) of L_ij at ``sigma2``, -1 where
    not known yet: no one-to-one subset of L_ij at this or a smaller sigma2 holds more (the
    runner-up search's bound, ``cbm.engine.filtered.rival_free_size``)."""

    at: np.ndarray
    length: np.ndarray
    ego: np.ndarray
    cav: np.ndarray
    distance: np.ndarray
    fill: np.ndarray
    bound: np.ndarray
    sigma2: float


NO_LISTING = ListingArrays(np.zeros(0, np.int64), np.zeros(0, np.int32), np.zeros(0, np.int32),
                           np.zeros(0, np.int32), np.zeros(0), np.zeros(1, np.int64), np.zeros(0, np.int32), 0.0)
"""The listing of a call that keeps nothing: every anchor is listed at the call's own sigma2."""


@dataclass(frozen=True)
class Listing:
    """The members of L_ij of the anchors listed so far at ``arrays.sigma2``, for one input and
    sigma1. ``lock`` is held by whoever lists into it."""

    width: int
    """The largest card(L_ij) at the listing's sigma2: the room a kernel needs for one set listed there."""
    arrays: ListingArrays
    lock: threading.RLock = field(default_factory=threading.RLock, compare=False)

    @property
    def sigma2(self) -> float:
        return self.arrays.sigma2


def new_listing(sigma2: float, count2: np.ndarray) -> Listing:
    """An empty listing at ``sigma2``, whose card(L_ij) are ``count2``."""
    n_pairs = len(count2)
    return Listing(max(1, int(count2.max(initial=0))),
                   ListingArrays(np.full(n_pairs, -1, np.int64), np.zeros(n_pairs, np.int32),
                                 np.empty(CAPACITY, np.int32), np.empty(CAPACITY, np.int32), np.empty(CAPACITY),
                                 np.zeros(1, np.int64), np.full(n_pairs, -1, np.int32), sigma2))


@numba.njit(cache=True, nogil=True)
def listed_into(i, j, sign, lookup, sigma2, listing, out):
    """The members of L_ij at ``sigma2`` into ``out`` (``members_into``: the same members in the
    same order), from ``listing`` when the anchor is in it, else listed at the listing's sigma2
    (kept in it while it has room) and filtered to the call's."""
    at, length, kept_ego, kept_cav, kept_distance, fill, _, listed_sigma2 = listing
    n_cav, a = lookup.n_cav, i * lookup.n_cav + j
    if len(at) == 0:
        return members_into(i, j, sign, lookup, sigma2, out)
    if at[a] < 0:
        size = members_into(i, j, sign, lookup, listed_sigma2, out)
        kept = max(size - 1, 0)
        if fill[0] + kept <= len(kept_ego):
            at[a], length[a] = fill[0], kept
            for k in range(kept):
                kept_ego[fill[0] + k], kept_cav[fill[0] + k] = out.ego[k], out.cav[k]
                kept_distance[fill[0] + k] = out.distance[k]
            fill[0] += kept
        return _within(i, j, n_cav, sigma2, out, size)
    pair, ego_of, cav_of, distance = out
    size = 0
    for k in range(at[a], at[a] + length[a]):
        e, c, d = kept_ego[k], kept_cav[k], kept_distance[k]
        pair[size], ego_of[size], cav_of[size], distance[size] = e * n_cav + c, e, c, d
        size += d <= sigma2
    return _with_anchor(i, j, n_cav, out, size)


@numba.njit(cache=True, nogil=True)
def _within(i, j, n_cav, sigma2, out, size):
    """The ``size`` rows listed (the anchor pair last) kept in place where their distance is within
    ``sigma2``, the anchor pair after them when any is; returns how many."""
    pair, ego_of, cav_of, distance = out
    kept = 0
    for k in range(size - 1):
        pair[kept], ego_of[kept], cav_of[kept], distance[kept] = pair[k], ego_of[k], cav_of[k], distance[k]
        kept += distance[k] <= sigma2
    return _with_anchor(i, j, n_cav, out, kept)


@numba.njit(cache=True, nogil=True)
def _with_anchor(i, j, n_cav, out, size):
    """``size`` members and, when there are any, the anchor pair after them (as ``members_into`` ends)."""
    if size == 0:
        return 0
    out.pair[size], out.ego[size], out.cav[size], out.distance[size] = i * n_cav + j, i, j, 0.0
    return size + 1


def in_parts(listing: Listing | None, part: Callable[[int, int, ListingArrays], T], n_parts: int) -> list[T]:
    """``part(k, n_parts, arguments)`` for k = 0..n_parts-1 on the threads (``shared_out``), each
    with ``listed_into``'s ``listing`` arguments for a part of the room of its own (``writers``),
    the listing closed up once all are done (``closed_up``); their results in order."""
    own = writers(listing, n_parts)
    results = shared_out([lambda k=k: part(k, n_parts, own[k]) for k in range(n_parts)])
    closed_up(listing, own)
    return results


def writers(listing: Listing | None, n: int) -> list[ListingArrays]:
    """``listed_into``'s ``listing`` arguments for ``n`` threads listing disjoint anchors at once:
    the room left is cut in ``n`` parts, writer k's arrays end where its part ends, and each but the
    first has a fill of its own from where its part begins (the first shares the listing's). Without
    a listing every writer takes ``NO_LISTING``."""
    if listing is None:
        return [NO_LISTING] * n
    arrays = listing.arrays
    begin = int(arrays.fill[0])
    cuts = [begin + (len(arrays.ego) - begin) * k // n for k in range(n + 1)]
    return [arrays._replace(ego=arrays.ego[:end], cav=arrays.cav[:end], distance=arrays.distance[:end],
                            fill=arrays.fill if k == 0 else np.array([start], np.int64))
            for k, (start, end) in enumerate(zip(cuts, cuts[1:]))]


def closed_up(listing: Listing | None, written: list[ListingArrays]) -> None:
    """The rows each writer but the first kept moved down, in order, to follow the rows before them,
    so that the listing has no gap and reads as one thread left it."""
    if listing is None:
        return
    arrays = listing.arrays
    for writer, begin in zip(written[1:], [len(w.ego) for w in written[:-1]]):
        _closed_up(arrays, begin, int(writer.fill[0]))


@numba.njit(cache=True, nogil=True)
def _closed_up(arrays, begin, end):
    """Rows ``begin:end`` moved to ``fill[0]`` on, the anchors listed there pointed to their new
    rows, and ``fill[0]`` past them."""
    shift = begin - arrays.fill[0]
    if end > begin and shift > 0:
        for k in range(begin, end):
            arrays.ego[k - shift], arrays.cav[k - shift] = arrays.ego[k], arrays.cav[k]
            arrays.distance[k - shift] = arrays.distance[k]
        for a in range(len(arrays.at)):
            if begin <= arrays.at[a] < end:
                arrays.at[a] -= shift
    arrays.fill[0] += end - begin


@dataclass(frozen=True)
class CandidateSets:
    """The candidate sets L_ij of every anchor at ``sigma2``: their sizes, and their members on
    demand (``members_into``, or read from the ``listing`` an earlier call left)."""

    count: np.ndarray
    """(Ne * Nc,) card(L_ij), the anchor pair included when the set is not empty."""
    lookup: Lookup
    sigma2: float
    signs: np.ndarray
    """(Ne, Nc) how the CAV frame is turned against each ego frame (``cbm.reference.pair_signs``)."""
    listing: Listing | None = None
    """The members listed so far for these contexts and sigma1, if kept (``cbm.engine.cache``)."""

    @property
    def width(self) -> int:
        """The largest card(L_ij) (at least 1), or the listing's when larger: the room a kernel needs
        for any one set, as listed."""
        largest = max(1, int(self.count.max())) if len(self.count) else 1
        return largest if self.listing is None else max(largest, self.listing.width)

    def members(self, anchor: int) -> np.ndarray:
        """Pair ids of L_ij for ``anchor = i * Nc + j``, in increasing order."""
        i, j = divmod(int(anchor), self.signs.shape[1])
        out = members_room(int(self.count[anchor]) + 1)
        size = members_into(i, j, float(self.signs[i, j]), self.lookup, self.sigma2, out)
        return np.sort(out.pair[:size])


def candidate_sets(prepared: Prepared, sigma1_rad: float, sigma2: float, count2: np.ndarray,
                   blocks: tuple[SortedBlocks, SortedBlocks] | None = None,
                   listing: Listing | None = None) -> CandidateSets:
    """L_ij of every anchor from its counts ``count2``: the members listed on demand from both
    agents' sorted blocks (``both_blocks``, unless given)."""
    blocks = both_blocks(prepared) if blocks is None else blocks
    return CandidateSets(count2, Lookup(*blocks, prepared.signs.shape[1], math.cos(sigma1_rad) ** 2), sigma2,
                         prepared.signs, listing)


def both_blocks(prepared: Prepared) -> tuple[SortedBlocks, SortedBlocks]:
    """Both agents' sorted blocks, sorted at once from ``BLOCKS_APART_FROM`` context vectors (numpy's
    sort and ``_gathered`` run without the interpreter lock)."""
    ego, cav = prepared.ego_context, prepared.cav_context
    n_ego, n_cav = prepared.signs.shape
    tasks = [lambda: sorted_blocks(ego, n_ego), lambda: sorted_blocks(cav, n_cav)]
    if parts(min(len(ego.vectors), len(cav.vectors)), tuning.BLOCKS_APART_FROM) == 1:
        return tuple(task() for task in tasks)
    return tuple(shared_out(tasks))
