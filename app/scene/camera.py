"""One tab's camera: framed on what matters (``framing``) when a frame is loaded, reset or jumped to;
while stepping, still unless something that matters would leave the view (the View tab's *camera
follows*); a camera a person moved stays where they put it until *reset camera*."""
from __future__ import annotations

import html
import math
import re
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import viser

from ..session.settings import ViewOptions
from . import focus, framing
from .deciding import Mark
from .framing import Area, Canvas
from .labelling import lay_out
from .layouts import move_camera, over_layout, screen_of
from .presentation import camera_over

if TYPE_CHECKING:
    from .drawing import Drawing

Pose = tuple[tuple[float, ...], tuple[float, ...]]

NEAR = 0.5
"""Metres to the camera's near clipping plane: depth precision enough to stack the footprints'
layers (``planes.STEP`` apart) seen from 100 m."""
TOP_DOWN = {"position": (5.0, 0.0, 60.0), "look_at": (8.0, 0.0, 0.0)}
"""The camera before the first frame: straight above the scene ahead of the ego."""
OBLIQUE = {"position": (-30.0, 0.0, 35.0), "look_at": (8.0, 0.0, 0.0)}
"""The 3D view: behind and above the ego, looking forward and down (about 43 degrees)."""
FRAMINGS, OVERSHOOT = 6, 1.2
"""Rounds of laying the labels out and framing them, and how much coarser than the last camera's
scale each round lays them out at (``TabCamera._framed``)."""
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


@dataclass(frozen=True)
class Aim:
    """Where the camera was put on a drawing: the metres per pixel its labels are laid out at (None:
    the camera's own), the part of the canvas it frames in, and the pairs left out of view."""

    scale: float | None
    area: Area | None = None
    away: tuple[Mark, ...] = ()


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
        self.on_moved: Callable[[], None] | None = None
        """Called on each report of a camera a person moved (the labels follow its scale)."""
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

    @property
    def pose(self) -> Pose:
        """Where the browser's camera stands and looks."""
        camera = self.client.camera
        return tuple(camera.position), tuple(camera.look_at)

    def frame(self, drawing: Drawing, view: ViewOptions, covered: Area | None, oblique: bool = False) -> Aim:
        """The tab's default camera on ``drawing``: what matters framed in the free part of the canvas
        (``focus``; presentation mode: over the agents; ``oblique``: the 3D view of the layout, held)."""
        if oblique:
            start = OBLIQUE
            self.move(*over_layout(start["position"], start["look_at"], drawing.centre_y,
                                   screen_of(self.client.camera)), held=True)
            return Aim(None)
        if view.presentation and drawing.agents:
            self.move(*camera_over(drawing.agents, self.client.camera.fov))
            return Aim(None)
        pose, aim = self._framed(drawing, covered)
        self.move(*pose)
        return aim

    def _framed(self, drawing: Drawing, covered: Area | None) -> tuple[Pose, Aim]:
        """A camera framing what ``focus`` chooses of ``drawing`` with its labels laid out, and the
        metres per pixel they are laid out at: the camera's, so that each label shows beside its
        thing. Laid out for a new camera, the labels may call for another: ``FRAMINGS`` rounds, then
        the coarser of the last two scales (labels laid out coarser than the camera's show apart)."""
        canvas = self.canvas
        areas = framing.free_areas(canvas, covered)
        shown, away = focus.choose(drawing, canvas, areas)
        spots = focus.base_spots(drawing, focus.READABLE)
        spots += [spot for mark in shown for spot in focus.mark_spots(drawing, mark, focus.READABLE)]
        around = focus.context(drawing, spots, canvas, areas)
        pose = framing.frame(spots + around, canvas, areas)
        area = focus.area_of(spots + around, pose, canvas, areas)
        for _ in range(FRAMINGS):
            scale = framing.metres_per_px(*pose, canvas)
            laid = lay_out(drawing.labels, scale, drawing.label_px, drawing.room, drawing.kept,
                           focus.bounds_of(pose, scale, canvas, area))
            spots = focus.framed_spots(drawing, shown, away, laid) + around
            if framing.inside_one(spots, *pose, canvas, areas):
                break
            pose = framing.frame(spots, canvas, areas)
            area = focus.area_of(spots, pose, canvas, areas)
        scale = max(scale, framing.metres_per_px(*pose, canvas))
        pose = framing.balanced(spots, pose, canvas, covered)
        return pose, Aim(scale, focus.area_of(spots, pose, canvas, areas),
                         tuple(focus.out_of_view(away, pose, canvas, covered)))

    def may_frame(self, view: ViewOptions) -> bool:
        """Whether a new result may move the camera: *camera follows* is on and neither a person nor
        the 3D view holds it."""
        return view.follow and not self.moved_by_person and not self.held

    def fly_to(self, drawing: Drawing, mark: Mark, covered: Area | None) -> Aim:
        """Frame one pair ``mark`` of ``drawing`` (its boxes and labels), as close as ``framing`` goes."""
        canvas = self.canvas
        areas = framing.free_areas(canvas, covered)
        pose = framing.frame(focus.mark_spots(drawing, mark, focus.READABLE), canvas, areas)
        self.move(*pose)
        return Aim(framing.metres_per_px(*pose, canvas), areas[0])

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
        elif self.moved_by_person and self.on_moved is not None:
            self.on_moved()
