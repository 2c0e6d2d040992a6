"""Hypotheses, verified (beyond the paper, step 7c): several anchors' answers refined and
the one that explains the scene best kept, as RANSAC-style verification does in registration.

Eq. 13 keeps one anchor; under heavy noise its set can be a coincidence, and nothing checks it.
So the ``HYPOTHESES`` anchors with the largest filtered sets (eq. 12-13; among the ``POOL`` largest
candidate sets, the eq. 13 winner always first) are each

1. fitted robustly (eq. 15, ``cbm.estimate.robust_fit``); the eq. 13 winner is also re-associated
   as without verification (``cbm.reassociate``);
2. re-associated once more under the noise-aware gate (``cbm.gates``): a one-to-one assignment
   (``cbm.reassociate.gated_assignment``) inside 3 sigma, sigma read from the pairs' residuals,
   keeping the pairs more likely one object seen twice than a coincidence (``evidence``: centres
   and heading axes), then least squares on the pairs kept, until the pairs stop changing;
3. scored by the evidence it has: the summed log-likelihood ratio of its pairs (``evidence``). A
   pose that pairs many boxes tightly scores high; a loose pose pays for its wide noise on every
   pair, and boxes it leaves unpaired add nothing.

The best-scoring hypothesis is the answer (the eq. 13 winner's own refinement when it lands on
the same pose, as it had the guided re-association; the pose keeps the best score); the best one
whose pose differs from it (by more than ``SAME_POSE_M`` or ``SAME_POSE_DEG``) is the runner-up,
and the difference of their scores is the evidence margin (``verdict``). CBM stands by its answer
when the margin, and its score itself (its margin over no pose at all), reach ``EVIDENCE_MARGIN``.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import se2
from .engine import Visit, anchor_sets
from .engine.assignment import gated_assignment
from .engine.gaps import pair_gaps, pose_gap
from .engine.threads import check_stop
from .estimate import residuals, weighted_procrustes
from .gates import clutter_density, heading_log_ratio, heading_sigma, pair_log_ratio, scene_sigma
from .reassociate import MAX_ROUNDS, reassociate
from .result import Fit

PAIR_EVIDENCE = 0.0
"""Least log-likelihood ratio of a pair kept by the noise-aware re-association: more likely one
object than a coincidence. Chosen on the hard set and CBM over time at once (shipped log and three
synthetic sequences): 1.0 raised heavy noise per frame (S@1 .878 -> .906, precision .67 -> .71) but
lowered drift-heavy over time as much (S@1 .850 -> .799); 0.5 sat between."""
HYPOTHESES = 6
"""Anchors refined and verified (the eq. 13 winner and the next best distinct sets)."""
POOL = 64
"""Anchors with the largest candidate sets card(L_ij) whose filtered sets are compared."""
SAME_POSE_M = 1.0
SAME_POSE_DEG = 1.0
"""Two hypotheses whose corrections differ by less than this (metres and degrees) are one."""
MIN_SHARED = 3
"""Fewest pairs of a pose CBM stands by: with two, any pose fits them exactly."""
ROUNDING = 1e-9
"""Times ``pose_gap``'s scale within which a pose's distance or turn is compared as numpy computes it:
the two computations differ by less than 1e-14 times it."""
EVIDENCE_MARGIN = 8.0
"""Least log-likelihood-ratio margin (natural log) of the answer over a different answer to stand
by it: the answer explains the scene at least e^8 = 3000 times better. Measured (docs/algorithm.md):
under heavy noise the lowest margins of right answers were 6.2 and 9.1, of wrong ones 4.4 and 6.7;
under hard noise and clutter every right answer's margin was above 20. The answer must explain the
scene that much better than no pose at all too (its pairs' evidence, the null pose's being 0): a
frame of a handful of boxes forms no rival pose, and on the scenes table's sparse rows (seeds 0-1)
each of the 36 answers so left with a margin of ∞ but evidence under 8 was wrong."""


@dataclass(frozen=True)
class Hypothesis:
    """One anchor's answer after refinement, and its evidence."""

    anchor: int
    """Pair id of the anchor (``i * Nc + j``)."""
    context_pairs: np.ndarray
    """(K0, 2) the anchor's filtered set (eq. 12)."""
    pairs: np.ndarray
    """(K, 2) the pairs after refinement, one-to-one, sorted by ego index."""
    correction: np.ndarray
    """(3, 3) the ego-frame correction fitted to ``pairs``."""
    sigma: float
    """Metres. Per-axis noise std-dev read from the pairs' residuals (``cbm.gates.scene_sigma``)."""
    score: float
    """Summed log-likelihood ratio of the pairs (``cbm.gates.pair_log_ratio``)."""


@dataclass(frozen=True)
class Verdict:
    """The verified answer, its strongest different rival and whether the evidence suffices."""

    best: Hypothesis
    runner_up: Hypothesis | None
    """The best hypothesis with a different pose, None when every hypothesis agrees with the best."""
    tried: int
    """Hypotheses refined."""

    @property
    def margin(self) -> float:
        """How much better the best explains the scene (log-likelihood ratio); inf without a rival."""
        return math.inf if self.runner_up is None else self.best.score - self.runner_up.score

    @property
    def reason(self) -> str:
        """Why CBM has not enough evidence, or "" when it has."""
        if len(self.best.pairs) < MIN_SHARED:
            return f"fewer than {MIN_SHARED} objects could be paired"
        if self.margin < EVIDENCE_MARGIN:
            return (f"a different pose explains the scene almost as well "
                    f"(margin {self.margin:.1f} < {EVIDENCE_MARGIN:g})")
        if self.best.score < EVIDENCE_MARGIN:
            return (f"its pairs explain the scene hardly better than a coincidence "
                    f"(evidence {self.best.score:.1f} < {EVIDENCE_MARGIN:g})")
        return ""


Refit = Callable[[np.ndarray, np.ndarray], Fit]


def refine(ego: np.ndarray, cav: np.ndarray, pairs: np.ndarray, fit: Fit, refit: Refit, floor: float,
           widest: float, density: float, guided: bool) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Steps 1-3 for one set of pairs and its robust ``fit``: (pairs, correction, sigma, score) after
    the guided re-association (when ``guided``: the eq. 13 winner's, as without verification) and
    the noise-aware re-association with least squares on the pairs kept. Once the pairs settle, the
    last round's evidence of them is their score (the same pose, noise and pairs: ``score``)."""
    current = reassociate(ego, cav, pairs, fit, widest, refit).pairs if guided else pairs
    T, sigma = least_squares(ego, cav, current, floor)
    for _ in range(MAX_ROUNDS):
        moved = se2.apply_boxes(T, cav)
        found = gated_assignment(ego, moved, widest * sigma, sigma)
        weight = evidence(ego, moved, found, sigma, density, current)
        found, weight = found[weight > PAIR_EVIDENCE], weight[weight > PAIR_EVIDENCE]
        if np.array_equal(found, current):
            return current, T, sigma, float(weight.sum())
        if len(found) < 2:
            break
        current = found
        T, sigma = least_squares(ego, cav, current, floor)
    return current, T, sigma, score(ego, cav, current, T, sigma, density)


def score(ego: np.ndarray, cav: np.ndarray, pairs: np.ndarray, T: np.ndarray, sigma: float, density: float) -> float:
    """Step 3: the summed evidence of ``pairs`` under the correction ``T`` and noise ``sigma``."""
    return float(evidence(ego, se2.apply_boxes(T, cav), pairs, sigma, density, pairs).sum())


def least_squares(ego: np.ndarray, cav: np.ndarray, pairs: np.ndarray, floor: float) -> tuple[np.ndarray, float]:
    """The least-squares correction of ``pairs`` (eq. 15 with every weight 1: the efficient fit once
    the gate has cleaned them) and the noise sigma of its residuals (``cbm.gates.scene_sigma``)."""
    src, dst = cav[pairs[:, 1], :2], ego[pairs[:, 0], :2]
    T = weighted_procrustes(src, dst)
    return T, scene_sigma(residuals(T, src, dst), floor)


def hypothesis(ego: np.ndarray, cav: np.ndarray, anchor: int, pairs: np.ndarray, fit: Fit, refit: Refit,
               floor: float, widest: float, density: float, guided: bool) -> Hypothesis:
    """One anchor's set and its robust fit refined and scored (``refine``)."""
    found, T, sigma, evidence_sum = refine(ego, cav, pairs, fit, refit, floor, widest, density, guided)
    return Hypothesis(anchor, pairs, found, T, sigma, evidence_sum)


def predicted(ego: np.ndarray, cav: np.ndarray, sigma: float, floor: float, widest: float) -> Hypothesis | None:
    """A pose from the frames before (CBM over time's prediction, the CAV boxes ``cav`` moved by it)
    as one more hypothesis: the boxes paired one-to-one within ``widest`` of its noise ``sigma``, then
    refined and scored as an anchor's set is (``refine``); None when fewer than ``MIN_SHARED`` pair."""
    pairs = gated_assignment(ego, cav, widest * sigma, sigma)
    if len(pairs) < MIN_SHARED:
        return None
    found, T, noise, evidence_sum = refine(ego, cav, pairs, None, None, floor, widest, clutter_density(cav[:, :2]),
                                           False)
    return Hypothesis(-1, pairs, found, T, noise, evidence_sum) if len(found) >= MIN_SHARED else None


def evidence(ego: np.ndarray, moved: np.ndarray, pairs: np.ndarray, sigma: float, density: float,
             reference: np.ndarray) -> np.ndarray:
    """Each pair's log-likelihood ratio, one object seen twice against a coincidence: its centres'
    (``pair_log_ratio``) plus its heading axes' (``heading_log_ratio``, the heading noise read from
    the ``reference`` pairs). ``moved``: the CAV boxes under the pose."""
    ego = np.ascontiguousarray(ego)
    d, turn = pair_gaps(ego, moved, pairs)
    heading = heading_sigma(pair_gaps(ego, moved, reference)[1])
    return pair_log_ratio(d, sigma, density) + heading_log_ratio(turn, heading)


def same_pose(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two corrections differ by less than ``SAME_POSE_M`` and ``SAME_POSE_DEG``: the
    transform between them (``pose_gap``), or where it lies within rounding of either bound, the
    transform ``inverse(a) @ b`` as numpy computes it (``_small``)."""
    metres, degrees, scale = pose_gap(a, b)
    if min(abs(metres - SAME_POSE_M), abs(degrees - SAME_POSE_DEG)) <= ROUNDING * scale:
        return _small(se2.inverse(a) @ b)
    return bool(metres < SAME_POSE_M and degrees < SAME_POSE_DEG)


def near_any(a: np.ndarray, poses: list[np.ndarray]) -> bool:
    """Whether ``a`` is the same pose as one of ``poses`` (``same_pose``)."""
    return any(same_pose(a, pose) for pose in poses)


def _small(d: np.ndarray) -> bool:
    """Whether the transform ``d`` between two corrections moves by less than ``SAME_POSE_M`` and
    turns by less than ``SAME_POSE_DEG``."""
    return (float(np.hypot(*se2.translation_of(d))) < SAME_POSE_M
            and abs(math.degrees(float(se2.yaw_of(d)))) < SAME_POSE_DEG)


def same_answer(a: Hypothesis, b: Hypothesis) -> bool:
    """Whether two hypotheses are one answer: the same pose (``same_pose``), or most (over half) of
    the pairs of either one in the other (the same objects, the pose apart by the noise)."""
    if same_pose(a.correction, b.correction):
        return True
    shared = len({tuple(p) for p in a.pairs.tolist()} & {tuple(p) for p in b.pairs.tolist()})
    return 2 * shared > min(len(a.pairs), len(b.pairs))


def verify(sets, winner: int, winner_fit: Fit, refit: Refit, floor: float, widest: float,
           visit: Visit | None = None) -> Verdict | None:
    """Refine and score the eq. 13 ``winner`` (its set's robust fit ``winner_fit``) and the next
    best anchors' sets of ``sets`` (``cbm.pipeline.Sets``); None when no set holds 2 pairs. A set
    whose robust fit lands on the pose of a set already tried (``same_pose``, before or after its
    refinement) would refine to the same answer: it is skipped, so an easy scene costs about one
    refinement. Only the winner runs the guided re-association (its robust refit every round is the
    costly part); the others go straight to the noise-aware one. The sets eq. 13's ``visit``
    (``cbm.engine.Visit``) filtered are not filtered again."""
    density = clutter_density(sets.cav_xy)
    ego, cav = sets.ego_boxes, sets.cav_boxes
    found: list[Hypothesis] = []
    poses: list[np.ndarray] = []
    for anchor, pairs in anchor_sets(sets.candidates, sets.voted_by, sets.rule, sets.ego_xy, sets.cav_xy,
                                     sets.params.distance_limit, winner, HYPOTHESES, POOL, visit):
        check_stop()
        if len(pairs) < 2:
            continue
        fit = winner_fit if anchor == winner else refit(cav[pairs[:, 1], :2], ego[pairs[:, 0], :2])
        if near_any(fit.transform, poses):
            continue
        found.append(hypothesis(ego, cav, anchor, pairs, fit, refit, floor, widest, density, anchor == winner))
        poses += [fit.transform, found[-1].correction]
    if not found:
        return None
    best = max(found, key=lambda h: h.score)
    rivals = [h for h in found if not same_answer(h, best)]
    if found[0].anchor == winner and same_pose(found[0].correction, best.correction):
        best = dataclasses.replace(found[0], score=best.score)
    return Verdict(best, max(rivals, key=lambda h: h.score) if rivals else None, len(found))
