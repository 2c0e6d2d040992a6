"""One anchor's filtered set L^(2)_ij (paper eq. 9-12), for the selection's visits (``cbm.selection``).

Its members are listed (``list_set``: from the listing kept after a sigma2 edit, or anew), filtered by
the consensus and the one-to-one rule (``cbm.consensus.final_set``) and rejected when its pairs lie
on average farther apart than the released code's distance limit (``final_size``). The runner-up
search asks first whether a set can matter at all (``rival_bound``): a set whose objects cannot
form a one-to-one set larger than the largest rival, or that is sure to keep a pair of the winner,
is not filtered (``rival_free_size``). ``kernel_arguments`` gathers what these kernels share.
"""
from __future__ import annotations

import contextlib
import math

import numba
import numpy as np

from .consensus import RULE_CODES, PairSets, final_set
from .local_matching import NO_LISTING, CandidateSets, listed_into

PAPER = RULE_CODES["paper"]
"""The rule code of eq. 10 as the paper states it, the one rule that may drop a lone pair."""


@numba.njit(cache=True, nogil=True)
def rival_bound(member, ego, cav, size, excluded, lone_kept, ego_count, cav_count):
    """For the listed pairs ``member[:size]`` (objects ``ego``, ``cav``): min(distinct ego objects,
    distinct CAV objects), the most pairs their filtered set can hold (L^(2) is a one-to-one subset
    of L_ij: eq. 10-11 only remove members); and whether, by a rule that keeps a pair alone in its
    row and column of L_ij (``lone_kept``: off and released), such a lone pair is ``excluded``, so
    that L^(2) holds it. The count arrays must be zero and are left so."""
    distinct_ego, distinct_cav = 0, 0
    for row in range(size):
        distinct_ego += ego_count[ego[row]] == 0
        distinct_cav += cav_count[cav[row]] == 0
        ego_count[ego[row]] += 1
        cav_count[cav[row]] += 1
    holds_excluded = False
    for row in range(size):
        holds_excluded |= lone_kept and excluded[member[row]] and ego_count[ego[row]] == 1 and cav_count[cav[row]] == 1
    for row in range(size):
        ego_count[ego[row]], cav_count[cav[row]] = 0, 0
    return min(distinct_ego, distinct_cav), holds_excluded


@numba.njit(cache=True, nogil=True)
def list_set(anchor, signs, lookup, listing, n_cav, work):
    """The members of L_ij of ``anchor`` listed into ``work``'s candidates, their objects and
    distances (``listed_into``); returns how many."""
    candidates, ego_of, cav_of, distance = work[5], work[6], work[7], work[8]
    i, j = anchor // n_cav, anchor % n_cav
    return listed_into(i, j, signs[i, j], lookup, listing, candidates, ego_of, cav_of, distance)


@numba.njit(cache=True, nogil=True)
def final_size(listed, voted_start, voted_by, rule, centres, limit, work):
    """card(L^(2)) of the ``listed`` members of L_ij in ``work`` (``list_set``), its members into
    ``work``'s ``out``; 0 when its pairs are farther apart than the limit on average (their
    distances computed from the ``centres``, ego and CAV). ``work`` comes from ``work_arrays``."""
    scratch, ego_count, cav_count, voter_here, out, candidates, ego_of, cav_of, distance = work
    size = final_set(candidates, ego_of, cav_of, listed, voted_start, voted_by, rule, scratch, ego_count, cav_count,
                     voter_here, out)
    ego_xy, cav_xy = centres
    total = 0.0
    for k in range(size):
        row = out[k]
        dx, dy = ego_xy[ego_of[row], 0] - cav_xy[cav_of[row], 0], ego_xy[ego_of[row], 1] - cav_xy[cav_of[row], 1]
        total += math.sqrt(dx * dx + dy * dy)
        out[k] = candidates[row]
    return size if size == 0 or total / size <= limit else 0


@numba.njit(cache=True, nogil=True)
def work_arrays(width, n_ego, n_cav, n_pairs):
    """The zeroed work arrays ``list_set`` and ``final_size`` need: scratch, counts, voter flags,
    out, candidates and their ego and CAV objects and distances."""
    return (np.zeros((2, width), np.bool_), np.zeros(n_ego, np.int64), np.zeros(n_cav, np.int64),
            np.zeros(n_pairs, np.bool_), np.empty(width, np.int64), np.empty(width + 1, np.int64),
            np.empty(width + 1, np.int64), np.empty(width + 1, np.int64), np.empty(width + 1))


@numba.njit(cache=True, nogil=True)
def rival_free_size(anchor, beyond, excluded, signs, lookup, listing, voted_start, voted_by, rule, n_ego, n_cav,
                    centres, limit, work):
    """card(L^(2)) of one anchor, 0 where the distance limit rejects it, its set holds an
    ``excluded`` pair or it cannot exceed ``beyond`` (``rival_bound``, or the bound the listing keeps
    from a larger or equal sigma2: then it is not filtered, nor listed)."""
    bound, listed_sigma2 = listing[6], listing[7]
    if len(bound) and 0 <= bound[anchor] <= beyond:
        return 0
    listed = list_set(anchor, signs, lookup, listing, n_cav, work)
    most, holds_excluded = rival_bound(work[5], work[6], work[7], listed, excluded, rule != PAPER, work[1], work[2])
    if len(bound) and lookup[-1] == listed_sigma2:
        bound[anchor] = most
    if most <= beyond or holds_excluded:
        return 0
    size = final_size(listed, voted_start, voted_by, rule, centres, limit, work)
    for k in range(size):
        if excluded[work[4][k]]:
            return 0
    return size


@numba.njit(cache=True, nogil=True)
def filtered_sizes_of(anchors, width, signs, lookup, listing, voted_start, voted_by, rule, n_ego, n_cav, centres,
                      limit):
    """card(L^(2)) of each anchor, 0 where the distance limit rejects it."""
    work = work_arrays(width, n_ego, n_cav, n_ego * n_cav)
    sizes = np.zeros(len(anchors), np.int64)
    for n in range(len(anchors)):
        sizes[n] = final_size(list_set(anchors[n], signs, lookup, listing, n_cav, work), voted_start, voted_by,
                              rule, centres, limit, work)
    return sizes


def kernel_arguments(L: CandidateSets, voted_by: PairSets, rule: str | None, ego_xy: np.ndarray,
                     cav_xy: np.ndarray, distance_limit: float) -> tuple:
    """The arguments the visiting kernels share, after their own (``RULE``, ``N_CAV``: where the rule
    and Nc are). The kernels add the anchors they list to
    the listing: the caller holds its lock (``listing_held``)."""
    centres = (np.ascontiguousarray(ego_xy, dtype=float), np.ascontiguousarray(cav_xy, dtype=float))
    listing = (NO_LISTING if L.listing is None else L.listing).arguments()
    return (L.signs, L.lookup, listing, voted_by.start, voted_by.member, RULE_CODES[rule], len(ego_xy), len(cav_xy),
            centres, float(distance_limit))


LISTING, RULE, N_EGO, N_CAV = 2, 5, 6, 7


def listing_held(L: CandidateSets):
    """The lock of ``L``'s listing, held while kernels list into it (a no-op without one)."""
    return contextlib.nullcontext() if L.listing is None else L.listing.lock
