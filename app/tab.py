"""One browser tab: its settings, the one place that changes them and recomputes, its scene, its
panels and its play loop."""
from __future__ import annotations

import dataclasses
import threading
import time

import numpy as np
import viser

from . import panels
from .panels.actions import Edit
from .panels.explore import ExplorePanel
from .scene import picking
from .scene.drawing import Drawing, draw
from .scene.view import SceneView
from .session.coalesce import Coalescer
from .session.explorer import CavChoice, Explorer, Outcome
from .session.history import FrameHistory
from .session.kernels import Kernels
from .session.presets import PresetError, discover, save_preset
from .session.progress import announced
from .session.settings import AUTO_CAV, Settings


class ClientSession:
    """Everything one tab has; nothing in it is shared with other tabs but the ``Explorer``.

    ``settings`` is one immutable value, replaced as a whole by ``apply``; a worker recomputes the
    latest value (``Coalescer``) and shows it, once CBM's ``kernels`` are ready."""

    def __init__(self, client: viser.ClientHandle, explorer: Explorer, settings: Settings, kernels: Kernels) -> None:
        self.client, self.explorer, self.kernels = client, explorer, kernels
        self._note = ""
        self._lock = threading.Lock()
        self._settings = settings
        self.last: Outcome | None = None
        self.last_drawing: Drawing | None = None
        self.history = FrameHistory()
        self._choices: list[CavChoice] = []
        self._choices_frame = -1
        self.presets, problems = discover()
        self.view = SceneView(client)
        self.view.reset_camera()
        self.controls = panels.build(client.gui, settings, len(explorer), list(self.presets))
        self.explore = ExplorePanel(client.gui, self.controls.tabs, self)
        panels.bind(self.controls, self)
        for problem in problems:
            self.notify("Preset skipped", problem, "yellow")
        self._playing = threading.Event()
        self._closed = threading.Event()
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

    def apply(self, edit: Edit, *, move_controls: bool = False) -> None:
        """Replace the settings by ``edit(settings)`` and recompute (coalesced); an edit that
        changes nothing computes nothing. Controls that apply to the new settings are shown;
        ``move_controls`` also moves every control to them (a preset, a jump, a step)."""
        try:
            with self._lock:
                new = edit(self._settings)
                if new == self._settings:
                    return
                self._settings = new
                self.worker.submit(new)
        except (ValueError, TypeError) as error:
            self.notify("Setting refused", str(error), "red")
            return
        if move_controls:
            self.controls.show(new)
        else:
            self.controls.reflect(new)

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
        except (KeyError, TypeError, ValueError) as error:
            self.notify("Preset not loaded", f"{name}: {error}", "red")
            return
        self.apply(lambda s: dataclasses.replace(loaded, frame=s.frame, cav=s.cav), move_controls=True)
        self.notify("Preset loaded", preset.description or name, "green")

    def save_preset(self, name: str) -> None:
        try:
            path = save_preset(name.strip(), self._settings)
        except (PresetError, OSError) as error:
            self.notify("Preset not saved", str(error), "red")
            return
        self.presets, _ = discover()
        self.controls.presets.preset.options = tuple(self.presets)
        self.notify("Preset saved", f"{name} -> {path.name} in your presets folder", "green")

    def reset_camera(self) -> None:
        """Back to the top-down view of the current layout."""
        self.view.reset_camera(0.0 if self.last_drawing is None else self.last_drawing.centre_y)

    def notify(self, title: str, body: str, color: str) -> None:
        self.client.add_notification(title, body, color=color, auto_close_seconds=8)

    def close(self) -> None:
        self._closed.set()
        self._playing.set()
        self.explore.close()
        self.worker.close()

    def _compute(self, settings: Settings) -> tuple[Outcome, Drawing]:
        """The outcome of ``settings`` and its drawing, once CBM's kernels are ready; the status
        line says what it waits for when that takes a moment."""
        say = self.controls.metrics.say
        if not self.kernels.ready:
            with announced(lambda s: say(f"Preparing CBM's compiled kernels (first start only)… {s:.0f} s"),
                           after=0.0, every=1.0, since=self.kernels.started):
                self.kernels.wait()
            self._note = self.kernels.note()
        with announced(lambda s: say(f"Computing… {s:.1f} s")):
            outcome = self.explorer.compute(settings)
            return outcome, draw(outcome, self.explorer.map_segments)

    def _deliver(self, computed: tuple[Outcome, Drawing], generation: int) -> None:
        """Show a result: the scene's changed nodes and the panels, in one batch sent at once."""
        outcome, picture = computed
        self.history.add(outcome)
        first = not self.view.meshes
        relaid = self.last is not None and outcome.settings.view.layout != self.last.settings.view.layout
        with self.client.atomic():
            self.view.show(picture)
            if relaid:
                self.view.reset_camera(picture.centre_y)
            self.controls.metrics.show(picture.metrics_markdown, self.history.arrays(), self._note)
            self._refresh_cav_choices(outcome)
            self.explore.refresh(outcome, picture)
        self.client.flush()
        self._note = ""
        if first:
            for name in ("ego_boxes", "cav_boxes"):
                self.view.meshes[name].on_click(self._picked)
        self.last, self.last_drawing = outcome, picture

    def _failed(self, error: BaseException) -> None:
        self.controls.metrics.say("")
        self.notify("Recompute failed", f"{type(error).__name__}: {error}", "red")

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
        """Label the object under a click (the ray meets the plane at mid box height) and show its
        context in the inspector."""
        outcome, picture = self.last, self.last_drawing
        origin, direction = np.asarray(event.ray_origin), np.asarray(event.ray_direction)
        if outcome is None or picture is None or abs(direction[2]) < 1e-9:
            return
        point = origin + direction * (0.8 - origin[2]) / direction[2]
        found = picking.pick(picture, point[:2])
        if found is None or not outcome.settings.view.labels:
            self.view.hide_label("picked")
        if found is None:
            return
        group, index = found
        self.explore.picked(outcome, picture, group, int(picture.objects[group][1][index]))
        if not outcome.settings.view.labels:
            return
        boxes, _ = picture.objects[group]
        self.view.label("picked", picking.describe(outcome, picture, group, index),
                        (float(boxes[index, 0]), float(boxes[index, 1]), float(boxes[index, 5]) + 1.0))
