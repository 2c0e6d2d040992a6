import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

import loaders
from loaders import synthetic
from loaders.errors import LoaderError


def _footprints(boxes):
    c, s = np.cos(boxes[:, 6]), np.sin(boxes[:, 6])
    half_l, half_w = boxes[:, 3] / 2, boxes[:, 4] / 2
    corners = [np.stack([boxes[:, 0] + a * half_l * c - b * half_w * s,
                         boxes[:, 1] + a * half_l * s + b * half_w * c], axis=1)
               for a, b in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    return shapely.polygons(np.stack(corners, axis=1))


def _overlapping_pairs(boxes):
    polygons = _footprints(boxes)
    first, second = shapely.STRtree(polygons).query(polygons, predicate="intersects")
    return int((first < second).sum())


@settings(max_examples=12, deadline=None)
@given(n=st.integers(0, 1000), seed=st.integers(0, 2**32 - 1))
def test_any_count_without_overlap_in_any_frame(n, seed):
    seq = synthetic.generate(n_objects=n, n_frames=30, seed=seed)
    assert len(seq) == 30
    for k in (0, 15, 29):
        frame = seq[k]
        assert len(frame) == n
        assert np.isfinite(frame.boxes()).all()
        assert _overlapping_pairs(frame.boxes()) == 0


@pytest.mark.parametrize("n", [0, 1, 1000, synthetic.MAX_OBJECTS])
def test_edge_counts(n):
    seq = synthetic.generate(n_objects=n, n_frames=2, seed=3)
    assert [len(f) for f in seq] == [n, n]
    assert _overlapping_pairs(seq[1].boxes()) == 0


def test_same_seed_same_scene_other_seed_other_scene():
    a, b = synthetic.generate(150, n_frames=3, seed=7), synthetic.generate(150, n_frames=3, seed=7)
    np.testing.assert_array_equal(a[2].boxes(), b[2].boxes())
    assert not np.array_equal(a[0].boxes(), synthetic.generate(150, n_frames=3, seed=8)[0].boxes())


def test_traffic_looks_like_traffic():
    seq = synthetic.generate(400, n_frames=40, seed=1)
    first, last = seq[0], seq[39]
    categories = first.categories
    assert {"car", "truck", "bus", "pedestrian"} <= set(categories)
    assert 0.08 < np.mean(categories == "pedestrian") < 0.16
    moved = np.linalg.norm(last.boxes()[:, :2] - first.boxes()[:, :2], axis=1)
    vehicles = loaders.is_vehicle(categories)
    assert 0.3 < np.mean(moved[vehicles] > 1.0) < 0.9          # queued and parked cars stand still
    speeds = moved[vehicles & (moved > 1.0)] / (seq.timestamps[39] - seq.timestamps[0])
    assert speeds.min() > 5.0 and speeds.max() < 13.0
    walkers = moved[categories == "pedestrian"] / 3.9
    assert walkers.max() < 1.7
    turning = [np.abs(np.sin(2 * seq[k].boxes()[:, 6])) > 1e-6 for k in range(40)]
    assert sum(t.sum() for t in turning) > 0                  # someone turns during the clip


def test_queued_cars_keep_realistic_headway():
    seq = synthetic.generate(300, n_frames=1, seed=4)
    boxes, categories = seq[0].boxes(), seq[0].categories
    cars = boxes[categories == "car"]
    gaps = []
    for x in np.unique(np.round(cars[:, 0], 0)):
        lane = cars[(np.abs(cars[:, 0] - x) < 0.3) & (np.abs(np.sin(cars[:, 6])) > 0.99)]
        if len(lane) > 2:
            gaps.extend(np.diff(np.sort(lane[:, 1])))
    gaps = np.array(gaps)
    assert len(gaps) > 10 and (gaps > 5.5).all()
    assert 6.0 < np.median(gaps) < 10.0


def test_map_and_names():
    seq = loaders.open("synthetic:50:seed=5")
    assert seq.name == "synthetic:50:seed=5" and len(seq[0]) == 50
    assert set(seq.map.kinds()) == {"lane_boundary", "crossing", "drivable_area"}
    assert len(loaders.open("synthetic")[0]) == 200
    assert len(loaders.open("synthetic:0")[0]) == 0


@pytest.mark.parametrize("name", ["synthetic:2001", "synthetic:-3", "synthetic:ten", "synthetic:5:seed=x"])
def test_bad_synthetic_names(name):
    with pytest.raises(loaders.LoaderError, match="synthetic"):
        loaders.open(name)


def test_bad_arguments():
    with pytest.raises(loaders.LoaderError, match="n_objects"):
        synthetic.generate(n_objects=2001)
    with pytest.raises(loaders.LoaderError, match="n_frames"):
        synthetic.generate(n_objects=5, n_frames=0)


@pytest.mark.parametrize("seed", [-1, 1.5, True])
def test_a_seed_that_is_not_a_non_negative_integer_is_named(seed):
    with pytest.raises(LoaderError, match=f"synthetic: seed must be a non-negative integer, got {seed!r}"):
        synthetic.generate(5, n_frames=2, seed=seed)
