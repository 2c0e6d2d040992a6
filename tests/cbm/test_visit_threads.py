"""Eq. 13's visit gives the same anchors, sizes and members on the calling thread and shared out
between two threads, and two threads listing at once leave the listing as one thread would: every
set they kept reads back as listed anew, with no gap between their rows."""
import numpy as np
import pytest

from cbm import CBMParams, local_matching, selection, visit
from cbm.local_matching import listing
from cbm.pipeline import build_sets, checked_inputs, match_sets
from cbm.reuse import Reuse

from .join_reference import NOISE, layouts
from .test_listing import assert_same_listing, candidate_sets, listed

NEVER = 2**62
ONE_THREAD = {visit: dict(VISIT_FIRST=NEVER, VISIT_APART_FROM=(NEVER, NEVER)),
              selection: dict(RIVAL_THREADS_FROM=NEVER)}
SHARED_OUT = {visit: dict(VISIT_FIRST=8, VISIT_APART_FROM=(0, 0)), selection: dict(RIVAL_FIRST=8, RIVAL_THREADS_FROM=0)}
"""Module constants of the visit and the runner-up search that keep every anchor on the calling
thread, and that share out all but the first few."""


def trial(layout: str, seed: int = 3):
    from evaluation.scenario import ScenarioParams, make_trial

    _, boxes, ids = next(entry for entry in layouts(200) if entry[0] == layout)
    return make_trial(boxes, ids, ScenarioParams(**NOISE, seed=seed))


def visit_and_match(t, params: CBMParams, reuse: Reuse | None, constants: dict, monkeypatch):
    for module, values in constants.items():
        for name, value in values.items():
            monkeypatch.setattr(module, name, value)
    ego, cav, init, params = checked_inputs(t.ego_boxes, t.cav_boxes, t.init, params)
    sets = build_sets(ego, cav, init, params, reuse=reuse)
    chosen = selection.select(sets.candidates, sets.voted_by, sets.rule, sets.ego_xy, sets.cav_xy,
                              params.distance_limit)
    return chosen, match_sets(sets, init), sets


@pytest.mark.parametrize("layout", ["street", "dense"])
@pytest.mark.parametrize("rule", ["released", "paper"])
def test_the_visit_shared_out_is_the_visit_on_one_thread(layout, rule, monkeypatch):
    t, params = trial(layout), CBMParams(sigma2=4.0, consensus_rule=rule)
    one, one_result, _ = visit_and_match(t, params, None, ONE_THREAD, monkeypatch)
    handed = []
    submit = local_matching.POOL.submit
    monkeypatch.setattr(local_matching.POOL, "submit", lambda *a, **k: handed.append(a[0]) or submit(*a, **k))
    two, two_result, _ = visit_and_match(t, params, None, SHARED_OUT, monkeypatch)
    assert visit._visit_part in handed
    assert len(one.visit.sizes) > SHARED_OUT[visit]["VISIT_FIRST"]
    for field in ("order", "sizes", "offsets", "members"):
        np.testing.assert_array_equal(getattr(two.visit, field), getattr(one.visit, field), err_msg=field)
    assert (two.anchor, two.runner_up_count) == (one.anchor, one.runner_up_count)
    np.testing.assert_array_equal(two_result.pairs, one_result.pairs)
    np.testing.assert_array_equal(two_result.transform, one_result.transform)


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_sigma2_edits_listed_by_two_threads_give_the_results_of_one(layout, monkeypatch):
    t = trial(layout)
    kept_one, kept_two = Reuse(), Reuse()
    for sigma2 in (4.0, 3.0, 3.5, 4.5, 2.5):
        params = CBMParams(sigma2=sigma2)
        one, one_result, _ = visit_and_match(t, params, kept_one, ONE_THREAD, monkeypatch)
        two, two_result, sets = visit_and_match(t, params, kept_two, SHARED_OUT, monkeypatch)
        for field in ("order", "sizes", "offsets", "members"):
            np.testing.assert_array_equal(getattr(two.visit, field), getattr(one.visit, field), err_msg=field)
        assert two.runner_up_count == one.runner_up_count
        np.testing.assert_array_equal(two_result.pairs, one_result.pairs)
        kept = sets.candidates.listing
        listed_anchors = kept.at >= 0
        assert int(kept.fill[0]) == int(kept.length[listed_anchors].sum()), "rows kept twice or lost"
        ends = (kept.at + kept.length)[listed_anchors]
        assert int(ends.max()) == int(kept.fill[0]), "a gap between the threads' rows"
        assert_same_listing(sets.candidates, kept.arguments())


def test_two_writers_keep_their_sets_and_close_up():
    kept = {}
    sets = candidate_sets("dense", 4.0, kept)
    anchors = np.flatnonzero(sets.count)[:60]
    first, second, middle = listing.two_writers(sets.listing)
    for n, anchor in enumerate(anchors):
        listed(sets, int(anchor), first if n % 2 == 0 else second)
    theirs = anchors[1::2]
    assert (sets.listing.at[theirs] >= middle).all() and (sets.listing.at[anchors[::2]] < middle).all()
    listing.closed_up(sets.listing, second, middle)
    kept_rows = int(sets.listing.length[anchors].sum())
    assert int(sets.listing.fill[0]) == kept_rows > 0
    assert int((sets.listing.at[anchors] + sets.listing.length[anchors]).max()) == kept_rows
    for anchor in anchors:
        expected = listed(sets, int(anchor), listing.NO_LISTING.arguments())
        for got, want in zip(listed(sets, int(anchor), sets.listing.arguments()), expected):
            np.testing.assert_array_equal(got, want, err_msg=f"anchor {anchor}")


def test_the_parts_are_merged_in_order_up_to_where_one_pass_stops():
    """Part 0 visited positions 0, 2, 4, part 1 positions 1, 3: to the end of the order, then with
    part 1 a position past where one pass stops (it read the best size before part 0 raised it)."""
    def part(sizes):
        sizes = np.array(sizes, np.int64)
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        return sizes, offsets, np.concatenate([np.full(s, 10 * len(sizes) + s) for s in sizes]).astype(np.int64)

    counts, anchors = np.array([9, 8, 7, 7, 7]), np.arange(5)
    even, odd = part([5, 7, 6]), part([3, 4])
    sizes, members = visit._interleaved(anchors, counts, 0, [even, odd])
    np.testing.assert_array_equal(sizes, [5, 3, 7, 4, 6])
    np.testing.assert_array_equal(members, np.concatenate([even[2][:5], odd[2][:3], even[2][5:12], odd[2][3:],
                                                           even[2][12:]]))
    sizes, members = visit._interleaved(np.arange(6), np.array([9, 8, 7, 7, 6, 6]), 0,
                                        [part([5, 8, 2]), part([3, 4])])
    np.testing.assert_array_equal(sizes, [5, 3, 8])
    assert len(members) == 16
