"""The Explore tab: sequence run, worst frames, context inspector, parameter search, export.

Long work (a sequence run, a search, a screenshot) runs off the GUI threads; a sequence run or a
search at a time, with the progress bar and a cancel button. Results are plain values
(``SequenceRun``, ``SearchResult``) that the tab keeps and shows.
"""
from __future__ import annotations

import dataclasses
import re
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import viser
from viser import uplot

from cbm.diagnosis import Finding

from . import export, inspector, worst
from .background import Runner, Task
from .drawing import Drawing
from .scene_view import SceneView
from .search_panel import OBJECTIVE_LABELS, SearchResult, run_search
from .sequence import SequenceRun, run_sequence
from .session import Outcome

if TYPE_CHECKING:
    from .client import ClientSession

NO_RUN = "(run the sequence first)"
NO_SEARCH = "(search first)"


class ExplorePanel:
    """The controls and outputs of the Explore tab of one browser tab."""

    def __init__(self, gui: viser.GuiApi, tabs: viser.GuiTabGroupHandle, session: ClientSession) -> None:
        self.gui, self.session = gui, session
        self.runner = Runner(self._progress, self._failed, self._finished, name=f"explore-{session.client.client_id}")
        self.run: SequenceRun | None = None
        self.findings: dict[int, list[Finding]] = {}
        self.searched: SearchResult | None = None
        self.inspected: tuple[int, int | None, int | None] | None = None
        """(frame, ego index, CAV index) of the pair the inspector shows."""
        self.shown: inspector.ContextPicture | None = None
        self.inspector_view = SceneView(session.client)
        with tabs.add_tab("Explore"):
            self.progress = gui.add_progress_bar(0.0, visible=False, animated=True)
            self.cancel = gui.add_button("cancel", color="red", visible=False)
            with gui.add_folder("Sequence run"):
                self.run_button = gui.add_button("run all frames", hint="the current settings on every frame")
                self.summary = gui.add_markdown("Runs the current settings over every frame of the sequence.")
                self.plot = gui.add_uplot(*_empty_plot(), title="per frame", aspect=2.0,
                                          scales={"x": uplot.Scale(time=False),
                                                  "y": uplot.Scale(auto=False, range=(0.0, 1.0)),
                                                  "m": uplot.Scale(auto=True)},
                                          axes=(uplot.Axis(), uplot.Axis(scale="y"), uplot.Axis(scale="m", side=1)))
            with gui.add_folder("Worst frames"):
                self.metric = gui.add_dropdown("rank by", tuple(worst.RANKINGS))
                self.worst = gui.add_dropdown("worst", (NO_RUN,))
                self.jump = gui.add_button("jump there", hint="that frame with the run's settings and noise draw")
                self.worst_table = gui.add_markdown("")
            with gui.add_folder("Context inspector"):
                self.inspect_winner = gui.add_button("inspect the winning anchor")
                self.look = gui.add_button("look at the context panels")
                self.clear = gui.add_button("clear")
                self.inspector_text = gui.add_markdown("Click a box in the scene to see its context and its "
                                                       "counterpart's, drawn right of the scene.")
            with gui.add_folder("Parameter search"):
                self.objective = gui.add_dropdown("objective", tuple(OBJECTIVE_LABELS), initial_value="success")
                self.stride = gui.add_number("every k-th frame", 1, min=1, step=1)
                self.search_button = gui.add_button("search σ1, σ2, σ3")
                self.search_table = gui.add_markdown("")
                self.best = gui.add_dropdown("setting", (NO_SEARCH,))
                self.apply = gui.add_button("apply to the sliders")
            with gui.add_folder("Export"):
                self.csv = gui.add_button("per-frame metrics (CSV)")
                self.parquet = gui.add_button("per-frame metrics (Parquet)")
                self.preset = gui.add_button("settings as a preset (TOML)")
                self.screenshot = gui.add_button("screenshot of the view (PNG)")
        self._bind()

    def _bind(self) -> None:
        self.cancel.on_click(lambda e: self.runner.cancel())
        self.run_button.on_click(lambda e: self.start_run())
        self.metric.on_update(lambda e: self._show_worst())
        self.jump.on_click(lambda e: self.jump_to(worst.frame_of(self.worst.value)) if self.worst.value != NO_RUN else None)
        self.inspect_winner.on_click(lambda e: self.inspect_anchor())
        self.clear.on_click(lambda e: self.clear_inspector())
        self.look.on_click(lambda e: self.look_at_inspector())
        self.search_button.on_click(lambda e: self.start_search())
        self.apply.on_click(lambda e: self.apply_setting(self.best.value))
        self.csv.on_click(lambda e: self._download_rows("csv", export.metrics_csv))
        self.parquet.on_click(lambda e: self._download_rows("parquet", export.metrics_parquet))
        self.preset.on_click(lambda e: self._download("cbm-explorer-preset.toml", export.preset_toml(
            self.session.settings, self.session.explorer.sequence.name)))
        self.screenshot.on_click(lambda e: self._in_thread("Screenshot", lambda: self._download(
            f"cbm-explorer-frame-{self.session.settings.frame}.png", export.screenshot(self.session.client))))

    # sequence run and worst frames

    def start_run(self) -> bool:
        """Run the tab's current settings over every frame; False when another task is running."""
        settings, explorer = self.session.settings, self.session.explorer

        def work(task: Task) -> tuple[SequenceRun, dict[int, list[Finding]]]:
            run = run_sequence(explorer, settings, task)
            return run, {} if run.cancelled else worst.diagnoses(explorer, run, worst.candidate_frames(run), task.check)

        return self._start("Sequence run", work, self._ran)

    def _ran(self, result: tuple[SequenceRun, dict[int, list[Finding]]], cancelled: bool) -> None:
        self.run, self.findings = result
        self.summary.content = self.run.markdown()
        self.plot.data = self.run.plot_data()
        self._show_worst()

    def _show_worst(self) -> None:
        if self.run is None or not self.run.rows:
            return
        metric = self.metric.value
        rows = worst.rank(self.run.rows, metric)
        self.worst.options = tuple(worst.label(row, metric) for row in rows)
        self.worst.value = self.worst.options[0]
        self.worst_table.content = worst.markdown(rows, metric, self.findings)

    def jump_to(self, frame: int) -> None:
        """Show ``frame`` with the last run's settings (and so its noise draw), keeping the view."""
        if self.run is None:
            return
        settings = dataclasses.replace(self.run.settings, frame=frame, view=self.session.settings.view)
        self.session.panels.set_values(settings)
        self.session.panels.frame.value = frame
        self.session.change(lambda s: settings)

    # parameter search

    def start_search(self) -> bool:
        """Search CBM's thresholds on the tab's sequence; False when another task is running."""
        settings, explorer = self.session.settings, self.session.explorer
        objective, stride = self.objective.value, max(1, int(self.stride.value))
        return self._start("Search", lambda task: run_search(explorer, settings, objective, stride, task), self._searched)

    def _searched(self, result: SearchResult, cancelled: bool) -> None:
        self.searched = result
        self.search_table.content = result.markdown()
        self.best.options = tuple(result.option(k) for k in range(min(10, len(result.candidates))))
        self.best.value = self.best.options[0]

    def apply_setting(self, option: str) -> None:
        """Move CBM's sliders to the searched setting ``option`` (as listed in the dropdown)."""
        if self.searched is None or option == NO_SEARCH:
            return
        rank = int(re.match(r"#(\d+)", option).group(1)) - 1
        params = self.searched.candidates[rank].params
        for name, value in params.items():
            self.session.panels.method_controls[("cbm", name)].value = value
        self.session.change(lambda s: s.with_params("cbm", **params))
        self.session.notify("Search result applied", option, "green")

    # context inspector

    def picked(self, outcome: Outcome, picture: Drawing, group: str, index: int) -> None:
        """Inspect a clicked object and its counterpart."""
        ego, cav = inspector.counterpart(outcome, group, index)
        self._inspect(outcome, picture, ego, cav)

    def inspect_anchor(self) -> None:
        """Inspect the winning anchor of the frame on screen."""
        outcome, picture = self.session.last, self.session.last_drawing
        if outcome is None or picture is None or outcome.result.anchor is None:
            self.session.notify("Nothing to inspect", "this frame has no winning anchor", "yellow")
            return
        self._inspect(outcome, picture, *map(int, outcome.result.anchor))

    def refresh(self, outcome: Outcome, picture: Drawing) -> None:
        """Follow a recompute: the same pair on the same frame is redrawn under the new thresholds;
        anything else clears the inspector."""
        if self.inspected is None:
            return
        frame, ego, cav = self.inspected
        fits = (ego is None or ego < len(outcome.trial.ego_boxes)) and (cav is None or cav < len(outcome.trial.cav_boxes))
        if frame == outcome.frame_index and fits:
            self._inspect(outcome, picture, ego, cav)
        else:
            self.clear_inspector()

    def look_at_inspector(self) -> None:
        """Point the camera down on the inspector's panels (reset camera goes back to the scene)."""
        if self.shown is None:
            self.session.notify("Nothing inspected", "click a box first", "yellow")
            return
        x, y = self.shown.centre
        camera = self.session.client.camera
        camera.position = (x - 10.0, y, 1.1 * self.shown.span)
        camera.look_at = (x, y, 0.0)

    def clear_inspector(self) -> None:
        self.inspected = self.shown = None
        self.inspector_view.show(inspector.empty())
        self.inspector_text.content = "Click a box in the scene to see its context."

    def _inspect(self, outcome: Outcome, picture: Drawing, ego: int | None, cav: int | None) -> None:
        shown = inspector.inspect(outcome, picture, ego, cav)
        self.inspected, self.shown = (outcome.frame_index, ego, cav), shown
        self.inspector_view.show(shown.drawing())
        self.inspector_text.content = shown.markdown

    # export

    def _download_rows(self, suffix: str, encode: Callable[[list[dict]], bytes]) -> None:
        if self.run is None or not self.run.rows:
            self.session.notify("Nothing to export", "run the sequence first", "yellow")
            return
        name = re.sub(r"[^A-Za-z0-9]+", "-", self.session.explorer.sequence.name).strip("-")[:40]
        self._download(f"cbm-{name}-seed{self.run.settings.scenario.seed}.{suffix}", encode(list(self.run.rows)))

    def _download(self, filename: str, content: bytes) -> None:
        self.session.client.send_file_download(filename, content, save_immediately=True)

    # plumbing

    def close(self) -> None:
        self.runner.cancel()

    def _start(self, title: str, work, done) -> bool:
        started = self.runner.start(title, work, done)
        if not started:
            self.session.notify("Busy", "another sequence run or search is running; cancel it first", "yellow")
            return False
        self.progress.value, self.progress.visible, self.cancel.visible = 0.0, True, True
        self.run_button.disabled = self.search_button.disabled = True
        return True

    def _progress(self, fraction: float) -> None:
        self.progress.value = round(100.0 * fraction, 1)

    def _finished(self) -> None:
        self.progress.visible, self.cancel.visible = False, False
        self.run_button.disabled = self.search_button.disabled = False

    def _failed(self, title: str, error: BaseException) -> None:
        self.session.notify(f"{title} failed", f"{type(error).__name__}: {error}", "red")

    def _in_thread(self, title: str, work: Callable[[], None]) -> None:
        def guarded() -> None:
            try:
                work()
            except Exception as error:  # reported to this tab only
                self._failed(title, error)

        threading.Thread(target=guarded, name=f"{title}-{self.session.client.client_id}", daemon=True).start()


def _empty_plot() -> tuple[tuple[np.ndarray, ...], tuple[uplot.Series, ...]]:
    series = (uplot.Series(label="frame"), uplot.Series(label="precision", stroke="#1e9c3c", width=2, scale="y"),
              uplot.Series(label="recall", stroke="#3478f6", width=2, scale="y"),
              uplot.Series(label="RTE (m)", stroke="#e1261e", width=2, scale="m"),
              uplot.Series(label="RRE (°)", stroke="#9b59b6", width=2, scale="m"))
    return tuple(np.zeros(0) for _ in series), series
