"""The runner-up of eq. 13 (the largest filtered set sharing no pair with the winner) is the one a
search over every anchor finds, under each consensus rule, whatever the search skips."""
import numpy as np
import pytest

from cbm import CBMParams
from cbm.engine import select
from cbm.engine.filtered import filtering
from cbm.engine.rival import runner_up
from cbm.engine.visit import filtered_members
from cbm.pipeline import checked_inputs
from cbm.sets import build_sets
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene

RULES = [dict(consensus=True, consensus_rule="paper", sigma3=3.0),
         dict(consensus=True, consensus_rule="paper", sigma3=1.0),
         dict(consensus=True, consensus_rule="released", sigma3=1.0),
         dict(consensus=False)]


def runner_up_over_every_anchor(sets, winner: np.ndarray) -> int:
    """The largest filtered set among all anchors whose set holds none of ``winner``'s pair ids."""
    L = sets.candidates
    f = filtering(L, sets.voted_by, sets.rule, sets.ego_xy, sets.cav_xy, sets.params.distance_limit)
    largest = 0
    for anchor in np.flatnonzero(L.count):
        members = filtered_members(int(anchor), L, f)
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
    assert runner_up(chosen.rival) == runner_up_over_every_anchor(sets, winner)


EDITS = [dict(sigma2=4.0), dict(sigma2=3.0), dict(sigma2=3.0, consensus_rule="paper", sigma3=3.0),
         dict(sigma2=2.5, consensus=False), dict(sigma2=4.0, sigma3=0.5), dict(sigma2=3.5, consensus_rule="paper")]
"""Edits at or below the first sigma2 that change the winner: the runner-up search reads the bounds
kept with the listing from the calls before."""


@pytest.mark.parametrize("seed", range(6))
def test_edits_that_read_kept_bounds_find_the_runner_up_of_a_fresh_match(seed):
    from cbm import match
    from cbm.engine import Reuse

    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(30, 60))
    world = street_scene(n, rng, extent=float(rng.uniform(30, 60)))
    trial = make_trial(world, np.arange(n), ScenarioParams(eta=0.6, sigma_p=0.3, sigma_theta=3.0, seed=seed))
    reuse = Reuse()
    for edit in EDITS:
        kept, fresh = (match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(**edit), reuse=r)
                       for r in (reuse, None))
        assert kept.runner_up_count == fresh.runner_up_count, edit
        np.testing.assert_array_equal(kept.pairs, fresh.pairs)


@pytest.mark.parametrize("seed", range(4))
def test_the_bound_kept_for_an_anchor_is_its_candidate_sets_own_whatever_the_winner(seed):
    """min(distinct ego objects, distinct CAV objects) of L_ij, never the 0 of a set the search
    skipped for holding the winner's pair: a later search with another winner reads it."""
    from cbm.engine import Reuse

    rng = np.random.default_rng(200 + seed)
    n = int(rng.integers(30, 60))
    world = street_scene(n, rng, extent=float(rng.uniform(30, 60)))
    trial = make_trial(world, np.arange(n), ScenarioParams(eta=0.8, sigma_p=0.2, sigma_theta=2.0, seed=seed))
    ego, cav, init, params = checked_inputs(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams())
    sets = build_sets(ego, cav, init, params, reuse=Reuse())
    L = sets.candidates
    runner_up(select(L, sets.voted_by, sets.rule, sets.ego_xy, sets.cav_xy, params.distance_limit).rival)
    kept = np.flatnonzero(L.listing.arrays.bound >= 0)
    assert len(kept) > 0
    for anchor in kept:
        members = L.members(int(anchor))
        own = min(len(np.unique(members // len(cav))), len(np.unique(members % len(cav))))
        assert L.listing.arrays.bound[anchor] == own
