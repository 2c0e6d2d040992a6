"""The paper's method step by step on one outcome, as plain data: each ``Step`` has a title with
its equation numbers, a few sentences with the frame's own numbers, and what the scene shows (line
sets, meshes, labels, where the CAV's boxes stand and, where motion explains, where they glide to).
No viser here: ``app.walkthrough.panel`` copies a step into scene nodes."""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from cbm import se2

from ..scene import planes
from ..scene.colours import CAV_BOXES, EGO_BOXES, GHOST, MISSED, RIGHT, WRONG
from ..scene.drawing import Lines, Mesh
from ..scene.inspector import BAND, REGION
from ..scene.text import number
from ..scene.words import plural
from ..session.explorer import Outcome, classified_pairs
from . import shapes
from .facts import Facts, gather, pose_error

ADDED = (150, 60, 200)
"""Pairs the guided re-association added (step 7b)."""
FOCUSED = range(1, 6)
"""The steps about the followed pair (context vectors to the anchor's matches)."""
MAX_LABELS = 20
"""Most per-pair labels (votes, weights) a step shows."""
SPAN = (24.0, 160.0)
"""Fewest and most metres across that a camera looking at a step's object shows."""
Label = tuple[str, tuple[float, float, float]]


@dataclass(frozen=True)
class Step:
    """One step of the walkthrough: its text and what the scene shows."""

    key: str
    title: str
    text: str
    lines: dict[str, Lines]
    meshes: dict[str, Mesh]
    labels: dict[str, Label]
    cav_pose: np.ndarray
    """(3, 3) where the nodes of the CAV's boxes and vehicle (``meshes["cav_boxes"]``,
    ``meshes["cav_vehicle"]``, CAV frame) stand."""
    motion: tuple[np.ndarray, np.ndarray] | None = field(default=None)
    """(from, to) poses the CAV's boxes glide between when the animation plays; None: no motion."""
    focus: tuple[float, float] | None = None
    """Where the followed ego object stands, in the steps about its pair (a camera may look there)."""
    span: float = SPAN[0]
    """Metres across around ``focus`` that hold what the step draws about the pair (a camera
    looking at the object fits them)."""


NAMES = (("pose", "The wrong pose", "eq. 4"),
         ("context", "Context vectors", "eq. 6-7"),
         ("local", "Local matching", "eq. 8"),
         ("candidates", "Candidate set", "eq. 9"),
         ("consensus", "Global consensus", "eq. 10-11"),
         ("anchor", "The anchor and its matches", "eq. 12-14"),
         ("estimate", "Robust estimate", "eq. 15-16"),
         ("reassociate", "Guided re-association", "step 7b, beyond the paper"),
         ("result", "Result", "metrics"),
         ("over_time", "Over time", "step 8, beyond the paper"))
"""Every step's key, name and equations; the last only for a method over time (``count``)."""


def count(facts: Facts) -> int:
    """The steps of ``facts``' walkthrough: the nine of one frame, and step 8 for a method over time."""
    return len(NAMES) if facts.outcome.result.track is not None else len(NAMES) - 1


def title(k: int, total: int = len(NAMES) - 1) -> str:
    """'Step k/total · <name> (eq. …)' of step ``k`` (0-based)."""
    _, name, eq = NAMES[k]
    return f"Step {k + 1}/{total} · {name} ({eq})"


def _step(facts: Facts, k: int, text: str, lines: dict[str, Lines], labels: dict[str, Label] | None = None,
          pose: np.ndarray | None = None, motion: tuple[np.ndarray, np.ndarray] | None = None,
          span: float | None = None) -> Step:
    trial = facts.trial
    pose = facts.result.init if pose is None else pose
    meshes = {"ego_boxes": shapes.ego_mesh(trial.ego_boxes), "cav_boxes": shapes.cav_mesh(trial.cav_boxes),
              **shapes.agent_meshes()}
    focus = None if facts.pair is None or k not in FOCUSED else tuple(map(float, facts.ego_xy[facts.pair[0]]))
    if focus is not None and span is None:
        span = reach(focus, lines)
    labels = {**shapes.agent_labels(pose), **(labels or {})}
    return Step(NAMES[k][0], title(k, count(facts)), text, lines, meshes, labels, pose, motion, focus,
                _clipped(span or SPAN[0]))



def reach(focus: tuple[float, float], lines: dict[str, Lines]) -> float:
    """Metres across a square centred on ``focus`` that holds every line drawn, and a margin."""
    ends = [line.segments[..., :2].reshape(-1, 2) for line in lines.values() if len(line.segments)]
    if not ends:
        return SPAN[0]
    return 2.0 * float(np.abs(np.concatenate(ends) - np.asarray(focus)).max()) + 6.0


def _clipped(span: float) -> float:
    return float(min(max(span, SPAN[0]), SPAN[1]))


def _at(xy: np.ndarray, z: float = 3.0) -> tuple[float, float, float]:
    return float(xy[0]), float(xy[1]), z


def _names(facts: Facts) -> dict[str, Label]:
    """Labels of the followed pair's two objects (the CAV's where ``init`` puts it)."""
    if facts.pair is None:
        return {}
    i, j = facts.pair
    return {"ego_object": (facts.ego_name(i), _at(facts.ego_xy[i])),
            "cav_object": (facts.cav_name(j), _at(facts.cav_xy[j], 3.6))}


def _no_pair(facts: Facts, k: int) -> Step:
    return _step(facts, k, "Neither agent's list holds an object here, so there is no pair to follow; "
                           "step to another frame.", {})


def wrong_pose(facts: Facts) -> Step:
    """Step 1: the CAV's boxes where the wrong pose puts them, the truth outlined."""
    trial, result = facts.trial, facts.result
    metres, degrees = pose_error(result.init, trial.T_true)
    truth = se2.apply_boxes(trial.T_true, trial.cav_boxes)
    text = (f"The ego sees {plural(len(trial.ego_boxes), 'object')} (blue), the CAV {len(trial.cav_boxes)} (orange). "
            f"Its pose `init` is off by {metres:.2f} m and {degrees:.2f}° (eq. 4), so its boxes land beside "
            f"their true places (grey outlines). Play the animation to watch CBM's estimate move them back.")
    return _step(facts, 0, text, {"truth": Lines(shapes.outlines(truth), GHOST, 1.5)},
                 motion=(result.init, result.transform))


def context_vectors(facts: Facts) -> Step:
    """Step 2: the followed objects' vectors to their neighbours (eq. 6-7)."""
    if facts.pair is None:
        return _no_pair(facts, 1)
    i, j = facts.pair
    ego_members, _ = facts.explanation.context("ego", i)
    cav_members, _ = facts.explanation.context("cav", j)
    same = ("the same object" if (i, j) in facts.truth() else
            "two different objects (an anchor need not be a true pair: its set's other pairs count)")
    text = (f"The pair followed, {'the winning anchor' if facts.is_anchor() else 'a true pair'}, is {same}. "
            f"CBM describes {facts.ego_name(i)} by the vectors to its {plural(len(ego_members), 'neighbour')} "
            f"(blue), z = R(θ)ᵀ(p′ − p), in its own frame (eq. 6-7); {facts.cav_name(j)} likewise by its "
            f"{len(cav_members)} (orange). The vectors do not change with the agents' poses, so the two lists "
            f"can be compared although `init` is wrong.")
    lines = {"ego_vectors": Lines(shapes.rays(facts.ego_xy[i], facts.ego_xy[ego_members]), EGO_BOXES, 2.0),
             "cav_vectors": Lines(shapes.rays(facts.cav_xy[j], facts.cav_xy[cav_members]), CAV_BOXES, 2.0)}
    return _step(facts, 1, text, lines, _names(facts))


def local_matching(facts: Facts) -> Step:
    """Step 3: the CAV object's vectors turned into the ego object's frame, one of them with its
    sigma1 wedge and sigma2 diamond (eq. 8), and the vectors that agree."""
    if facts.pair is None:
        return _no_pair(facts, 2)
    i, j = facts.pair
    explanation, params, detail = facts.explanation, facts.params, facts.detail
    ego_members, ego_vectors = explanation.context("ego", i)
    cav_members, cav_vectors = explanation.context("cav", j, against=i)
    origin, heading = facts.ego_xy[i], float(explanation.sets.ego_heading[i])
    placed = lambda segments, z=planes.LINES: shapes.to_scene(segments, origin, heading, z)  # noqa: E731
    others = detail.candidates[(detail.candidates[:, 0] != i) | (detail.candidates[:, 1] != j)]
    ego_hit, cav_hit = np.isin(ego_members, others[:, 0]), np.isin(cav_members, others[:, 1])
    lines = {"ego_vectors": Lines(placed(shapes.local_vectors(ego_vectors)), EGO_BOXES, 1.5),
             "cav_vectors": Lines(placed(shapes.local_vectors(cav_vectors)), CAV_BOXES, 1.5),
             "matched": Lines(placed(shapes.local_vectors(np.concatenate([ego_vectors[ego_hit], cav_vectors[cav_hit]])),
                                     planes.HIGHLIGHT), RIGHT, 4.0)}
    labels = {"ego_object": (f"{facts.ego_name(i)} ⇄ {facts.cav_name(j)}", _at(origin))}
    shown, span = "", None
    if len(others):
        shown_pair = others[_showcase(others, cav_members, cav_vectors, params.sigma2)]
        cav_row = int(np.flatnonzero(cav_members == shown_pair[1])[0])
        wedge, diamond = shapes.tolerance_region(cav_vectors[cav_row], params.sigma1, params.sigma2)
        lines["wedge"], lines["diamond"] = Lines(placed(wedge), BAND, 1.5), Lines(placed(diamond), REGION, 2.5)
        tip = placed(shapes.local_vectors(cav_vectors[cav_row:cav_row + 1]))[0, 1]
        labels["region"] = (f"{facts.cav_name(int(shown_pair[1]))} ⇄ {facts.ego_name(int(shown_pair[0]))}: "
                            f"σ1 {params.sigma1:g}° · σ2 {params.sigma2:g} m", _at(tip, 3.4))
        span = 2.0 * (float(np.linalg.norm(cav_vectors[cav_row])) + params.sigma2) + 8.0
        shown = (f" The grey wedge (σ1 = {params.sigma1:g}°) and the purple diamond (σ2 = {params.sigma2:g} m, "
                 f"L1) surround the vector to {facts.cav_name(int(shown_pair[1]))}; the vector to "
                 f"{facts.ego_name(int(shown_pair[0]))} lies in both, so they match.")
    text = (f"The CAV object's {plural(len(cav_vectors), 'vector')} (orange) are laid over the ego object's "
            f"{len(ego_vectors)} (blue) in its frame; two vectors match when their angle is within σ1 and "
            f"their L1 distance within σ2 (eq. 8).{shown} |L_ij| = {len(detail.candidates)} "
            f"(the anchor pair included; green: the vectors that found a partner).")
    return _step(facts, 2, text, lines, labels, span=span)


def _tally(count: int, noun: str, colour: str) -> str:
    """``count`` of ``noun`` with the colour their lines are drawn in, or "no ``noun``" (nothing drawn)."""
    return f"{plural(count, noun)} ({colour})" if count else f"no {noun}"


def _showcase(pairs: np.ndarray, cav_members: np.ndarray, cav_vectors: np.ndarray, sigma2: float) -> int:
    """Row of the matched pair whose tolerance region is drawn: the nearest CAV neighbour at least
    3 sigma2 away (its wedge and diamond apart), else the nearest."""
    rows = np.searchsorted(cav_members, pairs[:, 1], sorter=np.argsort(cav_members))
    lengths = np.linalg.norm(cav_vectors[np.argsort(cav_members)[rows]], axis=1)
    far = np.where(lengths >= 3 * sigma2, lengths, np.inf)
    return int(np.argmin(far)) if np.isfinite(far).any() else int(np.argmin(lengths))


def candidate_set(facts: Facts) -> Step:
    """Step 4: the anchor's candidate set L_ij as pair lines, true pairs green (eq. 9)."""
    if facts.pair is None:
        return _no_pair(facts, 3)
    candidates, truth = facts.detail.candidates, facts.truth()
    true = np.array([tuple(p) in truth for p in candidates.tolist()], dtype=bool)
    segments = shapes.pair_segments(facts.ego_xy, facts.cav_xy, candidates)
    i, j = facts.pair
    text = (f"Every object pair whose vectors matched joins the anchor's candidate set L_ij (eq. 9): "
            f"{plural(len(candidates), 'pair')} for the anchor ({facts.ego_name(i)}, {facts.cav_name(j)}), "
            f"{_tally(int(true.sum()), 'true pair', 'green')} and {_tally(int((~true).sum()), 'wrong pair', 'red')}. "
            + ("A set of fewer than two pairs is emptied." if len(candidates) == 0 else
               "A pair may still appear twice: an object is not yet matched one-to-one."))
    lines = {"true": Lines(segments[true], RIGHT, 3.0), "wrong": Lines(segments[~true], WRONG, 3.0),
             "anchor": _anchor_line(facts, 6.0)}
    return _step(facts, 3, text, lines, _names(facts))


def _anchor_line(facts: Facts, width: float) -> Lines:
    """The followed pair's line, over the other pairs' (``planes.HIGHLIGHT``)."""
    return Lines(shapes.pair_segments(facts.ego_xy, facts.cav_xy, [facts.pair], planes.HIGHLIGHT), CAV_BOXES, width)


def consensus(facts: Facts) -> Step:
    """Step 5: which candidates the voting sets kept and which they removed, with their votes (eq. 10-11)."""
    if facts.pair is None:
        return _no_pair(facts, 4)
    detail, params = facts.detail, facts.params
    segments = shapes.pair_segments(facts.ego_xy, facts.cav_xy, detail.candidates)
    kept = detail.kept_by_consensus
    labels = {f"votes_{n}": (f"{votes} vote{'s' if votes != 1 else ''}", tuple(map(float, at)))
              for n, (votes, at) in enumerate(zip(detail.votes.tolist(), shapes.midpoints(segments)))
              if n < MAX_LABELS}
    if not params.consensus:
        how = "Consensus is switched off (the paper's ablation): every candidate stays."
    else:
        rule = ("every candidate needs a vote from another member" if params.consensus_rule == "paper" else
                "a candidate that shares its ego or CAV object with another needs a vote from a lone member")
        how = (f"Each candidate votes for the members it sees within σ3 = {params.sigma3:g} m (as the authors' "
               f"released code; the paper's eq. 10 votes with the candidate sets themselves); under the "
               f"{params.consensus_rule} rule {rule} (eq. 10-11).")
    text = (f"{how} Of {plural(len(kept), 'candidate')}, it keeps {_tally(int(kept.sum()), 'candidate', 'green')} "
            f"and removes {_tally(int((~kept).sum()), 'candidate', 'red')}; the labels give each candidate's votes.")
    lines = {"kept": Lines(segments[kept], RIGHT, 3.0), "removed": Lines(segments[~kept], WRONG, 3.0)}
    return _step(facts, 4, text, lines, labels)


def anchor(facts: Facts) -> Step:
    """Step 6: the one-to-one rule, the anchor's score and the winner (eq. 12-14)."""
    if facts.pair is None:
        return _no_pair(facts, 5)
    detail, result, params = facts.detail, facts.result, facts.params
    survivors = detail.candidates[detail.kept_by_consensus]
    final = {tuple(p) for p in detail.final.tolist()}
    dropped = np.array([p for p in survivors.tolist() if tuple(p) not in final], dtype=int).reshape(-1, 2)
    i, j = facts.pair
    if facts.is_anchor():
        verdict = (f"It is the largest set of all anchors (eq. 13-14): the anchor ({facts.ego_name(i)}, "
                   f"{facts.cav_name(j)}) wins with {plural(result.consensus_count, 'pair')} against "
                   f"{result.runner_up_count} for the strongest rival (margin {result.margin}).")
    else:
        verdict = "No anchor won on this frame, so this true pair is shown instead; CBM matched nothing."
    text = (f"Pairs that share an object with another are dropped (eq. 12, grey): {len(detail.final)} of "
            f"{len(survivors)} remain, on average {number(detail.mean_distance, ' m', 1)} apart under `init` "
            f"(limit {params.distance_limit:g} m{', rejected' if detail.rejected else ''}). {verdict}")
    lines = {"final": Lines(shapes.pair_segments(facts.ego_xy, facts.cav_xy, detail.final), RIGHT, 3.5),
             "dropped": Lines(shapes.pair_segments(facts.ego_xy, facts.cav_xy, dropped), MISSED, 1.5),
             "anchor": _anchor_line(facts, 7.0)}
    return _step(facts, 5, text, lines, _names(facts))


def robust_estimate(facts: Facts) -> Step:
    """Step 7: CBM's pairs with their Welsch weights as line widths, the fitted pose outlined (eq. 15-16)."""
    pairs, fit = facts.own_pairs, facts.fit
    if fit is None:
        return _step(facts, 6, f"CBM matched {plural(len(pairs), 'pair')}: at least two are needed for a pose, so "
                               f"the CAV stays where `init` put it.", {})
    segments = shapes.pair_segments(facts.ego_xy, facts.cav_xy, pairs)
    lines = shapes.weight_lines(segments, fit.weights, RIGHT)
    lines["estimate"] = Lines(shapes.outlines(se2.apply_boxes(facts.fit_pose, facts.trial.cav_boxes)), CAV_BOXES, 1.5)
    labels = {f"weight_{n}": (f"w {w:.2f}", tuple(map(float, at)))
              for n, (w, at) in enumerate(zip(fit.weights.tolist(), shapes.midpoints(segments))) if n < MAX_LABELS}
    weighting = (f"Welsch's ψ with ν = {fit.scale:.2f} m, read from the residuals (σ = {fit.sigma:.2f} m): "
                 f"{int((fit.weights < 0.5).sum())} of {plural(len(pairs), 'pair')} weigh under 0.5"
                 if np.isfinite(fit.scale) else "least squares: every pair weighs 1")
    text = (f"The correction minimises Σ ψ(‖p_i − (R p_j + t)‖) over CBM's {plural(len(pairs), 'pair')} "
            f"(eq. 15), {weighting}; line width shows each pair's weight. {_correction_words(facts)} "
            f"Orange outlines: the boxes where it puts them; play to see it.")
    return _step(facts, 6, text, lines, labels, motion=(facts.result.init, facts.fit_pose))


def _correction_words(facts: Facts) -> str:
    """What the correction of eq. 16 does, and why its shift is not the CAV's error: it turns about
    the ego's origin, which moves the CAV too, so the CAV itself moves by another distance."""
    correction = facts.fit.transform
    shift = float(np.linalg.norm(se2.translation_of(correction)))
    turn = float(np.degrees(se2.yaw_of(correction)))
    away = float(np.linalg.norm(se2.translation_of(facts.result.init)))
    carried = 2.0 * away * abs(np.sin(np.radians(turn) / 2.0))
    moved = float(np.linalg.norm(se2.translation_of(facts.fit_pose) - se2.translation_of(facts.result.init)))
    off = pose_error(facts.result.init, facts.trial.T_true)[0]
    return (f"The correction (eq. 16) turns the CAV's boxes by {abs(turn):.2f}° about the ego's origin and shifts "
            f"them by {shift:.2f} m. Turning about the ego's origin also carries the CAV, {away:.1f} m from it, "
            f"{carried:.2f} m sideways, and the shift makes up for that too: the CAV itself moves by {moved:.2f} m, "
            f"back across the {off:.2f} m its pose was off.")


def reassociation(facts: Facts) -> Step:
    """Step 8: the pairs the guided re-association added (purple) and dropped (grey), under the estimate."""
    result, params = facts.result, facts.params
    pose, own = facts.fit_pose, facts.own_pairs
    moved = se2.apply_boxes(pose, facts.trial.cav_boxes)[:, :2]
    mine, final = {tuple(p) for p in own.tolist()}, {tuple(p) for p in result.pairs.tolist()}
    added = np.array(sorted(final - mine), dtype=int).reshape(-1, 2)
    dropped = np.array(sorted(mine - final), dtype=int).reshape(-1, 2)
    kept = np.array(sorted(mine & final), dtype=int).reshape(-1, 2)
    lines = {"kept": Lines(shapes.pair_segments(facts.ego_xy, moved, kept), RIGHT, 2.0),
             "added": Lines(shapes.pair_segments(facts.ego_xy, moved, added), ADDED, 5.0),
             "added_boxes": Lines(shapes.outlines(facts.trial.ego_boxes[added[:, 0]], planes.MARKS), ADDED, 3.0),
             "dropped": Lines(shapes.pair_segments(facts.ego_xy, moved, dropped), MISSED, 2.0)}
    if not params.refine:
        text = ("The guided re-association is switched off (Method tab, *guided re-association*): CBM's own pairs "
                "and pose stand, as in the paper.")
    elif facts.fit is None:
        text = "There is no estimate to start the re-association from, so nothing is added."
    else:
        text = (f"Beyond the paper: under the estimate, all boxes are paired one-to-one "
                f"within {params.refine_gate:g} σ (σ = {facts.fit.sigma:.2f} m) and the pose is refitted. "
                f"It added {_tally(len(added), 'pair', 'purple')} and dropped {_tally(len(dropped), 'pair', 'grey')}: "
                f"{plural(len(result.pairs), 'pair')} now against CBM's {len(own)}.")
    return _step(facts, 7, text, lines, pose=pose)


def outcome_step(facts: Facts) -> Step:
    """Step 9: the CAV's boxes at the final pose, the truth outlined, the pairs and the metrics."""
    trial, result, m = facts.trial, facts.result, facts.metrics
    moved = se2.apply_boxes(result.transform, trial.cav_boxes)
    right, wrong, _ = classified_pairs(result.pairs, trial.gt_pairs)
    before = pose_error(result.init, trial.T_true)
    text = (f"{plural(m.n_matched, 'pair')} matched, {m.n_correct} right, of {plural(m.n_true, 'co-visible object')}: "
            f"precision "
            f"{number(m.precision)}, recall {number(m.recall)}. The pose is off by {number(m.rte, ' m')} and "
            f"{number(m.rre, '°')} (RTE, RRE), against {before[0]:.2f} m and {before[1]:.2f}° before; "
            f"grey outlines: where the CAV's boxes truly are.")
    lines = {"truth": Lines(shapes.outlines(se2.apply_boxes(trial.T_true, trial.cav_boxes)), GHOST, 1.5),
             "right": Lines(shapes.pair_segments(facts.ego_xy, moved[:, :2], right), RIGHT, 3.0),
             "wrong": Lines(shapes.pair_segments(facts.ego_xy, moved[:, :2], wrong), WRONG, 3.0)}
    return _step(facts, 8, text, lines, pose=result.transform, motion=(result.init, result.transform))


def over_time(facts: Facts) -> Step:
    """Step 10 (a method over time): where the track predicted the CAV's boxes (grey), where this
    frame's own CBM answer put them (purple), and the answer (the boxes), the truth outlined."""
    trial, note = facts.trial, facts.outcome.result.track
    lines = {"truth": Lines(shapes.outlines(se2.apply_boxes(trial.T_true, trial.cav_boxes)), GHOST, 1.5)}
    said = []
    for key, pose, colour, words in (("predicted", note.predicted, MISSED, "the track predicted (grey)"),
                                     ("measured", note.measured, ADDED, "this frame's own CBM answer (purple)")):
        if pose is not None:
            lines[key] = Lines(shapes.outlines(se2.apply_boxes(pose, trial.cav_boxes), planes.MARKS), colour, 2.5)
            said.append(f"{words} is off by {_errors(pose, trial.T_true)}")
    if not said:
        said.append("there is no prediction yet and CBM found no answer of its own")
    text = (f"Beyond the paper (cbm/sequence.py): CBM over time follows the CAV's pose error from frame to frame. "
            f"Here {'; '.join(said)}; the answer ({note.event}) is off by {_errors(note.answer, trial.T_true)}"
            + (f", pooling {plural(note.pooled, 'frame')}." if note.pooled else "."))
    return _step(facts, 9, text, lines, pose=note.answer,
                 motion=None if note.predicted is None else (note.predicted, note.answer))


def _errors(pose: np.ndarray, truth: np.ndarray) -> str:
    metres, degrees = pose_error(pose, truth)
    return f"{metres:.2f} m and {degrees:.2f}°"


BUILDERS: tuple[Callable[[Facts], Step], ...] = (
    wrong_pose, context_vectors, local_matching, candidate_set, consensus, anchor, robust_estimate,
    reassociation, outcome_step, over_time)


def build(facts: Facts, k: int) -> Step:
    """Step ``k`` (0-based, below ``count(facts)``) of the walkthrough of ``facts``."""
    return BUILDERS[min(k, count(facts) - 1)](facts)


def walkthrough(outcome: Outcome) -> list[Step]:
    """Every step of ``outcome``'s walkthrough."""
    facts = gather(outcome)
    return [build(facts, k) for k in range(count(facts))]
