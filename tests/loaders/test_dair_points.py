"""DAIR-V2X-C LiDAR points (the .pcd files data_info.json names), through Frame.points."""
import numpy as np

import loaders
from cbm import se2

DAIR = "dair_v2x/cooperative-vehicle-infrastructure"


def placed_like_the_app(frame: loaders.Frame, agent: str) -> np.ndarray:
    """The agent's points in the world frame as the app places them: its SE(2) pose, raised by its z."""
    points = frame.points(agent)
    height = float(frame.agents.filter(frame.agents["agent_id"] == agent)["z"][0])
    return np.column_stack([se2.apply_points(frame.agent_pose(agent), points[:, :2]), points[:, 2] + height])


def inside(points: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Which world-frame points lie inside a box ``(x, y, z, length, width, height, yaw)``."""
    x, y, z, length, width, height, yaw = box
    local = se2.apply_points(se2.inverse(se2.make(x, y, yaw)), points[:, :2])
    return ((np.abs(local[:, 0]) <= length / 2) & (np.abs(local[:, 1]) <= width / 2)
            & (np.abs(points[:, 2] - z) <= height / 2))


def test_binary_sweeps_of_both_agents_in_their_lidar_frames(fixtures):
    frame = loaders.open(fixtures / DAIR)[0]
    vehicle, infrastructure = frame.points("vehicle"), frame.points("infrastructure")
    assert vehicle.shape == (12, 3) and infrastructure.shape == (20, 3) and vehicle.dtype == np.float32
    np.testing.assert_allclose(vehicle[0], [7.95, -0.7, 0.45], atol=1e-5)   # a corner of the Car, lidar frame
    np.testing.assert_allclose(infrastructure[8], [-0.2, -0.2, 0.3], atol=1e-5)  # the Pedestrian's


def test_points_of_each_object_lie_inside_its_box(fixtures):
    frame = loaders.open(fixtures / DAIR)[0]
    boxes = dict(zip(frame.track_ids, frame.boxes()))
    vehicle, infrastructure = placed_like_the_app(frame, "vehicle"), placed_like_the_app(frame, "infrastructure")
    assert inside(vehicle[:8], boxes["v0"]).all() and inside(infrastructure[:8], boxes["v0"]).all()
    assert inside(infrastructure[8:16], boxes["i1"]).all()
    ground = np.concatenate([vehicle[8:], infrastructure[16:]])
    assert not any(inside(ground, box).any() for box in boxes.values())


def test_a_missing_point_cloud_gives_none(copy_fixture):
    root = copy_fixture(DAIR)
    (root / "infrastructure-side" / "velodyne" / "000020.pcd").unlink()
    frame = loaders.open(root)[0]
    assert frame.points("infrastructure") is None and frame.points("vehicle").shape == (12, 3)
    assert len(frame.boxes()) == 2 and not loaders.open(root).warnings
