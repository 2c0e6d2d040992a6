"""Run only the latest request, one at a time, in order.

viser calls GUI callbacks on a thread pool, many at once while a slider moves. ``Coalescer``
keeps only the newest submitted value; one worker thread computes it and hands the result on,
so results are applied in the order they were asked for, a slow computation never piles up work,
and values superseded while one was computing are never computed at all.
"""
from __future__ import annotations

import threading
import time
import traceback
from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")
R = TypeVar("R")


class Coalescer(Generic[T, R]):
    """``submit(value)`` from any thread; ``compute(value)`` then ``deliver(result, generation)``
    run on the worker for the newest value only. An exception goes to ``fail(error)``."""

    def __init__(self, compute: Callable[[T], R], deliver: Callable[[R, int], None],
                 fail: Callable[[BaseException], None], name: str = "coalescer") -> None:
        self._compute, self._deliver, self._fail = compute, deliver, fail
        self._condition = threading.Condition()
        self._pending: tuple[int, T] | None = None
        self._generation = 0
        self._busy = False
        self._closed = False
        self._thread = threading.Thread(target=self._work, name=name, daemon=True)
        self._thread.start()

    def submit(self, value: T) -> int:
        """Ask for ``value`` to be computed; returns its generation (1, 2, ...)."""
        with self._condition:
            self._generation += 1
            self._pending = (self._generation, value)
            self._condition.notify()
            return self._generation

    @property
    def superseded(self) -> bool:
        """A newer value waits: the one computing now will be shown only briefly, if at all (a long
        computation may stop early)."""
        with self._condition:
            return self._pending is not None or self._closed

    def wait_idle(self, timeout: float | None = None) -> bool:
        """Block until nothing is pending or computing; False on timeout."""
        with self._condition:
            return self._condition.wait_for(lambda: self._pending is None and not self._busy, timeout)

    def close(self) -> None:
        with self._condition:
            self._closed = True
            self._condition.notify_all()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout=5)

    def _work(self) -> None:
        while True:
            with self._condition:
                self._condition.wait_for(lambda: self._pending is not None or self._closed)
                if self._closed:
                    return
                generation, value = self._pending
                self._pending, self._busy = None, True
            try:
                self._deliver(self._compute(value), generation)
            except Exception as error:  # a failed recompute is reported, the worker lives on
                self._fail(error)
            finally:
                with self._condition:
                    self._busy = False
                    self._condition.notify_all()


class Later:
    """``call(action)`` runs ``action`` after ``delay`` seconds on the instance's thread, unless a
    newer ``call`` comes first: only the latest of a burst runs (``close`` drops a pending one and
    ends the thread; a later ``call`` starts it again). One thread waits for every call, rather than
    a timer thread started per call (a thread's start on every result)."""

    def __init__(self, delay: float) -> None:
        self.delay = delay
        self._condition = threading.Condition()
        self._action: Callable[[], None] | None = None
        self._due = 0.0
        self._thread: threading.Thread | None = None

    def call(self, action: Callable[[], None]) -> None:
        with self._condition:
            self._action, self._due = action, time.monotonic() + self.delay
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="later", daemon=True)
                self._thread.start()
            self._condition.notify()

    def close(self) -> None:
        with self._condition:
            self._action, self._thread = None, None
            self._condition.notify()

    def _run(self) -> None:
        me = threading.current_thread()
        while True:
            with self._condition:
                if self._thread is not me:
                    return
                now = time.monotonic()
                if self._action is None or self._due > now:
                    self._condition.wait(None if self._action is None else self._due - now)
                    continue
                action, self._action = self._action, None
            try:
                action()
            except Exception:  # a failed action is reported; the later ones still run
                traceback.print_exc()
