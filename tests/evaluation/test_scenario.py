import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cbm import se2
from evaluation.scenario import ScenarioParams, Trial, make_trial, trial_rng

ARRAY_FIELDS = ("ego_boxes", "cav_boxes", "ego_ids", "cav_ids", "T_true", "init", "gt_pairs",
                "ego_true_xy", "cav_true_xy", "ego_pose", "cav_pose")


def scene(n: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    boxes = np.zeros((n, 7))
    boxes[:, :2] = rng.uniform(-60, 60, (n, 2))
    boxes[:, 3:6] = [4.5, 1.9, 1.6]
    boxes[:, 6] = rng.uniform(-np.pi, np.pi, n)
    return boxes, np.arange(100, 100 + n)


def noise_free(**kwargs) -> ScenarioParams:
    return ScenarioParams(sigma_p=0.0, sigma_theta=0.0, flip_prob=0.0, loc_x=0.0, loc_y=0.0, loc_yaw=0.0, **kwargs)


def same(a: Trial, b: Trial) -> bool:
    return all(np.array_equal(getattr(a, f), getattr(b, f)) for f in ARRAY_FIELDS)


def test_same_seed_gives_the_same_trial_bit_for_bit_and_another_seed_does_not():
    boxes, ids = scene(30)
    params = ScenarioParams(sigma_p=0.3, sigma_theta=5.0, localization="gaussian", seed=7)
    assert same(make_trial(boxes, ids, params), make_trial(boxes, ids, params))
    assert same(make_trial(boxes, ids, params, rng=trial_rng(7, 3)),
                make_trial(boxes, ids, params, rng=trial_rng(7, 3)))
    assert not same(make_trial(boxes, ids, params), make_trial(boxes, ids, replace(params, seed=8)))
    assert not same(make_trial(boxes, ids, params, rng=trial_rng(7, 3)),
                    make_trial(boxes, ids, params, rng=trial_rng(7, 4)))


@settings(max_examples=60, deadline=None)
@given(n=st.integers(0, 40), eta=st.floats(0.0, 1.0), seed=st.integers(0, 2**16))
def test_sind_split_has_round_eta_n_co_visible_objects_and_covers_all(n, eta, seed):
    boxes, ids = scene(n)
    trial = make_trial(boxes, ids, ScenarioParams(eta=eta, seed=seed))
    ego, cav = set(trial.ego_ids.tolist()), set(trial.cav_ids.tolist())
    co_visible = ego & cav
    assert len(co_visible) == round(eta * n)
    assert ego | cav == set(ids.tolist())
    assert len(ego) - len(cav) == (n - len(co_visible)) % 2
    assert [tuple(p) for p in trial.gt_pairs] == sorted(
        (i, trial.cav_ids.tolist().index(obj)) for i, obj in enumerate(trial.ego_ids.tolist()) if obj in co_visible)


def test_noise_free_sind_cav_boxes_mapped_by_T_true_land_on_the_ego_boxes_of_the_same_ids():
    boxes, ids = scene(25)
    trial = make_trial(boxes, ids, noise_free(eta=0.6), ego_pose=se2.make(5, -3, 0.4), cav_pose=se2.make(-20, 8, -2.0))
    mapped = se2.apply_boxes(trial.T_true, trial.cav_boxes)
    e, c = trial.gt_pairs.T
    assert len(e) == 15
    np.testing.assert_array_equal(trial.ego_ids[e], trial.cav_ids[c])
    np.testing.assert_allclose(mapped[c], trial.ego_boxes[e], atol=1e-9)
    np.testing.assert_allclose(trial.cav_true_xy[c], trial.ego_true_xy[e], atol=1e-9)
    np.testing.assert_allclose(se2.apply_boxes(se2.inverse(trial.ego_pose), boxes[np.isin(ids, trial.ego_ids)]),
                               trial.ego_boxes, atol=1e-12)


def test_sind_without_poses_puts_both_agents_at_the_centroid():
    boxes, ids = scene(10)
    trial = make_trial(boxes, ids, noise_free())
    np.testing.assert_allclose(trial.T_true, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(se2.translation_of(trial.ego_pose), boxes[:, :2].mean(axis=0))


def test_fixed_localization_error_is_exactly_the_offset_added_to_the_cav_world_pose():
    boxes, ids = scene(12)
    trial = make_trial(boxes, ids, ScenarioParams(loc_x=3.0, loc_y=3.0, loc_yaw=5.0))
    np.testing.assert_allclose(trial.init, se2.make(3.0, 3.0, math.radians(5.0)), atol=1e-12)

    ego_pose, cav_pose = se2.make(10, 20, 1.0), se2.make(-4, 7, 3.1)
    trial = make_trial(boxes, ids, ScenarioParams(loc_x=3.0, loc_y=-2.0, loc_yaw=5.0),
                       ego_pose=ego_pose, cav_pose=cav_pose)
    np.testing.assert_allclose(trial.T_true, se2.inverse(ego_pose) @ cav_pose, atol=1e-12)
    perturbed = ego_pose @ trial.init
    np.testing.assert_allclose(se2.translation_of(perturbed), [-1.0, 5.0], atol=1e-12)
    assert se2.wrap_angle(se2.yaw_of(perturbed) - (3.1 + math.radians(5.0))) == pytest.approx(0.0, abs=1e-12)
    correction = trial.init @ se2.inverse(trial.T_true)
    assert math.degrees(se2.yaw_of(correction)) == pytest.approx(5.0)


def test_gaussian_localization_error_is_drawn_with_the_given_std_devs():
    boxes, ids = scene(3)
    params = ScenarioParams(localization="gaussian", loc_x=3.0, loc_y=1.0, loc_yaw=5.0)
    errors = []
    for frame in range(400):
        t = make_trial(boxes, ids, params, rng=trial_rng(0, frame))
        perturbed = t.ego_pose @ t.init
        errors.append([*(se2.translation_of(perturbed) - se2.translation_of(t.cav_pose)),
                       math.degrees(se2.wrap_angle(se2.yaw_of(perturbed) - se2.yaw_of(t.cav_pose)))])
    np.testing.assert_allclose(np.std(errors, axis=0), [3.0, 1.0, 5.0], rtol=0.15)
    np.testing.assert_allclose(np.mean(errors, axis=0), [0.0, 0.0, 0.0], atol=0.8)


def test_range_protocol_sees_only_objects_within_range_and_never_itself():
    boxes = np.zeros((5, 7))
    boxes[:, 0] = [0.0, 30.0, 49.0, 80.0, 200.0]
    ids = np.array(["ego", "a", "cav", "b", "far"])
    trial = make_trial(boxes, ids, noise_free(protocol="range", sensor_range=50.0),
                       ego_pose=se2.make(0, 0, 0), cav_pose=se2.make(49, 0, np.pi / 2), cav_id="cav", ego_id="ego")
    assert trial.ego_ids.tolist() == ["a", "cav"]
    assert trial.cav_ids.tolist() == ["ego", "a", "b"]
    assert trial.gt_pairs.tolist() == [[0, 1]]
    np.testing.assert_allclose(trial.cav_boxes[:, :2], [[0, 49], [0, 19], [0, -31]], atol=1e-9)


def test_opv2v_protocol_requires_poses_and_visibility_and_follows_it():
    boxes, ids = scene(6)
    poses = dict(ego_pose=se2.make(0, 0, 0), cav_pose=se2.make(10, 0, 0))
    params = noise_free(protocol="opv2v")
    with pytest.raises(ValueError, match="visibility"):
        make_trial(boxes, ids, params, **poses)
    with pytest.raises(ValueError, match="visibility"):
        make_trial(boxes, ids, params, visibility={"ego": ids}, **poses)
    with pytest.raises(ValueError, match="cav_pose"):
        make_trial(boxes, ids, params, ego_pose=poses["ego_pose"], visibility={"ego": ids, "cav": ids})
    trial = make_trial(boxes, ids, params, visibility={"ego": [100, 101, 103], "cav": [103, 105, 101, 999]}, **poses)
    assert trial.ego_ids.tolist() == [100, 101, 103]
    assert trial.cav_ids.tolist() == [101, 103, 105]
    assert trial.gt_pairs.tolist() == [[1, 0], [2, 1]]


def test_flip_prob_one_turns_every_heading_by_pi_and_zero_turns_none():
    boxes, ids = scene(20)
    flipped = make_trial(boxes, ids, ScenarioParams(eta=1.0, flip_prob=1.0, loc_x=0, loc_y=0, loc_yaw=0))
    kept = make_trial(boxes, ids, ScenarioParams(eta=1.0, flip_prob=0.0, loc_x=0, loc_y=0, loc_yaw=0))
    for boxes_flipped, boxes_kept in ((flipped.ego_boxes, kept.ego_boxes), (flipped.cav_boxes, kept.cav_boxes)):
        np.testing.assert_allclose(np.abs(se2.wrap_angle(boxes_flipped[:, 6] - boxes_kept[:, 6])), np.pi, atol=1e-9)
        np.testing.assert_allclose(se2.wrap_angle(boxes_kept[:, 6] - boxes[:, 6]), 0.0, atol=1e-9)
        assert np.all((boxes_flipped[:, 6] >= -np.pi) & (boxes_flipped[:, 6] < np.pi))


def test_detection_noise_is_independent_per_agent_and_has_the_given_std_dev():
    boxes, ids = scene(400)
    trial = make_trial(boxes, ids, ScenarioParams(eta=1.0, sigma_p=0.5, sigma_theta=4.0, flip_prob=0.0,
                                                  loc_x=0, loc_y=0, loc_yaw=0))
    ego_err = trial.ego_boxes - se2.apply_boxes(se2.inverse(trial.ego_pose), boxes)
    cav_err = trial.cav_boxes - se2.apply_boxes(se2.inverse(trial.cav_pose), boxes)
    assert np.std(ego_err[:, :2]) == pytest.approx(0.5, rel=0.1)
    assert np.degrees(np.std(se2.wrap_angle(cav_err[:, 6]))) == pytest.approx(4.0, rel=0.1)
    assert abs(np.corrcoef(ego_err[:, 0], cav_err[:, 0])[0, 1]) < 0.2
    np.testing.assert_array_equal(trial.ego_boxes[:, 2:6], boxes[:, 2:6])


@pytest.mark.parametrize("protocol", ["sind", "range", "opv2v"])
def test_empty_scene_gives_empty_arrays_of_the_right_shapes(protocol):
    extra = {} if protocol == "sind" else dict(ego_pose=np.eye(3), cav_pose=np.eye(3))
    if protocol == "opv2v":
        extra["visibility"] = {"ego": [], "cav": []}
    trial = make_trial(np.empty((0, 7)), np.array([], dtype=np.int64), ScenarioParams(protocol=protocol), **extra)
    assert trial.ego_boxes.shape == trial.cav_boxes.shape == (0, 7)
    assert trial.ego_ids.shape == trial.cav_ids.shape == (0,)
    assert trial.ego_true_xy.shape == trial.cav_true_xy.shape == (0, 2)
    assert trial.gt_pairs.shape == (0, 2) and trial.gt_pairs.dtype == np.int64
    assert trial.init.shape == trial.T_true.shape == (3, 3)


@pytest.mark.parametrize("field, value", [
    ("eta", 1.5), ("eta", -0.1), ("eta", math.nan), ("sigma_p", -1.0), ("sigma_theta", -0.5), ("flip_prob", 2.0),
    ("sensor_range", 0.0), ("protocol", "carla"), ("localization", "no-gnss"), ("seed", -1), ("seed", 1.5),
])
def test_bad_params_raise_a_value_error_naming_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        ScenarioParams(**{field: value})


def test_negative_localization_is_an_offset_when_fixed_but_not_a_std_dev():
    ScenarioParams(loc_x=-3.0)
    with pytest.raises(ValueError, match="loc_x"):
        ScenarioParams(localization="gaussian", loc_x=-3.0)


def test_bad_inputs_raise():
    boxes, ids = scene(4)
    with pytest.raises(ValueError, match="ids"):
        make_trial(boxes, np.array([1, 1, 2, 3]), ScenarioParams())
    with pytest.raises(ValueError, match="boxes"):
        make_trial(boxes[:, :5], ids, ScenarioParams())
    with pytest.raises(ValueError, match="ego_pose"):
        make_trial(boxes, ids, ScenarioParams(protocol="range"), cav_pose=np.eye(3))
