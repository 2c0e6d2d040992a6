"""Global consensus maximization (paper eq. 9-11) over sparse candidate sets.

The candidate sets L_ij (eq. 8) and the voting sets V_k'h' (built the same way with sigma3 in place
of sigma2; every non-empty set holds its own pair) are stored grouped by their anchor pair, so the
consensus costs the sum over anchors of the votes cast in their sets, never (Ne Nc)^2. Two rules
decide which candidates keep their place:

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

from .local_matching import Quadruples


@dataclass(frozen=True)
class PairSets:
    """Sets of pairs grouped by their anchor: the members of anchor A are ``member[start[A]:start[A + 1]]``."""

    start: np.ndarray
    member: np.ndarray

    def anchors(self) -> np.ndarray:
        """The anchor of every row of ``member``."""
        return np.repeat(np.arange(len(self.start) - 1), np.diff(self.start))


@dataclass(frozen=True)
class FilteredSets:
    """The sets L^(2)_ij of eq. 11, as (anchor, member) rows sorted by anchor."""

    anchor: np.ndarray
    member: np.ndarray
    candidate_count: np.ndarray
    """(Ne * Nc,) card(L_ij) of every anchor before the filtering (eq. 8), 0 for an empty set."""


@numba.njit(cache=True)
def _group_by(keys, n_keys):
    """Counting sort: (order, start) so that keys[order[start[k]:start[k + 1]]] == k."""
    start = np.zeros(n_keys + 1, np.int64)
    for key in keys:
        start[key + 1] += 1
    for k in range(n_keys):
        start[k + 1] += start[k]
    fill = start[:-1].copy()
    order = np.empty(len(keys), np.int64)
    for row in range(len(keys)):
        order[fill[keys[row]]] = row
        fill[keys[row]] += 1
    return order, start


def sets_within(quads: Quadruples, tolerance: float, n_pairs: int, by_member: bool = False) -> PairSets:
    """The sets of all anchors at an L1 tolerance, each with its anchor pair once non-empty (eq. 8).

    ``by_member`` transposes them: row m lists the anchors whose set holds pair m.
    """
    inside = quads.l1 <= tolerance
    anchor, member = quads.anchor[inside], quads.member[inside]
    nonempty = np.flatnonzero(np.bincount(anchor, minlength=n_pairs))
    anchor, member = np.concatenate([anchor, nonempty]), np.concatenate([member, nonempty])
    if by_member:
        anchor, member = member, anchor
    order, start = _group_by(anchor, n_pairs)
    return PairSets(start=start, member=member[order])


@numba.njit(cache=True)
def _has_votes(start, member, is_voter, voted_start, voted_by, needed):
    """For every row of the sets: do at least ``needed`` voters of the same set hold its pair in
    their voting set? ``voted_by[voted_start[m]:voted_start[m + 1]]`` lists the pairs whose voting
    set holds pair m; the scan stops at the ``needed``-th vote."""
    n_pairs = len(voted_start) - 1
    voter_here = np.zeros(n_pairs, np.bool_)
    enough = np.zeros(len(member), np.bool_)
    for anchor in range(len(start) - 1):
        for row in range(start[anchor], start[anchor + 1]):
            voter_here[member[row]] = is_voter[row]
        for row in range(start[anchor], start[anchor + 1]):
            count = 0
            m = member[row]
            for k in range(voted_start[m], voted_start[m + 1]):
                if voter_here[voted_by[k]]:
                    count += 1
                    if count >= needed:
                        enough[row] = True
                        break
        for row in range(start[anchor], start[anchor + 1]):
            voter_here[member[row]] = False
    return enough


@numba.njit(cache=True)
def _alone(start, member, kept, n_ego, n_cav):
    """Rows whose ego object and CAV object each occur once among the kept rows of their set."""
    ego_count = np.zeros(n_ego, np.int64)
    cav_count = np.zeros(n_cav, np.int64)
    alone = np.zeros(len(member), np.bool_)
    for anchor in range(len(start) - 1):
        for row in range(start[anchor], start[anchor + 1]):
            if kept[row]:
                ego_count[member[row] // n_cav] += 1
                cav_count[member[row] % n_cav] += 1
        for row in range(start[anchor], start[anchor + 1]):
            if kept[row]:
                i, j = member[row] // n_cav, member[row] % n_cav
                alone[row] = ego_count[i] == 1 and cav_count[j] == 1
        for row in range(start[anchor], start[anchor + 1]):
            ego_count[member[row] // n_cav] = 0
            cav_count[member[row] % n_cav] = 0
    return alone


def paper_consensus(L: PairSets, voted_by: PairSets, n_ego: int, n_cav: int) -> np.ndarray:
    """Eq. 9-10: keep (i', j') of L_ij when the members of L_ij cast more than one vote for it."""
    everyone = np.ones(len(L.member), dtype=bool)
    return _has_votes(L.start, L.member, everyone, voted_by.start, voted_by.member, 2)


def released_consensus(L: PairSets, voted_by: PairSets, n_ego: int, n_cav: int) -> np.ndarray:
    """Released code: keep lone members, and the others that a lone member's voting set contains."""
    lone = _alone(L.start, L.member, np.ones(len(L.member), dtype=bool), n_ego, n_cav)
    return lone | _has_votes(L.start, L.member, lone, voted_by.start, voted_by.member, 1)


CONSENSUS_RULES = {"paper": paper_consensus, "released": released_consensus}


def filter_sets(quads: Quadruples, sigma2: float, sigma3: float, rule: str | None,
                n_ego: int, n_cav: int) -> FilteredSets:
    """L^(2)_ij for every anchor: candidate sets (eq. 8), consensus (eq. 9-10) unless ``rule`` is
    None, one-to-one (eq. 11)."""
    n_pairs = n_ego * n_cav
    L = sets_within(quads, sigma2, n_pairs)
    kept = np.ones(len(L.member), dtype=bool)
    if rule is not None:
        voted_by = sets_within(quads, sigma3, n_pairs, by_member=True)
        kept = CONSENSUS_RULES[rule](L, voted_by, n_ego, n_cav)
    kept &= _alone(L.start, L.member, kept, n_ego, n_cav)
    return FilteredSets(anchor=L.anchors()[kept], member=L.member[kept], candidate_count=np.diff(L.start))
