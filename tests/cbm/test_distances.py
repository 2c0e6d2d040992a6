"""A sigma2 edit counts card(L_ij) from the quadruples' kept distances; the counts, pairs and
transforms stay those of a fresh match."""
import numpy as np
import pytest

from cbm import CBMParams
from cbm.local_matching import distances
from cbm.reuse import Reuse

from .test_reuse import outcome, trial

EDITS = [dict(), dict(sigma2=2.0), dict(sigma2=2.9), dict(sigma2=1.0), dict(sigma2=3.0, sigma3=0.7),
         dict(sigma2=3.5), dict(sigma1=12.0, sigma2=3.5), dict(sigma1=12.0, sigma2=3.0)]
"""Edits one after the other: the first sigma2 edit keeps the distances within 1.5 x 2.0 m, the
next edits up to 3.0 m count from them, 3.5 m keeps them anew, a sigma1 edit counts with the join."""
KEPT_AFTER = [0, 1, 1, 1, 1, 2, 2, 3]
"""How many times the distances were kept after each edit."""


def passes(reuse: Reuse, name: str) -> int:
    return next(iter(reuse._entries.values())).passes(name)


@pytest.mark.parametrize("threads_from", [(distances.PARALLEL_FROM, distances.COUNT_APART_FROM), (0, 0)],
                         ids=["as-shipped", "both-threads"])
@pytest.mark.parametrize("layout", ["street", "dense"])
def test_sigma2_edits_count_from_the_kept_distances_and_give_a_fresh_matchs_results(layout, threads_from, monkeypatch):
    monkeypatch.setattr(distances, "PARALLEL_FROM", threads_from[0])
    monkeypatch.setattr(distances, "COUNT_APART_FROM", threads_from[1])
    t, reuse = trial(layout, 3), Reuse()
    for edit, kept in zip(EDITS, KEPT_AFTER):
        with_reuse, fresh = outcome(t, CBMParams(**edit), reuse), outcome(t, CBMParams(**edit), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], fresh[key], err_msg=f"{edit}: {key}")
        assert passes(reuse, "distances") == kept, edit
    assert passes(reuse, "count") == len(EDITS)


def test_past_the_most_quadruples_the_join_counts_and_the_distances_are_not_kept_again(monkeypatch):
    monkeypatch.setattr(distances, "MOST_QUADRUPLES", 100)
    t, reuse = trial("street", 4), Reuse()
    for edit in (dict(), dict(sigma2=2.0), dict(sigma2=2.5), dict(sigma2=4.0)):
        with_reuse, fresh = outcome(t, CBMParams(**edit), reuse), outcome(t, CBMParams(**edit), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], fresh[key], err_msg=f"{edit}: {key}")
    kept = next(iter(reuse._entries.values())).kept
    assert passes(reuse, "distances") == 1 and kept["distances"][1].anchor is None


def test_the_kept_distances_count_in_the_memory_budget():
    t, reuse = trial("dense", 0), Reuse()
    outcome(t, CBMParams(), reuse)
    before = reuse.nbytes()
    outcome(t, CBMParams(sigma2=2.0), reuse)
    kept = next(iter(reuse._entries.values())).kept["distances"][1]
    assert len(kept.anchor) > 0 and reuse.nbytes() - before >= kept.anchor.nbytes + kept.distance.nbytes
