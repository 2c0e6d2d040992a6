"""The reference methods: ``none`` reports the wrong pose as is, ``oracle`` is least squares on the
true pairs; together they bound what any calibration reaches on a trial."""
import numpy as np
import pytest

from cbm.baselines import match_none, match_oracle
from cbm.estimate import weighted_procrustes
from evaluation.metrics import evaluate, rre, rte
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene


def trial(seed=0, **scenario):
    rng = np.random.default_rng(seed)
    params = dict(eta=0.4, sigma_p=0.5, sigma_theta=5.0, seed=seed) | scenario
    return make_trial(street_scene(40, rng), np.arange(40), ScenarioParams(**params))


def test_none_keeps_the_wrong_pose_and_matches_nothing():
    t = trial()
    result = match_none(t.ego_boxes, t.cav_boxes, t.init)
    metrics = evaluate(result, t)
    np.testing.assert_array_equal(result.transform, t.init)
    assert len(result.pairs) == 0 and metrics.recall == 0.0
    assert metrics.rte == pytest.approx(rte(t.init, t.T_true)) and metrics.rre == pytest.approx(rre(t.init, t.T_true))


def test_oracle_is_least_squares_on_the_true_pairs():
    t = trial(1)
    result = match_oracle(t.ego_boxes, t.cav_boxes, t.init, true_pairs=t.gt_pairs)
    expected = weighted_procrustes(t.cav_boxes[t.gt_pairs[:, 1], :2], t.ego_boxes[t.gt_pairs[:, 0], :2])
    np.testing.assert_allclose(result.transform, expected)
    metrics = evaluate(result, t)
    assert metrics.precision == metrics.recall == 1.0


def test_oracle_without_two_true_pairs_makes_no_estimate():
    t = trial(2, eta=0.0)
    result = match_oracle(t.ego_boxes, t.cav_boxes, t.init, true_pairs=t.gt_pairs[:1])
    assert not result.estimated
    np.testing.assert_array_equal(result.transform, t.init)


def test_oracle_names_bad_true_pairs():
    t = trial(3)
    with pytest.raises(ValueError, match="true_pairs"):
        match_oracle(t.ego_boxes, t.cav_boxes, t.init, true_pairs=np.array([[0, 999], [1, 1]]))
