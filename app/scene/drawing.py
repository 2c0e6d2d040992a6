"""What one outcome looks like: the arrays of every scene node, in the ego frame (x forward, y left).

A ``Drawing`` is plain data (meshes, line sets, labels, the metrics text), so the session logic can
be tested without a browser and the viser layer (``view``) only copies arrays into nodes.
"""
from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np

from cbm import se2
from evaluation.clutter import is_false
from loaders import Frame, is_roadside

from ..session.explorer import Outcome
from ..session.settings import MAX_CAVS
from . import captions, cavs, colours, deciding, geometry, pairs, planes, seen
from .layouts import LAYOUTS, TITLE_AT, Panel
from .memo import ByContent
from .points import PointCloud, clouds, problems_markdown
from .text import metrics_markdown

MOST_PANELS = 2
"""The most copies of the scene a layout draws (side by side): each copy has its own map nodes."""
_footprint_mesh, _vehicle_mesh = ByContent(geometry.footprint_mesh), ByContent(geometry.vehicle_mesh)
_outline_segments, _cross_segments = ByContent(geometry.outline_segments), ByContent(geometry.cross_segments)
"""The geometry of boxes and vehicles, taken from an earlier drawing when they have not moved."""


@dataclass(frozen=True)
class Mesh:
    vertices: np.ndarray
    faces: np.ndarray
    color: tuple[int, int, int]
    opacity: float | None = None


@dataclass(frozen=True)
class Lines:
    segments: np.ndarray
    """(N, 2, 3) float32."""
    color: tuple[int, int, int]
    thickness: float = 2.0
    pose: np.ndarray | None = None
    """(3, 3) SE(2) placing the segments, given in a frame of their own, in the scene (the map: its
    arrays stay the same from frame to frame, only this pose moves); None: in the scene's frame."""


@dataclass(frozen=True)
class Drawing:
    meshes: dict[str, Mesh]
    lines: dict[str, Lines]
    labels: dict[str, tuple[str, tuple[float, float, float]]]
    metrics_markdown: str
    objects: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    """(boxes (N, 7) as drawn, index into the trial's list) by group, for picking: ``ego``, then each
    CAV's (``cav``, ``cav_2``, ... ``cavs.node("cav", rank)``, its trial's list), lowest layer first."""
    centre_y: float = 0.0
    """Sideways middle of the panels the layout shows (where the camera looks on reset)."""
    agents: tuple[tuple[float, float], ...] = ()
    """(x, y) of every vehicle drawn, ego and CAV of each panel (what the presentation camera frames)."""
    label_px: float = captions.LABEL_PX
    """Height of the labels' text in CSS pixels."""
    points: dict[str, PointCloud] = field(default_factory=dict)
    """The agents' LiDAR points (``ego_points``, ``cav_points``; empty unless the view asks for them)."""
    room: pairs.Room = field(default_factory=dict)
    """Half extents of what each label names (``labelling.lay_out`` sets the label beside it)."""
    kept: frozenset[str] = frozenset()
    """The labels the picture must show however crowded (the agents', the titles, the deciding pairs')."""
    marks: tuple[deciding.Mark, ...] = ()
    """The pairs the camera is to show, most telling first (``deciding``)."""


@dataclass
class _Parts:
    """Everything the copies of the scene contribute, gathered before it is joined into nodes."""

    ego: list[np.ndarray] = field(default_factory=list)
    tiles: dict[int, list[np.ndarray]] = field(default_factory=lambda: defaultdict(list))
    """Each CAV's boxes as drawn (what a click picks), by rank."""
    before: list[np.ndarray] = field(default_factory=list)
    ghosts: list[np.ndarray] = field(default_factory=list)
    false_boxes: list[np.ndarray] = field(default_factory=list)
    """Every agent's false boxes as drawn (crossed out while the ghosts show: no object is there)."""
    ego_poses: list[np.ndarray] = field(default_factory=list)
    cav_poses: dict[int, list[np.ndarray]] = field(default_factory=lambda: defaultdict(list))
    """Each CAV's vehicle poses, by rank."""
    before_poses: list[np.ndarray] = field(default_factory=list)
    shapes: list[pairs.PairShapes] = field(default_factory=list)
    labels: dict[str, tuple[str, tuple[float, float, float]]] = field(default_factory=dict)
    room: pairs.Room = field(default_factory=dict)
    marks: list[deciding.Mark] = field(default_factory=list)
    ranked: dict[int, list[deciding.Ranked]] = field(default_factory=dict)
    """Each CAV's pairs in the camera's order (``deciding.ranked_pairs``), found once for every copy."""
    map_poses: list[np.ndarray] = field(default_factory=list)
    roadside: set[int] = field(default_factory=set)
    """The ranks of the CAVs that are roadside units (drawn as a mast, not a car)."""
    fused_tp: list[np.ndarray] = field(default_factory=list)
    fused_fp: list[np.ndarray] = field(default_factory=list)


def draw(outcome: Outcome, map_segments: dict[str, np.ndarray], frame: Frame | None = None) -> Drawing:
    """The scene of ``outcome`` under its view options (``frame``: the dataset frame, for its LiDAR points)."""
    layout = LAYOUTS[outcome.settings.view.layout]
    panels = layout.panels(outcome)
    view = outcome.settings.view
    palette = colours.palette(view)
    parts = _Parts()
    for panel in panels:
        _add_panel(parts, outcome, panel, layout.before_ghosts, palette)
    ego = np.concatenate(parts.ego)
    objects = _objects(outcome, parts, ego, len(panels))
    lines = {**_lines(parts, palette), **_map_lines(map_segments, parts.map_poses, palette)}
    agents = tuple(tuple(map(float, se2.translation_of(pose)))
                   for pose in (*parts.ego_poses, *(p for poses in parts.cav_poses.values() for p in poses)))
    points = clouds(frame if view.points else None, (outcome.ego_id, outcome.cav_id),
                    (parts.ego_poses, parts.cav_poses[1]), view.points_every, (palette.ego_boxes, palette.cav_boxes))
    moved, moved_labels = seen.motion(outcome, panels)
    sights = _sights(seen.sight_fans(outcome, panels), palette)
    lines.update({**sights[1], "moved": Lines(moved, palette.cav_vehicle, 2.0)})
    labels = {**parts.labels, **{k: v for shapes in parts.shapes for k, v in shapes.labels.items()}, **moved_labels}
    room = {**parts.room, **{k: v for shapes in parts.shapes for k, v in shapes.room.items()}}
    marks = deciding.merged(parts.marks)
    kept = ({name for name in parts.labels} | set(moved_labels)
            | {name for mark in marks if mark.deciding for name in mark.labels})
    return Drawing(meshes={**_meshes(parts, ego, palette), **sights[0]}, lines=lines, labels=labels,
                   metrics_markdown=metrics_markdown(outcome) + problems_markdown(points), objects=objects,
                   centre_y=float(np.mean([panel.offset[1] for panel in panels])),
                   agents=agents, label_px=captions.label_px(view), points=points, room=room,
                   kept=frozenset(kept), marks=marks)


def _add_panel(parts: _Parts, outcome: Outcome, panel: Panel, before_ghosts: bool, palette: colours.Palette) -> None:
    """One copy of the scene: boxes, vehicles, ghosts, every CAV's boxes, vehicle, label and match
    lines, and where the map goes, shifted by its offset."""
    view, trial, offset = outcome.settings.view, outcome.trial, panel.offset
    where = outcome.placements
    shift = se2.make(offset[0], offset[1], 0.0)
    ego = pairs.Drawn(_shifted(trial.ego_boxes, offset), trial.ego_ids)
    parts.ego.append(ego.boxes)
    parts.ego_poses.append(shift)
    parts.labels[f"ego_{panel.placement}"] = ("ego", (*se2.translation_of(shift), planes.LABELS))
    parts.room[f"ego_{panel.placement}"] = _vehicle_room(shift, geometry.CAR_SIZE)
    if panel.title:
        parts.labels[panel.placement] = (panel.title, (TITLE_AT, float(panel.offset[1]), planes.LABELS))
    shown = cavs.every_cav(outcome)
    for cav in shown:
        _add_cav(parts, cav, len(shown), panel, ego, view.lines, palette)
    if before_ghosts:
        parts.before.append(se2.apply_boxes(where["before"], trial.cav_boxes))
        parts.before_poses.append(where["before"])
    if view.ghosts:
        seen = np.isin(outcome.world_ids, np.concatenate([trial.ego_ids, trial.cav_ids]))
        parts.ghosts.append(_shifted(outcome.world_boxes[seen], offset))
        drawn = (ego, *(cavs.drawn_cav(cav, panel.placement, offset) for cav in shown))
        parts.false_boxes.extend(d.boxes[is_false(d.ids)] for d in drawn)
    parts.map_poses.append(shift @ se2.inverse(trial.ego_pose))
    if view.fused:
        fused = outcome.fused(panel.placement)
        parts.fused_tp.append(_shifted(fused.boxes[fused.hits], offset))
        parts.fused_fp.append(_shifted(fused.boxes[~fused.hits], offset))


def _add_cav(parts: _Parts, cav: cavs.ShownCav, count: int, panel: Panel, ego: pairs.Drawn, lines: bool,
             palette: colours.Palette) -> None:
    """One CAV in one copy of the scene: its boxes as drawn, its vehicle and label, and (``lines``)
    its pairs between the boxes drawn (``pairs.pair_shapes``)."""
    drawn = cavs.drawn_cav(cav, panel.placement, panel.offset)
    pose = se2.make(panel.offset[0], panel.offset[1], 0.0) @ cav.placements[panel.placement]
    name = cavs.name(cav.rank, count, cav.cav_id)
    if is_roadside(cav.cav_id):
        parts.roadside.add(cav.rank)
    parts.tiles[cav.rank].append(drawn.boxes)
    parts.cav_poses[cav.rank].append(pose)
    label = f"{cavs.node('cav', cav.rank)}_{panel.placement}"
    parts.labels[label] = (name, (*se2.translation_of(pose), planes.LABELS))
    parts.room[label] = _vehicle_room(pose, _body(parts, cav.rank))
    if lines:
        partners = cavs.drawn_partners(cav, ego, panel.offset) if cav.rank > 1 else ego
        key = f"{cavs.node('pairs', cav.rank)}_{panel.placement}"
        shapes = pairs.pair_shapes(cav.pairs, cav.trial.gt_pairs, partners, drawn, palette, name, key)
        parts.shapes.append(shapes)
        if cav.rank not in parts.ranked:
            parts.ranked[cav.rank] = deciding.ranked_pairs(cav)
        parts.marks.extend(deciding.marks_of(parts.ranked[cav.rank], cav, name, partners, drawn, shapes.labels, key))


def _objects(outcome: Outcome, parts: _Parts, ego: np.ndarray, copies: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """What a click can pick: the ego's boxes and every CAV's, as drawn in every copy of the scene,
    with each box's index into its trial's list."""
    objects = {"ego": (ego, np.tile(np.arange(len(outcome.trial.ego_boxes)), copies))}
    for cav in cavs.every_cav(outcome):
        objects[cavs.node("cav", cav.rank)] = (np.concatenate(parts.tiles[cav.rank]),
                                               np.tile(np.arange(len(cav.trial.cav_boxes)), copies))
    return objects


def _meshes(parts: _Parts, ego: np.ndarray, palette: colours.Palette) -> dict[str, Mesh]:
    """Boxes as their footprints, flat in the plane of comparison (``planes``), each CAV's in its
    colour; vehicles as small bodies (empty nodes for the CAVs the outcome lacks: hidden)."""
    meshes = {"ego_boxes": Mesh(*_footprint_mesh(ego, planes.EGO), palette.ego_boxes),
              "ego_vehicle": Mesh(*_vehicle_mesh(parts.ego_poses), palette.ego_vehicle),
              "cav_vehicle_before": Mesh(*_vehicle_mesh(parts.before_poses, *_body(parts, 1)), palette.cav_vehicle,
                                         opacity=0.3)}
    for rank in range(1, MAX_CAVS + 1):
        tiles = np.concatenate(parts.tiles[rank]) if parts.tiles[rank] else np.zeros((0, 7))
        meshes[cavs.node("cav_boxes", rank)] = Mesh(*_footprint_mesh(tiles, planes.cav(rank)),
                                                    cavs.box_colour(rank, palette))
        meshes[cavs.node("cav_vehicle", rank)] = Mesh(*_vehicle_mesh(parts.cav_poses[rank], *_body(parts, rank)),
                                                      cavs.vehicle_colour(rank, palette))
    return meshes


def _sights(fans: dict[str, seen.Fan], palette: colours.Palette) -> tuple[dict[str, Mesh], dict[str, Lines]]:
    """Each agent's sight as a translucent fill and its edge, in the agent's colour."""
    colour = {"ego": palette.ego_boxes, "cav": palette.cav_boxes}
    return ({seen.sight_node(role): Mesh(v, f, colour[role], opacity=seen.SIGHT_OPACITY)
             for role, (v, f, _) in fans.items()},
            {seen.sight_node(role, "sight_edge"): Lines(edge, colour[role], 1.5)
             for role, (_, _, edge) in fans.items()})


def _vehicle_room(pose: np.ndarray, size: tuple[float, ...]) -> tuple[float, float]:
    """The half extents of a vehicle of ``size`` standing at ``pose``, for its label."""
    x, y = se2.translation_of(pose)
    return pairs.half_extents(np.array([x, y, 0.0, size[0], size[1], size[2], se2.yaw_of(pose)]))


def _body(parts: _Parts, rank: int) -> tuple[float, ...]:
    """The size (length, width, height) of CAV ``rank``'s body: a mast for a roadside unit, else a car's."""
    return geometry.ROADSIDE_SIZE if rank in parts.roadside else geometry.CAR_SIZE


def _lines(parts: _Parts, palette: colours.Palette) -> dict[str, Lines]:
    """Match lines and the marks of wrong and missed pairs (every CAV's); outlines of the CAV's
    boxes where ``init`` put them and of the ground truth; a cross over each false box (with the ghosts)."""
    strokes = {"right": palette.right, "wrong": palette.wrong, "missed": palette.missed}
    marks = {"wrong_marks": (palette.wrong.color, 3.0), "missed_marks": (palette.missed.color, 2.0)}
    return {**{name: Lines(_joined([getattr(p, name) for p in parts.shapes]), s.color, s.thickness)
               for name, s in strokes.items()},
            **{name: Lines(_joined([getattr(p, name) for p in parts.shapes]), colour, width)
               for name, (colour, width) in marks.items()},
            "cav_before": Lines(_outlines(parts.before, planes.OUTLINES), palette.cav_before, 1.5),
            "ghosts": Lines(_outlines(parts.ghosts, planes.OUTLINES), palette.ghost, 1.5),
            "false_marks": Lines(_crosses(parts.false_boxes), palette.ghost, 1.5),
            "fused_tp": Lines(_outlines(parts.fused_tp, planes.FUSED), palette.right.color, 3.0),
            "fused_fp": Lines(_outlines(parts.fused_fp, planes.FUSED), palette.wrong.color, 3.0)}


def _map_lines(map_segments: dict[str, np.ndarray], poses: list[np.ndarray],
               palette: colours.Palette) -> dict[str, Lines]:
    """A node per kind of map line and copy of the scene (``map_<kind>``, ``map_<kind>_2``): the
    world's segments about a fixed point of the map, placed by the copy's world->scene ``pose``;
    empty for a copy the layout does not draw."""
    if not map_segments:
        return {}
    origin = next(iter(map_segments.values()))[0, 0]
    nodes = {}
    for kind, segments in map_segments.items():
        local, colour = _lift(segments - origin), palette.map.get(kind, palette.map_other)
        for k in range(MOST_PANELS):
            name = f"map_{kind}" if k == 0 else f"map_{kind}_{k + 1}"
            shown = k < len(poses)
            nodes[name] = Lines(local if shown else no_lines(), colour, 1.0,
                                pose=poses[k] @ se2.make(origin[0], origin[1], 0.0) if shown else None)
    return nodes


def _shifted(boxes: np.ndarray, offset: np.ndarray) -> np.ndarray:
    out = boxes.copy()
    out[:, :2] += offset
    return out


def no_lines() -> np.ndarray:
    """An empty (0, 2, 3) segment array."""
    return np.zeros((0, 2, 3), np.float32)


def _outlines(parts: list[np.ndarray], z: float) -> np.ndarray:
    return _outline_segments(np.concatenate(parts), z) if parts else no_lines()


def _crosses(parts: list[np.ndarray]) -> np.ndarray:
    return _cross_segments(np.concatenate(parts), planes.OUTLINES) if parts else no_lines()


def _joined(parts: list[np.ndarray]) -> np.ndarray:
    return np.concatenate(parts) if parts else no_lines()


def _lift(segments2d: np.ndarray) -> np.ndarray:
    out = np.zeros((len(segments2d), 2, 3), np.float32)
    out[..., :2] = segments2d
    return out
