"""Triangles and line segments for the scene: boxes, vehicles, match lines, map polylines.

Every function turns many objects into one array, so each group becomes one scene node.
"""
from __future__ import annotations

import numpy as np

from cbm import se2

_CORNERS = np.array([[0.5, 0.5], [-0.5, 0.5], [-0.5, -0.5], [0.5, -0.5]])
_BOX_FACES = np.array([
    [0, 1, 2], [0, 2, 3],                   # bottom
    [4, 6, 5], [4, 7, 6],                   # top
    [0, 4, 5], [0, 5, 1], [1, 5, 6], [1, 6, 2],
    [2, 6, 7], [2, 7, 3], [3, 7, 4], [3, 4, 0],
], dtype=np.uint32)
_TOP_FACES = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)
_NOSE = np.array([[0.5, 0.0], [0.15, 0.42], [0.15, -0.42]])
_NOSE_FACES = np.array([[0, 1, 2], [3, 5, 4]], dtype=np.uint32)


def footprints(boxes: np.ndarray) -> np.ndarray:
    """(N, 4, 2) corners of each box's footprint (counter-clockwise from front-left)."""
    c, s = np.cos(boxes[:, 6]), np.sin(boxes[:, 6])
    local = _CORNERS[None] * np.stack([boxes[:, 3], boxes[:, 4]], axis=1)[:, None, :]
    x = boxes[:, None, 0] + c[:, None] * local[..., 0] - s[:, None] * local[..., 1]
    y = boxes[:, None, 1] + s[:, None] * local[..., 0] + c[:, None] * local[..., 1]
    return np.stack([x, y], axis=-1)


def box_mesh(boxes: np.ndarray, lift: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (8N, 3) and faces (12N, 3) of all boxes, standing on the ground (z from 0 up to
    the height; the datasets' absolute z is not drawn). Empty input gives empty arrays."""
    n = len(boxes)
    if n == 0:
        return np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32)
    corners = footprints(boxes)
    bottom = np.concatenate([corners, np.full((n, 4, 1), lift)], axis=2)
    top = np.concatenate([corners, (lift + boxes[:, 5])[:, None, None].repeat(4, axis=1)], axis=2)
    vertices = np.concatenate([bottom, top], axis=1).reshape(-1, 3)
    faces = (_BOX_FACES[None] + 8 * np.arange(n, dtype=np.uint32)[:, None, None]).reshape(-1, 3)
    return vertices.astype(np.float32), faces


def footprint_mesh(boxes: np.ndarray, z: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (4N, 3) and faces (2N, 3) of each box's footprint, a tile facing up at height ``z``
    (None: at each box's own height, its top face). A sixth of ``box_mesh``'s triangles and one
    layer of pixels per box: the scene stays cheap to render in software WebGL. Empty input gives
    empty arrays."""
    n = len(boxes)
    if n == 0:
        return np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32)
    heights = np.repeat((boxes[:, 5] if z is None else np.full(n, z))[:, None, None], 4, axis=1)
    vertices = np.concatenate([footprints(boxes), heights], axis=2).reshape(-1, 3)
    faces = (_TOP_FACES[None] + 4 * np.arange(n, dtype=np.uint32)[:, None, None]).reshape(-1, 3)
    return vertices.astype(np.float32), faces


CAR_SIZE = (4.8, 2.0, 1.5)
"""Length, width and height of a vehicle as drawn."""
ROADSIDE_SIZE = (1.5, 1.5, 6.0)
"""Length, width and height of a roadside unit as drawn: a mast, seen from above as a small square."""


def vehicle_mesh(poses: list[np.ndarray], length: float = CAR_SIZE[0], width: float = CAR_SIZE[1],
                 height: float = CAR_SIZE[2]) -> tuple[np.ndarray, np.ndarray]:
    """A body and an arrow-head on its roof pointing forward, for each (3, 3) pose."""
    if not poses:
        return np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32)
    boxes = np.array([[*se2.translation_of(T), height / 2, length, width, height, se2.yaw_of(T)] for T in poses])
    body_v, body_f = box_mesh(boxes)
    nose_v, nose_f = [], []
    for k, T in enumerate(poses):
        tip = se2.apply_points(T, _NOSE * [length, width])
        top = np.concatenate([tip, np.full((3, 1), height + 0.05)], axis=1)
        under = top.copy()
        under[:, 2] = height + 0.04
        nose_v.append(np.concatenate([top, under]))
        nose_f.append(_NOSE_FACES + len(body_v) + 6 * k)
    return (np.concatenate([body_v, *nose_v]).astype(np.float32),
            np.concatenate([body_f, *nose_f]).astype(np.uint32))


def segments(starts: np.ndarray, ends: np.ndarray, z: float) -> np.ndarray:
    """(N, 2, 3) line segments from ``starts`` to ``ends`` (both (N, 2)) at height ``z``."""
    n = len(starts)
    out = np.full((n, 2, 3), z, dtype=np.float32)
    out[:, 0, :2], out[:, 1, :2] = starts, ends
    return out


def dashed(starts: np.ndarray, ends: np.ndarray, z: float, dash: float = 0.8) -> np.ndarray:
    """Segments cut into dashes of length ``dash`` with equal gaps."""
    pieces = []
    for a, b in zip(starts, ends):
        length = float(np.linalg.norm(b - a))
        n = max(1, int(length / (2 * dash)))
        t0 = np.arange(n) / n
        t1 = t0 + 0.5 / n
        pieces.append(segments(a + np.outer(t0, b - a), a + np.outer(t1, b - a), z))
    return np.concatenate(pieces) if pieces else np.zeros((0, 2, 3), np.float32)


def cross_segments(boxes: np.ndarray, z: float = 0.05) -> np.ndarray:
    """(2N, 2, 3) the two diagonals of each box's footprint: a cross over it."""
    if len(boxes) == 0:
        return np.zeros((0, 2, 3), np.float32)
    corners = footprints(boxes)
    starts, ends = corners[:, :2].reshape(-1, 2), corners[:, 2:].reshape(-1, 2)
    return segments(starts, ends, z)


def outline_segments(boxes: np.ndarray, z: float = 0.05) -> np.ndarray:
    """(4N, 2, 3) footprint outlines of the boxes."""
    if len(boxes) == 0:
        return np.zeros((0, 2, 3), np.float32)
    corners = footprints(boxes)
    return segments(corners.reshape(-1, 2), np.roll(corners, -1, axis=1).reshape(-1, 2), z)
