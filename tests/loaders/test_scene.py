import numpy as np
import polars as pl
import pytest

import loaders
from loaders.scene import MapGeometry, Sequence


def _objects(rows):
    return pl.DataFrame(rows, schema={"frame": pl.Int64, "track_id": pl.Utf8, "category": pl.Utf8,
                                      **{c: pl.Float64 for c in loaders.BOX_COLUMNS}}, orient="row")


@pytest.fixture
def sequence():
    objects = _objects([
        (1, "b", "car", 5.0, 0.0, 0.8, 4.0, 2.0, 1.6, 0.5),
        (0, "a", "PEDESTRIAN", 1.0, 2.0, 0.9, 0.6, 0.6, 1.8, 0.0),
        (1, "a", "PEDESTRIAN", 1.5, 2.0, 0.9, 0.6, 0.6, 1.8, 0.1),
        (0, "c", "BUS", -3.0, 1.0, 1.5, 12.0, 2.5, 3.0, np.pi),
    ])
    agents = pl.DataFrame({"frame": [0, 1], "agent_id": ["ego", "ego"], "x": [1.0, 2.0], "y": [0.0, 0.0],
                           "z": [0.0, 0.0], "yaw": [0.0, np.pi / 2], "length": [4.9] * 2,
                           "width": [2.0] * 2, "height": [1.6] * 2})
    seen = pl.DataFrame({"frame": [1, 0, 1, 0], "agent_id": ["x", "ego", "ego", "ego"],
                         "track_id": ["a", "a", "b", "c"]})
    polylines = [("lane_boundary", np.array([[0.0, 0.0], [1.0, 0.0]]))]
    return Sequence("toy", objects, ["f0", "f1", "f2"], [0.0, 0.1, 0.2], agents=agents,
                    visibility=seen, map=MapGeometry(polylines))


def test_frames_group_rows_in_input_order(sequence):
    assert len(sequence) == 3
    first, second, empty = sequence[0], sequence[1], sequence[2]
    assert list(first.track_ids) == ["a", "c"]
    assert list(second.track_ids) == ["b", "a"]
    assert len(empty) == 0 and empty.boxes().shape == (0, 7)
    assert first.boxes()[1].tolist() == [-3.0, 1.0, 1.5, 12.0, 2.5, 3.0, np.pi]
    assert first.objects.columns == list(loaders.OBJECT_COLUMNS)
    assert list(second.categories) == ["car", "PEDESTRIAN"]
    assert (second.frame_id, second.timestamp, second.index) == ("f1", 0.1, 1)
    assert sequence[-1].index == 2
    with pytest.raises(IndexError):
        sequence[3]


def test_boxes_are_a_copy(sequence):
    boxes = sequence[0].boxes()
    boxes[:] = 0
    assert sequence[0].boxes()[0, 0] == 1.0


def test_visibility_agents_and_poses(sequence):
    assert {k: list(v) for k, v in sequence[1].visibility.items()} == {"ego": ["b"], "x": ["a"]}
    assert sequence[2].visibility == {}
    pose = sequence[1].agent_pose("ego")
    np.testing.assert_allclose(pose, [[0, -1, 2], [1, 0, 0], [0, 0, 1]], atol=1e-12)
    with pytest.raises(KeyError, match="no agent 'x'"):
        sequence[1].agent_pose("x")
    assert sequence[0].agents["agent_id"].to_list() == ["ego"]


def test_map_geometry(sequence):
    assert sequence.map.kinds() == ["lane_boundary"]
    low, high = sequence.map.bounds()
    assert low.tolist() == [0.0, 0.0] and high.tolist() == [1.0, 0.0]
    assert MapGeometry().bounds() is None


def test_is_vehicle():
    names = ["REGULAR_VEHICLE", "PEDESTRIAN", "BOX_TRUCK", "car", "Van", "bicycle", "VEHICULAR_TRAILER", "bus"]
    assert loaders.is_vehicle(names).tolist() == [True, False, True, True, True, False, False, True]
    assert loaders.is_vehicle(np.array([], dtype=str)).shape == (0,)
