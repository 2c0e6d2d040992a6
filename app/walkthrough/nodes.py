"""The walkthrough's scene nodes (under ``/walkthrough``): a step's meshes, line sets and labels
copied into viser nodes, the normal scene (``/scene``, ``/labels``) hidden meanwhile, and the
CAV's boxes placed by a pose so that an animation moves one node and sends nothing else."""
from __future__ import annotations

from collections.abc import Hashable

import numpy as np
import viser

from cbm import se2

from ..scene.drawing import Lines, Mesh
from ..scene.view import fingerprint
from .steps import Step

ROOT = "/walkthrough"
NORMAL_ROOTS = ("/scene", "/labels")
"""The parents of the normal scene's nodes: hidden while the walkthrough is on."""
CAV_NODE = "cav_boxes"


def placement(pose: np.ndarray) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """(position, wxyz) of a node standing at the SE(2) ``pose``."""
    yaw = se2.yaw_of(pose)
    x, y = se2.translation_of(pose)
    return (float(x), float(y), 0.0), (float(np.cos(yaw / 2)), 0.0, 0.0, float(np.sin(yaw / 2)))


def glide(start: np.ndarray, end: np.ndarray, steps: int) -> list[np.ndarray]:
    """``steps`` + 1 poses from ``start`` to ``end``: translation and yaw interpolated linearly
    (the yaw the short way round), eased in and out."""
    t0, t1 = se2.translation_of(start), se2.translation_of(end)
    yaw0 = se2.yaw_of(start)
    turn = float(se2.wrap_angle(se2.yaw_of(end) - yaw0))
    eased = [0.5 - 0.5 * np.cos(np.pi * k / steps) for k in range(steps + 1)]
    return [se2.make(*(t0 + s * (t1 - t0)), yaw0 + s * turn) for s in eased]


class WalkthroughNodes:
    """One client's walkthrough nodes, created on first use and updated in place."""

    def __init__(self, client: viser.ClientHandle) -> None:
        self.client = client
        self.meshes: dict[str, viser.MeshHandle] = {}
        self.lines: dict[str, viser.LineSegmentsHandle] = {}
        self.labels: dict[str, viser.LabelHandle] = {}
        self._shown: dict[str, Hashable] = {}
        self._normal: list[viser.FrameHandle] = []

    @property
    def visible_names(self) -> set[str]:
        """Names of the walkthrough's nodes now shown."""
        handles = (*self.meshes.values(), *self.lines.values(), *self.labels.values())
        return {h.name for h in handles if h.visible}

    def show(self, step: Step) -> None:
        """The scene of ``step``, the normal scene hidden; the CAV's boxes at ``step.cav_pose``."""
        with self.client.atomic():
            self._hide_normal(True)
            for name, mesh in step.meshes.items():
                self._mesh(name, mesh)
            self.place(step.cav_pose)
            for name, lines in step.lines.items():
                self._line_set(name, lines)
            for name in set(self.lines) - set(step.lines):
                self.lines[name].visible = False
            for name in set(self.meshes) - set(step.meshes):
                self.meshes[name].visible = False
            for name, (text, position) in step.labels.items():
                self._label(name, text, position)
            for name in set(self.labels) - set(step.labels):
                self.labels[name].visible = False

    def place(self, pose: np.ndarray) -> None:
        """Stand the CAV's boxes at ``pose`` (one pose update)."""
        handle = self.meshes.get(CAV_NODE)
        if handle is not None:
            handle.position, handle.wxyz = placement(pose)

    def hide(self) -> None:
        """Hide every walkthrough node and show the normal scene again."""
        with self.client.atomic():
            for handle in (*self.meshes.values(), *self.lines.values(), *self.labels.values()):
                handle.visible = False
            self._hide_normal(False)

    def _hide_normal(self, hidden: bool) -> None:
        if not self._normal:
            if not hidden:
                return
            self._normal = [self.client.scene.add_frame(root, show_axes=False) for root in NORMAL_ROOTS]
        for frame in self._normal:
            frame.visible = not hidden

    def _changed(self, name: str, shown: Hashable) -> bool:
        if self._shown.get(name) == shown:
            return False
        self._shown[name] = shown
        return True

    def _mesh(self, name: str, mesh: Mesh) -> None:
        handle = self.meshes.get(name)
        changed = self._changed(f"mesh/{name}", fingerprint((mesh.vertices, mesh.faces), mesh.color))
        if len(mesh.faces) == 0:
            if handle is not None:
                handle.visible = False
            return
        if handle is None:
            self.meshes[name] = self.client.scene.add_mesh_simple(
                f"{ROOT}/{name}", mesh.vertices, mesh.faces, color=mesh.color, flat_shading=True, side="double",
                cast_shadow=False, receive_shadow=False)
            return
        if changed:
            handle.vertices, handle.faces, handle.color = mesh.vertices, mesh.faces, mesh.color
        handle.visible = True

    def _line_set(self, name: str, lines: Lines) -> None:
        handle = self.lines.get(name)
        changed = self._changed(f"lines/{name}", fingerprint((lines.segments,), lines.color, lines.thickness))
        if len(lines.segments) == 0:
            if handle is not None:
                handle.visible = False
            return
        colors = np.broadcast_to(np.array(lines.color, np.uint8), lines.segments.shape).copy()
        if handle is None:
            self.lines[name] = self.client.scene.add_line_segments(
                f"{ROOT}/{name}", lines.segments, colors, thickness=lines.thickness, thickness_units="screen")
            return
        if changed:
            handle.points, handle.colors, handle.thickness = lines.segments, colors, lines.thickness
        handle.visible = True

    def _label(self, name: str, text: str, position: tuple[float, float, float]) -> None:
        handle = self.labels.get(name)
        if handle is None:
            self.labels[name] = self.client.scene.add_label(f"{ROOT}/labels/{name}", text, position=position)
        else:
            handle.text, handle.position, handle.visible = text, position, True
