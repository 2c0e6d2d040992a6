"""Hypotheses, verified, and the noise-aware gate: several anchors refined and the one that explains
the scene best kept; least squares on the pairs the gate keeps; "not enough evidence" said aloud."""
import math

import numpy as np
import pytest

import loaders
from cbm import CBMParams, match, se2
from cbm import hypotheses as module
from cbm.estimate import least_squares_fit
from cbm.gates import HEADING_FLOOR, clutter_density, heading_log_ratio, heading_sigma, pair_log_ratio, scene_sigma
from cbm.hypotheses import EVIDENCE_MARGIN, MIN_SHARED, Hypothesis, Verdict
from evaluation.conditions import CONDITIONS
from evaluation.metrics import evaluate, is_success, rte
from evaluation.run import frame_inputs
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene

pytestmark = pytest.mark.filterwarnings("error")


def trial_of(seed: int, n: int = 40, **scenario):
    world = street_scene(n, np.random.default_rng(seed), extent=70.0)
    return make_trial(world, np.arange(n), ScenarioParams(seed=seed, **scenario))


@pytest.mark.parametrize("seed", range(6))
def test_on_true_pairs_only_the_estimate_is_least_squares_on_them(seed):
    trial = trial_of(seed, eta=1.0, sigma_p=0.3, sigma_theta=5.0)
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init)
    pairs = trial.gt_pairs
    src = se2.apply_points(trial.init, trial.cav_boxes[pairs[:, 1], :2])
    oracle = least_squares_fit(src, trial.ego_boxes[pairs[:, 0], :2], 0.3).transform @ trial.init
    np.testing.assert_array_equal(result.pairs, pairs)
    assert rte(result.transform, trial.T_true) <= rte(oracle, trial.T_true) + 1e-9
    assert not result.abstained and result.reason == ""


def test_verifying_several_anchors_succeeds_more_often_under_heavy_noise(monkeypatch):
    """The heavy-noise condition on the shipped Argoverse 2 scene, every tenth frame."""
    sequence = loaders.open("argoverse2")
    inputs, _ = frame_inputs(sequence, range(0, len(sequence), 10), "sind")
    trials = [frame.build(CONDITIONS["heavy-noise"], seed) for frame in inputs for seed in (0, 1)]

    def successes():
        return sum(is_success(evaluate(match(t.ego_boxes, t.cav_boxes, t.init), t)) for t in trials)
    verified = successes()
    monkeypatch.setattr(module, "HYPOTHESES", 1)
    assert verified >= successes() + 2


def test_the_result_reports_the_runner_up_and_the_margin():
    trial = trial_of(3, n=60, eta=0.3, sigma_p=0.6, sigma_theta=10.0)
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init)
    assert result.hypotheses >= 1 and result.evidence > 0
    assert result.evidence_margin == result.evidence - result.runner_up_evidence >= EVIDENCE_MARGIN
    assert result.runner_up_transform is None or rte(result.runner_up_transform, result.transform) > 0.5
    paper = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(refine=False))
    assert paper.hypotheses == 0 and math.isnan(paper.evidence) and math.isnan(paper.evidence_margin)


def test_fewer_than_three_shared_objects_is_not_enough_evidence():
    rng = np.random.default_rng(1)
    ego = street_scene(2, rng)
    result = match(ego, ego.copy(), se2.make(1.0, 0.5, 0.02))
    assert result.estimated and len(result.pairs) == 2
    assert result.abstained and result.reason == f"fewer than {MIN_SHARED} objects could be paired"


def _hypothesis(score: float, n_pairs: int = 5) -> Hypothesis:
    pairs = np.stack([np.arange(n_pairs), np.arange(n_pairs)], axis=1)
    return Hypothesis(0, pairs, pairs, np.eye(3), 0.4, score)


def test_a_rival_pose_almost_as_good_is_not_enough_evidence_and_a_clear_winner_is():
    close = Verdict(_hypothesis(20.0), _hypothesis(20.0 - EVIDENCE_MARGIN / 2), tried=2)
    assert close.margin == pytest.approx(EVIDENCE_MARGIN / 2) and "almost as well" in close.reason
    assert Verdict(_hypothesis(20.0), _hypothesis(20.0 - 2 * EVIDENCE_MARGIN), tried=2).reason == ""
    alone = Verdict(_hypothesis(20.0), None, tried=1)
    assert alone.margin == math.inf and alone.reason == ""
    assert "fewer than" in Verdict(_hypothesis(20.0, n_pairs=2), None, tried=1).reason


def test_an_answer_no_rival_challenges_still_needs_its_own_evidence():
    """A frame of a handful of boxes forms no rival pose: the margin of ∞ then says nothing, and the
    answer must explain the scene better than no pose at all (evidence 0) by the same margin."""
    weak = Verdict(_hypothesis(EVIDENCE_MARGIN / 2, n_pairs=3), None, tried=1)
    assert weak.margin == math.inf and weak.reason == ("its pairs explain the scene hardly better than a "
                                                       "coincidence (evidence 4.0 < 8)")
    assert Verdict(_hypothesis(EVIDENCE_MARGIN, n_pairs=3), None, tried=1).reason == ""


def test_the_scene_sigma_is_the_residuals_rms_with_the_fits_freedom_taken_out():
    r = np.array([0.3, 0.4, 0.5, 0.2])
    assert scene_sigma(r, 0.1) == pytest.approx(math.sqrt(np.sum(r ** 2) / 5))
    assert scene_sigma(r, 1.0) == 1.0 and scene_sigma(r[:1], 0.2) == 0.2


def test_the_evidence_of_a_pair_falls_with_distance_and_heading_disagreement_and_with_crowding():
    sparse = clutter_density(np.random.default_rng(0).uniform(0, 100, (20, 2)))
    assert sparse == pytest.approx(20 / np.prod(np.ptp(np.random.default_rng(0).uniform(0, 100, (20, 2)), axis=0)))
    near, far = pair_log_ratio(np.array([0.3, 3.0]), 1.0, sparse)
    assert near > 0 > pair_log_ratio(np.array([3.0]), 1.0, 0.05)[0] and near > far
    assert pair_log_ratio(np.array([0.3]), 1.0, 0.05)[0] < near
    sigma = heading_sigma(np.radians([5.0, 10.0, 20.0]))
    assert sigma == pytest.approx(np.sqrt(np.mean(np.radians([5.0, 10.0, 20.0]) ** 2)))
    agree, across = heading_log_ratio(np.radians([3.0, 80.0]), sigma)
    assert agree > 0 > across
    assert heading_sigma(np.zeros(3)) == HEADING_FLOOR


@pytest.mark.parametrize("layout", ["street", "dense"])
@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("k, pool", [(6, 64), (3, 64), (6, 400)])
def test_the_pool_taken_from_the_visit_is_the_pool_filtered_whole(layout, seed, k, pool):
    from cbm.engine import anchor_sets, select
    from cbm.pipeline import checked_inputs
    from cbm.sets import build_sets
    from support.scenes import dense_scene

    if layout == "dense":
        boxes, ids = dense_scene(80, np.random.default_rng(60)), np.arange(80)
    else:
        frame = loaders.synthetic.generate(n_objects=80, n_frames=1, seed=60)[0]
        boxes, ids = frame.boxes(), frame.track_ids
    trial = make_trial(boxes, ids, ScenarioParams(protocol="sind", eta=0.5, sigma_p=0.3, sigma_theta=3.0,
                                                  flip_prob=0.5, seed=seed))
    ego, cav, init, params = checked_inputs(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams())
    sets = build_sets(ego, cav, init, params)
    arguments = (sets.candidates, sets.voted_by, sets.rule, sets.ego_xy, sets.cav_xy, params.distance_limit)
    chosen = select(*arguments)
    reused = anchor_sets(*arguments, chosen.anchor, k, pool, chosen.visit)
    whole = anchor_sets(*arguments, chosen.anchor, k, pool)
    assert [anchor for anchor, _ in reused] == [anchor for anchor, _ in whole]
    for (_, a), (_, b) in zip(reused, whole):
        np.testing.assert_array_equal(a, b)
