"""Local matching in one call: card(L_ij) of every anchor at sigma2 and the voting sets at sigma3
(``cbm.reference.candidate_sets``), from one join over the grids (``join``) and the grouping of
its votes (``voting``). Pair ids are ``i * Nc + j`` throughout.
"""
from __future__ import annotations

import numpy as np

from .context import Prepared
from .join import Grids, VoteRows, run_join
from .voting import PairSets, voted_by_member

MOST_PAIRS = 2**31 - 1
"""Most ego x CAV pairs: the voting quadruples are listed as 32-bit pair ids (half the memory)."""
NOTHING = np.zeros(0, np.int64)
"""The counters handed to a join that does not count."""


def counts_and_votes(prepared: Prepared, sigma1_rad: float, sigma2: float, sigma3: float | None,
                     counting: bool = True, listing: bool = True,
                     grids: Grids | None = None) -> tuple[np.ndarray | None, list[VoteRows]]:
    """One join: with ``counting``, card(L_ij) + 1 of every anchor with a candidate at ``sigma2``
    (0 for the others: eq. 9 with the anchor pair itself); with ``listing`` and a ``sigma3`` (None:
    the consensus is off), every quadruple within ``sigma3``, the voting sets (the released code's) without their
    own pairs, as the join's parts (``VoteRows``). The grids are built for the wider of both
    thresholds whichever pass runs, so that kept ``grids`` serve the next edit of either."""
    n_ego, n_cav = prepared.signs.shape
    if n_ego * n_cav > MOST_PAIRS:
        raise ValueError(f"cbm.match: {n_ego} x {n_cav} boxes make more than {MOST_PAIRS} pairs (the voting "
                         "sets keep pair ids in 32 bits)")
    listing = listing and sigma3 is not None
    if not (counting or listing):
        return None, []
    counters = np.zeros(n_ego * n_cav, np.int64) if counting else NOTHING
    radius = sigma2 if sigma3 is None else max(sigma2, sigma3)
    votes = run_join(prepared, sigma1_rad, radius, sigma2 if counting else -1.0, sigma3 if listing else -1.0,
                     counters, grids)
    if not counting:
        return None, votes
    counters += counters > 0
    return counters, votes


def local_matching(prepared: Prepared, sigma1_rad: float, sigma2: float,
                   sigma3: float | None) -> tuple[np.ndarray, PairSets]:
    """card(L_ij) + 1 of every anchor with a candidate at ``sigma2`` and the voting sets at ``sigma3``
    grouped by member (empty when ``sigma3`` is None: no consensus), from one join. The votes are
    grouped and freed before anything else is built."""
    count2, votes = counts_and_votes(prepared, sigma1_rad, sigma2, sigma3)
    n_pairs = prepared.signs.size
    return count2, PairSets.empty(n_pairs) if sigma3 is None else voted_by_member(votes, n_pairs)
