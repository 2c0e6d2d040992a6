"""The fast engine that ``cbm.match`` runs gives exactly what ``cbm.reference`` (eq. 5-14 as the
paper states them) gives: the winning pairs, the winner's card(L_ij), the anchor and the runner-up,
on random scenes of up to 40 objects per agent, for every heading rule and consensus rule, with the
engine's hand-overs as tuned for this machine, all taken (on four threads) and none taken."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cbm import CBMParams, match, reference
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene

from .conftest import NEVER

RULES = {"paper": dict(consensus_rule="paper"), "released": dict(consensus_rule="released"),
         "none": dict(consensus=False)}
TUNINGS = {"as tuned": {}, "every hand-over": dict(threads=4, every=0), "no hand-over": dict(threads=1, every=NEVER)}


@st.composite
def scenes(draw):
    """A trial of up to 40 objects per agent, its noise, co-visibility and thresholds drawn."""
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    n = draw(st.integers(2, 40))
    spacing = float(rng.choice([0.5, 4.0]))
    extent = max(float(rng.uniform(12.0, 50.0)), 1.5 * spacing * np.sqrt(n))
    world = street_scene(n, rng, extent=extent, spacing=spacing)
    scenario = ScenarioParams(eta=draw(st.floats(0.3, 1.0)), sigma_p=draw(st.sampled_from([0.0, 0.2, 0.5])),
                              sigma_theta=draw(st.sampled_from([0.0, 3.0, 10.0])), flip_prob=0.5, seed=seed)
    thresholds = dict(sigma1=draw(st.sampled_from([5.0, 10.0, 20.0])), sigma2=draw(st.sampled_from([1.0, 3.0, 5.0])),
                      sigma3=draw(st.sampled_from([0.5, 1.0, 3.0])),
                      distance_limit=draw(st.sampled_from([5.0, 20.0])))
    return make_trial(world, np.arange(n), scenario), thresholds


def reference_of(trial, params: CBMParams) -> reference.Matching:
    return reference.match_sets(trial.ego_boxes, trial.cav_boxes, trial.init, params.sigma1_rad, params.sigma2,
                                params.sigma3, params.distance_limit,
                                params.consensus_rule if params.consensus else None, params.heading)


@pytest.mark.parametrize("tuning", list(TUNINGS))
@pytest.mark.parametrize("rule", list(RULES))
@pytest.mark.parametrize("heading", ["align", "fold"])
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(scene=scenes())
def test_the_engine_gives_the_reference_pairs_counts_anchor_and_runner_up(scene, heading, rule, tuning, tuned):
    tuned(**TUNINGS[tuning])
    trial, thresholds = scene
    params = CBMParams(heading=heading, refine=False, **thresholds, **RULES[rule])
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    expected = reference_of(trial, params)
    np.testing.assert_array_equal(result.context_pairs, expected.pairs)
    assert result.anchor == expected.anchor
    assert result.candidate_count == expected.candidate_count
    assert result.runner_up_count == expected.runner_up_count


@pytest.mark.parametrize("seed", range(6))
def test_with_the_verification_beyond_the_paper_cbms_own_pairs_are_still_the_references(seed):
    rng = np.random.default_rng(seed)
    world = street_scene(30, rng, extent=40.0)
    trial = make_trial(world, np.arange(30), ScenarioParams(eta=0.6, sigma_p=0.3, sigma_theta=3.0, seed=seed))
    params = CBMParams()
    result, expected = match(trial.ego_boxes, trial.cav_boxes, trial.init, params), reference_of(trial, params)
    np.testing.assert_array_equal(result.context_pairs, expected.pairs)
    assert (result.anchor, result.candidate_count, result.runner_up_count) == (
        expected.anchor, expected.candidate_count, expected.runner_up_count)


def test_the_reference_reads_as_the_paper_on_a_scene_worked_by_hand():
    """Three cars in a row seen by both agents, the CAV's frame turned by 90 degrees: every anchor on
    one car matches the other two (eq. 8-9), the consensus keeps them (eq. 10-11), and the set of three
    wins (eq. 13)."""
    ego = np.zeros((3, 7))
    ego[:, 0], ego[:, 3:6] = [0.0, 10.0, 25.0], (4.5, 1.9, 1.6)
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    cav = ego.copy()
    cav[:, :2], cav[:, 6] = ego[:, :2] @ turn[:2, :2], -np.pi / 2
    found = reference.match_sets(ego, cav, turn, np.radians(10.0), 3.0, 1.0, 20.0, "paper")
    assert found.pairs.tolist() == [[0, 0], [1, 1], [2, 2]]
    assert found.candidate_count == 3 and found.runner_up_count == 0
    assert found.candidates[0, 0].sum() == 3 and not found.candidates[0, 1].any()


def test_eq_11_keeps_the_pairs_alone_in_their_row_and_column():
    pairs = np.zeros((4, 4), dtype=bool)
    pairs[0, 0] = pairs[1, 1] = pairs[1, 2] = pairs[3, 3] = pairs[2, 3] = True
    assert np.argwhere(reference.one_to_one(pairs)).tolist() == [[0, 0]]
