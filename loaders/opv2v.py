"""OPV2V, V2XSet, V2V4Real and V2X-Real scenarios: folders of per-CAV YAML annotations.

Layout (as OpenCOOD's ``BaseDataset`` walks it): ``<split>/<scenario>/<cav id>/<timestamp>.yaml``.
Open a scenario folder, a split folder (``train/``, ``validate/``, ``test/``: its scenarios), a
release root holding split folders (any of ``train``, ``validate``, ``test``, in that order), or a
single ``.yaml`` file (a one-frame, one-CAV scene whose agent id is its folder's name). Several
scenarios make one sequence: scenarios in name order within each split, frames of a scenario in a
row; ``Sequence.scenarios`` maps each scenario name (``<split>/<scenario>`` under a root, else the
folder name) to its first frame, ``Frame.scenario`` names a frame's scenario, frame ids are
``<scenario name>/<timestamp>`` (just ``<timestamp>`` for one scenario), and each frame's ego is
its scenario's (``Sequence.frame_egos``). Frames are the timestamps of the ego's files, at 10 Hz
(``Sequence.timestamps`` = index / 10 over the whole sequence); a CAV missing a timestamp is
absent from that frame. No agent's own capture time is kept (``Sequence.agent_times`` stays
empty): the files carry none, and a file's name is the frame's counter, the same for every agent
(OpenCOOD's loaders and V2V4Real's and V2X-Real's, which build on them, pair the agents' files by it
and simulate a late message by taking an older file); a late message is the scenario's delay alone.
Loads over a second show a progress bar (tqdm, on stderr).

- The ego is chosen as OpenCOOD does: CAV folders in string order, the first one, except that
  roadside units (V2XSet, Adver-City; negative ids) never lead -- all of them move to the end.
  Adver-City's ``data_dumping/<run>/<scenario>`` nests one level deeper: a folder of run folders
  opens every scenario (``<run>/<scenario>``). Agents keep their folder
  names as ids (``"641"``, ``"-1"``); ``Sequence.ego`` names the ego.
- Agent pose: the CAV's ``lidar_pose`` (the frame its detections are in). Sizes are not in the
  files: CAVs get a typical car size (4.9 x 2.0 x 1.6 m), roadside units a 0.6 x 0.6 x 5 m pole.
- Reported pose: ``lidar_pose`` is the sensor's true pose, ``true_ego_pos`` the vehicle body's
  true pose and ``predicted_ego_pos`` the body's noisy (GNSS) pose, all converted alike. The LiDAR
  pose the CAV reports is the sensor moved by the body's error, ``predicted_ego_pos ∘
  true_ego_pos⁻¹ ∘ lidar_pose`` (SE(2)), kept as ``Sequence.predicted_poses``
  (``Frame.predicted_pose``) when a file has both body poses; the ``dataset`` localization option
  of ``evaluation.scenario`` uses it as the CAV's initial pose.
- OPV2V / V2XSet (CARLA): poses and boxes are in CARLA's left-handed world; converted on read to
  ``x, -y, -yaw``; angles in degrees -> radians; ``extent`` half sizes -> full sizes; box centre =
  ``location + center`` (added in world axes). Each CAV's file lists the vehicles its LiDAR saw:
  that is the per-CAV visibility; an object's box is taken from the first CAV (in ego order) that
  lists it. Besides ``vehicles``, every top-level block of ``{id: {location, extent, ...}}`` is
  read (Adver-City's ``walkers``, whose ``location`` is the centre: no ``center`` key); the
  category is the entry's ``class`` / ``obj_type`` mapped by :data:`CATEGORY_NAMES`, else ``car``
  (``vehicles``) or ``pedestrian`` (``walkers``). Categories of the other blocks are left out of
  trials (``Sequence.left_out_of_trials``). Each CAV's labelled boxes are kept as its
  ``Sequence.agent_views``.
- V2V4Real (recognised by ``ass_id`` keys): boxes are in each CAV's own LiDAR frame (right-handed,
  real sensors), mapped to the world with that CAV's ``lidar_pose``; category from ``obj_type``.
  ``lidar_pose`` may be six numbers or a 4x4 sensor-to-world matrix, and the files may carry the tags
  ``yaml.dump`` writes for numpy numbers and arrays (``loaders.structured.read_yaml`` reads those).
  ``ass_id`` is the cross-CAV id of the same object (-1: seen by one CAV only): associated objects
  share the track id ``"a<ass_id>"`` (the ego's box is kept), others are ``"<cav>/<id>"``.
- V2X-Real (recognised by ``infra`` / ``true_ego_pose`` keys; ``loaders.v2x_real``): world-frame boxes
  as OPV2V's but right-handed (nothing mirrored); its infrastructure has negative ids, and its street
  furniture (``STATIC``: trash cans, fire hydrants) is left out of trials with one warning counting it.
- LiDAR points: the ``<timestamp>.pcd`` beside a ``<timestamp>.yaml`` is that CAV's sweep in its
  LiDAR frame (``Sequence.point_clouds``, read on demand by ``Frame.points``; CARLA's mirrored).
"""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import polars as pl
from tqdm import tqdm

from cbm import se2

from . import v2x_real
from .categories import normalised
from .errors import LoaderError
from .scene import Sequence
from .structured import field, number, numbers, read_yaml, rigid

FRAME_RATE = 10.0
CAV_SIZE = (4.9, 2.0, 1.6)
RSU_SIZE = (0.6, 0.6, 5.0)
SKIPPED = ("additional", "camera_gt", "gnss_imu")
"""Name parts of yaml files beside the annotations that are not annotations (Adver-City's
``<frame>_gnss_imu.yaml``, OPV2V's additional and camera ground-truth files)."""
BLOCK_CATEGORY = {"vehicles": "car", "walkers": "pedestrian"}
CATEGORY_NAMES = {"walker": "pedestrian", "pedestrian": "pedestrian", "car": "car", "van": "van", "truck": "truck",
                  "bus": "bus", "motorcycle": "motorcycle", "bicycle": "bicycle", "cyclist": "bicycle",
                  **v2x_real.CATEGORY_NAMES, **v2x_real.STATIC_PROPS}
"""Actor classes of the OPV2V-family releases (normalised) -> our category names."""
STATIC = frozenset(v2x_real.STATIC_PROPS.values())
"""Categories of labelled street furniture: never road users, left out of trials."""
SPLITS = ("train", "validate", "test")
PROGRESS_DELAY = 1.0
"""Seconds a load runs before its progress bar appears."""
EXPECTED = "an OPV2V / V2XSet / V2V4Real / V2X-Real scenario (numbered CAV folders of .yaml files)"
BROAD = True
"""Recognises any YAML file, and walks every subfolder of a folder: tried after the loaders that recognise narrowly."""


def recognises(path: Path) -> bool:
    if path.is_file():
        return path.suffix.lower() in (".yaml", ".yml")
    return bool(_scenarios(path) or _frame_files(path))


def _frame_files(folder: Path) -> dict[str, Path]:
    """One agent's frames in ``folder`` itself (a CAV folder opened alone): ``<frame>.yaml`` by frame."""
    return {p.stem: p for p in _yaml_files(folder) if p.stem.isdigit()}


def _is_integer(name: str) -> bool:
    return name.lstrip("-").isdigit()


def _yaml_files(folder: Path) -> list[Path]:
    """Every ``*.yaml`` entry of ``folder`` but the skipped kinds, files or not: one that cannot be
    read (a folder, a symlink loop) is refused when read, not left out with its agent (issue 50)."""
    return sorted(p for p in folder.glob("*.yaml") if not any(s in p.name for s in SKIPPED))


def _cav_folders(scenario: Path) -> list[Path]:
    """CAV folders in OpenCOOD's order (string order, roadside units last), with every roadside unit
    moved to the end: OpenCOOD moves only a leading one, which makes Adver-City's second RSU ``-2``
    the ego of a scenario with two."""
    folders = sorted((p for p in scenario.iterdir() if p.is_dir() and _is_integer(p.name) and _yaml_files(p)),
                     key=lambda p: p.name)
    return [p for p in folders if int(p.name) >= 0] + [p for p in folders if int(p.name) < 0]


def _scenario_folders(folder: Path) -> list[Path]:
    return sorted((p for p in folder.iterdir() if p.is_dir() and _cav_folders(p)), key=lambda p: p.name)


def _scenarios(path: Path) -> list[tuple[str, Path]]:
    """``(name, folder)`` of every scenario under ``path`` (a scenario, a split folder, a root of
    split folders, or a root of run folders as Adver-City's ``data_dumping/<run>/<scenario>``), in
    load order."""
    if _cav_folders(path):
        return [(path.name, path)]
    splits = [path / split for split in SPLITS if (path / split).is_dir()]
    if not splits:
        direct = [(p.name, p) for p in _scenario_folders(path)]
        splits = [] if direct else sorted(p for p in path.iterdir() if p.is_dir())
        if direct:
            return direct
    return [(f"{split.name}/{p.name}", p) for split in splits for p in _scenario_folders(split)]


def load(path: str | Path) -> Sequence:
    """Load an OPV2V / V2XSet / V2V4Real / V2X-Real release root, split folder, scenario folder, one
    agent's folder of frames or one file."""
    path = Path(path)
    if path.is_file():
        return _one_agent(path.stem, path.parent, {path.stem: path})
    scenarios = _scenarios(path)
    if not scenarios and _frame_files(path):
        return _one_agent(path.name, path, _frame_files(path))
    if not scenarios:
        raise LoaderError(f"{path}: no scenario folders (numbered CAV folders of .yaml files), "
                          f"directly or under {', '.join(SPLITS)}")
    parts, offset = [], 0
    bar = tqdm(scenarios, desc=f"OPV2V {path.name}", unit="scenario", delay=PROGRESS_DELAY, leave=False)
    for name, folder in bar:
        files = {cav.name: {p.stem: p for p in _yaml_files(cav)} for cav in _cav_folders(folder)}
        parts.append(_scenario(name, files, offset))
        offset += len(parts[-1]["stamps"])
    return _sequence(path.name, parts, single=len(parts) == 1 and scenarios[0][1] == path)


def _one_agent(name: str, folder: Path, files: dict[str, Path]) -> Sequence:
    """One agent's frames: its id is its folder's name (``641``, ``-1``), else read from its first
    file's ``infra`` flag (``v2x_real.agent_of``), with a note saying which agent it became."""
    agent, note = (folder.name, None) if _is_integer(folder.name) else \
        v2x_real.agent_of(folder.name, read_yaml(next(iter(files.values()))))
    sequence = _sequence(name, [_scenario(name, {agent: files}, 0)], single=True)
    if note:
        sequence.notes.append(f"{folder.name}: {note}")
        warnings.warn(sequence.notes[-1], UserWarning, stacklevel=3)
    return sequence


def _scenario(name: str, files: dict[str, dict[str, Path]], offset: int) -> dict:
    """One scenario's rows, with frame indices starting at ``offset``."""
    order = list(files)
    stamps = sorted(files[order[0]])
    records = {(k, cav): read_yaml(files[cav][stamp])
               for k, stamp in enumerate(stamps) for cav in order if stamp in files[cav]}
    kind = _kind(records.values())
    objects, agents, seen, predicted, left_out, views = [], [], [], {}, set(), {}
    kept: dict[int, set[str]] = {}
    for (k, cav), record in records.items():
        source, frame = files[cav][stamps[k]], offset + k
        if kind == "v2x_real":
            v2x_real.check_infra(source, record, cav)
        pose = _pose(source, record, kind != "opv2v")
        agents.append(_agent_row(frame, cav, pose))
        reported = _reported_lidar_pose(source, record, pose, kind != "opv2v")
        if reported is not None:
            predicted[(frame, cav)] = reported
        view = views.setdefault((frame, cav), ([], []))
        for block, track, row in _boxes(source, record, cav, pose, kind):
            if block != "vehicles" or row["category"] in STATIC:
                left_out.add(row["category"])
            view[0].append(track)
            view[1].append([row[c] for c in ("x", "y", "z", "length", "width", "height", "yaw")])
            seen.append({"frame": frame, "agent_id": cav, "track_id": track})
            if track not in kept.setdefault(frame, set()):
                kept[frame].add(track)
                objects.append({"frame": frame, "track_id": track, **row})
    return {"name": name, "stamps": stamps, "ego": order[0], "kind": kind, "objects": objects,
            "agents": agents, "seen": seen, "predicted": predicted, "left_out": left_out,
            "static": {(o["track_id"], o["category"]) for o in objects if o["category"] in STATIC},
            "views": {key: (np.array(ids, dtype=str), np.array(boxes, float).reshape(-1, 7))
                      for key, (ids, boxes) in views.items()},
            "points": {(offset + k, cav): (files[cav][stamps[k]].with_suffix(".pcd"), kind == "opv2v")
                       for k, cav in records if files[cav][stamps[k]].with_suffix(".pcd").is_file()}}


def _kind(records) -> str:
    """``v2x_real`` (an ``infra`` or ``true_ego_pose`` key), ``v2v4real`` (``ass_id`` keys) or ``opv2v``."""
    records = list(records)
    if any(v2x_real.is_record(record) for record in records):
        return "v2x_real"
    return "v2v4real" if any(_has_ass_id(record) for record in records) else "opv2v"


def _sequence(name: str, parts: list[dict], single: bool) -> Sequence:
    """The scenarios' rows as one sequence (frame ids prefixed by the scenario unless ``single``)."""
    starts = np.cumsum([0] + [len(p["stamps"]) for p in parts])
    frame_ids = [s if single else f"{p['name']}/{s}" for p in parts for s in p["stamps"]]
    kind = next((k for k in ("v2x_real", "v2v4real") if any(p["kind"] == k for p in parts)), "opv2v")
    sequence = Sequence(
        name=f"{kind}/{name}",
        objects=_table([r for p in parts for r in p["objects"]], OBJECT_SCHEMA),
        frame_ids=frame_ids,
        timestamps=np.arange(len(frame_ids)) / FRAME_RATE,
        agents=_table([r for p in parts for r in p["agents"]], AGENT_SCHEMA),
        visibility=_table([r for p in parts for r in p["seen"]],
                          {"frame": pl.Int64, "agent_id": pl.Utf8, "track_id": pl.Utf8}),
        ego=parts[0]["ego"],
        scenarios={p["name"]: int(k) for p, k in zip(parts, starts)},
        frame_egos=[p["ego"] for p in parts for _ in p["stamps"]],
        predicted_poses={key: pose[:2] + pose[3:] for p in parts for key, pose in p["predicted"].items()},
    )
    sequence.point_clouds = {key: source for p in parts for key, source in p["points"].items()}
    sequence.left_out_of_trials = frozenset().union(*(p["left_out"] for p in parts))
    sequence.agent_views = {key: view for p in parts for key, view in p["views"].items()}
    static = [(p["name"], track, name) for p in parts for track, name in p["static"]]
    if static:
        note = v2x_real.left_out_note(len(static), {name for _, _, name in static})
        sequence.notes.append(note)
        warnings.warn(note, UserWarning, stacklevel=3)
    return sequence


OBJECT_SCHEMA = {"frame": pl.Int64, "track_id": pl.Utf8, "category": pl.Utf8,
                 **{c: pl.Float64 for c in ("x", "y", "z", "length", "width", "height", "yaw")}}
AGENT_SCHEMA = {"frame": pl.Int64, "agent_id": pl.Utf8,
                **{c: pl.Float64 for c in ("x", "y", "z", "yaw", "length", "width", "height")}}


def _table(rows: list[dict], schema: dict) -> pl.DataFrame:
    return pl.DataFrame(rows, schema=schema, orient="row") if rows else pl.DataFrame(schema=schema)


def _has_ass_id(record) -> bool:
    vehicles = record.get("vehicles") if isinstance(record, dict) else None
    return isinstance(vehicles, dict) and any(isinstance(v, dict) and "ass_id" in v for v in vehicles.values())


def _pose(path: Path, record, right_handed: bool, key: str = "lidar_pose") -> tuple[float, float, float, float]:
    """``x, y, z, yaw`` (radians, right-handed world) of a CAV's ``lidar_pose`` (or ``key``): six
    numbers ``[x, y, z, roll, yaw, pitch]`` (degrees), or a 4x4 sensor-to-world matrix (V2V4Real)."""
    value = field(path, record, key)
    if isinstance(value, list) and value and all(isinstance(row, list) for row in value):
        m = rigid(path, value, key)
        x, y, z, yaw = float(m[0, 3]), float(m[1, 3]), float(m[2, 3]), math.atan2(m[1, 0], m[0, 0])
    else:
        x, y, z, _roll, yaw, _pitch = numbers(path, value, key, 6)
        yaw = math.radians(yaw)
    return (x, y, z, yaw) if right_handed else (x, -y, z, -yaw)


def _reported_lidar_pose(path: Path, record, lidar: tuple[float, float, float, float],
                         right_handed: bool) -> tuple[float, float, float, float] | None:
    """The LiDAR pose the CAV itself reports, ``x, y, z, yaw`` (right-handed world): the true LiDAR
    pose moved by the body's localization error, ``predicted_ego_pos ∘ true_ego_pos⁻¹ ∘ lidar_pose``
    (SE(2)); None when the file lacks ``predicted_ego_pos`` or ``true_ego_pos``."""
    if not isinstance(record, dict) or not {"predicted_ego_pos", "true_ego_pos"} <= record.keys():
        return None
    body_error = se2.make(*_planar(_pose(path, record, right_handed, "predicted_ego_pos"))) @ se2.inverse(
        se2.make(*_planar(_pose(path, record, right_handed, "true_ego_pos"))))
    reported = body_error @ se2.make(*_planar(lidar))
    x, y = se2.translation_of(reported)
    return float(x), float(y), lidar[2], se2.yaw_of(reported)


def _planar(pose: tuple[float, float, float, float]) -> tuple[float, float, float]:
    return pose[0], pose[1], pose[3]


def _agent_row(frame: int, cav: str, pose: tuple[float, float, float, float]) -> dict:
    length, width, height = RSU_SIZE if int(cav) < 0 else CAV_SIZE
    x, y, z, yaw = pose
    return {"frame": frame, "agent_id": cav, "x": x, "y": y, "z": z, "yaw": yaw,
            "length": length, "width": width, "height": height}


def _boxes(path: Path, record, cav: str, pose, kind: str):
    """``(block, track_id, box row)`` for every actor in one CAV's file (``vehicles`` and any other actor
    block such as Adver-City's ``walkers``), in the right-handed world."""
    vehicles = field(path, record, "vehicles")
    if vehicles is not None and not isinstance(vehicles, dict):
        raise LoaderError(f"{path}: vehicles: expected a mapping of vehicle id -> annotation")
    for block in _actor_blocks(record):
        for actor_id, entry in (record[block] or {}).items():
            yield (block, *_box(path, block, actor_id, entry, cav, pose, kind))


def _actor_blocks(record: dict) -> list[str]:
    """``vehicles`` first, then every other top-level mapping of id -> ``{location, extent, ...}``."""
    others = [key for key, value in record.items() if key != "vehicles" and isinstance(value, dict) and value
              and all(isinstance(entry, dict) and {"location", "extent"} <= entry.keys() for entry in value.values())]
    return ["vehicles", *sorted(others, key=str)]


def _box(path: Path, block: str, actor_id, entry, cav: str, pose, kind: str) -> tuple[str, dict]:
    where = f"{block}[{actor_id}]"
    location = numbers(path, field(path, entry, "location", where), f"{where}.location", 3)
    center = (numbers(path, field(path, entry, "center", where), f"{where}.center", 3)
              if block == "vehicles" or "center" in entry else [0.0, 0.0, 0.0])
    extent = numbers(path, field(path, entry, "extent", where), f"{where}.extent", 3)
    yaw = math.radians(numbers(path, field(path, entry, "angle", where), f"{where}.angle", 2)[1])
    if min(extent) <= 0:
        raise LoaderError(f"{path}: {where}.extent: expected positive half sizes, got {extent}")
    x, y, z = (a + b for a, b in zip(location, center))
    if kind == "v2v4real":
        x, y, yaw = _to_world(pose, x, y, yaw)
        z += pose[2]
        ass_id = int(number(path, field(path, entry, "ass_id", where), f"{where}.ass_id"))
        track = f"a{ass_id}" if ass_id != -1 else f"{cav}/{actor_id}"
    else:
        y, yaw = (y, yaw) if kind == "v2x_real" else (-y, -yaw)
        track = str(actor_id)
    return track, {"category": category(entry, block), "x": x, "y": y, "z": z,
                   "length": 2 * extent[0], "width": 2 * extent[1], "height": 2 * extent[2],
                   "yaw": math.atan2(math.sin(yaw), math.cos(yaw))}


def category(entry: dict, block: str) -> str:
    """An actor's category: its ``class`` (Adver-City) or ``obj_type`` (V2V4Real), else its block's
    (``vehicles``: car, ``walkers``: pedestrian), mapped by :data:`CATEGORY_NAMES`; unknown names kept."""
    name = entry.get("class", entry.get("obj_type"))
    if not isinstance(name, str) or not name.strip():
        return BLOCK_CATEGORY.get(block, block)
    return CATEGORY_NAMES.get(normalised(name), name.strip())


def _to_world(pose, x: float, y: float, yaw: float) -> tuple[float, float, float]:
    px, py, _, pyaw = pose
    c, s = math.cos(pyaw), math.sin(pyaw)
    return px + c * x - s * y, py + s * x + c * y, yaw + pyaw
