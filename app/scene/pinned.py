"""What a pinned baseline adds to a drawing: its matches as faint lines and a comparison table."""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from cbm import se2
from evaluation.metric_registry import TRIAL_METRICS

from ..session.explorer import Outcome
from . import beside as pinned_beside
from . import geometry, planes
from .differences import differences, now_words
from .drawing import Drawing, Lines, no_lines
from .layouts import LAYOUTS
from .linecolours import as_shown
from .text import number

PINNED_LINES = (125, 80, 190)
"""The pinned run's match lines: a thin violet, lower than the current run's, apart from every
palette's colours (missed true pairs are grey and dashed or dotted)."""
PINNED_WORDS = "thin violet lines"


def pinned_segments(outcome: Outcome, pinned: Outcome) -> np.ndarray:
    """The pinned run's pairs from its ego boxes to its CAV boxes at its estimate, in every copy of
    the scene that shows the CAV at the estimate (the only copy when none does)."""
    trial, pairs = pinned.trial, pinned.result.pairs.reshape(-1, 2)
    if not len(pairs):
        return no_lines()
    ego_xy = trial.ego_boxes[pairs[:, 0], :2]
    cav_xy = se2.apply_boxes(pinned.result.transform, trial.cav_boxes)[pairs[:, 1], :2]
    panels = LAYOUTS[outcome.settings.view.layout].panels(outcome)
    shown = [p for p in panels if p.placement == "after"] or panels[:1]
    return np.concatenate([geometry.segments(ego_xy + p.offset, cav_xy + p.offset, planes.PINNED) for p in shown])


def _row(name: str, current: float, pinned: float, unit: str, digits: int) -> str:
    difference = current - pinned
    sign = "+" if difference > 0 else ""
    shown = "—" if math.isnan(difference) else f"{sign}{difference:.{digits}f}{unit}"
    return f"| {name} | {number(current, unit, digits)} | {number(pinned, unit, digits)} | {shown} |"


def comparison_markdown(outcome: Outcome, pinned: Outcome, beside: bool = False) -> str:
    """Current against pinned on this frame, and the difference (current − pinned); ``beside``: the
    pinned run is drawn beside the current one."""
    m, p = outcome.metrics, pinned.metrics
    found = differences(pinned.settings, outcome.settings)
    settings = f"Pinned under other settings: {now_words(found)}." if found else "Pinned under the same settings."
    drawn = "drawn beside, on the left" if beside else f"its matches: {PINNED_WORDS}"
    return "\n".join([
        f"**Pinned baseline** (same frame and CAV; {drawn})",
        "",
        f"*{settings}*",
        "",
        "| | current | pinned | current − pinned |",
        "|---|---|---|---|",
        *(_row(metric.label, metric.unit.scale * metric.of(m), metric.unit.scale * metric.of(p), metric.unit.suffix,
               metric.unit.digits) for metric in TRIAL_METRICS.values()),
        _row("matches", float(m.n_matched), float(p.n_matched), "", 0),
    ])


def with_baseline(picture: Drawing, outcome: Outcome, pinned: Outcome | None, beside: bool = False) -> Drawing:
    """``picture`` with the ``pinned`` node (empty unless a baseline is pinned and the view asks
    for its lines) and, when pinned, the comparison below the metrics; ``beside``: the pinned run in
    a copy of the scene of its own instead of its lines (``beside.with_pinned_beside``)."""
    show = pinned is not None and outcome.settings.view.pinned_lines and not beside
    meshes, copy = pinned_beside.empty()
    lines = {**picture.lines, **copy, "pinned": Lines(pinned_segments(outcome, pinned) if show else no_lines(),
                                                      as_shown(PINNED_LINES), 1.5)}
    text = picture.metrics_markdown if pinned is None else \
        f"{picture.metrics_markdown}\n\n{comparison_markdown(outcome, pinned, beside)}"
    drawn = dataclasses.replace(picture, meshes={**picture.meshes, **meshes}, lines=lines, metrics_markdown=text)
    return pinned_beside.with_pinned_beside(drawn, outcome, pinned) if pinned is not None and beside else drawn
