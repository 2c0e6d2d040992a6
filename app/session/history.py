"""The per-frame results a tab has computed under its current settings: the timeline's rows.

A frame *fails* as the evaluation counts it (``evaluation.metrics.is_success``): no pose estimate, or
RTE >= 1 m, or RRE >= 1 deg. Rows come from the frames shown (``add``) and from sequence runs of
the same settings (``merge``); they are forgotten only when a setting other than the frame, the
CAV or the view changes.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from typing import Any, NamedTuple

from evaluation.metrics import TrialMetrics, evaluate, is_success

from .explorer import Outcome
from .settings import AUTO_CAV, Settings, ViewOptions

FAILED_MEANING = "failed = no pose estimate, or RTE ≥ 1 m or RRE ≥ 1° (the evaluation's success test)"


class Row(NamedTuple):
    """One frame's numbers on the timeline."""

    precision: float
    recall: float
    rte: float
    rre: float
    n_matched: int
    failed: bool
    alone_rte: float = math.nan
    """A method over time: per-frame CBM's RTE on the same frame (NaN otherwise)."""
    event: str = ""
    """A method over time: how its answer was reached (``cbm.result.TrackNote.event``)."""


MARKED_EVENTS = ("rejected", "re-acquired", "lost")
"""The events of a calibration over time the timeline marks."""


def row_of(metrics: TrialMetrics) -> Row:
    """The timeline row of one frame's metrics."""
    return Row(metrics.precision, metrics.recall, metrics.rte, metrics.rre, metrics.n_matched,
               not is_success(metrics))


def row_over_time(metrics: TrialMetrics, alone: TrialMetrics | None, event: str) -> Row:
    """The timeline row of a frame over time: its metrics, per-frame CBM's RTE (NaN while not
    computed yet) and the track's event."""
    return row_of(metrics)._replace(alone_rte=math.nan if alone is None else alone.rte, event=event)


def row_of_outcome(outcome: Outcome) -> Row:
    """The timeline row of a frame shown: with per-frame CBM's RTE and the event of a method over time."""
    if outcome.alone is None or outcome.result.track is None:
        return row_of(outcome.metrics)
    return row_over_time(outcome.metrics, evaluate(outcome.alone, outcome.trial), outcome.result.track.event)


def row_of_sweep(row: Mapping[str, Any]) -> Row:
    """The timeline row of one ``evaluation.sweep`` row (a sequence run's frame)."""
    def number(name: str) -> float:
        value = row.get(name)
        return math.nan if value is None else float(value)

    return Row(number("precision"), number("recall"), number("rte"), number("rre"), int(row.get("n_matched", 0)),
               not bool(row["success"]))


def settings_key(settings: Settings) -> Settings:
    """What a row depends on: the settings without the frame, the CAV and the view."""
    return dataclasses.replace(settings, frame=0, cav=AUTO_CAV, view=ViewOptions())


def step_to_failure(rows: Mapping[int, Row], frame: int, direction: int) -> int | None:
    """The nearest failed frame after (``direction`` > 0) or before ``frame`` among ``rows``."""
    failed = sorted(f for f, row in rows.items() if row.failed)
    ahead = [f for f in failed if f > frame] if direction > 0 else [f for f in reversed(failed) if f < frame]
    return ahead[0] if ahead else None


class FrameHistory:
    """Per-frame rows of the current settings (``settings_key``), by frame index."""

    def __init__(self) -> None:
        self.key: Settings | None = None
        self.rows: dict[int, Row] = {}

    def matches(self, settings: Settings) -> bool:
        """Whether ``settings`` would add to these rows rather than start new ones."""
        return settings_key(settings) == self.key

    def add(self, outcome: Outcome) -> None:
        """The row of a frame shown."""
        self.merge(outcome.settings, {outcome.frame_index: row_of_outcome(outcome)})

    def merge(self, settings: Settings, rows: Mapping[int, Row]) -> None:
        """Rows computed under ``settings``; other settings than the rows' so far start afresh."""
        if not self.matches(settings):
            self.key, self.rows = settings_key(settings), {}
        self.rows.update(rows)

    def over_time(self) -> bool:
        """Whether the rows are a method's over time (they carry per-frame CBM's RTE)."""
        return any(row.event for row in dict(self.rows).values())

    def failures(self) -> list[int]:
        """The failed frames among the rows (a sequence run may add rows meanwhile: read a copy)."""
        return sorted(f for f, row in dict(self.rows).items() if row.failed)


def sweep_rows(rows: Iterable[Mapping[str, Any]]) -> dict[int, Row]:
    """A sequence run's rows by frame."""
    return {int(row["frame"]): row_of_sweep(row) for row in rows}
