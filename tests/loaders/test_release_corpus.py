"""Every loader on a release in its exact published layout and encoding (``support.releases``: written
by the libraries the producers use), opened through ``loaders.open`` and shown as the app's first
frame; then what each release gets right that hand-made fixtures missed."""
from __future__ import annotations

import dataclasses
import json
import math
import shutil
import warnings

import numpy as np
import pytest

import loaders
from app.scene import drawing
from app.session.explorer import Explorer
from app.session.settings import Settings
from cbm import se2
from evaluation.scenario import ScenarioParams
from evaluation.trials import build_trial
from loaders.opv2v import category
from support import releases, releases_v2i

WRITERS = {
    "opv2v": lambda root: releases.opv2v_root(root / "OPV2V"),
    "v2xset": lambda root: releases.v2xset_scenario(root / "2021_08_20_21_48_35"),
    "adver_city": lambda root: releases.adver_city_run(root / "data_dumping"),
    "v2v4real": lambda root: releases.v2v4real_scenario(root / "testoutput_CAV_data_2022-03-15-09-54-40_0"),
    "v2v4real_matrix": lambda root: releases.v2v4real_scenario(root / "testoutput_CAV_data_2022-03-15-09-54-40_0",
                                                               pose="matrix"),
    "v2v4real_numpy": lambda root: releases.v2v4real_scenario(root / "testoutput_CAV_data_2022-03-15-09-54-40_0",
                                                              pose="numpy"),
    "v2x_real": lambda root: releases.v2x_real_root(root / "v2xreal"),
    "dair_v2x_c": lambda root: releases.dair_release(root / "cooperative-vehicle-infrastructure"),
    "dair_v2x_c_subset": lambda root: releases.dair_release(root / "cooperative-vehicle-infrastructure",
                                                            world_calib=False),
    "dair_v2x_c_no_offset": lambda root: releases.dair_release(root / "cooperative-vehicle-infrastructure",
                                                               offset=""),
    "v2x_seq_spd": lambda root: releases_v2i.spd_release(root / "V2X-Seq-SPD"),
    "tumtraf_v2x": lambda root: releases_v2i.tumtraf_release(root / "tumtraf_v2x_cooperative_perception_dataset"),
    "sind_without_lfs": lambda root: releases.sind_without_lfs(root / "Xian_412_m1"),
    "v2x_sim": lambda root: releases.v2x_sim_root(root / "V2X-Sim-2.0-mini"),
    "argoverse2": lambda root: shutil.copytree(releases.FIXTURES / "argoverse2", root / "logs"),
    "interaction": lambda root: shutil.copy(releases.FIXTURES / "interaction" / "vehicle_tracks_000.csv", root),
    "table": lambda root: releases.generic_table(root / "boxes.csv"),
}
EXPECTED = {  # release -> (frames, agents of the first frame)
    "opv2v": (4, ["641", "650"]), "v2xset": (2, ["641", "650", "-1"]), "adver_city": (1, ["641", "650", "-1", "-2"]),
    "v2v4real": (1, ["0", "1"]), "v2v4real_matrix": (1, ["0", "1"]), "v2v4real_numpy": (1, ["0", "1"]),
    "v2x_real": (2, ["1", "2", "-1"]),
    "dair_v2x_c": (3, ["vehicle", "infrastructure"]),
    "dair_v2x_c_subset": (3, ["vehicle", "infrastructure"]),
    "dair_v2x_c_no_offset": (3, ["vehicle", "infrastructure"]),
    "v2x_seq_spd": (3, ["vehicle", "infrastructure"]),
    "tumtraf_v2x": (3, ["vehicle", "infrastructure"]),
    "sind_without_lfs": (None, None),
    "v2x_sim": (2, ["0", "1", "2"]), "argoverse2": (3, ["ego"]), "interaction": (None, None),
    "table": (2, ["700", "702"]),
}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> dict:
    root = tmp_path_factory.mktemp("releases")
    out = {}
    for name, write in WRITERS.items():
        (root / name).mkdir()
        out[name] = write(root / name)
    return out


def opened(release: str, path):
    """The release opened; those that say what they skipped or used instead warn once."""
    if release in ("sind_without_lfs", "dair_v2x_c_subset", "v2x_real"):
        with pytest.warns(UserWarning):
            return loaders.open(path)
    return loaders.open(path)


@pytest.mark.parametrize("release", list(WRITERS))
def test_each_release_opens_and_shows_its_first_frame(corpus, release):
    sequence = opened(release, corpus[release])
    frames, agents = EXPECTED[release]
    if frames is not None:
        assert len(sequence) == frames
    if agents is not None:
        assert sequence[0].agents["agent_id"].to_list() == agents
    explorer = Explorer(sequence)
    settings = Settings() if agents else Settings().with_scenario(protocol="sind")
    outcome = explorer.compute(dataclasses.replace(settings, view=dataclasses.replace(settings.view, points=True)))
    picture = drawing.draw(outcome, explorer.map_segments, sequence[outcome.frame_index])
    assert "precision" in picture.metrics_markdown and "LiDAR points not shown" not in picture.metrics_markdown
    assert len(outcome.trial.ego_boxes) + len(outcome.trial.cav_boxes) == len(outcome.trial.ego_ids) + len(
        outcome.trial.cav_ids) > 0


def test_opv2v_reported_lidar_pose_carries_exactly_the_gnss_error(corpus):
    frame = loaders.open(corpus["opv2v"])[0]
    true_lidar, reported = frame.agent_pose("650"), frame.predicted_pose("650")
    x, y, yaw = releases.AGENTS["650"]
    dx, dy, dyaw = releases.GNSS_ERROR["650"]
    body, predicted_body = se2.make(x, y, yaw), se2.make(x + dx, y + dy, yaw + math.radians(dyaw))
    # the GNSS error of the file, expressed at the sensor: the body's error applied to the true LiDAR pose
    expected = predicted_body @ se2.inverse(body) @ true_lidar
    np.testing.assert_allclose(reported, expected, atol=1e-6)
    lever = np.linalg.norm(se2.translation_of(true_lidar) - [x, y])
    assert lever == pytest.approx(0.5, abs=1e-6)                       # the mount offset the old reading kept
    rotation_part = 2 * lever * math.sin(math.radians(dyaw) / 2)
    gap = np.linalg.norm(se2.translation_of(reported) - se2.translation_of(true_lidar))
    assert abs(gap - math.hypot(dx, dy)) <= rotation_part + 1e-3        # 0.05 m, not 0.5 m
    assert se2.yaw_of(reported) - se2.yaw_of(true_lidar) == pytest.approx(math.radians(dyaw), abs=1e-9)
    ego = loaders.open(corpus["opv2v"])[0]
    np.testing.assert_allclose(ego.predicted_pose("641"), ego.agent_pose("641"), atol=1e-9)  # no error: the truth


def test_opv2v_dataset_localization_init_is_the_reported_pose(corpus):
    frame = loaders.open(corpus["opv2v"])[0]
    trial = build_trial(frame, ScenarioParams(protocol="opv2v", localization="dataset"), seed=0, cav="650")
    np.testing.assert_allclose(trial.init, se2.inverse(frame.agent_pose("641")) @ frame.predicted_pose("650"))
    assert np.linalg.norm(se2.translation_of(trial.init) - se2.translation_of(trial.T_true)) < 0.1


def test_opv2v_open3d_ascii_sweeps_fall_inside_their_boxes(corpus):
    frame = loaders.open(corpus["opv2v"])[0]
    points = frame.points("650")
    world = se2.apply_points(frame.agent_pose("650"), points[:, :2])
    box = frame.boxes()[list(frame.track_ids).index("700")]
    local = se2.apply_points(se2.inverse(se2.make(box[0], box[1], box[6])), world)
    inside = (np.abs(local[:, 0]) <= box[3] / 2) & (np.abs(local[:, 1]) <= box[4] / 2)
    assert inside[:4].all()                         # the sweep's first four points are car 700's
    np.testing.assert_allclose(points[-64:, 2], -1.9, atol=1e-6)   # the ground ring, 1.9 m below the sensor


def test_adver_city_walkers_classes_and_two_roadside_units(corpus):
    sequence = loaders.open(corpus["adver_city"])
    frame = sequence[0]
    assert sequence.scenarios == {"2024_07_12_14_13_22/unj_cn_d": 0} and frame.ego == "641"
    categories = dict(zip(frame.track_ids, frame.categories))
    assert categories["1300"] == categories["1301"] == "pedestrian" and categories["702"] == "van"
    assert categories["704"] == "truck"
    walker = frame.boxes()[list(frame.track_ids).index("1300")]
    np.testing.assert_allclose(walker[[0, 1, 2, 3, 4]], [9.0, 8.0, 0.93, 0.38, 0.38], atol=1e-9)  # no center key
    assert sequence.left_out_of_trials == {"pedestrian"}
    trial = build_trial(frame, ScenarioParams(protocol="opv2v"), seed=0, cav="650")
    assert not any(str(i).startswith("13") for i in np.concatenate([trial.ego_ids, trial.cav_ids]))
    sequence.left_out_of_trials = frozenset()
    included = build_trial(sequence[0], ScenarioParams(protocol="opv2v"), seed=0, cav="650")
    assert "1300" in set(map(str, included.ego_ids))


def test_dair_compressed_sweeps_load_and_lie_in_their_boxes(corpus):
    frame = loaders.open(corpus["dair_v2x_c"])[0]
    for agent in ("vehicle", "infrastructure"):
        points = frame.points(agent)
        world = se2.apply_points(frame.agent_pose(agent), points[:, :2])
        box = frame.boxes()[0]
        local = se2.apply_points(se2.inverse(se2.make(box[0], box[1], box[6])), world)
        assert ((np.abs(local[:, 0]) <= box[3] / 2) & (np.abs(local[:, 1]) <= box[4] / 2)).sum() == 4


def test_dair_subset_uses_lidar_i2v_without_adding_the_offset_twice(corpus):
    full = loaders.open(corpus["dair_v2x_c"])
    with pytest.warns(UserWarning, match=r"3 of 3 pair\(s\) ship no world calibration, so the roadside unit is "
                                         r"placed by .*lidar_i2v.*vehicle frames 000010, 000011, 000012"):
        subset = loaders.open(corpus["dair_v2x_c_subset"])
    assert subset.warnings == [] and len(subset.notes) == 1
    for k in range(3):
        relative = se2.inverse(full[k].agent_pose("vehicle")) @ full[k].agent_pose("infrastructure")
        np.testing.assert_allclose(subset[k].agent_pose("infrastructure"), relative, atol=1e-9)
        np.testing.assert_allclose(subset[k].agent_pose("vehicle"), np.eye(3), atol=1e-12)
        truth = se2.inverse(releases.lidar_pose("641")) @ releases.lidar_pose("-1")
        np.testing.assert_allclose(relative, truth, atol=1e-9)


def test_dair_string_label_states_and_empty_offset_load_silently(corpus):
    infra_label = corpus["dair_v2x_c_no_offset"] / "infrastructure-side" / "label" / "virtuallidar" / "000020.json"
    first = json.loads(infra_label.read_text())[0]
    assert all(isinstance(first[k], str) for k in ("truncated_state", "occluded_state", "alpha"))
    info = json.loads((corpus["dair_v2x_c_no_offset"] / "cooperative" / "data_info.json").read_text())
    assert {pair["system_error_offset"] for pair in info} == {""}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sequence = loaders.open(corpus["dair_v2x_c_no_offset"])
    assert sequence.warnings == []
    truth = se2.inverse(releases.lidar_pose("641")) @ releases.lidar_pose("-1")
    for frame in sequence:
        relative = se2.inverse(frame.agent_pose("vehicle")) @ frame.agent_pose("infrastructure")
        np.testing.assert_allclose(relative, truth, atol=1e-9)
    assert len(sequence[0].visibility["infrastructure"]) == len(json.loads(infra_label.read_text()))


def _shift_infrastructure_label(root, object_id: int, metres: float) -> None:
    """Move one infrastructure label of the first frame ``metres`` along its LiDAR's x, beyond any derived match."""
    path = root / "infrastructure-side" / "label" / "virtuallidar" / "000000.json"
    labels = json.loads(path.read_text())
    label = next(label for label in labels if label["track_id"] == releases_v2i.spd_track("-1", object_id))
    label["3d_location"]["x"] += metres
    releases.write_json(path, labels)


def test_spd_cooperative_label_gives_the_association_and_the_ids_persist(corpus, tmp_path):
    root = shutil.copytree(corpus["v2x_seq_spd"], tmp_path / "V2X-Seq-SPD")
    _shift_infrastructure_label(root, 707, 3.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sequence = loaders.open(root)
    assert sequence.name.startswith("v2x-seq-spd") and sequence.scenarios == {"0000": 0}
    np.testing.assert_allclose(sequence.timestamps, [0.0, 0.1, 0.2], atol=1e-9)
    first, last = sequence[0], sequence[-1]
    track = {i: releases_v2i.spd_track("cooperative", i) for i in (702, 703, 705, 706, 707)}
    assert set(first.track_ids) == set(last.track_ids) and track[705] not in set(first.track_ids)
    seen = first.visibility
    assert track[702] not in seen["vehicle"] and track[702] in seen["infrastructure"]
    assert track[703] in seen["vehicle"] and track[703] not in seen["infrastructure"]
    assert track[707] in seen["vehicle"] and track[707] in seen["infrastructure"]   # 3 m apart, fused by the label
    ids, boxes = first.agent_view("infrastructure")
    fused = first.boxes()[list(first.track_ids).index(track[707])]
    assert np.linalg.norm(boxes[list(ids).index(track[707])][:2] - fused[:2]) == pytest.approx(3.0, abs=1e-6)
    truth = se2.inverse(releases.lidar_pose("641")) @ releases.lidar_pose("-1")
    relative = se2.inverse(first.agent_pose("vehicle")) @ first.agent_pose("infrastructure")
    np.testing.assert_allclose(relative, truth, atol=1e-9)                          # system_error_offset added


def test_spd_pair_without_cooperative_label_is_associated_by_distance_and_said(corpus, tmp_path):
    root = shutil.copytree(corpus["v2x_seq_spd"], tmp_path / "V2X-Seq-SPD")
    _shift_infrastructure_label(root, 707, 3.0)
    (root / "cooperative" / "label" / "000009.json").unlink()
    with pytest.warns(UserWarning, match=r"1 of 3 pair\(s\) have no cooperative label.*vehicle frames 000009"):
        sequence = loaders.open(root)
    seen = sequence[0].visibility
    vehicle_707, infra_707 = (f"v{releases_v2i.spd_track('641', 707)}", f"i{releases_v2i.spd_track('-1', 707)}")
    assert vehicle_707 in seen["vehicle"] and infra_707 in seen["infrastructure"]      # beyond 2 m: not matched
    assert f"v{releases_v2i.spd_track('641', 700)}" in seen["infrastructure"]               # within 2 m: matched
    assert len(sequence.notes) == 1 and releases_v2i.spd_track("cooperative", 700) in set(sequence[1].track_ids)


def test_spd_pair_naming_a_frame_the_side_lacks_names_the_field(corpus, tmp_path):
    root = shutil.copytree(corpus["v2x_seq_spd"], tmp_path / "V2X-Seq-SPD")
    info = json.loads((root / "cooperative" / "data_info.json").read_text())
    info[1]["infrastructure_frame"] = "000099"
    releases.write_json(root / "cooperative" / "data_info.json", info)
    with pytest.raises(loaders.LoaderError, match=r"data_info.json: \[1\].infrastructure_frame: '000099' is not a "
                                                  r"frame_id of infrastructure-side/data_info.json"):
        loaders.open(root)


def test_tumtraf_vehicle_pose_boxes_and_sensor_id_visibility(corpus):
    root = corpus["tumtraf_v2x"]
    registered = root / "train" / "labels_point_clouds" / releases_v2i.TUMTRAF_REGISTERED
    for opened_at in (root, root / "train", registered):
        sequence = loaders.open(opened_at)
        assert len(sequence) == 3 and sequence.scenarios == {"train": 0} and sequence.warnings == []
    np.testing.assert_allclose(sequence.timestamps, [0.0, 0.1, 0.2], atol=1e-6)
    frame = sequence[0]
    truth = se2.inverse(releases.lidar_pose("-1")) @ releases.lidar_pose("641")
    np.testing.assert_allclose(frame.agent_pose("vehicle"), truth, atol=1e-9)
    np.testing.assert_allclose(frame.agent_pose("infrastructure"), np.eye(3), atol=1e-12)
    uuid = {i: releases_v2i.tumtraf_uuid(i) for i in (700, 702, 703, 704, 705)}
    box = frame.boxes()[list(frame.track_ids).index(uuid[704])]
    world = se2.apply_points(releases.lidar_pose("-1"), [box[:2]])[0]
    np.testing.assert_allclose(world, [3.5, -20.0], atol=1e-9)
    assert frame.categories[list(frame.track_ids).index(uuid[704])] == "truck"
    assert set(frame.track_ids) == set(sequence[2].track_ids) and uuid[705] not in set(frame.track_ids)
    seen = frame.visibility
    assert uuid[702] in seen["infrastructure"] and uuid[702] not in seen["vehicle"]
    assert uuid[703] in seen["vehicle"] and uuid[703] not in seen["infrastructure"]
    assert uuid[700] in seen["vehicle"] and uuid[700] in seen["infrastructure"]


def test_tumtraf_without_sensor_id_has_no_visibility_and_says_so(corpus, tmp_path):
    root = shutil.copytree(corpus["tumtraf_v2x"], tmp_path / "tumtraf")
    path = sorted((root / "train" / "labels_point_clouds" / releases_v2i.TUMTRAF_REGISTERED).glob("*.json"))[1]
    record = json.loads(path.read_text())
    item = next(iter(record["openlabel"]["frames"]["1"]["objects"].values()))
    item["object_data"]["cuboid"]["attributes"]["text"] = []
    path.write_text(json.dumps(record, indent=4))
    with pytest.warns(UserWarning, match=r"1 of 27 object\(s\) have no sensor_id attribute"):
        sequence = loaders.open(root)
    assert sequence.visibility is None and sequence[0].agents is not None


def test_tumtraf_frame_without_the_vehicle_transform_names_the_key(corpus, tmp_path):
    root = shutil.copytree(corpus["tumtraf_v2x"], tmp_path / "tumtraf")
    path = sorted((root / "train" / "labels_point_clouds" / releases_v2i.TUMTRAF_REGISTERED).glob("*.json"))[0]
    record = json.loads(path.read_text())
    record["openlabel"]["frames"]["0"]["frame_properties"]["transforms"] = {}
    path.write_text(json.dumps(record))
    with pytest.raises(loaders.LoaderError, match=r"missing key openlabel.frames.0.frame_properties.transforms."
                                                  r"vehicle_lidar_robosense_to_s110_lidar_ouster_south"):
        loaders.open(root)


def test_dair_pair_missing_a_file_is_skipped_and_counted(corpus, tmp_path):
    root = shutil.copytree(corpus["dair_v2x_c_subset"], tmp_path / "subset")
    (root / "infrastructure-side" / "label" / "virtuallidar" / "000021.json").unlink()
    (root / "cooperative" / "calib" / "lidar_i2v" / "000012.json").write_bytes(releases.LFS_POINTER)
    with pytest.warns(UserWarning) as caught:
        sequence = loaders.open(root)
    assert sequence.frame_ids == ["000010"]
    skipped = [w for w in sequence.warnings if "skipped" in w]
    assert len(skipped) == 1 and "skipped 2 of 3 pair(s)" in skipped[0] and "1 Git LFS pointer" in skipped[0]
    assert len(caught) == 2


def test_sind_pedestrians_load_beside_an_lfs_pointer(corpus):
    with pytest.warns(UserWarning, match=r"Veh_smoothed_tracks.csv.*run `git lfs pull`"):
        sequence = loaders.open(corpus["sind_without_lfs"])
    assert set(sequence.objects["category"].unique()) == {"pedestrian"} and len(sequence) > 10
    assert "skipped 1 Git LFS pointer file(s)" in sequence.warnings[0]


def test_sind_with_only_a_pointer_names_it(tmp_path):
    (tmp_path / "Veh_smoothed_tracks.csv").write_bytes(releases.LFS_POINTER)
    with pytest.raises(loaders.LoaderError, match=r"Veh_smoothed_tracks.csv is a Git LFS pointer, not the data: "
                                                  r"run `git lfs pull` in the dataset's repository"):
        loaders.open(tmp_path)


def test_argoverse2_pose_table_as_an_lfs_pointer_names_it(corpus, tmp_path):
    log = shutil.copytree(corpus["argoverse2"], tmp_path / "logs") / "adcf7d18-0510-35b0-a2fa-b4cea13a6d76"
    (log / "city_SE3_egovehicle.feather").write_bytes(releases.LFS_POINTER)
    with pytest.raises(loaders.LoaderError, match=r"city_SE3_egovehicle.feather is a Git LFS pointer"):
        loaders.open(log)


def test_adver_city_documented_sample_reports_the_gnss_error_to_the_millimetre(tmp_path):
    """Adver-City's documented frame (its docs/annotations.md): LiDAR 0.49 m from the body origin;
    a GNSS error of (0.03, 0.04) m on the body moves the reported LiDAR pose by 0.05 m, not 0.5 m."""
    body = [213.65081787109375, -5.478086948394775, 0.0357675738632679, -0.00433349609375, -174.12957763671875,
            -0.2315092533826828]
    lidar = [214.1405487060547, -5.427590370178223, 1.9377721548080444, -0.00433349609375, -174.12957763671875,
             -0.2315092533826828]
    record = releases.cav_record("650", 0, adver_city=True)
    record.update(lidar_pose=lidar, true_ego_pos=body, predicted_ego_pos=[body[0] + 0.03, body[1] + 0.04, *body[2:]])
    releases.dump_yaml(tmp_path / "s" / "650" / "000060.yaml", record)
    frame = loaders.open(tmp_path / "s")[0]
    gap = se2.translation_of(frame.predicted_pose("650")) - se2.translation_of(frame.agent_pose("650"))
    assert np.linalg.norm(gap) == pytest.approx(0.05, abs=1e-6)
    np.testing.assert_allclose(gap, [0.03, -0.04], atol=1e-6)           # y mirrored: CARLA is left-handed
    old_reading = np.hypot(body[0] + 0.03 - lidar[0], body[1] + 0.04 - lidar[1])
    assert old_reading > 0.45


def test_unknown_actor_classes_keep_their_name():
    assert category({"class": "Scooter "}, "vehicles") == "Scooter"
    assert category({"obj_type": "Pedestrian"}, "vehicles") == "pedestrian"
    assert category({}, "walkers") == "pedestrian" and category({}, "cyclists") == "cyclists"


def test_v2v4real_pose_matrix_and_numpy_tags_give_the_same_scene(corpus):
    plain = loaders.open(corpus["v2v4real"])[0]
    assert "!!python/object/apply:numpy" in (corpus["v2v4real_numpy"] / "0" / "000000.yaml").read_text()
    for release in ("v2v4real_matrix", "v2v4real_numpy"):
        frame = loaders.open(corpus[release])[0]
        assert list(frame.track_ids) == list(plain.track_ids)
        np.testing.assert_allclose(frame.boxes(), plain.boxes(), atol=1e-9)
        for agent in ("0", "1"):
            np.testing.assert_allclose(frame.agent_pose(agent), plain.agent_pose(agent), atol=1e-9)
    np.testing.assert_allclose(plain.agent_pose("1"), releases.lidar_pose("650"), atol=1e-9)


@pytest.mark.parametrize("pose, message", [
    ([[1.0, 0.0, 0.0, 0.0]] * 4, r"lidar_pose: expected a rigid 4x4 transform"),
    ([[1.0, 0.0, 0.0]] * 4, r"lidar_pose\[0\]: expected 4 numbers"),
    ([[1.0, 0.0, 0.0, 0.0]] * 3, r"lidar_pose: expected 4 rows of 4 numbers"),
])
def test_v2v4real_bad_pose_matrix_is_named(corpus, tmp_path, pose, message):
    root = shutil.copytree(corpus["v2v4real_matrix"], tmp_path / "scenario")
    record = releases.yaml.safe_load((root / "1" / "000000.yaml").read_text())
    releases.dump_yaml(root / "1" / "000000.yaml", {**record, "lidar_pose": pose})
    with pytest.raises(loaders.LoaderError, match=r"1/000000.yaml: " + message):
        loaders.open(root)


def test_python_tags_other_than_numpy_values_are_refused(corpus, tmp_path):
    root = shutil.copytree(corpus["v2v4real_numpy"], tmp_path / "scenario")
    path = root / "0" / "000000.yaml"
    path.write_text(path.read_text().replace("numpy._core.multiarray._reconstruct", "os.system", 1)
                    .replace("numpy.core.multiarray._reconstruct", "os.system", 1))
    with pytest.raises(loaders.LoaderError, match=r"0/000000.yaml: not valid YAML \(.*apply:os.system: not read "
                                                  r"\(only numpy numbers and arrays are\)\)"):
        loaders.open(root)


def test_v2x_real_categories_infrastructure_and_static_props(corpus):
    with pytest.warns(UserWarning, match=r"1 static object\(s\) \(trash_can\) are not road users: left out of trials"):
        sequence = loaders.open(corpus["v2x_real"])
    assert sequence.name == "v2x_real/v2xreal" and sequence.warnings == [] and len(sequence.notes) == 1
    assert sequence.ego == "1"
    frame = sequence[0]
    categories = dict(zip(frame.track_ids, frame.categories))
    assert (categories["700"], categories["702"], categories["704"]) == ("car", "van", "truck")
    assert (categories["1300"], categories["1401"], categories["1400"]) == ("pedestrian", "bicycle", "trash_can")
    box = frame.boxes()[list(frame.track_ids).index("707")]          # right-handed: nothing mirrored
    np.testing.assert_allclose(box[[0, 1, 3, 6]], [16.0, -12.0, 4.6, 1.2], atol=1e-9)
    np.testing.assert_allclose(frame.agent_pose("-1"), releases.lidar_pose("-1"), atol=1e-9)
    infra = frame.agents.filter(frame.agents["agent_id"] == "-1")
    assert (infra["length"][0], infra["height"][0]) == (0.6, 5.0)        # a pole, as V2XSet's roadside units
    trial = build_trial(frame, ScenarioParams(protocol="opv2v"), seed=0, cav="2")
    ids = set(map(str, np.concatenate([trial.ego_ids, trial.cav_ids])))
    assert "1400" not in ids and "1401" in ids


@pytest.mark.parametrize("flag, message", [(True, r"infra: expected false in agent folder '2' \(negative ids are "
                                                  r"infrastructure\), got true"),
                                           ("yes please", r"infra: expected true or false, got 'yes please'")])
def test_v2x_real_infra_flag_must_agree_with_the_folder(corpus, tmp_path, flag, message):
    root = shutil.copytree(corpus["v2x_real"], tmp_path / "v2xreal")
    path = root / "train" / "2023-03-17-15-53-02_1_0" / "2" / "000001.yaml"
    releases.dump_yaml(path, {**releases.yaml.safe_load(path.read_text()), "infra": flag})
    with pytest.raises(loaders.LoaderError, match=r"2/000001.yaml: " + message):
        loaders.open(root)


def test_an_adver_city_agent_folder_loads_as_its_one_frame_file_does(corpus):
    """A folder holding one agent's frames (``<run>/<scenario>/641/000060.yaml``) loads as the file inside it."""
    folder = corpus["adver_city"] / "2024_07_12_14_13_22" / "unj_cn_d" / "641"
    from_folder, from_file = loaders.open(folder), loaders.open(folder / "000060.yaml")
    assert len(from_folder) == len(from_file) == 1
    assert list(from_folder[0].track_ids) == list(from_file[0].track_ids)
    np.testing.assert_allclose(from_folder[0].boxes(), from_file[0].boxes())
