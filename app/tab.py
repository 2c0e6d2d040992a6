"""One browser tab's session: its settings, the one place that changes them and recomputes, and its
play loop. What it shows goes to its stage (``app.stage``: the scene, the camera, the key numbers)
and its panels, which are found (``app.panels.registry``): the session builds them and tells them
of every change, and names none of them."""
from __future__ import annotations

import dataclasses
import threading
import time

import viser

from cbm import INTERPRETED_UP_TO, Cancelled, stoppable
from cbm.methods import METHODS

from . import panels
from .panels.actions import Edit, assign
from .panels.keynumbers import unusable_markdown
from .panels.metrics import timeline_of
from .scene.drawing import Drawing, draw
from .scene.pinned import with_baseline
from .scene.words import error_words, setting_words
from .session.baseline import Baseline
from .session.coalesce import Coalescer
from .session.explorer import Explorer, Outcome
from .session.history import FrameHistory, row_over_time, settings_key, sweep_rows
from .session.kernels import BASELINES, COMPILING, Kernels
from .session.offers import offers_of
from .session.over_time import Stopped
from .session.progress import announced
from .session.recording import Recording
from .session.settings import Settings
from .stage import Stage

COMPUTING_AFTER = 0.3
"""Seconds a recompute of the same method takes before the status line and the key numbers say it is
computing (the verdict on screen is then stale; a quicker one replaces it before anyone reads it)."""
PREVIEW_FROM = 50
"""Frames a method over time must compute before the one asked for, from which per-frame CBM's answer
is shown meanwhile (an edit deep in a sequence shows at once; 50 steps take about a quarter second)."""
MEANWHILE = "per-frame CBM shown meanwhile"
PREVIEW_WORDS = ("**Per-frame CBM on this frame, shown while CBM over time computes the frames before it** "
                 "(the answer over time replaces it).")


class ClientSession:
    """Everything one tab has; nothing in it is shared with other tabs but the ``Explorer``.

    ``settings`` is one immutable value, replaced as a whole by ``apply``; a worker recomputes the
    latest value (``Coalescer``) and shows it; a small frame runs CBM interpreted until ``kernels`` are ready."""

    def __init__(self, client: viser.ClientHandle, explorer: Explorer, settings: Settings, kernels: Kernels) -> None:
        self.client, self.explorer, self.kernels = client, explorer, kernels
        self._note = ""
        self._meanwhile = ""
        """Said beside what the tab waits for while per-frame CBM's answer stands in (``_preview``)."""
        self._play_note = ""
        """How fast a play that cannot keep up goes (``playing_words``), beside each frame it shows."""
        self._compiled_note_due = False
        """A result ran interpreted or waited for the compile: the next compiled one says how long it took."""
        self._lock = threading.Lock()
        self._settings = settings
        self.last: Outcome | None = None
        self.last_drawing: Drawing | None = None
        self.history = FrameHistory()
        self.recording = Recording()
        self.baseline = Baseline()
        self._frame_for: Settings | None = None
        """Settings whose result the camera is to frame when shown (a jump to a frame)."""
        self.stage = Stage(client, lambda *clicked: self.controls.call("picked", *clicked),
                           lambda marks: self.controls.metrics.show_away(marks))
        self.offers = offers_of(explorer.sequence)
        self.controls = panels.build(client.gui, self)
        for warning in explorer.sequence.warnings:
            self.notify("Dataset loaded with gaps", warning, "yellow")
        for note in explorer.sequence.notes:
            self.notify("How this dataset is read", note, "blue")
        self._playing = threading.Event()
        self._shown = threading.Event()
        """Set when a result is shown (or fails): the play loop asks for the next frame then."""
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
            self.notify("Setting refused", setting_words(error), "red")
            self.controls.show(self._settings)
            return
        if switched:
            self.notify("Method switched", switched, "blue")
        if move_controls or switched:
            self.controls.show(new)
        else:
            self.controls.reflect(new)

    def step(self, delta: int) -> None:
        self.apply(lambda s: dataclasses.replace(s, frame=(s.frame + delta) % len(self.explorer)), move_controls=True)

    def set_playing(self, playing: bool) -> None:
        (self._playing.set if playing else self._playing.clear)()
        if not playing:
            self._play_note = ""

    def reset_camera(self, oblique: bool = False) -> None:
        self.stage.reset_camera(oblique)

    def hide_click_label(self) -> None:
        self.stage.hide_click_label()

    def fly_to(self, key: str) -> None:
        self.stage.fly_to(key)

    def refresh(self, frame_camera: bool = False) -> None:
        """Recompute the settings on screen (the pinned baseline changed); ``frame_camera``: the
        camera frames the result."""
        with self._lock:
            self._frame_for = self._settings if frame_camera else self._frame_for
            self.worker.submit(self._settings)

    def add_frames(self, settings: Settings, rows: list[dict]) -> None:
        """A sequence run's rows join the timeline when they are the current settings'."""
        current = self._settings
        if settings_key(settings) != settings_key(current):
            return
        self.history.merge(settings, sweep_rows(rows))
        self.controls.metrics.show_timeline(*timeline_of(self, current.frame))

    def stop_catching_up(self) -> None:
        """Stop a method over time computing the frames before the one asked for: the frames done
        stay, and the last of them is shown."""
        self._stop_catching_up.set()

    def notify(self, title: str, body: str, color: str) -> None:
        self.client.add_notification(title, body, color=color, auto_close_seconds=8)

    def close(self) -> None:
        self._closed.set()
        self._playing.set()
        self.controls.close()
        self.worker.close()
        self.stage.close()

    def _compute(self, settings: Settings) -> tuple[Outcome, Drawing]:
        """The outcome of ``settings`` and its drawing. Until CBM's kernels are compiled a small
        frame runs interpreted, its note says so, and the tab recomputes once they are ready; a
        large frame waits for them, as does any frame when they are only loaded from the cache. The
        status line says what it waits for when that takes a moment."""
        self._meanwhile = ""
        if not self.kernels.ready_for(settings.method) and self._waits_for_kernels(settings):
            self._compiled_note_due = self._compiled_note_due or not self.kernels.ready
            whose = "CBM's" if not self.kernels.ready else f"{METHODS[settings.method].label}'s"
            with announced(lambda s: self._waiting(settings, f"Preparing {whose} compiled kernels (first start "
                                                             f"only)… {s:.0f} s", f"{whose} kernels first: {s:.0f} s"),
                           after=0.0, every=1.0, since=self.kernels.started):
                self.kernels.wait(method=settings.method)
        self._stop_catching_up.clear()
        if self.last is None or self.last.settings.method != settings.method:
            self._waiting(settings, "")
        try:
            with announced(lambda s: self._waiting(settings, f"Computing… {s:.1f} s", f"{s:.1f} s"),
                           after=COMPUTING_AFTER), \
                    self.kernels.running() as interpreting, stoppable(lambda: self.worker.superseded):
                self._preview(settings)
                outcome = self.explorer.compute(settings, self._catching_up(settings), self._stopping)
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
                                           self.explorer.sequence[outcome.frame_index]), outcome, pinned,
                                      self.baseline.beside)

    def _preview(self, settings: Settings) -> None:
        """Per-frame CBM's answer on the frame asked for, marked as such, when a method over time has
        at least ``PREVIEW_FROM`` frames to compute before it; what the tab says while it waits then
        says so too (``_meanwhile``)."""
        if not METHODS[settings.method].over_time or \
                self.explorer.over_time.to_compute(settings, settings.frame) < PREVIEW_FROM:
            return
        outcome = self.explorer.compute(dataclasses.replace(settings, method="cbm"))
        picture = draw(outcome, self.explorer.map_segments, self.explorer.sequence[outcome.frame_index])
        with self.client.atomic():
            self.stage.show(outcome, picture, reframe=self._frame_for == settings)
            self.controls.metrics.show(f"{PREVIEW_WORDS}\n\n{picture.metrics_markdown}")
        self.client.flush()
        self._meanwhile = MEANWHILE

    def _waiting(self, settings: Settings, status: str, progress: str = "") -> None:
        """Say what the tab waits for: ``status`` on the status line (none when empty), and in the key
        numbers the method computing in place of the verdict on screen (another method's, or stale),
        with its ``progress``."""
        if status:
            self.controls.metrics.say(status)
        frame = min(max(settings.frame, 0), len(self.explorer) - 1)
        detail = "; ".join(part for part in (progress, self._meanwhile) if part)
        self.stage.key_numbers.problem(f"{METHODS[settings.method].label} computing frame {frame}…"
                                       + (f" ({detail})" if detail else ""))

    def _waits_for_kernels(self, settings: Settings) -> bool:
        """Whether ``settings`` wait for their kernels rather than run interpreted: a baseline's
        always (``kernels.BASELINES``), CBM's when they load from the cache or the frame is large."""
        return settings.method in BASELINES or self.kernels.cached or self._objects(settings) > INTERPRETED_UP_TO

    def _catching_up(self, settings: Settings):
        """A method over time's report while it computes the frames before the one asked for: the
        status line, the key numbers and the stop button, at most four times a second."""
        shown = [0.0]

        def report(done: int, of: int) -> None:
            now = time.monotonic()
            if done < of and now - shown[0] >= 0.25:
                shown[0] = now
                self.controls.metrics.stop.visible = True
                self._waiting(settings, f"CBM over time computes the frames in order: frame {done} of {of}…",
                              f"the frames before it first: {done} of {of}")
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
        jumped, self._frame_for = self._frame_for == outcome.settings, None
        with self.client.atomic():
            self.stage.show(outcome, picture, reframe=jumped)
            self.controls.metrics.show(picture.metrics_markdown, self._note or self._play_note)
            self.controls.refresh(outcome, picture)
        self.client.flush()
        self.history.add(outcome)
        if outcome.alone is not None:
            self._merge_over_time(outcome.settings)
        self.recording.add(outcome)
        self.controls.metrics.show_timeline_soon(timeline_of(self, outcome.frame_index))
        self._note = ""
        self.last, self.last_drawing = outcome, picture
        self._shown.set()
        if outcome.alone is not None and self.kernels.ready:
            self._fill_over_time(outcome)

    def _merge_over_time(self, settings: Settings) -> None:
        """The timeline's rows of every frame a method over time computed under ``settings``."""
        done = self.explorer.over_time.done(settings)
        self.history.merge(settings, {frame: row_over_time(d.metrics, d.alone_metrics, d.result.track.event)
                                      for frame, d in done.items()})

    def _fill_over_time(self, outcome: Outcome) -> None:
        """Per-frame CBM on the frames a catch-up passed (the timeline's grey line), after the frame
        asked for is shown and until a newer setting waits; then the timeline again."""
        try:
            with stoppable(lambda: self.worker.superseded):
                filled = self.explorer.fill_over_time(outcome.settings, lambda: self.worker.superseded)
        except Cancelled:
            return
        if filled and not self._closed.is_set():
            self._merge_over_time(outcome.settings)
            self.controls.metrics.show_timeline_soon(timeline_of(self, outcome.frame_index))

    def _failed(self, error: BaseException) -> None:
        """A frame CBM cannot run on: a lasting message of what is missing, in place of the metrics
        (or above the last frame's, marked as such), and in the key numbers."""
        self._shown.set()
        if isinstance(error, (Stopped, Cancelled)):
            return
        message = unusable_markdown(self.explorer, self._settings, error)
        if self.last is None:
            self.controls.metrics.say("")
            assign(self.controls.metrics.text, content=message)
        else:
            self.controls.metrics.say(f"{message}\n\n*Below: the last frame computed ({self.last.frame_index}).*")
        method = METHODS[self._settings.method].label
        self.stage.key_numbers.problem(f"{method} cannot run on this frame: see the panel")
        self.notify(f"{method} cannot run on this frame", error_words(error), "red")

    def _play(self) -> None:
        """Step a frame at the play speed, each shown before the next is asked for: a frame that takes
        longer than its share slows the play down (never skips a frame), and the status line says so."""
        while not self._closed.is_set():
            self._playing.wait()
            if self._closed.is_set():
                return
            asked, started = max(1, int(self.controls.frame.speed.value)), time.monotonic()
            self._shown.clear()
            self.step(1)
            while not (self._shown.wait(timeout=0.5) or self.worker.wait_idle(timeout=0.0)):
                if self._closed.is_set():
                    return
            spent = time.monotonic() - started
            self._play_note = playing_words(asked, spent) if self._playing.is_set() else ""
            time.sleep(max(0.0, 1.0 / asked - spent))


def playing_words(asked: int, spent: float) -> str:
    """What the status line says of a play whose last frame took ``spent`` seconds at ``asked``
    frames per second: nothing while it keeps up."""
    if spent <= 1.05 / asked:
        return ""
    return (f"Playing at {1.0 / spent:.1f} frames/s of the {asked} asked: every frame is shown, and each takes "
            f"{spent:.2f} s to compute and show.")
