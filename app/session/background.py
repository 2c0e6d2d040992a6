"""One long task of a tab at a time (a sequence run, a search, a screenshot), off the GUI threads.

viser runs GUI callbacks on a shared thread pool and each tab recomputes on its own worker; a task
that takes seconds runs here instead, reports its progress, and stops when cancelled: at its next
checkpoint, and inside CBM's engine too (it runs under ``cbm.engine.threads.stoppable``, so a frame
of thousands of boxes stops within a second, not after its minutes). A failure goes to ``failed``
(the tab's notification), never up into viser.

Long tasks of all tabs share one bounded ``Slots`` (``LONG_JOBS``): at most ``LONG_JOB_SLOTS`` run
at once, the others wait in turn (first come, first served) and say so, so that one tab's run over
every frame never takes more than its share of the cores from the other tabs' edits. A task
cancelled while it waits leaves the queue without running.
"""
from __future__ import annotations

import os
import threading
from collections import deque
from collections.abc import Callable
from typing import TypeVar

from cbm import Cancelled, stoppable

R = TypeVar("R")

LONG_JOB_SLOTS = max(1, (os.cpu_count() or 2) // 2)
"""Long tasks running at once across all tabs: half the cores (1 on 2 cores), the rest for edits."""


class Task:
    """What a running task sees: ``report(fraction)`` its progress, ``check()`` for a cancel."""

    def __init__(self, report: Callable[[float], None]) -> None:
        self._report = report
        self._cancel = threading.Event()

    def report(self, fraction: float) -> None:
        self._report(min(max(fraction, 0.0), 1.0))

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancelled(self) -> bool:
        return self._cancel.is_set()

    def check(self) -> None:
        """Raise ``Cancelled`` if the task was asked to stop."""
        if self._cancel.is_set():
            raise Cancelled


class Slots:
    """A bounded, first-come-first-served set of ``size`` places shared by every tab's long tasks."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._condition = threading.Condition()
        self._queue: deque[object] = deque()
        self._running = 0

    @property
    def running(self) -> int:
        with self._condition:
            return self._running

    @property
    def waiting(self) -> int:
        with self._condition:
            return len(self._queue)

    def acquire(self, task: Task, waiting: Callable[[bool], None]) -> None:
        """Take a place for ``task``, in turn; ``waiting(True)`` once if it has to wait and
        ``waiting(False)`` when its turn comes. Raises ``Cancelled`` if it is cancelled meanwhile."""
        ticket = object()
        with self._condition:
            self._queue.append(ticket)
            queued = not self._turn(ticket)
        if queued:
            waiting(True)
        with self._condition:
            while not self._turn(ticket):
                if task.cancelled:
                    self._queue.remove(ticket)
                    self._condition.notify_all()
                    raise Cancelled
                self._condition.wait(timeout=0.2)
            self._queue.popleft()
            self._running += 1
        if queued:
            waiting(False)

    def release(self) -> None:
        with self._condition:
            self._running -= 1
            self._condition.notify_all()

    def _turn(self, ticket: object) -> bool:
        return self._queue[0] is ticket and self._running < self.size


LONG_JOBS = Slots(LONG_JOB_SLOTS)
"""The places every tab's long tasks share (one process, one pool)."""


class Runner:
    """Runs at most one task at a time on a daemon thread, once ``slots`` gives it a place;
    ``waiting(True/False)`` says when it queues behind other tabs' tasks and when its turn comes."""

    def __init__(self, report: Callable[[float], None], failed: Callable[[str, BaseException], None],
                 finished: Callable[[], None] = lambda: None, name: str = "task",
                 waiting: Callable[[bool], None] = lambda queued: None, slots: Slots | None = None) -> None:
        self._report, self._failed, self._finished, self._name = report, failed, finished, name
        self._waiting, self._slots = waiting, LONG_JOBS if slots is None else slots
        self._lock = threading.Lock()
        self._task: Task | None = None
        self._thread: threading.Thread | None = None

    @property
    def busy(self) -> bool:
        with self._lock:
            return self._thread is not None and self._thread.is_alive()

    def start(self, title: str, work: Callable[[Task], R], done: Callable[[R, bool], None]) -> bool:
        """Run ``work(task)`` then ``done(result, cancelled)``, then ``finished()``; False (nothing
        started) when busy. A ``Cancelled`` raised by ``work`` ends it quietly; any other error goes
        to ``failed``."""
        with self._lock:
            if self._thread is not None and self._thread.is_alive():
                return False
            task = Task(self._report)
            self._task = task
            self._thread = threading.Thread(target=self._run, args=(title, task, work, done),
                                            name=f"{self._name}-{title}", daemon=True)
            self._thread.start()
            return True

    def cancel(self) -> None:
        with self._lock:
            if self._task is not None:
                self._task.cancel()

    def join(self, timeout: float | None = None) -> bool:
        """Wait for the running task; False on timeout."""
        thread = self._thread
        if thread is not None:
            thread.join(timeout)
        return thread is None or not thread.is_alive()

    def _run(self, title: str, task: Task, work: Callable[[Task], R], done: Callable[[R, bool], None]) -> None:
        try:
            self._slots.acquire(task, self._waiting)
        except Cancelled:
            self._finished()
            return
        try:
            with stoppable(lambda: task.cancelled):
                result = work(task)
            done(result, task.cancelled)
        except Cancelled:
            pass
        except Exception as error:  # reported to the tab; the server lives on
            self._failed(title, error)
        finally:
            self._slots.release()
            self._finished()
