"""V2X-Sim 2.0: nuScenes-style JSON tables with one LiDAR per agent (``LIDAR_TOP_id_<k>``).

Layout (nuScenes tables, agents told apart by channel, as ``coperception/coperception``
``tools/det/create_data_det.py`` reads them):
open the dataset root (holding ``v2.0-mini/``, ``v2.0-trainval/`` or another ``v<x>.<y>-<split>/``
table folder) or the table folder itself. The tables read, field by field:

- ``scene.json``: ``token, name, first_sample_token`` -- every scene, in file order, one after the
  other (``Sequence.scenarios`` gives each one's first frame; frame ids are ``<scene name>/<k>``);
- ``sample.json``: ``token, timestamp`` (microseconds), ``next`` (the linked list of a scene's
  samples) -- one sample is one frame; ``Sequence.timestamps`` are seconds from the first sample;
- ``sample_data.json``: ``sample_token, ego_pose_token, calibrated_sensor_token, is_key_frame``;
  ``calibrated_sensor.json``: ``token, sensor_token, translation, rotation``; ``sensor.json``:
  ``token, channel`` -- a key frame of channel ``LIDAR_TOP_id_<k>`` makes agent ``"<k>"`` present,
  at its LiDAR pose in the world: ``ego_pose`` (``translation``, ``rotation``) composed with the
  sensor's calibration. Agent ``"0"`` is the roadside unit (a 0.6 x 0.6 x 5 m pole); ``"1"``...
  are vehicles (typical car size); the ego is the smallest vehicle id present in the first frame;
- ``sample_annotation.json``: ``sample_token, instance_token, translation`` (box centre, world),
  ``size`` (``[width, length, height]``, nuScenes order), ``rotation`` (quaternion ``[w, x, y, z]``;
  yaw = heading of the box's x axis on the ground plane); ``instance.json``
  (``token, category_token``) and ``category.json`` (``token, name``) give the class: ``vehicle.<x>``
  becomes ``<x>`` (``car``, ``truck``, ``bus``...), other names are kept (``human.pedestrian.adult``).
  Track id: the ``instance_token``.

Per-agent visibility: the tables annotate each sample once for all agents (``num_lidar_pts`` counts
the points of every agent together), so what each agent sees cannot be derived:
``frame.visibility`` is ``None`` and the OPV2V protocol falls back to the sensor range. The world
frame is the CARLA town's, already right-handed in V2X-Sim's tables (as in nuScenes).
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import polars as pl

from .errors import LoaderError, shown
from .scene import Sequence
from .structured import field, number, numbers, read_json

TABLES = ("scene", "sample", "sample_data", "ego_pose", "calibrated_sensor", "sensor",
          "sample_annotation", "instance", "category")
TABLE_FOLDER = re.compile(r"^v\d+\.\d+-[\w-]+$")
LIDAR_CHANNEL = re.compile(r"^LIDAR_TOP_id_(\d+)$")
RSU_ID = "0"
CAV_SIZE = (4.9, 2.0, 1.6)
RSU_SIZE = (0.6, 0.6, 5.0)
OBJECT_SCHEMA = {"frame": pl.Int64, "track_id": pl.Utf8, "category": pl.Utf8,
                 **{c: pl.Float64 for c in ("x", "y", "z", "length", "width", "height", "yaw")}}
AGENT_SCHEMA = {"frame": pl.Int64, "agent_id": pl.Utf8,
                **{c: pl.Float64 for c in ("x", "y", "z", "yaw", "length", "width", "height")}}
EXPECTED = "a V2X-Sim 2.0 root (v2.0-<split>/ tables with LIDAR_TOP_id_<k> sensors)"


def recognises(path: Path) -> bool:
    folder = _table_folder(path)
    if folder is None:
        return False
    sensors = folder / "sensor.json"
    return sensors.is_file() and b"LIDAR_TOP_id_" in sensors.read_bytes()


def _table_folder(path: Path) -> Path | None:
    """The folder of the JSON tables: ``path`` itself, or its ``v<x>.<y>-<split>`` child."""
    if not path.is_dir():
        return None
    if (path / "scene.json").is_file():
        return path
    children = sorted(p for p in path.iterdir() if p.is_dir() and TABLE_FOLDER.match(p.name)
                      and (p / "scene.json").is_file())
    return children[0] if children else None


def load(path: str | Path) -> Sequence:
    """Load a V2X-Sim 2.0 dataset root or table folder (every scene, one after the other)."""
    path = Path(path)
    folder = _table_folder(path)
    if folder is None:
        raise LoaderError(f"{path}: expected V2X-Sim tables (scene.json ...) here or in a v2.0-<split> folder")
    tables = {name: _table(folder / f"{name}.json") for name in TABLES}
    channels = _lidar_channels(folder, tables)
    data_of, annotations_of = _by_sample(tables["sample_data"]), _by_sample(tables["sample_annotation"])
    objects, agents, frame_ids, stamps, starts = [], [], [], [], {}
    for scene_path, scene in _rows(folder / "scene.json", tables["scene"]):
        starts[str(field(scene_path, scene, "name"))] = len(frame_ids)
        for k, sample in enumerate(_samples(folder, tables, scene)):
            frame = len(frame_ids)
            frame_ids.append(f"{scene['name']}/{k}")
            stamps.append(number(folder / "sample.json", field(folder / "sample.json", sample, "timestamp"),
                                 f"sample {sample['token']}.timestamp") / 1e6)
            agents.extend(_agent_rows(folder, tables, channels, data_of.get(sample["token"], []), frame))
            objects.extend(_object_rows(folder, tables, annotations_of.get(sample["token"], []), frame))
    if not frame_ids:
        raise LoaderError(f"{folder / 'scene.json'}: no scenes with samples")
    agent_table = _frame_table(agents, AGENT_SCHEMA)
    first = agent_table.filter(pl.col("frame") == 0)["agent_id"].to_list()
    vehicles = sorted((a for a in first if a != RSU_ID), key=int)
    return Sequence(
        name=f"v2x_sim/{path.name}",
        objects=_frame_table(objects, OBJECT_SCHEMA),
        frame_ids=frame_ids,
        timestamps=np.asarray(stamps) - stamps[0],
        agents=agent_table,
        ego=vehicles[0] if vehicles else None,
        scenarios=starts if len(starts) > 1 else None,
    )


def _frame_table(rows: list[dict], schema: dict) -> pl.DataFrame:
    return pl.DataFrame(rows, schema=schema, orient="row") if rows else pl.DataFrame(schema=schema)


def _table(path: Path) -> dict[str, dict]:
    """A table's rows by ``token``."""
    return {row["token"]: row for _, row in _rows(path, read_json(path))}


def _rows(path: Path, rows):
    """``(path, row)`` for each row of a table (a JSON list of objects with a ``token``)."""
    records = rows.values() if isinstance(rows, dict) else rows
    if not isinstance(records, (list, type({}.values()))):
        raise LoaderError(f"{path}: expected a JSON list of records")
    for i, row in enumerate(records):
        field(path, row, "token", f"[{i}]")
        yield path, row


def _by_sample(table: dict[str, dict]) -> dict[str, list[tuple[str, dict]]]:
    """``sample token -> [(token, row)]`` of a table with a ``sample_token`` field."""
    grouped: dict[str, list[tuple[str, dict]]] = {}
    for token, row in table.items():
        grouped.setdefault(row.get("sample_token"), []).append((token, row))
    return grouped


def _lidar_channels(folder: Path, tables: dict) -> dict[str, str]:
    """``calibrated_sensor token -> agent id`` for the ``LIDAR_TOP_id_<k>`` sensors."""
    channels = {}
    for token, sensor in tables["sensor"].items():
        match = LIDAR_CHANNEL.match(str(field(folder / "sensor.json", sensor, "channel", f"sensor {token}")))
        if match:
            channels[token] = str(int(match[1]))
    if not channels:
        raise LoaderError(f"{folder / 'sensor.json'}: no LIDAR_TOP_id_<k> channel (expected one per agent)")
    path = folder / "calibrated_sensor.json"
    return {token: channels[row["sensor_token"]] for token, row in tables["calibrated_sensor"].items()
            if field(path, row, "sensor_token", f"calibrated_sensor {token}") in channels}


def _samples(folder: Path, tables: dict, scene: dict) -> list[dict]:
    """A scene's samples in order, following ``first_sample_token`` and ``next``."""
    path, samples = folder / "sample.json", tables["sample"]
    token, out = field(folder / "scene.json", scene, "first_sample_token", f"scene {scene['token']}"), []
    while token:
        if token not in samples or len(out) > len(samples):
            raise LoaderError(f"{path}: sample {token!r} (from scene {scene['name']!r}): no such sample")
        out.append(samples[token])
        token = field(path, samples[token], "next", f"sample {token}")
    return out


def _agent_rows(folder: Path, tables: dict, channels: dict[str, str], sample_data: list, frame: int) -> list[dict]:
    """One row per agent whose LiDAR has a key frame among a sample's ``sample_data``, at its LiDAR pose."""
    rows, path = {}, folder / "sample_data.json"
    for token, data in sample_data:
        if not data.get("is_key_frame", True):
            continue
        agent = channels.get(field(path, data, "calibrated_sensor_token", f"sample_data {token}"))
        if agent is None or agent in rows:
            continue
        ego = _lookup(folder, tables, "ego_pose", field(path, data, "ego_pose_token", f"sample_data {token}"))
        sensor = tables["calibrated_sensor"][data["calibrated_sensor_token"]]
        x, y, z, yaw = _lidar_pose(folder, ego, sensor)
        length, width, height = RSU_SIZE if agent == RSU_ID else CAV_SIZE
        rows[agent] = {"frame": frame, "agent_id": agent, "x": x, "y": y, "z": z, "yaw": yaw,
                       "length": length, "width": width, "height": height}
    return [rows[a] for a in sorted(rows, key=int)]


def _object_rows(folder: Path, tables: dict, annotations: list, frame: int) -> list[dict]:
    path, rows = folder / "sample_annotation.json", []
    for token, ann in annotations:
        where = f"sample_annotation {token}"
        x, y, z = numbers(path, field(path, ann, "translation", where), f"{where}.translation", 3)
        width, length, height = numbers(path, field(path, ann, "size", where), f"{where}.size", 3)
        if min(width, length, height) <= 0:
            raise LoaderError(f"{path}: {where}.size: expected positive [width, length, height], got {ann['size']}")
        rotation = _quaternion(path, field(path, ann, "rotation", where), f"{where}.rotation")
        instance = _lookup(folder, tables, "instance", field(path, ann, "instance_token", where))
        category = _lookup(folder, tables, "category", instance.get("category_token"))
        rows.append({"frame": frame, "track_id": str(ann["instance_token"]),
                     "category": _category(str(category.get("name"))), "x": x, "y": y, "z": z,
                     "length": length, "width": width, "height": height, "yaw": _yaw(rotation)})
    return rows


def _lookup(folder: Path, tables: dict, table: str, token) -> dict:
    if token not in tables[table]:
        raise LoaderError(f"{folder / (table + '.json')}: no record with token {token!r}")
    return tables[table][token]


def _category(name: str) -> str:
    parts = name.split(".")
    return parts[1] if parts[0] == "vehicle" and len(parts) > 1 else name


def _quaternion(path: Path, value, where: str) -> np.ndarray:
    q = np.array(numbers(path, value, where, 4))
    norm = float(np.linalg.norm(q))
    if norm < 1e-9:
        raise LoaderError(f"{path}: {where}: expected a unit quaternion [w, x, y, z], got {shown(value)}")
    return q / norm


def _rotation(q: np.ndarray) -> np.ndarray:
    """3x3 rotation matrix of a unit quaternion ``[w, x, y, z]``."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _yaw(q: np.ndarray) -> float:
    """Heading of the rotated x axis on the ground plane, radians."""
    matrix = _rotation(q)
    return math.atan2(matrix[1, 0], matrix[0, 0])


def _lidar_pose(folder: Path, ego: dict, sensor: dict) -> tuple[float, float, float, float]:
    """``x, y, z, yaw`` of the LiDAR in the world: ``ego_pose`` composed with its calibration."""
    ego_path, cal_path = folder / "ego_pose.json", folder / "calibrated_sensor.json"
    ego_t = np.array(numbers(ego_path, field(ego_path, ego, "translation"), f"ego_pose {ego['token']}.translation", 3))
    ego_r = _rotation(_quaternion(ego_path, field(ego_path, ego, "rotation"), f"ego_pose {ego['token']}.rotation"))
    where = f"calibrated_sensor {sensor['token']}"
    cal_t = np.array(numbers(cal_path, field(cal_path, sensor, "translation"), f"{where}.translation", 3))
    cal_r = _rotation(_quaternion(cal_path, field(cal_path, sensor, "rotation"), f"{where}.rotation"))
    x, y, z = ego_t + ego_r @ cal_t
    world = ego_r @ cal_r
    return float(x), float(y), float(z), math.atan2(world[1, 0], world[0, 0])
