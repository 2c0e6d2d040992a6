"""The fast CBM returns exactly the pairs, winner set size and runner-up of the loop-by-loop
transcription of eq. 5-13 (its own pairs, before the guided re-association beyond the paper)."""
import numpy as np
import pytest

from cbm import CBMParams, match
from evaluation.scenario import ScenarioParams, make_trial
from support.oracle import oracle
from support.scenes import street_scene

SETTINGS = [
    dict(heading="align", consensus=True, consensus_rule="paper"),
    dict(heading="fold", consensus=True, consensus_rule="paper"),
    dict(heading="align", consensus=True, consensus_rule="released", sigma3=1.0),
    dict(heading="fold", consensus=False),
]


def random_trial(seed: int):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 13))
    world = street_scene(n, rng, extent=float(rng.uniform(15, 40)))
    scenario = ScenarioParams(eta=float(rng.uniform(0.3, 1.0)), sigma_p=float(rng.choice([0.0, 0.2, 0.5])),
                              sigma_theta=float(rng.choice([0.0, 3.0, 10.0])), seed=seed)
    return make_trial(world, np.arange(n), scenario), rng


@pytest.mark.parametrize("setting", SETTINGS, ids=lambda s: "-".join(str(v) for v in s.values()))
@pytest.mark.parametrize("seed", range(50))
def test_fast_pairs_equal_oracle_pairs(seed, setting):
    trial, rng = random_trial(seed)
    params = CBMParams(sigma1=float(rng.choice([5.0, 10.0, 20.0])), sigma2=float(rng.choice([1.0, 3.0, 5.0])),
                       distance_limit=float(rng.choice([5.0, 20.0, 20.0])), **setting)
    assert len(trial.ego_boxes) <= 12 and len(trial.cav_boxes) <= 12
    result = match(trial.ego_boxes, trial.cav_boxes, init=trial.init, params=params)
    pairs, candidate_count, runner_up = oracle(trial.ego_boxes, trial.cav_boxes, trial.init, params.sigma1,
                                               params.sigma2, params.sigma3, params.distance_limit, params.consensus,
                                               params.consensus_rule, params.heading)
    np.testing.assert_array_equal(result.context_pairs, pairs)
    assert result.candidate_count == candidate_count
    assert result.runner_up_count == runner_up
