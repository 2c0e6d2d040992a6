"""The coalescer: under a burst of concurrent submits only the latest value is delivered last,
results arrive in submission order, far fewer computations run than were asked for, and a failure
is reported without stopping the worker."""
from __future__ import annotations

import threading
import time

from app.session.coalesce import Coalescer, Later


def _collecting(compute_seconds: float = 0.005):
    delivered: list[tuple[int, int]] = []
    computed: list[int] = []
    failures: list[BaseException] = []

    def compute(value: int) -> int:
        computed.append(value)
        time.sleep(compute_seconds)
        if value < 0:
            raise ValueError("negative")
        return value

    worker = Coalescer(compute, lambda result, generation: delivered.append((result, generation)), failures.append)
    return worker, delivered, computed, failures


def test_concurrent_burst_draws_only_the_latest_state_last() -> None:
    worker, delivered, computed, _ = _collecting()
    lock = threading.Lock()
    latest = {"value": -1}
    counter = iter(range(10_000))

    def fire() -> None:
        for _ in range(50):
            with lock:
                value = next(counter)
                worker.submit(value)
                latest["value"] = value

    threads = [threading.Thread(target=fire) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert worker.wait_idle(timeout=10)
    worker.close()
    assert delivered[-1][0] == latest["value"]
    assert delivered[-1][1] == 400
    generations = [g for _, g in delivered]
    assert generations == sorted(generations) and len(set(generations)) == len(generations)
    assert len(computed) < 400 / 4


def test_failure_is_reported_and_the_worker_lives_on() -> None:
    worker, delivered, _, failures = _collecting(0.0)
    worker.submit(-1)
    assert worker.wait_idle(timeout=5)
    worker.submit(3)
    assert worker.wait_idle(timeout=5)
    worker.close()
    assert len(failures) == 1 and isinstance(failures[0], ValueError)
    assert delivered == [(3, 2)]


def test_a_slow_computation_never_piles_up_work() -> None:
    worker, delivered, computed, _ = _collecting(0.05)
    for value in range(100):
        worker.submit(value)
        time.sleep(0.001)
    assert worker.wait_idle(timeout=10)
    worker.close()
    assert computed[-1] == 99 and len(computed) <= 5


def test_later_runs_only_the_latest_of_a_burst_survives_a_failure_and_close_drops_a_pending_call() -> None:
    ran: list[int] = []
    done = threading.Event()
    later = Later(0.05)
    for k in range(5):
        later.call(lambda k=k: ran.append(k))
    later.call(lambda: (ran.append(9), done.set()))
    assert done.wait(10)
    assert ran == [9]
    failed = threading.Event()
    later.call(lambda: (failed.set(), 1 / 0))
    assert failed.wait(10)
    done.clear()
    later.call(lambda: done.set())
    assert done.wait(10)
    later.call(lambda: ran.append(10))
    later.close()
    time.sleep(0.15)
    assert ran == [9]
    done.clear()
    later.call(lambda: done.set())
    assert done.wait(10)
    later.close()


def test_a_computation_superseded_by_a_newer_edit_stops_early_and_is_not_shown() -> None:
    """A tab computes under ``stoppable(worker.superseded)`` (``ClientSession._compute``): a newer
    edit makes the engine raise ``Cancelled`` at its next check, and the result is never shown."""
    from cbm.engine.threads import Cancelled, check_stop, stoppable

    delivered, failed, started, checks = [], [], threading.Event(), []
    worker: Coalescer | None = None

    def compute(value: int) -> int:
        with stoppable(lambda: worker.superseded):
            started.set()
            for _ in range(10_000 if value == 1 else 1):
                checks.append(value)
                check_stop()
                time.sleep(0.01)
        return value

    worker = Coalescer(compute, lambda result, generation: delivered.append(result), failed.append)
    worker.submit(1)
    assert started.wait(60)
    worker.submit(2)
    assert worker.wait_idle(120)
    assert delivered == [2] and len(failed) == 1 and isinstance(failed[0], Cancelled)
    assert checks.count(1) < 10_000
    worker.close()
