"""The Explore tab's texts: a sequence run's aggregate, a search's ranking, the worst frames."""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from cbm.methods import METHODS
from evaluation.diagnosis import Finding
from evaluation.metric_registry import SHARE, TRIAL_METRICS, run_metrics
from evaluation.search import all_tie

from ..scene.differences import Difference, change_lines, now_words
from ..scene.text import number
from ..scene.words import plural
from ..session.search import OBJECTIVE_LABELS, SearchResult
from ..session.sequence import SequenceRun


def sequence_markdown(run: SequenceRun) -> str:
    """The aggregate table shown after a run: every run metric (``evaluation.metric_registry``), the
    frames with an estimate and the late-fusion AP."""
    s = run.summary()
    state = "cancelled after" if run.cancelled else "over"
    head = (f"**{METHODS[run.settings.method].label}**, {state} {len(run.rows)} of {plural(run.n_frames, 'frame')} "
            f"(seed {run.settings.scenario.seed}, {run.settings.scenario.protocol} protocol)")
    if not s:
        return head + "\n\nNo frame was run."
    lines = [head, "", "| | |", "|---|---|",
             *(f"| {metric.label} | {metric.unit.shown(s[metric.key], '—', suffix=True)} |"
               for metric in run_metrics()),
             f"| frames with an estimate | {int(s['n_estimated'])} |",
             *(f"| late-fusion AP@{t:g} (BEV IoU) | {SHARE.shown(ap, '—', suffix=True)} |"
               for t, ap in run.fused_ap().items())]
    if run.skipped:
        lines.append(f"\nSkipped (no ego or CAV): frames {', '.join(map(str, run.skipped))}")
    return "\n".join(lines)


def search_markdown(result: SearchResult, top: int = 5) -> str:
    """The table of the best settings against the current ones, with how ties were broken."""
    objective = OBJECTIVE_LABELS[result.objective]
    over = f"{plural(len(result.frames), 'frame')} (seed {result.settings.scenario.seed})"
    lines = [f"**Best of {len(result.candidates)} settings** by {objective} over {over}", "", ties_words(result), "",
             "| | σ1 | σ2 | σ3 | limit | score | RTE | margin | success | P / R |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    rows = [(f"#{k + 1}", c) for k, c in enumerate(result.candidates[:top])] + [("current", result.current)]
    for name, c in rows:
        p = {**result.current.params, **c.params}
        s = c.summary
        lines.append(f"| {name} | {p['sigma1']:g} | {p['sigma2']:g} | {p['sigma3']:g} | {p['distance_limit']:g} "
                     f"| {number(c.score, digits=3)} | {number(s['rte_mean'], ' m')} "
                     f"| {number(s['margin_median'], '', 1)} | {number(100 * s['success_rate'], digits=1)} % "
                     f"| {number(s['precision'])} / {number(s['recall'])} |")
    return "\n".join(lines)


def ties_words(result: SearchResult) -> str:
    """How the ranking was decided: every setting tying on the objective is said first."""
    name = result.objective if result.objective != "f1" else "F1"
    if all_tie(result.candidates):
        return (f"*All {len(result.candidates)} tie on {name} ({number(result.candidates[0].score, digits=3)}): "
                "ranked by mean RTE (lower first), then median consensus margin (higher first).*")
    tied = sum(c.score == result.candidates[0].score for c in result.candidates) if result.candidates else 0
    if tied > 1:
        return f"*{tied} tie on {name} at the top: ranked by mean RTE, then median consensus margin.*"
    return "*Ties on the score are ranked by mean RTE, then median consensus margin.*"


def worst_markdown(rows: Sequence[dict[str, Any]], metric: str, findings: dict[int, list[Finding]]) -> str:
    """The worst-frames table: metrics and the diagnosis of each frame."""
    if not rows:
        return "Run the sequence first."
    shown = TRIAL_METRICS.values()
    lines = [f"**Worst frames by {metric}**", "",
             f"| frame | {' | '.join(m.label for m in shown)} | why it failed |", "|---|" + "---|" * (len(shown) + 1)]
    for row in rows:
        why = "; ".join(f.message for f in findings.get(row["frame"], [])) or "—"
        values = " | ".join(m.unit.shown(row.get(m.key, math.nan), "—", suffix=True) for m in shown)
        lines.append(f"| {row['frame']} | {values} | {why} |")
    return "\n".join(lines)


def stale_markdown(found: list[Difference]) -> str:
    """The mark above a run's outputs computed under other settings than the controls' (empty when
    they are the controls')."""
    if not found:
        return ""
    return (f"⚠ **Computed under other settings** than the controls': {now_words(found)}. *run all frames* "
            "again for the current ones.\n\n")


def jump_markdown(frame: int, found: list[Difference]) -> str:
    """What *jump there* would change, asked before it changes it."""
    return (f"The run was computed under other settings than the controls'. Frame {frame} as the run saw it "
            f"(the same noise draw) needs the run's settings; the jump sets:\n\n{change_lines(found)}\n\n"
            f"Keeping your settings shows frame {frame} under them instead.")
