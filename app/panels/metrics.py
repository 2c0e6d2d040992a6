"""The outputs of the frame on screen: a status line (what the tab is waiting for) under the frame
controls, and, under the tabs, the frame's metrics, the timeline of the frames computed so far with
its help folded behind a "?", and its controls: step to the previous or next failed frame, jump to
a failed frame, pin the current settings as a baseline. The timeline marks every failed frame on the
one frame slider at the top of the panel (``frame``).

viser 1.1.1 sends no clicks on a chart; the frame slider spans the same frames."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import viser
from viser._messages import GuiSliderMark

from cbm.methods import METHODS

from ..scene.deciding import Mark
from ..session.baseline import Baseline
from ..session.coalesce import Later
from ..session.history import FAILED_MEANING, FrameHistory, step_to_failure
from .actions import TabActions, assign, on_user
from .plot import add_timeline, send, timeline_data, timeline_series

TIMELINE_DELAY = 0.2
"""Seconds after the latest result before the timeline is redrawn: the chart costs the browser more
than the rest of a result, and while a slider moves only the last result's timeline is worth drawing."""
FAILED_HEADER = "failed frames"
PIN, UNPIN = "pin baseline", "unpin"
HELP, HELP_SHOWN = "? what the timeline shows", "? hide the timeline's help"
AWAY_HINT = ("pairs (ego id ↔ CAV id, and how far from the ego) that tell why this frame failed but lie outside "
             "the view at a scale where a car still reads as a box; a click flies the camera there (an arrow at the "
             "scene's edge points to them)")
HINT = (f"Red dots: failed frames ({FAILED_MEANING}); black bar: this frame; dashed: pinned; a gap: frames not "
        "computed. Fills with every frame computed (stepping, play, *run all frames*) until a setting other than "
        "frame, CAV or view changes.")


class TimelineTab(TabActions, Protocol):
    """The browser tab as the timeline's controls see it."""

    history: FrameHistory
    baseline: Baseline

    def refresh(self) -> None:
        """Recompute the frame on screen (the pinned comparison changed)."""

    def stop_catching_up(self) -> None:
        """Stop a method over time computing the frames before the one asked for."""

    def fly_to(self, key: str) -> None:
        """Frame one pair of the frame on screen (``deciding.Mark.key``)."""


@dataclass
class MetricsControls:
    status: viser.GuiMarkdownHandle
    stop: viser.GuiButtonHandle
    """Stops a method over time computing the frames before the one asked for (shown meanwhile)."""
    text: viser.GuiMarkdownHandle
    away: viser.GuiButtonGroupHandle
    """The pairs left out of view, one button each (``show_away``): a click flies the camera there."""
    plot: viser.GuiUplotHandle
    scrubber: viser.GuiSliderHandle
    """The frame slider (``frame.Navigation``): a mark on each failed frame known."""
    failures: viser.GuiButtonGroupHandle
    failed: viser.GuiDropdownHandle
    pin: viser.GuiButtonHandle
    help: viser.GuiButtonHandle
    """The "?" that shows or hides ``legend``, the timeline's help."""
    legend: viser.GuiMarkdownHandle
    away_keys: dict[str, str] = field(default_factory=dict)
    """Each button of ``away`` -> the pair's key (``deciding.Mark.key``)."""
    later: Later = field(default_factory=lambda: Later(TIMELINE_DELAY))
    """Draws the timeline of the latest result (``show_timeline_soon``)."""
    closed: bool = False

    def toggle_help(self) -> None:
        """Show the timeline's help when it is folded away, fold it away when it shows."""
        self.legend.visible = not self.legend.visible
        self.help.label = HELP_SHOWN if self.legend.visible else HELP

    def say(self, status: str) -> None:
        """Show ``status`` under the frame controls; an empty one hides the line."""
        assign(self.status, content=status)
        self.status.visible = bool(status)

    def show(self, metrics_markdown: str, status: str = "") -> None:
        """One result's metrics, and what to say above them (the timeline follows, ``show_timeline``)."""
        self.say(status)
        assign(self.text, content=metrics_markdown)

    def show_away(self, marks: tuple[Mark, ...]) -> None:
        """A button for each pair out of view (hidden when there is none)."""
        keys = {f"{mark.words} · {mark.distance:.0f} m": mark.key for mark in marks}
        if keys != self.away_keys:
            self.away_keys = keys
            self.away.options = tuple(keys) or ("-",)
        self.away.visible = bool(keys)

    def show_timeline(self, timeline: tuple[np.ndarray, ...], failures: list[int], pinned: bool, frame: int,
                      over_time: bool = False) -> None:
        """The timeline, its slider at ``frame`` with the failed frames marked, the list of failed
        frames and the pin button's label."""
        send(self.plot, timeline, timeline_series(pinned, over_time))
        self.scrubber.value = frame
        ends = tuple(GuiSliderMark(value=float(v), label=str(int(v))) for v in (self.scrubber.min, self.scrubber.max))
        marks = ends + tuple(GuiSliderMark(value=float(f), label=None) for f in failures)
        if self.scrubber._marks != marks:
            self.scrubber._marks = marks
        options = (f"{FAILED_HEADER} ({len(failures)} known)", *(f"frame {f}" for f in failures))
        if tuple(self.failed.options) != options:
            self.failed.options = options
        shown = f"frame {frame}" if frame in failures else options[0]
        if self.failed.value != shown:
            self.failed.value = shown
        self.pin.label = UNPIN if pinned else PIN

    def show_timeline_soon(self, shown: tuple[Any, ...]) -> None:
        """``show_timeline(*shown)`` ``TIMELINE_DELAY`` after the latest result, unless closed by then."""
        self.later.call(lambda: self.closed or self.show_timeline(*shown))

    def close(self) -> None:
        """The browser tab closed: its client takes no update."""
        self.closed = True
        self.later.close()


def timeline_of(tab: TimelineTab, frame: int) -> tuple[Any, ...]:
    """What ``show_timeline`` draws of ``tab`` at ``frame``: the frames computed under the current
    settings, the pinned baseline's, and a method over time's per-frame CBM beside."""
    over_time = METHODS[tab.settings.method].over_time
    rows = dict(tab.history.rows) if tab.history.matches(tab.settings) else {}
    data = timeline_data(rows, dict(tab.baseline.rows), frame, len(tab.explorer), tab.baseline.pinned, over_time)
    return data, tab.history.failures(), tab.baseline.pinned, frame, over_time


def build_status(gui: viser.GuiApi) -> tuple[viser.GuiMarkdownHandle, viser.GuiButtonHandle]:
    """The status line and the stop button, under the frame controls (shown only when they speak)."""
    status = gui.add_markdown("", visible=False)
    stop = gui.add_button("stop computing the frames before", visible=False, color="red",
                          hint="keep the frames computed so far and show the last of them")
    return status, stop


def build(gui: viser.GuiApi, frame_slider: viser.GuiSliderHandle,
          status: tuple[viser.GuiMarkdownHandle, viser.GuiButtonHandle]) -> MetricsControls:
    """The metrics and the timeline's controls; ``frame_slider`` (built above them) carries the
    marks, ``status`` is ``build_status``'s line and button."""
    text = gui.add_markdown("Computing the first frame…")
    away = gui.add_button_group("not in view", ("-",), visible=False, hint=AWAY_HINT)
    plot = add_timeline(gui)
    failures = gui.add_button_group("failure", ("◀ previous failure", "next failure ▶"))
    failed = gui.add_dropdown("jump to", (f"{FAILED_HEADER} (0 known)",),
                              hint="a failed frame known so far ")
    pin = gui.add_button(PIN, hint="keep these settings and their per-frame results to compare against")
    help_button = gui.add_button(HELP, hint="what the timeline's dots, bar, dashes and gaps mean")
    legend = gui.add_markdown(HINT, visible=False)
    return MetricsControls(*status, text, away, plot, frame_slider, failures, failed, pin, help_button, legend)


def bind(c: MetricsControls, tab: TimelineTab) -> None:
    c.stop.on_click(lambda e: tab.stop_catching_up())
    c.away.on_click(lambda e: tab.fly_to(c.away_keys.get(e.target.value, "")))
    c.failures.on_click(lambda e: step_failure(tab, -1 if e.target.value.startswith("◀") else 1))
    on_user(c.failed, lambda: jump(tab, c.failed.value))
    c.pin.on_click(lambda e: toggle_pin(tab))
    c.help.on_click(lambda e: c.toggle_help())


def go_to(tab: TabActions, frame: int) -> None:
    """Jump to ``frame``, the camera framing it."""
    tab.apply(lambda s: dataclasses.replace(s, frame=frame), move_controls=True, frame_camera=True)


def step_failure(tab: TimelineTab, direction: int) -> None:
    """Show the nearest failed frame before or after this one among the frames computed; past the
    last (or before the first) wrap round to the first (the last), and say so."""
    frame = tab.settings.frame
    rows = dict(tab.history.rows) if tab.history.matches(tab.settings) else {}
    found = step_to_failure(rows, frame, direction)
    if found is None:
        found = step_to_failure(rows, -1 if direction > 0 else len(tab.explorer), direction)
        if found is None:
            tab.notify("No failed frame known", "none among the frames computed so far; run all frames (Explore "
                       "tab) to find every failure", "yellow")
            return
        tab.notify(*wrapped_words(found, frame, direction, len(rows) == len(tab.explorer)))
        if found == frame:
            return
    go_to(tab, found)


def wrapped_words(found: int, frame: int, direction: int, all_known: bool) -> tuple[str, str, str]:
    """The notification of a step past the last failure (or before the first) that wraps to ``found``."""
    if found == frame:
        return "The only failed frame known", f"frame {frame} is the only failure known", "blue"
    title, where, start = ("Past the last failure", "after", "first") if direction > 0 else \
        ("Before the first failure", "before", "last")
    known = "in the sequence" if all_known else "among the frames computed so far (run all frames to find every one)"
    return title, f"no failed frame {where} frame {frame} {known}; back to the {start}, frame {found}", "blue"


def jump(tab: TabActions, option: str) -> None:
    """Show the frame an entry of the failed frames' list names."""
    if option.startswith("frame "):
        go_to(tab, int(option.removeprefix("frame ")))


def toggle_pin(tab: TimelineTab) -> None:
    """Pin the settings on screen with their per-frame results, or unpin the baseline."""
    if tab.baseline.pinned:
        tab.baseline.unpin()
        tab.notify("Baseline unpinned", "the timeline and the metrics show the current settings only", "blue")
    else:
        outcome, _ = tab.current()
        tab.baseline.pin(tab.settings, tab.history, outcome)
        tab.notify("Baseline pinned", "change settings to compare: the metrics show current vs pinned, the "
                   "timeline both (dashed: pinned)", "green")
    tab.refresh()
