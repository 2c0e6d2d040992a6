"""An abandoned computation stops (issue 40, item 1): within ``stoppable(should_stop)`` the engine
asks before each part of its work and between CBM's steps, and raises ``Cancelled`` once told; a
part already running ends first, and nothing else changes (the same answer when nobody stops it)."""
from __future__ import annotations

import threading

import numpy as np
import pytest

from cbm import match, se2
from cbm.engine import tuning
from cbm.engine.threads import Cancelled, check_stop, shared_out, stoppable


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
