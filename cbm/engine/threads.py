"""The one way the engine runs work on several threads: ``shared_out``; and the one place where an
abandoned computation stops (``stoppable``).

The engine's kernels are numba functions compiled ``nogil``, so Python threads run them truly at
once. A site that splits its work makes one task per part, hands the list to ``shared_out`` and
merges the results, which come back in the tasks' order whatever thread ran each: so nothing the
engine returns depends on the threads. How many threads, and from what size a site splits at all,
is ``cbm.engine.tuning``'s.
"""
from __future__ import annotations

import ctypes
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from . import tuning
from .interpreted import COMPILE_LOCK

T = TypeVar("T")

_pool: ThreadPoolExecutor | None = None
_pool_lock = threading.Lock()
_inside = threading.local()


class Cancelled(Exception):
    """The caller abandoned the computation (``stoppable``): nothing it would return is wanted."""


WATCH_EVERY = 0.05
"""Seconds between two questions of a stoppable computation's watcher (``stoppable``)."""
NEVER = np.zeros(1, np.uint8)
"""The stop flag of a computation nobody can stop: never set."""


@dataclass(frozen=True)
class _Abandon:
    """How one stoppable computation learns it was abandoned: Python code asks ``should_stop``; the
    compiled kernels read ``flag[0]``, which a watcher thread sets once ``should_stop`` says so."""

    should_stop: Callable[[], bool]
    flag: np.ndarray

    def asked(self) -> bool:
        return bool(self.flag[0]) or self.should_stop()


@contextmanager
def stoppable(should_stop: Callable[[], bool]) -> Iterator[None]:
    """Within the block, on this thread, the engine asks ``should_stop()`` before each part of its
    work (each task of ``shared_out``, and between CBM's steps: ``check_stop``) and raises
    ``Cancelled`` once it says so. Inside a compiled kernel the question is the flag
    ``stop_flag()``, read between chunks of a few milliseconds of work: a watcher thread asks
    ``should_stop()`` every ``WATCH_EVERY`` seconds while the block runs and sets the flag when
    it says so; a kernel then returns early, and its caller raises ``Cancelled`` before anything
    reads what it returned (``check_stop``). Inside another such block, either one's question stops it."""
    outer = getattr(_inside, "stop", None)
    asked = should_stop if outer is None else lambda: should_stop() or outer.asked()
    abandon, done = _Abandon(asked, np.zeros(1, np.uint8)), threading.Event()
    _inside.stop = abandon
    watcher = threading.Thread(target=_watch, args=(abandon, done), name="cbm-stop-watcher", daemon=True)
    watcher.start()
    try:
        yield
    finally:
        done.set()
        _inside.stop = outer


def _watch(abandon: _Abandon, done: threading.Event) -> None:
    """Sets ``abandon.flag`` once ``abandon.should_stop()`` says so, until ``done``."""
    while not done.wait(WATCH_EVERY):
        if abandon.should_stop():
            abandon.flag[0] = 1
            return


def stop_flag() -> np.ndarray:
    """The flag the kernels of this thread's computation read: set once it was abandoned
    (``stoppable``; ``NEVER`` outside one)."""
    abandon = getattr(_inside, "stop", None)
    return NEVER if abandon is None else abandon.flag


def check_stop() -> None:
    """``Cancelled`` when the computation this thread runs was abandoned (see ``stoppable``)."""
    _raise_if(getattr(_inside, "stop", None))


def _raise_if(abandon: _Abandon | None) -> None:
    if abandon is not None and abandon.asked():
        raise Cancelled("the computation was abandoned")


def parts(size: int, threshold: float) -> int:
    """Parts to split a work of ``size`` into: ``tuning.THREADS`` from ``threshold`` on, else 1 (and
    1 inside a task of ``shared_out``, whose parts would run one after the other)."""
    return tuning.THREADS if size >= threshold and not getattr(_inside, "task", False) else 1


def shared_out(tasks: Sequence[Callable[[], T]]) -> list[T]:
    """Every task's result, in the tasks' order. Up to ``tuning.THREADS`` threads (the calling one
    and the pool's) each take the next task not yet taken until none is left, so a long task never
    holds up the ones behind it. One task, one thread, a call from inside a task, or a caller that
    holds the compile lock (``interpreted.COMPILE_LOCK``: a pool thread would wait on it to compile a
    kernel) runs them all on the calling thread. An exception of a task is raised here once every
    thread has stopped."""
    workers = min(tuning.THREADS, len(tasks))
    abandon = getattr(_inside, "stop", None)
    if workers <= 1 or getattr(_inside, "task", False) or COMPILE_LOCK._is_owned():
        return [_checked(task, abandon) for task in tasks]
    results: list = [None] * len(tasks)
    indices = iter(range(len(tasks)))
    taking = threading.Lock()

    def work() -> None:
        _inside.task, outer = True, getattr(_inside, "stop", None)
        _inside.stop = abandon
        try:
            while True:
                with taking:
                    k = next(indices, None)
                if k is None:
                    return
                results[k] = _checked(tasks[k], abandon)
        finally:
            _inside.task, _inside.stop = False, outer

    helpers = [_the_pool().submit(work) for _ in range(workers - 1)]
    failure = None
    try:
        work()
    except BaseException as error:  # the helpers must stop before it is raised
        failure = error
        with taking:
            for _ in indices:
                pass
    for helper in helpers:
        try:
            helper.result()
        except BaseException as error:
            failure = failure or error
    if failure is not None:
        raise failure
    return results


def _checked(task: Callable[[], T], abandon: _Abandon | None) -> T:
    """``task()``, unless the computation was abandoned before it started or while it ran (a
    kernel it ran may then have returned early: its result must not be read)."""
    _raise_if(abandon)
    result = task()
    _raise_if(abandon)
    return result


def _the_pool() -> ThreadPoolExecutor:
    """The pool of ``tuning.THREADS - 1`` threads (made anew when that changed)."""
    global _pool
    with _pool_lock:
        wanted = max(tuning.THREADS - 1, 1)
        if _pool is None or _pool._max_workers != wanted:
            _pool = ThreadPoolExecutor(max_workers=wanted, thread_name_prefix="cbm")
        return _pool


TRIM_FROM = 32 * 2**20
"""Bytes freed from which a kernel's caller hands the memory back to the system (``trim_freed``)."""


def _find_trim():
    """glibc's ``malloc_trim``, or None where the C library has none (or cannot be opened by name)."""
    try:
        return ctypes.CDLL(None).malloc_trim
    except (AttributeError, OSError, TypeError):
        return None


_MALLOC_TRIM = _find_trim()


def trim_freed() -> None:
    """Hands the memory the threads freed back to the system: glibc keeps it resident in the
    threads' arenas, where what comes next never reuses it."""
    if _MALLOC_TRIM is not None:
        _MALLOC_TRIM(0)
