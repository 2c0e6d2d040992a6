"""Releases of the vehicle-infrastructure family beyond DAIR-V2X-C, in their exact published layouts:
V2X-Seq-SPD (DAIR-like sides and a cooperative label, ``json.dump``) and TUMTraf-V2X (OpenLABEL JSON).
The same world as ``support.releases``: the ego ``641`` is the vehicle, ``-1`` the infrastructure."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from cbm import se2

from .releases import AGENTS, _dair_labels, _rigid, lidar_pose, moved, save_pcd, seen_by, sweep, write_json

# --- V2X-Seq-SPD -----------------------------------------------------------------------------------------------

SPD_OFFSET = {"delta_x": -0.7, "delta_y": -0.13999999999999996}
SPD_START_US = 1626155122981522
"""The first vehicle sweep's ``pointcloud_timestamp`` (microseconds); frames follow every 100 ms."""
SPD_REACH = 25.0
"""Metres each side labels around itself: the vehicle misses 702 and 705, the infrastructure 703, 705, 706."""
SPD_TRACKS = {"641": 9000, "-1": 5000, "cooperative": 2000}
"""Track id of object ``i`` in each label set: ``f"{base + i:06d}"`` (the sets share no ids, as in the release)."""


def spd_track(labels: str, object_id: int) -> str:
    return f"{SPD_TRACKS[labels] + object_id:06d}"


def _spd_side_labels(pose: np.ndarray, objects: list[tuple], labels: str) -> list[dict]:
    """A side's tracking labels, keys in the release's order."""
    return [{"token": f"{spd_track(labels, o[0])}-token", "type": label["type"], "track_id": spd_track(labels, o[0]),
             "truncated_state": 0, "occluded_state": 2, "alpha": -1.364216, "2d_box": label["2d_box"],
             "3d_dimensions": label["3d_dimensions"], "3d_location": label["3d_location"],
             "rotation": label["rotation"]}
            for o, label in zip(objects, _dair_labels(pose, objects))]


def _spd_source(agent: str, object_id: int, objects: list[tuple]) -> str:
    """The side track id a cooperative label names, ``"-1"`` when that side does not label the object."""
    return spd_track(agent, object_id) if object_id in {o[0] for o in seen_by(agent, objects, SPD_REACH)} else "-1"


def _spd_cooperative_labels(frames: tuple[str, str], stamps: tuple[str, str], objects: list[tuple]) -> list[dict]:
    """``cooperative/label/<vehicle frame>.json``: every object either side labels, in the vehicle LiDAR
    frame, with ``from_side`` and the side track ids and tokens it fuses."""
    labelled = {o[0] for agent in ("641", "-1") for o in seen_by(agent, objects, SPD_REACH)}
    fused = [o for o in objects if o[0] in labelled]
    labels = []
    for o, label in zip(fused, _spd_side_labels(lidar_pose("641"), fused, "cooperative")):
        veh, inf = _spd_source("641", o[0], objects), _spd_source("-1", o[0], objects)
        side = "coop" if "-1" not in (veh, inf) else ("inf" if veh == "-1" else "veh")
        dims = label["3d_dimensions"]
        labels.append({**label, "3d_dimensions": {"l": dims["l"], "w": dims["w"], "h": dims["h"]}, "from_side": side,
                       "veh_pointcloud_timestamp": stamps[0], "inf_pointcloud_timestamp": stamps[1],
                       "veh_frame_id": frames[0], "inf_frame_id": frames[1], "veh_track_id": veh, "inf_track_id": inf,
                       "veh_token": "-1" if veh == "-1" else f"{veh}-token",
                       "inf_token": "-1" if inf == "-1" else f"{inf}-token"})
    return labels


def _spd_frame_info(side: str, frame: str, stamp: str, frames: list[str]) -> dict:
    """One entry of ``<side>-side/data_info.json``, keys in the release's order."""
    calib = (["camera_intrinsic", "lidar_to_camera", "lidar_to_novatel", "novatel_to_world"] if side == "vehicle"
             else ["camera_intrinsic", "virtuallidar_to_camera", "virtuallidar_to_world"])
    label = "lidar" if side == "vehicle" else "virtuallidar"
    entry = {"image_path": f"image/{frame}.jpg", "pointcloud_path": f"velodyne/{frame}.pcd",
             **{f"calib_{name}_path": f"calib/{name}/{frame}.json" for name in calib},
             "label_camera_std_path": f"label/camera/{frame}.json",
             "label_lidar_std_path": f"label/{label}/{frame}.json", "intersection_loc": "yizhuang06"}
    if side == "infrastructure":
        entry.update(camera_ip="172.16.3.74", camera_id="1", lidar_id="3")
    entry.update(image_timestamp=str(int(stamp) + 79478), pointcloud_timestamp=stamp, frame_id=frame)
    if side == "vehicle":
        entry.update(start_frame_id=frames[0], end_frame_id=frames[-1])
    else:
        entry["valid_frames_splits"] = [{"start_frame_id": frames[0], "end_frame_id": frames[-1]}]
    entry.update(num_frames=len(frames), sequence_id="0000")
    return entry


def _spd_calibration(root: Path, vehicle_id: str, infra_id: str) -> None:
    """The frame's calibration files; the shipped ``virtuallidar_to_world`` lacks ``SPD_OFFSET``."""
    shipped = lidar_pose("-1").copy()
    shipped[:2, 2] -= [SPD_OFFSET["delta_x"], SPD_OFFSET["delta_y"]]
    write_json(root / "infrastructure-side" / "calib" / "virtuallidar_to_world" / f"{infra_id}.json",
               _rigid(shipped, 5.0))
    calib = root / "vehicle-side" / "calib"
    write_json(calib / "lidar_to_novatel" / f"{vehicle_id}.json", {"transform": _rigid(se2.make(0.9, 0.0, 0.0), 1.6)})
    write_json(calib / "novatel_to_world" / f"{vehicle_id}.json", _rigid(lidar_pose("641") @ se2.make(-0.9, 0.0, 0.0)))


def spd_release(root: Path, frames: int = 3) -> Path:
    """``V2X-Seq-SPD/`` as the release ships it: one sequence ``0000`` of vehicle frames ``000009``...
    paired with infrastructure frames ``000000``..., tracked labels per side, cooperative labels, LiDAR
    sweeps, and DAIR-V2X-C's calibration with ``system_error_offset``."""
    ids = {"vehicle": [f"{9 + k:06d}" for k in range(frames)], "infrastructure": [f"{k:06d}" for k in range(frames)]}
    stamps = {"vehicle": [str(SPD_START_US + 100_000 * k) for k in range(frames)],
              "infrastructure": [str(SPD_START_US + 100_000 * k + 62874) for k in range(frames)]}
    sides = {"vehicle": ("641", "lidar"), "infrastructure": ("-1", "virtuallidar")}
    for k in range(frames):
        objects = moved(k)
        for side, (agent, label) in sides.items():
            folder, frame = root / f"{side}-side", ids[side][k]
            seen = seen_by(agent, objects, SPD_REACH)
            write_json(folder / "label" / label / f"{frame}.json", _spd_side_labels(lidar_pose(agent), seen, agent))
            (folder / "velodyne").mkdir(parents=True, exist_ok=True)
            points = sweep(agent, seen, left_handed=False)
            save_pcd(folder / "velodyne" / f"{frame}.pcd", ("x", "y", "z", "intensity"),
                     np.hstack([points, np.ones((len(points), 1), np.float32)]), "binary_compressed")
        _spd_calibration(root, ids["vehicle"][k], ids["infrastructure"][k])
        write_json(root / "cooperative" / "label" / f"{ids['vehicle'][k]}.json",
                   _spd_cooperative_labels((ids["vehicle"][k], ids["infrastructure"][k]),
                                           (stamps["vehicle"][k], stamps["infrastructure"][k]), objects))
    for side in sides:
        write_json(root / f"{side}-side" / "data_info.json",
                   [_spd_frame_info(side, frame, stamp, ids[side]) for frame, stamp in zip(ids[side], stamps[side])])
    write_json(root / "cooperative" / "data_info.json",
               [{"vehicle_frame": v, "infrastructure_frame": i, "vehicle_sequence": "0000",
                 "infrastructure_sequence": "0000", "system_error_offset": SPD_OFFSET}
                for v, i in zip(ids["vehicle"], ids["infrastructure"])])
    return root


# --- TUMTraf-V2X -----------------------------------------------------------------------------------------------

TUMTRAF_REGISTERED = "s110_lidar_ouster_south_and_vehicle_lidar_robosense_registered"
TUMTRAF_SENSORS = {"641": "vehicle_lidar_robosense", "-1": "s110_lidar_ouster_south"}
TUMTRAF_START = (1688626050, 947334296)
"""The first frame's seconds and nanoseconds (its file name); frames follow every 100 ms."""


def tumtraf_uuid(object_id: int) -> str:
    return f"{object_id:08x}-5a1e-4c3b-9d2f-0000000{object_id:05d}"


def _tumtraf_object(object_id: int, category: str, box: tuple, sensors: list[str]) -> dict:
    """One OpenLABEL object as the dev kit's ``save_to_openlabel`` lays it out, the box in the south
    Ouster LiDAR's frame and ``sensor_id`` naming the sensors that saw it (joined by ``_and_``)."""
    x, y, yaw, length, width, height = box
    return {"object_data": {
        "name": f"{category.upper()}_{tumtraf_uuid(object_id).split('-')[0]}", "type": category.upper(),
        "cuboid": {"name": "shape3D",
                   "val": [x, y, height / 2 - 7.5, 0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2),
                           length, width, height],
                   "attributes": {"text": [{"name": "occlusion_level", "val": "NOT_OCCLUDED"},
                                           {"name": "sensor_id", "val": "_and_".join(sensors)}],
                                  "num": [{"name": "num_points", "val": 120}], "boolean": [], "vec": []}}}}



def _tumtraf_stamp(k: int) -> tuple[str, float]:
    """Frame ``k``'s ``<sec>_<nsec>`` (file names) and its time in seconds."""
    nanoseconds = TUMTRAF_START[0] * 10**9 + TUMTRAF_START[1] + 100_000_000 * k
    return f"{nanoseconds // 10**9}_{nanoseconds % 10**9:09d}", nanoseconds / 1e9


def tumtraf_vehicle_lidar() -> np.ndarray:
    """The vehicle LiDAR -> south Ouster LiDAR transform (4x4; the Ouster sits 5.6 m above the car's LiDAR)."""
    relative = se2.inverse(lidar_pose("-1")) @ lidar_pose("641")
    out = np.eye(4)
    out[:2, :2], out[:2, 3], out[2, 3] = relative[:2, :2], relative[:2, 2], -5.6
    return out


def _tumtraf_objects(k: int) -> dict:
    """``uuid -> object`` of every object a sensor sees at frame ``k``, in the south Ouster LiDAR's frame."""
    to_infra = se2.inverse(lidar_pose("-1"))
    objects = {}
    for i, category, x, y, yaw, length, width, height in moved(k):
        sensors = [TUMTRAF_SENSORS[a] for a in ("-1", "641")
                   if math.hypot(x - AGENTS[a][0], y - AGENTS[a][1]) <= SPD_REACH]
        if sensors:
            (lx, ly), = se2.apply_points(to_infra, [[x, y]])
            box = (float(lx), float(ly), float(se2.wrap_angle(yaw + se2.yaw_of(to_infra))), length, width, height)
            objects[tumtraf_uuid(i)] = _tumtraf_object(i, category, box, sensors)
    return objects


def _tumtraf_record(k: int) -> dict:
    """The OpenLABEL file of frame ``k``."""
    stamp, seconds = _tumtraf_stamp(k)
    properties = {"timestamp": seconds,
                  "image_file_names": [f"{stamp}_s110_camera_basler_south1_8mm.jpg",
                                       f"{stamp}_vehicle_camera_basler_16mm.jpg"],
                  "point_cloud_file_names": [f"{stamp}_vehicle_lidar_robosense.pcd",
                                             f"{stamp}_s110_lidar_ouster_south.pcd",
                                             f"{stamp}_{TUMTRAF_REGISTERED}.pcd"],
                  "transforms": {"vehicle_lidar_robosense_to_s110_lidar_ouster_south": {
                      "src": "vehicle_lidar_robosense", "dst": "s110_lidar_ouster_south",
                      "transform_src_to_dst": {"matrix4x4": tumtraf_vehicle_lidar().tolist()}}}}
    systems = {"s110_lidar_ouster_south": {"type": "sensor_cs", "parent": "", "children": ["vehicle_lidar_robosense"]},
               "vehicle_lidar_robosense": {"type": "sensor_cs", "parent": "s110_lidar_ouster_south", "children": []}}
    return {"openlabel": {"metadata": {"schema_version": "1.0.0"}, "coordinate_systems": systems,
                          "frames": {str(k): {"frame_properties": properties, "objects": _tumtraf_objects(k)}}}}


def tumtraf_release(root: Path, frames: int = 3) -> Path:
    """A TUMTraf-V2X release root: ``train/labels_point_clouds/<registered>/<sec>_<nsec>_<registered>.json``,
    OpenLABEL written as the dev kit writes it (``json.dumps(..., ensure_ascii=True, indent=4)``)."""
    folder = root / "train" / "labels_point_clouds" / TUMTRAF_REGISTERED
    folder.mkdir(parents=True)
    for k in range(frames):
        text = json.dumps(_tumtraf_record(k), ensure_ascii=True, indent=4)
        (folder / f"{_tumtraf_stamp(k)[0]}_{TUMTRAF_REGISTERED}.json").write_text(text, encoding="utf-8")
    return root
