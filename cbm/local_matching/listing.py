"""Candidate sets listed once per input and sigma1, read again after a sigma2 edit (paper eq. 7-8).

The selection (eq. 12-13) lists the members of every anchor it visits (``members_into``), and a
sigma2 edit makes it visit them again. With sigma1 fixed, L_ij at a smaller sigma2 is L_ij at a
larger one without the members whose L1 distance (eq. 7) exceeds it, in the same order: the
listing's window only shrinks and its test reads the same numbers. So per input and sigma1 the
members of the anchors visited so far are kept with their distances (``Listing``), listed at the
largest sigma2 asked for, and a later call at a sigma2 up to that one filters them instead of
listing them again; a larger sigma2 starts a new listing there. Two threads that list disjoint
anchors at once keep their rows in the two halves of the room left (``two_writers``), closed up
after (``closed_up``).
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import numba
import numpy as np

from ..reuse import recall, remember
from .candidates import NO_LISTING, Listing, members_into
from .join import POOL

T = TypeVar("T")

CAPACITY = 1 << 20
"""Members a listing keeps (16 MB); anchors listed once it is full are listed again when asked."""


def listing_for(kept: dict | None, sigma1_rad: float, sigma2: float, count2: np.ndarray) -> Listing | None:
    """The listing kept for this sigma1 when it was listed at a sigma2 of at least ``sigma2``, else a
    new empty one at ``sigma2``, whose card(L_ij) are ``count2`` (kept in ``kept``, replacing the one
    before); None without ``kept``."""
    if kept is None:
        return None
    found = recall(kept, "listing", (sigma1_rad,))
    if found is None or found.sigma2 < sigma2:
        n_pairs = len(count2)
        found = Listing(sigma2, max(1, int(count2.max(initial=0))), np.full(n_pairs, -1, np.int64),
                        np.zeros(n_pairs, np.int32), np.empty(CAPACITY, np.int32), np.empty(CAPACITY, np.int32),
                        np.empty(CAPACITY), np.zeros(1, np.int64), np.full(n_pairs, -1, np.int32))
        remember(kept, "listing", (sigma1_rad,), found)
    return found


@numba.njit(cache=True, nogil=True)
def listed_into(i, j, sign, lookup, listing, out, ego_of, cav_of, distance):
    """The members of L_ij at the sigma2 of ``lookup`` (``members_into``, same members in the same
    order), from ``listing`` (``Listing.arguments``) when the anchor is in it, else listed at the
    listing's sigma2 (kept in it while it has room) and filtered to the call's."""
    at, length, kept_ego, kept_cav, kept_distance, fill, _, listed_sigma2 = listing
    e_key, ex, ey, e_member, per_ego, c_key, cx, cy, c_member, per_cav, n_cav, cos2_sigma1, sigma2 = lookup
    a = i * n_cav + j
    if len(at) == 0:
        return members_into(i, j, sign, *lookup, out, ego_of, cav_of, distance)
    if at[a] < 0:
        size = members_into(i, j, sign, e_key, ex, ey, e_member, per_ego, c_key, cx, cy, c_member, per_cav, n_cav,
                            cos2_sigma1, listed_sigma2, out, ego_of, cav_of, distance)
        kept = max(size - 1, 0)
        if fill[0] + kept <= len(kept_ego):
            at[a], length[a] = fill[0], kept
            for k in range(kept):
                kept_ego[fill[0] + k], kept_cav[fill[0] + k] = ego_of[k], cav_of[k]
                kept_distance[fill[0] + k] = distance[k]
            fill[0] += kept
        return _within(i, j, n_cav, sigma2, out, ego_of, cav_of, distance, size)
    size = 0
    for k in range(at[a], at[a] + length[a]):
        out[size] = kept_ego[k] * n_cav + kept_cav[k]
        ego_of[size], cav_of[size], distance[size] = kept_ego[k], kept_cav[k], kept_distance[k]
        size += kept_distance[k] <= sigma2
    return _with_anchor(i, j, n_cav, out, ego_of, cav_of, distance, size)


@numba.njit(cache=True, nogil=True)
def _within(i, j, n_cav, sigma2, out, ego_of, cav_of, distance, size):
    """The ``size`` rows listed (the anchor pair last) kept in place where their distance is within
    ``sigma2``, the anchor pair after them when any is; returns how many."""
    kept = 0
    for k in range(size - 1):
        out[kept], ego_of[kept], cav_of[kept], distance[kept] = out[k], ego_of[k], cav_of[k], distance[k]
        kept += distance[k] <= sigma2
    return _with_anchor(i, j, n_cav, out, ego_of, cav_of, distance, kept)


@numba.njit(cache=True, nogil=True)
def _with_anchor(i, j, n_cav, out, ego_of, cav_of, distance, size):
    """``size`` members and, when there are any, the anchor pair after them (as ``members_into`` ends)."""
    if size == 0:
        return 0
    out[size], ego_of[size], cav_of[size], distance[size] = i * n_cav + j, i, j, 0.0
    return size + 1


def in_two_parts(listing: Listing | None, part: Callable[..., T], *args) -> tuple[T, T]:
    """``part(0, arguments, *args)`` on the calling thread while ``part(1, arguments, *args)`` runs
    on ``POOL``, each with ``listed_into``'s ``listing`` arguments for its half of the room
    (``two_writers``), the listing closed up once both are done (``closed_up``); their two results."""
    mine, theirs, middle = two_writers(listing)
    job = POOL.submit(part, 1, theirs, *args)
    own = part(0, mine, *args)
    other = job.result()
    closed_up(listing, theirs, middle)
    return own, other


def two_writers(listing: Listing | None) -> tuple[tuple, tuple, int]:
    """``listed_into``'s ``listing`` arguments for two threads listing disjoint anchors at once, and
    where the second's rows begin: the first keeps rows below the middle of the room left (its
    arrays end there), the second from the middle on, with a fill of its own. ``closed_up`` moves
    the second's rows down once both are done. Without a listing both take ``NO_LISTING``'s."""
    if listing is None:
        arguments = NO_LISTING.arguments()
        return arguments, arguments, 0
    middle = int(listing.fill[0]) + (len(listing.ego) - int(listing.fill[0])) // 2
    first = (listing.at, listing.length, listing.ego[:middle], listing.cav[:middle], listing.distance[:middle],
             listing.fill, listing.bound, listing.sigma2)
    second = (listing.at, listing.length, listing.ego, listing.cav, listing.distance, np.array([middle], np.int64),
              listing.bound, listing.sigma2)
    return first, second, middle


def closed_up(listing: Listing | None, second: tuple, middle: int) -> None:
    """The rows the second of ``two_writers`` kept (from ``middle``) moved down to follow the
    first's, so that the listing has no gap."""
    if listing is not None:
        _closed_up(listing.at, listing.ego, listing.cav, listing.distance, listing.fill, middle, second[5][0])


@numba.njit(cache=True, nogil=True)
def _closed_up(at, ego, cav, distance, fill, middle, end):
    """Rows ``middle:end`` moved to ``fill[0]`` on, the anchors listed there pointed to their new
    rows, and ``fill[0]`` past them."""
    shift = middle - fill[0]
    if end > middle and shift > 0:
        for k in range(middle, end):
            ego[k - shift], cav[k - shift], distance[k - shift] = ego[k], cav[k], distance[k]
        for a in range(len(at)):
            if at[a] >= middle:
                at[a] -= shift
    fill[0] += end - middle
