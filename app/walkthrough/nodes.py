"""The walkthrough's scene nodes (under ``/walkthrough``): a step's meshes, line sets and labels
copied into viser nodes, the normal scene (``/scene``, ``/labels``) hidden meanwhile, and the
CAV's boxes, vehicle and label placed by a pose so that an animation moves three nodes and sends
nothing else. Lines show the colours the steps' words name (``scene.linecolours``)."""
from __future__ import annotations

import dataclasses

import numpy as np
import viser

from cbm import se2

from ..scene.linecolours import as_shown
from ..scene.view import SceneView
from .shapes import CAV_LABEL, cav_label
from .steps import Step

ROOT = "/walkthrough"
NORMAL_ROOTS = ("/scene", "/labels")
"""The parents of the normal scene's nodes: hidden while the walkthrough is on."""
CAV_NODE = "cav_boxes"
CAV_NODES = (CAV_NODE, "cav_vehicle")
"""The nodes given in the CAV's frame, placed by a pose (its boxes and its vehicle)."""


def glide(start: np.ndarray, end: np.ndarray, steps: int) -> list[np.ndarray]:
    """``steps`` + 1 poses from ``start`` to ``end``: translation and yaw interpolated linearly
    (the yaw the short way round), eased in and out."""
    t0, t1 = se2.translation_of(start), se2.translation_of(end)
    yaw0 = se2.yaw_of(start)
    turn = float(se2.wrap_angle(se2.yaw_of(end) - yaw0))
    eased = [0.5 - 0.5 * np.cos(np.pi * k / steps) for k in range(steps + 1)]
    return [se2.make(*(t0 + s * (t1 - t0)), yaw0 + s * turn) for s in eased]


class WalkthroughNodes:
    """One client's walkthrough nodes: a ``SceneView`` under ``/walkthrough``, and the normal
    scene's parents, hidden while a step is shown."""

    def __init__(self, client: viser.ClientHandle) -> None:
        self.client = client
        self.view = SceneView(client, ROOT, f"{ROOT}/labels")
        self._normal: list[viser.FrameHandle] = []

    @property
    def meshes(self) -> dict[str, viser.MeshHandle]:
        return self.view.meshes

    @property
    def visible_names(self) -> set[str]:
        """Names of the walkthrough's nodes now shown."""
        return self.view.visible_names

    def show(self, step: Step) -> None:
        """The scene of ``step``, the normal scene hidden; the CAV's boxes at ``step.cav_pose``."""
        with self.client.atomic():
            self._hide_normal(True)
            lines = {name: dataclasses.replace(line, color=as_shown(line.color)) for name, line in step.lines.items()}
            self.view.show_only(step.meshes, lines, step.labels)
            self.place(step.cav_pose)

    def place(self, pose: np.ndarray) -> None:
        """Stand the CAV's boxes, vehicle and label at ``pose`` (an update each)."""
        for name in CAV_NODES:
            self.view.place(name, pose)
        self.view.label(CAV_LABEL, *cav_label(pose))

    def hide(self) -> None:
        """Hide every walkthrough node and show the normal scene again."""
        with self.client.atomic():
            self.view.hide_all()
            self._hide_normal(False)

    def _hide_normal(self, hidden: bool) -> None:
        if not self._normal:
            if not hidden:
                return
            self._normal = [self.client.scene.add_frame(root, show_axes=False) for root in NORMAL_ROOTS]
        for frame in self._normal:
            frame.visible = not hidden
