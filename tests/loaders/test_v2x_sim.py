"""V2X-Sim 2.0 (nuScenes-style tables, one LIDAR_TOP_id_<k> per agent): conversions by hand."""
import json
import math

import numpy as np
import pytest

import loaders

ROOT = "v2x_sim/V2X-Sim-2.0-mini"


def _box(frame, track):
    return frame.boxes()[list(frame.track_ids).index(track)]


def test_scene_samples_agents_and_boxes(fixtures):
    seq = loaders.open(fixtures / ROOT)
    assert seq.name == "v2x_sim/V2X-Sim-2.0-mini" and seq.ego == "1"
    assert seq.frame_ids == ["scene_5/0", "scene_5/1"]
    np.testing.assert_allclose(seq.timestamps, [0.0, 0.2])          # microseconds -> seconds from the first
    first, second = seq
    assert first.agents["agent_id"].to_list() == ["0", "1", "2"]     # the camera channel is no agent
    assert second.agents["agent_id"].to_list() == ["0", "1"]         # agent 2 has no key frame in sample 2
    # agent 1: ego pose (100, 50) facing +y (quaternion [cos 45, 0, 0, sin 45]) + LiDAR 0.5 m ahead -> (100, 50.5)
    np.testing.assert_allclose(first.agent_pose("1"), [[0, -1, 100], [1, 0, 50.5], [0, 0, 1]], atol=1e-12)
    # agent 2 faces -x (quaternion [0, 0, 0, 1]): its LiDAR 0.5 m ahead is at x = 119.5
    np.testing.assert_allclose(first.agent_pose("2")[:2, 2], [119.5, 50.0])
    rsu = first.agents.row(0, named=True)
    assert (rsu["z"], rsu["length"], rsu["height"]) == (5.0, 0.6, 5.0)
    # size is [width, length, height] in nuScenes order
    np.testing.assert_allclose(_box(first, "i1"), [105.0, 52.0, 0.8, 4.5, 1.8, 1.6, math.pi / 2], atol=1e-12)
    assert list(first.categories) == ["car", "human.pedestrian.adult"]
    assert first.visibility is None
    np.testing.assert_allclose(_box(second, "i1")[:2], [105.0, 54.0])


def test_table_folder_opens_too_and_trial_uses_sensor_range(fixtures):
    from evaluation.scenario import ScenarioParams
    from evaluation.trials import frame_inputs

    seq = loaders.open(fixtures / ROOT / "v2.0-mini")
    inputs = frame_inputs(seq[0], "opv2v", cav="2")
    assert inputs.trial["ego_id"] == "1" and inputs.trial["cav_id"] == "2"
    assert "sensor range used" in inputs.note
    assert len(inputs.build(ScenarioParams(protocol="opv2v"), seed=0).gt_pairs) == 2


def test_missing_field_names_file_and_record(copy_fixture):
    root = copy_fixture(ROOT)
    path = root / "v2.0-mini" / "sample_annotation.json"
    rows = json.loads(path.read_text())
    del rows[1]["size"]
    path.write_text(json.dumps(rows))
    with pytest.raises(loaders.LoaderError, match=r"sample_annotation.json: missing key sample_annotation a2.size"):
        loaders.open(root)


def test_broken_sample_link_names_the_token(copy_fixture):
    root = copy_fixture(ROOT)
    path = root / "v2.0-mini" / "sample.json"
    rows = json.loads(path.read_text())
    rows[0]["next"] = "nowhere"
    path.write_text(json.dumps(rows))
    with pytest.raises(loaders.LoaderError, match=r"sample.json: sample 'nowhere'.*no such sample"):
        loaders.open(root)
