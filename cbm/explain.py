"""Why CBM answered as it did: any anchor's context, candidate set, votes and filtered set.

``cbm.match(..., explain=True)`` hands its result an ``Explanation`` of the very run that answered:
its sets (steps 1-4, ``cbm.sets``), the fit of its winning set and what its selection filtered. An
anchor is explained with the paper's own steps (``cbm.reference``: the consensus, the one-to-one
rule and the distance limit) on those sets, so the app shows why a pair was kept or dropped in the
terms a reader of the reference finds there, and never from a second computation of the answer.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import reference
from .engine import PairSets, Visit, filtered_sizes
from .params import CBMParams
from .result import Fit
from .sets import Sets


@dataclass(frozen=True)
class AnchorDetail:
    """One anchor pair's way through eq. 9-13."""

    anchor: tuple[int, int]
    candidates: np.ndarray
    """(K, 2) L_ij, the anchor pair included (eq. 9); empty when fewer than 2 pairs were accepted."""
    votes: np.ndarray
    """(K,) votes each candidate got from the set's voters (the sum of eq. 10)."""
    kept_by_consensus: np.ndarray
    """(K,) bool: the candidate survived the consensus rule (all True when consensus is off)."""
    final: np.ndarray
    """(M, 2) L^(2)_ij after the one-to-one rule (eq. 12)."""
    mean_distance: float
    """Mean centre distance of the final pairs after ``init`` (NaN when empty)."""
    rejected: bool
    """The distance limit rejects the anchor."""

    @property
    def size(self) -> int:
        """What the anchor scores in eq. 13: card(L^(2)_ij), 0 when rejected."""
        return 0 if self.rejected else len(self.final)


def votes_from(voted_by: PairSets, members: np.ndarray, by: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """``cbm.reference.votes`` at the pair ids ``members`` (0 elsewhere), from the engine's voting
    sets grouped by member: how many of the pairs ``by`` (an (Ne, Nc) boolean matrix) hold each."""
    starts = voted_by.start[members]
    lengths = voted_by.start[members + 1] - starts
    owner = np.repeat(np.arange(len(members)), lengths)
    rows = starts[owner] + np.arange(lengths.sum()) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    counted = np.zeros(shape, np.int64)
    counted.flat[members] = np.bincount(owner, weights=by.ravel()[voted_by.member[rows]], minlength=len(members))
    return counted


class Explanation:
    """The sets, fit and selection of one ``cbm.match`` run, kept so that any anchor can be explained."""

    def __init__(self, sets: Sets, init: np.ndarray, fit: Fit | None, visit: Visit | None) -> None:
        self.sets, self.init, self.fit = sets, init, fit
        """What the run built (steps 1-4), the ``init`` it started from, and the robust fit of its
        winning set (eq. 15; None with fewer than two pairs)."""
        self.n_cav = len(sets.cav_xy)
        self._anchors: dict[tuple[int, int], AnchorDetail] = {}
        """Anchors explained so far: kept with this explanation and forgotten with it."""
        self.visit = visit
        """What the selection's visit filtered (eq. 13), None when every set was empty."""

    @property
    def params(self) -> CBMParams:
        return self.sets.params

    def _pairs(self, ids: np.ndarray) -> np.ndarray:
        return np.stack([ids // self.n_cav, ids % self.n_cav], axis=1).reshape(-1, 2)

    def context(self, agent: str, index: int, against: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(neighbour indices, (n - 1, 2) context vectors) of one object in its own local frame
        (eq. 6-7, ``cbm.reference.context_vectors``). For a CAV object compared ``against`` an ego
        object, the frame as CBM turns it (step 2)."""
        sets = self.sets
        xy, heading = (sets.ego_xy, sets.ego_heading) if agent == "ego" else (sets.cav_xy, sets.cav_heading)
        vectors = np.delete(reference.context_vectors(xy, heading, index), index, axis=0)
        if agent == "cav" and against is not None:
            vectors = vectors * sets.signs[against, index]
        return np.delete(np.arange(len(xy)), index), vectors

    def anchor(self, i: int, j: int) -> AnchorDetail:
        """Anchor (i, j) through candidate set, consensus, one-to-one rule and distance limit."""
        key = (int(i), int(j))
        if key not in self._anchors:
            self._anchors[key] = self._explain(*key)
        return self._anchors[key]

    def _explain(self, i: int, j: int) -> AnchorDetail:
        """Anchor (i, j) through the reference's eq. 10-12, on the run's candidate and voting sets."""
        sets = self.sets
        shape = sets.signs.shape
        members = sets.candidates.members(i * self.n_cav + j)
        candidates = self._pairs(members)
        in_set = np.zeros(shape, dtype=bool)
        in_set.flat[members] = True

        def votes_of(by: np.ndarray) -> np.ndarray:
            return votes_from(sets.voted_by, members, by, shape)

        agents = reference.Agents(sets.ego_xy, sets.ego_heading, sets.cav_xy, sets.cav_heading, sets.signs)
        kept = reference.consensus(in_set, votes_of, sets.rule)
        final = reference.one_to_one(kept)
        distance = reference.mean_distance(agents, final)
        return AnchorDetail(anchor=(i, j), candidates=candidates,
                            votes=votes_of(reference.voters(in_set, sets.rule)).flat[members].astype(int),
                            kept_by_consensus=kept.flat[members], final=np.argwhere(final),
                            mean_distance=distance,
                            rejected=bool(final.any()) and distance > sets.params.distance_limit)

    def best_anchor_among(self, pairs: np.ndarray) -> AnchorDetail | None:
        """The anchor with the largest score among the given pairs (ties: the first), or None.
        The scores come from the selection's kernel; only the best anchor is explained."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        if len(pairs) == 0:
            return None
        sizes = self._sizes(pairs[:, 0] * self.n_cav + pairs[:, 1])
        return self.anchor(*pairs[int(np.argmax(sizes))])

    def _sizes(self, anchors: np.ndarray) -> np.ndarray:
        """The filtered sizes of ``anchors`` (``selection.filtered_sizes``) as far as their largest
        and its first holder go: those the selection's visit computed (the same kernel on the same
        sets: the same sizes) are taken from it, the others filtered now, except an anchor whose
        card(L_ij) is below the largest size taken (filtering never grows a set: it cannot be the
        largest), which gets -1."""
        sets = self.sets
        visit = self.visit
        taken = {} if visit is None else dict(zip(visit.order[:len(visit.sizes)].tolist(), visit.sizes.tolist()))
        sizes = np.array([taken.get(anchor, -1) for anchor in anchors.tolist()], np.int64)
        unknown = (sizes < 0) & (sets.candidates.count[anchors] >= sizes.max(initial=0))
        sizes[unknown] = filtered_sizes(anchors[unknown], sets.candidates, sets.voted_by, sets.rule, sets.ego_xy,
                                        sets.cav_xy, sets.params.distance_limit)
        return sizes
