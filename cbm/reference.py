"""CBM as the paper states it: eq. 5-14, one short function per equation, in plain numpy.

Song et al., "A Spatial Calibration Method for Robust Cooperative Perception", IEEE RA-L 2024,
section III-B. This module is the definition of CBM's matching: the fast engine that ``cbm.match``
runs (``cbm.engine``) must give the same pairs, counts, anchor and runner-up as ``match_sets``
(``tests/cbm/test_engine_reference.py``). It builds every set of every anchor, so it suits scenes
of a few tens of objects; it needs nothing else of this package.

Notation. The ego sees objects i = 0..Ne-1 at centres p_i with headings theta_i; the CAV sees
objects j = 0..Nc-1, which step 1 moves into the ego frame with the (wrong) initial pose. A pair
(i, j) says "ego object i and CAV object j are one object". A set of pairs is an (Ne, Nc) boolean
matrix; the sets of every anchor pair (i, j) are an (Ne, Nc, Ne, Nc) array, ``sets[i, j]``.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

Rule = Literal["paper", "released"] | None
"""Eq. 10 as the paper states it, the authors' released code's variant, or no consensus at all."""


@dataclass(frozen=True)
class Agents:
    """Both agents' objects after steps 1-2: centres and folded headings in the ego frame, and the
    sign each CAV object's frame takes against each ego object's."""

    ego_xy: np.ndarray
    """(Ne, 2) ego centres p_i."""
    ego_heading: np.ndarray
    """(Ne,) folded ego headings theta_i."""
    cav_xy: np.ndarray
    """(Nc, 2) CAV centres after the initial pose."""
    cav_heading: np.ndarray
    """(Nc,) folded CAV headings after the initial pose."""
    signs: np.ndarray
    """(Ne, Nc) +1, or -1 where the CAV frame is turned by pi to face the ego frame's way."""


def pre_transform(init: np.ndarray, cav_boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Step 1: the CAV's centres and headings in the ego frame under the initial pose ``init``
    (a (3, 3) SE(2) matrix): ``p = R p_cav + t``, ``theta = theta_cav + yaw(R)``, wrapped to [-pi, pi)."""
    xy = cav_boxes[:, :2] @ init[:2, :2].T + init[:2, 2]
    yaw = (cav_boxes[:, 6] + np.arctan2(init[1, 0], init[0, 0]) + np.pi) % (2.0 * np.pi) - np.pi
    return xy, yaw


def fold_heading(yaw: np.ndarray) -> np.ndarray:
    """Step 2: headings folded into (-pi/2, pi/2], as the released code does: a box's heading is
    known up to a half turn, so theta and theta + pi are one frame."""
    folded = np.mod(np.asarray(yaw, dtype=float) + np.pi / 2, np.pi) - np.pi / 2
    return np.where(folded == -np.pi / 2, np.pi / 2, folded)


def pair_signs(ego_heading: np.ndarray, cav_heading: np.ndarray, mode: str) -> np.ndarray:
    """Step 2: (Ne, Nc) the sign of a CAV object's frame when it is compared with an ego object's.

    ``fold``: always +1 (the released code); an object near +-90 degrees may then fold to opposite
    directions for the two agents, and its frame flips. ``align``: -1 where the folded headings
    differ by more than 90 degrees, which turns the CAV frame by pi to lie within 90 degrees of the
    ego frame, so a co-visible object's frames never flip."""
    if mode == "fold":
        return np.ones((len(ego_heading), len(cav_heading)))
    apart = np.abs(np.asarray(cav_heading, dtype=float)[None, :] - np.asarray(ego_heading, dtype=float)[:, None])
    return np.where(apart <= np.pi / 2, 1.0, -1.0)


def agents(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, heading: str) -> Agents:
    """Steps 1-2 on (N, 7) boxes ``x, y, z, length, width, height, yaw``."""
    cav_xy, cav_yaw = pre_transform(init, cav_boxes)
    ego_heading, cav_heading = fold_heading(ego_boxes[:, 6]), fold_heading(cav_yaw)
    return Agents(np.asarray(ego_boxes[:, :2], dtype=float), ego_heading, cav_xy, cav_heading,
                  pair_signs(ego_heading, cav_heading, heading))


def context_vectors(xy: np.ndarray, heading: np.ndarray, i: int) -> np.ndarray:
    """Eq. 6-7: the context matrix P_i of object i, as (N, 2) rows ``z_ii' = R(theta_i)^T (p_i' - p_i)``,
    every neighbour i' in its anchor's own frame (row i is the zero vector and never used)."""
    c, s = np.cos(heading[i]), np.sin(heading[i])
    d = xy - xy[i]
    return np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=1)


def similar(z: np.ndarray, w: np.ndarray, sigma1: float, sigma2: float) -> np.ndarray:
    """Eq. 8 (Algorithm 1): context vectors z and w (broadcast, last axis x, y) match when the
    angle between their lines is within sigma1 (radians) and their L1 distance within sigma2:

        arccos(|z . w| / (|z| |w|)) <= sigma1      and      ||z - w||_1 <= sigma2

    A zero vector has no direction and matches nothing."""
    norms = np.linalg.norm(z, axis=-1) * np.linalg.norm(w, axis=-1)
    cosine = np.abs(np.sum(z * w, axis=-1)) / np.where(norms > 0, norms, 1.0)
    angle = np.arccos(np.minimum(cosine, 1.0))
    return (norms > 0) & (angle <= sigma1) & (np.abs(z - w).sum(axis=-1) <= sigma2)


def candidate_set(a: Agents, i: int, j: int, sigma1: float, tolerance: float) -> np.ndarray:
    """Eq. 9: L_ij, the pairs (i', j') whose context vectors seen from the anchor pair (i, j) match
    (eq. 8 with L1 tolerance ``tolerance``), i' != i and j' != j; the anchor pair joins a set that
    is not empty. The CAV frame is turned by the pair's sign (step 2). With sigma3 for the
    tolerance it is the voting set V_ij (the authors' released code: beyond the paper, whose eq. 10
    votes with the sets L_ij themselves)."""
    z = context_vectors(a.ego_xy, a.ego_heading, i)
    w = a.signs[i, j] * context_vectors(a.cav_xy, a.cav_heading, j)
    members = similar(z[:, None, :], w[None, :, :], sigma1, tolerance)
    members[i, :] = members[:, j] = False
    members[i, j] = members.any()
    return members


def candidate_sets(a: Agents, sigma1: float, tolerance: float) -> np.ndarray:
    """Eq. 9 for every anchor pair: ``sets[i, j]`` is L_ij (with sigma3, V_ij: ``candidate_set``)."""
    n_ego, n_cav = a.signs.shape
    sets = np.zeros((n_ego, n_cav, n_ego, n_cav), dtype=bool)
    for i in range(n_ego):
        for j in range(n_cav):
            sets[i, j] = candidate_set(a, i, j, sigma1, tolerance)
    return sets


def one_to_one(pairs: np.ndarray) -> np.ndarray:
    """Eq. 12: the pairs of the set ``pairs`` that are alone in their row and their column, so that
    no ego or CAV object is paired twice."""
    return pairs & (pairs.sum(axis=1, keepdims=True) == 1) & (pairs.sum(axis=0, keepdims=True) == 1)


def voters(members: np.ndarray, rule: Rule) -> np.ndarray:
    """The members of a candidate set whose voting sets count in eq. 10: every member under the
    paper's rule, the members alone in their row and column under the released code's, none
    without consensus."""
    if rule is None:
        return np.zeros_like(members)
    return members if rule == "paper" else one_to_one(members)


def votes(voting: np.ndarray, by: np.ndarray) -> np.ndarray:
    """Eq. 10's sum for every pair (i', j'): how many of the pairs ``by`` hold it in their
    voting set, ``sum_{(k', h') in by} V_k'h'(i', j')``, from every pair's voting set ``voting``."""
    return voting[by].sum(axis=0)


def consensus(members: np.ndarray, votes_of: Callable[[np.ndarray], np.ndarray], rule: Rule) -> np.ndarray:
    """Eq. 10-11: the members of a candidate set that its own members vouch for; ``votes_of(by)``
    counts, for every pair, the voting sets of the pairs ``by`` that hold it (``votes``).

    ``paper``: (i', j') stays when ``sum_{(k', h') in L_ij} V_k'h'(i', j') > 1``: another member's
    voting set holds it too (each non-empty voting set holds its own pair). ``released`` (the
    authors' code): members alone in their row and column stay as they are; the others stay when
    the voting set of one of those lone members holds them. ``None``: no consensus."""
    if rule is None:
        return members
    counted = votes_of(voters(members, rule))
    if rule == "paper":
        return members & (counted > 1)
    return one_to_one(members) | (members & (counted >= 1))


def mean_distance(a: Agents, pairs: np.ndarray) -> float:
    """How far apart a set's pairs lie on average under the initial pose (metres; NaN when empty)."""
    i, j = np.nonzero(pairs)
    return float(np.linalg.norm(a.ego_xy[i] - a.cav_xy[j], axis=1).mean()) if len(i) else float("nan")


def filtered_set(a: Agents, members: np.ndarray, votes_of: Callable[[np.ndarray], np.ndarray], rule: Rule,
                 distance_limit: float) -> np.ndarray:
    """Eq. 12's L^(2)_ij: a candidate set after the consensus (eq. 10-11) and the one-to-one rule
    (eq. 12); empty when its pairs lie on average farther apart than ``distance_limit`` metres
    under the initial pose (the released code's check)."""
    kept = one_to_one(consensus(members, votes_of, rule))
    return np.zeros_like(kept) if mean_distance(a, kept) > distance_limit else kept


def rigid_rms(ego_xy: np.ndarray, cav_xy: np.ndarray) -> float:
    """RMS residual of the least-squares rigid fit ``ego ~ R cav + t`` of matched centres (0 for
    fewer than two): how well one rigid motion explains a set."""
    if len(ego_xy) < 2:
        return 0.0
    s, d = cav_xy - cav_xy.mean(axis=0), ego_xy - ego_xy.mean(axis=0)
    yaw = np.arctan2(np.sum(s[:, 0] * d[:, 1] - s[:, 1] * d[:, 0]), np.sum(s[:, 0] * d[:, 0] + s[:, 1] * d[:, 1]))
    c, n = np.cos(yaw), np.sin(yaw)
    moved = np.stack([c * s[:, 0] - n * s[:, 1], n * s[:, 0] + c * s[:, 1]], axis=1)
    return float(np.sqrt(np.mean(np.sum((moved - d) ** 2, axis=1))))


def set_key(ego_xy: np.ndarray, cav_xy: np.ndarray) -> tuple[float, ...]:
    """Eq. 13's order among sets of one size, which the paper leaves open: the smaller rigid-fit
    residual of the set's matched centres, then its ego and CAV centroids, rounded to 1e-9. The
    pairs are put in the order of their coordinates first, so the key never depends on the order of
    the input boxes."""
    order = np.lexsort((cav_xy[:, 1], cav_xy[:, 0], ego_xy[:, 1], ego_xy[:, 0]))
    ego_xy, cav_xy = ego_xy[order], cav_xy[order]
    key = (rigid_rms(ego_xy, cav_xy), *ego_xy.mean(axis=0), *cav_xy.mean(axis=0))
    return tuple(round(float(value), 9) for value in key)


def tie_key(a: Agents, pairs: np.ndarray, anchor: tuple[int, int]) -> tuple[float, ...]:
    """``set_key`` of the set ``pairs``, then the anchor's centres (two anchors may hold one set)."""
    i, j = np.nonzero(pairs)
    return set_key(a.ego_xy[i], a.cav_xy[j]) + (*a.ego_xy[anchor[0]], *a.cav_xy[anchor[1]])


def select_anchor(a: Agents, filtered: np.ndarray) -> tuple[int, int] | None:
    """Eq. 13: the anchor pair whose filtered set L^(2)_ij is largest (ties by ``tie_key``), or
    None when every filtered set is empty."""
    sizes = filtered.sum(axis=(2, 3))
    if sizes.max(initial=0) == 0:
        return None
    tied = [(int(i), int(j)) for i, j in zip(*np.nonzero(sizes == sizes.max()))]
    return min(tied, key=lambda anchor: tie_key(a, filtered[anchor], anchor))


def runner_up(filtered: np.ndarray, winner: np.ndarray) -> int:
    """The size of the largest filtered set that shares no pair with the ``winner``'s set: the
    strongest rival answer (0 when there is none)."""
    disjoint = ~(filtered & winner).any(axis=(2, 3))
    return int(filtered.sum(axis=(2, 3))[disjoint].max(initial=0))


@dataclass(frozen=True)
class Matching:
    """What eq. 5-14 give on one input."""

    pairs: np.ndarray
    """(K, 2) (ego index, CAV index) of the winning filtered set, sorted by ego index."""
    anchor: tuple[int, int] | None
    """The winning anchor pair, None when every filtered set is empty."""
    candidate_count: int
    """card(L_ij) of the winning anchor (eq. 9), the anchor pair included."""
    runner_up_count: int
    """The largest filtered set sharing no pair with the winner's (``runner_up``)."""
    candidates: np.ndarray
    """(Ne, Nc, Ne, Nc) every anchor's candidate set L_ij (eq. 9)."""
    filtered: np.ndarray
    """(Ne, Nc, Ne, Nc) every anchor's filtered set L^(2)_ij (eq. 12)."""


def match_sets(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, sigma1: float, sigma2: float,
               sigma3: float, distance_limit: float, rule: Rule, heading: str = "align") -> Matching:
    """Eq. 5-14 on (N, 7) boxes and the initial pose: every anchor's candidate set (eq. 9) and
    voting set (sigma3: the released code's), its filtered set (eq. 10-12), and the largest of them
    (eq. 13-14). ``sigma1``
    in radians, the others in metres; ``rule`` None switches the consensus off."""
    a = agents(np.asarray(ego_boxes, dtype=float), np.asarray(cav_boxes, dtype=float), init, heading)
    candidates = candidate_sets(a, sigma1, sigma2)
    voting = candidate_sets(a, sigma1, sigma3) if rule is not None else None
    filtered = np.zeros_like(candidates)
    for i, j in np.ndindex(a.signs.shape):
        filtered[i, j] = filtered_set(a, candidates[i, j], lambda by: votes(voting, by), rule, distance_limit)
    anchor = select_anchor(a, filtered)
    if anchor is None:
        return Matching(np.zeros((0, 2), dtype=np.intp), None, 0, 0, candidates, filtered)
    return Matching(np.argwhere(filtered[anchor]), anchor, int(candidates[anchor].sum()),
                    runner_up(filtered, filtered[anchor]), candidates, filtered)
