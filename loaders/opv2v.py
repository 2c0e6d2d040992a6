"""OPV2V, V2XSet and V2V4Real scenarios: folders of per-CAV YAML annotations.

Layout: ``<scenario>/<cav id>/<timestamp>.yaml``; open the scenario folder (or a single
``.yaml`` file, as a one-frame, one-CAV scene whose agent id is its folder's name). Frames are the
timestamps of the ego's files, at 10 Hz (``Sequence.timestamps`` = index / 10); a CAV missing a
timestamp is absent from that frame.

- The ego is chosen as OpenCOOD does: CAV folders in string order, the first one, except that a
  roadside unit (V2XSet; negative id) never leads -- it moves to the end. Agents keep their folder
  names as ids (``"641"``, ``"-1"``); ``Sequence.ego`` names the ego.
- Agent pose: the CAV's ``lidar_pose`` (the frame its detections are in). Sizes are not in the
  files: CAVs get a typical car size (4.9 x 2.0 x 1.6 m), roadside units a 0.6 x 0.6 x 5 m pole.
- OPV2V / V2XSet (CARLA): poses and boxes are in CARLA's left-handed world; converted on read to
  ``x, -y, -yaw``; angles in degrees -> radians; ``extent`` half sizes -> full sizes; box centre =
  ``location + center`` (added in world axes). Each CAV's file lists the vehicles its LiDAR saw:
  that is the per-CAV visibility; an object's box is taken from the first CAV (in ego order) that
  lists it. Category ``car``.
- V2V4Real (recognised by ``ass_id`` keys): boxes are in each CAV's own LiDAR frame (right-handed,
  real sensors), mapped to the world with that CAV's ``lidar_pose``; category from ``obj_type``.
  ``ass_id`` is the cross-CAV id of the same object (-1: seen by one CAV only): associated objects
  share the track id ``"a<ass_id>"`` (the ego's box is kept), others are ``"<cav>/<id>"``.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import polars as pl

from .errors import LoaderError
from .scene import Sequence
from .structured import field, number, numbers, read_yaml

FRAME_RATE = 10.0
CAV_SIZE = (4.9, 2.0, 1.6)
RSU_SIZE = (0.6, 0.6, 5.0)
SKIPPED = ("additional", "camera_gt")


def recognises(path: Path) -> bool:
    if path.is_file():
        return path.suffix.lower() in (".yaml", ".yml")
    return bool(_cav_folders(path))


def _is_integer(name: str) -> bool:
    return name.lstrip("-").isdigit()


def _yaml_files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.glob("*.yaml") if p.is_file() and not any(s in p.name for s in SKIPPED))


def _cav_folders(scenario: Path) -> list[Path]:
    """CAV folders in OpenCOOD's order: string order, a leading roadside unit moved to the end."""
    folders = sorted((p for p in scenario.iterdir() if p.is_dir() and _is_integer(p.name) and _yaml_files(p)),
                     key=lambda p: p.name)
    if folders and int(folders[0].name) < 0:
        folders = folders[1:] + folders[:1]
    return folders


def load(path: str | Path) -> Sequence:
    """Load an OPV2V / V2XSet / V2V4Real scenario folder or one annotation file."""
    path = Path(path)
    if path.is_file():
        agent = path.parent.name if _is_integer(path.parent.name) else "0"
        files = {agent: {path.stem: path}}
    else:
        cavs = _cav_folders(path)
        if not cavs:
            raise LoaderError(f"{path}: no CAV folders (integer names) holding .yaml files")
        files = {cav.name: {p.stem: p for p in _yaml_files(cav)} for cav in cavs}
    order = list(files)
    stamps = sorted(files[order[0]])
    records = {(k, cav): read_yaml(files[cav][stamp])
               for k, stamp in enumerate(stamps) for cav in order if stamp in files[cav]}
    v2v4real = any(_has_ass_id(record) for record in records.values())
    objects, agents, seen = [], [], []
    for k, stamp in enumerate(stamps):
        kept: set[str] = set()
        for cav in order:
            if (k, cav) not in records:
                continue
            source = files[cav][stamp]
            record = records[(k, cav)]
            pose = _pose(source, record, v2v4real)
            agents.append(_agent_row(k, cav, pose))
            for track, row in _boxes(source, record, cav, pose, v2v4real):
                seen.append({"frame": k, "agent_id": cav, "track_id": track})
                if track not in kept:
                    kept.add(track)
                    objects.append({"frame": k, "track_id": track, **row})
    return Sequence(
        name=f"{'v2v4real' if v2v4real else 'opv2v'}/{path.stem if path.is_file() else path.name}",
        objects=_table(objects, OBJECT_SCHEMA),
        frame_ids=stamps,
        timestamps=np.arange(len(stamps)) / FRAME_RATE,
        agents=_table(agents, AGENT_SCHEMA),
        visibility=_table(seen, {"frame": pl.Int64, "agent_id": pl.Utf8, "track_id": pl.Utf8}),
        ego=order[0],
    )


OBJECT_SCHEMA = {"frame": pl.Int64, "track_id": pl.Utf8, "category": pl.Utf8,
                 **{c: pl.Float64 for c in ("x", "y", "z", "length", "width", "height", "yaw")}}
AGENT_SCHEMA = {"frame": pl.Int64, "agent_id": pl.Utf8,
                **{c: pl.Float64 for c in ("x", "y", "z", "yaw", "length", "width", "height")}}


def _table(rows: list[dict], schema: dict) -> pl.DataFrame:
    return pl.DataFrame(rows, schema=schema, orient="row") if rows else pl.DataFrame(schema=schema)


def _has_ass_id(record) -> bool:
    vehicles = record.get("vehicles") if isinstance(record, dict) else None
    return isinstance(vehicles, dict) and any(isinstance(v, dict) and "ass_id" in v for v in vehicles.values())


def _pose(path: Path, record, right_handed: bool) -> tuple[float, float, float, float]:
    """``x, y, z, yaw`` (radians, right-handed world) of a CAV's ``lidar_pose``."""
    x, y, z, _roll, yaw, _pitch = numbers(path, field(path, record, "lidar_pose"), "lidar_pose", 6)
    yaw = math.radians(yaw)
    return (x, y, z, yaw) if right_handed else (x, -y, z, -yaw)


def _agent_row(frame: int, cav: str, pose: tuple[float, float, float, float]) -> dict:
    length, width, height = RSU_SIZE if int(cav) < 0 else CAV_SIZE
    x, y, z, yaw = pose
    return {"frame": frame, "agent_id": cav, "x": x, "y": y, "z": z, "yaw": yaw,
            "length": length, "width": width, "height": height}


def _boxes(path: Path, record, cav: str, pose, v2v4real: bool):
    """``(track_id, box row)`` for every vehicle in one CAV's file, in the right-handed world."""
    vehicles = field(path, record, "vehicles")
    if vehicles is None:
        return
    if not isinstance(vehicles, dict):
        raise LoaderError(f"{path}: vehicles: expected a mapping of vehicle id -> annotation")
    for vehicle_id, entry in vehicles.items():
        where = f"vehicles[{vehicle_id}]"
        location = numbers(path, field(path, entry, "location", where), f"{where}.location", 3)
        center = numbers(path, field(path, entry, "center", where), f"{where}.center", 3)
        extent = numbers(path, field(path, entry, "extent", where), f"{where}.extent", 3)
        yaw = math.radians(numbers(path, field(path, entry, "angle", where), f"{where}.angle", 2)[1])
        if min(extent) <= 0:
            raise LoaderError(f"{path}: {where}.extent: expected positive half sizes, got {extent}")
        x, y, z = (a + b for a, b in zip(location, center))
        if v2v4real:
            x, y, yaw = _to_world(pose, x, y, yaw)
            z += pose[2]
            ass_id = int(number(path, field(path, entry, "ass_id", where), f"{where}.ass_id"))
            track = f"a{ass_id}" if ass_id != -1 else f"{cav}/{vehicle_id}"
            category = str(entry.get("obj_type", "car"))
        else:
            y, yaw = -y, -yaw
            track, category = str(vehicle_id), "car"
        yield track, {"category": category, "x": x, "y": y, "z": z,
                      "length": 2 * extent[0], "width": 2 * extent[1], "height": 2 * extent[2],
                      "yaw": math.atan2(math.sin(yaw), math.cos(yaw))}


def _to_world(pose, x: float, y: float, yaw: float) -> tuple[float, float, float]:
    px, py, _, pyaw = pose
    c, s = math.cos(pyaw), math.sin(pyaw)
    return px + c * x - s * y, py + s * x + c * y, yaw + pyaw
