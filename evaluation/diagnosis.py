"""Why a frame failed: rules that read a result, its trial and CBM's own sets.

Each rule returns a ``Finding`` or None; ``diagnose`` lists the findings of all rules, most basic first.
Objects are named by their ids as the app's labels show them (``short_id``), never by row index.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cbm import Explanation, MatchResult

from .scenario import Trial


@dataclass(frozen=True)
class Finding:
    code: str
    """One of: few_covisible, no_anchor, single_pair, distance_limit, heading_fold, wrong_anchor."""
    message: str


ID_CHARS = 8
"""Characters of an object id that labels show."""


def short_id(value: object) -> str:
    """An object id as labels show it: its first ``ID_CHARS`` characters."""
    return str(value)[:ID_CHARS]


def pair_name(trial: Trial, pair: tuple[int, int] | np.ndarray) -> str:
    """An (ego row, CAV row) pair by the objects' ids: ``ego 46 ↔ CAV 20``."""
    i, j = (int(k) for k in pair)
    return f"ego {_name(trial.ego_ids, i)} ↔ CAV {_name(trial.cav_ids, j)}"


def _name(ids: np.ndarray, row: int) -> str:
    """The id of ``row``; its row number only for a trial that has no ids (a constructed one)."""
    return short_id(ids[row]) if row < len(ids) else f"row {row}"


def too_few_covisible(trial: Trial, minimum: int = 3) -> Finding | None:
    """Fewer co-visible objects than a context needs to be told apart."""
    n = len(trial.gt_pairs)
    if n < minimum:
        return Finding("few_covisible", f"too few co-visible objects: {n} (fewer than {minimum})")
    return None


def no_anchor_reached_two(result: MatchResult, explanation: Explanation) -> Finding | None:
    """No candidate set held 2 pairs (eq. 9), or the distance limit rejected every one."""
    if result.anchor is not None:
        return None
    if explanation.sets.candidates.count.any():
        return Finding("no_anchor", "no anchor reached 2 pairs: every candidate set was emptied by consensus "
                                    "and the one-to-one rule or rejected by the distance limit")
    return Finding("no_anchor",
                   "no anchor reached 2 pairs: no context vectors agreed within sigma1 and sigma2 (eq. 8-9)")


def single_pair(result: MatchResult) -> Finding | None:
    """The winning set held one pair: nothing to estimate a pose from."""
    if result.anchor is not None and result.consensus_count == 1:
        return Finding("single_pair", "the winner had a single pair: no pose estimate was made")
    return None


def distance_limit(result: MatchResult, trial: Trial, explanation: Explanation, near: float = 0.8) -> Finding | None:
    """The right anchor was rejected by the distance limit, or the winner came within ``near`` of it."""
    limit = explanation.sets.params.distance_limit
    right = explanation.best_anchor_among(trial.gt_pairs)
    if right is not None and right.rejected:
        return Finding("distance_limit", f"the right anchor {pair_name(trial, right.anchor)} was rejected by the "
                                         f"distance limit: its pairs are {right.mean_distance:.1f} m apart on "
                                         f"average (limit {limit:g} m)")
    if result.anchor is not None:
        winner = explanation.anchor(*result.anchor)
        if winner.mean_distance >= near * limit:
            return Finding("distance_limit", f"the winning anchor was nearly rejected by the distance limit: "
                                             f"{winner.mean_distance:.1f} m of {limit:g} m")
    return None


def heading_fold(trial: Trial, explanation: Explanation) -> Finding | None:
    """Co-visible objects whose local frames CBM compares turned by pi against each other: the frames
    as compared (CAV frame times its sign) point more than 135 degrees apart. Only ``fold`` can do this."""
    sets = explanation.sets
    gt = np.asarray(trial.gt_pairs).reshape(-1, 2)
    if len(gt) == 0:
        return None
    alignment = np.cos(sets.ego_heading[gt[:, 0]] - sets.cav_heading[gt[:, 1]]) * sets.signs[gt[:, 0], gt[:, 1]]
    flipped = np.flatnonzero(alignment < -math.cos(math.pi / 4))
    if len(flipped) == 0:
        return None
    ids = ", ".join(short_id(trial.ego_ids[gt[k, 0]]) for k in flipped[:5])
    return Finding("heading_fold", f"{len(flipped)} co-visible object(s) folded differently for the two agents "
                                   f"(heading near +-90 degrees: {ids}); their local frames are flipped — "
                                   f"heading='align' avoids this")


def wrong_anchor(result: MatchResult, trial: Trial, explanation: Explanation) -> Finding | None:
    """The winning anchor is not a true pair; how the best true anchor scored against the
    consensus margin's runner-up (eq. 13: ``result.runner_up_count``). Nothing when every pair of the
    answer is right (the re-association left the anchor out): the anchor did no harm."""
    if result.anchor is None:
        return None
    gt = {tuple(p) for p in np.asarray(trial.gt_pairs).reshape(-1, 2).tolist()}
    answer = {tuple(p) for p in np.asarray(result.pairs).reshape(-1, 2).tolist()}
    if tuple(result.anchor) in gt or (answer and answer <= gt):
        return None
    winner = f"the winning anchor {pair_name(trial, result.anchor)} was wrong with {result.consensus_count} pairs"
    right = explanation.best_anchor_among(trial.gt_pairs)
    if right is None:
        return Finding("wrong_anchor", f"{winner} and there is no right anchor")
    return Finding("wrong_anchor", f"{winner}; the best right anchor {pair_name(trial, right.anchor)} "
                                   f"{rank_against_runner_up(right.size, result.runner_up_count)}")


def rank_against_runner_up(size: int, runner_up: int) -> str:
    """How a right anchor holding ``size`` pairs placed, in the consensus margin's terms."""
    if size == runner_up:
        return f"came second with {size} (the runner-up of the consensus margin)"
    if size < runner_up:
        return f"held only {size}: a wrong anchor came second with {runner_up}"
    return (f"held {size}, more than the runner-up's {runner_up}, but shares pairs with the winning set, "
            f"so the margin does not count it")


def diagnose(result: MatchResult, trial: Trial, explanation: Explanation) -> list[Finding]:
    """Every finding that applies, most basic first; empty when nothing looks wrong."""
    findings = [too_few_covisible(trial), no_anchor_reached_two(result, explanation), single_pair(result),
                distance_limit(result, trial, explanation), heading_fold(trial, explanation),
                wrong_anchor(result, trial, explanation)]
    return [f for f in findings if f is not None]
