"""Line of sight: what an agent's sensor sees among the boxes of a scene, in the bird's-eye view.

A lidar or camera sees an object when its rays reach the object before any other object: a truck
hides what lies behind it from one agent while another, elsewhere, sees it all. So an object within
range is seen when at least ``share`` of its footprint, as the sensor looks at it, is not hidden:
``RAYS`` rays from the sensor sweep the angle the footprint subtends, and a ray sees the object when
the object's footprint is the first one it meets. The box the sensor sits in (its own vehicle) hides
nothing. Everything follows from the boxes of one frame, so what is co-visible changes smoothly as
the traffic moves.

``sight_outline`` gives the area a sensor sees (a polygon of the first hits of rays all around), to
draw an agent's sight and the shadows behind the boxes.
"""
from __future__ import annotations

import numpy as np

from cbm import se2

RAYS = 16
"""Rays across each object's footprint: its visible share is known to 1/16."""
SHARE = 0.25
"""Least visible share of a footprint for the object to be seen (a quarter of a car's side gives a
detector tens of lidar points within 50 m)."""
OUTLINE_RAYS = 720
"""Rays of a sight outline: one every half degree."""


def footprints(boxes: np.ndarray) -> np.ndarray:
    """(N, 4, 2) corners of each box's footprint, counter-clockwise."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 7)
    half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * 0.5
    local = half[None] * boxes[:, None, 3:5]
    c, s = np.cos(boxes[:, 6])[:, None], np.sin(boxes[:, 6])[:, None]
    x = boxes[:, None, 0] + c * local[..., 0] - s * local[..., 1]
    y = boxes[:, None, 1] + s * local[..., 0] + c * local[..., 1]
    return np.stack([x, y], axis=-1)


def first_hits(origin: np.ndarray, directions: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(R, M) distance along each unit ray ``origin + t d`` to where it first meets each footprint's
    outline (inf where it misses): the least ``t > 0`` over the footprint's four edges."""
    a = corners - origin
    edge = np.roll(corners, -1, axis=1) - corners
    d = directions[:, None, None, :]
    denominator = d[..., 0] * edge[None, ..., 1] - d[..., 1] * edge[None, ..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a[None, ..., 0] * edge[None, ..., 1] - a[None, ..., 1] * edge[None, ..., 0]) / denominator
        s = (a[None, ..., 0] * d[..., 1] - a[None, ..., 1] * d[..., 0]) / denominator
    hit = (denominator != 0) & (t > 0) & (s >= 0) & (s <= 1)
    return np.where(hit, t, np.inf).min(axis=2)


def contains(corners: np.ndarray, point: np.ndarray) -> np.ndarray:
    """(M,) whether ``point`` lies inside each convex footprint (counter-clockwise corners)."""
    edge = np.roll(corners, -1, axis=1) - corners
    to_point = point - corners
    return ((edge[..., 0] * to_point[..., 1] - edge[..., 1] * to_point[..., 0]) >= 0).all(axis=1)


def visible_share(boxes: np.ndarray, origin: np.ndarray, sensor_range: float, rays: int = RAYS) -> np.ndarray:
    """(N,) share of each box's footprint the sensor at ``origin`` sees: 0 beyond ``sensor_range``
    (the centre's distance), 1 for a box the sensor sits in."""
    corners = footprints(boxes)
    origin = np.asarray(origin, dtype=float)
    own = contains(corners, origin)
    distance = np.linalg.norm(np.asarray(boxes, dtype=float).reshape(-1, 7)[:, :2] - origin, axis=1)
    share = np.where(own, 1.0, 0.0)
    occluders = np.flatnonzero(~own)
    for k in np.flatnonzero(~own & (distance <= sensor_range)):
        directions = _rays_across(corners[k] - origin, rays)
        hits = first_hits(origin, directions, corners[occluders])
        mine = hits[:, np.searchsorted(occluders, k)]
        share[k] = np.mean(np.isfinite(mine) & (mine <= hits.min(axis=1)))
    return share


def _rays_across(corners: np.ndarray, rays: int) -> np.ndarray:
    """(rays, 2) unit directions evenly inside the angle the footprint ``corners`` (relative to the
    sensor, which lies outside it) subtends."""
    centre = np.arctan2(*corners.mean(axis=0)[::-1])
    offsets = se2.wrap_angle(np.arctan2(corners[:, 1], corners[:, 0]) - centre)
    angles = centre + np.linspace(offsets.min(), offsets.max(), rays + 2)[1:-1]
    return np.stack([np.cos(angles), np.sin(angles)], axis=1)


def line_of_sight(boxes: np.ndarray, pose: np.ndarray, sensor_range: float, share: float = SHARE) -> np.ndarray:
    """(N,) mask of the boxes the agent at ``pose`` (agent->world) sees: within range and at least
    ``share`` of the footprint in sight (``visible_share``)."""
    return visible_share(boxes, se2.translation_of(pose), sensor_range) >= share


def sight_outline(boxes: np.ndarray, origin: np.ndarray, sensor_range: float, rays: int = OUTLINE_RAYS) -> np.ndarray:
    """(rays, 2) the outline of what a sensor at ``origin`` sees: along each of ``rays`` directions
    all around, the first footprint met or the range, whichever is nearer. Inside it the sensor
    sees the ground; within range outside it lie the shadows of the boxes."""
    origin = np.asarray(origin, dtype=float)
    corners = footprints(boxes)
    corners = corners[~contains(corners, origin)] if len(corners) else corners
    angles = np.linspace(-np.pi, np.pi, rays, endpoint=False)
    directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    reach = np.full(rays, float(sensor_range))
    if len(corners):
        reach = np.minimum(reach, first_hits(origin, directions, corners).min(axis=1))
    return origin + directions * reach[:, None]
