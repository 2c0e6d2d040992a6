"""The voting sets (sigma3, as in the authors' released code: beyond the paper) grouped by the pair
they hold (``cbm.reference.votes`` reads them the other way round), so that the consensus of one
anchor costs the votes cast in its own set, never (Ne Nc)^2.
"""
from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from . import tuning
from .threads import TRIM_FROM, parts, shared_out, stop_flag, trim_freed


class PairSets(NamedTuple):
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
def _count_by_member(rows, bits, n_cav, has_set, start, stop):
    """Adds the quadruples of ``rows`` (``VoteRows``) to ``start[member + 1]`` and marks their
    anchors in ``has_set``; a head adds to ``start[0]`` and marks ``has_set[-1]``, the caller's
    spare entries. Returns early once ``stop[0]`` is set (``threads.stop_flag``)."""
    anchor_row = member_row = 0
    for r in range(len(rows)):
        if stop[0]:
            return
        anchor_row, member_row, anchor, member = _decoded(rows[r], bits, n_cav, anchor_row, member_row)
        has_set[anchor] = True
        start[member + 1] += 1


@numba.njit(cache=True, nogil=True)
def _place_by_member(rows, bits, n_cav, fill, values, stop):
    """Writes each quadruple's anchor of ``rows`` (``VoteRows``) at ``values[fill[member]]`` and moves
    that member's ``fill`` on; returns early once ``stop[0]`` is set (``threads.stop_flag``)."""
    anchor_row = member_row = 0
    for r in range(len(rows)):
        if stop[0]:
            return
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


def voted_by_member(votes: list, n_pairs: int) -> PairSets:
    """Row m: the pairs whose voting set (quadruples within sigma3, the released code's) holds pair m.

    ``votes`` are the join's parts (``cbm.engine.join.VoteRows``), in order. A counting sort
    groups their quadruples by member (in row order), then adds (A, A) for every anchor A that has
    a quadruple (every non-empty voting set holds its own pair). From ``VOTES_APART_FROM`` rows the
    parts are cut into as many runs as threads, each counted and then placed by a thread of its own,
    each run's quadruples of a member after the runs' before it: the same groups as one pass. The
    list is emptied as the parts are placed, so the rows and their grouping are never held twice;
    large votes' memory, freed, goes back to the system (``trim_freed``)."""
    nbytes = sum(part.rows.nbytes for part in votes)
    n_runs = min(parts(sum(len(part.rows) for part in votes), tuning.VOTES_APART_FROM), max(len(votes), 1))
    runs, stop = _runs(votes, n_runs), stop_flag()
    votes.clear()
    counts = shared_out([lambda run=run: _counted(run, n_pairs, stop) for run in runs])
    has_set = counts[0][0][:-1]
    for spare, _ in counts[1:]:
        has_set |= spare[:-1]
    start = counts[0][1]
    if len(counts) > 1:
        start = np.zeros(n_pairs + 1, np.int64)
        for _, count in counts:
            start[1:] += count[1:]
    start[0] = 0
    start[1:] += has_set
    np.cumsum(start, out=start)
    fills = [start]
    for _, count in counts[:-1]:
        _after(fills[-1], count)
        fills.append(count)
    values = np.empty(start[n_pairs], np.int32)
    shared_out([lambda run=run, fill=fill: _placed(run, fill, values, stop) for run, fill in zip(runs, fills)])
    _place_own(has_set, fills[-1], values)
    if nbytes >= TRIM_FROM:
        trim_freed()
    return PairSets(start=fills[-1], member=values)


def _runs(votes: list, n: int) -> list[list]:
    """The parts in order, cut into ``n`` runs of about as many rows each."""
    if n <= 1:
        return [list(votes)]
    ends = np.cumsum([len(part.rows) for part in votes])
    cuts = [0, *(min(max(int(np.searchsorted(ends, ends[-1] * k / n)) + 1, k), len(votes) - n + k)
                 for k in range(1, n)), len(votes)]
    return [votes[a:b] for a, b in zip(cuts, cuts[1:])]


@numba.njit(cache=True, nogil=True)
def _after(fill, counts):
    """``counts[m + 1]`` (a run's quadruples of member m) turned in place into where the next run's
    go: ``fill[m] + counts[m + 1]``, ``fill`` being where this run's go."""
    for m in range(len(fill) - 1):
        counts[m] = fill[m] + counts[m + 1]
    counts[-1] = fill[-1]


def _counted(parts_: list, n_pairs: int, stop: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The anchors that have a quadruple in ``parts_`` (with a spare entry last) and the count of
    each member's quadruples at ``[member + 1]``, ``_count_by_member`` of every part."""
    spare, count = np.zeros(n_pairs + 1, np.bool_), np.zeros(n_pairs + 1, np.int64)
    for part in parts_:
        _count_by_member(part.rows, part.bits, part.n_cav, spare, count, stop)
    return spare, count


def _placed(parts: list, fill: np.ndarray, values: np.ndarray, stop: np.ndarray) -> None:
    """``_place_by_member`` of every part, in order, each part dropped from ``parts`` once placed."""
    while parts:
        part = parts.pop(0)
        _place_by_member(part.rows, part.bits, part.n_cav, fill, values, stop)


