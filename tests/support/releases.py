"""A small corpus of releases in their exact published layouts, written by the libraries their
producers use: PyYAML ``yaml.dump(..., default_flow_style=False)`` for the OPV2V family (OpenCDA's
``save_yaml``), ``json.dump`` for DAIR-V2X-C, pypcd4 for PCD sweeps (``DATA ascii`` with Open3D's
``x y z rgb`` fields for the OPV2V family, PCL-style ``binary_compressed`` with ``x y z intensity``
for DAIR-V2X-C), numpy ``tofile`` for V2X-Sim's ``.pcd.bin`` sweeps, polars for CSV tables.

Every release shows the same right-handed world: a few cars and pedestrians around an intersection,
the ego at the origin, a CAV and a roadside unit. Each writer returns the folder a user opens.
"""
from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pypcd4
import yaml

from cbm import se2

FIXTURES = Path(__file__).resolve().parents[1] / "loaders" / "fixtures"
OBJECTS = [  # id, category, x, y, yaw (rad), length, width, height (right-handed world)
    (700, "car", 12.0, 3.5, 0.0, 4.6, 1.9, 1.5), (701, "car", -9.0, -3.5, math.pi, 4.4, 1.8, 1.5),
    (702, "van", 25.0, -3.5, 0.05, 5.2, 2.0, 2.1), (703, "car", 6.0, 14.0, math.pi / 2, 4.5, 1.9, 1.5),
    (704, "truck", 3.5, -20.0, -math.pi / 2, 8.0, 2.5, 3.2), (705, "car", 30.0, 10.0, 0.4, 4.7, 1.9, 1.6),
    (706, "car", -18.0, 7.0, 0.1, 4.3, 1.8, 1.5), (707, "car", 16.0, -12.0, 1.2, 4.6, 1.9, 1.5),
    (1300, "pedestrian", 9.0, 8.0, 0.7, 0.38, 0.38, 1.86), (1301, "pedestrian", 20.0, 6.0, -2.0, 0.4, 0.4, 1.7),
]
AGENTS = {"641": (0.0, 0.0, 0.0), "650": (18.0, 4.0, 0.3), "-1": (10.0, -12.0, 1.2)}
"""Agent id -> true body pose (x, y, yaw) in the world; the roadside unit's is its pole."""
LIDAR_MOUNT = (-0.5, 0.0, 1.9)
"""The LiDAR in the body frame (x back of the body origin, as CARLA's OPV2V vehicles carry it)."""
GNSS_ERROR = {"641": (0.0, 0.0, 0.0), "650": (0.03, -0.04, 0.2), "-1": (0.0, 0.0, 0.0)}
"""predicted_ego_pos - true_ego_pos per agent: x, y metres, yaw degrees (right-handed)."""
LFS_POINTER = b"version https://git-lfs.github.com/spec/v1\noid sha256:" + b"a1" * 32 + b"\nsize 48213407\n"


def lidar_pose(agent: str) -> np.ndarray:
    x, y, yaw = AGENTS[agent]
    mount = (0.0, 0.0) if agent.startswith("-") else LIDAR_MOUNT[:2]
    return se2.make(x, y, yaw) @ se2.make(*mount, 0.0)


def carla(x: float, y: float, z: float, yaw: float) -> list[float]:
    """A right-handed pose as CARLA's left-handed ``[x, y, z, roll, yaw, pitch]`` (degrees)."""
    return [float(x), float(-y), float(z), 0.0, float(-math.degrees(yaw)), 0.0]


def moved(k: int) -> list[tuple]:
    """The objects at timestamp ``k``: cars drive 0.5 m a frame along their heading."""
    return [(i, c, x + 0.5 * k * math.cos(yaw) * (c != "pedestrian"), y + 0.5 * k * math.sin(yaw) * (c != "pedestrian"),
             yaw, length, width, height) for i, c, x, y, yaw, length, width, height in OBJECTS]


def seen_by(agent: str, objects: list[tuple], reach: float = 45.0) -> list[tuple]:
    x, y, _ = AGENTS[agent]
    return [o for o in objects if math.hypot(o[2] - x, o[3] - y) <= reach]


def sweep(agent: str, objects: list[tuple], left_handed: bool) -> np.ndarray:
    """``(N, 3)`` points in the agent's LiDAR frame: 4 points inside each object, a ground ring."""
    to_lidar = se2.inverse(lidar_pose(agent))
    points = []
    for _, _, x, y, yaw, length, width, height in objects:
        local = np.array([[0.3 * length * a, 0.3 * width * b] for a in (-1, 1) for b in (-1, 1)])
        world = se2.apply_points(se2.make(x, y, yaw), local)
        xy = se2.apply_points(to_lidar, world)
        points += [[px, py, height / 2 - LIDAR_MOUNT[2]] for px, py in xy]
    angles = np.linspace(0, 2 * math.pi, 64, endpoint=False)
    ring = [[6 * math.cos(a), 6 * math.sin(a), -LIDAR_MOUNT[2]] for a in angles]
    out = np.array(points + ring, np.float32)
    if left_handed:
        out[:, 1] *= -1
    return out


def save_pcd(path: Path, fields: tuple[str, ...], columns: np.ndarray, encoding: str) -> None:
    n = len(fields)
    metadata = pypcd4.MetaData.model_validate({"fields": fields, "size": (4,) * n, "type": ("F",) * n,
                                               "count": (1,) * n, "points": len(columns), "width": len(columns)})
    records = np.rec.fromarrays(columns.T.astype(np.float32), dtype=metadata.build_dtype())
    pypcd4.PointCloud(metadata, records).save(path, encoding=pypcd4.Encoding(encoding))


def dump_yaml(path: Path, record: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w") as file:
        yaml.dump(record, file, default_flow_style=False)


# --- the OPV2V family ------------------------------------------------------------------------------------------

def cav_record(agent: str, k: int, adver_city: bool = False) -> dict:
    """One CAV's ``<timestamp>.yaml`` as OpenCDA's data dumper writes it (Adver-City: with ``class``
    fields and a ``walkers`` block)."""
    x, y, yaw = AGENTS[agent]
    lidar = lidar_pose(agent)
    dx, dy, dyaw = GNSS_ERROR[agent]
    objects = [o for o in seen_by(agent, moved(k)) if str(o[0]) != agent]
    vehicles, walkers = {}, {}
    for i, category, ox, oy, oyaw, length, width, height in objects:
        entry = {"angle": [0.0, float(-math.degrees(oyaw)), 0.0], "extent": [length / 2, width / 2, height / 2],
                 "speed": 20.0}
        if category == "pedestrian":
            walkers[i] = {**entry, "location": [ox, -oy, height / 2], "bp_id": "walker.pedestrian.0024",
                          "class": "walker"}
        else:
            vehicles[i] = {**entry, "location": [ox, -oy, 0.03], "center": [0.0, 0.0, height / 2],
                           "bp_id": "vehicle.lincoln.mkz_2017", "color": "0, 0, 255",
                           **({"class": category} if adver_city else {})}
    record = {"RSU": agent.startswith("-"), "ego_speed": 18.0,
              "lidar_pose": carla(*se2.translation_of(lidar), 1.9, se2.yaw_of(lidar)),
              "true_ego_pos": carla(x, y, 0.03, yaw),
              "predicted_ego_pos": carla(x + dx, y + dy, 0.03, yaw + math.radians(dyaw)),
              "plan_trajectory": [[x + 1.0, -y, 18.0]], "vehicles": vehicles}
    if adver_city:
        record["walkers"] = walkers
    return record


def opv2v_root(root: Path) -> Path:
    """``OPV2V/train/<scenario>/<cav>/<timestamp>.{yaml,pcd}`` and ``test/``: two CAVs, no RSU."""
    for split, scenario in (("train", "2021_08_16_22_26_54"), ("test", "2021_08_18_19_48_05")):
        for agent in ("641", "650"):
            folder = root / split / scenario / agent
            for k, stamp in enumerate(("000068", "000070")):
                dump_yaml(folder / f"{stamp}.yaml", cav_record(agent, k))
                points = sweep(agent, seen_by(agent, moved(k)), left_handed=True)
                rgb = np.zeros((len(points), 1), np.float32)
                save_pcd(folder / f"{stamp}.pcd", ("x", "y", "z", "rgb"), np.hstack([points, rgb]), "ascii")
        dump_yaml(root / split / scenario / "data_protocol.yaml", {"world": {"sync_mode": True}})
    return root


def v2xset_scenario(root: Path) -> Path:
    """A V2XSet scenario: two CAVs and the roadside unit ``-1``."""
    for agent in AGENTS:
        for k, stamp in enumerate(("000068", "000070")):
            dump_yaml(root / agent / f"{stamp}.yaml", cav_record(agent, k))
    return root


def adver_city_run(root: Path) -> Path:
    """``data_dumping/<run>/<scenario>/<cav>/000060.yaml`` with ``walkers`` and ``class``, two RSUs,
    ``_gnss_imu.yaml`` files and ``_lidar.ply`` sweeps beside them (not read)."""
    scenario = root / "2024_07_12_14_13_22" / "unj_cn_d"
    for agent in ("641", "650", "-1"):
        dump_yaml(scenario / agent / "000060.yaml", cav_record(agent, 0, adver_city=True))
        dump_yaml(scenario / agent / "000060_gnss_imu.yaml", {"gnss": [0.0, 0.0, 0.0], "imu": [0.0] * 6})
        (scenario / agent / "000060_lidar.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nend_header\n")
    second_rsu = cav_record("-1", 0, adver_city=True)
    dump_yaml(scenario / "-2" / "000060.yaml", second_rsu)
    dump_yaml(scenario / "summary.yaml", {"frames": 1})
    return root


def v2v4real_scenario(root: Path, pose: str = "numbers") -> Path:
    """V2V4Real: CAVs ``0`` and ``1``, boxes in each CAV's LiDAR frame with ``obj_type`` and ``ass_id``.
    ``pose``: ``lidar_pose`` as six ``numbers``, a 4x4 ``matrix`` (nested lists), or ``numpy``: the
    matrix a numpy array and every box number a numpy float, dumped as PyYAML dumps numpy values
    (``!!python/object/apply:numpy...`` tags), as the release's files are."""
    real = np.float64 if pose == "numpy" else float
    for folder, agent in (("0", "641"), ("1", "650")):
        to_lidar = se2.inverse(lidar_pose(agent))
        vehicles = {}
        for i, category, x, y, yaw, length, width, height in seen_by(agent, moved(0)):
            if category == "pedestrian" or str(i) in AGENTS:
                continue
            (lx, ly), = se2.apply_points(to_lidar, [[x, y]])
            numbers = {"angle": [0.0, math.degrees(yaw + se2.yaw_of(to_lidar)), 0.0], "center": [0.0, 0.0, 0.0],
                       "extent": [length / 2, width / 2, height / 2], "location": [lx, ly, -1.0]}
            vehicles[i] = {**{key: [real(v) for v in values] for key, values in numbers.items()},
                           "obj_type": category.capitalize(), "ass_id": i}
        dump_yaml(root / folder / "000000.yaml", {"lidar_pose": _v2v4real_pose(agent, pose), "vehicles": vehicles})
    return root


def _v2v4real_pose(agent: str, pose: str):
    """An agent's ``lidar_pose`` as six numbers, a 4x4 list of lists or a 4x4 numpy array."""
    lidar = lidar_pose(agent)
    x, y = se2.translation_of(lidar)
    if pose == "numbers":
        return [float(x), float(y), 1.9, 0.0, math.degrees(se2.yaw_of(lidar)), 0.0]
    matrix = np.eye(4)
    matrix[:2, :2], matrix[:3, 3] = lidar[:2, :2], [x, y, 1.9]
    return matrix if pose == "numpy" else matrix.tolist()



V2X_REAL_AGENTS = {"1": "641", "2": "650", "-1": "-1"}
"""V2X-Real agent folder -> the corpus agent it stands for (vehicles 1, 2; infrastructure -1)."""
V2X_REAL_TYPES = {"car": "Car", "van": "Van", "truck": "ConcreteTruck", "pedestrian": "Pedestrian"}
V2X_REAL_EXTRA = [(1400, "TrashCan", 8.0, -6.0, 0.0, 0.6, 0.6, 1.0),
                  (1401, "BicycleRider", 14.0, 7.0, 0.2, 1.8, 0.6, 1.7)]
"""Objects only the V2X-Real corpus has: a static prop and a cyclist (obj_type as the release writes it)."""


def v2x_real_record(folder: str, k: int) -> dict:
    """One V2X-Real agent's ``<timestamp>.yaml``: world-frame (right-handed) boxes with ``obj_type``,
    ``lidar_pose`` and ``true_ego_pose`` in degrees, the ``infra`` flag; car 706 parked (``static``)."""
    agent = V2X_REAL_AGENTS[folder]
    vehicles = {}
    for i, kind, x, y, yaw, length, width, height in seen_by(agent, moved(k) + V2X_REAL_EXTRA):
        vehicles[i] = {"angle": [0.0, math.degrees(yaw), 0.0], "center": [0.0, 0.0, height / 2],
                       "extent": [length / 2, width / 2, height / 2], "location": [x, y, 0.0],
                       "obj_type": V2X_REAL_TYPES.get(kind, kind), **({"attribute": "static"} if i == 706 else {})}
    lidar, (x, y, yaw) = lidar_pose(agent), AGENTS[agent]
    lx, ly = se2.translation_of(lidar)
    return {"infra": folder.startswith("-"), "lidar_pose": [float(lx), float(ly), 1.9, 0.0,
                                                            math.degrees(se2.yaw_of(lidar)), 0.0],
            "true_ego_pose": [x, y, 0.0, 0.0, math.degrees(yaw), 0.0], "vehicles": vehicles}


def v2x_real_root(root: Path) -> Path:
    """``v2xreal/train/<scenario>/{1,2,-1}/00000{0,1}.yaml`` with ``.bin`` sweeps (float32 x y z
    intensity, numpy ``tofile``), as the release is laid out for its OpenCOOD-based code."""
    scenario = root / "train" / "2023-03-17-15-53-02_1_0"
    for folder, agent in V2X_REAL_AGENTS.items():
        for k in range(2):
            dump_yaml(scenario / folder / f"{k:06d}.yaml", v2x_real_record(folder, k))
            xyz = sweep(agent, seen_by(agent, moved(k)), left_handed=False)
            np.hstack([xyz, np.ones((len(xyz), 1), np.float32)]).tofile(scenario / folder / f"{k:06d}.bin")
    return root


# --- DAIR-V2X-C ------------------------------------------------------------------------------------------------

DAIR_OFFSET = {"delta_x": -0.52, "delta_y": 0.31}
DAIR_START_US = 1626155150098000
"""The first vehicle sweep's ``pointcloud_timestamp`` (microseconds); pairs follow every 100 ms."""
DAIR_INFRA_US = (-40123, 23877, -98000)
"""Microseconds from each pair's vehicle sweep to its infrastructure sweep (the roadside unit first,
then after, then almost a frame before)."""
DAIR_TYPES = {"car": "Car", "van": "Van", "truck": "Truck", "pedestrian": "Pedestrian"}


def _rigid(T: np.ndarray, z: float = 0.0) -> dict:
    rotation = np.eye(3)
    rotation[:2, :2] = T[:2, :2]
    return {"rotation": rotation.tolist(), "translation": [[float(T[0, 2])], [float(T[1, 2])], [z]]}


def _dair_labels(pose: np.ndarray, objects: list[tuple], infrastructure: bool = False) -> list[dict]:
    """A DAIR-V2X label list; the infrastructure side's as DAIR-V2X-C ships it, with ``truncated_state``,
    ``occluded_state`` and ``alpha`` as strings (``"0"``, ``"1"``, ``"-1.5707963267948966"``)."""
    to_sensor = se2.inverse(pose)
    labels = []
    for k, (_, category, x, y, yaw, length, width, height) in enumerate(objects):
        (lx, ly), = se2.apply_points(to_sensor, [[x, y]])
        rotation = float(se2.wrap_angle(yaw + se2.yaw_of(to_sensor)))
        if infrastructure:
            states = {"type": DAIR_TYPES[category], "truncated_state": "0", "occluded_state": str(k % 2),
                      "alpha": str(rotation - math.pi / 2)}
        else:
            states = {"type": DAIR_TYPES[category], "occluded_state": 0, "truncated_state": 0, "alpha": 0.0}
        labels.append({**states, "2d_box": {"xmin": 0, "ymin": 0, "xmax": 1, "ymax": 1},
                       "3d_dimensions": {"h": height, "w": width, "l": length},
                       "3d_location": {"x": float(lx), "y": float(ly), "z": height / 2 - 1.7},
                       "rotation": rotation})
    return labels


def dair_release(root: Path, pairs: int = 3, world_calib: bool = True, infra_error: tuple = (0.0, 0.0),
                 offset: dict | str = DAIR_OFFSET) -> Path:
    """``cooperative-vehicle-infrastructure/`` as DAIR-V2X-C ships it (``world_calib=False``: a
    shared subset without the vehicle's world calibration, with ``cooperative/calib/lidar_i2v`` as
    DAIR-V2X's ``calib_i2v.py`` writes it). ``infra_error`` shifts the last pair's shipped
    ``virtuallidar_to_world`` by (x, y) metres, as a wrong release calibration would. ``offset=""``:
    every pair's ``system_error_offset`` an empty string, the shipped calibration then exact."""
    info, sides = [], {"vehicle": [], "infrastructure": []}
    delta = (0.0, 0.0) if offset == "" else (offset["delta_x"], offset["delta_y"])
    for k in range(pairs):
        vehicle_id, infra_id = f"{10 + k:06d}", f"{20 + k:06d}"
        vehicle, infra = lidar_pose("641"), lidar_pose("-1")
        objects = moved(k)
        shipped = infra.copy()
        shipped[:2, 2] -= delta
        if k == pairs - 1:
            shipped[:2, 2] += infra_error
        write_json(root / "vehicle-side" / "label" / "lidar" / f"{vehicle_id}.json",
                   _dair_labels(vehicle, seen_by("641", objects)))
        write_json(root / "infrastructure-side" / "label" / "virtuallidar" / f"{infra_id}.json",
                   _dair_labels(infra, seen_by("-1", objects), infrastructure=True))
        write_json(root / "infrastructure-side" / "calib" / "virtuallidar_to_world" / f"{infra_id}.json",
                   _rigid(shipped, 5.0))
        if world_calib:
            calib = root / "vehicle-side" / "calib"
            write_json(calib / "lidar_to_novatel" / f"{vehicle_id}.json",
                       {"transform": _rigid(se2.make(0.9, 0.0, 0.0), 1.6)})
            write_json(calib / "novatel_to_world" / f"{vehicle_id}.json", _rigid(vehicle @ se2.make(-0.9, 0.0, 0.0)))
        with_offset = shipped.copy()
        with_offset[:2, 2] += delta
        write_json(root / "cooperative" / "calib" / "lidar_i2v" / f"{vehicle_id}.json",
                   _rigid(se2.inverse(vehicle) @ with_offset, 3.4))
        for side, agent, frame in (("vehicle-side", "641", vehicle_id), ("infrastructure-side", "-1", infra_id)):
            points = sweep(agent, seen_by(agent, objects), left_handed=False)
            intensity = (np.arange(len(points)) % 255).astype(np.float32)[:, None]
            (root / side / "velodyne").mkdir(parents=True, exist_ok=True)
            save_pcd(root / side / "velodyne" / f"{frame}.pcd", ("x", "y", "z", "intensity"),
                     np.hstack([points, intensity]), "binary_compressed")
        info.append({"infrastructure_image_path": f"infrastructure-side/image/{infra_id}.jpg",
                     "infrastructure_pointcloud_path": f"infrastructure-side/velodyne/{infra_id}.pcd",
                     "vehicle_image_path": f"vehicle-side/image/{vehicle_id}.jpg",
                     "vehicle_pointcloud_path": f"vehicle-side/velodyne/{vehicle_id}.pcd",
                     "cooperative_label_path": f"cooperative/label_world/{vehicle_id}.json",
                     "system_error_offset": offset})
        stamp = DAIR_START_US + 100_000 * k
        sides["vehicle"].append(_dair_frame_info("vehicle", vehicle_id, stamp))
        sides["infrastructure"].append(_dair_frame_info("infrastructure", infra_id,
                                                        stamp + DAIR_INFRA_US[k % len(DAIR_INFRA_US)]))
    write_json(root / "cooperative" / "data_info.json", info)
    for side, entries in sides.items():
        write_json(root / f"{side}-side" / "data_info.json", entries)
    return root


def _dair_frame_info(side: str, frame: str, stamp: int) -> dict:
    """One entry of DAIR-V2X-C's ``<side>-side/data_info.json``, keys in the release's order, numbers
    as strings (``pointcloud_timestamp`` in microseconds)."""
    if side == "vehicle":
        return {"image_path": f"image/{frame}.jpg", "image_timestamp": str(stamp - 58000),
                "pointcloud_path": f"velodyne/{frame}.pcd", "pointcloud_timestamp": str(stamp),
                **{f"calib_{name}_path": f"calib/{name}/{frame}.json"
                   for name in ("camera_intrinsic", "lidar_to_camera", "lidar_to_novatel", "novatel_to_world")},
                "label_camera_std_path": f"label/camera/{frame}.json",
                "label_lidar_std_path": f"label/lidar/{frame}.json",
                "batch_start_id": frame, "batch_end_id": frame, "batch_id": "34", "intersection_loc": "yizhuang10"}
    return {"pointcloud_path": f"velodyne/{frame}.pcd", "pointcloud_timestamp": str(stamp), "lidar_id": "151",
            "intersection_loc": "yizhuang10",
            **{f"calib_{name}_path": f"calib/{name}/{frame}.json"
               for name in ("camera_intrinsic", "virtuallidar_to_world", "virtuallidar_to_camera")},
            "image_path": f"image/{frame}.jpg", "image_timestamp": str(stamp + 102348), "camera_ip": "172_18_9_101",
            "camera_id": "1", "batch_id": "122",
            "valid_batch_splits": [{"batch_start_id": frame, "batch_end_id": frame}]}


def write_json(path: Path, value) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w") as file:
        json.dump(value, file)


# --- the others ------------------------------------------------------------------------------------------------

def sind_without_lfs(root: Path) -> Path:
    """A SinD recording cloned without Git LFS: ``Veh_smoothed_tracks.csv`` a pointer, the
    pedestrian file (real, from the SinD repository) and the meta files present."""
    root.mkdir(parents=True)
    shutil.copy(FIXTURES / "sind" / "Xian_412_m1" / "Ped_smoothed_tracks.csv", root)
    (root / "Veh_smoothed_tracks.csv").write_bytes(LFS_POINTER)
    return root


def v2x_sim_root(root: Path) -> Path:
    """The V2X-Sim 2.0 tables with each agent's sweeps as ``.pcd.bin`` (float32 x y z intensity, numpy)."""
    shutil.copytree(FIXTURES / "v2x_sim" / "V2X-Sim-2.0-mini", root)
    for agent in ("0", "1", "2"):
        folder = root / "sweeps" / f"LIDAR_TOP_id_{agent}"
        folder.mkdir(parents=True)
        xyz = sweep("641", moved(0), False)
        points = np.hstack([xyz, np.ones((len(xyz), 1), np.float32)])
        points.astype(np.float32).tofile(folder / f"scene_1_000000_LIDAR_TOP_id_{agent}.pcd.bin")
    return root


def generic_table(path: Path) -> Path:
    """The generic table (``loaders/README.md``): one row per box and frame, ``agent`` rows for what
    each agent sees, written by polars."""
    import polars as pl

    rows = [{"frame": k, "track_id": str(i), "category": c, "x": x, "y": y, "length": length, "width": width,
             "height": height, "yaw": yaw, "agent": None}
            for k in range(2) for i, c, x, y, yaw, length, width, height in moved(k)]
    rows += [{**row, "agent": agent} for row in list(rows) for agent in ("700", "702")
             if row["track_id"] != agent and math.hypot(row["x"], row["y"]) < 28]
    path.parent.mkdir(parents=True, exist_ok=True)
    pl.DataFrame(rows).write_csv(path)
    return path
