"""Late messages against the shipped log's own frames: a delay of exactly two frame periods gives
the CAV's frame k-2, bit for bit; a delay between frames lies between them; the jitter is drawn
from the seed, and a message is never older than the sequence."""
import numpy as np
import pytest

import loaders
from cbm import se2
from evaluation.delay import between, pose_between
from evaluation.scenario import ScenarioParams
from evaluation.trials import frame_inputs

EXACT = dict(protocol="range", sensor_range=60.0, sigma_p=0.0, sigma_theta=0.0, flip_prob=0.0, localization="fixed",
             loc_x=0.0, loc_y=0.0, loc_yaw=0.0)


@pytest.fixture(scope="module")
def log():
    return loaders.open("argoverse2")


def test_a_delay_of_two_frame_periods_gives_the_cavs_frame_k_minus_2(log):
    k = 60
    late = frame_inputs(log[k], "range", window_s=0.5)
    delay_ms = 1000.0 * (log.timestamps[k] - log.timestamps[k - 2])
    trial = late.build(ScenarioParams(**EXACT, delay_ms=delay_ms), seed=0)
    then = frame_inputs(log[k - 2], "range", cav=late.cav).build(ScenarioParams(**EXACT), seed=0)
    assert trial.message_age_s == pytest.approx(delay_ms / 1000.0, abs=1e-12)
    np.testing.assert_array_equal(trial.cav_pose, then.cav_pose)
    np.testing.assert_allclose(trial.T_true, se2.inverse(late.trial["ego_pose"]) @ then.cav_pose, atol=1e-12)
    common = np.intersect1d(trial.cav_ids, then.cav_ids)
    assert len(common) > 10
    now_rows = [list(trial.cav_ids).index(i) for i in common]
    then_rows = [list(then.cav_ids).index(i) for i in common]
    np.testing.assert_allclose(trial.cav_boxes[now_rows], then.cav_boxes[then_rows], atol=1e-9)
    ego_now = frame_inputs(log[k], "range").build(ScenarioParams(**EXACT), seed=0)
    np.testing.assert_array_equal(trial.ego_boxes, ego_now.ego_boxes)


def test_a_delay_between_frames_interpolates_the_two_around_it(log):
    k = 40
    late = frame_inputs(log[k], "range", window_s=0.5)
    t0, t1 = log.timestamps[k - 2], log.timestamps[k - 1]
    w = 0.3
    age = log.timestamps[k] - (t0 + w * (t1 - t0))
    boxes, pose, captured = late.history.at(log.timestamps[k] - age)
    assert captured == pytest.approx(t0 + w * (t1 - t0))
    np.testing.assert_allclose(pose, pose_between(late.history.cav_poses[-3], late.history.cav_poses[-2], w))
    want = between(late.history.boxes[-3], late.history.boxes[-2], w)
    np.testing.assert_allclose(boxes[~np.isnan(want[:, 0])], want[~np.isnan(want[:, 0])])


def test_the_jitter_is_the_seeds_and_keeps_within_its_bounds(log):
    late = frame_inputs(log[80], "range", window_s=0.4)
    params = ScenarioParams(**EXACT, delay_ms=200.0, jitter_ms=100.0)
    ages = [late.build(params, seed=s).message_age_s for s in range(20)]
    assert all(0.1 - 1e-9 <= a <= 0.3 + 1e-9 for a in ages) and len(set(ages)) > 10
    assert ages == [late.build(params, seed=s).message_age_s for s in range(20)]


def test_a_message_is_never_older_than_the_sequence(log):
    first = frame_inputs(log[1], "range", window_s=0.5)
    trial = first.build(ScenarioParams(**EXACT, delay_ms=400.0), seed=0)
    assert trial.message_age_s == pytest.approx(log.timestamps[1] - log.timestamps[0])


def test_a_late_message_without_history_says_what_is_missing(log):
    with pytest.raises(ValueError, match="window_s"):
        frame_inputs(log[5], "range").build(ScenarioParams(**EXACT, delay_ms=100.0), seed=0)


def test_a_moving_car_moved_while_the_message_travelled(log):
    k = 100
    late = frame_inputs(log[k], "range", window_s=0.5)
    trial = late.build(ScenarioParams(**EXACT, delay_ms=300.0), seed=0)
    moved = np.linalg.norm(trial.ego_true_xy[trial.gt_pairs[:, 0]] - trial.cav_true_xy[trial.gt_pairs[:, 1]], axis=1)
    assert moved.max() > 0.5, "some object of the log moves: at 300 ms it has moved"
    assert np.median(moved) < 0.05, "most objects of the log are parked: they have not"
