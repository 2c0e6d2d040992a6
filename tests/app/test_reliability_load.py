"""Fair under load (issue 16, part 4): a short ``bench/load.py`` (3 tabs × 5 edits at once, one
tab's run over every frame going on) shows every edit within 10 s with no server traceback; long
jobs of all tabs share a bounded, first-come-first-served pool, a queued job says it waits, and a
tab closed while its job waits leaves the queue."""
from __future__ import annotations

import sys
import threading
from pathlib import Path

import pytest

from app.server import ExplorerServer
from app.session.background import LONG_JOBS, Cancelled, Slots, Task
from app.session.settings import Settings
from support.browser import open_page, requires_chromium, wait_until

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

import load  # noqa: E402


def _task() -> Task:
    return Task(lambda fraction: None)


def test_slots_run_in_turn_and_a_cancelled_waiter_leaves_the_queue() -> None:
    slots, order, said = Slots(1), [], []
    holder = _task()
    slots.acquire(holder, said.append)
    first, second = _task(), _task()

    def wait_for(task: Task, name: str) -> None:
        try:
            slots.acquire(task, said.append)
        except Cancelled:
            order.append(f"{name} cancelled")
            return
        order.append(name)
        slots.release()

    threads = [threading.Thread(target=wait_for, args=(first, "first")),
               threading.Thread(target=wait_for, args=(second, "second"))]
    threads[0].start()
    wait_until(lambda: slots.waiting == 1, timeout=5)
    threads[1].start()
    wait_until(lambda: slots.waiting == 2, timeout=5)
    first.cancel()
    wait_until(lambda: slots.waiting == 1, timeout=5)
    slots.release()
    for thread in threads:
        thread.join(timeout=5)
    assert order == ["first cancelled", "second"]
    assert said.count(True) == 2 and said.count(False) == 1
    assert slots.running == 0 and slots.waiting == 0


@requires_chromium
def test_three_tabs_editing_at_once_see_every_edit_within_10_s(small_explorer, browser) -> None:
    server = ExplorerServer(small_explorer, Settings(), port=0)
    try:
        result = load.run_load(server, browser, tabs=3, edits=5, jobs=1)
    finally:
        server.stop()
    assert result.lost == 0 and len(result.times) == 15, result.summary()
    assert max(result.times) < load.SLOW_MS, result.summary()
    assert result.tracebacks == 0, result.summary()


@pytest.fixture
def taken_slots() -> Task:
    """Every place of the process-wide pool held by a job of the test's own, given back after."""
    holder = _task()
    for _ in range(LONG_JOBS.size):
        LONG_JOBS.acquire(holder, lambda queued: None)
    yield holder
    for _ in range(LONG_JOBS.size):
        LONG_JOBS.release()


@requires_chromium
def test_a_queued_run_says_it_waits_and_leaves_the_queue_when_its_tab_closes(small_explorer, browser,
                                                                             taken_slots) -> None:
    server = ExplorerServer(small_explorer, Settings(), port=0)
    try:
        page = open_page(browser, server)
        page.get_by_role("tab", name="Explore").click()
        page.get_by_role("button", name="run all frames").click()
        page.get_by_text("waiting for another tab's job").wait_for(timeout=30_000)
        assert LONG_JOBS.waiting == 1
        page.close()
        wait_until(lambda: LONG_JOBS.waiting == 0, timeout=15)
        assert LONG_JOBS.running == LONG_JOBS.size, "the cancelled run never ran"
    finally:
        server.stop()
