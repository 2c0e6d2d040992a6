"""The join's packed votes (``VoteRows``) give the same voting sets in either packing, and grouped
in one run or in several at once."""
import numpy as np
import pytest

from cbm import CBMParams
from cbm.engine import join
from cbm.engine.context import prepare
from cbm.engine.counting import counts_and_votes
from cbm.engine.voting import voted_by_member
from cbm.warmup import scene


def voting_sets(ego, cav, init, params):
    ready = prepare(ego, cav, init, params.heading)
    _, votes = counts_and_votes(ready, params.sigma1_rad, params.sigma2, params.sigma3)
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


@pytest.mark.parametrize("threads", [2, 3, 8])
def test_the_voting_sets_grouped_in_runs_at_once_are_the_same_as_in_one_run(threads, tuned):
    ego, cav, init = scene(60)
    params = CBMParams(sigma3=2.0)
    ready = prepare(ego, cav, init, params.heading)
    grouped = {}
    for runs, threshold in ((1, float("inf")), (threads, 0)):
        tuned(GROUP_PARTS_FROM=0, threads=4)
        _, votes = counts_and_votes(ready, params.sigma1_rad, params.sigma2, params.sigma3)
        assert len(votes) > threads
        tuned(threads=runs, VOTES_APART_FROM=threshold)
        grouped[runs] = voted_by_member(votes, ready.signs.size)
        assert votes == []
    assert grouped[1].member.size > len(ego)
    np.testing.assert_array_equal(grouped[threads].start, grouped[1].start)
    np.testing.assert_array_equal(grouped[threads].member, grouped[1].member)
