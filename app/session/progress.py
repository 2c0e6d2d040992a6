"""Saying how long a tab has been waiting, while it waits.

A recompute of a large scene, or the first one while CBM's kernels compile, takes long enough to
look like a freeze; ``announced`` runs a block and, once it has taken a moment, reports the seconds
elapsed at a steady pace until it ends. Nothing is reported for a block that ends quickly.

Every block's reports come from one thread of the process (``_Ticker``), started once: a thread of
its own per block cost a thread's start and join on every recompute, a few milliseconds on a busy
machine, for reports almost no block needs.
"""
from __future__ import annotations

import contextlib
import math
import threading
import time
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field


@dataclass(eq=False)
class _Announcement:
    """One block's reports: when the next is due (``time.monotonic()``), and the lock a report holds."""

    report: Callable[[float], None]
    start: float
    due: float
    every: float
    active: bool = True
    lock: threading.Lock = field(default_factory=threading.Lock)


class _Ticker:
    """The thread that makes every block's reports, each when it is due."""

    def __init__(self) -> None:
        self._condition = threading.Condition()
        self._waiting: set[_Announcement] = set()
        self._thread: threading.Thread | None = None

    def add(self, announcement: _Announcement) -> None:
        with self._condition:
            self._waiting.add(announcement)
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="announced", daemon=True)
                self._thread.start()
            self._condition.notify()

    def remove(self, announcement: _Announcement) -> None:
        """No report of ``announcement`` after this returns (one being made is waited for)."""
        with self._condition:
            announcement.active = False
            self._waiting.discard(announcement)
        with announcement.lock:
            pass

    def _run(self) -> None:
        while True:
            with self._condition:
                due = self._next_due()
                if due is None:
                    continue
                due.due = math.inf
            self._report(due)

    def _next_due(self) -> _Announcement | None:
        """The announcement whose report is due, after waiting for one (None: woken before any is)."""
        first = min(self._waiting, key=lambda a: a.due, default=None)
        now = time.monotonic()
        if first is None or first.due > now:
            self._condition.wait(None if first is None or first.due == math.inf else first.due - now)
            return None
        return first

    def _report(self, announcement: _Announcement) -> None:
        """Make one report, unless the block has ended; schedule the next."""
        with announcement.lock:
            if not announcement.active:
                return
            try:
                announcement.report(time.monotonic() - announcement.start)
            except Exception:  # a failing report ends that block's reports, not the other blocks'
                traceback.print_exc()
                announcement.active = False
        with self._condition:
            if announcement.active:
                announcement.due = time.monotonic() + announcement.every


_TICKER = _Ticker()


@contextlib.contextmanager
def announced(report: Callable[[float], None], after: float = 0.5, every: float = 0.5,
              since: float | None = None) -> Iterator[None]:
    """Run the block; from ``after`` seconds into it, call ``report(seconds)`` every ``every``
    seconds until it ends (seconds since ``since``, a ``time.monotonic()`` value, or since the
    block began). No call comes after the block has ended."""
    began = time.monotonic()
    announcement = _Announcement(report, began if since is None else since, began + after, every)
    _TICKER.add(announcement)
    try:
        yield
    finally:
        _TICKER.remove(announcement)
