"""The ego's objects over time: parked cars stand still, a driving car's speed is found from the
ego's own moving frame, and a late message's age is the slope of the residuals on the speeds."""
import numpy as np
import pytest

from cbm import se2
from cbm.estimate import weighted_procrustes
from cbm.motion import AgeEstimate, EgoTracks, compensated, message_age


def world(t: float, rng: np.random.Generator | None = None) -> np.ndarray:
    """20 parked cars on a grid and two driving along x at 10 and -8 m/s, at time t."""
    parked = np.array([[x, y] for x in range(-40, 41, 20) for y in (-12.0, -6.0, 6.0, 12.0)], float)
    driving = np.array([[-30.0 + 10.0 * t, 2.0], [35.0 - 8.0 * t, -2.0]])
    xy = np.concatenate([parked, driving])
    boxes = np.zeros((len(xy), 7))
    boxes[:, :2], boxes[:, 3:6] = xy, (4.5, 1.9, 1.6)
    if rng is not None:
        boxes[:, :2] += rng.normal(0.0, 0.2, (len(xy), 2))
    return boxes


def ego_pose(t: float) -> np.ndarray:
    """The ego drives at 5 m/s and turns slowly."""
    return se2.make(5.0 * t, 0.5 * t, 0.05 * t)


def test_the_speed_of_a_driving_car_is_found_from_the_ego_s_moving_frame():
    rng = np.random.default_rng(0)
    tracks = EgoTracks()
    for k in range(15):
        t = 0.1 * k
        seen = se2.apply_boxes(se2.inverse(ego_pose(t)), world(t, rng))
        velocity = tracks.step(seen, t)
    in_world = velocity @ se2.make(0, 0, se2.yaw_of(ego_pose(t)))[:2, :2].T
    np.testing.assert_allclose(in_world[-2], [10.0, 0.0], atol=0.6)
    np.testing.assert_allclose(in_world[-1], [-8.0, 0.0], atol=0.6)
    assert np.nanmax(np.linalg.norm(in_world[:-2], axis=1)) < 0.6, "parked cars stand still"


def test_a_first_frame_and_time_going_back_know_no_speed():
    tracks = EgoTracks()
    assert np.isnan(tracks.step(world(0.0), 0.0)).all()
    tracks.step(world(0.1), 0.1)
    assert np.isnan(tracks.step(world(0.0), 0.0)).all()


@pytest.mark.parametrize("age", [0.1, 0.25])
def test_the_age_is_the_slope_of_the_residuals_on_the_speeds(age):
    rng = np.random.default_rng(1)
    velocity = np.array([[10.0, 0.0], [-8.0, 1.0], [0.0, 0.0], [0.0, 0.0]])
    residuals = velocity * age + rng.normal(0.0, 0.05, (4, 2))
    d, weight, noise = message_age(residuals, velocity)
    assert d == pytest.approx(age, abs=0.02) and weight == pytest.approx(165.0)
    assert noise == pytest.approx(0.05 ** 2, rel=1.5), "the standing pairs' residuals are the noise"
    assert message_age(residuals, np.zeros((4, 2)))[1] == 0.0


def test_a_frame_with_much_motion_tells_its_own_age_one_with_little_the_typical_one():
    estimate = AgeEstimate()
    rng = np.random.default_rng(3)
    for _ in range(20):
        estimate.add(0.2 + rng.uniform(-0.1, 0.1), 200.0, 0.01)
    pooled = estimate.seconds
    assert estimate.of_frame(0.28, 5000.0, 0.01) == pytest.approx(0.28, abs=0.01)
    assert estimate.of_frame(0.28, 2.0, 0.05) == pytest.approx(pooled, abs=0.01)


def test_the_pooled_age_waits_for_enough_motion_and_shrugs_off_a_wrong_frame():
    estimate = AgeEstimate()
    estimate.add(0.2, 100.0, 0.02)
    assert estimate.seconds is None
    for age in (0.21, 0.19, 0.2, 3.0):
        estimate.add(age, 100.0, 0.02)
    assert estimate.seconds == pytest.approx(0.2, abs=0.011)
    noisy = AgeEstimate()
    for age in (0.21, 0.19, 0.2, 0.2):
        noisy.add(age, 100.0, 2.0)
    assert noisy.seconds is None, "detections this noisy do not tell the age"


def test_moving_the_ego_boxes_back_by_their_motion_removes_the_bias():
    rng = np.random.default_rng(2)
    truth = se2.make(3.0, -2.0, 0.1)
    ego = world(1.0)[:, :2]
    velocity = np.zeros_like(ego)
    velocity[-2:] = [[10.0, 0.0], [8.0, 0.0]]
    captured = ego - 0.3 * velocity
    cav = se2.apply_points(se2.inverse(truth), captured) + rng.normal(0.0, 0.01, ego.shape)
    biased = weighted_procrustes(cav, ego)
    fitted = compensated(biased, ego, cav, velocity, 0.3)
    assert np.linalg.norm(se2.translation_of(biased) - se2.translation_of(truth)) > 0.1
    assert np.linalg.norm(se2.translation_of(fitted) - se2.translation_of(truth)) < 0.05
    assert np.array_equal(compensated(biased, ego, cav, velocity, 0.0), biased), "no age, no change"
