"""V2X-Seq-SPD (Yu et al., CVPR 2023), the sequential perception part of V2X-Seq: a vehicle and a
roadside infrastructure unit over continuous sequences, every object tracked.

Open the ``V2X-Seq-SPD`` folder (or its ``cooperative/data_info.json``). The layout is DAIR-V2X-C's
per side (as ``AIR-THU/DAIR-V2X-Seq``'s ``dataset/v2x-seq-spd/README.md`` gives it and
``AIR-THU/DAIR-V2X``'s ``v2x/dataset/dair_v2x_for_detection_spd.py`` reads it):

- ``cooperative/data_info.json``: a list of pairs ``{vehicle_frame, infrastructure_frame,
  vehicle_sequence, infrastructure_sequence, system_error_offset}`` (frame ids such as ``"000009"``,
  sequence ids such as ``"0000"``); one pair is one frame here, ordered by vehicle sequence then
  vehicle frame; each vehicle sequence is a scenario (``Sequence.scenarios``);
- ``vehicle-side/data_info.json`` and ``infrastructure-side/data_info.json``: one entry per frame
  with ``frame_id``, ``pointcloud_path`` (relative to the side folder) and ``pointcloud_timestamp``
  (microseconds, a string): the frame's time (seconds from the first frame: the vehicle's sweep), each
  agent's capture time (``Sequence.agent_times``: the infrastructure's sweep) and LiDAR points;
- ``vehicle-side/label/lidar/<frame>.json`` and ``infrastructure-side/label/virtuallidar/<frame>.json``:
  DAIR-V2X labels with a ``track_id`` per object, kept across the frames of a sequence;
- ``cooperative/label/<vehicle frame>.json``: the fused objects, in the vehicle LiDAR frame, each
  with its own ``track_id`` and ``veh_track_id`` / ``inf_track_id`` naming the side labels it fuses
  (``"-1"``: that side did not label it);
- the calibration of DAIR-V2X-C (``loaders.dair_v2x``): vehicle LiDAR -> world from
  ``lidar_to_novatel`` and ``novatel_to_world``, infrastructure from ``virtuallidar_to_world`` plus
  the pair's ``system_error_offset``.

The scene's objects are the cooperative label's (track id: its ``track_id``); each agent sees the
objects whose ``veh_track_id`` / ``inf_track_id`` names one of its labels (ground-truth
association), and its own labels are its view (``Sequence.agent_views``). A side label the
cooperative label does not fuse stays an object of its own, ``v<track_id>`` / ``i<track_id>``.
Without a cooperative label for a pair, the two sides are associated as in DAIR-V2X-C (optimal
assignment of world centres within 2 m, derived) and one warning counts those pairs. Pairs missing
a side label or calibration file are skipped and counted, as in DAIR-V2X-C.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from . import dair_v2x as dair
from .errors import LfsPointer, LoaderError, shown
from .scene import AGENT_COLUMNS, BOX_COLUMNS, Sequence
from .structured import field, read_json

DATA_INFO = Path("cooperative") / "data_info.json"
COOPERATIVE_LABELS = Path("cooperative") / "label"
MARKER = b'"vehicle_frame"'
"""What sets a V2X-Seq-SPD pair list apart from DAIR-V2X-C's (whose pairs name point cloud paths)."""
HEAD_BYTES = 4096
NO_TRACK = "-1"
EXPECTED = "a V2X-Seq-SPD folder (cooperative/data_info.json pairing vehicle_frame and infrastructure_frame)"


@dataclass(frozen=True)
class Pair:
    """One entry of ``cooperative/data_info.json``, its frames found in the side ``data_info.json``."""

    where: str
    sequence: str
    vehicle: dict
    infrastructure: dict
    offset: object


def recognises(path: Path) -> bool:
    if path.is_file():
        return path.name == "data_info.json" and path.parent.name == "cooperative" and _names_frames(path)
    return (path / DATA_INFO).is_file() and _names_frames(path / DATA_INFO)


def _names_frames(info_file: Path) -> bool:
    try:
        with info_file.open("rb") as file:
            return MARKER in file.read(HEAD_BYTES)
    except OSError:
        return False


def load(path: str | Path) -> Sequence:
    """Load a V2X-Seq-SPD folder."""
    path = Path(path)
    root = path.parent.parent if path.is_file() else path
    info_file = root / DATA_INFO
    pairs = _pairs(root, info_file)
    rows = {"objects": [], "seen": [], "agents": []}
    frame_ids, times, scenarios, missing, derived, clouds, views = [], [], {}, [], [], {}, {}
    infra_times = []
    for pair in tqdm(pairs, desc="V2X-Seq-SPD pairs", unit="pair", delay=dair.PROGRESS_DELAY, leave=False):
        frame = len(frame_ids)
        try:
            objects, seen, agents, frame_views, fused = _pair_rows(root, info_file, pair, frame)
        except (dair.MissingFile, LfsPointer) as exc:
            missing.append(exc)
            continue
        for name, new in zip(("objects", "seen", "agents"), (objects, seen, agents)):
            rows[name].extend(new)
        views.update(frame_views)
        clouds.update(_point_files(root, pair, frame))
        scenarios.setdefault(pair.sequence, frame)
        frame_ids.append(pair.vehicle["frame_id"])
        times.append(_sweep_time(root, "vehicle", pair.vehicle))
        infra_times.append(_sweep_time(root, "infrastructure", pair.infrastructure))
        if not fused:
            derived.append(pair.vehicle["frame_id"])
    if not frame_ids:
        raise LoaderError(f"{info_file}: no pair could be loaded; {len(missing)} lack a label or calibration "
                          f"file, first: {missing[0]}")
    sequence = Sequence(
        name=f"v2x-seq-spd/{root.name}",
        objects=dair._frame_table(rows["objects"], ["track_id", "category"], BOX_COLUMNS),
        frame_ids=frame_ids,
        timestamps=(np.array(times) - times[0]) / 1e6,
        agents=dair._frame_table(rows["agents"], ["agent_id"], list(AGENT_COLUMNS)[1:]),
        visibility=dair._frame_table(rows["seen"], ["agent_id", "track_id"], []),
        ego="vehicle",
        scenarios=scenarios,
        warnings=dair._skipped_notes(info_file, missing, len(pairs)),
        notes=_derived_notes(root, derived, len(frame_ids)),
    )
    sequence.point_clouds = clouds
    sequence.agent_views = views
    sequence.agent_times = {k: {"vehicle": (vehicle - times[0]) / 1e6, "infrastructure": (infra - times[0]) / 1e6}
                            for k, (vehicle, infra) in enumerate(zip(times, infra_times))}
    return sequence


def _sweep_time(root: Path, side: str, entry: dict) -> float:
    """Microseconds: a side frame's ``pointcloud_timestamp``."""
    return dair._number(root / f"{side}-side" / "data_info.json", entry.get("pointcloud_timestamp"),
                        f"frame {entry['frame_id']}.pointcloud_timestamp")


def _pairs(root: Path, info_file: Path) -> list[Pair]:
    """The pairs of ``cooperative/data_info.json`` with their side entries, in sequence and frame order."""
    entries = read_json(info_file)
    if not isinstance(entries, list) or not entries:
        raise LoaderError(f"{info_file}: expected a non-empty list of vehicle/infrastructure frame pairs")
    sides = {side: _side_frames(root / f"{side}-side" / "data_info.json") for side in ("vehicle", "infrastructure")}
    pairs = []
    for k, entry in enumerate(entries):
        where = f"[{k}]"
        found = {}
        for side in sides:
            frame_id = _name(info_file, field(info_file, entry, f"{side}_frame", where), f"{where}.{side}_frame")
            if frame_id not in sides[side]:
                raise LoaderError(f"{info_file}: {where}.{side}_frame: {shown(frame_id)} is not a frame_id of "
                                  f"{side}-side/data_info.json")
            found[side] = sides[side][frame_id]
        sequence = str(entry.get("vehicle_sequence", found["vehicle"].get("sequence_id", "")))
        pairs.append(Pair(where, sequence, found["vehicle"], found["infrastructure"],
                          dair.system_error_offset(entry.get("system_error_offset"))))
    return sorted(pairs, key=lambda pair: (pair.sequence, pair.vehicle["frame_id"]))


def _side_frames(path: Path) -> dict[str, dict]:
    """``frame_id -> entry`` of a side's ``data_info.json``."""
    entries = read_json(path)
    if not isinstance(entries, list):
        raise LoaderError(f"{path}: expected a list of frames")
    frames = {}
    for k, entry in enumerate(entries):
        frame_id = _name(path, field(path, entry, "frame_id", f"[{k}]"), f"[{k}].frame_id")
        frames[frame_id] = entry
    return frames


def _name(path: Path, value, where: str) -> str:
    """A frame or track id: a non-empty string of letters, digits, ``-`` and ``_`` (it names files)."""
    if not isinstance(value, str) or not value or not all(c.isalnum() or c in "-_" for c in value):
        raise LoaderError(f"{path}: {where}: expected a frame id such as \"000009\", got {shown(value)}")
    return value


def _pair_rows(root: Path, info_file: Path, pair: Pair, frame: int) -> tuple[list, list, list, dict, bool]:
    """(object rows, visibility rows, agent rows, each agent's own labelled boxes, whether a cooperative
    label gave the association) of one pair."""
    vehicle_id, infra_id = pair.vehicle["frame_id"], pair.infrastructure["frame_id"]
    vehicle_pose = dair._vehicle_to_world(root, vehicle_id)
    infra_pose = dair._infrastructure_to_world(root, infra_id, info_file, pair.offset,
                                               f"{pair.where}.system_error_offset")
    vehicle = _tracked(root / "vehicle-side" / "label" / "lidar" / f"{vehicle_id}.json", vehicle_pose)
    infra = _tracked(root / "infrastructure-side" / "label" / "virtuallidar" / f"{infra_id}.json", infra_pose)
    cooperative_file = root / COOPERATIVE_LABELS / f"{vehicle_id}.json"
    if cooperative_file.is_file():
        objects, vehicle_ids, infra_ids = _fused(cooperative_file, vehicle_pose, vehicle, infra)
    else:
        objects, vehicle_ids, infra_ids = _derived(vehicle, infra)
    objects = [{"frame": frame, **row} for row in objects]
    seen = [{"frame": frame, "agent_id": "vehicle", "track_id": t} for t in vehicle_ids]
    seen += [{"frame": frame, "agent_id": "infrastructure", "track_id": t} for t in infra_ids]
    agents = [dair._agent(frame, "vehicle", vehicle_pose, dair.VEHICLE_SIZE),
              dair._agent(frame, "infrastructure", infra_pose, dair.INFRASTRUCTURE_SIZE)]
    views = {(frame, "vehicle"): dair._view(vehicle_ids, [box for _, box in vehicle]),
             (frame, "infrastructure"): dair._view(infra_ids, [box for _, box in infra])}
    return objects, seen, agents, views, cooperative_file.is_file()


def _tracked(path: Path, pose: np.ndarray) -> list[tuple[str, dict]]:
    """``(track_id, world box)`` of each label of a side's label file."""
    labels = dair.label_list(path)
    boxes = dair.label_boxes(path, labels, pose)
    return [(_track(path, label, i), box) for i, (label, box) in enumerate(zip(labels, boxes))]


def _track(path: Path, label, i: int) -> str:
    """The ``track_id`` of label ``i``."""
    return _name(path, field(path, label, "track_id", f"[{i}]"), f"[{i}].track_id")


def _fused(path: Path, vehicle_pose: np.ndarray, vehicle: list, infra: list) -> tuple[list, list[str], list[str]]:
    """The cooperative label's objects (plus the side labels it does not fuse) and the scene track id of
    each vehicle and infrastructure label, from its ``veh_track_id`` / ``inf_track_id``."""
    labels = dair.label_list(path)
    boxes = dair.label_boxes(path, labels, vehicle_pose)
    to_scene = {"veh_track_id": {}, "inf_track_id": {}}
    objects = []
    for i, (label, box) in enumerate(zip(labels, boxes)):
        track = _track(path, label, i)
        objects.append({"track_id": track, **box})
        for key, side in to_scene.items():
            source = str(field(path, label, key, f"[{i}]"))
            if source != NO_TRACK:
                side[source] = track
    vehicle_ids = [to_scene["veh_track_id"].get(t, f"v{t}") for t, _ in vehicle]
    infra_ids = [to_scene["inf_track_id"].get(t, f"i{t}") for t, _ in infra]
    objects += [{"track_id": f"v{t}", **box} for t, box in vehicle if t not in to_scene["veh_track_id"]]
    objects += [{"track_id": f"i{t}", **box} for t, box in infra if t not in to_scene["inf_track_id"]]
    return objects, vehicle_ids, infra_ids


def _derived(vehicle: list, infra: list) -> tuple[list, list[str], list[str]]:
    """Objects and scene track ids when no cooperative label fuses the pair: DAIR-V2X-C's derived
    association of world centres; associated infrastructure labels take the vehicle label's id."""
    vehicle_ids = [f"v{t}" for t, _ in vehicle]
    matched = dair._associate([box for _, box in vehicle], [box for _, box in infra])
    infra_ids = [vehicle_ids[int(m[1:])] if m.startswith("v") else f"i{t}" for m, (t, _) in zip(matched, infra)]
    objects = [{"track_id": scene, **box} for scene, (_, box) in zip(vehicle_ids, vehicle)]
    objects += [{"track_id": scene, **box} for scene, (_, box) in zip(infra_ids, infra) if scene.startswith("i")]
    return objects, vehicle_ids, infra_ids


def _point_files(root: Path, pair: Pair, frame: int) -> dict[tuple[int, str], tuple[Path, bool]]:
    """``(frame, agent) -> (PCD file, False)`` for the pair's point clouds that exist."""
    files = {}
    for side, entry in (("vehicle", pair.vehicle), ("infrastructure", pair.infrastructure)):
        path = dair._existing_file(root / f"{side}-side", entry.get("pointcloud_path"))
        if path is not None:
            files[(frame, side)] = (path, False)
    return files


def _derived_notes(root: Path, vehicle_frames: list[str], loaded: int) -> list[str]:
    """The one note naming the pairs without a cooperative label."""
    return dair.pairs_note(vehicle_frames, lambda shown: (
        f"{root / COOPERATIVE_LABELS}: {len(vehicle_frames)} of {loaded} pair(s) have no cooperative label: "
        f"their vehicle and infrastructure labels are associated by world centres within "
        f"{dair.ASSOCIATION_RADIUS:g} m, derived, not ground truth (vehicle frames {shown})"))
