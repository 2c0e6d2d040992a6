"""Nothing the engine returns depends on its threads: at 1, 2, 4 and 8 threads with every hand-over
taken, a match gives the pairs, transform, counts, voting sets and visited sets of one thread with
none taken, fresh and through threshold edits (the listing then written by several threads at once);
and so does the runner-up search run beside the verification."""
from __future__ import annotations

import numpy as np
import pytest

from cbm import CBMParams, match
from cbm.engine import Reuse, rival, tuning

from .conftest import NEVER
from .join_reference import NOISE, layouts

EDITS = [dict(sigma2=4.0), dict(sigma2=2.5), dict(sigma2=3.0, consensus_rule="paper", sigma3=3.0), dict(sigma3=0.5),
         dict(sigma1=15.0)]
"""Threshold edits one after the other on one input, as a user makes them."""
SHARE_EARLY = dict(VISIT_FIRST=4, RIVAL_FIRST=4, RIVAL_CHUNK=64)
"""The visit and the runner-up search share out all but their first few anchors."""


def trial(layout: str, seed: int = 3):
    from evaluation.scenario import ScenarioParams, make_trial

    _, boxes, ids = next(entry for entry in layouts(120) if entry[0] == layout)
    return make_trial(boxes, ids, ScenarioParams(**NOISE, seed=seed))


def outcome(t, params: CBMParams, reuse: Reuse | None = None) -> dict:
    """Everything a match computed that a thread could change (the voting sets as sets: the join's
    parts may list a set's votes in another order, which no count reads)."""
    result = match(t.ego_boxes, t.cav_boxes, t.init, params, reuse=reuse, explain=True)
    sets, visit = result.explanation.sets, result.explanation.visit
    voted_by, n_pairs = sets.voted_by, len(sets.candidates.count)
    owner = np.repeat(np.arange(n_pairs), np.diff(voted_by.start))
    return dict(pairs=result.pairs, transform=result.transform, context_pairs=result.context_pairs,
                counts=sets.candidates.count, voting=np.sort(owner * n_pairs + voted_by.member),
                selection=np.array([result.candidate_count, result.runner_up_count, result.hypotheses]),
                visited_sizes=visit.sizes, visited_members=visit.members)


def assert_same(got: dict, want: dict, what: str) -> None:
    for key, value in want.items():
        np.testing.assert_array_equal(got[key], value, err_msg=f"{what}: {key}")


@pytest.mark.parametrize("threads", [1, 2, 4, 8])
@pytest.mark.parametrize("heading", ["align", "fold"])
@pytest.mark.parametrize("layout", ["street", "dense"])
def test_a_match_is_the_same_at_any_thread_count(layout, heading, threads, tuned):
    t, params = trial(layout), CBMParams(heading=heading, sigma2=4.0)
    tuned(threads=1, every=NEVER)
    one = outcome(t, params)
    tuned(threads=threads, every=0, **SHARE_EARLY)
    assert_same(outcome(t, params), one, f"{threads} threads")


@pytest.mark.parametrize("threads", [2, 4, 8])
def test_threshold_edits_are_the_same_at_any_thread_count(threads, tuned):
    t, reuse = trial("dense", 5), Reuse()
    for edit in EDITS:
        tuned(threads=1, every=NEVER)
        fresh = outcome(t, CBMParams(**edit))
        tuned(threads=threads, every=0, **SHARE_EARLY)
        assert_same(outcome(t, CBMParams(**edit), reuse), fresh, f"{edit} on {threads} threads")
    listing = next(iter(reuse._entries.values())).listing.value
    used = int(listing.arrays.fill[0])
    listed = np.flatnonzero(listing.arrays.at >= 0)
    assert len(listed) > 0 and used == int(listing.arrays.length[listed].sum())


def test_the_runner_up_search_beside_the_verification_finds_the_same(tuned, monkeypatch):
    t, params = trial("street"), CBMParams(sigma2=4.0)
    tuned(threads=2, every=NEVER)
    alone = outcome(t, params)
    beside = []
    shared_out = rival.shared_out
    monkeypatch.setattr(rival, "shared_out", lambda tasks: beside.append(len(tasks)) or shared_out(tasks))
    tuned(RIVAL_BESIDE_FROM=0, RIVAL_BESIDE_BELOW=NEVER)
    assert_same(outcome(t, params), alone, "beside")
    assert beside == [2] and alone["selection"][1] > 0


def test_the_thread_count_follows_the_cpus_this_process_may_use_or_cbm_threads(monkeypatch):
    import os

    monkeypatch.delenv("CBM_THREADS", raising=False)
    assert tuning.available_threads() == len(os.sched_getaffinity(0))
    monkeypatch.setenv("CBM_THREADS", "3")
    assert tuning.available_threads() == 3
    monkeypatch.setenv("CBM_THREADS", "many")
    with pytest.raises(ValueError, match="CBM_THREADS must be a positive integer, got 'many'"):
        tuning.available_threads()


def test_shared_out_gives_results_in_order_and_runs_inline_where_a_pool_thread_could_wait(tuned):
    import threading

    from cbm.engine.interpreted import COMPILE_LOCK as LOCK
    from cbm.engine.threads import shared_out

    tuned(threads=4)
    assert shared_out([lambda k=k: k * k for k in range(20)]) == [k * k for k in range(20)]
    met = threading.Barrier(4, timeout=120)
    names = shared_out([lambda: met.wait() * 0 or threading.current_thread().name for _ in range(4)])
    assert len(set(names)) == 4
    with LOCK:
        assert set(shared_out([lambda: threading.current_thread().name for _ in range(8)])) == {
            threading.current_thread().name}
    nested = shared_out([lambda: shared_out([lambda: threading.current_thread().name] * 4)])
    assert len(set(nested[0])) == 1


def test_an_exception_in_a_shared_out_task_reaches_the_caller(tuned):
    from cbm.engine.threads import shared_out

    tuned(threads=3)

    def fail():
        raise RuntimeError("part 5 failed")

    with pytest.raises(RuntimeError, match="part 5 failed"):
        shared_out([lambda: 1] * 5 + [fail] + [lambda: 2] * 5)
