"""The geometry of the synthetic intersection (``loaders.synthetic``): lanes, parking strips,
sidewalks and crossings as paths that objects move along, and the map drawn under them."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scene import MapGeometry

LANE = 3.5
PARKING = 2.5
CROSSING = (0.5, 4.5)
STOP_LINE = 5.5
DEPARTURE_START = 13.0
SIDEWALK_START = 7.0


@dataclass
class Path:
    """A polyline driven at constant speed; positions beyond its ends continue straight."""

    points: np.ndarray

    def __post_init__(self) -> None:
        steps = np.diff(self.points, axis=0)
        lengths = np.linalg.norm(steps, axis=1)
        self.directions = steps / lengths[:, None]
        self.start = np.r_[0.0, np.cumsum(lengths)]

    @property
    def length(self) -> float:
        return float(self.start[-1])

    def at(self, s: np.ndarray, lateral: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions ``(..., 2)`` and headings at arclength ``s``, shifted ``lateral`` to the left."""
        segment = np.clip(np.searchsorted(self.start, s, side="right") - 1, 0, len(self.directions) - 1)
        direction = self.directions[segment]
        left = np.stack([-direction[..., 1], direction[..., 0]], axis=-1)
        along = (s - self.start[segment])[..., None]
        xy = self.points[segment] + along * direction + lateral[..., None] * left
        return xy, np.arctan2(direction[..., 1], direction[..., 0])


def line(a: tuple[float, float], b: tuple[float, float]) -> Path:
    return Path(np.array([a, b], dtype=float))


@dataclass
class Layout:
    """Geometry of the intersection for ``k`` lanes per direction and arms of length ``arm``."""

    k: int
    arm: float

    @property
    def edge(self) -> float:
        """Distance from a road's centre line to its kerb (lanes and parking strip)."""
        return self.k * LANE + PARKING

    def lane_offset(self, lane: int) -> float:
        return (lane + 0.5) * LANE

    def through_path(self, direction: str, lane: int) -> Path:
        """Road A through lane, ``"east"`` (south side) or ``"west"`` (north side)."""
        y, L = self.lane_offset(lane), self.arm
        return line((-L, -y), (L, -y)) if direction == "east" else line((L, y), (-L, y))

    def queue_path(self, direction: str, lane: int) -> Path:
        """Road B approach lane, from the end of the arm to the stop line."""
        x, stop, L = self.lane_offset(lane), self.edge + STOP_LINE, self.arm
        return line((x, -L), (x, -stop)) if direction == "north" else line((-x, L), (-x, stop))

    def departure_path(self, direction: str, lane: int) -> Path:
        """Road B departing lane, ``s = 0`` at the intersection's edge."""
        x, e, L = self.lane_offset(lane), self.edge, self.arm
        return line((x, e), (x, L)) if direction == "north" else line((-x, -e), (-x, -L))

    def turn_path(self) -> tuple[Path, float, float]:
        """Westbound kerb lane turning right into northbound kerb lane, with the arclengths where
        the turn starts and ends."""
        e, L = self.edge, self.arm
        y = self.lane_offset(self.k - 1)
        radius = e - y
        angles = np.linspace(-np.pi / 2, -np.pi, 13)
        arc = np.stack([e + radius * np.cos(angles), e + radius * np.sin(angles)], axis=1)
        points = np.vstack([[L, y], arc, [y, L]])
        path = Path(points)
        return path, L - e, path.start[len(arc)]

    def parking_paths(self) -> list[Path]:
        """Parking strips on all arms, pointing along the adjacent lane's traffic."""
        o, start, L = self.k * LANE + PARKING / 2, self.edge + SIDEWALK_START - 1.0, self.arm
        return [line((start, -o), (L, -o)), line((-L, -o), (-start, -o)),
                line((L, o), (start, o)), line((-start, o), (-L, o)),
                line((o, start), (o, L)), line((o, -L), (o, -start)),
                line((-o, L), (-o, start)), line((-o, -start), (-o, -L))]

    def sidewalk_paths(self) -> list[Path]:
        """Two walking lines on each sidewalk, pointing away from the intersection."""
        e, L = self.edge, self.arm
        start = e + SIDEWALK_START
        paths = []
        for offset in (e + 5.0, e + 6.0):
            for sign in (-1.0, 1.0):
                for side in (-1.0, 1.0):
                    paths.append(line((sign * start, side * offset), (sign * L, side * offset)))
                    paths.append(line((side * offset, sign * start), (side * offset, sign * L)))
        return paths

    def crossing_paths(self) -> list[Path]:
        """Walking lines over the south crossing: two eastbound, one westbound."""
        e = self.edge
        return [line((-e, -(e + 1.5)), (e, -(e + 1.5))),
                line((e, -(e + 2.5)), (-e, -(e + 2.5))),
                line((-e, -(e + 3.5)), (e, -(e + 3.5)))]

    def map(self) -> MapGeometry:
        e, L, k = self.edge, self.arm, self.k
        lines = []
        for i in range(k + 1):
            for offset in {i * LANE, -i * LANE}:
                for sign in (-1.0, 1.0):
                    lines.append(np.array([[sign * e, offset], [sign * L, offset]]))
                    lines.append(np.array([[offset, sign * e], [offset, sign * L]]))
        polylines = [("lane_boundary", line) for line in lines]
        near, far = e + CROSSING[0], e + CROSSING[1]
        for flip in (np.array([1.0, 1.0]), np.array([-1.0, -1.0])):
            for swap in (False, True):
                corners = np.array([[-e, near], [e, near], [e, far], [-e, far], [-e, near]]) * flip
                polylines.append(("crossing", corners[:, ::-1] if swap else corners))
        outline = np.array([[L, -e], [e, -e], [e, -L], [-e, -L], [-e, -e], [-L, -e],
                            [-L, e], [-e, e], [-e, L], [e, L], [e, e], [L, e], [L, -e]])
        polylines.append(("drivable_area", outline))
        return MapGeometry(polylines)
