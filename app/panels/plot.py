"""The per-frame plots (uPlot): precision and recall on the left axis (0 to 1), RTE (and RRE) on
the right; the timeline adds the pinned baseline's series, the failed frames and the current one.

Two things of viser 1.1.1's uPlot shape the data sent (``timeline_data``):

- a chart created empty never draws the data sent later, so charts start with two rows of gaps;
- an x scale left to itself does not follow a single frame (one row at frame 7 is drawn on an axis
  from 0 to 1, off the chart: the plot looked empty after each settings change), so the timeline's
  rows always include the first and last frame of the sequence, fixing its x axis to the whole
  sequence. Gaps are NaN (viser sends float64 arrays, not uPlot's nulls): a line skips them.

viser sends no event for a click or the cursor on a uPlot chart (``GuiUplotHandle`` has no
callback and its client component registers none), so the frames are reached by the controls
under the chart instead.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import viser
from viser import uplot

from ..session.history import Row

SERIES = (uplot.Series(label="frame"),
          uplot.Series(label="precision", stroke="#1e9c3c", width=2, scale="y"),
          uplot.Series(label="recall", stroke="#3478f6", width=2, scale="y"),
          uplot.Series(label="RTE (m)", stroke="#e1261e", width=2, scale="m"),
          uplot.Series(label="RRE (°)", stroke="#9b59b6", width=2, scale="m"))
SCALES = {"x": uplot.Scale(time=False, auto=True), "y": uplot.Scale(auto=False, range=(-0.05, 1.0)),
          "m": uplot.Scale(auto=True)}
AXES = (uplot.Axis(), uplot.Axis(scale="y"), uplot.Axis(scale="m", side=1))
TIMELINE = (*SERIES[:4],
            uplot.Series(label="pinned P", stroke="#8fd19e", width=1.5, dash=(6.0, 4.0), scale="y"),
            uplot.Series(label="pinned R", stroke="#9cbcf9", width=1.5, dash=(6.0, 4.0), scale="y"),
            uplot.Series(label="pinned RTE", stroke="#f19a96", width=1.5, dash=(6.0, 4.0), scale="m"),
            uplot.Series(label="failed", stroke="#c0141e", width=0, scale="y",
                         points=uplot.Series_Points(show=True, size=8, fill="#c0141e", stroke="#c0141e")),
            uplot.Series(label="now", stroke="#222222", width=2, scale="y"))
"""frame; current precision, recall, RTE; pinned precision, recall, RTE; failed frames (red
dots on the x axis); the current frame (a vertical bar)."""


def _placeholder(n_series: int) -> tuple[np.ndarray, ...]:
    return (np.array([0.0, 1.0]), *(np.full(2, np.nan) for _ in range(n_series - 1)))


def add_frame_plot(gui: viser.GuiApi, title: str, with_rre: bool) -> viser.GuiUplotHandle:
    """A plot over frames, with RRE as a fifth series when ``with_rre``."""
    series = SERIES if with_rre else SERIES[:4]
    return gui.add_uplot(_placeholder(len(series)), series, title=title, aspect=2.0, scales=SCALES, axes=AXES)


def add_timeline(gui: viser.GuiApi) -> viser.GuiUplotHandle:
    """The timeline of the metrics area (``timeline_data`` fills it)."""
    return gui.add_uplot(_placeholder(len(TIMELINE)), TIMELINE, title="timeline", aspect=2.2, scales=SCALES,
                         axes=AXES, legend=uplot.Legend(live=False))


def timeline_data(rows: Mapping[int, Row], pinned: Mapping[int, Row], current: int,
                  n_frames: int) -> tuple[np.ndarray, ...]:
    """The timeline's arrays: a row per frame computed (current or pinned), the current frame twice
    (its bar goes from 0 to 1) and the sequence's first and last frames (they fix the x axis)."""
    frames = sorted({0, max(n_frames - 1, 0), current, *rows, *pinned})
    x = np.array(sorted([*frames, current]), dtype=float)
    nan = np.full(len(x), np.nan)

    def column(source: Mapping[int, Row], field: str) -> np.ndarray:
        return np.array([getattr(source[int(f)], field) if int(f) in source else np.nan for f in x], dtype=float)

    failed = np.array([0.0 if int(f) in rows and rows[int(f)].failed else np.nan for f in x])
    now = nan.copy()
    first = int(np.searchsorted(x, current))
    now[first], now[first + 1] = 0.0, 1.0
    return (x, column(rows, "precision"), column(rows, "recall"), column(rows, "rte"),
            column(pinned, "precision"), column(pinned, "recall"), column(pinned, "rte"), failed, now)
