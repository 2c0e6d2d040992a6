"""DAIR-V2X cooperative (DAIR-V2X-C): a vehicle and a roadside infrastructure unit.

Open the ``cooperative-vehicle-infrastructure`` folder (or its ``cooperative/data_info.json``).
Each entry of ``cooperative/data_info.json`` pairs a vehicle frame with an infrastructure frame
(frame ids: the stems of ``vehicle_pointcloud_path`` / ``infrastructure_pointcloud_path``, or of
the image paths) and is one frame here; frame id = the vehicle frame id; timestamps are
index / 10 (the pairs are samples, not a continuous recording, and their label indices are no track
ids: ``Sequence.tracked`` is False).

Capture times: ``<side>-side/data_info.json`` lists a side's frames, ``pointcloud_path`` (``velodyne/
<id>.pcd``) with ``pointcloud_timestamp`` (microseconds, a string; the labels are the LiDAR's). Where
both sides list a pair's frames, ``Sequence.agent_times`` keeps each agent's capture: the vehicle at
the frame's timestamp, the infrastructure its sweep's time apart (e.g. 40 ms earlier). Without those
files, none; a timestamp that is no number is a :class:`LoaderError` naming the file and entry.

Per frame, read:

- ``vehicle-side/label/lidar/<id>.json`` and ``infrastructure-side/label/virtuallidar/<id>.json``:
  lists of ``{type, 3d_dimensions: {h, w, l}, 3d_location: {x, y, z}, rotation}`` (box centre in
  the vehicle LiDAR / infrastructure virtual-LiDAR frame; ``rotation`` the yaw in radians about z);
- ``vehicle-side/calib/lidar_to_novatel/<id>.json`` (``transform: {rotation, translation}``) and
  ``vehicle-side/calib/novatel_to_world/<id>.json`` (``rotation``, ``translation``): vehicle
  LiDAR -> world is their product;
- ``infrastructure-side/calib/virtuallidar_to_world/<id>.json``: infrastructure -> world, with the
  pair's ``system_error_offset {delta_x, delta_y}`` added to its translation (as the DAIR-V2X
  and CoAlign code do);
- without those world calibration files (shared subsets): ``cooperative/calib/lidar_i2v/<vehicle
  id>.json`` (infrastructure LiDAR -> vehicle LiDAR, offset already included by DAIR-V2X's
  ``calib_i2v.py``), the vehicle's LiDAR frame being that pair's world; one warning names them;
- LiDAR points: the ``.pcd`` files ``vehicle_pointcloud_path`` / ``infrastructure_pointcloud_path``
  name (relative to the folder, as OpenCOOD / CoAlign's DAIR dataset joins them; ``x y z
  intensity``, ``DATA binary``), each in its agent's LiDAR frame, the frame its labels and pose
  use (``Sequence.point_clouds``, read on demand by ``Frame.points``; ``None`` without the file).

Real releases (DAIR-V2X-C as distributed, read as the DAIR-V2X devkit and OpenCOOD / CoAlign's
DAIR dataset read it) have gaps and quirks, handled so:

- a pair whose label or calibration file is missing (or a Git LFS pointer) is skipped; the
  sequence's ``warnings`` (and a ``UserWarning``) give the count and the first missing file; nothing loadable is a
  :class:`LoaderError`. A file that exists but is malformed is still a :class:`LoaderError`;
- numbers stored as strings (``"delta_x": "-0.52"``, label sizes, calibration entries) are read as
  numbers; any other string where a number belongs is a :class:`LoaderError` naming file and field;
  the label fields not read (the infrastructure side's ``truncated_state``, ``occluded_state``,
  ``alpha`` are strings such as ``"0"`` and ``"-1.57"``) are not checked;
- a ``system_error_offset`` given as an empty string ``""`` (or absent) is no offset, silently;
- a load over a second shows a progress bar (tqdm, on stderr).

World frame: DAIR-V2X's world frame. Agents ``"vehicle"`` (the ego; typical car size) and
``"infrastructure"`` (a 0.6 x 0.6 x 5 m pole), at their LiDAR poses; each sees its own labels.
The two label sets carry no shared ids, so the same object is associated across them by an
optimal one-to-one assignment of box centres in the world frame within
:data:`ASSOCIATION_RADIUS` metres (derived, not ground truth). Associated objects get the
vehicle's track id and box; track ids are ``v<i>`` / ``i<j>`` (label index in their file).
"""
from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import polars as pl
from scipy.optimize import linear_sum_assignment
from tqdm import tqdm

from .errors import LfsPointer, LoaderError
from .scene import Sequence
from .structured import field, matrix, metres, number, read_json, rotation

ASSOCIATION_RADIUS = 2.0
FRAME_RATE = 10.0
VEHICLE_SIZE = (4.9, 2.0, 1.6)
INFRASTRUCTURE_SIZE = (0.6, 0.6, 5.0)
DATA_INFO = Path("cooperative") / "data_info.json"
EXPECTED = "a DAIR-V2X cooperative folder (cooperative/data_info.json pairing point clouds)"
BROAD = True
"""Recognises any ``cooperative/data_info.json``, V2X-Seq-SPD's too (``v2x_seq`` reads those): tried
after the loaders that recognise narrowly."""
I2V = Path("cooperative") / "calib" / "lidar_i2v"
PROGRESS_DELAY = 1.0
"""Seconds a load runs before its progress bar appears."""
SIDES = ("vehicle", "infrastructure")


class MissingFile(LoaderError):
    """A label or calibration file that data_info.json names and the release lacks."""

    def __init__(self, path: Path) -> None:
        super().__init__(f"{path}: missing (named by cooperative/data_info.json)")
        self.path = path


def recognises(path: Path) -> bool:
    if path.is_file():
        return path.name == "data_info.json" and path.parent.name == "cooperative"
    return (path / DATA_INFO).is_file()


def load(path: str | Path) -> Sequence:
    """Load a DAIR-V2X cooperative folder."""
    path = Path(path)
    root = path.parent.parent if path.is_file() else path
    info_file = root / DATA_INFO
    pairs = read_json(info_file)
    if not isinstance(pairs, list) or not pairs:
        raise LoaderError(f"{info_file}: expected a non-empty list of vehicle/infrastructure pairs")
    objects, agents, seen, frame_ids, missing, clouds, relative, views = [], [], [], [], [], {}, [], {}
    sweeps, times = {side: side_sweeps(root, side) for side in SIDES}, {}
    for k, pair in enumerate(tqdm(pairs, desc="DAIR-V2X pairs", unit="pair", delay=PROGRESS_DELAY, leave=False)):
        try:
            rows = _pair_rows(root, info_file, pair, k, len(frame_ids))
        except (MissingFile, LfsPointer) as exc:
            missing.append(exc)
            continue
        for table, new in zip((objects, seen, agents), rows[1:4]):
            table.extend(new)
        if rows[4]:
            relative.append(rows[0])
        views.update(rows[5])
        clouds.update(_point_files(root, pair, len(frame_ids)))
        gap = capture_gap(root, sweeps, {side: _frame_id(info_file, pair, side, f"[{k}]") for side in SIDES})
        if gap is not None:
            times[len(frame_ids)] = {"vehicle": len(frame_ids) / FRAME_RATE,
                                     "infrastructure": len(frame_ids) / FRAME_RATE + gap}
        frame_ids.append(rows[0])
    if not frame_ids:
        raise LoaderError(f"{info_file}: no pair could be loaded; {len(missing)} lack a label or calibration "
                          f"file, first: {missing[0]}")
    sequence = Sequence(
        name=f"dair-v2x/{root.name}",
        objects=_frame_table(objects, ["track_id", "category"], ["x", "y", "z", "length", "width", "height", "yaw"]),
        frame_ids=frame_ids,
        timestamps=np.arange(len(frame_ids)) / FRAME_RATE,
        agents=_frame_table(agents, ["agent_id"], ["x", "y", "z", "yaw", "length", "width", "height"]),
        visibility=_frame_table(seen, ["agent_id", "track_id"], []),
        ego="vehicle",
        warnings=_skipped_notes(info_file, missing, len(pairs)),
        notes=_relative_notes(root, relative, len(frame_ids)),
    )
    sequence.point_clouds = clouds
    sequence.agent_views = views
    sequence.agent_times = times
    sequence.tracked = False
    return sequence


def side_sweeps(root: Path, side: str) -> dict[str, tuple[int, dict]]:
    """``frame id -> (index, entry)`` of a side's ``data_info.json`` by ``pointcloud_path`` (none without it)."""
    path = root / f"{side}-side" / "data_info.json"
    if not path.is_file():
        return {}
    entries = read_json(path)
    if not isinstance(entries, list):
        raise LoaderError(f"{path}: expected a list of frames (pointcloud_path, pointcloud_timestamp)")
    return {Path(entry["pointcloud_path"]).stem: (k, entry) for k, entry in enumerate(entries)
            if isinstance(entry, dict) and isinstance(entry.get("pointcloud_path"), str)}


def capture_gap(root: Path, sweeps: dict[str, dict], frames: dict[str, str]) -> float | None:
    """Seconds from the vehicle's sweep to the infrastructure's (negative: the infrastructure's came
    first) of a pair whose two frames both sides' ``data_info.json`` list; None otherwise."""
    found = {side: sweeps[side].get(frames[side]) for side in SIDES}
    if None in found.values():
        return None
    stamps = {side: _number(root / f"{side}-side" / "data_info.json", found[side][1].get("pointcloud_timestamp"),
                            f"[{found[side][0]}].pointcloud_timestamp") for side in SIDES}
    return (stamps["infrastructure"] - stamps["vehicle"]) / 1e6


def _pair_rows(root: Path, info_file: Path, pair, k: int, frame: int) -> tuple[str, list, list, list, bool, dict]:
    """(vehicle frame id, object rows, visibility rows, agent rows, whether the poses come from
    ``cooperative/calib/lidar_i2v``, each agent's own labelled boxes) of data_info entry ``k``."""
    where = f"[{k}]"
    vehicle_id = _frame_id(info_file, pair, "vehicle", where)
    infra_id = _frame_id(info_file, pair, "infrastructure", where)
    vehicle_pose, infra_pose, relative = _poses(root, info_file, pair, where, vehicle_id, infra_id)
    vehicle_boxes = _labels(root / "vehicle-side" / "label" / "lidar" / f"{vehicle_id}.json", vehicle_pose)
    infra_boxes = _labels(root / "infrastructure-side" / "label" / "virtuallidar" / f"{infra_id}.json", infra_pose)
    infra_tracks = _associate(vehicle_boxes, infra_boxes)
    objects = [{"frame": frame, "track_id": f"v{i}", **box} for i, box in enumerate(vehicle_boxes)]
    objects += [{"frame": frame, "track_id": track, **box}
                for track, box in zip(infra_tracks, infra_boxes) if track.startswith("i")]
    seen = [{"frame": frame, "agent_id": "vehicle", "track_id": f"v{i}"} for i in range(len(vehicle_boxes))]
    seen += [{"frame": frame, "agent_id": "infrastructure", "track_id": track} for track in infra_tracks]
    agents = [_agent(frame, "vehicle", vehicle_pose, VEHICLE_SIZE),
              _agent(frame, "infrastructure", infra_pose, INFRASTRUCTURE_SIZE)]
    views = {(frame, "vehicle"): _view([f"v{i}" for i in range(len(vehicle_boxes))], vehicle_boxes),
             (frame, "infrastructure"): _view(infra_tracks, infra_boxes)}
    return vehicle_id, objects, seen, agents, relative, views


def _view(tracks: list[str], boxes: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    columns = ["x", "y", "z", "length", "width", "height", "yaw"]
    return np.array(tracks, dtype=str), np.array([[b[c] for c in columns] for b in boxes], float).reshape(-1, 7)


def _poses(root: Path, info_file: Path, pair, where: str, vehicle_id: str,
           infra_id: str) -> tuple[np.ndarray, np.ndarray, bool]:
    """The vehicle's and the infrastructure's LiDAR -> world poses (4x4) and whether they are the
    relative fallback: with the world calibration, DAIR-V2X's world frame and ``system_error_offset``
    added to the infrastructure's translation; without it (a subset lacking ``lidar_to_novatel`` /
    ``novatel_to_world`` / ``virtuallidar_to_world``), ``cooperative/calib/lidar_i2v/<vehicle
    frame>.json`` with the vehicle's LiDAR frame as the world. That file already includes the
    offset (DAIR-V2X's ``tools/dataset_converter/calib_i2v.py`` adds it before composing), so it is
    not added again."""
    try:
        offset = system_error_offset(pair.get("system_error_offset") if isinstance(pair, dict) else None)
        return (_vehicle_to_world(root, vehicle_id),
                _infrastructure_to_world(root, infra_id, info_file, offset, f"{where}.system_error_offset"), False)
    except MissingFile as world_missing:
        i2v_file = root / I2V / f"{vehicle_id}.json"
        if not i2v_file.is_file():
            raise world_missing from None
        calib = _read(i2v_file)
        return np.eye(4), _rigid(i2v_file, calib.get("transform", calib) if isinstance(calib, dict) else calib), True


def system_error_offset(value):
    """The pair's ``system_error_offset``, with no offset (zeros) where the release gives none: the key
    absent, ``null`` or an empty string ``""`` (as some DAIR-V2X-C pairs ship it). Anything else is
    read as ``{delta_x, delta_y}`` and checked there."""
    if value is None or value == "":
        return {"delta_x": 0.0, "delta_y": 0.0}
    return value


def _relative_notes(root: Path, vehicle_frames: list[str], loaded: int) -> list[str]:
    """The one note naming the pairs whose poses come from ``lidar_i2v``."""
    return pairs_note(vehicle_frames, lambda shown: (
        f"{len(vehicle_frames)} of {loaded} pair(s) ship no world calibration, so the roadside unit is placed "
        f"by the vehicle-to-infrastructure calibration the release ships ({root / I2V}) and the vehicle's "
        f"LiDAR is the world (vehicle frames {shown})"))


def pairs_note(vehicle_frames: list[str], words: Callable[[str], str]) -> list[str]:
    """``[words(the first frames)]`` about some pairs, also a ``UserWarning``; none without pairs."""
    if not vehicle_frames:
        return []
    note = words(", ".join(vehicle_frames[:5]) + (", ..." if len(vehicle_frames) > 5 else ""))
    warnings.warn(note, UserWarning, stacklevel=4)
    return [note]


def _point_files(root: Path, pair: dict, frame: int) -> dict[tuple[int, str], tuple[Path, bool]]:
    """``(frame, agent) -> (PCD file, False)`` for the pair's point clouds that exist (right-handed)."""
    files = {}
    for side in ("vehicle", "infrastructure"):
        path = _existing_file(root, pair.get(f"{side}_pointcloud_path"))
        if path is not None:
            files[(frame, side)] = (path, False)
    return files


def _existing_file(root: Path, name) -> Path | None:
    """``root / name`` when ``name`` is a relative path to a file there, else ``None``."""
    if not isinstance(name, str) or not name or Path(name).is_absolute():
        return None
    try:
        return root / name if (root / name).is_file() else None
    except (OSError, ValueError):
        return None


def _skipped_notes(info_file: Path, missing: list[LoaderError], total: int) -> list[str]:
    """The warning about pairs skipped for missing files (also raised as a ``UserWarning``)."""
    if not missing:
        return []
    pointers = sum(isinstance(exc, LfsPointer) for exc in missing)
    note = (f"{info_file}: skipped {len(missing)} of {total} pair(s) with a missing label or "
            f"calibration file{f' ({pointers} Git LFS pointer(s))' if pointers else ''} (first: {missing[0].path})")
    warnings.warn(note, UserWarning, stacklevel=3)
    return [note]


def _number(path: Path, value, where: str) -> float:
    """``structured.number``, reading a string that holds a number (DAIR-V2X stores some so)."""
    return number(path, _numeric(value), where)


def _numeric(value):
    """``value`` with strings that hold a number (also inside lists) turned into floats."""
    if isinstance(value, list):
        return [_numeric(v) for v in value]
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return value
    return value


def _frame_table(rows: list[dict], text: list[str], floats: list[str]) -> pl.DataFrame:
    schema = {"frame": pl.Int64, **{c: pl.Utf8 for c in text}, **{c: pl.Float64 for c in floats}}
    return pl.DataFrame(rows, schema=schema, orient="row") if rows else pl.DataFrame(schema=schema)


def _frame_id(path: Path, pair, side: str, where: str) -> str:
    for key in (f"{side}_pointcloud_path", f"{side}_image_path"):
        value = pair.get(key) if isinstance(pair, dict) else None
        if isinstance(value, str) and value:
            stem = Path(value).stem
            if stem and all(c.isalnum() or c in "-_" for c in stem):
                return stem
    raise LoaderError(f"{path}: {where}: expected {side}_pointcloud_path or {side}_image_path "
                      f"naming the {side} frame")


def _rigid(path: Path, calib, where: str = "") -> np.ndarray:
    """4x4 transform from ``{rotation: 3x3, translation: 3x1}``: a rotation, and at most
    ``structured.MAX_METRES`` of translation (``LoaderError`` naming the field otherwise)."""
    out = np.eye(4)
    out[:3, :3] = rotation(path, _numeric(field(path, calib, "rotation", where)), f"{where}.rotation".lstrip("."))
    name = f"{where}.translation".lstrip(".")
    translation = matrix(path, _numeric(field(path, calib, "translation", where)), name, 3, 1)
    out[:3, 3] = [metres(path, row[0], f"{name}[{i}][0]") for i, row in enumerate(translation)]
    return out


def _vehicle_to_world(root: Path, frame_id: str) -> np.ndarray:
    calib = root / "vehicle-side" / "calib"
    to_novatel_file = calib / "lidar_to_novatel" / f"{frame_id}.json"
    to_world_file = calib / "novatel_to_world" / f"{frame_id}.json"
    to_novatel = _rigid(to_novatel_file, field(to_novatel_file, _read(to_novatel_file), "transform"), "transform")
    return _rigid(to_world_file, _read(to_world_file)) @ to_novatel


def _infrastructure_to_world(root: Path, frame_id: str, info_file: Path, offset, where: str) -> np.ndarray:
    calib_file = root / "infrastructure-side" / "calib" / "virtuallidar_to_world" / f"{frame_id}.json"
    pose = _rigid(calib_file, _read(calib_file))
    pose[0, 3] += metres(info_file, _numeric(field(info_file, offset, "delta_x", where)), f"{where}.delta_x")
    pose[1, 3] += metres(info_file, _numeric(field(info_file, offset, "delta_y", where)), f"{where}.delta_y")
    return pose


def _read(path: Path):
    if not path.is_file():
        raise MissingFile(path)
    return read_json(path)


def _yaw(pose: np.ndarray, yaw: float = 0.0) -> float:
    heading = pose[:3, :3] @ np.array([np.cos(yaw), np.sin(yaw), 0.0])
    return float(np.arctan2(heading[1], heading[0]))


def _labels(path: Path, pose: np.ndarray) -> list[dict]:
    """The label file's boxes mapped to the world frame."""
    return label_boxes(path, label_list(path), pose)


def label_list(path: Path) -> list:
    """The list of labelled objects a DAIR-V2X label file holds (:class:`MissingFile` when absent)."""
    labels = _read(path)
    if not isinstance(labels, list):
        raise LoaderError(f"{path}: expected a list of labelled objects")
    return labels


def label_boxes(path: Path, labels: list, pose: np.ndarray) -> list[dict]:
    """``{category, x, y, z, length, width, height, yaw}`` of each label of ``path``, mapped to the
    world with ``pose`` (sensor -> world, 4x4). Only the box fields are read: the others
    (``truncated_state``, ``occluded_state``, ``alpha``, ``2d_box``), numbers or strings, are ignored."""
    boxes = []
    for i, label in enumerate(labels):
        where = f"[{i}]"
        size = field(path, label, "3d_dimensions", where)
        location = field(path, label, "3d_location", where)
        centre = np.array([metres(path, _numeric(field(path, location, a, f"{where}.3d_location")),
                                  f"{where}.3d_location.{a}") for a in "xyz"] + [1.0])
        length, width, height = (metres(path, _numeric(field(path, size, a, f"{where}.3d_dimensions")),
                                        f"{where}.3d_dimensions.{a}")
                                 for a in "lwh")
        yaw = _number(path, field(path, label, "rotation", where), f"{where}.rotation")
        x, y, z, _ = pose @ centre
        boxes.append({"category": str(field(path, label, "type", where)), "x": float(x), "y": float(y),
                      "z": float(z), "length": length, "width": width, "height": height,
                      "yaw": _yaw(pose, yaw)})
    return boxes


def _associate(vehicle: list[dict], infrastructure: list[dict]) -> list[str]:
    """Track id of each infrastructure box: the vehicle's ``v<i>`` when associated, else ``i<j>``."""
    tracks = [f"i{j}" for j in range(len(infrastructure))]
    if not vehicle or not infrastructure:
        return tracks
    a = np.array([[b["x"], b["y"]] for b in vehicle])
    b = np.array([[b["x"], b["y"]] for b in infrastructure])
    cost = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(cost)
    for i, j in zip(rows, cols):
        if cost[i, j] <= ASSOCIATION_RADIUS:
            tracks[j] = f"v{i}"
    return tracks


def _agent(frame: int, agent_id: str, pose: np.ndarray, size: tuple[float, float, float]) -> dict:
    return {"frame": frame, "agent_id": agent_id, "x": float(pose[0, 3]), "y": float(pose[1, 3]),
            "z": float(pose[2, 3]), "yaw": _yaw(pose), "length": size[0], "width": size[1], "height": size[2]}
