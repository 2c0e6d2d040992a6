"""Why a frame failed: rules that read a result, its trial and CBM's own sets.

Each rule returns a ``Finding`` or None; ``diagnose`` lists the findings of CBM's rules, most basic
first; ``diagnose_failure`` adds the rules any method's failure answers to (the noise, wrong pairs,
too few right pairs), so that every failed frame has a diagnosis. They compare least squares on
chosen pairs (the oracle's fit, eq. 15 with psi(r) = r^2): on all the true pairs, on the answer's
right pairs alone. Objects are named by their ids as the app's labels show them (``short_id``),
never by row index.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from cbm import Explanation, MatchResult
from cbm.methods import METHODS

from .metrics import TrialMetrics, evaluate, is_success
from .scenario import Trial

SURE_FROM = 8.0
"""The evidence margin (natural-log likelihood ratio over the best different pose) from which CBM
stands by its pose: ``cbm.hypotheses.EVIDENCE_MARGIN`` (``tests/evaluation/test_diagnosis.py``
checks they agree)."""
NAMED = 3
"""Wrong pairs a finding names before it counts the rest."""
LIMIT, NEAR = 1.0, 0.8
"""A frame fails from 1 m of RTE or 1° of RRE (``metrics.is_success``); least squares on the true pairs
within ``NEAR`` of that (0.8 m, 0.8°) leaves the matching too little room to call it its fault."""
CLOSE_M = 40.0
"""Right pairs all this close together (metres) are said to be: a short lever for the rotation."""


@dataclass(frozen=True)
class Finding:
    code: str
    """One of: few_covisible, no_anchor, single_pair, distance_limit, heading_fold, wrong_anchor (CBM's
    rules), no_estimate, nothing_paired, noise, wrong_pairs, few_right_pairs, not_the_fit, unexplained
    (any method's), track, over_time (a method over time's)."""
    message: str
    short: str = ""
    """The finding in a few words (the key numbers' reason); ``message`` when empty."""

    @property
    def brief(self) -> str:
        return self.short or self.message


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
        return Finding("few_covisible", f"too few co-visible objects: {n} (fewer than {minimum})",
                       f"too few co-visible objects ({n})")
    return None


def no_anchor_reached_two(result: MatchResult, explanation: Explanation) -> Finding | None:
    """No candidate set held 2 pairs (eq. 9), or the distance limit rejected every one."""
    if result.anchor is not None:
        return None
    if explanation.sets.candidates.count.any():
        return Finding("no_anchor", "no anchor reached 2 pairs: every candidate set was emptied by consensus "
                                    "and the one-to-one rule or rejected by the distance limit",
                       "no anchor reached 2 pairs")
    return Finding("no_anchor",
                   "no anchor reached 2 pairs: no context vectors agreed within sigma1 and sigma2 (eq. 8-9)",
                   "no anchor reached 2 pairs")


def single_pair(result: MatchResult) -> Finding | None:
    """The winning set held one pair: nothing to estimate a pose from."""
    if result.anchor is not None and result.consensus_count == 1:
        return Finding("single_pair", "the winner had a single pair: no pose estimate was made",
                       "its winning anchor held a single pair")
    return None


def distance_limit(result: MatchResult, trial: Trial, explanation: Explanation, near: float = 0.8) -> Finding | None:
    """The right anchor was rejected by the distance limit, or the winner came within ``near`` of it."""
    limit = explanation.sets.params.distance_limit
    right = explanation.best_anchor_among(trial.gt_pairs)
    if right is not None and right.rejected:
        return Finding("distance_limit", f"the right anchor {pair_name(trial, right.anchor)} was rejected by the "
                                         f"distance limit: its pairs are {right.mean_distance:.1f} m apart on "
                                         f"average (limit {limit:g} m)", "the distance limit rejected the right anchor")
    if result.anchor is not None:
        winner = explanation.anchor(*result.anchor)
        if winner.mean_distance >= near * limit:
            return Finding("distance_limit", f"the winning anchor was nearly rejected by the distance limit: "
                                             f"{winner.mean_distance:.1f} m of {limit:g} m",
                           "the distance limit nearly rejected its winning anchor")
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
                                   f"heading='align' avoids this", "headings folded differently for the two agents")


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
        return Finding("wrong_anchor", f"{winner} and there is no right anchor", "its winning anchor was a wrong pair")
    return Finding("wrong_anchor", f"{winner}; the best right anchor {pair_name(trial, right.anchor)} "
                                   f"{rank_against_runner_up(right.size, result.runner_up_count)}",
                   "its winning anchor was a wrong pair")


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


def least_squares_on(trial: Trial, pairs: np.ndarray) -> TrialMetrics:
    """The metrics of least squares on ``pairs`` (the oracle's fit given them as the true pairs)."""
    pairs = np.asarray(pairs).reshape(-1, 2)
    return evaluate(METHODS["oracle"](trial.ego_boxes, trial.cav_boxes, trial.init, true_pairs=pairs), trial)


def errors(m: TrialMetrics) -> str:
    """``0.99° / 1.08 m``: a pose's RRE and RTE."""
    return f"{m.rre:.2f}° / {m.rte:.2f} m"


def split_pairs(result: MatchResult, trial: Trial) -> tuple[np.ndarray, np.ndarray]:
    """The answer's (right, wrong) pairs against the trial's true pairs."""
    pairs = np.asarray(result.pairs, int).reshape(-1, 2)
    truth = {tuple(p) for p in np.asarray(trial.gt_pairs, int).reshape(-1, 2).tolist()}
    right = np.array([tuple(p) in truth for p in pairs.tolist()], bool)
    return pairs[right], pairs[~right]


def no_estimate(result: MatchResult) -> Finding | None:
    """No pose was estimated: the CAV stays where its pose before calibration puts it."""
    if result.estimated:
        return None
    return Finding("no_estimate", f"no pose was estimated: {len(result.pairs)} pair(s) matched, 2 are needed; the "
                                  f"CAV stays where its pose before calibration puts it", "no pose was estimated")


def nothing_paired(result: MatchResult) -> Finding | None:
    """A pose with no pair behind it: the pose before calibration (method *none*)."""
    if not result.estimated or len(result.pairs):
        return None
    return Finding("nothing_paired", "nothing was paired: the pose is the one before calibration, off by the "
                                     "localization error", "nothing was paired")


def noise_limited(metrics: TrialMetrics, oracle: TrialMetrics) -> Finding | None:
    """Least squares on the true pairs fails too, or comes within ``NEAR`` of the limit, on an error
    the frame fails on: the noise alone costs about as much as the answer does."""
    if not oracle.estimated:
        return None
    near = [f"{getattr(oracle, name):.2f}{unit}" for name, unit in (("rre", "°"), ("rte", " m"))
            if getattr(metrics, name) >= LIMIT and getattr(oracle, name) >= NEAR * LIMIT]
    if not near:
        return None
    off = " / ".join(near)
    return Finding("noise", f"least squares on the true pairs is off by {off} too: the noise, not the matching",
                   f"the noise: least squares on the true pairs is off by {off} too")


def wrong_pairs(result: MatchResult, trial: Trial) -> Finding | None:
    """The answer holds wrong pairs; when least squares on its right pairs alone succeeds, they are why."""
    right, wrong = split_pairs(result, trial)
    if not len(wrong):
        return None
    names = ", ".join(pair_name(trial, p) for p in wrong[:NAMED]) + \
        (f" and {len(wrong) - NAMED} more" if len(wrong) > NAMED else "")
    if not len(right):
        return Finding("wrong_pairs", f"every one of its {len(wrong)} pairs is wrong ({names})",
                       f"every one of its {len(wrong)} pairs is wrong")
    short = f"{len(wrong)} of its {len(right) + len(wrong)} pairs {'is' if len(wrong) == 1 else 'are'} wrong"
    head = f"{short} ({names})"
    if len(right) < 2:
        return Finding("wrong_pairs", f"{head}: one right pair alone fits no pose", short)
    alone = least_squares_on(trial, right)
    if is_success(alone):
        return Finding("wrong_pairs", f"{head}: least squares on its {len(right)} right pairs alone is off by only "
                                      f"{errors(alone)}", short)
    return Finding("wrong_pairs", head, short)


def few_right_pairs(result: MatchResult, trial: Trial, oracle: TrialMetrics) -> Finding | None:
    """The answer's right pairs are too few (or too close together) for the noise: least squares on
    them fails where least squares on every true pair succeeds."""
    right, _ = split_pairs(result, trial)
    if len(right) < 2 or not is_success(oracle):
        return None
    alone = least_squares_on(trial, right)
    if is_success(alone):
        return None
    xy = trial.ego_boxes[right[:, 0], :2]
    spread = float(np.max(np.linalg.norm(xy[:, None] - xy[None], axis=2)))
    close = f", all within {spread:.0f} m of each other" if spread < CLOSE_M else ""
    return Finding("few_right_pairs", f"the pose rests on {len(right)} right pairs of the {len(trial.gt_pairs)} "
                                      f"co-visible{close}: least squares on them is off by {errors(alone)}, on all "
                                      f"{len(trial.gt_pairs)} true pairs by {errors(oracle)}",
                   f"its {len(right)} right pairs are too few for the noise")


def not_the_fit(result: MatchResult, trial: Trial) -> Finding | None:
    """Every pair of the answer is right and least squares on them succeeds, yet the pose is off: the
    pose came from elsewhere than a fit of these pairs (a robust fit's weights, a track's prediction)."""
    right, wrong = split_pairs(result, trial)
    if len(wrong) or len(right) < 2:
        return None
    alone = least_squares_on(trial, right)
    if not is_success(alone):
        return None
    return Finding("not_the_fit", f"its {len(right)} pairs are all right and least squares on them is off by only "
                                  f"{errors(alone)}: the pose shown is not their fit",
                   "its pose is not the fit of its right pairs")


def track_answered(result: MatchResult, trial: Trial, metrics: TrialMetrics) -> Finding | None:
    """A method over time failed with its track's answer: its prediction, where the frame gave it no
    measurement or it set the frame's measurement aside; or pooled off the frame's own measurement,
    which succeeds (``accepted``). None where the answer is the frame's own, or was pooled from a
    measurement that fails too (the frame's own findings say why)."""
    note = getattr(result, "track", None)
    if note is None:
        return None
    if note.event == "no measurement":
        return Finding("track", f"this frame gave the track no measurement of its own (CBM paired fewer than 3 "
                                f"objects): the answer is the track's prediction from the other frames, off by "
                                f"{errors(metrics)}", "the answer is the track's prediction: this frame gave it "
                                                      "no measurement")
    if note.measured is None or np.allclose(note.measured, result.transform):
        return None
    measured = evaluate(dataclasses.replace(result, transform=note.measured), trial)
    own, right = errors(measured), is_success(measured)
    if note.event == "accepted":
        return None if not right else Finding(
            "track", f"this frame's own measurement is off by only {own}; pooled with other frames by the track, "
                     f"the answer is off by {errors(metrics)}: the other frames pulled it away",
            f"the frames pooled with it pulled it off this frame's own measurement ({own})")
    only = "only " if right else ""
    return Finding("track", f"the track set aside this frame's own measurement, off by {only}{own} ({note.event}): "
                            f"the answer is its prediction from the other frames, off by {errors(metrics)}",
                   f"the track set aside this frame's own measurement ({own}) for its prediction")


def per_frame_succeeds(metrics: TrialMetrics, trial: Trial, alone: MatchResult | None) -> Finding | None:
    """A method over time failed on a frame that per-frame CBM (``alone``, its result) gets right on its
    own: the other frames made it worse (a track's prediction guided the matching, or its answer, away)."""
    if alone is None or not is_success(alone := evaluate(alone, trial)):
        return None
    return Finding("over_time", f"per-frame CBM on this frame alone is off by only {errors(alone)}: over time, "
                                f"the other frames led the answer to {errors(metrics)}",
                   f"per-frame CBM alone gets this frame right ({errors(alone)})")


def diagnose_failure(result: MatchResult, trial: Trial, metrics: TrialMetrics, oracle: TrialMetrics,
                     explanation: Explanation | None = None, alone: MatchResult | None = None) -> list[Finding]:
    """Every finding on a frame: CBM's rules when the run is explained (``diagnose``), then those any
    method's failure answers to (none for a frame that succeeded), and for a method over time those
    that compare with the frame's own measurement and with per-frame CBM's result ``alone``. A
    failed frame always has one."""
    findings = diagnose(result, trial, explanation) if explanation is not None else []
    if is_success(metrics):
        return findings
    more = [no_estimate(result), nothing_paired(result), noise_limited(metrics, oracle), wrong_pairs(result, trial),
            few_right_pairs(result, trial, oracle), not_the_fit(result, trial), track_answered(result, trial, metrics),
            per_frame_succeeds(metrics, trial, alone)]
    known = {f.code for f in findings}
    findings += [f for f in more if f is not None and not (f.code == "no_estimate" and "single_pair" in known)]
    if not findings:
        findings.append(Finding("unexplained", f"the pose is off by {errors(metrics)}; least squares on the true "
                                               f"pairs reaches {errors(oracle)}", "no rule found why"))
    return findings
