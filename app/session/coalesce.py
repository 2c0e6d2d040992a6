"""Run only the latest request, one at a time, in order.

viser calls GUI callbacks on a thread pool, many at once while a slider moves. ``Coalescer``
keeps only the newest submitted value; one worker thread computes it and hands the result on,
so results are applied in the order they were asked for, a slow computation never piles up work,
and values superseded while one was computing are never computed at all.
"""
from __future__ import annotations

import threading
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
    """``call(action)`` runs ``action`` after ``delay`` seconds on a timer thread, unless a newer
    ``call`` comes first: only the latest of a burst runs (``close`` drops a pending one)."""

    def __init__(self, delay: float) -> None:
        self.delay = delay
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None

    def call(self, action: Callable[[], None]) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
            self._timer = threading.Timer(self.delay, action)
            self._timer.daemon = True
            self._timer.start()

    def close(self) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
