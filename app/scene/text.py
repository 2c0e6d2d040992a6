"""Text the app shows: numbers with units, and the metrics panel of one outcome."""
from __future__ import annotations

import math

import numpy as np

from cbm import MatchResult, se2
from cbm.methods import METHODS, ORACLE_WORDS, Method
from evaluation.clutter import is_false
from evaluation.metric_registry import TRIAL_METRICS
from evaluation.metrics import TrialMetrics, evaluate, is_success

from ..session.explorer import Outcome
from ..session.names import agent_name
from .cavs import per_cav_rows
from .confidence import verdict
from .seen import late_rows
from .words import margin_words, plural

VOTE_ROW = "consensus vote"
"""The row of the consensus margin (eq. 13): pairs of the winning anchor's set against the runner-up's,
a count, not a confidence (the evidence margin's row is)."""
ORACLE_ROW = f"{ORACLE_WORDS} (oracle)"
"""The row of what least squares on the true pairs reaches: a reference, not a bound (a robust fit can beat it)."""
LAID_OUT = ("precision", "recall", "ad", "rre", "rte", "margin")
"""The trial metrics the panel's own rows show (paired, beside the pose before calibration and the
oracle); every other metric of ``evaluation.metric_registry.TRIAL_METRICS`` gets a row of its own."""


def number(value: float, unit: str = "", digits: int = 2) -> str:
    """``value`` with ``digits`` decimals and ``unit``; a dash when it is undefined (None, NaN)."""
    return "—" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.{digits}f}{unit}"


def own_pairs(result: MatchResult) -> str:
    """How many of the pairs CBM found itself, when the re-association changed them."""
    own = result.context_pairs
    if own is None or np.array_equal(own, result.pairs):
        return ""
    return f"; CBM's own {len(own)}"


def thresholds(outcome: Outcome) -> list[str]:
    """The row naming CBM's thresholds behind the numbers shown (none for other methods)."""
    if METHODS[outcome.settings.method].params_key != "cbm":
        return []
    p = outcome.settings.cbm
    return [f"| thresholds | σ1 {p.sigma1:.1f}° · σ2 {p.sigma2:.2f} m · σ3 {p.sigma3:.2f} m |"]


def clutter_rows(outcome: Outcome) -> list[str]:
    """The rows of the scenario's clutter (none without): how many of each agent's boxes are false
    (counted among its objects, as the evaluation counts them) and the share of detections missed."""
    scenario, trial = outcome.settings.scenario, outcome.trial
    rows = []
    if scenario.false_rate > 0:
        counts = f"{int(is_false(trial.ego_ids).sum())} / {int(is_false(trial.cav_ids).sum())}"
        rows.append(f"| of them false boxes | {counts} (they match no object) |")
    if scenario.miss_rate > 0:
        rows.append(f"| missed detections | {scenario.miss_rate:.0%} of each agent's |")
    return rows


def findings_heading(outcome: Outcome) -> str:
    """``Why it failed`` above the diagnosis of a failed frame; ``Warnings`` when the frame succeeded
    (``evaluation.metrics.is_success``) and a rule still found something."""
    return "**Warnings** (the frame succeeded)" if is_success(outcome.metrics) else "**Why it failed**"


def time_row(method: Method) -> str:
    """The time row's name: the method's short name (its label before any explanation in brackets)
    and "time" ("time of this frame" for a method over time, which also computes earlier frames)."""
    if method.name == "none":
        return "time"
    short = method.label.split(" (")[0]
    return f"time of this frame ({short})" if method.over_time else f"{short} time"


def metrics_markdown(outcome: Outcome) -> str:
    """The metrics panel's text for one frame."""
    m, result, trial, limit = outcome.metrics, outcome.result, outcome.trial, outcome.limit
    init_rre = abs(math.degrees(se2.wrap_angle(se2.yaw_of(trial.init) - se2.yaw_of(trial.T_true))))
    init_rte = float(np.linalg.norm(se2.translation_of(trial.init) - se2.translation_of(trial.T_true)))
    method = METHODS[outcome.settings.method]
    ego = agent_name("ego", outcome.ego_id, code=True)
    cav = agent_name("CAV 1" if outcome.others else "CAV", outcome.cav_id, code=True)
    agents = f"{ego} · {cav} ({outcome.cav_note})"
    lines = [
        f"**Frame {outcome.frame_index}** · {agents}",
        *(["", "The table is CAV 1's (orange); every CAV has a row in the table after it."] if outcome.others else []),
        "",
        "| | |",
        "|---|---|",
        f"| objects (ego / CAV) | {m.n_ego} / {m.n_cav} |",
        *clutter_rows(outcome),
        *late_rows(outcome),
        f"| co-visible | {m.n_true} |",
        *thresholds(outcome),
        f"| matches | {m.n_matched} ({m.n_correct} right){own_pairs(result)} |",
        f"| precision / recall | {number(m.precision)} / {number(m.recall)} |",
        f"| AD | {number(m.ad, ' m')} |",
        f"| RRE / RTE | {number(m.rre, '°')} / {number(m.rte, ' m')} |",
        f"| before calibration | {number(init_rre, '°')} / {number(init_rte, ' m')} |",
        f"| {ORACLE_ROW} | {number(limit.rre, '°')} / {number(limit.rte, ' m')} |",
        *other_metric_rows(m),
    ]
    if outcome.voted:
        lines.append(f"| {VOTE_ROW} | {margin_words(result.consensus_count, result.runner_up_count)} |")
    lines.extend(confidence_rows(result, is_success(m), outcome.findings))
    lines.extend(over_time_rows(outcome))
    lines.append(f"| {time_row(method)} | {number(1000 * result.timings.get('total', float('nan')), ' ms', 1)} |")
    lines.extend(per_cav_rows(outcome))
    if not result.estimated:
        lines.append("")
        lines.append("No pose estimate: fewer than 2 pairs matched; the CAV stays where its pose before "
                     "calibration put it.")
    if outcome.findings:
        lines.append("")
        lines.append(findings_heading(outcome))
        lines.extend(f"- {f.message}" for f in outcome.findings)
    return "\n".join(lines)


def other_metric_rows(m: TrialMetrics) -> list[str]:
    """A row for each trial metric of the registry that the panel's own rows do not lay out."""
    return [f"| {metric.label} | {metric.unit.shown(metric.of(m), '—', suffix=True)} |"
            for key, metric in TRIAL_METRICS.items() if key not in LAID_OUT]


EVENT_WORDS = {
    "per frame": "this frame alone: the error has not been seen to persist, so this is per-frame CBM's answer",
    "started": "the error persists: a calibration over time started",
    "accepted": "this frame's own answer agreed with the track and joined it",
    "rejected": "this frame's own answer disagreed with the track and was set aside: the track's prediction stands",
    "no measurement": "CBM paired too few objects in this frame: the track's prediction stands",
    "weak measurement": "this frame's pairs explain it hardly better than a coincidence: set aside, the track's "
                        "prediction stands",
    "re-acquired": "the error jumped: the track moved onto this frame's answer",
    "sure, not yet confirmed": "CBM was sure of this frame's answer, which the settled track rejected: it is the "
                               "answer, and the track moves onto it only if the next frame agrees",
    "lost": "lost: no frame agreed with the track for too long; per-frame CBM's answer, without confidence",
}
"""How a method over time reached a frame's answer, in words (``cbm.result.TrackNote.event``)."""


def over_time_rows(outcome: Outcome) -> list[str]:
    """A method over time: how the answer was reached, which frames it pools, and per-frame CBM's
    errors on the same frame; nothing for other methods."""
    note = outcome.result.track
    if note is None or outcome.alone is None:
        return []
    event = note.event
    words = EVENT_WORDS.get(event, f"started over ({event.removeprefix('reset: ')})")
    rows = [f"| over time | {words} |"]
    if outcome.pooled_from is not None:
        first, last = outcome.pooled_from, outcome.frame_index
        rows.append(f"| answer from | frames {first}–{last} ({plural(note.pooled, 'frame')} pooled) |")
    alone = evaluate(outcome.alone, outcome.trial)
    rows.append(f"| per-frame CBM (this frame) | {number(alone.rre, '°')} / {number(alone.rte, ' m')} |")
    return rows


def confidence_rows(result: object, success: bool, findings: list) -> list[str]:
    """CBM's confidence in its pose against the truth (step 7c, ``cbm.hypotheses``;
    ``confidence.verdict``), with a warning sign when it was not sure; nothing for methods that do
    not verify."""
    words = verdict(result, success, findings)
    if words is None:
        return []
    return [f"| confidence | {'⚠ ' if getattr(result, 'abstained', False) else ''}{words} |"]
