"""The runner-up search gives the same result on the calling thread, on the two threads, and left
running on the pool while the winner is verified."""
import numpy as np
import pytest

from cbm import CBMParams, match, selection

from .join_reference import NOISE, layouts

WAYS = {"calling thread": (2**62, (0, 0)), "two threads": (0, (0, 0)), "on the pool meanwhile": (2**62, (0, 2**62))}
"""(``RIVAL_THREADS_FROM``, ``RIVAL_APART``) of each way the search can run."""


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_runner_up_is_the_same_whichever_way_the_search_runs(layout, monkeypatch):
    from evaluation.scenario import ScenarioParams, make_trial

    _, boxes, ids = next(entry for entry in layouts(200) if entry[0] == layout)
    t = make_trial(boxes, ids, ScenarioParams(**NOISE, seed=3))
    results = {}
    for way, (threads_from, apart) in WAYS.items():
        monkeypatch.setattr(selection, "RIVAL_THREADS_FROM", threads_from)
        monkeypatch.setattr(selection, "RIVAL_APART", apart)
        results[way] = match(t.ego_boxes, t.cav_boxes, t.init, CBMParams(sigma2=4.0))
    one = results.pop("calling thread")
    assert one.runner_up_count > 0
    for way, other in results.items():
        assert other.runner_up_count == one.runner_up_count, way
        np.testing.assert_array_equal(other.pairs, one.pairs)
        np.testing.assert_array_equal(other.transform, one.transform)


def test_without_a_listing_the_search_is_left_running_on_the_pool(monkeypatch):
    from evaluation.scenario import ScenarioParams, make_trial

    _, boxes, ids = next(entry for entry in layouts(200) if entry[0] == "street")
    t = make_trial(boxes, ids, ScenarioParams(**NOISE, seed=3))
    started = []
    submit = selection.POOL.submit
    monkeypatch.setattr(selection, "RIVAL_APART", (0, 2**62))
    monkeypatch.setattr(selection.POOL, "submit", lambda *a, **k: started.append(a[0]) or submit(*a, **k))
    result = match(t.ego_boxes, t.cav_boxes, t.init, CBMParams(sigma2=4.0))
    assert selection.strongest_rival in started and result.runner_up_count > 0
