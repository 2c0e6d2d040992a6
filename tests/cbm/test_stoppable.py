"""An abandoned computation stops (issue 40, item 1): within ``stoppable(should_stop)`` the engine
asks before each part of its work and between CBM's steps, and raises ``Cancelled`` once told; a
part already running ends first, and nothing else changes (the same answer when nobody stops it)."""
from __future__ import annotations

import threading

import numpy as np
import pytest

from cbm import match, se2
from cbm.engine import tuning
from cbm.engine.threads import Cancelled, check_stop, shared_out, stop_flag, stoppable


@pytest.fixture
def two_threads(monkeypatch):
    monkeypatch.setattr(tuning, "THREADS", 2)


def test_no_part_starts_once_the_computation_is_abandoned(two_threads) -> None:
    stop, ran = threading.Event(), []

    def part(k: int):
        def run() -> int:
            ran.append(k)
            if k == 1:
                stop.set()
            return k
        return run

    with stoppable(stop.is_set), pytest.raises(Cancelled):
        shared_out([part(k) for k in range(50)])
    assert 1 in ran and len(ran) < 50


def test_parts_on_the_pool_threads_can_ask_too(two_threads) -> None:
    stop = threading.Event()

    def asks() -> None:
        stop.set()
        check_stop()

    with stoppable(stop.is_set), pytest.raises(Cancelled):
        shared_out([asks, asks])


def scene(n: int = 80, seed: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    ego = np.column_stack([rng.uniform(-60, 60, (n, 2)), np.zeros(n), np.tile([4.5, 1.9, 1.6], (n, 1)),
                           rng.uniform(-np.pi, np.pi, n)])
    true = se2.make(10.0, -4.0, 0.3)
    return ego, se2.apply_boxes(se2.inverse(true), ego), true


def test_cbm_stops_between_its_steps_and_answers_the_same_when_not_stopped() -> None:
    ego, cav, true = scene()
    with stoppable(lambda: True), pytest.raises(Cancelled):
        match(ego, cav, true)
    asked = []
    with stoppable(lambda: asked.append(1) or False):
        kept = match(ego, cav, true)
    assert asked
    np.testing.assert_array_equal(kept.pairs, match(ego, cav, true).pairs)


def test_a_kernel_returns_at_its_next_check_once_the_flag_is_set() -> None:
    """Inside a compiled kernel the question is ``stop_flag()``: set, the join counts and lists
    nothing more (its caller then raises ``Cancelled``: the tests below)."""
    from cbm.engine.context import prepare
    from cbm.engine.grid import build_grid, group_signs, heading_groups
    from cbm.engine.join import EgoVectors, Test, joined

    ego, cav, true = scene(200)
    ready = prepare(ego, cav, true, "align")
    vectors = EgoVectors(ready.ego_context.vectors, ready.ego_context.member, len(ego) - 1)
    group = heading_groups(ready.ego_heading, ready.signs)[0]
    grid = build_grid(ready.cav_context, group_signs(ready.signs, group), 3.0)
    test = Test(np.cos(np.radians(10.0)) ** 2, 3.0, 1.0)

    def join() -> tuple[int, int]:
        counts = np.zeros(ready.signs.size, np.int64)
        rows = joined(group, grid, vectors, ready.signs, test, counts, 1)
        return int(counts.sum()), sum(len(part.rows) for part in rows)

    with stoppable(lambda: False):
        stop_flag()[0] = 1
        assert join() == (0, 0)
    counted, listed = join()
    assert counted > 0 and listed > 0


def test_the_watcher_sets_the_flag_the_kernels_read_and_nothing_outside_a_stoppable_block() -> None:
    told = threading.Event()
    with stoppable(told.is_set):
        flag = stop_flag()
        assert flag[0] == 0
        told.set()
        deadline = threading.Event()
        while not flag[0] and not deadline.wait(0.01):
            pass
        with pytest.raises(Cancelled):
            check_stop()
    assert stop_flag()[0] == 0


@pytest.mark.parametrize("edits", [dict(sigma2=2.0), dict(sigma3=0.5), dict(sigma1=15.0)])
def test_an_edit_stopped_inside_a_kernel_leaves_the_kept_results_as_a_fresh_match_finds_them(edits,
                                                                                           monkeypatch) -> None:
    """What the edit cache keeps is never what a stopped kernel returned: after an edit stopped
    inside its kernels (the flag set as the join takes its grid, after every check before it; one
    thread and one heading group, so no other part asks after it), the same edit left alone answers
    as a fresh match."""
    from cbm import CBMParams, match
    from cbm.engine import Reuse
    from cbm.engine.join import Grids

    monkeypatch.setattr(tuning, "THREADS", 1)
    ego, cav, true = scene(200)
    reuse, params = Reuse(), CBMParams(heading="fold", **edits)
    match(ego, cav, true, CBMParams(heading="fold"), reuse=reuse)
    grid = Grids.grid

    def grid_then_stop(self, *args):
        stop_flag()[0] = 1
        return grid(self, *args)

    with stoppable(lambda: False), monkeypatch.context() as patched:
        patched.setattr(Grids, "grid", grid_then_stop)
        with pytest.raises(Cancelled):
            match(ego, cav, true, params, reuse=reuse)
    kept = match(ego, cav, true, params, reuse=reuse)
    fresh = match(ego, cav, true, params)
    np.testing.assert_array_equal(kept.pairs, fresh.pairs)
    np.testing.assert_array_equal(kept.transform, fresh.transform)
