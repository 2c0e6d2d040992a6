"""One long task of a tab at a time (a sequence run, a search, a screenshot), off the GUI threads.

viser runs GUI callbacks on a shared thread pool and each tab recomputes on its own worker; a task
that takes seconds runs here instead, reports its progress, and stops at its next checkpoint when
cancelled. A failure goes to ``failed`` (the tab's notification), never up into viser.
"""
from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TypeVar

R = TypeVar("R")


class Cancelled(Exception):
    """Raised at a checkpoint of a task whose cancel was asked for."""


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


class Runner:
    """Runs at most one task at a time on a daemon thread."""

    def __init__(self, report: Callable[[float], None], failed: Callable[[str, BaseException], None],
                 finished: Callable[[], None] = lambda: None, name: str = "task") -> None:
        self._report, self._failed, self._finished, self._name = report, failed, finished, name
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
            done(work(task), task.cancelled)
        except Cancelled:
            pass
        except Exception as error:  # reported to the tab; the server lives on
            self._failed(title, error)
        finally:
            self._finished()
