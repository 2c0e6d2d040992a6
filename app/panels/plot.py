"""The per-frame plots (uPlot): each unit on an axis of its own, labelled with it. The timeline draws
precision and recall on the left axis (0 to 1) and RTE on the right (metres), the failed frames and
the current one, and the pinned baseline's series only while one is pinned; the Explore tab's run
draws precision and recall in one chart and the pose errors in another (RTE in metres on the left,
RRE in degrees on the right).

What viser 1.1.1's uPlot asks of the data sent:

- a chart created empty never draws the data sent later, so charts start with two rows of gaps;
- an x scale left to itself does not follow a single frame, so the timeline's rows always include
  the first and last frame of the sequence, fixing its x axis to the whole sequence;
- uPlot breaks a line only at a null and turns a NaN into an empty auto-ranged scale (the RTE axis
  vanished), while viser sends every array as float64: ``send`` puts the arrays on the wire as
  lists with null for NaN, and a row of nulls lies between two frames computed that are not
  neighbours, so no line bridges frames never computed.

viser sends no event for a click or the cursor on a uPlot chart (``GuiUplotHandle`` has no
callback and its client component registers none), so the frames are reached by the controls
under the chart instead.
"""
from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import numpy as np
import viser
from viser import uplot

from ..session.history import MARKED_EVENTS, Row

DOTS = uplot.Series_Points(show=True, size=4)
"""Every frame computed is a dot, so a frame computed alone shows too (a line needs two)."""
FRAME = uplot.Series(label="frame")
PRECISION = uplot.Series(label="precision", stroke="#1e9c3c", width=2, scale="y", points=DOTS)
RECALL = uplot.Series(label="recall", stroke="#3478f6", width=2, scale="y", points=DOTS)
RTE = uplot.Series(label="RTE (m)", stroke="#e8820c", width=2, scale="m", points=DOTS)
RRE = uplot.Series(label="RRE (°)", stroke="#9b59b6", width=2, scale="deg", points=DOTS)
FAILED = uplot.Series(label="failed", stroke="#c0141e", width=0, scale="y",
                      points=uplot.Series_Points(show=True, size=9, width=1.5, fill="#c0141e", stroke="#5c000a"))
NOW = uplot.Series(label="this frame", stroke="#222222", width=2, scale="y", points=uplot.Series_Points(show=False))
PINNED = (uplot.Series(label="pinned precision", stroke="#8fd19e", width=1.5, dash=(6.0, 4.0), scale="y"),
          uplot.Series(label="pinned recall", stroke="#9cbcf9", width=1.5, dash=(6.0, 4.0), scale="y"),
          uplot.Series(label="pinned RTE", stroke="#f5c28a", width=1.5, dash=(6.0, 4.0), scale="m"))
ALONE = uplot.Series(label="per-frame CBM RTE", stroke="#5a5a5a", width=1.5, dash=(3.0, 3.0), scale="m", points=DOTS)
TRACKED = uplot.Series(label="rejected / re-acquired / lost", stroke="#6a3d9a", width=0, scale="y",
                       points=uplot.Series_Points(show=True, size=8, width=1.5, fill="#ffffff", stroke="#6a3d9a"))
OVER_TIME = (ALONE, TRACKED)
"""A method over time: per-frame CBM's RTE on the same frames (grey, dashed), and the frames where
the calibration over time rejected a frame's answer, re-acquired or was lost (purple rings at the top)."""
TIMELINE = (FRAME, PRECISION, RECALL, RTE, FAILED, NOW)
"""frame; precision, recall, RTE; failed frames (large red dots ringed dark red on the x axis, apart
from RTE's small orange ones); the current frame (a vertical bar). While a baseline is pinned,
``PINNED`` follows (``timeline_series``)."""

FROM_ZERO = {"min": {"pad": 0.0, "soft": 0.0, "mode": 1}, "max": {"pad": 0.1, "soft": 1.0, "mode": 1}}
"""An error axis starts at 0 and reaches at least 1 (the success test's 1 m and 1°)."""
SCALES = {"x": uplot.Scale(time=False, auto=True), "y": uplot.Scale(auto=False, range=(-0.05, 1.0)),
          "m": uplot.Scale(auto=True, range=FROM_ZERO), "deg": uplot.Scale(auto=True, range=FROM_ZERO)}
LABEL = {"labelSize": 16, "labelFont": "12px sans-serif", "size": 36, "font": "11px sans-serif"}
X_AXIS = uplot.Axis(label="frame", **LABEL)
RATIO_AXIS = uplot.Axis(scale="y", label="precision, recall", **LABEL)
PADDING = (12, 4, 0, 0)
"""Room above the top tick's value (uPlot draws it centred on the chart's top edge)."""


def metres_axis(side: int) -> uplot.Axis:
    return uplot.Axis(scale="m", side=side, label="RTE (m)", stroke="#e8820c", grid=uplot.Axis_Grid(show=side == 3),
                      **LABEL)


def degrees_axis(side: int) -> uplot.Axis:
    return uplot.Axis(scale="deg", side=side, label="RRE (°)", stroke="#9b59b6", grid=uplot.Axis_Grid(show=False),
                      **LABEL)


def _placeholder(n_series: int) -> tuple[np.ndarray, ...]:
    return (np.array([0.0, 1.0]), *(np.full(2, np.nan) for _ in range(n_series - 1)))


def add_run_plots(gui: viser.GuiApi, ratios_title: str,
                  errors_title: str) -> tuple[viser.GuiUplotHandle, viser.GuiUplotHandle]:
    """Two plots over a run's frames: precision and recall (0 to 1), and the pose errors (RTE in
    metres on the left axis, RRE in degrees on the right)."""
    ratios = gui.add_uplot(_placeholder(3), (FRAME, PRECISION, RECALL), title=ratios_title,
                           aspect=2.0, scales=SCALES, axes=(X_AXIS, RATIO_AXIS), padding=PADDING)
    errors = gui.add_uplot(_placeholder(3), (FRAME, RTE, RRE), title=errors_title, aspect=2.0,
                           scales=SCALES, axes=(X_AXIS, metres_axis(3), degrees_axis(1)), padding=PADDING)
    return ratios, errors


def add_timeline(gui: viser.GuiApi) -> viser.GuiUplotHandle:
    """The timeline of the metrics area (``show_timeline`` fills it)."""
    return gui.add_uplot(_placeholder(len(TIMELINE)), TIMELINE, title="timeline", aspect=2.0, scales=SCALES,
                         axes=(X_AXIS, RATIO_AXIS, metres_axis(1)), legend=uplot.Legend(live=False),
                         padding=PADDING)


def timeline_series(pinned: bool, over_time: bool = False) -> tuple[uplot.Series, ...]:
    """The timeline's series: the pinned ones only while a baseline is pinned, those of a method
    over time only for one."""
    return (*TIMELINE, *(PINNED if pinned else ()), *(OVER_TIME if over_time else ()))


def frame_axis(frames: Iterable[int], n_frames: int, current: int | None = None) -> np.ndarray:
    """The x values of a plot over ``frames``: each frame, the sequence's first and last (they fix
    the x axis), ``current`` twice (its bar goes from 0 to 1), and half a frame after each frame
    whose next frame is missing (a row of nulls there breaks the lines)."""
    known = set(frames)
    ends = {0, max(n_frames - 1, 0)}
    gaps = {f + 0.5 for f in known if f + 1 not in known and f + 1 < n_frames}
    doubled = [] if current is None else [current]
    return np.array(sorted([*known, *ends, *gaps, *doubled]), dtype=float)


def column(x: np.ndarray, values: Mapping[int, float]) -> np.ndarray:
    """``values`` by frame at each x (NaN where a frame has none, and between frames)."""
    return np.array([values.get(int(f), math.nan) if f == int(f) else math.nan for f in x], dtype=float)


def timeline_data(rows: Mapping[int, Row], pinned: Mapping[int, Row], current: int, n_frames: int,
                  with_pinned: bool = False, over_time: bool = False) -> tuple[np.ndarray, ...]:
    """The timeline's arrays (``timeline_series(with_pinned, over_time)``): a row per frame computed
    (current or pinned) and the rows ``frame_axis`` adds."""
    x = frame_axis([*rows, *pinned], n_frames, current)

    def field(source: Mapping[int, Row], name: str) -> np.ndarray:
        return column(x, {f: getattr(row, name) for f, row in source.items()})

    failed = column(x, {f: 0.0 for f, row in rows.items() if row.failed})
    now = np.full(len(x), np.nan)
    first = int(np.searchsorted(x, current))
    now[first], now[first + 1] = 0.0, 1.0
    current_series = (field(rows, "precision"), field(rows, "recall"), field(rows, "rte"), failed, now)
    pinned_series = (field(pinned, "precision"), field(pinned, "recall"), field(pinned, "rte")) if with_pinned else ()
    tracked = column(x, {f: 1.0 for f, row in rows.items() if row.event in MARKED_EVENTS})
    over_time_series = (field(rows, "alone_rte"), tracked) if over_time else ()
    return (x, *current_series, *pinned_series, *over_time_series)


def run_data(frames: np.ndarray, columns: Iterable[np.ndarray], n_frames: int) -> tuple[np.ndarray, ...]:
    """A run's per-frame columns on ``frame_axis`` (gaps where frames were not run)."""
    x = frame_axis(frames.astype(int).tolist(), n_frames)
    return (x, *(column(x, dict(zip(frames.astype(int).tolist(), values.tolist()))) for values in columns))


def send(handle: viser.GuiUplotHandle, data: tuple[np.ndarray, ...],
         series: tuple[uplot.Series, ...] | None = None) -> None:
    """Show ``data`` (NaN where there is none) in ``handle``, with nulls on the wire (see above);
    ``series`` changes the chart's series too, in the order that never leaves a series without data."""
    changed = series is not None and tuple(series) != tuple(handle.series)
    arrays = tuple(np.asarray(a, dtype=float) for a in data)
    if not changed and _same(arrays, handle._impl.props.data):
        return
    if changed and len(series) < len(handle.series):
        handle.series = series
    handle._impl.props.data = arrays
    handle._queue_update("data", tuple([None if math.isnan(v) else v for v in a.tolist()] for a in data))
    if changed and tuple(series) != tuple(handle.series):
        handle.series = series


def _same(arrays: tuple[np.ndarray, ...], shown: tuple) -> bool:
    """Whether ``arrays`` are what ``send`` last put in the chart (NaN where it shows a gap): nothing
    to send. Never for a chart showing no value (its placeholder went out with NaN, not null)."""
    shown = tuple(np.asarray(b, dtype=float) for b in shown)
    return (len(arrays) == len(shown) and any(np.isfinite(b).any() for b in shown[1:])
            and all(a.shape == b.shape and np.array_equal(a, b, equal_nan=True) for a, b in zip(arrays, shown)))
