"""Every method on the whole sequence, side by side: a folder first in the Explore tab (``Panel.inside``).

Tick the methods and *run every method ticked*: each runs the tab's settings over every frame
(``app.session.compare``), with a progress bar and a stop button. Then one table of run metrics
(``evaluation.metric_registry``) with a row per method, one chart with a line per method (RTE per
frame), and under the chart a slider over the same frames: moving it shows that frame (viser 1.1.1
sends no clicks on a chart, ``plot``); the frames where method A fails and another succeeds are
marked on it and listed. Any two methods' pairs on the frame shown: A becomes the tab's method and B is pinned as its
baseline, drawn over A's (``overlaid``: its lines) or beside them (``side by side``: a scene of its own)."""
from __future__ import annotations

import dataclasses
import re
import threading
from typing import Protocol

import numpy as np
import viser
from viser import uplot
from viser._messages import GuiSliderMark

from cbm.methods import METHODS
from evaluation.metric_registry import SuccessRate

from ..scene.differences import Difference, differences
from ..session.background import Runner
from ..session.baseline import Baseline
from ..session.compare import COMPARABLE, TICKED, Comparison, columns, refusals, run_comparison
from ..session.history import FrameHistory, sweep_rows
from ..session.settings import Settings
from .actions import TabActions, assign, on_user
from .plot import DOTS, FRAME, LABEL, PADDING, X_AXIS, column, frame_axis, send
from .registry import Panel
from .reports import stale_markdown

COLOURS = {"cbm": "#1e9c3c", "cbm-time": "#6a3d9a", "cbm-smooth": "#b15928", "icp": "#e8820c", "ricp": "#8c564b",
           "vips": "#3478f6", "v2xregpp": "#d62790", "freealign": "#17becf", "oracle": "#555555"}
"""Each method's line on the chart."""
HOW = ("overlaid", "side by side")
NONE_YET = "(run first)"
WAITING = "*waiting for another tab's job…*"
INTRO = ("Runs the current settings with each method ticked on every frame: one table, one chart with a line "
         "per method. Frames already computed (a sequence run, CBM over time's frames) are taken, not run again.")
SUCCESS_LINE = uplot.Series(label="1 m (success)", stroke="#999999", width=1, dash=(4.0, 4.0), scale="m",
                            points=uplot.Series_Points(show=False))
SCALES = {"x": uplot.Scale(time=False, auto=True), "m": uplot.Scale(auto=True, distr=3, log=10)}
"""RTE on a log scale: a failure's metres and a success's centimetres on one chart."""
RTE_AXIS = uplot.Axis(scale="m", side=3, label="RTE (m, log scale)", **LABEL)
LISTED = 200
"""Frames the list of disagreements names at most."""


class CompareTab(TabActions, Protocol):
    """The browser tab as the comparison sees it."""

    history: FrameHistory
    baseline: Baseline

    def refresh(self, frame_camera: bool = False) -> None:
        """Recompute the frame on screen (the pinned baseline changed); ``frame_camera``: frame its result."""


def short(method: str) -> str:
    """A method's name without its explanation: "oracle" for "oracle (least squares on the true pairs)"."""
    return METHODS[method].label.split(" (")[0]


def by_short(name: str) -> str:
    return next(m for m in COMPARABLE if short(m) == name)


def stale(comparison: Comparison, current: Settings) -> list[Difference]:
    """How the settings a comparison ran under differ from ``current``, for any of its methods
    (the method itself apart)."""
    found: dict[str, Difference] = {}
    for method in comparison.runs:
        for d in differences(dataclasses.replace(comparison.settings, method=method),
                             dataclasses.replace(current, method=method)):
            found.setdefault(d.label, d)
    return list(found.values())


def table_markdown(comparison: Comparison, found: list[Difference]) -> str:
    """Two tables with a row per method: its success rates, then the other run metrics of
    ``compare.COLUMNS`` (labels and units from the registry) and the frames it ran."""
    metrics = columns()
    levels = [m for m in metrics if isinstance(m, SuccessRate)]
    others = [m for m in metrics if not isinstance(m, SuccessRate)]
    settings, summaries = comparison.settings, comparison.summaries()
    state = "stopped" if comparison.stopped else "every frame"
    lines = [f"{stale_markdown(found)}**{len(comparison.runs)} of {len(comparison.asked)} methods**, {state} "
             f"(seed {settings.scenario.seed}, {settings.scenario.protocol} protocol)"]
    for shown, frames in ((levels, False), (others, True)):
        lines += ["", f"| method | {' | '.join(m.heading for m in shown)} |{' frames |' if frames else ''}",
                  "|---|" + "---|" * (len(shown) + frames)]
        for method, summary in summaries.items():
            run = comparison.runs[method]
            values = " | ".join(m.unit.shown(summary.get(m.key), "—") for m in shown)
            ran = f" {len(run.rows)} of {run.n_frames} |" if frames else ""
            lines.append(f"| {short(method)} | {values} |{ran}")
    return "\n".join(lines)


def chart_series(comparison: Comparison) -> tuple[uplot.Series, ...]:
    return (FRAME, *(uplot.Series(label=short(m), stroke=COLOURS.get(m, "#333333"), width=1.5, scale="m",
                                  points=DOTS) for m in comparison.runs), SUCCESS_LINE)


def chart_data(comparison: Comparison, n_frames: int) -> tuple[np.ndarray, ...]:
    """x (``plot.frame_axis``), each method's RTE per frame, and the success test's 1 m."""
    rte = comparison.per_frame("rte")
    x = frame_axis(set().union(*(set(by_frame) for by_frame in rte.values())), n_frames)
    ones = np.where(x == np.round(x), 1.0, np.nan)
    return (x, *(column(x, rte[m]) for m in comparison.runs), ones)


def beaten_options(comparison: Comparison | None, method: str) -> tuple[str, ...]:
    """An entry per frame ``method`` fails on and another method succeeds (at most ``LISTED``)."""
    if comparison is None:
        return (NONE_YET,)
    if method not in comparison.runs:
        return (f"({short(method)} was not run)",)
    found = comparison.beaten(method)[:LISTED]
    if not found:
        return (f"(none: where {short(method)} fails, every other fails too)",)
    return tuple(f"frame {frame}: ✓ {', '.join(map(short, others))}" for frame, others in found)


class ComparePanel:
    """The folder's controls and the last comparison of one browser tab."""

    def __init__(self, gui: viser.GuiApi, tab: CompareTab) -> None:
        self.tab = tab
        self.comparison: Comparison | None = None
        self.marked: list[Difference] | None = None
        """The settings the table says differ from the controls' (None: no table yet)."""
        self._closed = threading.Event()
        self.runner = Runner(self._open(self._progress), self._open(self._failed), self._open(self._finished),
                             name=f"compare-{tab.client.client_id}", waiting=self._open(self._waiting))
        self.ticks = {m: gui.add_checkbox(short(m), m in TICKED, hint=METHODS[m].label) for m in COMPARABLE}
        self.run = gui.add_button("run every method ticked", hint="each on every frame, under the current settings")
        self.progress = gui.add_progress_bar(0.0, visible=False, animated=True)
        self.queued = gui.add_markdown(WAITING, visible=False)
        self.stop = gui.add_button("stop", color="red", visible=False, hint="keeps the frames and methods done")
        self.table = gui.add_markdown(INTRO)
        self.chart = gui.add_uplot((np.array([0.0, 1.0]), np.full(2, np.nan)), (FRAME, SUCCESS_LINE),
                                   title="RTE per frame, a line per method", aspect=1.6, scales=SCALES,
                                   axes=(X_AXIS, RTE_AXIS), padding=PADDING, legend=uplot.Legend(live=False))
        last = max(len(tab.explorer) - 1, 0)
        self.frame = gui.add_slider("show frame", 0, last, 1, min(tab.settings.frame, last),
                                    hint="the chart's frames, left to right: a frame clicked shows it")
        names = tuple(short(m) for m in COMPARABLE)
        self.first = gui.add_dropdown("method A", names, initial_value=short("cbm"), hint="the tab's method")
        self.beaten = gui.add_dropdown("A fails, others not", (NONE_YET,),
                                       hint="frames where method A fails and another method succeeds (✓)")
        self.second = gui.add_dropdown("method B", names, initial_value=short("icp"), hint="pinned as the baseline")
        self.how = gui.add_button_group("A and B on this frame", HOW)

    def bind(self) -> None:
        self.run.on_click(lambda e: self.start())
        self.stop.on_click(lambda e: self.runner.cancel())
        on_user(self.frame, lambda: self.show_frame(int(self.frame.value)))
        on_user(self.beaten, lambda: self._picked(self.beaten.value))
        on_user(self.first, self._list_beaten)
        self.how.on_click(lambda e: self.show_pair(by_short(self.first.value), by_short(self.second.value),
                                                   e.target.value == "side by side"))

    def start(self) -> bool:
        """Run every method ticked on every frame; False when none is ticked or a comparison runs."""
        settings, explorer = self.tab.settings, self.tab.explorer
        methods = [m for m, box in self.ticks.items() if box.value]
        refused = refusals(self.tab.offers, settings, methods)
        for method, why in refused.items():
            self.tab.notify(f"{short(method)} left out", why, "yellow")
        methods = [m for m in methods if m not in refused]
        if not methods:
            self.tab.notify("Nothing to run", "tick at least one method", "yellow")
            return False
        started = self.runner.start("Comparison", lambda task: run_comparison(explorer, settings, methods, task),
                                    self._open(self._done))
        if not started:
            self.tab.notify("Busy", "a comparison is running; stop it first", "yellow")
            return False
        self.progress.value, self.progress.visible, self.stop.visible, self.run.disabled = 0.0, True, True, True
        return True

    def show_frame(self, frame: int) -> None:
        """Show ``frame`` under the tab's settings, the camera framing it."""
        self.tab.apply(lambda s: dataclasses.replace(s, frame=frame), move_controls=True, frame_camera=True)

    def show_pair(self, first: str, second: str, beside: bool) -> None:
        """``first`` as the tab's method and ``second`` pinned as its baseline, drawn ``beside`` it or
        over it, on the frame shown (the comparison's rows of ``second`` fill the timeline's pinned series)."""
        if first == second:
            self.tab.notify("Pick two methods", f"A and B are both {short(first)}", "yellow")
            return
        settings = self.tab.settings
        refused = refusals(self.tab.offers, settings, (first, second))
        if refused:
            self.tab.notify("Not offered here", "; ".join(refused.values()), "yellow")
            return
        rows = None
        if self.comparison is not None and second in self.comparison.runs and not stale(self.comparison, settings):
            rows = sweep_rows(self.comparison.runs[second].rows)
        self.tab.baseline.pin(dataclasses.replace(settings, method=second), self.tab.history, None, rows=rows,
                              beside=beside)
        self.tab.apply(lambda s: dataclasses.replace(s, method=first), move_controls=True)
        self.tab.refresh(frame_camera=True)
        where = "beside it, on the left" if beside else "as thin violet lines over it"
        self.tab.notify(f"{short(first)} and {short(second)}", f"frame {settings.frame}: {short(first)} is the "
                        f"tab's method, {short(second)} pinned and drawn {where} (unpin under the timeline)", "blue")

    def reflect(self, settings: Settings) -> None:
        """Follow the tab's frame, and mark the table when the settings moved since it ran (the table
        redrawn only when what differs changed)."""
        assign(self.frame, value=min(settings.frame, self.frame.max))
        found = None if self.comparison is None else stale(self.comparison, settings)
        if found != self.marked:
            self.marked = found
            assign(self.table, content=table_markdown(self.comparison, found))

    def close(self) -> None:
        self._closed.set()
        self.runner.cancel()

    def _done(self, comparison: Comparison, cancelled: bool) -> None:
        self.comparison, self.marked = comparison, stale(comparison, self.tab.settings)
        assign(self.table, content=table_markdown(comparison, self.marked))
        send(self.chart, chart_data(comparison, len(self.tab.explorer)), chart_series(comparison))
        self._list_beaten()

    def _list_beaten(self) -> None:
        """List (and mark on the slider) the frames method A fails on and another method succeeds."""
        method = by_short(self.first.value)
        options = beaten_options(self.comparison, method)
        self.beaten.options = options
        self.beaten.value = options[0]
        found = [] if self.comparison is None else self.comparison.beaten(method)[:LISTED]
        self.frame._marks = tuple(GuiSliderMark(value=float(v), label=str(int(v)))
                                  for v in (self.frame.min, self.frame.max)) + \
            tuple(GuiSliderMark(value=float(f), label=None) for f, _ in found)

    def _picked(self, option: str) -> None:
        found = re.match(r"frame (\d+):", option)
        if found:
            self.show_frame(int(found.group(1)))

    def _open(self, update):
        """``update``, skipped once the tab closed (a job's last reports come after it)."""
        return lambda *args: None if self._closed.is_set() else update(*args)

    def _progress(self, fraction: float) -> None:
        self.progress.value = round(100.0 * fraction, 1)

    def _waiting(self, queued: bool) -> None:
        self.queued.visible = queued

    def _finished(self) -> None:
        self.progress.visible, self.stop.visible, self.queued.visible, self.run.disabled = False, False, False, False

    def _failed(self, title: str, error: BaseException) -> None:
        self.tab.notify(f"{title} failed", f"{type(error).__name__}: {error}", "red")


PANEL = Panel("Every method, whole sequence", 55, "every method ticked over every frame: one table, one chart "
              "with a line per method, any two methods' pairs on one frame", ComparePanel,
              lambda part, tab: part.bind(), inside="Explore")
