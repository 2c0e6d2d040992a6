"""Seeded synthetic traffic at a four-arm intersection, for tests, benchmarks and teaching.

Two roads cross at the origin: road A along x, road B along y, each with ``k`` lanes per
direction (3.5 m, right-hand traffic), a parking strip at each kerb, sidewalks beyond, and a
pedestrian crossing on every arm. The signal is green for road A:

- road A's cars drive through at a common speed per direction, in platoons with 6-10 m
  headway; a few westbound cars in the kerb lane turn right into road B northbound;
- road B's cars queue, stopped, behind the stop lines (red), while the cars that left at the
  last green drive away from the intersection;
- pedestrians walk over the south crossing (both ways) and along the sidewalks, away from the
  intersection; parked cars stand in the parking strips.

Every object moves along a fixed path at a fixed speed (the same speed for every object on a
lane), and the paths only meet where the turning cars join an emptied departing lane, so objects
placed apart in the first frame stay apart in every frame (the tests check this). The road arms
grow with the object count (and the lanes per direction, from 1 to 4), so up to ``MAX_OBJECTS``
(2000) objects fit without overlap.
Every random draw comes from ``numpy.random.default_rng(seed)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import polars as pl

from .errors import LoaderError
from .scene import Sequence
from .synthetic_layout import DEPARTURE_START, SIDEWALK_START, STOP_LINE, Layout, Path

MAX_OBJECTS = 2000
FRAME_RATE = 10.0
PEDESTRIAN_SIZE = (0.6, 0.6)


def _lanes_per_direction(n_objects: int) -> int:
    return 1 if n_objects <= 30 else 2 if n_objects <= 250 else 3 if n_objects <= 600 else 4


def _vehicle_sizes(rng: np.random.Generator, n: int, only_cars: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Categories and ``(n, 3)`` length, width, height of cars (90 %), trucks and buses."""
    kind = np.zeros(n, dtype=int) if only_cars else rng.choice(3, size=n, p=[0.9, 0.06, 0.04])
    low = np.array([[4.2, 1.75, 1.45], [7.0, 2.3, 3.0], [11.0, 2.55, 3.0]])
    high = np.array([[5.0, 1.95, 1.7], [9.0, 2.5, 3.5], [12.5, 2.55, 3.2]])
    sizes = rng.uniform(low[kind], high[kind])
    return np.array(["car", "truck", "bus"])[kind], sizes


def _spacings(rng: np.random.Generator, lengths: np.ndarray, gap: tuple[float, float]) -> np.ndarray:
    """Centre-to-centre distances between consecutive objects in a line."""
    return (lengths[:-1] + lengths[1:]) / 2 + rng.uniform(*gap, size=max(len(lengths) - 1, 0))


def _needed(lengths: np.ndarray, spacings: np.ndarray) -> float:
    return float(spacings.sum() + (lengths[0] + lengths[-1]) / 2) if len(lengths) else 0.0


def _spread(rng: np.random.Generator, lengths: np.ndarray, spacings: np.ndarray,
            room: float, groups: int) -> np.ndarray:
    """Arclengths of objects spread over ``[0, room]`` in up to ``groups`` platoons: the slack
    goes into the gaps between platoons and before the first."""
    if not len(lengths):
        return np.zeros(0)
    slack = max(room - _needed(lengths, spacings), 0.0)
    breaks = np.zeros(len(lengths), dtype=float)
    cut = rng.choice(len(lengths), size=min(groups, len(lengths)), replace=False)
    breaks[cut] = rng.dirichlet(np.ones(len(cut))) * slack * rng.uniform(0.5, 1.0)
    return lengths[0] / 2 + np.cumsum(np.r_[0.0, spacings] + breaks)


def _split(rng: np.random.Generator, n: int, parts: int) -> np.ndarray:
    return rng.multinomial(n, np.full(parts, 1.0 / parts)) if parts else np.zeros(0, dtype=int)


def generate(n_objects: int = 200, n_frames: int = 50, seed: int = 0) -> Sequence:
    """A synthetic intersection scene with ``n_objects`` objects (0 to 2000) in every one of
    ``n_frames`` frames at 10 Hz; same ``seed`` (a non-negative integer), same scene."""
    if not isinstance(n_objects, (int, np.integer)) or not 0 <= n_objects <= MAX_OBJECTS:
        raise LoaderError(f"synthetic: n_objects must be an integer from 0 to {MAX_OBJECTS}, got {n_objects!r}")
    if not isinstance(n_frames, (int, np.integer)) or n_frames < 1:
        raise LoaderError(f"synthetic: n_frames must be a positive integer, got {n_frames!r}")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise LoaderError(f"synthetic: seed must be a non-negative integer, got {seed!r}")
    rng = np.random.default_rng(seed)
    k = _lanes_per_direction(n_objects)
    n_pedestrians = round(0.12 * n_objects)
    n_parked = round(0.08 * n_objects)
    n_through, n_queued, n_departing = rng.multinomial(
        n_objects - n_pedestrians - n_parked, [0.5, 0.27, 0.23])

    groups = {
        "through": _vehicle_groups(rng, _split(rng, n_through, 2 * k)),
        "queued": _vehicle_groups(rng, _split(rng, n_queued, 2 * k)),
        "departing": _vehicle_groups(rng, _split(rng, n_departing, 2 * k)),
        "parked": _vehicle_groups(rng, _split(rng, n_parked, 8), only_cars=True, gap=(1.5, 3.0)),
    }
    probe = Layout(k, 0.0)
    crossing_room = 2 * probe.edge - 1.0
    per_crossing_line = _split(rng, n_pedestrians, 3)
    on_crossings = np.minimum(per_crossing_line, int(crossing_room // 1.8))
    walkers = _pedestrian_groups(rng, on_crossings, gap=(0.6, 1.2))
    strollers = _pedestrian_groups(rng, _split(rng, int(n_pedestrians - on_crossings.sum()), 16),
                                   gap=(0.8, 4.0))
    layout = Layout(k, _arm_length(probe.edge, groups, strollers))
    speeds = {d: rng.uniform(7.0, 12.0) for d in ("east", "west", "south")}

    placed = [
        *_through(rng, layout, groups["through"], speeds),
        *_queued(layout, groups["queued"], rng),
        *_departing(rng, layout, groups["departing"], speeds),
        *_along(rng, layout.parking_paths(), groups["parked"], 0.0, from_start=False),
        *_walking(rng, layout.crossing_paths(), walkers, from_start=False),
        *_walking(rng, layout.sidewalk_paths(), strollers, from_start=True),
    ]
    return _sequence(rng, placed, n_frames, layout, seed)


@dataclass
class _Group:
    """Objects sharing one line (a lane, a strip, a walking line), front first."""

    categories: np.ndarray
    sizes: np.ndarray
    spacings: np.ndarray

    @property
    def needed(self) -> float:
        return _needed(self.sizes[:, 0], self.spacings)


def _vehicle_groups(rng: np.random.Generator, counts: np.ndarray, only_cars: bool = False,
                    gap: tuple[float, float] = (2.0, 5.0)) -> list[_Group]:
    groups = []
    for count in counts:
        categories, sizes = _vehicle_sizes(rng, int(count), only_cars)
        groups.append(_Group(categories, sizes, _spacings(rng, sizes[:, 0], gap)))
    return groups


def _pedestrian_groups(rng: np.random.Generator, counts: np.ndarray, gap: tuple[float, float]) -> list[_Group]:
    groups = []
    for count in counts:
        sizes = np.column_stack([np.full(count, PEDESTRIAN_SIZE[0]), np.full(count, PEDESTRIAN_SIZE[1]),
                                 rng.uniform(1.55, 1.9, size=count)])
        groups.append(_Group(np.full(count, "pedestrian"), sizes, _spacings(rng, sizes[:, 0], gap)))
    return groups


def _arm_length(edge: float, groups: dict[str, list[_Group]], strollers: list[_Group]) -> float:
    """Shortest arm (rounded up to 10 m, at least 60 m) that holds every line with some room."""
    need = [
        max((g.needed for g in groups["through"]), default=0.0) * 0.6,
        edge + STOP_LINE + max((g.needed for g in groups["queued"]), default=0.0),
        edge + DEPARTURE_START + 20.0 + max((g.needed for g in groups["departing"]), default=0.0) * 1.2,
        edge + SIDEWALK_START + max((g.needed for g in groups["parked"]), default=0.0) * 1.2,
        edge + SIDEWALK_START + max((g.needed for g in strollers), default=0.0) * 1.2,
        60.0,
    ]
    return float(np.ceil((max(need) + 5.0) / 10.0) * 10.0)


@dataclass
class _Placed:
    """Objects on one path: their arclengths at time 0, speed, lateral offsets."""

    path: Path
    group: _Group
    s: np.ndarray
    speed: float
    lateral: np.ndarray


def _through(rng, layout: Layout, groups: list[_Group], speeds: dict) -> list[_Placed]:
    """Road A's moving lanes; in the westbound kerb lane, cars near the corner turn right."""
    placed = []
    k = layout.k
    for index, group in enumerate(groups):
        direction, lane = ("east", "west")[index // k], index % k
        if direction == "west" and lane == k - 1:
            placed.extend(_turning(rng, layout, group, speeds["west"]))
            continue
        path = layout.through_path(direction, lane)
        s = _spread(rng, group.sizes[:, 0], group.spacings, path.length, len(group.sizes) // 5 + 1)
        placed.append(_Placed(path, group, s, speeds[direction], rng.uniform(-0.25, 0.25, size=len(s))))
    return placed


def _turning(rng, layout: Layout, group: _Group, speed: float) -> list[_Placed]:
    """The westbound kerb lane: its foremost car before the corner is part-way round the turn;
    up to three cars (category car) within 30 m of it turn right, the rest go straight."""
    turn, turn_start, turn_end = layout.turn_path()
    straight = layout.through_path("west", layout.k - 1)
    lengths, n = group.sizes[:, 0], len(group.sizes)
    front = turn_start + rng.uniform(0.2, 0.7) * (turn_end - turn_start)
    n_ahead = n - int(np.ceil(n * front / straight.length))
    beyond = turn_end + 10.0
    ahead = beyond + _spread(rng, lengths[:n_ahead], group.spacings[:max(n_ahead - 1, 0)],
                             straight.length - beyond, n_ahead // 5 + 1)
    behind = _spread(rng, lengths[n_ahead:], group.spacings[n_ahead:], front, (n - n_ahead) // 5 + 1)
    s = np.r_[ahead, behind + front - behind[-1] if len(behind) else behind]
    candidates = np.flatnonzero((s <= front) & (s > front - 30.0) & (group.categories == "car"))
    turners = np.zeros(n, dtype=bool)
    turners[candidates[np.argsort(-s[candidates])][: rng.integers(1, 4)]] = True
    lateral = np.where(turners, 0.0, rng.uniform(-0.25, 0.25, size=n))
    return [_Placed(straight, _subset(group, ~turners), s[~turners], speed, lateral[~turners]),
            _Placed(turn, _subset(group, turners), s[turners], speed, lateral[turners])]


def _subset(group: _Group, keep: np.ndarray) -> _Group:
    return _Group(group.categories[keep], group.sizes[keep], np.zeros(0))


def _queued(layout: Layout, groups: list[_Group], rng) -> list[_Placed]:
    """Road B's approach lanes: stopped queues behind the stop lines."""
    placed = []
    for index, group in enumerate(groups):
        direction, lane = ("north", "south")[index // layout.k], index % layout.k
        lengths = group.sizes[:, 0]
        behind_stop = (rng.uniform(0.3, 1.5) + lengths[0] / 2 + np.cumsum(np.r_[0.0, group.spacings])
                       if len(lengths) else np.zeros(0))
        path = layout.queue_path(direction, lane)
        placed.append(_Placed(path, group, path.length - behind_stop, 0.0,
                              rng.uniform(-0.25, 0.25, size=len(lengths))))
    return placed


def _departing(rng, layout: Layout, groups: list[_Group], speeds: dict) -> list[_Placed]:
    """Road B's departing lanes: cars driving away, beyond the crossings and clear of turners."""
    placed = []
    for index, group in enumerate(groups):
        direction, lane = ("north", "south")[index // layout.k], index % layout.k
        path = layout.departure_path(direction, lane)
        start = DEPARTURE_START + (15.0 if direction == "north" and lane == layout.k - 1 else 0.0)
        s = start + _spread(rng, group.sizes[:, 0], group.spacings, path.length - start,
                            len(group.sizes) // 5 + 1)
        speed = speeds["west"] if direction == "north" else speeds["south"]
        placed.append(_Placed(path, group, s, speed, rng.uniform(-0.25, 0.25, size=len(s))))
    return placed


def _along(rng, paths: list[Path], groups: list[_Group], speed: float, from_start: bool) -> list[_Placed]:
    """Objects spread along each path (one group per path)."""
    placed = []
    for path, group in zip(paths, groups):
        s = _spread(rng, group.sizes[:, 0], group.spacings, path.length, len(group.sizes) // 4 + 1)
        placed.append(_Placed(path, group, s if from_start else path.length - s, speed,
                              rng.uniform(-0.1, 0.1, size=len(s))))
    return placed


def _walking(rng, paths: list[Path], groups: list[_Group], from_start: bool) -> list[_Placed]:
    """Pedestrians on walking lines, each line at its own walking speed."""
    placed = _along(rng, paths, groups, 0.0, from_start)
    for p in placed:
        p.speed = rng.uniform(1.1, 1.6)
    return placed


def _sequence(rng, placed: list[_Placed], n_frames: int, layout: Layout, seed: int) -> Sequence:
    times = np.arange(n_frames) / FRAME_RATE
    xy, yaw, categories, sizes = [], [], [], []
    for p in placed:
        if not len(p.s):
            continue
        s = p.s[None, :] + p.speed * times[:, None]
        position, heading = p.path.at(s, np.broadcast_to(p.lateral, s.shape))
        xy.append(position)
        yaw.append(heading)
        categories.append(p.group.categories)
        sizes.append(p.group.sizes)
    n = sum(len(c) for c in categories)
    order = rng.permutation(n)
    if n:
        xy, yaw = np.concatenate(xy, axis=1)[:, order], np.concatenate(yaw, axis=1)[:, order]
        categories, sizes = np.concatenate(categories)[order], np.concatenate(sizes)[order]
    else:
        xy, yaw = np.zeros((n_frames, 0, 2)), np.zeros((n_frames, 0))
        categories, sizes = np.zeros(0, dtype=str), np.zeros((0, 3))
    objects = pl.DataFrame({
        "frame": np.repeat(np.arange(n_frames), n),
        "track_id": np.tile(np.array([str(i) for i in range(n)], dtype=object), n_frames),
        "category": np.tile(categories.astype(object), n_frames),
        "x": xy[..., 0].ravel(), "y": xy[..., 1].ravel(),
        "z": np.tile(sizes[:, 2] / 2, n_frames),
        "length": np.tile(sizes[:, 0], n_frames), "width": np.tile(sizes[:, 1], n_frames),
        "height": np.tile(sizes[:, 2], n_frames),
        "yaw": yaw.ravel(),
    }, schema_overrides={"track_id": pl.Utf8, "category": pl.Utf8})
    return Sequence(
        name=f"synthetic:{n}:seed={seed}",
        objects=objects,
        frame_ids=list(range(n_frames)),
        timestamps=times,
        map=layout.map(),
    )
