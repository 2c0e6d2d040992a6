"""Where the camera stands to show given spots (what ``focus`` chooses: the agents, the pairs that
explain the result, their labels), whole, inside the part of the canvas no floating panel covers.

Lengths on the page are CSS pixels. The browser reports its canvas in drawing-buffer pixels (CSS
pixels times a pixel ratio the server is not told), so the canvas's CSS size is estimated
(``canvas_of``): exact at one pixel per CSS pixel, and too small, never too large, on the usual
denser screens, which only leaves more room around what is framed."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .layouts import SCREEN, screen_of

MARGIN_PX = 24.0
"""CSS pixels kept free between what is framed and the edges of the free part of the canvas."""
LOWEST = 40.0
"""The framing camera's lowest height (m): two agents close together still show their surroundings."""
TILT = 0.05
"""How far the camera stands behind the point it looks at, per metre of height (a camera looking
straight down has no 'up' to keep x pointing up the screen)."""
TALLEST_CSS = 1200.0
"""The tallest canvas, in CSS pixels, taken for one pixel per CSS pixel: a taller drawing buffer is
taken for a denser screen (``pixel_ratio``)."""
CHAR_EM, LINE_EM = 0.62, 1.45
"""A label's character width and line height, in ems of its text height (viser draws labels in the
system sans-serif font, on a background padded by a fifth of an em)."""
BISECTIONS = 24
"""Halvings of the scale's bracket (``_fitting_scale``): to a sixteen-millionth of the closest scale."""
SHIFTS = (1.0, 0.75, 0.5, 0.25)
"""The shares of the way to the canvas's middle ``balanced`` tries, the longest first."""
NARROWINGS, NARROW_PX = 6, 8.0
"""How often, and by how many CSS pixels each time, ``frame`` narrows the area it frames in."""


@dataclass(frozen=True)
class Canvas:
    """The scene's canvas: vertical field of view (radians) and size in CSS pixels."""

    fov: float
    width: float
    height: float

    @property
    def focal(self) -> float:
        """CSS pixels per unit of tangent off the line of sight."""
        return self.height / 2.0 / math.tan(self.fov / 2.0)


@dataclass(frozen=True)
class Area:
    """A rectangle of the canvas, CSS pixels from its top left corner."""

    left: float
    top: float
    right: float
    bottom: float

    @property
    def size(self) -> float:
        return max(0.0, self.right - self.left) * max(0.0, self.bottom - self.top)

    def inset(self, by: float) -> Area:
        return Area(self.left + by, self.top + by, self.right - by, self.bottom - by)


@dataclass(frozen=True)
class Spot:
    """A point of the ground (x, y metres) that must show, and the label box it carries: ``width``
    CSS pixels to its right and ``height`` below it (0 for a bare point)."""

    x: float
    y: float
    width: float = 0.0
    height: float = 0.0


def pixel_ratio(buffer_height: float) -> float:
    """Drawing-buffer pixels per CSS pixel, estimated from the buffer's height (``TALLEST_CSS``)."""
    return max(1.0, math.ceil(buffer_height / TALLEST_CSS))


def canvas_of(camera: Any) -> Canvas:
    """The canvas of a viser camera, in CSS pixels (``layouts.SCREEN`` until the browser reports its size)."""
    fov, width, height = screen_of(camera)
    if not height:
        fov, width, height = SCREEN
    ratio = pixel_ratio(height)
    return Canvas(fov, width / ratio, height / ratio)


def free_areas(canvas: Canvas, covered: Area | None, margin: float = MARGIN_PX) -> list[Area]:
    """The rectangles of the canvas beside, above or below the ``covered`` one (a panel floating in a
    corner; None: the whole canvas), each less ``margin`` all round, the largest first."""
    if covered is None:
        return [Area(0.0, 0.0, canvas.width, canvas.height).inset(margin)]
    options = (Area(0.0, 0.0, covered.left, canvas.height), Area(covered.right, 0.0, canvas.width, canvas.height),
               Area(0.0, 0.0, canvas.width, covered.top), Area(0.0, covered.bottom, canvas.width, canvas.height))
    shrunk = [area.inset(margin) for area in sorted(options, key=lambda area: -area.size)]
    return [area for area in shrunk if area.right - area.left > 0 and area.bottom - area.top > 0]


def label_spot(text: str, x: float, y: float, label_px: float) -> Spot:
    """The spot of a label at (x, y): its text runs right and down of its point (viser's top-left anchor)."""
    return Spot(x, y, CHAR_EM * label_px * len(text) + label_px / 5, LINE_EM * label_px)


def _span(ground: np.ndarray, extent: np.ndarray, k: float) -> tuple[float, float]:
    """(low, high) screen offsets covered along one axis at ``k`` pixels per metre, the screen
    running against ``ground`` (metres) and each spot reaching ``extent`` pixels further."""
    at = -k * ground
    return float(at.min()), float((at + extent).max())


def _length(ground: np.ndarray, extent: np.ndarray, k: float) -> float:
    """Pixels the spots cover along one axis at ``k`` pixels per metre."""
    low, high = _span(ground, extent, k)
    return high - low


def _fitting_scale(ground: np.ndarray, extent: np.ndarray, room: float, most: float) -> float:
    """The most pixels per metre (up to ``most``) at which the spots fit ``room`` pixels along one
    axis: a bisection (the length covered is convex in the scale and fits at scale 0 when any label does)."""
    if _length(ground, extent, most) <= room:
        return most
    low, high = 0.0, most
    for _ in range(BISECTIONS):
        middle = (low + high) / 2
        low, high = (middle, high) if _length(ground, extent, middle) <= room else (low, middle)
    return max(low, most * 1e-3)


def framed(spots: list[Spot], canvas: Canvas, area: Area) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Camera position and look-at point, looking down, at which every spot shows whole inside
    ``area`` of ``canvas`` (no lower than ``LOWEST``): x points up the screen, y to its left."""
    return centred(spots, canvas, area, fitting_scale(spots, canvas, area))


def fitting_scale(spots: list[Spot], canvas: Canvas, area: Area) -> float:
    """The most pixels per metre (no closer than ``LOWEST``) at which the spots fit ``area``, seen
    straight down (the perspective left out: ``frame_in`` narrows the area for it)."""
    xs, ys = np.array([s.x for s in spots]), np.array([s.y for s in spots])
    widths, heights = np.array([s.width for s in spots]), np.array([s.height for s in spots])
    most = canvas.focal / LOWEST
    return min(_fitting_scale(ys, widths, area.right - area.left, most),
               _fitting_scale(xs, heights, area.bottom - area.top, most))


def centred(spots: list[Spot], canvas: Canvas, area: Area, k: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Camera position and look-at point, looking down at ``k`` pixels per metre, with the spots'
    extent centred in ``area``."""
    xs, ys = np.array([s.x for s in spots]), np.array([s.y for s in spots])
    widths, heights = np.array([s.width for s in spots]), np.array([s.height for s in spots])
    across, down = _span(ys, widths, k), _span(xs, heights, k)
    look_y = ((area.left + area.right) / 2 - canvas.width / 2 - sum(across) / 2) / k
    look_x = ((area.top + area.bottom) / 2 - canvas.height / 2 - sum(down) / 2) / k
    height = canvas.focal / k
    return (look_x - TILT * height, look_y, height), (look_x, look_y, 0.0)


def frame(spots: list[Spot], canvas: Canvas, areas: list[Area]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The camera closest to the ground that frames every spot in one of ``areas`` (``frame_in``)."""
    return min((frame_in(spots, canvas, area) for area in areas), key=lambda pose: pose[0][2])


def balanced(spots: list[Spot], pose: tuple[tuple[float, ...], tuple[float, ...]], canvas: Canvas,
             covered: Area | None) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """``pose`` moved, at its scale, towards centring the spots in the whole canvas, as far as they stay
    clear of the ``covered`` corner (the whole way, or ``SHIFTS`` of it): a framing beside a panel
    otherwise leaves the rest of the canvas empty."""
    if covered is None or not spots:
        return pose
    whole = Area(0.0, 0.0, canvas.width, canvas.height).inset(MARGIN_PX)
    target = centred(spots, canvas, whole, 1.0 / metres_per_px(*pose, canvas))
    clear = [Area(0.0, 0.0, canvas.width, covered.top - MARGIN_PX), Area(0.0, covered.bottom + MARGIN_PX,
             canvas.width, canvas.height), Area(0.0, 0.0, covered.left - MARGIN_PX, canvas.height)]
    for share in SHIFTS:
        moved = tuple(tuple(a + share * (b - a) for a, b in zip(now, then)) for now, then in zip(pose, target))
        where = project(*moved, canvas, np.array([(s.x, s.y) for s in spots]))
        ends = where + np.array([(s.width, s.height) for s in spots])
        if all_inside(spots, *moved, canvas, whole) and all(
                any(a.left <= u and a.top <= v and e <= a.right and f <= a.bottom for a in clear)
                for (u, v), (e, f) in zip(where, ends)):
            return moved
    return pose


def frame_in(spots: list[Spot], canvas: Canvas, area: Area) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """``framed``, the area narrowed a step at a time until the camera's perspective (which the
    estimate leaves out) keeps every spot inside it too."""
    pose = framed(spots, canvas, area)
    for step in range(1, NARROWINGS + 1):
        if all_inside(spots, *pose, canvas, area):
            break
        pose = framed(spots, canvas, area.inset(step * NARROW_PX))
    return pose


def project(position: tuple[float, ...], look_at: tuple[float, ...], canvas: Canvas, xy: np.ndarray) -> np.ndarray:
    """(N, 2) CSS pixels (x right, y down) where ground points (N, 2) show through the camera at
    ``position`` looking at ``look_at`` (+z up)."""
    position, look_at = np.asarray(position, float), np.asarray(look_at, float)
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = np.c_[xy, np.zeros(len(xy))] - position
    depth = rel @ forward
    return np.stack([canvas.width / 2 + canvas.focal * (rel @ right) / depth,
                     canvas.height / 2 - canvas.focal * (rel @ up) / depth], axis=1)


def unproject(position: tuple[float, ...], look_at: tuple[float, ...], canvas: Canvas, uv: np.ndarray,
              z: float = 0.0) -> np.ndarray:
    """(N, 2) ground points at height ``z`` that show at CSS pixels ``uv`` (N, 2) through the camera at
    ``position`` looking at ``look_at`` (``project``'s inverse)."""
    position, look_at = np.asarray(position, float), np.asarray(look_at, float)
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    uv = np.asarray(uv, float).reshape(-1, 2)
    rays = forward + ((uv[:, :1] - canvas.width / 2) * right - (uv[:, 1:] - canvas.height / 2) * up) / canvas.focal
    reach = (z - position[2]) / rays[:, 2]
    return position[:2] + reach[:, None] * rays[:, :2]


def inside_one(spots: list[Spot], position: tuple[float, ...], look_at: tuple[float, ...], canvas: Canvas,
               areas: list[Area]) -> bool:
    """Whether every spot shows whole inside one of ``areas`` (all in the same) through that camera."""
    return any(all_inside(spots, position, look_at, canvas, area) for area in areas)


def all_inside(spots: list[Spot], position: tuple[float, ...], look_at: tuple[float, ...], canvas: Canvas,
               area: Area) -> bool:
    """Whether every spot, with its label box, shows whole inside ``area`` through that camera."""
    if not spots:
        return True
    where = project(position, look_at, canvas, np.array([(s.x, s.y) for s in spots]))
    ends = where + np.array([(s.width, s.height) for s in spots])
    return bool((where[:, 0] >= area.left).all() and (where[:, 1] >= area.top).all()
                and (ends[:, 0] <= area.right).all() and (ends[:, 1] <= area.bottom).all())


def metres_per_px(position: tuple[float, ...], look_at: tuple[float, ...], canvas: Canvas) -> float:
    """Metres of ground one CSS pixel spans at the point the camera looks at."""
    return float(np.linalg.norm(np.subtract(look_at, position))) / canvas.focal
