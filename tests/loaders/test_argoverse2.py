import json
import shutil

import numpy as np
import polars as pl
import pytest

import loaders
from loaders import argoverse2


def _quaternion_yaw(qw, qx, qy, qz):
    """Yaw of the rotated x axis, from the rotation-matrix formula (not scipy)."""
    r00 = 1 - 2 * (qy * qy + qz * qz)
    r10 = 2 * (qx * qy + qw * qz)
    return np.arctan2(r10, r00)


def test_default_scene_is_the_shipped_log():
    seq = loaders.open("argoverse2")
    assert len(seq) == 156
    assert seq.ego == "ego"
    counts = [len(frame) for frame in seq]
    assert sum(counts) == 12078 and min(counts) == 47 and max(counts) == 114
    np.testing.assert_allclose(np.diff(seq.timestamps).mean(), 0.1, atol=0.002)
    assert set(seq.map.kinds()) == {"lane_boundary", "crossing", "drivable_area"}
    assert len(seq.map.of_kind("crossing")) == 11 and len(seq.map.of_kind("drivable_area")) == 8
    assert len(seq.map.of_kind("lane_boundary")) == 2 * 199


def test_real_frame_matches_the_feather_file(shipped_log):
    seq = loaders.open(shipped_log)
    k = 40
    frame = seq[k]
    raw = pl.read_ipc(shipped_log / "annotations.feather")
    sweep = sorted(raw["timestamp_ns"].unique())[k]
    rows = raw.filter(pl.col("timestamp_ns") == sweep)
    pose = (pl.read_ipc(shipped_log / "city_SE3_egovehicle.feather")
            .filter(pl.col("timestamp_ns") == sweep).row(0, named=True))
    assert frame.frame_id == sweep
    assert list(frame.track_ids) == rows["track_uuid"].to_list()
    assert list(frame.categories) == rows["category"].to_list()
    ego_yaw = _quaternion_yaw(pose["qw"], pose["qx"], pose["qy"], pose["qz"])
    c, s = np.cos(ego_yaw), np.sin(ego_yaw)
    tx, ty = rows["tx_m"].to_numpy(), rows["ty_m"].to_numpy()
    boxes = frame.boxes()
    # Pittsburgh is nearly flat: roll and pitch of the car stay below a degree, so the planar
    # formula agrees with the full 3D mapping to centimetres.
    np.testing.assert_allclose(boxes[:, 0], pose["tx_m"] + c * tx - s * ty, atol=0.05)
    np.testing.assert_allclose(boxes[:, 1], pose["ty_m"] + s * tx + c * ty, atol=0.05)
    np.testing.assert_allclose(boxes[:, 3:6], rows.select("length_m", "width_m", "height_m").to_numpy())
    own = _quaternion_yaw(*(rows[q].to_numpy() for q in ("qw", "qx", "qy", "qz")))
    wrapped = np.angle(np.exp(1j * (boxes[:, 6] - own - ego_yaw)))
    np.testing.assert_allclose(wrapped, 0.0, atol=0.02)
    ego = frame.agents.row(0, named=True)
    assert ego["agent_id"] == "ego" and (ego["length"], ego["width"], ego["height"]) == (4.9, 2.0, 1.6)
    np.testing.assert_allclose([ego["x"], ego["y"], ego["yaw"]], [pose["tx_m"], pose["ty_m"], ego_yaw], atol=1e-3)


def test_one_box_by_hand(shipped_log):
    """First box of the first sweep: a bollard, values read from the feather file."""
    seq = loaders.open(shipped_log)
    x, y, z, length, width, height, yaw = seq[0].boxes()[0]
    assert seq[0].track_ids[0].startswith("364174e3")
    np.testing.assert_allclose([length], [0.593010], atol=1e-5)
    # ego pose at that sweep: (1468.8715, 211.5118), yaw 0.33473; box at (-49.0585, 8.3747) in the car frame
    c, s = np.cos(0.33473), np.sin(0.33473)
    np.testing.assert_allclose([x, y], [1468.8715 + c * -49.0585 - s * 8.3747, 211.5118 + s * -49.0585 + c * 8.3747],
                               atol=0.01)


def test_without_poses_frames_stay_in_the_car_frame(tmp_path, shipped_log):
    log = tmp_path / "log"
    log.mkdir()
    shutil.copy(shipped_log / "annotations.feather", log)
    seq = loaders.open(log)
    raw = pl.read_ipc(log / "annotations.feather")
    first = raw.filter(pl.col("timestamp_ns") == raw["timestamp_ns"].min())
    np.testing.assert_allclose(seq[0].boxes()[:, :3], first.select("tx_m", "ty_m", "tz_m").to_numpy())
    assert seq.map is None
    np.testing.assert_allclose(seq[5].agent_pose("ego"), np.eye(3))


def test_loading_all_frames_gives_every_frame(shipped_log):
    seq = argoverse2.load(shipped_log)
    frames = [(f.objects, f.boxes(), f.agents) for f in seq]
    assert len(frames) == 156 and all(len(boxes) == len(objects) for objects, boxes, _ in frames)


def test_missing_pose_for_a_sweep_is_refused(copy_fixture):
    log = copy_fixture("argoverse2/adcf7d18-0510-35b0-a2fa-b4cea13a6d76")
    poses = pl.read_ipc(log / "city_SE3_egovehicle.feather")
    poses.slice(1).write_ipc(log / "city_SE3_egovehicle.feather")
    with pytest.raises(loaders.LoaderError, match="no pose row with timestamp_ns"):
        loaders.open(log)


@pytest.mark.parametrize("change, message", [
    (lambda t: t.drop("qw"), "missing column.*qw"),
    (lambda t: t.rename({"tx_m": "x"}), "missing column.*tx_m"),
    (lambda t: t.with_columns(pl.lit("abc").alias("length_m")), "row 1, column length_m: 'abc' is not a number"),
    (lambda t: t.with_columns(pl.lit(0.0).alias("qw"), pl.lit(0.0).alias("qz")), "quaternion"),
    (lambda t: t.head(0), "no data rows"),
])
def test_malformed_annotations(copy_fixture, change, message):
    log = copy_fixture("argoverse2/adcf7d18-0510-35b0-a2fa-b4cea13a6d76")
    change(pl.read_ipc(log / "annotations.feather")).write_ipc(log / "annotations.feather")
    with pytest.raises(loaders.LoaderError, match=message):
        loaders.open(log)


def test_nan_rows_are_dropped_and_counted(copy_fixture):
    log = copy_fixture("argoverse2/adcf7d18-0510-35b0-a2fa-b4cea13a6d76")
    table = pl.read_ipc(log / "annotations.feather")
    table = table.with_columns(
        pl.when(pl.int_range(pl.len()) < 3).then(float("nan")).otherwise(pl.col("tx_m")).alias("tx_m"))
    table.write_ipc(log / "annotations.feather")
    with pytest.warns(UserWarning, match="dropped 3 row"):
        seq = loaders.open(log)
    assert seq.dropped_rows == 3 and sum(len(f) for f in seq) == table.height - 3


def test_map_with_a_bad_point_names_the_key(copy_fixture):
    log = copy_fixture("argoverse2/adcf7d18-0510-35b0-a2fa-b4cea13a6d76")
    map_file = next((log / "map").glob("*.json"))
    map_file.write_text(map_file.read_text().replace('"x"', '"X"', 1))
    with pytest.raises(loaders.LoaderError, match=r"pedestrian_crossings\[\d+\]\.edge1"):
        loaders.open(log)


def test_a_folder_of_several_logs_asks_for_one(tmp_path, copy_fixture):
    log = copy_fixture("argoverse2/adcf7d18-0510-35b0-a2fa-b4cea13a6d76")
    shutil.copytree(log, tmp_path / "second")
    with pytest.raises(loaders.LoaderError, match="holds 2 Argoverse 2 logs"):
        loaders.open(tmp_path)


def test_a_map_with_none_of_its_sections_is_refused_not_empty(copy_fixture):
    """Issue 50, item 9: the shipped map with its three sections renamed (was: an empty map, no word)."""
    log = copy_fixture("argoverse2/adcf7d18-0510-35b0-a2fa-b4cea13a6d76")
    map_file = next((log / "map").glob("*.json"))
    data = json.loads(map_file.read_text())
    map_file.write_text(json.dumps({f"{key}_v3": value for key, value in data.items()}))
    with pytest.raises(loaders.LoaderError, match=r"none of lane_segments, pedestrian_crossings, drivable_areas "
                                                  r"\(keys: \['pedestrian_crossings_v3', .*\]\): not an Argoverse 2"):
        loaders.open(log)


def test_a_map_key_beside_its_sections_is_named_in_a_warning(copy_fixture):
    log = copy_fixture("argoverse2/adcf7d18-0510-35b0-a2fa-b4cea13a6d76")
    map_file = next((log / "map").glob("*.json"))
    map_file.write_text(json.dumps({**json.loads(map_file.read_text()), "stop_lines": []}))
    with pytest.warns(UserWarning, match=r"key\(s\) \['stop_lines'\] not read"):
        seq = loaders.open(log)
    assert seq.map is not None and len(seq.map.polylines) > 0
