"""What one browser tab shows of its results over the control panel: the scene (``SceneView``), the
camera that frames it, presentation mode's caption, the key numbers floating over the canvas, and
the label of a box clicked."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
import viser

from .panels.keynumbers import GAP, WIDTH, KeyNumbers
from .scene import picking, planes, presentation
from .scene.camera import TabCamera, key_numbers_area
from .scene.drawing import Drawing
from .scene.framing import Area
from .scene.view import SceneView
from .session.explorer import Outcome
from .session.settings import ViewOptions

Picked = Callable[[Outcome, Drawing, str, int], None]
"""Told of a click on an ego or CAV box: the outcome, its drawing, the group and the box's row."""


class Stage:
    """The scene and what floats over it, for one browser tab; ``picked`` hears of a box clicked."""

    def __init__(self, client: viser.ClientHandle, picked: Picked) -> None:
        self.client, self.picked = client, picked
        self.view = SceneView(client)
        self.camera = TabCamera(client)
        self.camera.on_measured = self.reset_camera
        self.caption = presentation.Caption(client)
        self.key_numbers = KeyNumbers(client.gui)
        self.shown: tuple[Outcome, Drawing] | None = None

    def show(self, outcome: Outcome, picture: Drawing, reframe: bool) -> None:
        """Draw a result (inside the client's batch), the camera framing it when ``reframe`` (a jump)
        or when it is the first, lays the boxes out anew or enters or leaves presentation mode, else
        following it."""
        first, last = not self.view.meshes, self.shown and self.shown[0].settings.view
        self.key_numbers.show(outcome)
        staged = presentation.restage(self.client, last, outcome.settings.view)
        relaid = last is not None and outcome.settings.view.layout != last.layout
        self.view.show(picture, self._aim(outcome, picture, reframe or relaid or staged or first))
        self.caption.show(outcome)
        if first:
            for name in picking.NODES:
                self.view.meshes[name].on_click(self._picked)
        self.shown = outcome, picture

    def reset_camera(self, oblique: bool = False) -> None:
        """Frame the frame on screen from straight above (presentation mode: over the two agents);
        ``oblique``: the 3D view, from behind and above the ego. The labels are spread apart again."""
        if self.shown is None:
            return
        outcome, picture = self.shown
        view = outcome.settings.view
        self.view.lay_out(self.camera.frame(picture, view, self._covered(view), oblique))

    def hide_click_label(self) -> None:
        self.view.hide_label("picked")

    def _covered(self, view: ViewOptions) -> Area | None:
        """The part of the canvas a floating panel covers: the key numbers' (none in presentation
        mode, whose camera frames the agents for a caption at the page's bottom left)."""
        if view.presentation:
            return None
        return key_numbers_area(self.key_numbers.handle.content, self.camera.canvas, GAP, WIDTH)

    def _aim(self, outcome: Outcome, picture: Drawing, reframe: bool) -> float | None:
        """Frame the result (``reframe``), else follow it; the metres per pixel to spread its labels at
        (None: the camera's)."""
        view, covered = outcome.settings.view, self._covered(outcome.settings.view)
        return (self.camera.frame if reframe else self.camera.follow)(picture, view, covered)

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
                        (float(boxes[index, 0]), float(boxes[index, 1]), planes.LABELS))
