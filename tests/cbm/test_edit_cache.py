"""A threshold edit reuses what CBM built for the same input (``cbm.engine.EditCache``): it reruns
only the join's pass that depends on the edited threshold, reads the members listed at a larger
sigma2 again, and its results stay those of a fresh match."""
import numpy as np
import pytest

from cbm import CBMParams, match
from cbm.engine import EditCache, Reuse, listing
from cbm.engine.cache import Keyed
from cbm.engine.candidates import members_into, members_room
from cbm.engine.context import prepare
from cbm.engine.listing import NO_LISTING, listed_into

from .join_reference import NOISE, layouts

EDITS = [dict(), dict(sigma2=2.0), dict(sigma2=4.5), dict(sigma1=15.0), dict(sigma3=0.5), dict(consensus=False),
         dict(sigma2=8.0), dict(consensus_rule="paper", sigma3=3.0), dict(heading="fold")]
"""From the defaults, one edit after the other, as a user makes them (the last one a new input)."""
PASSES = [
    (dict(), 1, 1),
    (dict(sigma2=2.5), 2, 1),
    (dict(sigma2=2.5, sigma3=0.7), 2, 2),
    (dict(sigma2=3.5, sigma3=0.7), 3, 2),
    (dict(sigma1=12.0, sigma2=3.5, sigma3=0.7), 4, 3),
    (dict(sigma1=12.0, sigma2=3.5, sigma3=0.7, consensus=False), 4, 3),
    (dict(sigma1=12.0, sigma2=3.5, sigma3=0.7, consensus_rule="paper"), 4, 3),
    (dict(sigma1=12.0, sigma2=3.5, sigma3=4.0), 4, 4),
    (dict(sigma1=12.0, sigma2=2.0, sigma3=4.0), 5, 4),
]
"""Edits one after the other, and how many times the join counted and listed the votes after
each: a sigma2 edit counts, a sigma3 edit lists the votes, a sigma1 edit does both; the consensus
off and on again, or another rule, changes neither."""
SIGMA2_EDITS = [3.0, 2.0, 2.5, 4.0, 1.5, 4.0, 3.5]
"""A user dragging sigma2 down and up again."""


def trial(layout: str, seed: int):
    from evaluation.scenario import ScenarioParams, make_trial

    name, boxes, ids = next(entry for entry in layouts(60) if entry[0] == layout)
    return make_trial(boxes, ids, ScenarioParams(**NOISE, seed=seed))


def outcome(t, params: CBMParams, reuse: Reuse | None) -> dict:
    """The match of ``t`` under ``params``, its candidate counts and its voting sets (each as a set)."""
    result = match(t.ego_boxes, t.cav_boxes, t.init, params, reuse=reuse, explain=True)
    sets = result.explanation.sets
    voted_by, n_pairs = sets.voted_by, len(sets.candidates.count)
    owner = np.repeat(np.arange(n_pairs), np.diff(voted_by.start))
    return dict(pairs=result.pairs, transform=result.transform, counts=sets.candidates.count,
                votes=np.sort(owner * n_pairs + voted_by.member), starts=voted_by.start,
                selection=(result.candidate_count, result.consensus_count, result.runner_up_count))


def only_cache(reuse: Reuse) -> EditCache:
    return next(iter(reuse._entries.values()))


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_threshold_edits_reuse_the_input_and_give_the_same_results(layout):
    t, reuse = trial(layout, 0), Reuse()
    for edit in EDITS:
        with_reuse, without = outcome(t, CBMParams(**edit), reuse), outcome(t, CBMParams(**edit), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], without[key], err_msg=f"{edit}: {key}")
    assert (reuse.misses, reuse.hits) == (2, len(EDITS) - 2)


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_each_edit_recomputes_only_what_depends_on_its_threshold(layout):
    t, reuse = trial(layout, 2), Reuse()
    for edit, counts, voting_sets in PASSES:
        with_reuse, fresh = outcome(t, CBMParams(**edit), reuse), outcome(t, CBMParams(**edit), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], fresh[key], err_msg=f"{edit}: {key}")
        passes = only_cache(reuse).passes
        assert (passes["count"], passes["votes"]) == (counts, voting_sets), edit
    assert (reuse.misses, reuse.hits) == (1, len(PASSES) - 1)


def test_an_edit_keeps_the_grids_and_sorted_blocks_and_a_wide_radius_rebuilds_the_grids():
    t, reuse = trial("street", 1), Reuse()
    outcome(t, CBMParams(), reuse)
    cache = only_cache(reuse)
    grids, blocks = dict(cache.grids.by_group), cache.blocks
    outcome(t, CBMParams(sigma1=20.0, sigma2=4.0), reuse)
    assert cache.blocks is blocks and all(cache.grids.by_group[k] is grid for k, grid in grids.items())
    outcome(t, CBMParams(sigma2=9.0), reuse)
    assert not any(cache.grids.by_group[k] is grid for k, grid in grids.items())


def test_a_noise_or_frame_change_is_a_new_input_and_only_the_latest_inputs_are_kept():
    reuse = Reuse(frames=2)
    trials = [trial("street", seed) for seed in range(3)]
    for t in trials:
        outcome(t, CBMParams(), reuse)
    assert (reuse.misses, reuse.hits, len(reuse)) == (3, 0, 2)
    outcome(trials[2], CBMParams(sigma2=2.5), reuse)
    outcome(trials[0], CBMParams(), reuse)
    assert (reuse.misses, reuse.hits, len(reuse)) == (4, 1, 2)
    assert [(c.passes["count"], c.passes["votes"]) for c in reuse._entries.values()] == [(2, 1), (1, 1)]


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


def test_the_kept_counts_and_voting_sets_count_in_the_memory_budget():
    t, reuse = trial("dense", 0), Reuse()
    outcome(t, CBMParams(), reuse)
    cache = only_cache(reuse)
    before = reuse.nbytes()
    count, voted_by = cache.counts.value, cache.voting.value
    cache.counts, cache.voting = Keyed(), Keyed()
    assert before - reuse.nbytes() == count.nbytes + voted_by.start.nbytes + voted_by.member.nbytes > 0


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_sigma2_edits_read_the_listing_and_give_the_results_of_a_fresh_match(layout):
    t, reuse = trial(layout, 2), Reuse()
    listed_at = []
    for sigma2 in SIGMA2_EDITS:
        with_reuse, without = outcome(t, CBMParams(sigma2=sigma2), reuse), outcome(t, CBMParams(sigma2=sigma2), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], without[key], err_msg=f"sigma2={sigma2}: {key}")
        listed_at.append(only_cache(reuse).listing.value.sigma2)
    assert listed_at == [3.0, 3.0, 3.0, 4.0, 4.0, 4.0, 4.0]
    assert np.count_nonzero(only_cache(reuse).listing.value.arrays.at >= 0) > 0


def candidate_sets(cache: EditCache, sigma2: float):
    params = CBMParams(sigma2=sigma2)
    count2, _ = cache.local_matching(params.sigma1_rad, sigma2, None)
    return cache.candidate_sets(params.sigma1_rad, sigma2, count2)


def new_cache(layout: str) -> EditCache:
    t = trial(layout, 3)
    return EditCache(prepare(t.ego_boxes, t.cav_boxes, t.init, CBMParams().heading))


def assert_same_listing(sets, arguments) -> None:
    """Every seventh anchor's members read through ``listed_into`` equal those listed anew."""
    for anchor in np.flatnonzero(sets.count)[::7]:
        i, j = divmod(int(anchor), sets.signs.shape[1])
        got, want = members_room(sets.width + 1), members_room(sets.width + 1)
        size = listed_into(i, j, sets.signs[i, j], sets.lookup, sets.sigma2, arguments, got)
        assert size == members_into(i, j, sets.signs[i, j], sets.lookup, sets.sigma2, want)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g[:size], w[:size], err_msg=f"anchor {anchor}")


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_a_set_read_from_a_wider_listing_is_the_set_listed_anew(layout):
    cache = new_cache(layout)
    wide = candidate_sets(cache, 4.0)
    assert_same_listing(wide, wide.listing.arrays)
    narrow = candidate_sets(cache, 2.0)
    assert narrow.listing is wide.listing and narrow.listing.sigma2 == 4.0
    assert np.count_nonzero(narrow.listing.arrays.at >= 0) > 0
    assert_same_listing(narrow, narrow.listing.arrays)


def test_a_full_listing_lists_again_what_it_has_no_room_for(monkeypatch):
    monkeypatch.setattr(listing, "CAPACITY", 200)
    cache = new_cache("street")
    wide = candidate_sets(cache, 4.0)
    assert_same_listing(wide, wide.listing.arrays)
    assert 0 < wide.listing.arrays.fill[0] <= 200
    narrow = candidate_sets(cache, 2.5)
    assert_same_listing(narrow, narrow.listing.arrays)


@pytest.mark.parametrize("writers", [2, 3, 5])
def test_writers_listing_at_once_leave_the_listing_as_one_writer_would(writers):
    cache = new_cache("dense")
    sets = candidate_sets(cache, 4.0)
    anchors = np.flatnonzero(sets.count)
    parts = listing.writers(sets.listing, writers)
    for k, part in enumerate(parts):
        for anchor in anchors[k::writers]:
            i, j = divmod(int(anchor), sets.signs.shape[1])
            listed_into(i, j, sets.signs[i, j], sets.lookup, sets.sigma2, part, members_room(sets.width + 1))
    listing.closed_up(sets.listing, parts)
    arrays = sets.listing.arrays
    kept = np.flatnonzero(arrays.at >= 0)
    assert len(kept) == len(anchors) and int(arrays.fill[0]) == int(arrays.length[kept].sum())
    assert_same_listing(sets, arrays)


def test_without_an_edit_cache_nothing_is_listed_to_keep():
    from cbm.engine import candidate_sets as fresh_sets
    from cbm.engine.counting import counts_and_votes

    t = trial("street", 3)
    params = CBMParams()
    ready = prepare(t.ego_boxes, t.cav_boxes, t.init, params.heading)
    count2, _ = counts_and_votes(ready, params.sigma1_rad, params.sigma2, None)
    sets = fresh_sets(ready, params.sigma1_rad, params.sigma2, count2)
    assert sets.listing is None
    assert_same_listing(sets, NO_LISTING)


DISTANCE_EDITS = [dict(), dict(sigma2=2.0), dict(sigma2=2.9), dict(sigma2=1.0), dict(sigma2=3.0, sigma3=0.7),
                  dict(sigma2=3.5), dict(sigma1=12.0, sigma2=3.5), dict(sigma1=12.0, sigma2=3.0)]
"""Edits one after the other: the first sigma2 edit keeps the distances within 1.5 x 2.0 m, the
next edits up to 3.0 m count from them, 3.5 m keeps them anew, a sigma1 edit counts with the join."""
KEPT_AFTER = [0, 1, 1, 1, 1, 2, 2, 3]
"""How many times the distances were kept after each edit."""


@pytest.mark.parametrize("tuning", [{}, dict(threads=3, DISTANCES_APART_FROM=0, COUNT_APART_FROM=0)],
                         ids=["as-tuned", "on-three-threads"])
@pytest.mark.parametrize("layout", ["street", "dense"])
def test_sigma2_edits_count_from_the_kept_distances_and_give_a_fresh_matchs_results(layout, tuning, tuned):
    tuned(**tuning)
    t, reuse = trial(layout, 3), Reuse()
    for edit, kept in zip(DISTANCE_EDITS, KEPT_AFTER):
        with_reuse, fresh = outcome(t, CBMParams(**edit), reuse), outcome(t, CBMParams(**edit), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], fresh[key], err_msg=f"{edit}: {key}")
        assert only_cache(reuse).passes["distances"] == kept, edit
    assert only_cache(reuse).passes["count"] == len(DISTANCE_EDITS)


def test_past_the_most_quadruples_the_join_counts_and_the_distances_are_not_kept_again(monkeypatch):
    from cbm.engine import distances

    monkeypatch.setattr(distances, "MOST_QUADRUPLES", 100)
    t, reuse = trial("street", 4), Reuse()
    for edit in (dict(), dict(sigma2=2.0), dict(sigma2=2.5), dict(sigma2=4.0)):
        with_reuse, fresh = outcome(t, CBMParams(**edit), reuse), outcome(t, CBMParams(**edit), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], fresh[key], err_msg=f"{edit}: {key}")
    cache = only_cache(reuse)
    assert cache.passes["distances"] == 1 and cache.distances.value.anchor is None


def test_the_kept_distances_count_in_the_memory_budget():
    t, reuse = trial("dense", 0), Reuse()
    outcome(t, CBMParams(), reuse)
    before = reuse.nbytes()
    outcome(t, CBMParams(sigma2=2.0), reuse)
    kept = only_cache(reuse).distances.value
    assert len(kept.anchor) > 0 and reuse.nbytes() - before >= kept.anchor.nbytes + kept.distance.nbytes
