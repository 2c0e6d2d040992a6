"""One tab's camera: framed on what matters (``framing``) when a frame is loaded, reset or jumped to;
while stepping, still unless something that matters would leave the view (the View tab's *camera
follows*); a camera a person moved stays where they put it until *reset camera*."""
from __future__ import annotations

import html
import math
import re
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import viser

from ..session.settings import ViewOptions
from . import framing
from .framing import Area, Canvas
from .labelling import spread
from .layouts import move_camera, over_layout, screen_of
from .presentation import camera_over

if TYPE_CHECKING:
    from .drawing import Drawing

NEAR = 0.5
"""Metres to the camera's near clipping plane: depth precision enough to stack the footprints'
layers (``planes.STEP`` apart) seen from 100 m."""
TOP_DOWN = {"position": (5.0, 0.0, 60.0), "look_at": (8.0, 0.0, 0.0)}
"""The camera before the first frame: straight above the scene ahead of the ego."""
OBLIQUE = {"position": (-30.0, 0.0, 35.0), "look_at": (8.0, 0.0, 0.0)}
"""The 3D view: behind and above the ego, looking forward and down (about 43 degrees)."""
FRAMINGS, OVERSHOOT = 6, 1.2
"""Rounds of spreading the labels apart and framing them, and how much coarser than the last
camera's scale each round spreads them at (``TabCamera._framed``)."""
ARRIVED_M = 0.1
"""Metres within which the browser's report of its camera counts as the pose the app sent."""
KEY_NUMBERS_HEAD_PX, KEY_NUMBERS_LINE_PX, KEY_NUMBERS_CHARS = 68.0, 18.5, 46
"""The key numbers panel's height in CSS pixels: its title bar, tab and padding, then a line of its
13 px text per ``KEY_NUMBERS_CHARS`` characters (a longer line wraps)."""


def key_numbers_area(content: str, canvas: Canvas, gap: float, width: float) -> Area:
    """The part of the canvas the key numbers panel (floating ``gap`` pixels from the canvas's top
    right corner, ``width`` wide, showing the HTML ``content``) covers."""
    lines = [html.unescape(re.sub(r"<[^>]+>", "", line)) for line in re.split(r"<br\s*/?>", content)]
    rows = sum(max(1, math.ceil(len(line) / KEY_NUMBERS_CHARS)) for line in lines)
    height = KEY_NUMBERS_HEAD_PX + KEY_NUMBERS_LINE_PX * rows
    return Area(canvas.width - gap - width, gap, canvas.width - gap, gap + height)


class TabCamera:
    """The camera of one browser tab, moved by the app only through ``move``.

    The browser reports its camera now and then; once a report shows the pose last sent, any later
    report elsewhere is a person's move (``moved_by_person``), until the app moves it again or the
    camera is back at that pose (the walkthrough and the inspector put back the camera they moved)."""

    def __init__(self, client: viser.ClientHandle) -> None:
        self.client = client
        self._lock = threading.Lock()
        self._sent: tuple[np.ndarray, np.ndarray] | None = None
        self._arrived = False
        self.moved_by_person = False
        self.held = False
        """The app put the camera where stepping must not move it (the 3D view)."""
        self.on_measured: Callable[[], None] | None = None
        """Called once, when the browser first reports the canvas's size (a frame framed before
        then assumed ``layouts.SCREEN``)."""
        self._measured = False
        client.camera.near = NEAR
        client.camera.on_update(self._reported)
        move_camera(client, TOP_DOWN["position"], TOP_DOWN["look_at"])

    @property
    def arrived(self) -> bool:
        """Whether the browser has reported the camera where the app last put it."""
        return self._arrived

    @property
    def canvas(self) -> Canvas:
        return framing.canvas_of(self.client.camera)

    def move(self, position: tuple[float, ...], look_at: tuple[float, ...], held: bool = False) -> None:
        """Put the camera at ``position`` looking at ``look_at`` (``held``: stepping leaves it there)."""
        with self._lock:
            self._sent = (np.asarray(position, float), np.asarray(look_at, float))
            self._arrived = self.moved_by_person = False
            self.held = held
        move_camera(self.client, position, look_at)

    def frame(self, drawing: Drawing, view: ViewOptions, covered: Area | None, oblique: bool = False) -> float | None:
        """The tab's default camera on ``drawing``: what matters framed in the free part of the canvas
        (presentation mode: over the agents; ``oblique``: the 3D view of the layout, held). Returns
        the metres per pixel to spread the labels at (None: the camera's own)."""
        if oblique:
            start = OBLIQUE
            self.move(*over_layout(start["position"], start["look_at"], drawing.centre_y,
                                   screen_of(self.client.camera)), held=True)
            return None
        if view.presentation and drawing.agents:
            self.move(*camera_over(drawing.agents, self.client.camera.fov))
            return None
        pose, scale = self._framed(drawing, covered)
        self.move(*pose)
        return scale

    def _framed(self, drawing: Drawing, covered: Area | None) -> tuple[tuple[tuple[float, ...], ...], float]:
        """A camera framing ``drawing`` with its labels spread apart, and the metres per pixel they
        are spread at: no less than the camera's, so that it shows them apart. Spreading at a
        coarser scale stacks more labels, which may call for a higher camera: ``FRAMINGS`` rounds,
        each spreading at ``OVERSHOOT`` times the scale the last camera showed."""
        canvas = self.canvas
        areas = framing.free_areas(canvas, covered)
        pose = framing.frame(framing.spots_of(drawing), canvas, areas)
        scale = framing.metres_per_px(*pose, canvas)
        for _ in range(FRAMINGS):
            labels = spread(drawing.labels, scale, drawing.label_px)
            pose = framing.frame(framing.spots_of(drawing, labels), canvas, areas)
            shown = framing.metres_per_px(*pose, canvas)
            if shown <= scale:
                break
            scale = shown * OVERSHOOT
        return pose, scale

    def follow(self, drawing: Drawing, view: ViewOptions, covered: Area | None) -> float | None:
        """Stepping: frame ``drawing`` again only when something that matters would leave the free
        part of the canvas, *camera follows* is on, and neither a person nor the 3D view holds the
        camera. Returns what ``frame`` does (None when the camera stays)."""
        if not view.follow or self.moved_by_person or self.held:
            return None
        camera, canvas = self.client.camera, self.canvas
        position, look_at = tuple(camera.position), tuple(camera.look_at)
        labels = spread(drawing.labels, framing.metres_per_px(position, look_at, canvas), drawing.label_px)
        areas = framing.free_areas(canvas, covered, margin=0.0)
        if not framing.inside_one(framing.spots_of(drawing, labels), position, look_at, canvas, areas):
            return self.frame(drawing, view, covered)
        return None

    def _reported(self, camera: viser.CameraHandle) -> None:
        """A report of the browser's camera: the pose sent has arrived, or a person moved it since."""
        with self._lock:
            measured = not self._measured and camera.image_height > 0
            self._measured = self._measured or measured
            if self._sent is not None:
                here = np.allclose(camera.position, self._sent[0], atol=ARRIVED_M) and \
                    np.allclose(camera.look_at, self._sent[1], atol=ARRIVED_M)
                self.moved_by_person = not here and (self._arrived or self.moved_by_person)
                self._arrived = self._arrived or here
        if measured and self.on_measured is not None and not self.moved_by_person:
            self.on_measured()
