"""One tab's 3D scene: a fixed set of nodes (one per group of boxes or lines) whose arrays are
replaced on each redraw, all in one atomic message batch. A node whose content is what it last
sent is left alone, so a redraw sends (and the browser rebuilds) only what changed."""
from __future__ import annotations

import hashlib
from collections import Counter
from collections.abc import Hashable

import numpy as np
import viser

from cbm import se2

from . import framing
from .captions import LABEL_PX
from .drawing import Drawing, Lines, Mesh
from .framing import Area
from .labelling import lay_out, screen_bounds, size_px
from .pairs import Labels, Room
from .points import POINT_SIZE, PointCloud

_DUMMY_VERTICES = np.zeros((3, 3), np.float32)
_DUMMY_FACES = np.array([[0, 1, 2]], np.uint32)
_DUMMY_SEGMENTS = np.zeros((1, 2, 3), np.float32)
VISER_LABEL_PX = 12.0
"""Height in CSS pixels of viser's screen-space label text at ``font_screen_scale`` 1."""
LEADERS = "label_leaders"
"""The node of the lines from labels moved off their thing's side back to it."""
LEADER_COLOUR = (120, 120, 120)


def fingerprint(arrays: tuple[np.ndarray, ...], *style: Hashable) -> Hashable:
    """What a node shows, in a few bytes: the arrays' shapes and a digest of their contents (the
    arrays of a scene are at most a few hundred kB), and its style (colour, opacity, thickness)."""
    digest = hashlib.blake2b(digest_size=16)
    for array in arrays:
        digest.update(np.ascontiguousarray(array).view(np.uint8).data)
    return tuple(a.shape for a in arrays), digest.digest(), style


def _place(handle: viser.SceneNodeHandle, pose: np.ndarray) -> None:
    """Move a node to the SE(2) ``pose`` (viser sends nothing when it is where it was)."""
    yaw = se2.yaw_of(pose)
    handle.position = (*se2.translation_of(pose), 0.0)
    handle.wxyz = (np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2))


class SceneView:
    """The nodes of one client's scene, created once and updated in place."""

    def __init__(self, client: viser.ClientHandle, root: str = "/scene", labels_root: str = "/labels") -> None:
        self.client, self.root, self.labels_root = client, root, labels_root
        self.meshes: dict[str, viser.MeshHandle] = {}
        self.lines: dict[str, viser.LineSegmentsHandle] = {}
        self.labels: dict[str, viser.LabelHandle] = {}
        self.clouds: dict[str, viser.PointCloudHandle] = {}
        self.shown: dict[str, Hashable] = {}
        """Fingerprint of what each node shows."""
        self.placed: dict[str, bytes] = {}
        """The SE(2) pose each placed node was last given (its bytes): the same pose is not set again."""
        self.written: dict[str, tuple] = {}
        """What each label was last given (text, position, scale): a visible one given the same is left alone."""
        self.updates: Counter[str] = Counter()
        """How often each node was created or changed (a redraw that leaves it alone does not count)."""
        self.label_px = LABEL_PX
        """Height of the labels' text in CSS pixels, as the last drawing shown asks."""
        self.wanted: Labels = {}
        """Every label to show, where it belongs (``lay_out`` sets each beside its thing on screen)."""
        self.room: Room = {}
        """Half extents of what each wanted label names."""
        self.kept: frozenset[str] = frozenset()
        """The wanted labels that show however crowded; the others may wait for a click (``hidden``)."""
        self.hidden: frozenset[str] = frozenset()
        """The labels the last layout found no free place for near their thing."""
        self.skipped: frozenset[str] = frozenset()
        """Wanted labels not to show for now (those of pairs out of view: an edge marker stands for them)."""
        self.scale = 0.0
        """Metres per pixel the labels were last laid out at."""
        self.area: Area | None = None
        """The part of the canvas the labels are to stay in where they can (None: anywhere)."""

    @property
    def node_names(self) -> set[str]:
        """Names of the nodes drawn so far (visible or not)."""
        return {h.name for h in (*self.meshes.values(), *self.lines.values(), *self.labels.values(),
                                 *self.clouds.values())}

    def show(self, drawing: Drawing, scale: float | None = None, extra: Labels | None = None,
             skipped: frozenset[str] = frozenset()) -> None:
        """Replace the scene's arrays with ``drawing``'s, leaving the nodes that show the same alone;
        the labels (and the ``extra`` ones, kept in place; none of ``skipped``) laid out at ``scale``
        metres per pixel (``lay_out``)."""
        with self.client.atomic():
            self._show_meshes(drawing.meshes)
            self._show_lines(drawing.lines)
            for name, cloud in drawing.points.items():
                if self._changed(name, fingerprint((cloud.points,), cloud.color)):
                    self._cloud(name, cloud)
            self.label_px = drawing.label_px
            self.room, self.kept, self.skipped = drawing.room, drawing.kept, skipped
            self._show_labels({**drawing.labels, **(extra or {})}, scale)

    def show_only(self, meshes: dict[str, Mesh], lines: dict[str, Lines],
                  labels: dict[str, tuple[str, tuple[float, float, float]]]) -> None:
        """Show these nodes and hide the view's others (a view whose set of nodes changes, such as
        the walkthrough's steps)."""
        with self.client.atomic():
            for name in set(self.meshes) - set(meshes):
                self._hide(self.meshes, name)
            for name in set(self.lines) - set(lines):
                self._hide(self.lines, name)
            self._show_meshes(meshes)
            self._show_lines(lines)
            self.room, self.kept, self.skipped = {}, frozenset(labels), frozenset()
            self._show_labels(labels)

    def hide_all(self) -> None:
        """Hide every node of the view (shown again by the next ``show`` or ``show_only``)."""
        with self.client.atomic():
            for handles in (self.meshes, self.lines, self.clouds, self.labels):
                for name in list(handles):
                    self._hide(handles, name)

    def place(self, name: str, pose: np.ndarray) -> None:
        """Stand mesh ``name`` (when drawn) at the SE(2) ``pose``: one pose update."""
        if name in self.meshes and self._moved(name, pose):
            _place(self.meshes[name], pose)

    @property
    def visible_names(self) -> set[str]:
        """Names of the view's nodes now shown."""
        handles = (*self.meshes.values(), *self.lines.values(), *self.clouds.values(), *self.labels.values())
        return {h.name for h in handles if h.visible}

    def _show_meshes(self, meshes: dict[str, Mesh]) -> None:
        for name, mesh in meshes.items():
            if self._changed(name, fingerprint((mesh.vertices, mesh.faces), mesh.color, mesh.opacity)):
                self._mesh(name, mesh)

    def _show_lines(self, lines: dict[str, Lines]) -> None:
        for name, line_set in lines.items():
            if self._changed(name, fingerprint((line_set.segments,), line_set.color, line_set.thickness)):
                self._lines(name, line_set)
            if line_set.pose is not None and self._moved(name, line_set.pose):
                _place(self.lines[name], line_set.pose)

    def _show_labels(self, labels: Labels, scale: float | None = None) -> None:
        """Show ``labels`` (hiding the others), laid out (``lay_out``)."""
        self.wanted = dict(labels)
        self.lay_out(scale)

    def set_extra(self, prefix: str, labels: Labels, skipped: frozenset[str] = frozenset()) -> None:
        """Replace the wanted labels named ``prefix``... by ``labels`` (kept where they are put), and
        show none of ``skipped`` for now."""
        self.wanted = {**{k: v for k, v in self.wanted.items() if not k.startswith(prefix)}, **labels}
        self.skipped = skipped

    def lay_out(self, scale: float | None = None) -> None:
        """Write every wanted label where ``labelling.lay_out`` puts it at ``scale`` metres per pixel
        (the scale a framing laid them out at), or the camera's as it stands when that is coarser:
        labels laid out at a coarser scale than the camera's show apart; hide the others, and draw the
        leader lines of the labels moved."""
        camera = self.client.camera
        here = framing.metres_per_px(tuple(camera.position), tuple(camera.look_at), framing.canvas_of(camera))
        self.scale = max(scale or 0.0, here)
        wanted = {name: label for name, label in self.wanted.items() if name not in self.skipped}
        canvas, area = framing.canvas_of(camera), self.area
        bounds = None if area is None else screen_bounds(tuple(camera.look_at), self.scale, canvas.width,
                                                         canvas.height, (area.left, area.top, area.right, area.bottom))
        laid = lay_out(wanted, self.scale, self.label_px, self.room, self.kept, bounds)
        self.hidden = laid.hidden
        for name in set(self.labels) - set(laid.labels):
            self.labels[name].visible = False
        for name, (text, (x, y, z)) in laid.labels.items():
            if name in laid.flush_right:
                self._write(name, text, (x, y - size_px(text, self.label_px)[0] * self.scale, z), "top-right")
            else:
                self._write(name, text, (x, y, z))
        if len(laid.leaders) or LEADERS in self.lines:
            leaders = Lines(laid.leaders, LEADER_COLOUR, 1.5)
            if self._changed(LEADERS, fingerprint((leaders.segments,), leaders.color, leaders.thickness)):
                self._lines(LEADERS, leaders)

    def _hide(self, handles: dict, name: str) -> None:
        """Hide node ``name``; forget what it showed, so that showing it again redraws it."""
        handles[name].visible = False
        self.shown.pop(name, None)

    def label(self, name: str, text: str, position: tuple[float, float, float],
              room: tuple[float, float] = (0.0, 0.0)) -> None:
        """Show (or move) the label ``name`` beside the thing at ``position`` (its half extents ``room``),
        as near as keeps it off the others."""
        self.wanted[name] = (text, position)
        self.room = {**self.room, name: room}
        self.lay_out(self.scale)

    def _write(self, name: str, text: str, position: tuple[float, float, float], anchor: str = "top-left") -> None:
        """Show (or move) the label ``name``, its text ``label_px`` high, its ``anchor`` at ``position``."""
        scale = self.label_px / VISER_LABEL_PX
        handle = self.labels.get(name)
        if not _differs(self.written, name, (text, position, scale, anchor)) and handle is not None and handle.visible:
            return
        if handle is None:
            self.labels[name] = self.client.scene.add_label(f"{self.labels_root}/{name}", text, position=position,
                                                            font_screen_scale=scale, anchor=anchor)
        else:
            handle.text, handle.position, handle.visible, handle.font_screen_scale = text, position, True, scale
            handle.anchor = anchor

    def hide_label(self, name: str) -> None:
        """Hide the label ``name`` (and forget it: a redraw does not show it again)."""
        self.wanted.pop(name, None)
        if name in self.labels:
            self.labels[name].visible = False

    def _moved(self, name: str, pose: np.ndarray) -> bool:
        """Whether node ``name`` is to stand elsewhere than the pose it was last given; remembers it."""
        return _differs(self.placed, name, np.ascontiguousarray(pose, dtype=float).tobytes())

    def _changed(self, name: str, shown: Hashable) -> bool:
        """Whether node ``name`` is to show something else than it does; remembers it."""
        if not _differs(self.shown, name, shown):
            return False
        self.updates[name] += 1
        return True

    def _mesh(self, name: str, mesh: Mesh) -> None:
        empty = len(mesh.faces) == 0
        vertices, faces = (_DUMMY_VERTICES, _DUMMY_FACES) if empty else (mesh.vertices, mesh.faces)
        handle = self.meshes.get(name)
        if handle is None:
            self.meshes[name] = self.client.scene.add_mesh_simple(
                f"{self.root}/{name}", vertices, faces, color=mesh.color, opacity=mesh.opacity, flat_shading=True,
                side="double", cast_shadow=False, receive_shadow=False, visible=not empty)
            return
        handle.vertices, handle.faces = vertices, faces
        handle.color, handle.opacity, handle.visible = mesh.color, mesh.opacity, not empty

    def _cloud(self, name: str, cloud: PointCloud) -> None:
        empty = len(cloud.points) == 0
        points = _DUMMY_VERTICES if empty else cloud.points
        handle = self.clouds.get(name)
        if handle is None:
            self.clouds[name] = self.client.scene.add_point_cloud(
                f"{self.root}/{name}", points, cloud.color, point_size=POINT_SIZE, precision="float32",
                visible=not empty)
            return
        handle.points, handle.colors, handle.visible = points, np.array(cloud.color, np.uint8), not empty

    def _lines(self, name: str, lines: Lines) -> None:
        empty = len(lines.segments) == 0
        points = _DUMMY_SEGMENTS if empty else lines.segments
        colors = np.broadcast_to(np.array(lines.color, np.uint8), points.shape).copy()
        handle = self.lines.get(name)
        if handle is None:
            self.lines[name] = self.client.scene.add_line_segments(
                f"{self.root}/{name}", points, colors, thickness=lines.thickness, thickness_units="screen",
                visible=not empty)
            return
        handle.points, handle.colors, handle.visible, handle.thickness = points, colors, not empty, lines.thickness


def _differs(given: dict, name: str, value: Hashable) -> bool:
    """Whether ``value`` differs from what ``given`` holds for ``name``; ``given`` holds it after."""
    if given.get(name) == value:
        return False
    given[name] = value
    return True
