"""Context similarity-based coarse matching (paper eq. 7-8 and Algorithm 1), one file per step.

For an anchor pair (i, j) a candidate (i', j') is accepted when the context vectors
``z = z_ii'`` and ``w = z_jj'`` satisfy

    arccos(|z . w| / (|z| |w|)) <= sigma1      and      ||z - w||_1 <= sigma2        (eq. 7)

- ``grid``: the CAV vectors of each heading group of ego objects in cells over u = x + y,
  v = x - y, where eq. 7's L1 diamond is a square (``VectorGrid``);
- ``join``: the output-sensitive join that counts card(L_ij) for every anchor and lists only the
  quadruples within sigma3 (the voting sets of the consensus), in parallel and in a fixed order;
- ``candidates``: the members of one L_ij when the selection asks for them (``CandidateSets``);
- ``listing``: the members listed so far, kept per input and sigma1 and read again after a sigma2
  edit (``Listing``);
- ``counting``: the three as one call (``count_candidates``).

Pair ids are ``i * Nc + j`` throughout.
"""
from .candidates import NO_LISTING, CandidateSets, Listing, SortedBlocks, member_lookup, members_into, sorted_blocks
from .counting import MOST_PAIRS, count_candidates
from .grid import MARGIN, VectorGrid, build_grid, group_signs, heading_groups
from .join import POOL, THREADS, TRIM_FROM, Done, trim_freed
from .listing import listed_into

__all__ = ["MARGIN", "MOST_PAIRS", "NO_LISTING", "POOL", "THREADS", "CandidateSets", "Done", "Listing", "SortedBlocks",
           "TRIM_FROM", "VectorGrid", "build_grid", "count_candidates", "group_signs", "heading_groups",
           "listed_into", "member_lookup", "members_into", "sorted_blocks", "trim_freed"]
