"""One browser tab: its settings, the one place that changes them and recomputes, its scene, its
panels and its play loop."""
from __future__ import annotations

import dataclasses
import threading
import time

import numpy as np
import viser

from cbm.engine.interpreted import SMALL
from cbm.engine.threads import Cancelled, stoppable
from cbm.methods import METHODS

from . import panels
from .panels.actions import Edit, assign
from .panels.explore import ExplorePanel
from .panels.keynumbers import GAP, WIDTH, KeyNumbers, unusable_markdown
from .panels.plot import timeline_data
from .scene import picking, planes, presentation
from .scene.camera import TabCamera, key_numbers_area
from .scene.drawing import Drawing, draw
from .scene.framing import Area
from .scene.pinned import with_baseline
from .scene.view import SceneView
from .scene.words import error_words
from .session.baseline import Baseline
from .session.coalesce import Coalescer, Later
from .session.explorer import CavChoice, Explorer, Outcome
from .session.history import FrameHistory, row_over_time, settings_key, sweep_rows
from .session.kernels import COMPILING, Kernels
from .session.offers import offers_of
from .session.over_time import Stopped
from .session.presets import PresetError, discover, in_use, save_preset, skipped_markdown
from .session.progress import announced
from .session.recording import Recording
from .session.settings import AUTO_CAV, Settings, ViewOptions
from .walkthrough.panel import WalkthroughPanel

TIMELINE_DELAY = 0.2
"""Seconds after the latest result before the timeline is redrawn: the chart costs the browser more
than the rest of a result, and while a slider moves only the last result's timeline is worth drawing."""


def descriptions(presets: dict) -> dict[str, str]:
    """Each preset's description by its name."""
    return {name: preset.description for name, preset in presets.items()}


class ClientSession:
    """Everything one tab has; nothing in it is shared with other tabs but the ``Explorer``.

    ``settings`` is one immutable value, replaced as a whole by ``apply``; a worker recomputes the
    latest value (``Coalescer``) and shows it; a small frame runs CBM interpreted until ``kernels`` are ready."""

    def __init__(self, client: viser.ClientHandle, explorer: Explorer, settings: Settings, kernels: Kernels) -> None:
        self.client, self.explorer, self.kernels = client, explorer, kernels
        self._note = ""
        self._compiled_note_due = False
        """A result ran interpreted or waited for the compile: the next compiled one says how long it took."""
        self._lock = threading.Lock()
        self._settings = settings
        self.last: Outcome | None = None
        self.last_drawing: Drawing | None = None
        self.history = FrameHistory()
        self.recording = Recording()
        self.baseline = Baseline()
        self._timeline_later = Later(TIMELINE_DELAY)
        self._choices: list[CavChoice] = []
        self._choices_frame = -1
        self.presets, problems = discover()
        self.view = SceneView(client)
        self.camera = TabCamera(client)
        self.camera.on_measured = self.reset_camera
        self._frame_for: Settings | None = None
        """Settings whose result the camera is to frame when shown (a jump to a frame)."""
        self.caption = presentation.Caption(client)
        self.key_numbers = KeyNumbers(client.gui)
        self.offers = offers_of(explorer.sequence)
        self.controls = panels.build(client.gui, settings, len(explorer), descriptions(self.presets), self.offers)
        self.explore = ExplorePanel(client.gui, self.controls.tabs, self)
        self.walkthrough = WalkthroughPanel(client.gui, self.controls.tabs, self)
        panels.bind(self.controls, self)
        panels.metrics.bind(self.controls.metrics, self)
        self.controls.presets.skipped.content = skipped_markdown(problems)
        self.controls.presets.in_use(in_use(self.presets, settings))
        if problems:
            self.notify("Preset files skipped", f"{len(problems)} file(s): see the Presets tab", "yellow")
        for warning in explorer.sequence.warnings:
            self.notify("Dataset loaded with gaps", warning, "yellow")
        for note in explorer.sequence.notes:
            self.notify("How this dataset is read", note, "blue")
        self._playing = threading.Event()
        self._closed = threading.Event()
        self._stop_catching_up = threading.Event()
        self.worker: Coalescer[Settings, tuple[Outcome, Drawing]] = Coalescer(
            self._compute, self._deliver, self._failed, name=f"recompute-{client.client_id}")
        self._player = threading.Thread(target=self._play, name=f"play-{client.client_id}", daemon=True)
        self._player.start()
        self.worker.submit(settings)

    @property
    def settings(self) -> Settings:
        return self._settings

    def current(self) -> tuple[Outcome | None, Drawing | None]:
        return self.last, self.last_drawing

    def apply(self, edit: Edit, *, move_controls: bool = False, frame_camera: bool = False) -> None:
        """Replace the settings by ``edit(settings)`` and recompute (coalesced); an edit that
        changes nothing computes nothing, one to fewer CAVs than the method needs switches the method
        and says so (``Offers.adapted``). Controls that apply to the new settings are shown;
        ``move_controls`` also moves every control to them (a preset, a jump, a step);
        ``frame_camera``: the camera frames the result (at once when nothing changes)."""
        try:
            with self._lock:
                new = edit(self._settings)
                if new == self._settings:
                    if frame_camera:
                        self.reset_camera()
                    return
                new, switched = self.offers.adapted(self._settings, new)
                refused = self.offers.refusal(new)
                if refused:
                    raise ValueError(refused)
                self._settings = new
                self._frame_for = new if frame_camera else self._frame_for
                self.worker.submit(new)
        except (ValueError, TypeError) as error:
            self.notify("Setting refused", str(error), "red")
            self.controls.show(self._settings)
            return
        if switched:
            self.notify("Method switched", switched, "blue")
        if move_controls or switched:
            self.controls.show(new)
        else:
            self.controls.reflect(new)
        self.controls.presets.in_use(in_use(self.presets, new))

    def step(self, delta: int) -> None:
        self.apply(lambda s: dataclasses.replace(s, frame=(s.frame + delta) % len(self.explorer)), move_controls=True)

    def set_playing(self, playing: bool) -> None:
        (self._playing.set if playing else self._playing.clear)()

    def cav_id(self, label: str) -> str:
        return next((c.id for c in self._choices if c.label == label), AUTO_CAV)

    def load_preset(self, name: str) -> None:
        preset = self.presets.get(name)
        if preset is None:
            self.notify("No such preset", f"{name!r} is not among the presets", "red")
            return
        try:
            loaded = preset.apply(self._settings)
            refused = self.offers.refusal(dataclasses.replace(loaded, cavs=self._settings.cavs))
            if refused:
                raise ValueError(refused)
        except (KeyError, TypeError, ValueError) as error:
            self.notify("Preset not loaded", f"{name}: {error}", "red")
            return
        self.apply(lambda s: dataclasses.replace(loaded, frame=s.frame, cav=s.cav, cavs=s.cavs), move_controls=True)
        self.notify("Preset loaded", preset.description or name, "green")

    def save_preset(self, name: str) -> None:
        try:
            path = save_preset(name.strip(), self._settings)
        except (PresetError, OSError) as error:
            self.notify("Preset not saved", str(error), "red")
            return
        self.presets, problems = discover()
        self.controls.presets.offer(descriptions(self.presets))
        self.controls.presets.skipped.content = skipped_markdown(problems)
        self.controls.presets.in_use(in_use(self.presets, self._settings))
        self.notify("Preset saved", f"{name} -> {path.name} in your presets folder", "green")

    def reset_camera(self, oblique: bool = False) -> None:
        """Frame the frame on screen from straight above (presentation mode: over the two agents);
        ``oblique``: the 3D view, from behind and above the ego. The labels are spread apart again."""
        outcome, picture = self.last, self.last_drawing
        if outcome is None or picture is None:
            return
        self.view.lay_out(self.camera.frame(picture, outcome.settings.view, self._covered(outcome.settings.view),
                                            oblique))

    def hide_click_label(self) -> None:
        self.view.hide_label("picked")

    def _covered(self, view: ViewOptions) -> Area | None:
        """The part of the canvas a floating panel covers: the key numbers' (none in presentation
        mode, whose camera frames the agents for a caption at the page's bottom left)."""
        if view.presentation:
            return None
        return key_numbers_area(self.key_numbers.handle.content, self.camera.canvas, GAP, WIDTH)

    def _aim(self, outcome: Outcome, picture: Drawing, reframe: bool) -> float | None:
        """Frame the result (``reframe``: a first frame, a jump, a new layout or mode), else follow
        it; the metres per pixel to spread its labels at (None: the camera's)."""
        view, covered = outcome.settings.view, self._covered(outcome.settings.view)
        return (self.camera.frame if reframe else self.camera.follow)(picture, view, covered)

    def refresh(self) -> None:
        """Recompute the settings on screen (the pinned baseline changed)."""
        self.worker.submit(self._settings)

    def add_frames(self, settings: Settings, rows: list[dict]) -> None:
        """A sequence run's rows join the timeline when they are the current settings'."""
        current = self._settings
        if settings_key(settings) != settings_key(current):
            return
        self.history.merge(settings, sweep_rows(rows))
        self.controls.metrics.show_timeline(self._timeline(current.frame), self.history.failures(),
                                            self.baseline.pinned, current.frame, self._over_time())

    def _show_timeline_soon(self, frame: int) -> None:
        """The timeline at ``frame``, drawn ``TIMELINE_DELAY`` after the latest result."""
        data, failures, pinned = self._timeline(frame), self.history.failures(), self.baseline.pinned
        over_time = self._over_time()
        self._timeline_later.call(lambda: self._closed.is_set()  # a closed tab's client takes no update
                                  or self.controls.metrics.show_timeline(data, failures, pinned, frame, over_time))

    def _timeline(self, frame: int) -> tuple[np.ndarray, ...]:
        rows = dict(self.history.rows) if self.history.matches(self._settings) else {}
        return timeline_data(rows, dict(self.baseline.rows), frame, len(self.explorer), self.baseline.pinned,
                             self._over_time())

    def _over_time(self) -> bool:
        """Whether the timeline draws a method over time beside per-frame CBM."""
        return METHODS[self._settings.method].over_time

    def stop_catching_up(self) -> None:
        """Stop a method over time computing the frames before the one asked for: the frames done
        stay, and the last of them is shown."""
        self._stop_catching_up.set()

    def notify(self, title: str, body: str, color: str) -> None:
        self.client.add_notification(title, body, color=color, auto_close_seconds=8)

    def close(self) -> None:
        self._closed.set()
        self._playing.set()
        self.explore.close()
        self.worker.close()
        self._timeline_later.close()

    def _compute(self, settings: Settings) -> tuple[Outcome, Drawing]:
        """The outcome of ``settings`` and its drawing. Until CBM's kernels are compiled a small
        frame runs interpreted, its note says so, and the tab recomputes once they are ready; a
        large frame waits for them, as does any frame when they are only loaded from the cache. The
        status line says what it waits for when that takes a moment."""
        say = self.controls.metrics.say
        if not self.kernels.ready and (self.kernels.cached or self._objects(settings) > SMALL):
            self._compiled_note_due = True
            with announced(lambda s: say(f"Preparing CBM's compiled kernels (first start only)… {s:.0f} s"),
                           after=0.0, every=1.0, since=self.kernels.started):
                self.kernels.wait()
        self._stop_catching_up.clear()
        try:
            with announced(lambda s: say(f"Computing… {s:.1f} s")), self.kernels.running() as interpreting, \
                    stoppable(lambda: self.worker.superseded):
                outcome = self.explorer.compute(settings, self._catching_up(), self._stopping)
                pinned = self.baseline.outcome(self.explorer, settings)
        except Stopped as stopped:
            if self.worker.superseded:
                raise
            last = stopped.frame
            self.apply(lambda s: dataclasses.replace(s, frame=last), move_controls=True)
            self.notify("Stopped", f"the frames up to {last} are computed and kept; step on or jump ahead "
                        "to continue from there", "blue")
            raise
        finally:
            self.controls.metrics.stop.visible = False
        self._note_kernels(interpreting)
        return outcome, with_baseline(draw(outcome, self.explorer.map_segments,
                                           self.explorer.sequence[outcome.frame_index]), outcome, pinned)

    def _catching_up(self):
        """A method over time's report while it computes the frames before the one asked for: the
        status line and the stop button, at most four times a second."""
        shown = [0.0]

        def report(done: int, of: int) -> None:
            now = time.monotonic()
            if done < of and now - shown[0] >= 0.25:
                shown[0] = now
                self.controls.metrics.stop.visible = True
                self.controls.metrics.say(f"CBM over time computes the frames in order: frame {done} of {of}…")
        return report

    def _stopping(self) -> bool:
        """Whether a method over time's catch-up should stop: asked to, or a newer setting waits."""
        return self._stop_catching_up.is_set() or self.worker.superseded

    def _objects(self, settings: Settings) -> int:
        """Objects in the frame ``settings`` shows (a bound on what each agent sees)."""
        return len(self.explorer.sequence[min(max(settings.frame, 0), len(self.explorer) - 1)].track_ids)

    def _note_kernels(self, interpreting: bool) -> None:
        """The note beside this result: the compile still running, or (once) the compile's time."""
        if interpreting:
            self._note = COMPILING
            if not self._compiled_note_due:
                self.kernels.when_ready(self._recompute)
            self._compiled_note_due = True
        elif self._compiled_note_due:
            self._note, self._compiled_note_due = self.kernels.note(), False

    def _recompute(self) -> None:
        """The current settings again (the kernels got ready: the note and CBM time change)."""
        if not self._closed.is_set():
            self.worker.submit(self._settings)

    def _deliver(self, computed: tuple[Outcome, Drawing], generation: int) -> None:
        """Show a result: the scene's changed nodes and the panels, in one batch sent at once; then
        keep its row and record (the timeline, drawn later, and the recording read them); not once closed."""
        if self._closed.is_set():
            return
        outcome, picture = computed
        first = not self.view.meshes
        relaid = self.last is not None and outcome.settings.view.layout != self.last.settings.view.layout
        jumped, self._frame_for = self._frame_for == outcome.settings, None
        with self.client.atomic():
            self.key_numbers.show(outcome)
            staged = presentation.restage(self.client, self.last and self.last.settings.view, outcome.settings.view)
            self.view.show(picture, self._aim(outcome, picture, relaid or staged or first or jumped))
            self.controls.metrics.show(picture.metrics_markdown, self._note)
            self.caption.show(outcome)
            self._refresh_cav_choices(outcome)
            self.explore.refresh(outcome, picture)
            self.walkthrough.refresh(outcome)
        self.client.flush()
        self.history.add(outcome)
        if outcome.alone is not None:
            done = self.explorer.over_time.done(outcome.settings)
            self.history.merge(outcome.settings, {frame: row_over_time(d.metrics, d.alone_metrics, d.result.track.event)
                                                  for frame, d in done.items()})
        self.recording.add(outcome)
        self._show_timeline_soon(outcome.frame_index)
        self._note = ""
        if first:
            for name in picking.NODES:
                self.view.meshes[name].on_click(self._picked)
        self.last, self.last_drawing = outcome, picture

    def _failed(self, error: BaseException) -> None:
        """A frame CBM cannot run on: a lasting message of what is missing, in place of the metrics
        (or above the last frame's, marked as such), and in the key numbers."""
        if isinstance(error, (Stopped, Cancelled)):
            return
        message = unusable_markdown(self.explorer, self._settings, error)
        if self.last is None:
            self.controls.metrics.say("")
            assign(self.controls.metrics.text, content=message)
        else:
            self.controls.metrics.say(f"{message}\n\n*Below: the last frame computed ({self.last.frame_index}).*")
        method = METHODS[self._settings.method].label
        self.key_numbers.problem(f"{method} cannot run on this frame: see the panel")
        self.notify(f"{method} cannot run on this frame", error_words(error), "red")

    def _refresh_cav_choices(self, outcome: Outcome) -> None:
        if outcome.frame_index == self._choices_frame:
            return
        self._choices_frame = outcome.frame_index
        self._choices = self.explorer.cav_choices(outcome.frame_index)
        cav = self.controls.frame.cav
        cav.options = (AUTO_CAV, *[c.label for c in self._choices])
        cav.value = next((c.label for c in self._choices if c.id == outcome.settings.cav), AUTO_CAV)

    def _play(self) -> None:
        while not self._closed.is_set():
            self._playing.wait()
            if self._closed.is_set():
                return
            self.step(1)
            time.sleep(1.0 / max(1, int(self.controls.frame.speed.value)))

    def _picked(self, event: viser.SceneNodePointerEvent) -> None:
        """Label the object under a click (the ray meets the plane of the footprints) and, for the ego's
        and the first CAV's (the pair CBM's inspection holds), show its context in the inspector."""
        outcome, picture = self.last, self.last_drawing
        origin, direction = np.asarray(event.ray_origin), np.asarray(event.ray_direction)
        if outcome is None or picture is None or abs(direction[2]) < 1e-9:
            return
        point = origin + direction * (planes.EGO - origin[2]) / direction[2]
        found = picking.pick(picture, point[:2])
        if found is None or not outcome.settings.view.labels:
            self.view.hide_label("picked")
        if found is None:
            return
        group, index = found
        if group in ("ego", "cav"):
            self.explore.picked(outcome, picture, group, int(picture.objects[group][1][index]))
        if not outcome.settings.view.labels:
            return
        boxes, _ = picture.objects[group]
        self.view.label("picked", picking.describe(outcome, picture, group, index),
                        (float(boxes[index, 0]), float(boxes[index, 1]), planes.LABELS))
