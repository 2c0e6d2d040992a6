"""The fast exact path of CBM's matching (eq. 8-14): the same pairs, counts, anchor and runner-up
as ``cbm.reference``, at a cost that grows with the quadruples eq. 8 accepts, not with (Ne Nc)^2.

``cbm.pipeline`` runs it step by step: ``local_matching`` (the join over grids of context vectors,
eq. 8-9, and the voting sets of sigma3, beyond the paper), ``candidate_sets`` (members on demand,
eq. 9), ``select`` (eq. 10-14 by branch and bound)
and ``runner_up_beside``; ``EditCache`` and ``Reuse`` keep what a threshold edit does not change.
How many threads it uses, and from what size, is ``tuning``'s.
"""
from .cache import EditCache, Reuse
from .counting import local_matching
from .listing import CandidateSets, candidate_sets
from .rival import runner_up_beside
from .selection import Selection, anchor_sets, filtered_sizes, select
from .visit import Visit
from .voting import PairSets

__all__ = ["CandidateSets", "EditCache", "PairSets", "Reuse", "Selection", "Visit", "anchor_sets", "candidate_sets",
           "filtered_sizes", "local_matching", "runner_up_beside", "select"]
