"""A threshold edit reruns only the join's pass that depends on it: card(L_ij) on (sigma1, sigma2),
the voting sets on (sigma1, sigma3); the results stay those of a fresh match."""
import numpy as np
import pytest

from cbm import CBMParams
from cbm.reuse import Reuse

from .test_reuse import outcome, trial

STEPS = [
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


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_each_edit_recomputes_only_what_depends_on_its_threshold(layout):
    t, reuse = trial(layout, 2), Reuse()
    for edit, counts, voting_sets in STEPS:
        with_reuse, fresh = outcome(t, CBMParams(**edit), reuse), outcome(t, CBMParams(**edit), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], fresh[key], err_msg=f"{edit}: {key}")
        prepared = next(iter(reuse._entries.values()))
        assert (prepared.passes("count"), prepared.passes("votes")) == (counts, voting_sets), edit
    assert (reuse.misses, reuse.hits) == (1, len(STEPS) - 1)


def test_a_new_input_computes_both_again():
    reuse = Reuse()
    outcome(trial("street", 0), CBMParams(), reuse)
    outcome(trial("street", 1), CBMParams(), reuse)
    assert [(p.passes("count"), p.passes("votes")) for p in reuse._entries.values()] == [(1, 1), (1, 1)]


def test_the_kept_counts_and_voting_sets_count_in_the_memory_budget():
    t, reuse = trial("dense", 0), Reuse()
    outcome(t, CBMParams(), reuse)
    kept = next(iter(reuse._entries.values())).kept
    before = reuse.nbytes()
    count, voted_by = kept.pop("count")[1], kept.pop("voted_by")[1]
    assert before - reuse.nbytes() == count.nbytes + voted_by.start.nbytes + voted_by.member.nbytes > 0
