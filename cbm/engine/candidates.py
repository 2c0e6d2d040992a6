"""The members of one candidate set L_ij on demand (``cbm.reference.candidate_set``).

The join only counts; when the selection asks for the members of one L_ij they are listed again
by a window sliding over both anchors' vectors sorted by x + y, O(N) per anchor pair.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from .context import Context
from .grid import MARGIN, accepts
from .threads import check_stop

SORTED_AT_ONCE = 256
"""Anchors whose blocks ``sorted_blocks`` sorts between two ``check_stop``: tens of milliseconds."""


class SortedBlocks(NamedTuple):
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
    ``_gathered`` puts the equal ones back in order as it gathers the rows; ``SORTED_AT_ONCE``
    anchors at a time, each time asking whether the computation was abandoned."""
    per_anchor = max(n_objects - 1, 0)
    rows = len(context.vectors)
    key = context.vectors[:, 0] + context.vectors[:, 1]
    blocks = SortedBlocks(np.empty(rows), np.empty(rows), np.empty(rows), np.empty(rows, context.member.dtype),
                          per_anchor)
    n_blocks = rows // per_anchor if rows else 0
    for first in range(0, n_blocks, SORTED_AT_ONCE):
        check_stop()
        last = min(first + SORTED_AT_ONCE, n_blocks)
        order = np.argsort(key[first * per_anchor:last * per_anchor].reshape(last - first, per_anchor), axis=1)
        _gathered(key, context.vectors, context.member, order, first, blocks)
    return blocks


@numba.njit(cache=True, nogil=True)
def _gathered(key, vectors, member, order, first, out):
    """Block by block (row ``b`` of ``order``, the order of the keys of block ``first + b``'s rows),
    the rows in order of their keys into the blocks ``out``; each run of equal keys in increasing
    row order (``order`` is changed), as a stable sort leaves them."""
    sorted_key, x, y, sorted_member, per_anchor = out
    for b in range(order.shape[0]):
        lo, block = (first + b) * per_anchor, order[b]
        run, last = 0, np.nan
        for q in range(per_anchor):
            row = lo + block[q]
            if key[row] != last:
                if q - run > 1:
                    _in_row_order(key, vectors, member, lo, block, run, q, out)
                run, last = q, key[row]
            sorted_key[lo + q], x[lo + q], y[lo + q], sorted_member[lo + q] = (key[row], vectors[row, 0],
                                                                               vectors[row, 1], member[row])
        if per_anchor - run > 1:
            _in_row_order(key, vectors, member, lo, block, run, per_anchor, out)


@numba.njit(cache=True, nogil=True)
def _in_row_order(key, vectors, member, lo, block, first, last, out):
    """The run ``first:last`` of equal keys of the block at ``lo`` gathered again in row order."""
    sorted_key, x, y, sorted_member, _ = out
    block[first:last] = np.sort(block[first:last])
    for q in range(first, last):
        row = lo + block[q]
        sorted_key[lo + q], x[lo + q], y[lo + q], sorted_member[lo + q] = (key[row], vectors[row, 0],
                                                                           vectors[row, 1], member[row])


class Lookup(NamedTuple):
    """What ``members_into`` reads to list any anchor's candidate set: both agents' sorted blocks,
    Nc, and cos^2(sigma1)."""

    ego: SortedBlocks
    cav: SortedBlocks
    n_cav: int
    cos2_sigma1: float


class Members(NamedTuple):
    """Where ``members_into`` writes a set's members: their pair ids, their ego and CAV objects (so
    that no consumer divides a pair id) and their L1 distances of eq. 8."""

    pair: np.ndarray
    ego: np.ndarray
    cav: np.ndarray
    distance: np.ndarray


def members_room(width: int) -> Members:
    """Room for one set of up to ``width`` members."""
    return Members(np.empty(width, np.int64), np.empty(width, np.int64), np.empty(width, np.int64), np.empty(width))


@numba.njit(cache=True, nogil=True)
def members_into(i, j, sign, lookup, sigma2, out):
    """The members of L_ij at ``sigma2`` (``cbm.reference.candidate_set``) into ``out``
    (``Members``), the anchor pair last (distance 0); returns how many.

    Both anchors' blocks are sorted by ``x + y``, so the CAV vectors (turned by ``sign``) whose key
    lies within sigma2 of an ego vector's form a window that only slides forward: O(N) per anchor
    pair plus the vectors in the windows.
    """
    ego, cav, n_cav, cos2_sigma1 = lookup
    e_key, ex, ey, e_member, per_ego = ego
    c_key, cx, cy, c_member, per_cav = cav
    pair, ego_of, cav_of, distance = out
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
                pair[size] = e_member[u] * n_cav + c_member[v]
                ego_of[size], cav_of[size], distance[size] = e_member[u], c_member[v], l1
                size += 1
            k += 1
    if size:
        pair[size] = i * n_cav + j
        ego_of[size], cav_of[size], distance[size] = i, j, 0.0
        size += 1
    return size


@numba.njit(cache=True, nogil=True, inline="always")
def _turned(key, lo, hi, k, sign):
    """The k-th smallest key of the block lo..hi-1 after turning its vectors by ``sign``."""
    return key[lo + k] if sign > 0 else -key[hi - 1 - k]
