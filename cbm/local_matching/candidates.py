"""Step 4c of local matching: the members of one candidate set L_ij on demand (paper eq. 8).

The join only counts; when the selection asks for the members of one L_ij they are listed again
by a window sliding over both anchors' vectors sorted by x + y, O(N) per anchor pair.
"""
from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field

import numba
import numpy as np

from ..context import Context
from .grid import MARGIN, accepts
from .join import PARALLEL_FROM, POOL


@dataclass(frozen=True)
class SortedBlocks:
    """One agent's context vectors, each anchor's block of ``per_anchor`` rows sorted by the key
    ``x + y``: two vectors within L1 distance r have keys within r, and the key spreads the
    vectors along the streets of either axis, where x alone would pile them up."""

    key: np.ndarray
    x: np.ndarray
    y: np.ndarray
    member: np.ndarray
    per_anchor: int


def sorted_blocks(context: Context, n_objects: int) -> SortedBlocks:
    """Each anchor's context vectors sorted by ``x + y`` (for the sliding windows of ``members_into``),
    equal keys in their order in the context (a stable sort): numpy's quicksort orders the keys,
    ``_gathered`` puts the equal ones back in order as it gathers the rows."""
    per_anchor = max(n_objects - 1, 0)
    rows = len(context.vectors)
    key = context.vectors[:, 0] + context.vectors[:, 1]
    sorted_key, x, y, member = np.empty(rows), np.empty(rows), np.empty(rows), np.empty(rows, context.member.dtype)
    if rows:
        order = np.argsort(key.reshape(rows // per_anchor, per_anchor), axis=1)
        _gathered(key, context.vectors, context.member, order, sorted_key, x, y, member)
    return SortedBlocks(sorted_key, x, y, member, per_anchor)


@numba.njit(cache=True, nogil=True)
def _gathered(key, vectors, member, order, sorted_key, x, y, sorted_member):
    """Block by block (row ``b`` of ``order``, the order of the keys of rows ``b * per_anchor`` on),
    the rows in order of their keys into ``sorted_key``, ``x``, ``y``, ``sorted_member``; each run
    of equal keys in increasing row order (``order`` is changed), as a stable sort leaves them."""
    per_anchor = order.shape[1]
    for b in range(order.shape[0]):
        lo, block = b * per_anchor, order[b]
        run, last = 0, np.nan
        for q in range(per_anchor):
            row = lo + block[q]
            if key[row] != last:
                if q - run > 1:
                    _in_row_order(key, vectors, member, lo, block, run, q, sorted_key, x, y, sorted_member)
                run, last = q, key[row]
            sorted_key[lo + q], x[lo + q], y[lo + q], sorted_member[lo + q] = (key[row], vectors[row, 0],
                                                                               vectors[row, 1], member[row])
        if per_anchor - run > 1:
            _in_row_order(key, vectors, member, lo, block, run, per_anchor, sorted_key, x, y, sorted_member)


@numba.njit(cache=True, nogil=True)
def _in_row_order(key, vectors, member, lo, block, first, last, sorted_key, x, y, sorted_member):
    """The run ``first:last`` of equal keys of the block at ``lo`` gathered again in row order."""
    block[first:last] = np.sort(block[first:last])
    for q in range(first, last):
        row = lo + block[q]
        sorted_key[lo + q], x[lo + q], y[lo + q], sorted_member[lo + q] = (key[row], vectors[row, 0],
                                                                           vectors[row, 1], member[row])


@numba.njit(cache=True, nogil=True)
def members_into(i, j, sign, e_key, ex, ey, e_member, per_ego, c_key, cx, cy, c_member, per_cav, n_cav, cos2_sigma1,
                 sigma2, out, ego_of, cav_of, distance):
    """The members of L_ij (eq. 8) into ``out`` as pair ids, into ``ego_of`` and ``cav_of`` as their
    ego and CAV objects (so that no consumer divides a pair id) and into ``distance`` as their L1
    distance (eq. 7), the anchor pair last (distance 0); returns how many.

    Both anchors' blocks are sorted by ``x + y``, so the CAV vectors (turned by ``sign``) whose key
    lies within sigma2 of an ego vector's form a window that only slides forward: O(N) per anchor
    pair plus the vectors in the windows.
    """
    size = 0
    lo_j, hi_j = j * per_cav, (j + 1) * per_cav
    window = 0
    for u in range(i * per_ego, (i + 1) * per_ego):
        zx, zy, zk = ex[u], ey[u], e_key[u]
        while window < per_cav and _turned(c_key, lo_j, hi_j, window, sign) < zk - sigma2 - MARGIN:
            window += 1
        k = window
        while k < per_cav:
            if _turned(c_key, lo_j, hi_j, k, sign) > zk + sigma2 + MARGIN:
                break
            v = lo_j + k if sign > 0 else hi_j - 1 - k
            l1 = accepts(zx, zy, sign * cx[v], sign * cy[v], cos2_sigma1, sigma2)
            if l1 >= 0.0:
                out[size] = e_member[u] * n_cav + c_member[v]
                ego_of[size], cav_of[size], distance[size] = e_member[u], c_member[v], l1
                size += 1
            k += 1
    if size:
        out[size] = i * n_cav + j
        ego_of[size], cav_of[size], distance[size] = i, j, 0.0
        size += 1
    return size


@numba.njit(cache=True, nogil=True, inline="always")
def _turned(key, lo, hi, k, sign):
    """The k-th smallest key of the block lo..hi-1 after turning its vectors by ``sign``."""
    return key[lo + k] if sign > 0 else -key[hi - 1 - k]


@dataclass(frozen=True)
class Listing:
    """The members of L_ij of the anchors listed so far at ``sigma2`` (``listing.listed_into``): anchor a's are rows
    ``at[a]:at[a] + length[a]`` of ``ego``, ``cav`` (their objects) and ``distance`` (their L1
    distance of eq. 7), without the anchor pair; ``at[a]`` is -1 for an anchor not listed. ``fill``
    holds the rows in use. ``lock`` is held by whoever lists into it."""

    sigma2: float
    width: int
    """The largest card(L_ij) at ``sigma2``: the room a kernel needs for one set listed there."""
    at: np.ndarray
    length: np.ndarray
    ego: np.ndarray
    cav: np.ndarray
    distance: np.ndarray
    fill: np.ndarray
    bound: np.ndarray
    """Per anchor, min(distinct ego objects, distinct CAV objects) of L_ij at ``sigma2``, -1 where
    not known yet: no one-to-one subset of L_ij at this or a smaller sigma2 holds more (the
    runner-up search's bound, ``cbm.selection``)."""
    lock: threading.RLock = field(default_factory=threading.RLock, compare=False)

    def arguments(self) -> tuple:
        """``listed_into``'s ``listing`` argument (for calls at a sigma2 up to ``self.sigma2``): only
        one thread at a time may list into it (``lock``)."""
        return (self.at, self.length, self.ego, self.cav, self.distance, self.fill, self.bound, self.sigma2)


NO_LISTING = Listing(0.0, 1, np.zeros(0, np.int64), np.zeros(0, np.int32), np.zeros(0, np.int32),
                     np.zeros(0, np.int32), np.zeros(0), np.zeros(1, np.int64), np.zeros(0, np.int32))
"""The listing of a call that keeps nothing (no ``kept``): every anchor is listed at its own sigma2."""


@dataclass(frozen=True)
class CandidateSets:
    """The candidate sets L_ij of every anchor (eq. 8): their sizes, and their members on demand."""

    count: np.ndarray
    """(Ne * Nc,) card(L_ij), the anchor pair included when the set is not empty."""
    lookup: tuple
    """``members_into``'s arguments after (i, j, sign) and before its outputs."""
    signs: np.ndarray
    """(Ne, Nc) how the CAV frame is turned against each ego frame (``cbm.context.pair_signs``)."""
    listing: Listing | None = None
    """The members listed so far for these contexts and sigma1, if kept."""

    @property
    def width(self) -> int:
        """The largest card(L_ij) (at least 1), or the listing's when larger: the room a kernel needs
        for any one set, as listed."""
        largest = max(1, int(self.count.max())) if len(self.count) else 1
        return largest if self.listing is None else max(largest, self.listing.width)

    def members(self, anchor: int) -> np.ndarray:
        """Pair ids of L_ij for ``anchor = i * Nc + j``, in increasing order."""
        n_cav = self.signs.shape[1]
        i, j = divmod(int(anchor), n_cav)
        out, ego_of, cav_of = (np.empty(int(self.count[anchor]) + 1, np.int64) for _ in range(3))
        size = members_into(i, j, float(self.signs[i, j]), *self.lookup, out, ego_of, cav_of,
                            np.empty(len(out)))
        return np.sort(out[:size])



def member_lookup(ego: Context, cav: Context, n_ego: int, n_cav: int, sigma1_rad: float, sigma2: float,
                  kept: dict | None = None) -> tuple:
    """What ``members_into`` needs after (i, j, sign) to list any anchor's candidate set; the sorted
    blocks are taken from ``kept`` when an earlier call on the same contexts put them there."""
    blocks = None if kept is None else kept.get("blocks")
    if blocks is None:
        blocks = _both_blocks(ego, cav, n_ego, n_cav)
        if kept is not None:
            kept["blocks"] = blocks
    e, c = blocks
    return (e.key, e.x, e.y, e.member, e.per_anchor, c.key, c.x, c.y, c.member, c.per_anchor, n_cav,
            math.cos(sigma1_rad) ** 2, sigma2)


def _both_blocks(ego: Context, cav: Context, n_ego: int, n_cav: int) -> tuple[SortedBlocks, SortedBlocks]:
    """Both agents' sorted blocks; from ``PARALLEL_FROM`` context vectors on, the ego's on ``POOL``
    while the CAV's are sorted here (numpy's sort and ``_gathered`` run without the interpreter lock)."""
    if min(len(ego.vectors), len(cav.vectors)) < PARALLEL_FROM:
        return sorted_blocks(ego, n_ego), sorted_blocks(cav, n_cav)
    ego_blocks = POOL.submit(sorted_blocks, ego, n_ego)
    cav_blocks = sorted_blocks(cav, n_cav)
    return ego_blocks.result(), cav_blocks
