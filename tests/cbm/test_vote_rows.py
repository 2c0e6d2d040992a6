"""The join's packed votes (``VoteRows``) give the same voting sets in either packing, and grouped
in one pass or in two halves at once."""
import numpy as np

from cbm import CBMParams
from cbm.consensus import voted_by_member
from cbm.local_matching import join
from cbm.local_matching.counting import counts_and_votes
from cbm.reuse import prepare
from cbm.warmup import scene


def voting_sets(ego, cav, init, params):
    ready = prepare(ego, cav, init, params.heading)
    _, votes = counts_and_votes(ready.ego_context, ready.cav_context, ready.ego_heading, ready.signs,
                                params.sigma1_rad, params.sigma2, params.sigma3)
    return voted_by_member(votes, ready.signs.size)


def test_the_wide_packing_gives_the_same_voting_sets(monkeypatch):
    ego, cav, init = scene(40)
    params = CBMParams(sigma3=3.0)
    narrow = voting_sets(ego, cav, init, params)
    monkeypatch.setattr(join, "packing", lambda n_ego, n_cav: (np.int64, 32))
    wide = voting_sets(ego, cav, init, params)
    assert narrow.member.size > len(ego)
    np.testing.assert_array_equal(narrow.start, wide.start)
    np.testing.assert_array_equal(narrow.member, wide.member)


def test_the_narrow_packing_holds_objects_up_to_15_bits():
    assert join.packing(2**15 - 1, 2**15 - 1) == (np.int32, 16)
    assert join.packing(2**15, 3) == (np.int64, 32)




def test_the_voting_sets_grouped_in_two_halves_at_once_are_the_same_as_in_one_pass(monkeypatch):
    ego, cav, init = scene(60)
    params = CBMParams(sigma3=2.0)
    ready = prepare(ego, cav, init, params.heading)
    grouped = {}
    for halves in (False, True):
        _, votes = counts_and_votes(ready.ego_context, ready.cav_context, ready.ego_heading, ready.signs,
                                    params.sigma1_rad, params.sigma2, params.sigma3)
        assert len(votes) > 2
        grouped[halves] = voted_by_member(votes, ready.signs.size, halves=halves)
        assert votes == []
    assert grouped[False].member.size > len(ego)
    np.testing.assert_array_equal(grouped[True].start, grouped[False].start)
    np.testing.assert_array_equal(grouped[True].member, grouped[False].member)
