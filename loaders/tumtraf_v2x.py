"""TUMTraf-V2X (Zimmer et al., CVPR 2024): a test vehicle and the S110 roadside unit of the Providentia
test field, labelled once in OpenLABEL.

Open a release root (``train/``, ``val/``, ``test/``: each split a scenario), a split folder, or the
label folder ``<split>/labels_point_clouds/s110_lidar_ouster_south_and_vehicle_lidar_robosense_registered/``
(the layout of ``tum-traffic-dataset/tum-traffic-dataset-dev-kit``'s README and of CoopDet3D's
``tools/data_converter/tumtraf_v2x_converter.py``). Each ``.json`` there is one OpenLABEL file:
``openlabel.frames.<frame id>`` with

- ``objects.<uuid>.object_data``: ``type`` (CAR, TRUCK, TRAILER, VAN, BUS, PEDESTRIAN, BICYCLE,
  MOTORCYCLE, EMERGENCY_VEHICLE, OTHER: lower-cased into the category) and ``cuboid.val`` =
  ``[x, y, z, qx, qy, qz, qw, length, width, height]``, the box in the infrastructure LiDAR's frame
  (``s110_lidar_ouster_south``, the world here); the uuid is the track id (kept across frames);
- ``frame_properties.timestamp`` (seconds) and ``frame_properties.transforms.
  vehicle_lidar_robosense_to_s110_lidar_ouster_south.transform_src_to_dst.matrix4x4``: the vehicle
  LiDAR's pose in that frame.

Agents: ``"vehicle"`` (the vehicle LiDAR, the ego) and ``"infrastructure"`` (the south Ouster LiDAR,
at the origin). The labels are one fused list; which sensor saw an object is the cuboid's text
attribute ``sensor_id`` (``vehicle_lidar_robosense``, ``s110_lidar_ouster_south``, or both joined by
``_and_``, as the dev kit writes it). When any object lacks it, the sequence has no per-agent
visibility (trials fall back to the sensor range) and one warning counts those objects. Not read:
``coordinate_systems``, images, point clouds.
"""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from . import dair_v2x as dair
from .errors import LoaderError
from .scene import AGENT_COLUMNS, BOX_COLUMNS, Sequence
from .structured import field, numbers, read_json, rigid

REGISTERED = "s110_lidar_ouster_south_and_vehicle_lidar_robosense_registered"
LABELS = Path("labels_point_clouds") / REGISTERED
TRANSFORM = "vehicle_lidar_robosense_to_s110_lidar_ouster_south"
SENSORS = {"vehicle": "vehicle_lidar_robosense", "infrastructure": "s110_lidar_ouster_south"}
SPLITS = ("train", "val", "test")
EXPECTED = f"a TUMTraf-V2X root, split or {LABELS.as_posix()} folder"


def recognises(path: Path) -> bool:
    return path.is_dir() and bool(_label_folders(path))


def _label_folders(path: Path) -> list[tuple[str, Path]]:
    """``(scenario, folder of OpenLABEL files)`` under ``path``: the folder itself, a split's, or each split's."""
    if path.name == REGISTERED:
        return [(path.parent.parent.name, path)]
    if (path / LABELS).is_dir():
        return [(path.name, path / LABELS)]
    return [(split, path / split / LABELS) for split in SPLITS if (path / split / LABELS).is_dir()]


def load(path: str | Path) -> Sequence:
    """Load a TUMTraf-V2X release root, split or registered label folder."""
    path = Path(path)
    files = [(scenario, file) for scenario, folder in _label_folders(path) for file in sorted(folder.glob("*.json"))]
    if not files:
        raise LoaderError(f"{path}: no OpenLABEL .json files in {LABELS}")
    several = len({scenario for scenario, _ in files}) > 1
    objects, agents, seen, frame_ids, times, scenarios, unattributed = [], [], [], [], [], {}, 0
    for scenario, file in files:
        for frame in _frames(file):
            k = len(frame_ids)
            scenarios.setdefault(scenario, k)
            stamp = file.stem.split("_s110")[0]
            frame_ids.append(f"{scenario}/{stamp}" if several else stamp)
            times.append(frame["timestamp"])
            agents += [dair._agent(k, "vehicle", frame["vehicle"], dair.VEHICLE_SIZE),
                       dair._agent(k, "infrastructure", np.eye(4), dair.INFRASTRUCTURE_SIZE)]
            for track, box, sensors in frame["objects"]:
                objects.append({"frame": k, "track_id": track, **box})
                seen += [{"frame": k, "agent_id": agent, "track_id": track} for agent in sensors]
                unattributed += not sensors
    return Sequence(
        name=f"tumtraf-v2x/{path.name}",
        objects=dair._frame_table(objects, ["track_id", "category"], BOX_COLUMNS),
        frame_ids=frame_ids,
        timestamps=np.array(times) - times[0],
        agents=dair._frame_table(agents, ["agent_id"], list(AGENT_COLUMNS)[1:]),
        visibility=None if unattributed else dair._frame_table(seen, ["agent_id", "track_id"], []),
        ego="vehicle",
        scenarios=scenarios,
        warnings=_unattributed_notes(path, unattributed, len(objects)),
    )


def _frames(path: Path) -> list[dict]:
    """``{timestamp, vehicle (4x4 pose), objects: [(uuid, box, agents that saw it)]}`` of each frame of a file."""
    frames = field(path, field(path, read_json(path), "openlabel"), "frames", "openlabel")
    if not isinstance(frames, dict) or not frames:
        raise LoaderError(f"{path}: openlabel.frames: expected a mapping of frame ids to frames")
    out = []
    for frame_id, frame in frames.items():
        where = f"openlabel.frames.{frame_id}"
        properties = field(path, frame, "frame_properties", where)
        transform = field(path, field(path, properties, "transforms", f"{where}.frame_properties"), TRANSFORM,
                          f"{where}.frame_properties.transforms")
        matrix4x4 = field(path, field(path, transform, "transform_src_to_dst", TRANSFORM), "matrix4x4",
                          f"{TRANSFORM}.transform_src_to_dst")
        items = field(path, frame, "objects", where)
        if not isinstance(items, dict):
            raise LoaderError(f"{path}: {where}.objects: expected a mapping of object uuids to objects")
        out.append({"timestamp": dair._number(path, field(path, properties, "timestamp", f"{where}.frame_properties"),
                                              f"{where}.frame_properties.timestamp"),
                    "vehicle": rigid(path, matrix4x4, f"{TRANSFORM}.transform_src_to_dst.matrix4x4"),
                    "objects": [_object(path, f"{where}.objects.{uuid}", uuid, item) for uuid, item in items.items()]})
    return out


def _object(path: Path, where: str, uuid: str, item) -> tuple[str, dict, list[str]]:
    """``(uuid, box, agents whose sensor_id names them)`` of one OpenLABEL object."""
    data = field(path, item, "object_data", where)
    cuboid = field(path, data, "cuboid", f"{where}.object_data")
    x, y, z, qx, qy, qz, qw, length, width, height = numbers(path, field(path, cuboid, "val", f"{where}.cuboid"),
                                                             f"{where}.object_data.cuboid.val", 10)
    yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
    box = {"category": str(field(path, data, "type", f"{where}.object_data")).lower(), "x": x, "y": y, "z": z,
           "length": length, "width": width, "height": height, "yaw": yaw}
    sensor_id = _sensor_id(cuboid)
    return str(uuid), box, [agent for agent, sensor in SENSORS.items() if sensor in sensor_id]


def _sensor_id(cuboid: dict) -> str:
    """The cuboid's text attribute ``sensor_id``, ``""`` when it has none."""
    texts = cuboid.get("attributes", {}).get("text", []) if isinstance(cuboid.get("attributes"), dict) else []
    values = [a.get("val") for a in texts if isinstance(a, dict) and a.get("name") == "sensor_id"]
    return values[0] if values and isinstance(values[0], str) else ""


def _unattributed_notes(path: Path, unattributed: int, total: int) -> list[str]:
    """The one warning when objects carry no ``sensor_id`` naming a sensor (also a ``UserWarning``)."""
    if not unattributed:
        return []
    note = (f"{path}: {unattributed} of {total} object(s) have no sensor_id attribute naming "
            f"{' or '.join(SENSORS.values())}: no per-agent visibility (trials use the sensor range)")
    warnings.warn(note, UserWarning, stacklevel=3)
    return [note]
