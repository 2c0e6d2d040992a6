"""The why-it-failed rules on constructed cases, and the inspector against the fast path."""
import dataclasses

import numpy as np
import pytest

from cbm import CBMParams, Explanation, match
from evaluation.diagnosis import diagnose, pair_name, rank_against_runner_up, short_id
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene


def explained(ego, cav, init, params=None) -> Explanation:
    """CBM's explanation of its own run on the input (``match(..., explain=True)``)."""
    return match(ego, cav, init, params, explain=True).explanation


def codes(trial, params=None):
    params = params or CBMParams()
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    return {f.code for f in diagnose(result, trial, explained(trial.ego_boxes, trial.cav_boxes, trial.init, params))}


def trial_of(world, **scenario):
    return make_trial(world, np.arange(len(world)), ScenarioParams(**scenario))


def test_a_clean_frame_has_no_findings():
    world = street_scene(40, np.random.default_rng(0))
    assert codes(trial_of(world, eta=0.6, sigma_p=0.1, seed=1)) == set()


def test_too_few_covisible_objects():
    world = street_scene(30, np.random.default_rng(1))
    assert "few_covisible" in codes(trial_of(world, eta=0.05, seed=2))


def test_no_anchor_reached_two_pairs():
    world = street_scene(12, np.random.default_rng(2))
    trial = trial_of(world, eta=1.0, sigma_p=2.0, seed=3)
    assert "no_anchor" in codes(trial, CBMParams(sigma2=0.05, sigma1=1.0))


def boxes(rows):
    out = np.zeros((len(rows), 7))
    out[:, [0, 1, 6]] = rows
    out[:, 3:6] = (4.5, 1.9, 1.6)
    return out


def test_single_pair_winner():
    """Anchor (0, 0) accepts CAV objects 1 and 2 for ego object 1: the one-to-one rule drops both.
    CAV objects 1 and 2 face 30 degrees off, so no other anchor accepts anything."""
    ego = boxes([(0, 0, 0), (10, 0, 0)])
    cav = boxes([(0, 0, 0), (10, 0.5, np.radians(30)), (10, -0.5, np.radians(30))])
    params = CBMParams(consensus=False)
    result = match(ego, cav, np.eye(3), params)
    assert result.anchor == (0, 0) and result.consensus_count == 1 and not result.estimated
    findings = diagnose(result, make_trial(np.zeros((0, 7)), np.zeros(0), ScenarioParams()),
                        explained(ego, cav, np.eye(3), params))
    assert "single_pair" in {f.code for f in findings}


def test_right_anchor_rejected_by_the_distance_limit():
    world = street_scene(30, np.random.default_rng(4))
    trial = trial_of(world, eta=0.7, seed=5, loc_x=12.0, loc_y=12.0)
    assert "distance_limit" in codes(trial, CBMParams(distance_limit=10.0))


def test_heading_fold_is_reported_in_fold_mode_only():
    rng = np.random.default_rng(5)
    world = street_scene(24, rng)
    world[:, 6] = np.pi / 2 - 0.02
    trial = trial_of(world, eta=1.0, flip_prob=0.0, loc_x=0.0, loc_y=0.0, loc_yaw=3.0)
    assert "heading_fold" in codes(trial, CBMParams(heading="fold"))
    assert "heading_fold" not in codes(trial, CBMParams(heading="align"))


def test_wrong_anchor_reports_both_counts():
    world = street_scene(40, np.random.default_rng(0))
    trial = trial_of(world, eta=0.15, sigma_p=0.8, sigma_theta=10.0, seed=0)
    params = CBMParams(sigma2=6.0, sigma1=25.0, consensus=False)
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    inspection = explained(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    findings = {f.code: f.message for f in diagnose(result, trial, inspection)}
    assert tuple(result.anchor) not in {tuple(p) for p in trial.gt_pairs.tolist()}
    right = inspection.best_anchor_among(trial.gt_pairs)
    assert right.size <= result.consensus_count
    message = findings["wrong_anchor"]
    assert message.startswith(f"the winning anchor {pair_name(trial, result.anchor)} was wrong with "
                              f"{result.consensus_count} pairs; the best right anchor {pair_name(trial, right.anchor)}")
    assert message.endswith(rank_against_runner_up(right.size, result.runner_up_count))


def test_a_wrong_anchor_whose_answer_is_all_right_is_no_finding():
    """The re-association can leave a wrong anchor out of the answer: every pair right, nothing to warn of."""
    world = street_scene(40, np.random.default_rng(0))
    trial = trial_of(world, eta=0.15, sigma_p=0.8, sigma_theta=10.0, seed=0)
    params = CBMParams(sigma2=6.0, sigma1=25.0, consensus=False)
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    right = dataclasses.replace(result, pairs=np.asarray(trial.gt_pairs)[:5])
    inspection = explained(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    assert "wrong_anchor" in {f.code for f in diagnose(result, trial, inspection)}
    assert "wrong_anchor" not in {f.code for f in diagnose(right, trial, inspection)}


def test_messages_name_objects_by_their_ids_not_rows():
    """The ids are made to differ from the rows, so a row index in a message would show."""
    world = street_scene(40, np.random.default_rng(0))
    trial = trial_of(world, eta=0.15, sigma_p=0.8, sigma_theta=10.0, seed=0)
    trial = dataclasses.replace(trial, ego_ids=np.array([f"e{k + 500}" for k in range(len(trial.ego_boxes))]),
                                cav_ids=np.array([f"c{k + 700}" for k in range(len(trial.cav_boxes))]))
    params = CBMParams(sigma2=6.0, sigma1=25.0, consensus=False)
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    inspection = explained(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    message = {f.code: f.message for f in diagnose(result, trial, inspection)}["wrong_anchor"]
    i, j = result.anchor
    assert f"ego e{i + 500} ↔ CAV c{j + 700}" in message
    assert str(tuple(result.anchor)) not in message


@pytest.mark.parametrize(("size", "runner_up", "says"), [(5, 5, "came second with 5"),
                                                         (3, 5, "a wrong anchor came second with 5"),
                                                         (6, 5, "more than the runner-up's 5")])
def test_came_second_only_when_it_did(size, runner_up, says):
    text = rank_against_runner_up(size, runner_up)
    assert says in text
    assert ("came second" in text.split(":")[0]) == (size == runner_up)


def test_short_ids_are_what_labels_show():
    assert short_id("0123456789abcdef") == "01234567" and short_id(42) == "42"


@pytest.mark.parametrize("setting", [dict(), dict(consensus_rule="released", sigma3=1.0), dict(consensus=False),
                                     dict(heading="fold")])
def test_inspector_agrees_with_the_fast_path(setting):
    world = street_scene(30, np.random.default_rng(8))
    trial = trial_of(world, eta=0.6, sigma_p=0.3, sigma_theta=3.0, seed=9)
    params = CBMParams(**setting)
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    again = match(trial.ego_boxes, trial.cav_boxes, trial.init, params, explain=True)
    inspection = again.explanation
    np.testing.assert_array_equal(again.pairs, result.pairs)
    np.testing.assert_array_equal(again.transform, result.transform)
    winner = inspection.anchor(*result.anchor)
    np.testing.assert_array_equal(winner.final, result.pairs)
    assert len(winner.candidates) == result.candidate_count
    sizes = [inspection.anchor(i, j).size for i in range(len(trial.ego_boxes)) for j in range(len(trial.cav_boxes))]
    assert max(sizes) == result.consensus_count


def test_context_of_a_cav_object_turns_with_its_sign():
    world = street_scene(10, np.random.default_rng(9))
    ego = world.copy()
    cav = world.copy()
    cav[:, 6] += np.pi
    inspection = explained(ego, cav, np.eye(3), CBMParams(heading="align"))
    members, ego_vectors = inspection.context("ego", 0)
    _, cav_vectors = inspection.context("cav", 0, against=0)
    np.testing.assert_allclose(cav_vectors, ego_vectors, atol=1e-9)
    assert list(members) == list(range(1, 10))


def test_an_inspection_is_freed_when_dropped():
    """Explained anchors are cached with their inspection, not process-wide (a tab recomputes
    hundreds of times: every old inspection must go)."""
    import gc
    import weakref

    trial = make_trial(street_scene(40, np.random.default_rng(0)), np.arange(40), ScenarioParams(eta=0.6, sigma_p=0.2))
    inspection = explained(trial.ego_boxes, trial.cav_boxes, trial.init)
    first = inspection.best_anchor_among(trial.gt_pairs)
    assert inspection.best_anchor_among(trial.gt_pairs) is first
    alive = weakref.ref(inspection)
    del inspection
    gc.collect()
    assert alive() is None


@pytest.mark.parametrize("rule", ["released", "paper"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_best_anchor_among_the_true_pairs_equals_explaining_each_of_them(seed, rule):
    world = street_scene(60, np.random.default_rng(seed))
    trial = trial_of(world, eta=0.5, sigma_p=0.6, sigma_theta=4.0, seed=seed)
    params = CBMParams(consensus_rule=rule, distance_limit=6.0)
    inspection = explained(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    details = [inspection.anchor(i, j) for i, j in trial.gt_pairs]
    slowest = max(details, key=lambda d: d.size)
    assert inspection.best_anchor_among(trial.gt_pairs).anchor == slowest.anchor
    assert inspection.best_anchor_among(np.zeros((0, 2), int)) is None


@pytest.mark.parametrize("rule", ["released", "paper"])
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("limit", [2.0, 6.0])
def test_the_best_true_anchor_after_a_match_reuses_the_visit_and_stays_the_same(seed, rule, limit):
    """After ``match`` the sizes come partly from the selection's visit: the anchor found is the one
    an inspection that never matched finds, as are the diagnosis' findings."""
    world = street_scene(60, np.random.default_rng(seed))
    trial = trial_of(world, eta=0.5, sigma_p=0.6, sigma_theta=4.0, seed=seed)
    params = CBMParams(consensus_rule=rule, distance_limit=limit)
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init, params, explain=True)
    matched = result.explanation
    fresh = Explanation(matched.sets, matched.init, matched.fit, visit=None)
    assert (matched.visit is not None) == (result.anchor is not None)
    assert matched.best_anchor_among(trial.gt_pairs).anchor == fresh.best_anchor_among(trial.gt_pairs).anchor
    assert diagnose(result, trial, matched) == diagnose(result, trial, fresh)
    wrong = np.array([[i, (j + 1) % len(trial.cav_boxes)] for i, j in trial.gt_pairs])
    assert matched.best_anchor_among(wrong).anchor == fresh.best_anchor_among(wrong).anchor
