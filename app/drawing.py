"""What one outcome looks like: the arrays of every scene node, in the ego frame (x forward, y left).

A ``Drawing`` is plain data (meshes, line sets, labels, the metrics text), so the session logic can
be tested without a browser and the viser layer only copies arrays into nodes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cbm import se2
from cbm.methods import METHODS

from . import geometry
from .session import Outcome

EGO_BOXES = (52, 120, 246)
CAV_BOXES = (255, 140, 0)
EGO_VEHICLE = (16, 40, 150)
CAV_VEHICLE = (190, 70, 0)
RIGHT = (30, 170, 60)
WRONG = (225, 30, 30)
MISSED = (140, 140, 140)
GHOST = (110, 110, 110)
MAP_COLORS = {"lane_boundary": (185, 185, 185), "crossing": (225, 200, 120), "drivable_area": (215, 215, 215)}
LINE_HEIGHT = 1.7
SIDE_GAP = 20.0


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


@dataclass(frozen=True)
class Drawing:
    meshes: dict[str, Mesh]
    lines: dict[str, Lines]
    labels: dict[str, tuple[str, tuple[float, float, float]]]
    metrics_markdown: str
    objects: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    centre_y: float = 0.0
    """Sideways middle of the panels the layout shows (where the camera looks on reset)."""
    """(boxes (N, 7) as drawn, index into the trial's list) by group (``ego``, ``cav``), for picking."""


def _placement(outcome: Outcome) -> dict[str, np.ndarray]:
    """CAV->ego transforms: before (``init``), after (the estimate), truth."""
    return {"before": outcome.result.init, "after": outcome.result.transform, "truth": outcome.trial.T_true}


def _panels(outcome: Outcome) -> list[tuple[str, np.ndarray]]:
    """(which CAV placement, offset added to y) of each copy of the scene the layout shows."""
    layout = outcome.settings.view.layout
    if layout == "side by side":
        boxes = np.concatenate([outcome.trial.ego_boxes[:, :2], outcome.world_boxes[:, :2], np.zeros((1, 2))])
        width = float(boxes[:, 1].max() - boxes[:, 1].min()) + SIDE_GAP
        return [("before", np.array([0.0, width])), ("after", np.zeros(2))]
    return [("after" if layout in ("overlay", "after") else "before", np.zeros(2))]


def _slim(boxes: np.ndarray) -> np.ndarray:
    """CAV boxes drawn narrower and taller than the ego's, so a matched pair shows both colours."""
    out = boxes.copy()
    out[:, 3:5] *= 0.7
    out[:, 5] *= 1.3
    return out


def _shift(boxes: np.ndarray, offset: np.ndarray) -> np.ndarray:
    out = boxes.copy()
    out[:, :2] += offset
    return out


def draw(outcome: Outcome, map_segments: dict[str, np.ndarray]) -> Drawing:
    """The scene of ``outcome`` under its view options."""
    view = outcome.settings.view
    trial = outcome.trial
    placements = _placement(outcome)
    panels = _panels(outcome)
    ego_parts, cav_parts, before_parts, ghost_parts, ego_poses, cav_poses, before_poses = [], [], [], [], [], [], []
    right, wrong, missed, maps = [], [], [], {kind: [] for kind in map_segments}
    world_to_ego = se2.inverse(trial.ego_pose)
    for placement, offset in panels:
        T = placements[placement]
        shift = se2.make(offset[0], offset[1], 0.0)
        ego_parts.append(_shift(trial.ego_boxes, offset))
        cav = se2.apply_boxes(shift @ T, trial.cav_boxes)
        cav_parts.append(cav)
        ego_poses.append(shift)
        cav_poses.append(shift @ T)
        if view.layout == "overlay":
            before_parts.append(se2.apply_boxes(placements["before"], trial.cav_boxes))
            before_poses.append(placements["before"])
        if view.ghosts:
            ghost_parts.append(_shift(outcome.world_boxes[np.isin(outcome.world_ids, np.concatenate([trial.ego_ids, trial.cav_ids]))], offset))
        if view.lines:
            r, w, m = _match_lines(trial, shown_pairs(outcome), trial.ego_boxes[:, :2] + offset, cav[:, :2])
            right.append(r), wrong.append(w), missed.append(m)
        for kind, segments in map_segments.items():
            local = se2.apply_points(shift @ world_to_ego, segments.reshape(-1, 2)).reshape(-1, 2, 2)
            maps[kind].append(local)
    ego = np.concatenate(ego_parts)
    cav = np.concatenate(cav_parts)
    meshes = {
        "ego_boxes": Mesh(*geometry.box_mesh(ego), EGO_BOXES),
        "cav_boxes": Mesh(*geometry.box_mesh(_slim(cav)), CAV_BOXES),
        "cav_before": Mesh(*geometry.box_mesh(_slim(np.concatenate(before_parts)) if before_parts else np.zeros((0, 7))),
                           CAV_BOXES, opacity=0.3),
        "ego_vehicle": Mesh(*geometry.vehicle_mesh(ego_poses), EGO_VEHICLE),
        "cav_vehicle": Mesh(*geometry.vehicle_mesh(cav_poses), CAV_VEHICLE),
        "cav_vehicle_before": Mesh(*geometry.vehicle_mesh(before_poses), CAV_VEHICLE, opacity=0.3),
    }
    lines = {
        "right": Lines(_joined(right), RIGHT, 3.0),
        "wrong": Lines(_joined(wrong), WRONG, 3.0),
        "missed": Lines(_joined(missed), MISSED, 2.0),
        "ghosts": Lines(geometry.outline_segments(np.concatenate(ghost_parts)) if ghost_parts else _no_lines(), GHOST, 1.5),
        **{f"map_{kind}": Lines(np.concatenate([_lift(p) for p in parts]), MAP_COLORS.get(kind, (200, 200, 200)), 1.0)
           for kind, parts in maps.items()},
    }
    labels = {}
    for (placement, _), ego_pose, cav_pose in zip(panels, ego_poses, cav_poses):
        labels[f"ego_{placement}"] = ("ego", (*se2.translation_of(ego_pose), 2.5))
        labels[f"cav_{placement}"] = ("CAV", (*se2.translation_of(cav_pose), 2.5))
    if view.layout == "side by side":
        labels["before"] = ("BEFORE calibration (CAV at init)", (-12.0, float(panels[0][1][1]), 3.0))
        labels["after"] = ("AFTER calibration (CAV at estimate)", (-12.0, 0.0, 3.0))
    copies = len(panels)
    objects = {"ego": (ego, np.tile(np.arange(len(trial.ego_boxes)), copies)),
               "cav": (cav, np.tile(np.arange(len(trial.cav_boxes)), copies))}
    return Drawing(meshes=meshes, lines=lines, labels=labels, metrics_markdown=metrics_markdown(outcome),
                   objects=objects, centre_y=float(np.mean([offset[1] for _, offset in panels])))


def pick(picture: Drawing, point: np.ndarray) -> tuple[str, int] | None:
    """(group, row) of the drawn box whose footprint holds ``point``, else of the nearest centre
    within 2 m; None when there is none."""
    best: tuple[float, str, int] | None = None
    for group, (boxes, _) in picture.objects.items():
        if len(boxes) == 0:
            continue
        local = point[None, :2] - boxes[:, :2]
        c, s = np.cos(boxes[:, 6]), np.sin(boxes[:, 6])
        along, across = c * local[:, 0] + s * local[:, 1], -s * local[:, 0] + c * local[:, 1]
        inside = (np.abs(along) <= boxes[:, 3] / 2) & (np.abs(across) <= boxes[:, 4] / 2)
        distance = np.where(inside, 0.0, np.hypot(local[:, 0], local[:, 1]))
        k = int(np.argmin(distance))
        if distance[k] <= 2.0 and (best is None or distance[k] < best[0]):
            best = (float(distance[k]), group, k)
    return None if best is None else (best[1], best[2])


def describe(outcome: Outcome, picture: Drawing, group: str, row: int) -> str:
    """Label text of one drawn box: whose detection, its id, and what it was matched to."""
    trial, pairs = outcome.trial, outcome.result.pairs
    index = int(picture.objects[group][1][row])
    ids = trial.ego_ids if group == "ego" else trial.cav_ids
    column = 0 if group == "ego" else 1
    partner = pairs[pairs[:, column] == index]
    truth = trial.gt_pairs[trial.gt_pairs[:, column] == index]
    text = f"{group.upper()} {str(ids[index])[:8]}"
    if len(partner):
        other = int(partner[0, 1 - column])
        right = len(truth) and int(truth[0, 1 - column]) == other
        other_ids = trial.cav_ids if group == "ego" else trial.ego_ids
        text += f" -> {str(other_ids[other])[:8]} ({'right' if right else 'wrong'})"
    elif len(truth):
        text += " (co-visible, missed)"
    else:
        text += " (seen by one agent)"
    return text


def _no_lines() -> np.ndarray:
    return np.zeros((0, 2, 3), np.float32)


def _joined(parts: list[np.ndarray]) -> np.ndarray:
    return np.concatenate(parts) if parts else _no_lines()


def _lift(segments2d: np.ndarray) -> np.ndarray:
    out = np.zeros((len(segments2d), 2, 3), np.float32)
    out[..., :2] = segments2d
    return out


def shown_pairs(outcome: Outcome) -> np.ndarray:
    """The pairs the match lines show: CBM's own (before the re-association) when the view asks
    for them and the method has them, else the method's final pairs."""
    result = outcome.result
    if outcome.settings.view.line_pairs == "own" and result.context_pairs is not None:
        return result.context_pairs
    return result.pairs


def _match_lines(trial, pairs: np.ndarray, ego_xy: np.ndarray, cav_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments of right pairs, wrong pairs, and true pairs the method missed (dashed)."""
    truth = {tuple(p) for p in trial.gt_pairs.tolist()}
    found = {tuple(p) for p in pairs.tolist()}
    right = np.array([p for p in found if p in truth], dtype=int).reshape(-1, 2)
    wrong = np.array([p for p in found if p not in truth], dtype=int).reshape(-1, 2)
    missed = np.array([p for p in truth if p not in found], dtype=int).reshape(-1, 2)
    return (geometry.segments(ego_xy[right[:, 0]], cav_xy[right[:, 1]], LINE_HEIGHT),
            geometry.segments(ego_xy[wrong[:, 0]], cav_xy[wrong[:, 1]], LINE_HEIGHT),
            geometry.dashed(ego_xy[missed[:, 0]], cav_xy[missed[:, 1]], LINE_HEIGHT))


def number(value: float, unit: str = "", digits: int = 2) -> str:
    """``value`` with ``digits`` decimals and ``unit``; a dash when it is undefined (None, NaN)."""
    return "—" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.{digits}f}{unit}"


def _own_pairs(result) -> str:
    """How many of the pairs CBM found itself, when the re-association changed them."""
    own = result.context_pairs
    if own is None or np.array_equal(own, result.pairs):
        return ""
    return f"; CBM's own {len(own)}"


def metrics_markdown(outcome: Outcome) -> str:
    """The metrics panel's text for one frame."""
    m, result, trial, limit = outcome.metrics, outcome.result, outcome.trial, outcome.limit
    init_rre = abs(math.degrees(se2.wrap_angle(se2.yaw_of(trial.init) - se2.yaw_of(trial.T_true))))
    init_rte = float(np.linalg.norm(se2.translation_of(trial.init) - se2.translation_of(trial.T_true)))
    method = METHODS[outcome.settings.method].label
    lines = [
        f"**Frame {outcome.frame_index}** · ego `{str(outcome.ego_id)[:8]}` · CAV `{str(outcome.cav_id)[:8]}` ({outcome.cav_note})",
        "",
        "| | |",
        "|---|---|",
        f"| objects (ego / CAV) | {m.n_ego} / {m.n_cav} |",
        f"| co-visible | {m.n_true} |",
        f"| matches ({method}) | {m.n_matched} ({m.n_correct} right){_own_pairs(result)} |",
        f"| precision / recall | {number(m.precision)} / {number(m.recall)} |",
        f"| AD | {number(m.ad, ' m')} |",
        f"| RRE / RTE | {number(m.rre, '°')} / {number(m.rte, ' m')} |",
        f"| before calibration | {number(init_rre, '°')} / {number(init_rte, ' m')} |",
        f"| limit (oracle: true pairs) | {number(limit.rre, '°')} / {number(limit.rte, ' m')} |",
    ]
    if result.anchor is not None:
        lines.append(f"| consensus margin | {result.margin} ({result.consensus_count} vs {result.runner_up_count}) |")
    lines.append(f"| {method} time | {number(1000 * result.timings.get('total', float('nan')), ' ms', 1)} |")
    if not result.estimated:
        lines.append("")
        lines.append("No pose estimate: fewer than 2 pairs matched; the CAV stays where `init` put it.")
    if outcome.findings:
        lines.append("")
        lines.append("**Why it failed**")
        lines.extend(f"- {f.message}" for f in outcome.findings)
    return "\n".join(lines)
