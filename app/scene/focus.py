"""What the camera frames: the ego and every CAV always; then the pairs that explain the result
(``deciding``), most telling first, each while a car stays a readable box (``READABLE``); then the
boxes nearest what is framed, as many as fit without a higher camera. The pairs left out are the
frame's pairs out of view: the panel lists them (a click flies there) and a marker at the edge of
the canvas points to them (``edge_labels``)."""
from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from . import framing
from .deciding import Mark, corners
from .framing import Area, Canvas, Spot
from .geometry import CAR_SIZE
from .labelling import GAP_PX, Bounds, Laid, screen_bounds, size_px
from .words import plural

if TYPE_CHECKING:
    from .drawing import Drawing

READABLE = 0.125
"""The coarsest scale, in metres of ground per CSS pixel, at which the camera takes in a pair: a car
(4.6 m by 1.9 m) still shows as a box 37 by 15 pixels. Only the agents themselves may need more."""
SLANT = 1.1
"""How much higher the camera's final framing may stand than ``needed`` estimates (straight down): its
slight slant (``framing.TILT``) stretches the near edge of a 75° view by up to a tenth, which
``framing.frame_in`` narrows for; ``choose`` aims that much lower."""
CONTEXT_SLACK = 1.02
"""How much higher (a share) the camera may stand to take in the boxes around what it frames."""
EDGE_PX = 6.0
"""CSS pixels between an edge marker and the edge of the part of the canvas the camera frames in."""
ARROWS = "→↗↑↖←↙↓↘"
"""The arrow of an edge marker, by the direction on screen it points (from right, anticlockwise)."""


def ordered(marks: Iterable[Mark]) -> list[Mark]:
    """The deciding pairs in their order, then the others nearest the ego first."""
    marks = list(marks)
    return [m for m in marks if m.deciding] + sorted((m for m in marks if not m.deciding), key=lambda m: m.distance)


def beside(drawing: Drawing, name: str, m: float) -> Spot:
    """The spot of label ``name`` beside the thing it names (``labelling``'s first place), at ``m``
    metres per pixel."""
    text, (x, y, _) = drawing.labels[name]
    width, height = size_px(text, drawing.label_px)
    across, _ = drawing.room.get(name, (0.0, 0.0))
    return Spot(x + height / 2 * m, y - across - GAP_PX * m, width, height)


AGENT_REACH = math.hypot(*CAR_SIZE[:2]) / 2
"""Metres from an agent's centre that a car of ``geometry.CAR_SIZE`` reaches, whatever its heading: the
camera frames the square this far around it, so that a car at the edge of the view shows whole (the
CAV of *drift-heavy*'s frame 14 showed cut by the canvas's edge when only its centre was framed)."""


def agent_spots(drawing: Drawing) -> list[Spot]:
    """The corners of the square ``AGENT_REACH`` around each agent (ego and CAV of every panel)."""
    r = AGENT_REACH
    return [Spot(x + dx, y + dy) for x, y in drawing.agents for dx in (-r, r) for dy in (-r, r)]


def base_spots(drawing: Drawing, m: float) -> list[Spot]:
    """The agents and the labels that name no pair (the agents', the layout's titles), beside their things."""
    named = {label for mark in drawing.marks for label in mark.labels}
    return agent_spots(drawing) + \
        [beside(drawing, name, m) for name in drawing.labels if name not in named and name in drawing.kept]


def mark_spots(drawing: Drawing, mark: Mark, m: float) -> list[Spot]:
    """The corners of a pair's boxes and its labels beside them."""
    return [Spot(float(x), float(y)) for x, y in mark.points] + [beside(drawing, name, m) for name in mark.labels]


def needed(spots: list[Spot], canvas: Canvas, areas: list[Area]) -> float:
    """Metres per pixel of the closest camera that frames ``spots`` in one of ``areas`` (seen straight
    down: the final ``framing.frame`` takes the perspective in)."""
    return 1.0 / max(framing.fitting_scale(spots, canvas, area) for area in areas)


def choose(drawing: Drawing, canvas: Canvas, areas: list[Area]) -> tuple[list[Mark], list[Mark]]:
    """(shown, away): the pairs the camera takes in, in ``ordered`` order, each while the scale
    stays at ``READABLE`` (or at what the agents alone need), and the others."""
    spots = base_spots(drawing, READABLE)
    limit = max(READABLE / SLANT, needed(spots, canvas, areas))
    shown, away = [], []
    for mark in ordered(drawing.marks):
        trial = spots + mark_spots(drawing, mark, limit)
        if needed(trial, canvas, areas) <= limit:
            shown.append(mark)
            spots = trial
        else:
            away.append(mark)
    return shown, away


def context(drawing: Drawing, spots: list[Spot], canvas: Canvas, areas: list[Area]) -> list[Spot]:
    """The corners of the boxes nearest ``spots`` (every agent's, as drawn), as many as fit in
    without a camera more than ``CONTEXT_SLACK`` higher: the longest such run, nearest first."""
    boxes = [boxes for boxes, _ in drawing.objects.values() if len(boxes)]
    if not boxes or not spots:
        return []
    points = corners(np.concatenate(boxes)).reshape(-1, 4, 2)
    centre = np.mean([(s.x, s.y) for s in spots], axis=0)
    points = points[np.argsort(np.linalg.norm(points.mean(axis=1) - centre, axis=1), kind="stable")]
    limit = needed(spots, canvas, areas) * CONTEXT_SLACK

    def with_first(n: int) -> list[Spot]:
        return spots + [Spot(float(x), float(y)) for x, y in points[:n].reshape(-1, 2)]

    low, high = 0, len(points)
    while low < high:
        middle = (low + high + 1) // 2
        low, high = (middle, high) if needed(with_first(middle), canvas, areas) <= limit else (low, middle - 1)
    return [Spot(float(x), float(y)) for x, y in points[:low].reshape(-1, 2)]


def framed_spots(drawing: Drawing, shown: list[Mark], away: list[Mark], laid: Laid) -> list[Spot]:
    """What the camera frames once the labels are laid out: the agents, the shown pairs' boxes, and
    every label laid out but those of the pairs away."""
    gone = {label for mark in away for label in mark.labels}
    spots = agent_spots(drawing)
    spots += [Spot(float(x), float(y)) for mark in shown for x, y in mark.points]
    spots += [framing.label_spot(text, p[0], p[1], drawing.label_px) for name, (text, p) in laid.labels.items()
              if name not in gone]
    return spots


def bounds_of(pose: tuple[tuple[float, ...], tuple[float, ...]], metres_per_px: float, canvas: Canvas,
              area: Area) -> Bounds:
    """``area`` of the canvas seen through the camera ``pose`` at ``metres_per_px``, in the labels' layout frame."""
    return screen_bounds(pose[1], metres_per_px, canvas.width, canvas.height, (area.left, area.top, area.right,
                                                                               area.bottom))


def area_of(spots: list[Spot], pose: tuple[tuple[float, ...], tuple[float, ...]], canvas: Canvas,
            areas: list[Area]) -> Area:
    """The first of ``areas`` that shows every spot through the camera ``pose`` (the first when none does)."""
    return next((area for area in areas if framing.all_inside(spots, *pose, canvas, area)), areas[0])


def in_sight(points: np.ndarray, pose: tuple[tuple[float, ...], tuple[float, ...]], canvas: Canvas,
             covered: Area | None) -> bool:
    """Whether every ground point shows on the canvas through the camera ``pose``, none under ``covered``."""
    where = framing.project(*pose, canvas, points)
    on = (where[:, 0] >= 0) & (where[:, 0] <= canvas.width) & (where[:, 1] >= 0) & (where[:, 1] <= canvas.height)
    if covered is not None:
        on &= ~((where[:, 0] > covered.left) & (where[:, 0] < covered.right) & (where[:, 1] > covered.top)
                & (where[:, 1] < covered.bottom))
    return bool(on.all())


def out_of_view(marks: Iterable[Mark], pose: tuple[tuple[float, ...], tuple[float, ...]], canvas: Canvas,
                covered: Area | None) -> list[Mark]:
    """The marks not wholly in sight through the camera ``pose`` (``in_sight``)."""
    return [mark for mark in marks if not in_sight(mark.points, pose, canvas, covered)]


def edge_labels(away: list[Mark], pose: tuple[tuple[float, ...], tuple[float, ...]], canvas: Canvas,
                covered: Area | None, label_px: float, z: float) -> dict[str, tuple[str, tuple[float, float, float]]]:
    """A marker at the edge of the canvas for the pairs ``away`` beyond each of its sides, where the
    line from the middle of the scene in sight to them leaves it: an arrow towards them and how many
    (``edge_top``, ``edge_left``, ...), off the ``covered`` corner."""
    inner = Area(0.0, 0.0, canvas.width, canvas.height).inset(EDGE_PX)
    free = framing.free_areas(canvas, covered, margin=0.0)[0]
    middle = np.array([(free.left + free.right) / 2, (free.top + free.bottom) / 2])
    sides: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for mark in away:
        where = framing.project(*pose, canvas, mark.points.mean(axis=0, keepdims=True))[0]
        side, at = _exit(middle, where, inner)
        sides.setdefault(side, []).append((at, where - middle))
    labels = {}
    for side, found in sides.items():
        at, direction = np.mean([a for a, _ in found], axis=0), np.mean([d for _, d in found], axis=0)
        arrow = ARROWS[round(math.atan2(-direction[1], direction[0]) / (math.pi / 4)) % 8]
        text = f"{arrow} {plural(len(found), 'pair')} out of view"
        width, height = size_px(text, label_px)
        left = min(max(at[0] - width / 2, inner.left), inner.right - width)
        top = min(max(at[1] - height / 2, inner.top), inner.bottom - height)
        left, top = _off(Area(left, top, left + width, top + height), covered, side)
        x, y = framing.unproject(*pose, canvas, np.array([[left, top]]), z)[0]
        labels[f"edge_{side}"] = (text, (float(x), float(y), z))
    return labels


def _off(box: Area, covered: Area | None, side: str) -> tuple[float, float]:
    """The top left corner of ``box`` moved off the ``covered`` corner: to its left on the top side,
    below it on the right side."""
    if covered is None or not (box.left < covered.right and covered.left < box.right and box.top < covered.bottom
                               and covered.top < box.bottom):
        return box.left, box.top
    if side == "right":
        return box.left, covered.bottom + EDGE_PX
    return covered.left - EDGE_PX - (box.right - box.left), box.top


def _exit(middle: np.ndarray, where: np.ndarray, area: Area) -> tuple[str, np.ndarray]:
    """The side of ``area`` the line from ``middle`` towards ``where`` leaves it by, and the point."""
    direction = where - middle
    reach = []
    for side, axis, bound in (("left", 0, area.left), ("right", 0, area.right), ("top", 1, area.top),
                              ("bottom", 1, area.bottom)):
        if direction[axis] * (bound - middle[axis]) > 0:
            reach.append(((bound - middle[axis]) / direction[axis], side))
    t, side = min(reach, default=(0.0, "bottom"))
    return side, middle + min(t, 1.0) * direction
