"""Explain CBM on one input: any anchor's context, candidate set, votes and filtered set.

``Inspection`` runs steps 1-4 once (``cbm.pipeline.build_sets``) and then answers questions about
single anchors with plain numpy, so the app can show why a pair was kept or dropped.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .consensus import PairSets
from .params import CBMParams
from .pipeline import Sets, build_sets, checked_inputs, match_sets_visited
from .result import MatchResult
from .reuse import Reuse
from .selection import filtered_sizes


@dataclass(frozen=True)
class AnchorDetail:
    """One anchor pair's way through eq. 8-13."""

    anchor: tuple[int, int]
    candidates: np.ndarray
    """(K, 2) L_ij, the anchor pair included (eq. 8); empty when fewer than 2 pairs were accepted."""
    votes: np.ndarray
    """(K,) votes each candidate got from the set's voters (left side of eq. 10)."""
    kept_by_consensus: np.ndarray
    """(K,) bool: the candidate survived the consensus rule (all True when consensus is off)."""
    final: np.ndarray
    """(M, 2) L^(2)_ij after the one-to-one rule (eq. 11)."""
    mean_distance: float
    """Mean centre distance of the final pairs after ``init`` (NaN when empty)."""
    rejected: bool
    """The distance limit rejects the anchor."""

    @property
    def size(self) -> int:
        """What the anchor scores in eq. 12: card(L^(2)_ij), 0 when rejected."""
        return 0 if self.rejected else len(self.final)


def _occurs_once(values: np.ndarray) -> np.ndarray:
    """Whether each of ``values`` (object indices, not negative) occurs once among them."""
    return np.bincount(values)[values] == 1


def _votes_from(voted_by: PairSets, members: np.ndarray, voters: np.ndarray, n_pairs: int) -> np.ndarray:
    """For each member: how many ``voters`` hold it in their voting set."""
    is_voter = np.zeros(n_pairs, dtype=bool)
    is_voter[voters] = True
    starts = voted_by.start[members]
    lengths = voted_by.start[members + 1] - starts
    owner = np.repeat(np.arange(len(members)), lengths)
    rows = starts[owner] + np.arange(lengths.sum()) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    return np.bincount(owner, weights=is_voter[voted_by.member[rows]], minlength=len(members)).astype(int)


def one_to_one_mask(pairs: np.ndarray) -> np.ndarray:
    """Eq. 11: pairs whose ego object and CAV object each occur once."""
    if len(pairs) == 0:
        return np.zeros(0, dtype=bool)
    return _occurs_once(pairs[:, 0]) & _occurs_once(pairs[:, 1])


class Inspection:
    """CBM's sets on one input, kept so that any anchor can be explained."""

    def __init__(self, ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray | None = None,
                 params: CBMParams | None = None, reuse: Reuse | None = None) -> None:
        """Steps 1-4 on the input; with ``reuse``, what an earlier inspection of it built is reused."""
        started = time.perf_counter()
        ego, cav, init, params = checked_inputs(ego_boxes, cav_boxes, init, params)
        self._timings: dict[str, float] = {}
        self.sets: Sets = build_sets(ego, cav, init, params, self._timings, reuse)
        self.init, self.n_cav, self._started = init, len(cav), started
        self._anchors: dict[tuple[int, int], AnchorDetail] = {}
        """Anchors explained so far: kept with this inspection and forgotten with it."""
        self._visited: tuple[np.ndarray, np.ndarray] | None = None
        """(anchors, filtered sizes) the selection's visit computed (``match``), None before."""

    def match(self) -> MatchResult:
        """What ``cbm.match`` returns on the same input, from the sets already built; the filtered
        sizes its selection computed are kept for ``best_anchor_among``."""
        result, visit = match_sets_visited(self.sets, self.init, dict(self._timings), self._started)
        if visit is not None:
            self._visited = visit.order[:len(visit.sizes)], visit.sizes
        return result

    def _pairs(self, ids: np.ndarray) -> np.ndarray:
        return np.stack([ids // self.n_cav, ids % self.n_cav], axis=1).reshape(-1, 2)

    def context(self, agent: str, index: int, against: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(neighbour indices, (n - 1, 2) context vectors) of one object in its own local frame
        (eq. 5-6). For a CAV object compared ``against`` an ego object, the frame as CBM turns it."""
        context = self.sets.ego_context if agent == "ego" else self.sets.cav_context
        rows = context.anchor == index
        vectors = context.vectors[rows]
        if agent == "cav" and against is not None:
            vectors = vectors * self.sets.signs[against, index]
        return context.member[rows], vectors

    def anchor(self, i: int, j: int) -> AnchorDetail:
        """Anchor (i, j) through candidate set, consensus, one-to-one rule and distance limit."""
        key = (int(i), int(j))
        if key not in self._anchors:
            self._anchors[key] = self._explain(*key)
        return self._anchors[key]

    def _explain(self, i: int, j: int) -> AnchorDetail:
        sets = self.sets
        a = i * self.n_cav + j
        members = sets.candidates.members(a)
        candidates = self._pairs(members)
        lone = one_to_one_mask(candidates)
        voters = members[lone] if sets.rule == "released" else members
        votes = _votes_from(sets.voted_by, members, voters, len(sets.signs.ravel()))
        kept = {None: np.ones(len(members), dtype=bool), "paper": votes > 1, "released": lone | (votes >= 1)}[sets.rule]
        survivors = candidates[kept]
        final = survivors[one_to_one_mask(survivors)]
        final = final[np.argsort(final[:, 0], kind="stable")]
        distance = (float(np.linalg.norm(sets.ego_xy[final[:, 0]] - sets.cav_xy[final[:, 1]], axis=1).mean())
                    if len(final) else float("nan"))
        return AnchorDetail(anchor=(i, j), candidates=candidates, votes=votes, kept_by_consensus=kept, final=final,
                            mean_distance=distance, rejected=bool(len(final)) and distance > sets.params.distance_limit)

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
        taken = {} if self._visited is None else dict(zip(*(values.tolist() for values in self._visited)))
        sizes = np.array([taken.get(anchor, -1) for anchor in anchors.tolist()], np.int64)
        unknown = (sizes < 0) & (sets.candidates.count[anchors] >= sizes.max(initial=0))
        sizes[unknown] = filtered_sizes(anchors[unknown], sets.candidates, sets.voted_by, sets.rule, sets.ego_xy,
                                        sets.cav_xy, sets.params.distance_limit)
        return sizes
