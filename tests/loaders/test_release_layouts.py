"""Real release layouts: DAIR-V2X-C with gaps and string numbers, OPV2V-family split roots and
``predicted_ego_pos`` as the dataset's own localization error (fixtures built here from the
hand-made ones, field by field as the releases write them)."""
import json
import math
import shutil

import numpy as np
import pytest

import loaders
from evaluation.scenario import ScenarioParams
from evaluation.trials import build_trial

DAIR = "dair_v2x/cooperative-vehicle-infrastructure"
PAIR = {
    "vehicle_image_path": "vehicle-side/image/000011.jpg",
    "vehicle_pointcloud_path": "vehicle-side/velodyne/000011.pcd",
    "infrastructure_image_path": "infrastructure-side/image/000021.jpg",
    "infrastructure_pointcloud_path": "infrastructure-side/velodyne/000021.pcd",
    "cooperative_label_path": "cooperative/label_world/000011.json",
    "system_error_offset": {"delta_x": "-0.5", "delta_y": "0"},
}


def _info(root):
    return root / "cooperative" / "data_info.json"


def _write_pairs(root, pairs):
    _info(root).write_text(json.dumps(pairs))


def test_dair_missing_files_are_skipped_counted_and_named(copy_fixture):
    root = copy_fixture(DAIR)
    pairs = json.loads(_info(root).read_text())
    _write_pairs(root, pairs + [PAIR, {**PAIR, "vehicle_pointcloud_path": "vehicle-side/velodyne/000012.pcd"}])
    with pytest.warns(UserWarning, match=r"skipped 2 of 3 pair\(s\).*first: .*lidar_to_novatel.000011\.json"):
        seq = loaders.open(root)
    assert seq.frame_ids == ["000010"]
    assert len(seq.warnings) == 1 and "skipped 2 of 3" in seq.warnings[0]


def test_slow_loads_show_progress(copy_fixture, release, monkeypatch, capsys):
    from loaders import dair_v2x, opv2v
    monkeypatch.setattr(dair_v2x, "PROGRESS_DELAY", 0.0)
    monkeypatch.setattr(opv2v, "PROGRESS_DELAY", 0.0)
    loaders.open(copy_fixture(DAIR))
    loaders.open(release)
    err = capsys.readouterr().err
    assert "DAIR-V2X pairs" in err and "OPV2V OPV2V" in err


def test_dair_nothing_loadable_is_refused(copy_fixture):
    root = copy_fixture(DAIR)
    _write_pairs(root, [PAIR])
    with pytest.raises(loaders.LoaderError, match=r"no pair could be loaded; 1 lack .*000011\.json: missing"):
        loaders.open(root)


def test_dair_numbers_stored_as_strings_are_numbers(copy_fixture, fixtures):
    root = copy_fixture(DAIR)
    pairs = json.loads(_info(root).read_text())
    pairs[0]["system_error_offset"] = {"delta_x": "-0.5", "delta_y": "0.0"}
    _write_pairs(root, pairs)
    label = root / "infrastructure-side" / "label" / "virtuallidar" / "000020.json"
    boxes = json.loads(label.read_text())
    boxes[0]["3d_location"] = {"x": "10.0", "y": "10", "z": "1.0"}
    boxes[0]["rotation"] = "-1.5707963267948966"
    label.write_text(json.dumps(boxes))
    calib = root / "vehicle-side" / "calib" / "lidar_to_novatel" / "000010.json"
    calib.write_text(json.dumps({"transform": {"rotation": [["1", 0, 0], [0, "1", 0], [0, 0, 1]],
                                               "translation": [["1.0"], [0.0], [0.0]]}}))
    expected = loaders.open(fixtures / DAIR)[0]
    frame = loaders.open(root)[0]
    np.testing.assert_allclose(frame.boxes(), expected.boxes())
    np.testing.assert_allclose(frame.agent_pose("infrastructure"), expected.agent_pose("infrastructure"))


def test_dair_text_that_is_no_number_names_file_and_field(copy_fixture):
    root = copy_fixture(DAIR)
    pairs = json.loads(_info(root).read_text())
    pairs[0]["system_error_offset"]["delta_x"] = "half a metre"
    _write_pairs(root, pairs)
    with pytest.raises(loaders.LoaderError, match=r"data_info\.json: \[0\]\.system_error_offset\.delta_x: "
                                                  r"expected a number, got 'half a metre'"):
        loaders.open(root)


def _scenario(target, source, predicted="keep"):
    """A copy of ``source`` whose CAV 650 reports ``predicted`` as its predicted_ego_pos (None: no key)."""
    shutil.copytree(source, target)
    if predicted != "keep":
        cav = target / "650" / "000068.yaml"
        lines = [line for line in cav.read_text().splitlines() if not line.startswith("predicted_ego_pos")]
        cav.write_text("\n".join(lines + ([f"predicted_ego_pos: {predicted}"] if predicted else [])) + "\n")


@pytest.fixture
def release(tmp_path, fixtures):
    """An OPV2V release root: train/{b, a}, test/c (each a copy of the hand-made scenario)."""
    root = tmp_path / "OPV2V"
    source = fixtures / "opv2v" / "scenario"
    _scenario(root / "train" / "2021_b", source)
    _scenario(root / "train" / "2021_a", source, predicted="[31, -18, 1.9, 0, 175, 0]")
    _scenario(root / "test" / "2021_c", source)
    (root / "train" / "notes").mkdir()
    return root


def test_opv2v_release_root_is_one_sequence_in_split_then_name_order(release):
    seq = loaders.open(release)
    assert seq.scenarios == {"train/2021_a": 0, "train/2021_b": 2, "test/2021_c": 4}
    assert seq.frame_ids[:3] == ["train/2021_a/000068", "train/2021_a/000070", "train/2021_b/000068"]
    assert [frame.scenario for frame in seq] == ["train/2021_a"] * 2 + ["train/2021_b"] * 2 + ["test/2021_c"] * 2
    np.testing.assert_allclose(seq.timestamps, np.arange(6) / 10)
    assert [frame.ego for frame in seq] == ["641"] * 6
    assert seq[3].agents["agent_id"].to_list() == ["641", "-1"]


def test_opv2v_split_folder_and_scenario_folder(release):
    split = loaders.open(release / "train")
    assert split.scenarios == {"2021_a": 0, "2021_b": 2} and split.frame_ids[2] == "2021_b/000068"
    one = loaders.open(release / "test" / "2021_c")
    assert one.frame_ids == ["000068", "000070"] and one[1].scenario == "2021_c"


def test_opv2v_predicted_ego_pos_is_the_dataset_localization(release):
    seq = loaders.open(release)
    frame = seq[0]
    # CARLA (31, -18, yaw 175 deg) -> right-handed (31, 18, -175 deg); the true pose is (30, -20, 180 deg)
    np.testing.assert_allclose(frame.predicted_pose("650"), _se2(31.0, 18.0, -math.radians(175)), atol=1e-12)
    trial = build_trial(frame, ScenarioParams(protocol="opv2v", localization="dataset"), seed=0, cav="650")
    expected = np.linalg.inv(frame.agent_pose("641")) @ frame.predicted_pose("650")
    np.testing.assert_allclose(trial.init, expected, atol=1e-12)
    fixed = build_trial(frame, ScenarioParams(protocol="opv2v"), seed=0, cav="650")
    assert not np.allclose(fixed.init, trial.init)


def test_dataset_localization_without_a_predicted_pose_says_so(tmp_path, fixtures):
    _scenario(tmp_path / "s", fixtures / "opv2v" / "scenario", predicted=None)
    frame = loaders.open(tmp_path / "s")[0]
    assert frame.predicted_pose("650") is None
    with pytest.raises(ValueError, match="noisy pose the dataset reports for the CAV"):
        build_trial(frame, ScenarioParams(protocol="opv2v", localization="dataset"), seed=0, cav="650")


def test_opv2v_folder_without_scenarios_is_refused(tmp_path):
    (tmp_path / "train" / "empty").mkdir(parents=True)
    with pytest.raises(loaders.LoaderError, match="nothing recognisable"):
        loaders.open(tmp_path)


def _se2(x, y, yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, x], [s, c, y], [0, 0, 1.0]])
