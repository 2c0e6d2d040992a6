"""What one browser tab shows of its results over the control panel: the scene (``SceneView``), the
camera that frames it, presentation mode's caption, the key numbers floating over the canvas, the
label of a box clicked, and the markers at the canvas's edge pointing to pairs out of view."""
from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import viser

from .panels.keynumbers import GAP, WIDTH, KeyNumbers
from .scene import focus, framing, picking, planes, presentation
from .scene.camera import Aim, TabCamera, key_numbers_area
from .scene.deciding import Mark
from .scene.drawing import Drawing
from .scene.framing import Area
from .scene.pairs import Labels, half_extents
from .scene.view import SceneView
from .session.coalesce import Later
from .session.explorer import Outcome
from .session.settings import ViewOptions

Picked = Callable[[Outcome, Drawing, str, int], None]
"""Told of a click on an ego or CAV box: the outcome, its drawing, the group and the box's row."""
Away = Callable[[tuple[Mark, ...]], None]
"""Told of the pairs a framing left out of view (the panel lists them)."""
EDGE = "edge_"
"""The names of the edge markers' labels."""
RELAY_S = 0.25
"""Seconds after a person last moved the camera before the labels and edge markers follow it."""


class Stage:
    """The scene and what floats over it, for one browser tab; ``picked`` hears of a box clicked,
    ``away`` of the pairs a framing left out of view."""

    def __init__(self, client: viser.ClientHandle, picked: Picked, away: Away = lambda marks: None) -> None:
        self.client, self.picked, self.away = client, picked, away
        self.shown: tuple[Outcome, Drawing] | None = None
        self.aim = Aim(None)
        """The last framing: its scale, area and the pairs it left out."""
        self._lock = threading.RLock()
        """Held while the scene or the camera changes: a result shown, a reset, a flight, a person's move."""
        self._later = Later(RELAY_S)
        self._closed = False
        self.view = SceneView(client)
        self.camera = TabCamera(client)
        self.camera.on_measured = self.reset_camera
        self.camera.on_moved = lambda: self._later.call(self._follow_person)
        self.caption = presentation.Caption(client)
        self.key_numbers = KeyNumbers(client.gui)

    def show(self, outcome: Outcome, picture: Drawing, reframe: bool) -> None:
        """Draw a result (inside the client's batch), the camera framing it (``focus``) unless a person
        or the 3D view holds it or *camera follows* is off; framed anyway when ``reframe`` (a jump), when
        it is the first, lays the boxes out anew or enters or leaves presentation mode."""
        with self._lock:
            first, last = not self.view.meshes, self.shown and self.shown[0].settings.view
            self.key_numbers.show(outcome)
            staged = presentation.restage(self.client, last, outcome.settings.view)
            relaid = last is not None and outcome.settings.view.layout != last.layout
            view = outcome.settings.view
            if reframe or relaid or staged or first or self.camera.may_frame(view):
                self.aim = self.camera.frame(picture, view, self._covered(view))
            else:
                self.aim = Aim(None, self.aim.area, tuple(self._out_of_view(picture, view)))
            self.view.area = self.aim.area if self.aim.scale else self._canvas_area()
            self.view.show(picture, self.aim.scale, *self._edges(picture, view))
            self.caption.show(outcome)
            if first:
                for name in picking.NODES:
                    self.view.meshes[name].on_click(self._picked)
            self.shown = outcome, picture
            self.away(self.aim.away)

    def reset_camera(self, oblique: bool = False) -> None:
        """Frame the frame on screen from straight above (presentation mode: over the two agents);
        ``oblique``: the 3D view, from behind and above the ego. The labels are laid out again."""
        with self._lock:
            if self.shown is None:
                return
            outcome, picture = self.shown
            view = outcome.settings.view
            self.aim = self.camera.frame(picture, view, self._covered(view), oblique)
            self.view.area = self.aim.area
            self.view.set_extra(EDGE, *self._edges(picture, view))
            self.view.lay_out(self.aim.scale)
            self.away(self.aim.away)

    def fly_to(self, key: str) -> None:
        """Frame the pair ``key`` (``deciding.Mark.key``) of the frame on screen."""
        with self._lock:
            if self.shown is None:
                return
            outcome, picture = self.shown
            mark = next((m for m in picture.marks if m.key == key), None)
            if mark is None:
                return
            covered = self._covered(outcome.settings.view)
            flown = self.camera.fly_to(picture, mark, covered)
            self.aim = Aim(flown.scale, flown.area, self.aim.away)
            self.view.area = flown.area
            self.view.set_extra(EDGE, *self._edges(picture, outcome.settings.view))
            self.view.lay_out(flown.scale)

    def _out_of_view(self, picture: Drawing, view: ViewOptions) -> list[Mark]:
        """The pairs of ``picture`` not wholly in sight through the camera as it stands."""
        return focus.out_of_view(picture.marks, self.camera.pose, self.camera.canvas, self._covered(view))

    def _edges(self, picture: Drawing, view: ViewOptions) -> tuple[Labels, frozenset[str]]:
        """The edge markers of the pairs out of view through the camera as it stands, and those pairs'
        own labels, not shown meanwhile (neither in the 3D view or presentation mode, whose cameras
        frame otherwise)."""
        if self.aim.area is None or self.camera.held or view.presentation:
            return {}, frozenset()
        away = self._out_of_view(picture, view)
        markers = focus.edge_labels(away, self.camera.pose, self.camera.canvas, self._covered(view),
                                    picture.label_px, planes.LABELS)
        return markers, frozenset(label for mark in away for label in mark.labels)

    def close(self) -> None:
        """No more follow-ups of a person's camera moves: the tab's scene is about to be removed (another
        dataset, or the tab closed), and a layout then would write to removed labels."""
        with self._lock:
            self._closed = True
            self._later.close()

    def _follow_person(self) -> None:
        """A person moved the camera: the labels are laid out for its scale and the edge markers point
        from where it stands."""
        with self._lock:
            if self._closed or self.shown is None:
                return
            outcome, picture = self.shown
            self.view.area = self._canvas_area()
            self.view.set_extra(EDGE, *self._edges(picture, outcome.settings.view))
            self.view.lay_out()

    def _canvas_area(self) -> Area:
        """The whole canvas, less the framing's margin: where labels stay under a camera a person moved."""
        canvas = self.camera.canvas
        return Area(0.0, 0.0, canvas.width, canvas.height).inset(framing.MARGIN_PX)

    def hide_click_label(self) -> None:
        self.view.hide_label("picked")

    def _covered(self, view: ViewOptions) -> Area | None:
        """The part of the canvas a floating panel covers: the key numbers' (none in presentation
        mode, whose camera frames the agents for a caption at the page's bottom left)."""
        if view.presentation:
            return None
        return key_numbers_area(self.key_numbers.handle.content, self.camera.canvas, GAP, WIDTH)

    def _picked(self, event: viser.SceneNodePointerEvent) -> None:
        """Label the object under a click (the ray meets the plane of the footprints) and, for the ego's
        and the first CAV's (the pair CBM's inspection holds), tell ``picked``."""
        origin, direction = np.asarray(event.ray_origin), np.asarray(event.ray_direction)
        if self.shown is None or abs(direction[2]) < 1e-9:
            return
        outcome, picture = self.shown
        point = origin + direction * (planes.EGO - origin[2]) / direction[2]
        found = picking.pick(picture, point[:2])
        if found is None or not outcome.settings.view.labels:
            self.view.hide_label("picked")
        if found is None:
            return
        group, index = found
        if group in ("ego", "cav"):
            self.picked(outcome, picture, group, int(picture.objects[group][1][index]))
        if not outcome.settings.view.labels:
            return
        boxes, _ = picture.objects[group]
        self.view.label("picked", picking.describe(outcome, picture, group, index),
                        (float(boxes[index, 0]), float(boxes[index, 1]), planes.LABELS), half_extents(boxes[index]))
