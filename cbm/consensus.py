"""Global consensus maximization (paper eq. 9-11) over sparse candidate sets.

The voting sets V_k'h' (built like the candidate sets L_ij of eq. 8 with sigma3 in place of sigma2;
every non-empty set holds its own pair) are stored grouped by the pair they hold, so the consensus
of one anchor costs the votes cast in its own set, never (Ne Nc)^2; ``cbm.selection`` only asks for
the anchors whose candidate set is large enough to win, and lists their members on demand
(``cbm.local_matching.CandidateSets``). Two rules decide which candidates keep
their place:

- ``paper`` (eq. 9-10): (i', j') in L_ij survives when ``sum_{(k',h') in L_ij} V_k'h'(i', j') > 1``,
  i.e. some other member of the set accepts it too. With sigma3 = sigma2 this is eq. 10 exactly.
- ``released`` (the authors' code): members that are alone in their row and column of L_ij survive
  as they are; the others survive when a voting set of one of those lone members contains them.

Then every row and column of a set that still holds more than one pair is emptied (eq. 11; rows
and columns at once, where the released code empties rows first), so each set is one-to-one.
"""
from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from .local_matching import POOL, TRIM_FROM, trim_freed

VOTES_APART_FROM = 200_000
"""Vote rows from which ``voted_by_member`` counts and places them in two halves at once."""


@dataclass(frozen=True)
class PairSets:
    """Sets of pairs grouped by a key pair: the set of pair A is ``member[start[A]:start[A + 1]]``."""

    start: np.ndarray
    member: np.ndarray

    def sizes(self) -> np.ndarray:
        return np.diff(self.start)

    @staticmethod
    def empty(n_pairs: int) -> PairSets:
        return PairSets(start=np.zeros(n_pairs + 1, dtype=np.int64), member=np.zeros(0, dtype=np.int32))


@numba.njit(cache=True, nogil=True, inline="always")
def _decoded(code, bits, n_cav, anchor_row, member_row):
    """One value of ``VoteRows.rows`` after the rows of its ego vector's anchor i and member i'
    start at ``anchor_row``, ``member_row`` (``i Nc``, ``i' Nc``): the rows then, and the value's
    anchor and member pairs, (-1, -1) for a head. Without a branch: heads and quadruples alternate
    unpredictably where votes are few."""
    low, head = (1 << bits) - 1, code < 0
    query = -code - 1
    anchor_row = (query >> bits) * n_cav if head else anchor_row
    member_row = (query & low) * n_cav if head else member_row
    anchor = -1 if head else anchor_row + (code >> bits)
    member = -1 if head else member_row + (code & low)
    return anchor_row, member_row, anchor, member


@numba.njit(cache=True, nogil=True)
def _count_by_member(rows, bits, n_cav, has_set, start):
    """Adds the quadruples of ``rows`` (``VoteRows``) to ``start[member + 1]`` and marks their
    anchors in ``has_set``; a head adds to ``start[0]`` and marks ``has_set[-1]``, the caller's
    spare entries."""
    anchor_row = member_row = 0
    for r in range(len(rows)):
        anchor_row, member_row, anchor, member = _decoded(rows[r], bits, n_cav, anchor_row, member_row)
        has_set[anchor] = True
        start[member + 1] += 1


@numba.njit(cache=True, nogil=True)
def _place_by_member(rows, bits, n_cav, fill, values):
    """Writes each quadruple's anchor of ``rows`` (``VoteRows``) at ``values[fill[member]]`` and moves
    that member's ``fill`` on."""
    anchor_row = member_row = 0
    for r in range(len(rows)):
        anchor_row, member_row, anchor, member = _decoded(rows[r], bits, n_cav, anchor_row, member_row)
        if member >= 0:
            values[fill[member]] = anchor
            fill[member] += 1


@numba.njit(cache=True, nogil=True)
def _place_own(has_set, fill, values):
    """Writes every anchor A with a quadruple last in its own group, (A, A) (each non-empty voting set
    holds its own pair); ``fill`` then holds each group's end and becomes the groups' starts, moved
    up by one."""
    n_pairs = len(has_set)
    for a in range(n_pairs):
        if has_set[a]:
            values[fill[a]] = a
            fill[a] += 1
    for a in range(n_pairs, 0, -1):
        fill[a] = fill[a - 1]
    fill[0] = 0


def voted_by_member(votes: list, n_pairs: int, halves: bool | None = None) -> PairSets:
    """Row m: the pairs whose voting set (eq. 9, quadruples within sigma3) holds pair m.

    ``votes`` are the join's parts (``cbm.local_matching.join.VoteRows``), in order; a counting
    sort groups their quadruples by member (in row order), then adds (A, A) for every anchor A that
    has a quadruple (every non-empty voting set holds its own pair). The list is emptied part by
    part as the parts are placed, so the rows and their grouping are never held twice; the
    groups' starts are moved along as they fill (no copy of them). With ``halves`` (by default from
    ``VOTES_APART_FROM`` rows) the parts are counted and placed in two halves at once
    (``_grouped_apart``). Large votes' memory, freed, goes back to the system (``trim_freed``)."""
    nbytes = sum(part.rows.nbytes for part in votes)
    grouped = _grouped_apart(votes, n_pairs) if _in_halves(votes, halves) else _grouped(votes, n_pairs)
    if nbytes >= TRIM_FROM:
        trim_freed()
    return grouped


def _in_halves(votes: list, halves: bool | None) -> bool:
    """Whether ``voted_by_member`` groups the votes in two halves at once."""
    if halves is None:
        halves = sum(len(part.rows) for part in votes) >= VOTES_APART_FROM
    return halves and len(votes) > 1


def _grouped(votes: list, n_pairs: int) -> PairSets:
    """``voted_by_member`` in one pass."""
    spare = np.zeros(n_pairs + 1, np.bool_)
    has_set, start = spare[:-1], np.zeros(n_pairs + 1, np.int64)
    _counted(votes, spare, start)
    start[0] = 0
    start[1:] += has_set
    np.cumsum(start, out=start)
    values = np.empty(start[n_pairs], np.int32)
    _placed(votes, start, values)
    _place_own(has_set, start, values)
    return PairSets(start=start, member=values)


def _grouped_apart(votes: list, n_pairs: int) -> PairSets:
    """``voted_by_member`` with the parts in two halves of about as many rows, each counted and then
    placed on a thread of its own (the second on ``POOL``): the first half's quadruples of a member
    go first in its group, the second's right after them, so the groups are the same as one pass's.
    The first half's counts become where the second half's quadruples go (``_after_first``): one
    array more than one pass holds (8 MB at 1000 objects per agent)."""
    halves = _halves(votes)
    votes.clear()
    counts = [(np.zeros(n_pairs + 1, np.bool_), np.zeros(n_pairs + 1, np.int64)) for _ in halves]
    _both(_counted, *((half, *count) for half, count in zip(halves, counts)))
    (spare, behind), (other, start) = counts
    has_set = spare[:-1] | other[:-1]
    start[0] = 0
    start[1:] += behind[1:] + has_set
    np.cumsum(start, out=start)
    values = np.empty(start[n_pairs], np.int32)
    _after_first(start, behind)
    _both(_placed, (halves[0], start, values), (halves[1], behind, values))
    _place_own(has_set, behind, values)
    return PairSets(start=behind, member=values)


@numba.njit(cache=True, nogil=True)
def _after_first(start, counts):
    """``counts[m + 1]`` (the first half's quadruples of member m) turned in place into where the
    second half's go in the groups that begin at ``start``: ``start[m] + counts[m + 1]``."""
    for m in range(len(start) - 1):
        counts[m] = start[m] + counts[m + 1]
    counts[-1] = start[-1]


def _halves(votes: list) -> tuple[list, list]:
    """The parts in order, cut into two lists where the rows before the cut first reach half of them."""
    ends = np.cumsum([len(part.rows) for part in votes])
    cut = min(max(int(np.searchsorted(ends, ends[-1] / 2)) + 1, 1), len(votes) - 1)
    return votes[:cut], votes[cut:]


def _both(function, mine: tuple, theirs: tuple) -> None:
    """``function(*mine)`` on the calling thread while ``function(*theirs)`` runs on ``POOL``."""
    job = POOL.submit(function, *theirs)
    function(*mine)
    job.result()


def _counted(parts: list, spare: np.ndarray, start: np.ndarray) -> None:
    """``_count_by_member`` of every part."""
    for part in parts:
        _count_by_member(part.rows, part.bits, part.n_cav, spare, start)


def _placed(parts: list, fill: np.ndarray, values: np.ndarray) -> None:
    """``_place_by_member`` of every part, in order, each part dropped from ``parts`` once placed."""
    while parts:
        part = parts.pop(0)
        _place_by_member(part.rows, part.bits, part.n_cav, fill, values)


RULE_CODES = {None: 0, "paper": 1, "released": 2}


@numba.njit(cache=True, nogil=True)
def _voters(ego, cav, size, rule, ego_count, cav_count, voter):
    """voter[r] for rows 0..size-1 (pair of ego object ``ego[r]`` and CAV object ``cav[r]``): every row
    under the paper rule (eq. 9-10), else the rows whose objects occur once in the set (the released
    rule's lone members). ``ego_count`` and ``cav_count`` must be zero and are left holding how often
    each object occurs."""
    for row in range(size):
        ego_count[ego[row]] += 1
        cav_count[cav[row]] += 1
    for row in range(size):
        voter[row] = (rule == 1) | ((ego_count[ego[row]] == 1) & (cav_count[cav[row]] == 1))


@numba.njit(cache=True, nogil=True)
def _scan(rows, n, member, voted_start, voted_by, needed, voter_here, enough):
    """enough[r] for the ``n`` rows r of ``rows``: at least ``needed`` of the pairs whose voting set
    holds the row's pair (``voted_by[voted_start[m]:voted_start[m + 1]]``) are marked in
    ``voter_here``; each scan stops at the vote it needs. The next row's list is looked up before
    this one is scanned, so its loads are under way when the scan's last branch is mispredicted."""
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
def _voted(member, size, is_voter, voted_start, voted_by, needed, voter_here, enough, rows):
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
    _scan(rows, n, member, voted_start, voted_by, needed, voter_here, enough)
    for row in range(size):
        voter_here[member[row]] = False


@numba.njit(cache=True, nogil=True)
def final_set(member, ego, cav, size, voted_start, voted_by, rule, scratch, ego_count, cav_count, voter_here, out):
    """L^(2) of the candidate set ``member[:size]`` (pair ids; ``ego`` and ``cav`` their objects):
    the rows it keeps, in order, into ``out``; returns how many.

    Consensus (eq. 9-10) by ``rule`` (0 off, 1 paper, 2 released), then the one-to-one rule (eq. 11):
    the kept rows whose objects occur once among the kept rows, counted by taking the rows not kept
    off the set's counts. ``scratch`` is a (2, max set size) bool work array; the count arrays and
    ``voter_here`` must be zero/False and are left so. Branches the data decide are left out where
    the passes allow (sums and ``&`` of booleans instead)."""
    voter, kept = scratch[0], scratch[1]
    _voters(ego, cav, size, rule, ego_count, cav_count, voter)
    if rule == 0:
        kept[:size] = True
    else:
        _voted(member, size, voter, voted_start, voted_by, 2 if rule == 1 else 1, voter_here, kept, out)
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
