"""The CAV choice rule of evaluation.agents: deterministic, order-free, shared by the app and evaluate.py."""
import numpy as np
import polars as pl
import pytest

import loaders
from cbm import se2
from evaluation.agents import agent_pose, choose_cav, choose_ego, frame_trial_inputs
from evaluation.scenario import ScenarioParams, make_trial
from loaders.scene import Sequence

OBJECT_SCHEMA = {"frame": pl.Int64, "track_id": pl.Utf8, "category": pl.Utf8,
                 **{c: pl.Float64 for c in loaders.BOX_COLUMNS}}


def objects(rows):
    """Rows of (track_id, category, x, y, yaw) in frame 0."""
    return pl.DataFrame([(0, t, c, x, y, 0.8, 4.5, 1.9, 1.6, yaw) for t, c, x, y, yaw in rows],
                        schema=OBJECT_SCHEMA, orient="row")


def agents(rows):
    """Rows of (agent_id, x, y, yaw) in frame 0."""
    return pl.DataFrame({"frame": [0] * len(rows), "agent_id": [r[0] for r in rows], "x": [r[1] for r in rows],
                         "y": [r[2] for r in rows], "z": [0.0] * len(rows), "yaw": [r[3] for r in rows],
                         "length": [4.9] * len(rows), "width": [2.0] * len(rows), "height": [1.6] * len(rows)})


def frame_of(object_rows, agent_rows=None, ego=None, visibility=None):
    seq = Sequence("toy", objects(object_rows), [0], [0.0], agents=None if agent_rows is None else agents(agent_rows),
                   visibility=visibility, ego=ego)
    return seq[0]


STREET = [("near", "car", 10.0, 0.0, 0.0), ("target", "REGULAR_VEHICLE", 0.0, 24.0, 1.0),
          ("far", "bus", -60.0, 0.0, 0.0), ("walker", "PEDESTRIAN", 25.0, 0.0, 0.0)]


def test_the_cav_is_the_vehicle_whose_distance_from_the_ego_is_nearest_the_target():
    frame = frame_of(STREET, [("ego", 0.0, 0.0, 0.0)], ego="ego")
    assert choose_ego(frame) == "ego"
    assert choose_cav(frame, "ego") == "target"
    assert choose_cav(frame, "ego", target_distance=8.0) == "near"
    assert choose_cav(frame, "ego", target_distance=100.0) == "far"


def test_pedestrians_and_the_ego_itself_are_never_the_cav():
    frame = frame_of([("walker", "PEDESTRIAN", 25.0, 0.0, 0.0), ("me", "car", 0.0, 0.0, 0.0)])
    assert choose_ego(frame) == "me"
    assert choose_cav(frame, "me") is None


def test_ties_go_to_the_smallest_id_whatever_the_row_order():
    rows = [("b", "car", 25.0, 0.0, 0.0), ("a", "car", -25.0, 0.0, 0.0), ("c", "car", 0.0, 25.0, 0.0)]
    for order in (rows, rows[::-1], rows[1:] + rows[:1]):
        assert choose_cav(frame_of(order, [("ego", 0.0, 0.0, 0.0)], ego="ego"), "ego") == "a"


def test_without_a_dataset_ego_the_vehicle_nearest_the_centroid_is_the_ego():
    rows = [("west", "car", -20.0, 0.0, 0.0), ("mid", "truck", 1.0, 1.0, 0.0), ("east", "car", 20.0, 0.0, 0.0),
            ("walker", "PEDESTRIAN", 0.0, 0.0, 0.0)]
    frame = frame_of(rows)
    assert choose_ego(frame) == "mid"
    assert choose_cav(frame, "mid", target_distance=19.0) == "east"


def test_other_agents_are_preferred_to_vehicles_and_carry_their_visibility():
    seen = pl.DataFrame({"frame": [0, 0, 0], "agent_id": ["ego", "ego", "cav7"], "track_id": ["near", "far", "far"]})
    frame = frame_of(STREET, [("ego", 0.0, 0.0, 0.0), ("cav7", 80.0, 0.0, 0.5)], ego="ego", visibility=seen)
    assert choose_cav(frame, "ego") == "cav7"
    inputs = frame_trial_inputs(frame, "ego", "cav7")
    assert inputs["visibility"]["ego"].tolist() == ["near", "far"]
    assert inputs["visibility"]["cav"].tolist() == ["far"]
    np.testing.assert_allclose(inputs["cav_pose"], se2.make(80.0, 0.0, 0.5))


def test_frame_trial_inputs_make_a_range_trial_with_the_cav_pose_from_its_box():
    frame = frame_of(STREET, [("ego", 0.0, 0.0, 0.0)], ego="ego")
    inputs = frame_trial_inputs(frame, "ego", "target")
    assert set(inputs) == {"boxes", "ids", "ego_pose", "cav_pose", "cav_id", "ego_id", "visibility"}
    assert inputs["visibility"] is None
    np.testing.assert_allclose(inputs["cav_pose"], se2.make(0.0, 24.0, 1.0))
    trial = make_trial(**inputs, params=ScenarioParams(protocol="range", sensor_range=30.0))
    assert "target" not in trial.cav_ids and "target" in trial.ego_ids
    with pytest.raises(KeyError, match="nobody"):
        agent_pose(frame, "nobody")


def test_on_the_shipped_scene_every_frame_has_a_cav_about_25_m_from_the_ego():
    seq = loaders.open("argoverse2")
    for k in (0, 77, 155):
        frame = seq[k]
        cav = choose_cav(frame, choose_ego(frame))
        row = np.flatnonzero(frame.track_ids == cav)[0]
        assert loaders.is_vehicle(frame.categories[row : row + 1])[0]
        distance = np.linalg.norm(frame.boxes()[row, :2] - se2.translation_of(frame.agent_pose("ego")))
        assert 15.0 < distance < 35.0
