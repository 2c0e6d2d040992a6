"""Line of sight on hand-made scenes: a car straight behind a truck is hidden from the agent behind
the truck and seen by one on the other side; a car beside the truck is seen by both."""
import numpy as np
import pytest

from cbm import se2
from evaluation.scenario import ScenarioParams, make_trial
from evaluation.sight import line_of_sight, sight_outline, visible_share

TRUCK = (12.0, 2.6, 3.5)
CAR = (4.5, 1.9, 1.6)


def box(x, y, size, yaw=0.0):
    return [x, y, 0.0, *size, yaw]


def scene():
    """Agent A at x = 0 looking along +x, a truck at x = 15, a car straight behind it at x = 30, a car
    beside the truck at (15, 8); agent B at (45, 10), past the far end. Rows: truck, hidden car, side car."""
    return np.array([box(15.0, 0.0, TRUCK), box(30.0, 0.0, CAR), box(15.0, 8.0, CAR)])


def test_a_car_straight_behind_a_truck_is_hidden_from_one_agent_and_seen_by_the_other():
    boxes = scene()
    a, b = se2.make(0.0, 0.0, 0.0), se2.make(45.0, 10.0, np.pi)
    assert line_of_sight(boxes, a, 60.0).tolist() == [True, False, True]
    assert line_of_sight(boxes, b, 60.0).tolist() == [True, True, True]


def test_the_share_grows_as_the_car_steps_out_from_behind_the_truck():
    shares = [visible_share(np.array([box(15.0, 0.0, TRUCK), box(30.0, y, CAR)]), np.zeros(2), 60.0)[1]
              for y in (0.0, 1.5, 3.0, 6.0)]
    assert shares[0] == 0.0 and shares[-1] == 1.0
    assert all(a <= b for a, b in zip(shares, shares[1:])), shares


def test_range_and_the_agents_own_box():
    boxes = np.array([box(0.0, 0.0, CAR), box(70.0, 0.0, CAR), box(5.0, 0.0, CAR)])
    seen = line_of_sight(boxes, se2.make(0.0, 0.0, 0.0), 60.0)
    assert seen.tolist() == [True, False, True], "the own car hides nothing and is 'seen'; 70 m is out of range"


def test_the_sight_outline_stops_at_the_first_box_and_at_the_range():
    outline = sight_outline(scene(), np.zeros(2), 60.0, rays=8)
    reach = np.linalg.norm(outline, axis=1)
    ahead, behind = reach[4], reach[0]
    assert ahead == pytest.approx(15.0 - TRUCK[0] / 2), "the ray along +x stops at the truck's near side"
    assert behind == pytest.approx(60.0), "nothing behind the agent: the range"


def test_a_trial_under_line_of_sight_pairs_only_what_both_see():
    boxes = scene()
    ids = np.array(["truck", "hidden", "side"])
    ego, cav = se2.make(0.0, 0.0, 0.0), se2.make(45.0, 10.0, np.pi)
    params = ScenarioParams(protocol="range", sensor_range=60.0, sight=True, localization="fixed", flip_prob=0.0)
    trial = make_trial(boxes, ids, params, ego_pose=ego, cav_pose=cav)
    assert trial.ego_ids.tolist() == ["truck", "side"] and trial.cav_ids.tolist() == ["truck", "hidden", "side"]
    assert [(trial.ego_ids[i], trial.cav_ids[j]) for i, j in trial.gt_pairs] == [("truck", "truck"), ("side", "side")]
    plain = make_trial(boxes, ids, ScenarioParams(protocol="range", sensor_range=60.0, flip_prob=0.0),
                       ego_pose=ego, cav_pose=cav)
    assert len(plain.gt_pairs) == 3


def test_on_the_shipped_log_the_recording_car_sees_what_its_lidar_saw_and_the_cav_its_line_of_sight():
    import loaders
    from evaluation.conditions import condition
    from evaluation.trials import frame_inputs

    frame = loaders.open("argoverse2")[120]
    inputs = frame_inputs(frame, "range")
    occluded = condition("occluded")
    trial = inputs.build(occluded, seed=0)
    open_sky = inputs.build(ScenarioParams(**{**occluded.__dict__, "sight": False}), seed=0)
    lidar = set(frame.visibility["ego"].tolist())
    assert set(trial.ego_ids.tolist()) <= lidar and set(trial.ego_ids.tolist()) < set(open_sky.ego_ids.tolist())
    assert set(trial.cav_ids.tolist()) < set(open_sky.cav_ids.tolist()), "some objects hide behind others"
