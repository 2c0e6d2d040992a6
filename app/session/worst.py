"""Worst frames of a sequence run, ranked by one metric, with the diagnosis of each.

A frame's diagnosis comes from recomputing it exactly as the tab would (``Explorer.compute`` with
the run's settings at that frame), so the list shows what a jump there puts on screen.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from evaluation.diagnosis import Finding
from evaluation.metric_registry import TRIAL_METRICS, TrialMetric

from .explorer import Explorer
from .sequence import SequenceRun

RANKINGS: dict[str, TrialMetric] = {metric.label: metric for metric in TRIAL_METRICS.values()}
"""Metrics the worst frames can be ranked by (``evaluation.metric_registry``), by label. An undefined
value (no estimate, no match, no anchor) ranks worst."""


def badness(row: dict[str, Any], metric: str) -> float:
    """How bad ``row`` is by ``metric``: larger is worse, undefined is worst (+inf)."""
    ranked = RANKINGS[metric]
    value = row[ranked.key]
    if value is None or math.isnan(float(value)):
        return math.inf
    return float(value) if ranked.better == "lower" else -float(value)


def rank(rows: Iterable[dict[str, Any]], metric: str, count: int = 10) -> list[dict[str, Any]]:
    """The ``count`` worst rows by ``metric``, worst first (ties: lower frame first)."""
    return sorted(rows, key=lambda row: (-badness(row, metric), row["frame"]))[:count]


def label(row: dict[str, Any], metric: str) -> str:
    """One entry of the jump list, e.g. ``frame 37 · RTE 4.21 m``."""
    ranked = RANKINGS[metric]
    return f"frame {row['frame']} · {metric} {ranked.unit.shown(row[ranked.key], '—', suffix=True)}"


def frame_of(entry: str) -> int:
    """The frame of a jump-list entry made by ``label``."""
    return int(entry.split(" · ")[0].removeprefix("frame "))


def diagnoses(explorer: Explorer, run: SequenceRun, frames: Sequence[int],
              check: Callable[[], None] = lambda: None) -> dict[int, list[Finding]]:
    """The diagnosis of each of ``frames`` under the run's settings (``check()`` between frames may
    raise to stop)."""
    found = {}
    for frame in frames:
        check()
        found[frame] = explorer.compute(dataclasses.replace(run.settings, frame=frame)).findings
    return found


def candidate_frames(run: SequenceRun, count: int = 10) -> list[int]:
    """Every frame that is among the ``count`` worst by some metric (each once, in frame order)."""
    return sorted({row["frame"] for metric in RANKINGS for row in rank(run.rows, metric, count)})
