"""A threshold edit reuses what CBM built for the same input; the results stay identical."""
import numpy as np
import pytest

from cbm import CBMParams
from cbm.pipeline import build_sets, checked_inputs, match_sets
from cbm.reuse import Reuse

from .join_reference import NOISE, layouts

EDITS = [dict(), dict(sigma2=2.0), dict(sigma2=4.5), dict(sigma1=15.0), dict(sigma3=0.5), dict(consensus=False),
         dict(sigma2=8.0), dict(consensus_rule="paper", sigma3=3.0), dict(heading="fold")]
"""From the defaults, one edit after the other, as a user makes them (the last one a new input)."""


def trial(layout: str, seed: int):
    from evaluation.scenario import ScenarioParams, make_trial

    name, boxes, ids = next(entry for entry in layouts(60) if entry[0] == layout)
    return make_trial(boxes, ids, ScenarioParams(**NOISE, seed=seed))


def outcome(t, params: CBMParams, reuse: Reuse | None) -> dict:
    """The match of ``t`` under ``params``, its candidate counts and its voting sets (each as a set)."""
    ego, cav, init, params = checked_inputs(t.ego_boxes, t.cav_boxes, t.init, params)
    sets = build_sets(ego, cav, init, params, reuse=reuse)
    result = match_sets(sets, init)
    voted_by, n_pairs = sets.voted_by, len(sets.candidates.count)
    owner = np.repeat(np.arange(n_pairs), np.diff(voted_by.start))
    return dict(pairs=result.pairs, transform=result.transform, counts=sets.candidates.count,
                votes=np.sort(owner * n_pairs + voted_by.member), starts=voted_by.start,
                selection=(result.candidate_count, result.consensus_count, result.runner_up_count))


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_threshold_edits_reuse_the_input_and_give_the_same_results(layout):
    t, reuse = trial(layout, 0), Reuse()
    for edit in EDITS:
        with_reuse, without = outcome(t, CBMParams(**edit), reuse), outcome(t, CBMParams(**edit), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], without[key], err_msg=f"{edit}: {key}")
    assert (reuse.misses, reuse.hits) == (2, len(EDITS) - 2)


def test_an_edit_keeps_the_grids_and_sorted_blocks_and_a_wide_radius_rebuilds_the_grids():
    t, reuse = trial("street", 1), Reuse()
    outcome(t, CBMParams(), reuse)
    kept = next(iter(reuse._entries.values())).kept
    grids, blocks = dict(kept["grids"]), kept["blocks"]
    outcome(t, CBMParams(sigma1=20.0, sigma2=4.0), reuse)
    assert kept["blocks"] is blocks and all(kept["grids"][k] is grid for k, grid in grids.items())
    outcome(t, CBMParams(sigma2=9.0), reuse)
    assert not any(kept["grids"][k] is grid for k, grid in grids.items())


def test_a_noise_or_frame_change_is_a_new_input_and_only_the_latest_inputs_are_kept():
    reuse = Reuse(frames=2)
    trials = [trial("street", seed) for seed in range(3)]
    for t in trials:
        outcome(t, CBMParams(), reuse)
    assert (reuse.misses, reuse.hits, len(reuse)) == (3, 0, 2)
    outcome(trials[2], CBMParams(sigma2=2.5), reuse)
    outcome(trials[0], CBMParams(), reuse)
    assert (reuse.misses, reuse.hits, len(reuse)) == (4, 1, 2)


def test_past_the_memory_budget_only_the_latest_inputs_are_kept():
    trials = [trial("dense", seed) for seed in range(3)]
    probe = Reuse()
    outcome(trials[0], CBMParams(), probe)
    one = probe.nbytes()
    assert one > 0
    reuse = Reuse(frames=4, most_bytes=int(1.5 * one))
    for t in trials:
        outcome(t, CBMParams(), reuse)
    outcome(trials[2], CBMParams(sigma1=12.0), reuse)
    assert reuse.hits == 1 and len(reuse) == 1 and reuse.nbytes() <= 1.5 * one
