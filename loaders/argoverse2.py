"""Argoverse 2 sensor-dataset logs, read from their native files.

A log folder holds ``annotations.feather`` (or ``annotations_with_ego.feather``), optionally
``city_SE3_egovehicle.feather`` and ``map/log_map_archive_*.json``. One frame per LiDAR sweep
(``timestamp_ns``); the frame id is that timestamp, ``Sequence.timestamps`` are seconds since
the first sweep.

World frame: the city frame when ``city_SE3_egovehicle.feather`` exists -- every box is mapped
with the recording car's pose at its sweep (the pose row whose timestamp equals the sweep's) --
otherwise the recording car's frame at each sweep (then there is no map: it is drawn in the
city frame). The recording car is the agent ``"ego"``: its pose is the egovehicle frame (origin at
the rear axle, which is the frame its boxes are given in), with a typical car size of
4.9 x 2.0 x 1.6 m for drawing, since the log does not give one. Box yaw is the heading of the
box's x axis after rotating it by its quaternion (scipy), projected on the ground plane.
Categories keep Argoverse's own names (REGULAR_VEHICLE, PEDESTRIAN, ...). Where the annotations
count each box's lidar points (``num_interior_pts``), the objects with at least one are what the
recording car saw: its ``visibility`` (the other agents' is not said).
"""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import polars as pl
from scipy.spatial.transform import Rotation

from .errors import READ_ERRORS, LoaderError, nonempty_file, shown
from .scene import MapGeometry, Sequence
from .tables import drop_unusable, read_arrow, require_rows

ANNOTATION_FILES = ("annotations.feather", "annotations_with_ego.feather")
POSE_FILE = "city_SE3_egovehicle.feather"
EGO_SIZE = (4.9, 2.0, 1.6)

QUATERNION = ["qw", "qx", "qy", "qz"]
TRANSLATION = ["tx_m", "ty_m", "tz_m"]
ANNOTATION_TYPES = {
    "timestamp_ns": pl.Int64, "track_uuid": pl.Utf8, "category": pl.Utf8,
    "length_m": pl.Float64, "width_m": pl.Float64, "height_m": pl.Float64,
    **{c: pl.Float64 for c in QUATERNION + TRANSLATION},
}
POSE_TYPES = {"timestamp_ns": pl.Int64, **{c: pl.Float64 for c in QUATERNION + TRANSLATION}}
EXPECTED = "an Argoverse 2 log (annotations.feather)"
POINTS = "num_interior_pts"
"""The optional column of lidar points inside each box: at least one and the recording car saw it."""


def recognises(path: Path) -> bool:
    """Whether ``path`` is a log folder, a folder holding one, or a log's annotation file."""
    if path.is_file():
        return path.name in ANNOTATION_FILES
    return find_log(path) is not None


def is_log(folder: Path) -> bool:
    """Whether ``folder`` holds an Argoverse 2 annotation file."""
    return any((folder / name).is_file() for name in ANNOTATION_FILES)


def find_log(folder: Path) -> Path | None:
    """``folder`` itself if it is a log, else its only subfolder that is a log."""
    if is_log(folder):
        return folder
    logs = [sub for sub in sorted(folder.iterdir()) if sub.is_dir() and is_log(sub)]
    if len(logs) > 1:
        raise LoaderError(f"{folder}: holds {len(logs)} Argoverse 2 logs "
                          f"({', '.join(p.name for p in logs)}); open one of them")
    return logs[0] if logs else None


def load(path: str | Path) -> Sequence:
    """Load one Argoverse 2 log folder (or a folder holding exactly one log)."""
    folder = Path(path)
    if folder.is_file() and folder.name in ANNOTATION_FILES:
        folder = folder.parent
    log = find_log(folder) if folder.is_dir() else None
    if log is None:
        raise LoaderError(f"{folder}: no {' or '.join(ANNOTATION_FILES)} here")
    annotations_file = next(log / n for n in ANNOTATION_FILES if (log / n).is_file())
    boxes, dropped = drop_unusable(
        annotations_file, read_arrow(annotations_file, {**ANNOTATION_TYPES, POINTS: pl.Int64}, optional=(POINTS,)),
        list(ANNOTATION_TYPES))
    require_rows(annotations_file, boxes)
    sweeps = np.unique(boxes["timestamp_ns"].to_numpy())
    frame = np.searchsorted(sweeps, boxes["timestamp_ns"].to_numpy())
    ego_rotation, ego_translation = _ego_poses(log / POSE_FILE, sweeps)
    centres, yaws = _boxes_in_world(annotations_file, boxes, frame, ego_rotation, ego_translation)
    objects = pl.DataFrame({
        "frame": frame,
        "track_id": boxes["track_uuid"],
        "category": boxes["category"],
        "x": centres[:, 0], "y": centres[:, 1], "z": centres[:, 2],
        "length": boxes["length_m"], "width": boxes["width_m"], "height": boxes["height_m"],
        "yaw": yaws,
    })
    has_city = (log / POSE_FILE).is_file()
    return Sequence(
        name=f"argoverse2/{log.name}",
        objects=objects,
        frame_ids=[int(t) for t in sweeps],
        timestamps=(sweeps - sweeps[0]) * 1e-9,
        agents=_ego_agent(ego_rotation, ego_translation),
        visibility=_seen_by_the_car(boxes, frame),
        map=_read_map(log) if has_city else None,
        ego="ego",
        dropped_rows=dropped,
    )


def _seen_by_the_car(boxes: pl.DataFrame, frame: np.ndarray) -> pl.DataFrame | None:
    """The recording car's visibility: the objects with a lidar point inside their box, frame by
    frame (None without ``num_interior_pts``)."""
    if POINTS not in boxes.columns:
        return None
    seen = (boxes[POINTS].fill_null(0) > 0).to_numpy()
    return pl.DataFrame({"frame": frame[seen], "agent_id": "ego", "track_id": boxes["track_uuid"].filter(seen)})


def _ego_poses(pose_file: Path, sweeps: np.ndarray) -> tuple[Rotation, np.ndarray]:
    """Rotation and translation (ego-to-city) at each sweep; identity without a pose file."""
    if not pose_file.is_file():
        return Rotation.identity(len(sweeps)), np.zeros((len(sweeps), 3))
    poses, _ = drop_unusable(pose_file, read_arrow(pose_file, POSE_TYPES), list(POSE_TYPES))
    poses = poses.unique("timestamp_ns", keep="first").sort("timestamp_ns")
    times = poses["timestamp_ns"].to_numpy()
    at = np.clip(np.searchsorted(times, sweeps), 0, len(times) - 1)
    missing = times[at] != sweeps
    if missing.any():
        raise LoaderError(f"{pose_file}: no pose row with timestamp_ns {int(sweeps[missing][0])} "
                          f"(a sweep time of the annotations); expected one row per sweep time")
    rows = poses[at]
    return (_rotations(pose_file, rows.select(QUATERNION).to_numpy()),
            rows.select(TRANSLATION).to_numpy())


def _rotations(path: Path, wxyz: np.ndarray) -> Rotation:
    with np.errstate(over="ignore", invalid="ignore"):
        norms = np.linalg.norm(wxyz, axis=1)
    bad = ~np.isfinite(norms) | (norms < 1e-9)
    if bad.any():
        raise LoaderError(f"{path}: row {int(np.argmax(bad)) + 1}: quaternion qw, qx, qy, qz "
                          f"{wxyz[np.argmax(bad)].tolist()} is not a rotation (expected unit length)")
    return Rotation.from_quat(wxyz[:, [1, 2, 3, 0]] / norms[:, None])


def _heading(rotation: Rotation) -> np.ndarray:
    """Yaw of each rotation: the direction of its rotated x axis in the ground plane."""
    x_axis = rotation.apply(np.array([1.0, 0.0, 0.0]))
    return np.arctan2(x_axis[:, 1], x_axis[:, 0])


def _boxes_in_world(path: Path, boxes: pl.DataFrame, frame: np.ndarray, ego_rotation: Rotation,
                    ego_translation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Box centres ``(N, 3)`` and yaws ``(N,)`` in the world frame."""
    to_world = ego_rotation[frame]
    centres = to_world.apply(boxes.select(TRANSLATION).to_numpy()) + ego_translation[frame]
    own = _rotations(path, boxes.select(QUATERNION).to_numpy())
    return centres, _heading(to_world * own)


def _ego_agent(rotation: Rotation, translation: np.ndarray) -> pl.DataFrame:
    n = len(translation)
    length, width, height = EGO_SIZE
    return pl.DataFrame({
        "frame": np.arange(n), "agent_id": ["ego"] * n,
        "x": translation[:, 0], "y": translation[:, 1], "z": translation[:, 2],
        "yaw": _heading(rotation),
        "length": np.full(n, length), "width": np.full(n, width), "height": np.full(n, height),
    })


def _read_map(log: Path) -> MapGeometry | None:
    files = sorted((log / "map").glob("log_map_archive_*.json"))
    if not files:
        return None
    path = nonempty_file(files[0])
    try:
        data = json.loads(path.read_bytes())
    except (*READ_ERRORS, RecursionError) as exc:
        raise LoaderError(f"{path}: not valid JSON ({exc})") from exc
    if not isinstance(data, dict):
        raise LoaderError(f"{path}: expected a JSON object with {', '.join(MAP_SECTIONS)}")
    _check_sections(path, data)
    polylines = []
    for key, segment in _entries(path, data, "lane_segments"):
        for side in ("left_lane_boundary", "right_lane_boundary"):
            polylines.append(("lane_boundary", _points(path, segment, f"lane_segments[{key}]", side)))
    for key, crossing in _entries(path, data, "pedestrian_crossings"):
        edge1 = _points(path, crossing, f"pedestrian_crossings[{key}]", "edge1")
        edge2 = _points(path, crossing, f"pedestrian_crossings[{key}]", "edge2")
        polylines.append(("crossing", np.vstack([edge1, edge2[::-1], edge1[:1]])))
    for key, area in _entries(path, data, "drivable_areas"):
        boundary = _points(path, area, f"drivable_areas[{key}]", "area_boundary")
        polylines.append(("drivable_area", np.vstack([boundary, boundary[:1]])))
    return MapGeometry(polylines)


MAP_SECTIONS = ("lane_segments", "pedestrian_crossings", "drivable_areas")
"""What an Argoverse 2 map holds (av2's ``ArgoverseStaticMap.from_json`` reads these three)."""


def _check_sections(path: Path, data: dict) -> None:
    """``LoaderError`` for a map with none of ``MAP_SECTIONS`` (it would draw as an empty map); a
    warning naming the keys that are not read beside them."""
    unknown = [str(key) for key in data if key not in MAP_SECTIONS]
    if not any(key in data for key in MAP_SECTIONS):
        raise LoaderError(f"{path}: none of {', '.join(MAP_SECTIONS)} (keys: {shown(unknown)}): "
                          f"not an Argoverse 2 map")
    if unknown:
        warnings.warn(f"{path}: key(s) {shown(unknown)} not read (an Argoverse 2 map holds "
                      f"{', '.join(MAP_SECTIONS)})", UserWarning, stacklevel=4)


def _entries(path: Path, data: dict, key: str) -> list[tuple[str, dict]]:
    section = data.get(key, {})
    items = section.items() if isinstance(section, dict) else enumerate(section) if isinstance(section, list) else None
    if items is None:
        raise LoaderError(f"{path}: {key} must be an object or a list")
    entries = []
    for name, entry in items:
        if not isinstance(entry, dict):
            raise LoaderError(f"{path}: {key}[{name}] must be an object")
        entries.append((str(name), entry))
    return entries


def _points(path: Path, entry: dict, where: str, key: str) -> np.ndarray:
    """An ``(M, 2)`` array from a list of ``{x, y, z}`` points."""
    points = entry.get(key)
    if not isinstance(points, list) or not points:
        raise LoaderError(f"{path}: {where}.{key}: expected a non-empty list of {{x, y, z}} points")
    try:
        xy = np.array([[p["x"], p["y"]] for p in points], dtype=np.float64)
    except (KeyError, TypeError, ValueError, OverflowError) as exc:
        raise LoaderError(f"{path}: {where}.{key}: expected points with numeric x and y ({exc!r})") from exc
    if not np.isfinite(xy).all():
        raise LoaderError(f"{path}: {where}.{key}: NaN or infinite coordinate")
    return xy
