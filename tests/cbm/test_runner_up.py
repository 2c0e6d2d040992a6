"""The runner-up of eq. 13 (the largest filtered set sharing no pair with the winner) is the one a
search over every anchor finds, under each consensus rule, whatever the search skips."""
import numpy as np
import pytest

from cbm import CBMParams
from cbm.pipeline import build_sets, checked_inputs
from cbm.selection import filtered_members, kernel_arguments, select
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene

RULES = [dict(consensus=True, consensus_rule="paper", sigma3=3.0),
         dict(consensus=True, consensus_rule="paper", sigma3=1.0),
         dict(consensus=True, consensus_rule="released", sigma3=1.0),
         dict(consensus=False)]


def runner_up_over_every_anchor(sets, winner: np.ndarray) -> int:
    """The largest filtered set among all anchors whose set holds none of ``winner``'s pair ids."""
    L = sets.candidates
    common = kernel_arguments(L, sets.voted_by, sets.rule, sets.ego_xy, sets.cav_xy, sets.params.distance_limit)
    largest = 0
    for anchor in np.flatnonzero(L.count):
        members = filtered_members(int(anchor), L, common)
        if not np.isin(members, winner).any():
            largest = max(largest, len(members))
    return largest


@pytest.mark.parametrize("rule", RULES, ids=lambda r: "-".join(str(v) for v in r.values()))
@pytest.mark.parametrize("seed", range(12))
def test_the_runner_up_is_the_largest_set_sharing_no_pair_with_the_winner(seed, rule):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(25, 60))
    world = street_scene(n, rng, extent=float(rng.uniform(30, 60)))
    trial = make_trial(world, np.arange(n), ScenarioParams(eta=float(rng.uniform(0.4, 0.9)), sigma_p=0.3,
                                                           sigma_theta=3.0, seed=seed))
    params = CBMParams(sigma2=float(rng.choice([2.0, 3.0, 4.0])), **rule)
    ego, cav, init, params = checked_inputs(trial.ego_boxes, trial.cav_boxes, trial.init, params)
    sets = build_sets(ego, cav, init, params)
    chosen = select(sets.candidates, sets.voted_by, sets.rule, sets.ego_xy, sets.cav_xy, params.distance_limit)
    winner = chosen.pairs[:, 0] * len(cav) + chosen.pairs[:, 1]
    assert chosen.runner_up_count == runner_up_over_every_anchor(sets, winner)
