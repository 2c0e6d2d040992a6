"""The runner-up search gives the same result on the calling thread as on the two threads."""
import numpy as np
import pytest

from cbm import CBMParams, match, selection

from .join_reference import NOISE, layouts


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_runner_up_is_the_same_on_one_thread_and_on_two(layout, monkeypatch):
    from evaluation.scenario import ScenarioParams, make_trial

    _, boxes, ids = next(entry for entry in layouts(200) if entry[0] == layout)
    t = make_trial(boxes, ids, ScenarioParams(**NOISE, seed=3))
    results = []
    for threads_from in (0, 2**62):
        monkeypatch.setattr(selection, "RIVAL_THREADS_FROM", threads_from)
        results.append(match(t.ego_boxes, t.cav_boxes, t.init, CBMParams(sigma2=4.0)))
    two, one = results
    assert two.runner_up_count == one.runner_up_count and two.runner_up_count > 0
    np.testing.assert_array_equal(two.pairs, one.pairs)
    np.testing.assert_array_equal(two.transform, one.transform)
