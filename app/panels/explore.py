"""The Explore tab: sequence run, worst frames, context inspector, parameter search, export.

Long work (a sequence run, a search, a screenshot) runs off the GUI threads, one at a time, with the
progress bar and a cancel button. Results are plain values (``SequenceRun``, ``SearchResult``) that
the tab keeps and shows; once the controls move to other settings, a run's outputs name the settings
they were computed under, *jump there* asks before setting them, and the per-frame export runs the
current settings first (the frames computed already taken: ``Explorer.rows``)."""
from __future__ import annotations

import dataclasses
import re
import threading
from collections.abc import Callable

import numpy as np
import viser

from evaluation.diagnosis import Finding

from ..scene import inspector, layouts
from ..scene.differences import Difference, differences, now_words
from ..scene.drawing import Drawing
from ..scene.recording_html import recording_html
from ..scene.view import SceneView
from ..session import export, worst
from ..session.background import Runner, Task
from ..session.calibration import CalibrationCheck
from ..session.explorer import Outcome
from ..session.markup import no_html
from ..session.search import OBJECTIVE_LABELS, SearchResult, run_search
from ..session.sequence import SequenceRun, known_frames, run_sequence
from . import confirm
from .actions import TabActions, assign
from .plot import add_run_plots, run_data, send
from .registry import Panel
from .reports import jump_markdown, search_markdown, sequence_markdown, stale_markdown, worst_markdown

NO_RUN = "(run the sequence first)"
NO_SEARCH = "(search first)"
APPLY_HINT = "Moves CBM's sliders to the setting picked above"
APPLY_BEFORE = f"Disabled: no search yet (search σ1, σ2, σ3 first). {APPLY_HINT}"
RATIOS_TITLE, ERRORS_TITLE = "precision and recall per frame", "pose error per frame"
JUMP_HINT = "that frame with the run's settings and noise draw"
WAITING = "*waiting for another tab's job…*"


class ExplorePanel:
    """The controls and outputs of the Explore tab of one browser tab."""

    def __init__(self, gui: viser.GuiApi, tab: TabActions) -> None:
        self.gui, self.tab = gui, tab
        self._closed = threading.Event()
        self.runner = Runner(self._while_open(self._progress), self._while_open(self._failed),
                             self._while_open(self._finished), name=f"explore-{tab.client.client_id}",
                             waiting=self._while_open(self._waiting))
        self.run: SequenceRun | None = None
        self.findings: dict[int, list[Finding]] = {}
        self.searched: SearchResult | None = None
        self.marked: list[Difference] | None = None
        """The settings the run's outputs say they differ in (None: not shown yet)."""
        self.after_run: Callable[[SequenceRun], None] | None = None
        """What to do with the next run once it is complete (an export asked for before it)."""
        self.inspected: tuple[int, int | None, int | None] | None = None
        """(frame, ego index, CAV index) of the pair the inspector shows."""
        self.shown: inspector.ContextPicture | None = None
        self.camera_before: tuple[tuple[float, ...], tuple[float, ...]] | None = None
        """Where the camera stood before it was moved to the inspector's panels (``clear`` goes back)."""
        self.inspector_view = SceneView(tab.client)
        self.progress = gui.add_progress_bar(0.0, visible=False, animated=True)
        self.queued = gui.add_markdown(WAITING, visible=False)
        self.cancel = gui.add_button("cancel", color="red", visible=False)
        with gui.add_folder("Sequence run"):
            self.run_button = gui.add_button("run all frames", hint="the current settings on every frame")
            self.summary = gui.add_markdown("Runs the current settings over every frame of the sequence.")
            self.ratios, self.errors = add_run_plots(gui, RATIOS_TITLE, ERRORS_TITLE)
        with gui.add_folder("Worst frames"):
            self.metric = gui.add_dropdown("rank by", tuple(worst.RANKINGS))
            self.worst = gui.add_dropdown("worst", (NO_RUN,))
            self.jump = gui.add_button("jump there", hint=JUMP_HINT)
            self.worst_table = gui.add_markdown("")
        with gui.add_folder("Context inspector"):
            self.inspect_winner = gui.add_button("inspect the winning anchor")
            self.look = gui.add_button("look at the context panels")
            self.clear = gui.add_button("clear")
            self.inspector_text = gui.add_markdown("Click a box in the scene to see its context and its "
                                                   "counterpart's, drawn left of the scene.")
        with gui.add_folder("Parameter search"):
            self.objective = gui.add_dropdown("objective", tuple(OBJECTIVE_LABELS), initial_value="success")
            self.stride = gui.add_number("every k-th frame", 1, min=1, step=1)
            self.search_button = gui.add_button("search σ1, σ2, σ3")
            self.search_table = gui.add_markdown("")
            self.best = gui.add_dropdown("setting", (NO_SEARCH,))
            self.apply = gui.add_button("apply to the sliders", disabled=True, hint=APPLY_BEFORE)
        self.calibration = CalibrationCheck(tab.explorer.sequence)
        with gui.add_folder("Dataset calibration", expand_by_default=False):
            self.check = gui.add_button("check the dataset's calibration", disabled=not self.calibration.usable,
                                        hint="the shipped transform against the dataset's own labels")
            self.check_text = gui.add_markdown(no_html(self.calibration.text))
            self.flagged = gui.add_dropdown("flagged frame", ("(check first)",))
            self.go = gui.add_button("go to frame", hint="that frame and CAV, under the current settings")
        with gui.add_folder("Export"):
            self.csv = gui.add_button("per-frame metrics (CSV)")
            self.parquet = gui.add_button("per-frame metrics (Parquet)")
            self.preset = gui.add_button("settings as a preset (TOML)")
            self.screenshot = gui.add_button("screenshot of the view (PNG)")
            self.recording = gui.add_button("recording of the frames computed (HTML)",
                                            hint="a page that replays the frames shown, offline")
            self.with_panel = gui.add_checkbox("include the control panel", False,
                                               hint="the frame's metrics drawn beside the 3D view in the PNG")
        self._bind()

    def _bind(self) -> None:
        self.cancel.on_click(lambda e: self.runner.cancel())
        self.check.on_click(lambda e: self.calibration.start(self._checked) and self._checked())
        self.go.on_click(lambda e: self.go_to_flagged(self.flagged.value))
        self.run_button.on_click(lambda e: self.start_run())
        self.metric.on_update(lambda e: self._show_worst())
        self.jump.on_click(lambda e: self.ask_jump(worst.frame_of(self.worst.value))
                           if self.worst.value != NO_RUN else None)
        self.inspect_winner.on_click(lambda e: self.inspect_anchor())
        self.clear.on_click(lambda e: self.clear_inspector())
        self.look.on_click(lambda e: self.look_at_inspector())
        self.search_button.on_click(lambda e: self.start_search())
        self.apply.on_click(lambda e: self.apply_setting(self.best.value))
        self.csv.on_click(lambda e: self._download_rows("csv", export.metrics_csv))
        self.parquet.on_click(lambda e: self._download_rows("parquet", export.metrics_parquet))
        self.preset.on_click(lambda e: self._download("cbm-explorer-preset.toml", export.preset_toml(
            self.tab.settings, self.tab.explorer.sequence.name)))
        self.recording.on_click(lambda e: self._in_thread("Recording", self.download_recording))
        self.screenshot.on_click(lambda e: self._in_thread("Screenshot", lambda: self._download(
            f"cbm-explorer-frame-{self.tab.settings.frame}.png", self.screenshot_png())))

    # sequence run and worst frames

    def start_run(self, then: Callable[[SequenceRun], None] | None = None) -> bool:
        """Run the tab's current settings over every frame, then ``then(run)`` if it completes; False
        when another task is running."""
        settings, explorer = self.tab.settings, self.tab.explorer
        waiting, self.after_run = self.after_run, then

        def work(task: Task) -> tuple[SequenceRun, dict[int, list[Finding]]]:
            run = run_sequence(explorer, settings, task)
            return run, {} if run.cancelled else worst.diagnoses(explorer, run, worst.candidate_frames(run), task.check)

        started = self._start("Sequence run", work, self._ran)
        if not started:
            self.after_run = waiting
        return started

    def _ran(self, result: tuple[SequenceRun, dict[int, list[Finding]]], cancelled: bool) -> None:
        self.run, self.findings = result
        self.marked = None
        frames, precision, recall, rte, rre = self.run.plot_data()
        n_frames = len(self.tab.explorer)
        send(self.ratios, run_data(frames, (precision, recall), n_frames))
        send(self.errors, run_data(frames, (rte, rre), n_frames))
        self.tab.add_frames(self.run.settings, list(self.run.rows))
        self.mark_stale()
        then, self.after_run = self.after_run, None
        if then is not None and self.run.cancelled:
            self.tab.notify("Nothing exported", "the run was cancelled before every frame was done", "yellow")
        elif then is not None:
            then(self.run)

    def run_differences(self) -> list[Difference]:
        """How the last run's settings differ from the controls' (empty: no run, or the same)."""
        return [] if self.run is None else differences(self.run.settings, self.tab.settings)

    def mark_stale(self) -> None:
        """Show the run's summary and worst frames marked, when the controls have moved since, with
        the settings they were computed under (each change of settings calls this)."""
        found = self.run_differences()
        if self.run is None or found == self.marked:
            return
        self.marked = found
        assign(self.summary, content=stale_markdown(found) + sequence_markdown(self.run))
        for chart, title in ((self.ratios, RATIOS_TITLE), (self.errors, ERRORS_TITLE)):
            chart.title = f"{title} (other settings)" if found else title
        self.jump.hint = JUMP_HINT if not found else "the run used other settings: asks before setting them"
        self._show_worst()

    def _show_worst(self) -> None:
        if self.run is None or not self.run.rows:
            return
        metric = self.metric.value
        rows = worst.rank(self.run.rows, metric)
        self.worst.options = tuple(worst.label(row, metric) for row in rows)
        self.worst.value = self.worst.options[0]
        table = worst_markdown(rows, metric, self.findings)
        assign(self.worst_table, content=stale_markdown(self.marked or []) + table)

    def ask_jump(self, frame: int) -> None:
        """Show ``frame`` as the run computed it; when the controls have moved since, first ask,
        listing the settings the jump would set."""
        if self.run is None:
            return
        found = self.run_differences()
        if not found:
            self.tab.apply(lambda s: dataclasses.replace(s, frame=frame), move_controls=True, frame_camera=True)
            return
        run, apply = self.run, self.tab.apply
        confirm.ask(self.gui, f"Jump to frame {frame}", jump_markdown(frame, found), {
            "set the run's settings and jump": lambda: apply(
                lambda s: dataclasses.replace(run.settings, frame=frame, view=s.view), move_controls=True,
                frame_camera=True),
            "jump, keep my settings": lambda: apply(lambda s: dataclasses.replace(s, frame=frame), move_controls=True,
                                                    frame_camera=True),
            "cancel": None})

    # dataset calibration

    def _checked(self) -> None:
        assign(self.check_text, content=self.calibration.text)
        self.flagged.options = self.calibration.options()
        self.flagged.value = self.flagged.options[0]

    def go_to_flagged(self, chosen: str) -> None:
        """Show a flagged frame of the calibration check with its CAV, under the current settings."""
        row = self.calibration.row_of(chosen)
        if row is not None:
            self.tab.apply(lambda s: dataclasses.replace(s, frame=row.frame, cav=row.cav), move_controls=True,
                           frame_camera=True)

    # parameter search

    def start_search(self) -> bool:
        """Search CBM's thresholds on the tab's sequence; False when another task is running."""
        settings, explorer = self.tab.settings, self.tab.explorer
        objective, stride = self.objective.value, max(1, int(self.stride.value))
        return self._start("Search", lambda task: run_search(explorer, settings, objective, stride, task),
                           self._searched)

    def _searched(self, result: SearchResult, cancelled: bool) -> None:
        self.searched = result
        assign(self.search_table, content=search_markdown(result))
        self.best.options = tuple(result.option(k) for k in range(min(10, len(result.candidates))))
        self.best.value = self.best.options[0]
        self.apply.disabled, self.apply.hint = False, APPLY_HINT

    def apply_setting(self, option: str) -> None:
        """Move CBM's sliders to the searched setting ``option`` (as listed in the dropdown)."""
        if self.searched is None or option == NO_SEARCH:
            return
        rank = int(re.match(r"#(\d+)", option).group(1)) - 1
        params = self.searched.candidates[rank].params
        self.tab.apply(lambda s: s.with_params("cbm", **params), move_controls=True)
        self.tab.notify("Search result applied", option, "green")

    # context inspector

    def picked(self, outcome: Outcome, picture: Drawing, group: str, index: int) -> None:
        """Inspect a clicked object and its counterpart."""
        ego, cav = inspector.counterpart(outcome, group, index)
        self._inspect(outcome, picture, ego, cav)

    def inspect_anchor(self) -> None:
        """Inspect the winning anchor of the frame on screen."""
        outcome, picture = self.tab.current()
        if outcome is None or picture is None or outcome.result.anchor is None:
            self.tab.notify("Nothing to inspect", "this frame has no winning anchor", "yellow")
            return
        self._inspect(outcome, picture, *map(int, outcome.result.anchor))
        self.look_at_inspector()

    def refresh(self, outcome: Outcome, picture: Drawing) -> None:
        """Follow a recompute: the run's outputs say whether they are still the controls'; the same
        pair on the same frame is redrawn under the new thresholds, anything else clears the inspector."""
        self.mark_stale()
        if self.inspected is None:
            return
        frame, ego, cav = self.inspected
        trial = outcome.trial
        fits = (ego is None or ego < len(trial.ego_boxes)) and (cav is None or cav < len(trial.cav_boxes))
        if frame == outcome.frame_index and fits:
            self._inspect(outcome, picture, ego, cav)
        else:
            self.clear_inspector()

    def look_at_inspector(self) -> None:
        """Point the camera down on the inspector's panels (reset camera goes back to the scene)."""
        if self.shown is None:
            self.tab.notify("Nothing inspected", "click a box first", "yellow")
            return
        client = self.tab.client
        if self.camera_before is None:
            self.camera_before = (tuple(client.camera.position), tuple(client.camera.look_at))
        height = layouts.fitting_height(self.shown.span, layouts.screen_of(client.camera))
        position, look_at = layouts.looking_down(self.shown.centre, height, 0.15)
        client.flush()
        layouts.move_camera(client, position, look_at)
        client.flush()

    def clear_inspector(self) -> None:
        """Hide the inspector's panels and put back the camera they moved."""
        if self.camera_before is not None:
            layouts.move_camera(self.tab.client, *self.camera_before)
            self.camera_before = None
        self.inspected = self.shown = None
        self.tab.hide_click_label()
        self.inspector_view.show(inspector.empty())
        assign(self.inspector_text, content="Click a box in the scene to see its context.")

    def _inspect(self, outcome: Outcome, picture: Drawing, ego: int | None, cav: int | None) -> None:
        shown = inspector.inspect(outcome, picture, ego, cav)
        self.inspected, self.shown = (outcome.frame_index, ego, cav), shown
        self.inspector_view.show(shown.drawing())
        assign(self.inspector_text, content=shown.markdown)

    # export

    def _download_rows(self, suffix: str, encode: Callable[[list[dict]], bytes]) -> None:
        """The per-frame rows of the current settings: the last run's when it ran them, else those
        of a run started now (the file follows when it completes)."""
        found = self.run_differences()
        if self.run is not None and self.run.rows and not found:
            self._export(self.run, suffix, encode)
            return
        why = "no run yet" if self.run is None else f"the last run used other settings: {now_words(found)}"
        known = f"{known_frames(self.tab.explorer, self.tab.settings)} of {len(self.tab.explorer)} frames"
        if self.start_run(then=lambda run: self._export(run, suffix, encode)):
            self.tab.notify("Running the current settings first", f"{why}; {known} computed already are taken. "
                            "The file downloads when every frame is done.", "blue")

    def _export(self, run: SequenceRun, suffix: str, encode: Callable[[list[dict]], bytes]) -> None:
        name = export.slug(self.tab.explorer.sequence.name)
        self._download(f"cbm-{name}-seed{run.settings.scenario.seed}.{suffix}", encode(list(run.rows)))

    def download_recording(self) -> None:
        """The frames this tab has shown under its current settings as a self-contained HTML page."""
        recording = self.tab.recording
        if not len(recording):
            self.tab.notify("Nothing to export", "no frame computed yet", "yellow")
            return
        dataset = self.tab.explorer.sequence.name
        page = recording_html(recording, dataset, self.tab.settings.view.presentation)
        self._download(f"cbm-explorer-{export.slug(dataset)}-{len(recording)}frames.html", page)

    def screenshot_png(self) -> bytes:
        """The view as PNG bytes, with the metrics panel beside it when "include the control panel" is on."""
        _, picture = self.tab.current()
        dark = self.tab.settings.view.dark
        if not self.with_panel.value or picture is None:
            return export.png(export.opaque(render(self.tab.client), dark))
        return export.png(export.with_panel(render(self.tab.client), picture.metrics_markdown, dark=dark))

    def _download(self, filename: str, content: bytes) -> None:
        self.tab.client.send_file_download(filename, content, save_immediately=True)

    # plumbing

    def close(self) -> None:
        self._closed.set()
        self.runner.cancel()

    def _while_open(self, update: Callable[..., None]) -> Callable[..., None]:
        """``update``, skipped once the tab closed: a job's last reports come after it, and viser
        warns of every update queued on a closed connection."""
        return lambda *args: None if self._closed.is_set() else update(*args)

    def _start(self, title: str, work, done) -> bool:
        started = self.runner.start(title, work, self._while_open(done))
        if not started:
            self.tab.notify("Busy", "another sequence run or search is running; cancel it first", "yellow")
            return False
        self.progress.value, self.progress.visible, self.cancel.visible = 0.0, True, True
        self.run_button.disabled = self.search_button.disabled = True
        return True

    def _waiting(self, queued: bool) -> None:
        self.queued.visible = queued

    def _progress(self, fraction: float) -> None:
        self.progress.value = round(100.0 * fraction, 1)

    def _finished(self) -> None:
        self.progress.visible, self.cancel.visible, self.queued.visible = False, False, False
        self.run_button.disabled = self.search_button.disabled = False

    def _failed(self, title: str, error: BaseException) -> None:
        self.tab.notify(f"{title} failed", f"{type(error).__name__}: {error}", "red")

    def _in_thread(self, title: str, work: Callable[[], None]) -> None:
        def guarded() -> None:
            try:
                work()
            except Exception as error:  # reported to this tab only
                self._failed(title, error)

        threading.Thread(target=guarded, name=f"{title}-{self.tab.client.client_id}", daemon=True).start()


def render(client: viser.ClientHandle, timeout: float = 20.0) -> np.ndarray:
    """The tab's view from its own camera, (H, W, 3|4) uint8; blocks until the browser answers."""
    camera = client.camera
    width, height = camera.image_width or 1280, camera.image_height or 720
    return client.get_render(height, width, transport_format="png", timeout=timeout)


PANEL = Panel("Explore", 50, "every frame at once: sequence run, worst frames, context inspector, parameter search, "
              "dataset calibration, export", ExplorePanel)
