"""Every failed frame has a diagnosis (issue 47, item 3): the rules any method's failure answers to,
on constructed cases (the shipped scene's failed frames: ``tests/app/test_failure_picture.py``)."""
import dataclasses

import numpy as np
import pytest

from cbm import TrackNote, se2
from cbm.hypotheses import EVIDENCE_MARGIN
from cbm.methods import METHODS
from evaluation.diagnosis import SURE_FROM, diagnose_failure, least_squares_on
from evaluation.metrics import evaluate, is_success
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene


def trial_of(world, **scenario):
    return make_trial(world, np.arange(len(world)), ScenarioParams(**scenario))


def given(trial, pairs):
    """A result that paired ``pairs`` and fitted them by least squares (a method's answer, made to order)."""
    return METHODS["oracle"](trial.ego_boxes, trial.cav_boxes, trial.init, true_pairs=np.asarray(pairs).reshape(-1, 2))


def findings(trial, result, alone=None):
    oracle = least_squares_on(trial, trial.gt_pairs)
    return diagnose_failure(result, trial, evaluate(result, trial), oracle, alone=alone)


def tracked(trial, event, measured):
    """CBM over time's answer on ``trial``, 3 degrees off the truth, reached by ``event`` from the
    frame's own ``measured`` transform."""
    right = given(trial, trial.gt_pairs)
    off = se2.make(0.0, 0.0, np.radians(3.0)) @ trial.T_true
    note = TrackNote(event=event, persists=True, since_s=0.0, pooled=12, predicted=off, measured=measured, answer=off)
    return dataclasses.replace(right, transform=off, track=note)


def test_the_sure_threshold_is_cbms_own():
    assert SURE_FROM == EVIDENCE_MARGIN


def test_a_frame_the_noise_alone_fails_says_so():
    trial = trial_of(street_scene(40, np.random.default_rng(0)), eta=0.3, sigma_p=1.5, sigma_theta=10.0, seed=4)
    oracle = least_squares_on(trial, trial.gt_pairs)
    assert not is_success(oracle), "least squares on the true pairs fails here (else this proves nothing)"
    found = findings(trial, given(trial, trial.gt_pairs))
    assert found[0].code == "noise" and found[0].message.startswith("least squares on the true pairs is off by")
    assert found[0].message.endswith("too: the noise, not the matching")


def test_wrong_pairs_are_named_and_the_right_ones_alone_would_do():
    trial = trial_of(street_scene(40, np.random.default_rng(1)), eta=0.6, sigma_p=0.1, seed=2)
    truth = np.asarray(trial.gt_pairs)
    wrong = np.c_[truth[:3, 0], truth[3:6, 1]]
    result = given(trial, np.r_[truth[6:], wrong])
    assert not is_success(evaluate(result, trial)), "the wrong pairs pull the pose off (else this proves nothing)"
    found = {f.code: f for f in findings(trial, result)}
    assert "3 of its" in found["wrong_pairs"].message and "alone is off by only" in found["wrong_pairs"].message
    assert found["wrong_pairs"].brief.startswith("3 of its")


def test_a_pose_on_too_few_right_pairs_is_the_few_right_pairs():
    trial = trial_of(street_scene(60, np.random.default_rng(3)), eta=0.8, sigma_p=0.6, sigma_theta=5.0, seed=9)
    truth = np.asarray(trial.gt_pairs)
    near = truth[np.argsort(np.hypot(*trial.ego_boxes[truth[:, 0], :2].T))[:2]]
    result = given(trial, near)
    assume = is_success(least_squares_on(trial, truth)) and not is_success(evaluate(result, trial))
    assert assume, "two pairs fail where all succeed (else this proves nothing)"
    found = {f.code for f in findings(trial, result)}
    assert "few_right_pairs" in found


def test_nothing_paired_and_no_estimate_are_findings_too():
    trial = trial_of(street_scene(30, np.random.default_rng(4)), eta=0.6, seed=1)
    none = METHODS["none"](trial.ego_boxes, trial.cav_boxes, trial.init)
    assert [f.code for f in findings(trial, none)] == ["nothing_paired"]


@pytest.mark.parametrize("event, says", [
    ("accepted", "pooled with other frames by the track, the answer is off by 3.0"),
    ("rejected", "the track set aside this frame's own measurement, off by only 0.00° / 0.00 m (rejected): the "
                 "answer is its prediction from the other frames, off by 3.0")])
def test_a_track_that_pulled_its_answer_off_a_right_measurement_says_so(event, says):
    trial = trial_of(street_scene(40, np.random.default_rng(5)), eta=0.6, sigma_p=0.1, seed=3)
    result = tracked(trial, event, measured=trial.T_true)
    found = {f.code: f for f in findings(trial, result)}
    assert says in found["track"].message and "this frame's own measurement" in found["track"].message
    assert "(0.00° / 0.00 m)" in found["track"].brief


def test_a_track_answer_is_blamed_where_it_was_the_prediction_not_where_it_pooled_a_wrong_measurement():
    trial = trial_of(street_scene(40, np.random.default_rng(5)), eta=0.6, sigma_p=0.1, seed=3)
    wrong = se2.make(2.0, 0.0, 0.0) @ trial.T_true
    assert "track" not in {f.code for f in findings(trial, tracked(trial, "accepted", measured=wrong))}
    set_aside = {f.code: f for f in findings(trial, tracked(trial, "rejected", measured=wrong))}
    assert set_aside["track"].brief == ("the track set aside this frame's own measurement (0.00° / 2.00 m) for its "
                                        "prediction")
    unmeasured = {f.code: f for f in findings(trial, tracked(trial, "no measurement", measured=None))}
    assert unmeasured["track"].brief == "the answer is the track's prediction: this frame gave it no measurement"


def test_over_time_failing_where_per_frame_cbm_succeeds_says_so():
    trial = trial_of(street_scene(40, np.random.default_rng(5)), eta=0.6, sigma_p=0.1, seed=3)
    result = tracked(trial, "no measurement", measured=None)
    alone = evaluate(given(trial, trial.gt_pairs), trial)
    found = {f.code: f for f in findings(trial, result, given(trial, trial.gt_pairs))}
    told = f"per-frame CBM on this frame alone is off by only {alone.rre:.2f}° / {alone.rte:.2f} m: over time"
    assert found["over_time"].message.startswith(told) and found["over_time"].message.endswith("3.00° / 0.00 m")
    assert "over_time" not in {f.code for f in findings(trial, result, result)}
