"""Step 4 of local matching as one call: card(L_ij) of every anchor and the voting quadruples
(paper eq. 7-8, Algorithm 1), from the grid (``grid``), the join (``join``) and the candidate
sets listed on demand (``candidates``). Pair ids are ``i * Nc + j`` throughout.

card(L_ij) depends on (sigma1, sigma2) only, the voting quadruples on (sigma1, sigma3) only: with
``kept`` (``cbm.reuse.Prepared.kept``) the counts of the latest (sigma1, sigma2) are kept, and the
join runs only the passes an edit changed.
"""
from __future__ import annotations

import numpy as np

from ..context import Context
from ..reuse import kept_key, ran, recall, remember
from .candidates import CandidateSets, member_lookup
from .distances import HEADROOM, Distances, counted, distances_within
from .join import VoteRows, run_join
from .listing import listing_for

MOST_PAIRS = 2**31 - 1
"""Most ego x CAV pairs: the voting quadruples are listed as 32-bit pair ids (half the memory)."""
NOTHING = np.zeros(0, np.int64)
"""The counters handed to a join that does not count."""


def count_candidates(ego: Context, cav: Context, ego_heading: np.ndarray, signs: np.ndarray, sigma1_rad: float,
                     sigma2: float, sigma3: float | None, kept: dict | None = None,
                     list_votes: bool = True) -> tuple[CandidateSets, list[VoteRows]]:
    """card(L_ij) at sigma2 for every anchor, and (with ``sigma3`` and ``list_votes``) every
    quadruple within sigma3 (the voting sets of eq. 9 without their own pairs), from one join, as
    the join's parts (``VoteRows``, packed); ``sigma3`` None: the consensus is off.
    ``kept`` (``cbm.reuse.Prepared.kept``): the grids, sorted blocks and counts built earlier for the
    same contexts, read and filled; counts kept for this (sigma1, sigma2) are not counted again."""
    count2, votes = counts_and_votes(ego, cav, ego_heading, signs, sigma1_rad, sigma2, sigma3, kept, list_votes)
    return candidate_sets(ego, cav, signs, sigma1_rad, sigma2, count2, kept), votes


def counts_and_votes(ego: Context, cav: Context, ego_heading: np.ndarray, signs: np.ndarray, sigma1_rad: float,
                     sigma2: float, sigma3: float | None, kept: dict | None = None,
                     list_votes: bool = True) -> tuple[np.ndarray, list[VoteRows]]:
    """The join of ``count_candidates``: card(L_ij) + 1 of every anchor with a candidate (0 for the
    others; eq. 8 with the anchor pair itself) and the votes, before any candidate set is listed."""
    n_ego, n_cav = signs.shape
    if n_ego * n_cav > MOST_PAIRS:
        raise ValueError(f"cbm.match: {n_ego} x {n_cav} boxes make more than {MOST_PAIRS} pairs (the voting "
                         "sets keep pair ids in 32 bits)")
    count2 = recall(kept, "count", (sigma1_rad, sigma2))
    if count2 is None:
        count2 = scanned_count(ego, cav, ego_heading, signs, sigma1_rad, sigma2, kept)
    counting, listing = count2 is None, sigma3 is not None and list_votes
    votes = []
    if counting or listing:
        counters = np.zeros(n_ego * n_cav, np.int64) if counting else NOTHING
        radius = sigma2 if sigma3 is None else max(sigma2, sigma3)
        votes = run_join(ego, cav, ego_heading, signs, sigma1_rad, radius, sigma2 if counting else -1.0,
                         sigma3 if listing else -1.0, counters, kept)
        if counting:
            ran(kept, "count")
        if listing:
            ran(kept, "votes")
    if counting:
        count2 = counters
        count2 += count2 > 0
        remember(kept, "count", (sigma1_rad, sigma2), count2)
    return count2, votes


def scanned_count(ego: Context, cav: Context, ego_heading: np.ndarray, signs: np.ndarray, sigma1_rad: float,
                  sigma2: float, kept: dict | None) -> np.ndarray | None:
    """card(L_ij) + 1 of every anchor with a candidate (``counts_and_votes``'s) counted from the
    quadruples' distances kept for this sigma1 (``distances``), kept here at ``HEADROOM`` times
    sigma2 when this is a sigma2 edit (the counts kept are for this sigma1 and another sigma2);
    None when the join must count: a first count, a sigma1 edit, or too many quadruples."""
    if kept is None:
        return None
    found = recall(kept, "distances", (sigma1_rad,))
    if found is None or (found.anchor is not None and found.radius < sigma2):
        earlier = kept_key(kept, "count")
        if earlier is None or earlier[0] != sigma1_rad:
            return None
        radius = HEADROOM * sigma2
        found = distances_within(ego, cav, ego_heading, signs, sigma1_rad, radius, kept)
        if found is None:
            found = Distances(radius, None, None)
        remember(kept, "distances", (sigma1_rad,), found)
        ran(kept, "distances")
    if found.anchor is None:
        return None
    count2 = counted(found, sigma2, signs.size)
    count2 += count2 > 0
    ran(kept, "count")
    remember(kept, "count", (sigma1_rad, sigma2), count2)
    return count2


def candidate_sets(ego: Context, cav: Context, signs: np.ndarray, sigma1_rad: float, sigma2: float,
                   count2: np.ndarray, kept: dict | None = None) -> CandidateSets:
    """L_ij of every anchor (eq. 8) from its counts ``count2``: the members listed on demand from
    both agents' sorted blocks, built here unless ``kept`` holds them."""
    n_ego, n_cav = signs.shape
    return CandidateSets(count2, member_lookup(ego, cav, n_ego, n_cav, sigma1_rad, sigma2, kept), signs,
                         listing_for(kept, sigma1_rad, sigma2, count2))
