"""One anchor's filtered set L^(2)_ij (``cbm.reference.filtered_set``), for the selection's visits.

Its members are listed (``list_set``: from the listing kept after a sigma2 edit, or anew),
filtered by the consensus and the one-to-one rule (``final_set``) and rejected when its pairs lie
on average farther apart than the distance limit (``final_size``). The runner-up search asks first
whether a set can matter at all: a set whose objects cannot form a one-to-one set larger than the
largest rival, or that is sure to keep a pair of the winner, is not filtered (``rival_free_size``).
``Filtering`` bundles what these kernels read, ``Work`` the room they write in.
"""
from __future__ import annotations

import contextlib
import math
from typing import NamedTuple

import numba
import numpy as np

from .candidates import Lookup, Members
from .listing import NO_LISTING, CandidateSets, ListingArrays, listed_into
from .voting import PairSets

PAPER = 1
"""The rule code of eq. 10 as the paper states it, the one rule that may drop a lone pair."""


class Lister(NamedTuple):
    """What listing a candidate set reads (``list_set``): the signs, the lookup and sigma2."""

    signs: np.ndarray
    lookup: Lookup
    sigma2: float


class Judge(NamedTuple):
    """What filtering a listed set reads (``final_size``): the voting sets by member, the rule's code
    (``RULE_CODES``), both agents' centres and the distance limit."""

    voting: PairSets
    rule: int
    ego_xy: np.ndarray
    cav_xy: np.ndarray
    limit: float


class Filtering(NamedTuple):
    """What the visiting kernels read: how to list a set, the listing kept (``NO_LISTING`` without
    one), how to filter a listed set, and Ne (Nc is the lookup's)."""

    lister: Lister
    listing: ListingArrays
    judge: Judge
    n_ego: int


class Work(NamedTuple):
    """Room for one set: its listed members (``listed``, one more than ``width`` for the anchor
    pair), the kept rows and then their pair ids (``out``), a (2, width) boolean scratch, each
    object's count in the set, and a flag per pair (``voter_here``)."""

    listed: Members
    out: np.ndarray
    scratch: np.ndarray
    ego_count: np.ndarray
    cav_count: np.ndarray
    voter_here: np.ndarray


RULE_CODES = {None: 0, "paper": PAPER, "released": 2}


def filtering(L: CandidateSets, voted_by: PairSets, rule: str | None, ego_xy: np.ndarray, cav_xy: np.ndarray,
              distance_limit: float) -> Filtering:
    """The kernels' ``Filtering`` of candidate sets ``L``. The kernels add the anchors they list to
    the listing: the caller holds its lock (``listing_held``)."""
    judge = Judge(voted_by, RULE_CODES[rule], np.ascontiguousarray(ego_xy, dtype=float),
                  np.ascontiguousarray(cav_xy, dtype=float), float(distance_limit))
    return Filtering(Lister(L.signs, L.lookup, float(L.sigma2)),
                     NO_LISTING if L.listing is None else L.listing.arrays, judge, len(ego_xy))


def listing_held(L: CandidateSets):
    """The lock of ``L``'s listing, held while kernels list into it (a no-op without one)."""
    return contextlib.nullcontext() if L.listing is None else L.listing.lock


@numba.njit(cache=True, nogil=True)
def work_room(width, n_ego, n_cav, n_pairs):
    """A zeroed ``Work`` for sets of up to ``width`` members."""
    listed = Members(np.empty(width + 1, np.int64), np.empty(width + 1, np.int64), np.empty(width + 1, np.int64),
                     np.empty(width + 1))
    return Work(listed, np.empty(width, np.int64), np.zeros((2, width), np.bool_), np.zeros(n_ego, np.int64),
                np.zeros(n_cav, np.int64), np.zeros(n_pairs, np.bool_))


@numba.njit(cache=True, nogil=True)
def list_set(anchor, lister, listing, listed):
    """The members of L_ij of ``anchor`` listed into ``listed`` (``listed_into``, with the
    ``listing`` arguments of the calling thread); returns how many."""
    signs, lookup, sigma2 = lister
    n_cav = lookup.n_cav
    i, j = anchor // n_cav, anchor % n_cav
    return listed_into(i, j, signs[i, j], lookup, sigma2, listing, listed)


@numba.njit(cache=True, nogil=True)
def final_size(listed, judge, work):
    """card(L^(2)) of the ``listed`` members of L_ij in ``work`` (``list_set``), its members into
    ``work.out``; 0 when its pairs are farther apart than the limit on average (their distances
    computed from the centres)."""
    voting, rule, ego_xy, cav_xy, limit = judge
    size = final_set(listed, voting, rule, work)
    out, (pair, ego, cav, _) = work.out, work.listed
    total = 0.0
    for k in range(size):
        row = out[k]
        dx, dy = ego_xy[ego[row], 0] - cav_xy[cav[row], 0], ego_xy[ego[row], 1] - cav_xy[cav[row], 1]
        total += math.sqrt(dx * dx + dy * dy)
        out[k] = pair[row]
    return size if size == 0 or total / size <= limit else 0


@numba.njit(cache=True, nogil=True)
def rival_bound(size, excluded, lone_kept, work):
    """For the listed pairs in ``work`` (``size`` of them): min(distinct ego objects, distinct CAV
    objects), the most pairs their filtered set can hold (L^(2) is a one-to-one subset of L_ij); and
    whether, by a rule that keeps a pair alone in its row and column of L_ij (``lone_kept``: off and
    released), such a lone pair is ``excluded``, so that L^(2) holds it. The count arrays must be
    zero and are left so."""
    member, ego, cav, _ = work.listed
    ego_count, cav_count = work.ego_count, work.cav_count
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
def rival_free_size(anchor, beyond, excluded, lister, listing, judge, work):
    """card(L^(2)) of one anchor, 0 where the distance limit rejects it, its set holds an
    ``excluded`` pair or it cannot exceed ``beyond`` (``rival_bound``, or the bound the listing
    keeps from a larger or equal sigma2: then it is not filtered, nor listed)."""
    bound = listing.bound
    if len(bound) and 0 <= bound[anchor] <= beyond:
        return 0
    listed = list_set(anchor, lister, listing, work.listed)
    most, holds_excluded = rival_bound(listed, excluded, judge.rule != PAPER, work)
    if len(bound) and lister.sigma2 == listing.sigma2:
        bound[anchor] = most
    if most <= beyond or holds_excluded:
        return 0
    size = final_size(listed, judge, work)
    for k in range(size):
        if excluded[work.out[k]]:
            return 0
    return size


@numba.njit(cache=True, nogil=True)
def filtered_sizes_of(anchors, width, f):
    """card(L^(2)) of each anchor, 0 where the distance limit rejects it."""
    lister, listing, judge, n_ego = f
    n_cav = lister.lookup.n_cav
    work = work_room(width, n_ego, n_cav, n_ego * n_cav)
    sizes = np.zeros(len(anchors), np.int64)
    for n in range(len(anchors)):
        sizes[n] = final_size(list_set(anchors[n], lister, listing, work.listed), judge, work)
    return sizes


@numba.njit(cache=True, nogil=True)
def _voters(ego, cav, size, rule, ego_count, cav_count, voter):
    """voter[r] for rows 0..size-1 (pair of ego object ``ego[r]`` and CAV object ``cav[r]``): every row
    under the paper rule (eq. 10-11), else the rows whose objects occur once in the set (the released
    rule's lone members). ``ego_count`` and ``cav_count`` must be zero and are left holding how often
    each object occurs."""
    for row in range(size):
        ego_count[ego[row]] += 1
        cav_count[cav[row]] += 1
    for row in range(size):
        voter[row] = (rule == 1) | ((ego_count[ego[row]] == 1) & (cav_count[cav[row]] == 1))


@numba.njit(cache=True, nogil=True)
def _scan(rows, n, member, voting, needed, voter_here, enough):
    """enough[r] for the ``n`` rows r of ``rows``: at least ``needed`` of the pairs whose voting set
    holds the row's pair m (``voting``'s group of it, ``voting.member[voting.start[m]:voting.start[m + 1]]``)
    are marked in
    ``voter_here``; each scan stops at the vote it needs. The next row's list is looked up before
    this one is scanned, so its loads are under way when the scan's last branch is mispredicted."""
    voted_start, voted_by = voting
    if n == 0 or len(voted_by) == 0:
        return
    last = len(voted_by) - 1
    m = member[rows[0]]
    begin, end = voted_start[m], voted_start[m + 1]
    first = voted_by[min(begin, last)]
    for q in range(n):
        m = member[rows[min(q + 1, n - 1)]]
        next_begin, next_end = voted_start[m], voted_start[m + 1]
        next_first = voted_by[min(next_begin, last)]
        count = 0
        if end > begin:
            count = np.int64(voter_here[first])
            k = begin + 1
            while count < needed and k < end:
                count += voter_here[voted_by[k]]
                k += 1
        enough[rows[q]] = count >= needed
        begin, end, first = next_begin, next_end, next_first


@numba.njit(cache=True, nogil=True)
def _voted(member, size, is_voter, voting, needed, voter_here, enough, rows):
    """enough[r] for rows 0..size-1: at least ``needed`` voters of the set hold the row's pair in their
    voting set (``_scan``). With ``needed`` 1 (the released rule) a voter's own row is taken as
    enough unscanned: that rule keeps the voters whatever their votes. ``rows`` is work room for
    ``size`` row numbers; ``voter_here`` must be False and is left so."""
    n = 0
    for row in range(size):
        voter_here[member[row]] = is_voter[row]
        enough[row] = (needed == 1) & is_voter[row]
        rows[n] = row
        n += not enough[row]
    _scan(rows, n, member, voting, needed, voter_here, enough)
    for row in range(size):
        voter_here[member[row]] = False


@numba.njit(cache=True, nogil=True)
def final_set(size, voting, rule, work):
    """L^(2) of the candidate set listed in ``work.listed`` (``size`` members): the rows it keeps,
    in order, into ``work.out``; returns how many.

    Consensus (``cbm.reference.consensus``) by ``rule`` (0 off, 1 paper, 2 released), then the
    one-to-one rule (``cbm.reference.one_to_one``): the kept rows whose objects occur once among the
    kept rows, counted by taking the rows not kept off the set's counts. ``work``'s count arrays and
    ``voter_here`` must be zero / False and are left so. Branches the data decide are left out
    where the passes allow (sums and ``&`` of booleans instead)."""
    member, ego, cav, _ = work.listed
    ego_count, cav_count, out = work.ego_count, work.cav_count, work.out
    voter, kept = work.scratch[0], work.scratch[1]
    _voters(ego, cav, size, rule, ego_count, cav_count, voter)
    if rule == 0:
        kept[:size] = True
    else:
        _voted(member, size, voter, voting, 2 if rule == 1 else 1, work.voter_here, kept, out)
        for row in range(size):
            ego_count[ego[row]] -= 1 - kept[row]
            cav_count[cav[row]] -= 1 - kept[row]
    kept_size = 0
    for row in range(size):
        out[kept_size] = row
        kept_size += kept[row] & (ego_count[ego[row]] == 1) & (cav_count[cav[row]] == 1)
    for row in range(size):
        ego_count[ego[row]] = 0
        cav_count[cav[row]] = 0
    return kept_size
