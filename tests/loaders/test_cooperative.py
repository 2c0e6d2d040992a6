"""OPV2V / V2XSet / V2V4Real and DAIR-V2X: conversions worked out by hand."""
import math

import numpy as np
import pytest

import loaders


def _box(frame, track):
    return frame.boxes()[list(frame.track_ids).index(track)]


def test_opv2v_left_handed_box_from_the_tutorial(fixtures):
    seq = loaders.open(fixtures / "opv2v" / "000069.yaml")
    frame = seq[0]
    # location (158.55, -385.75, 0.032) + center (0.0004, 0.0005, 0.71) in CARLA's left-handed
    # world -> (158.5504, +385.7495, 0.742); yaw -(-177.86 deg); extent (2.45, 1.06, 0.75) halves
    np.testing.assert_allclose(_box(frame, "4796"),
                               [158.5504, 385.7495, 0.742, 4.9, 2.12, 1.5, math.radians(177.86)], atol=1e-9)
    ego = frame.agents.row(0, named=True)
    np.testing.assert_allclose([ego["x"], ego["y"], ego["yaw"]], [144.33, 388.94, -math.radians(174.18)])


def test_opv2v_scenario_ego_visibility_and_rsu(fixtures):
    seq = loaders.open(fixtures / "opv2v" / "scenario")
    assert seq.ego == "641"                                     # "-1" sorts first but never leads
    assert seq.frame_ids == ["000068", "000070"]
    np.testing.assert_allclose(seq.timestamps, [0.0, 0.1])
    first = seq[0]
    assert first.agents["agent_id"].to_list() == ["641", "650", "-1"]
    vis = {k: sorted(v) for k, v in first.visibility.items()}
    assert vis == {"641": ["700"], "650": ["641", "700"], "-1": ["700"]}
    # vehicle 700 from the ego's file: (15, 22) + (0.5, -1) -> (15.5, 21) -> right-handed (15.5, -21)
    np.testing.assert_allclose(_box(first, "700"), [15.5, -21.0, 0.8, 4.5, 2.0, 1.5, -math.radians(30)])
    np.testing.assert_allclose(_box(first, "641")[[0, 1, 6]], [10.0, -20.0, -math.pi / 2])
    np.testing.assert_allclose(first.agent_pose("650"), [[-1, 0, 30], [0, -1, -20], [0, 0, 1]], atol=1e-12)
    rsu = first.agents.filter(first.agents["agent_id"] == "-1").row(0, named=True)
    assert (rsu["length"], rsu["height"]) == (0.6, 5.0)
    second = seq[1]
    assert second.agents["agent_id"].to_list() == ["641", "-1"]   # 650 has no file at 000070
    assert second.visibility["-1"].size == 0                  # present, sees nothing
    np.testing.assert_allclose(_box(second, "700")[:2], [15.5, -22.0])


def test_v2v4real_per_cav_frames_and_ass_id(fixtures):
    seq = loaders.open(fixtures / "v2v4real" / "scenario")
    assert seq.name == "v2v4real/scenario" and seq.ego == "0"
    frame = seq[0]
    assert sorted(frame.track_ids) == ["0/4", "1/2", "a7"]
    # CAV 0 at (100, 50) facing +y sees object 3 at (10, 0) in its LiDAR frame -> (100, 60);
    # CAV 1 at (100, 70) facing -y sees object 9 at (10, 0) -> (100, 60): both carry ass_id 7
    np.testing.assert_allclose(_box(frame, "a7"), [100.0, 60.0, 2.8, 4.0, 2.0, 1.6, math.pi / 2], atol=1e-9)
    np.testing.assert_allclose(_box(frame, "0/4")[:2], [95.0, 55.0], atol=1e-9)
    np.testing.assert_allclose(_box(frame, "1/2")[:2], [100.0, 67.0], atol=1e-9)
    assert frame.categories[list(frame.track_ids).index("0/4")] == "truck"  # V2V4Real obj_type Truck, in our names
    assert {k: sorted(v) for k, v in frame.visibility.items()} == {"0": ["0/4", "a7"], "1": ["1/2", "a7"]}


def test_dair_v2x_calibration_offset_and_association(fixtures):
    seq = loaders.open(fixtures / "dair_v2x" / "cooperative-vehicle-infrastructure")
    assert seq.ego == "vehicle" and seq.frame_ids == ["000010"]
    frame = seq[0]
    # vehicle LiDAR (10, 0, 1) -> novatel (11, 0, 1) -> world: rotate 90 deg, + (100, 200)
    np.testing.assert_allclose(_box(frame, "v0"), [100.0, 211.0, 1.0, 4.5, 1.8, 1.5, math.pi / 2], atol=1e-9)
    # infrastructure (10, 10) -> rotate 180 deg, + (110.5 - 0.5 offset, 221): the same car
    assert {k: sorted(v) for k, v in frame.visibility.items()} == {"infrastructure": ["i1", "v0"], "vehicle": ["v0"]}
    np.testing.assert_allclose(_box(frame, "i1")[:3], [110.0, 221.0, 1.0], atol=1e-9)
    np.testing.assert_allclose(frame.agent_pose("vehicle"), [[0, -1, 100], [1, 0, 201], [0, 0, 1]], atol=1e-12)
    np.testing.assert_allclose(frame.agent_pose("infrastructure"), [[-1, 0, 110], [0, -1, 221], [0, 0, 1]], atol=1e-12)


def test_dair_v2x_missing_calibration_names_the_file(copy_fixture):
    root = copy_fixture("dair_v2x/cooperative-vehicle-infrastructure")
    (root / "vehicle-side" / "calib" / "novatel_to_world" / "000010.json").unlink()
    with pytest.raises(loaders.LoaderError, match="novatel_to_world.000010.json: missing"):
        loaders.open(root)


def test_opv2v_missing_key_names_it(copy_fixture):
    scenario = copy_fixture("opv2v/scenario")
    path = scenario / "650" / "000068.yaml"
    path.write_text(path.read_text().replace("extent: [2.4, 1.0, 0.8]", "size: [2.4, 1.0, 0.8]"))
    with pytest.raises(loaders.LoaderError, match=r"650.000068.yaml: missing key vehicles\[641\]\.extent"):
        loaders.open(scenario)


@pytest.mark.parametrize("old, new, message", [
    ("location: [15, 22, 0]", "location: [.nan, 22, 0]", r"vehicles\[700\]\.location\[0\]: expected a finite number"),
    ("location: [15, 22, 0]", "location: [fifteen, 22, 0]", r"vehicles\[700\]\.location\[0\]: expected a number"),
    ("lidar_pose: [10, 20, 1.9, 0, 90, 0]", "lidar_pose: [10, 20]", "lidar_pose: expected a list of 6 numbers"),
    ("vehicles:", "vehicles: [", "not valid YAML"),
])
def test_opv2v_bad_values(copy_fixture, old, new, message):
    scenario = copy_fixture("opv2v/scenario")
    path = scenario / "641" / "000068.yaml"
    path.write_text(path.read_text().replace(old, new, 1))
    with pytest.raises(loaders.LoaderError, match=message):
        loaders.open(scenario)


def test_empty_yaml_is_refused(copy_fixture):
    scenario = copy_fixture("opv2v/scenario")
    (scenario / "641" / "000068.yaml").write_text("")
    with pytest.raises(loaders.LoaderError, match="000068.yaml: the file is empty"):
        loaders.open(scenario)


def test_dair_v2x_bad_label_value(copy_fixture):
    root = copy_fixture("dair_v2x/cooperative-vehicle-infrastructure")
    label = root / "vehicle-side" / "label" / "lidar" / "000010.json"
    label.write_text(label.read_text().replace('"x": 10.0', '"x": "ten"'))
    with pytest.raises(loaders.LoaderError, match=r"000010.json: \[0\]\.3d_location\.x: expected a number"):
        loaders.open(root)
