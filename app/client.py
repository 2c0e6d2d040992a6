"""One browser tab: its settings, its recompute worker, its scene and panels, its play loop."""
from __future__ import annotations

import dataclasses
import threading
import time
from collections.abc import Callable

import numpy as np
import viser

from . import drawing
from .coalesce import Coalescer
from .explore import ExplorePanel
from .panels import Panels
from .presets import PresetError, discover, save_preset
from .scene_view import SceneView
from .session import CavChoice, Explorer, Outcome
from .settings import AUTO_CAV, Settings, ViewOptions


class FrameHistory:
    """Per-frame metrics of the current settings, for the plot over frames; forgotten when any
    setting other than the frame, the CAV or the view changes."""

    def __init__(self) -> None:
        self.key: Settings | None = None
        self.rows: dict[int, tuple[float, float, float]] = {}

    @staticmethod
    def _key(settings: Settings) -> Settings:
        return dataclasses.replace(settings, frame=0, cav=AUTO_CAV, view=ViewOptions())

    def add(self, outcome: Outcome) -> None:
        key = self._key(outcome.settings)
        if key != self.key:
            self.key, self.rows = key, {}
        m = outcome.metrics
        self.rows[outcome.frame_index] = (m.precision, m.recall, m.rte)

    def arrays(self) -> tuple[np.ndarray, ...]:
        frames = np.array(sorted(self.rows), dtype=float)
        values = np.array([self.rows[int(f)] for f in frames], dtype=float).reshape(-1, 3)
        return (frames, *(np.where(np.isfinite(values[:, k]), values[:, k], np.nan) for k in range(3)))


class ClientSession:
    """Everything one tab has; nothing in it is shared with other tabs but the ``Explorer``."""

    def __init__(self, client: viser.ClientHandle, explorer: Explorer, settings: Settings) -> None:
        self.client, self.explorer = client, explorer
        self._lock = threading.Lock()
        self.settings = settings
        self.last: Outcome | None = None
        self.history = FrameHistory()
        self._choices: list[CavChoice] = []
        self._choices_frame = -1
        presets, problems = discover()
        self.presets = presets
        self.view = SceneView(client)
        self.view.reset_camera()
        self.panels = Panels(client.gui, self, settings, len(explorer), list(presets))
        self.explore = ExplorePanel(client.gui, self.panels.tabs, self)
        for problem in problems:
            self.notify("Preset skipped", problem, "yellow")
        self._playing = threading.Event()
        self._closed = threading.Event()
        self.worker: Coalescer[Settings, tuple[Outcome, drawing.Drawing]] = Coalescer(
            self._compute, self._deliver, self._failed, name=f"recompute-{client.client_id}")
        self._player = threading.Thread(target=self._play, name=f"play-{client.client_id}", daemon=True)
        self._player.start()
        self.last_drawing: drawing.Drawing | None = None
        self.worker.submit(settings)

    def change(self, edit: Callable[[Settings], Settings]) -> None:
        """Apply ``edit`` to the settings and recompute (coalesced); no-op edits compute nothing.
        Submitting under the lock keeps the worker's latest value the latest settings."""
        try:
            with self._lock:
                current = edit(self.settings)
                if current == self.settings:
                    return
                self.settings = current
                self.worker.submit(current)
        except (ValueError, TypeError) as error:
            self.notify("Setting refused", str(error), "red")

    def step(self, delta: int) -> None:
        self.panels.frame.value = (self.settings.frame + delta) % len(self.explorer)

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
            settings = preset.apply(self.settings)
        except (KeyError, TypeError, ValueError) as error:
            self.notify("Preset not loaded", f"{name}: {error}", "red")
            return
        self.panels.set_values(settings)
        self.change(lambda s: dataclasses.replace(settings, frame=s.frame, cav=s.cav))
        self.notify("Preset loaded", preset.description or name, "green")

    def save_preset(self, name: str) -> None:
        try:
            path = save_preset(name.strip(), self.settings)
        except (PresetError, OSError) as error:
            self.notify("Preset not saved", str(error), "red")
            return
        self.presets, _ = discover()
        self.panels.preset.options = tuple(self.presets)
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

    def _compute(self, settings: Settings) -> tuple[Outcome, drawing.Drawing]:
        outcome = self.explorer.compute(settings)
        return outcome, drawing.draw(outcome, self.explorer.map_segments)

    def _deliver(self, computed: tuple[Outcome, drawing.Drawing], generation: int) -> None:
        outcome, picture = computed
        self.history.add(outcome)
        first = not self.view.meshes
        relaid = self.last is not None and outcome.settings.view.layout != self.last.settings.view.layout
        self.view.show(picture)
        if relaid:
            self.view.reset_camera(picture.centre_y)
        if first:
            for name in ("ego_boxes", "cav_boxes"):
                self.view.meshes[name].on_click(self._picked)
        self.last, self.last_drawing = outcome, picture
        self.panels.metrics.content = picture.metrics_markdown
        self.panels.plot.data = self.history.arrays()
        self._refresh_cav_choices(outcome)
        self.explore.refresh(outcome, picture)

    def _failed(self, error: BaseException) -> None:
        self.notify("Recompute failed", f"{type(error).__name__}: {error}", "red")

    def _refresh_cav_choices(self, outcome: Outcome) -> None:
        if outcome.frame_index == self._choices_frame:
            return
        self._choices_frame = outcome.frame_index
        self._choices = self.explorer.cav_choices(outcome.frame_index)
        labels = (AUTO_CAV, *[c.label for c in self._choices])
        chosen = next((c.label for c in self._choices if c.id == outcome.settings.cav), AUTO_CAV)
        self.panels.cav.options = labels
        self.panels.cav.value = chosen

    def _play(self) -> None:
        while not self._closed.is_set():
            self._playing.wait()
            if self._closed.is_set():
                return
            self.step(1)
            time.sleep(1.0 / max(1, int(self.panels.speed.value)))

    def _picked(self, event: viser.SceneNodePointerEvent) -> None:
        """Label the object under a click (the ray meets the plane at mid box height) and show its
        context in the inspector."""
        outcome, picture = self.last, self.last_drawing
        origin, direction = np.asarray(event.ray_origin), np.asarray(event.ray_direction)
        if outcome is None or picture is None or abs(direction[2]) < 1e-9:
            return
        point = origin + direction * (0.8 - origin[2]) / direction[2]
        found = drawing.pick(picture, point[:2])
        if found is None or not outcome.settings.view.labels:
            self.view.hide_label("picked")
        if found is None:
            return
        group, index = found
        self.explore.picked(outcome, picture, group, int(picture.objects[group][1][index]))
        if not outcome.settings.view.labels:
            return
        boxes, _ = picture.objects[group]
        self.view.label("picked", drawing.describe(outcome, picture, group, index),
                        (float(boxes[index, 0]), float(boxes[index, 1]), float(boxes[index, 5]) + 1.0))
