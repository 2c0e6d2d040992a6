"""Stopping a run cleanly: SIGINT (Ctrl-C) and SIGTERM become :class:`Stopped` in the main process.

    with StopSignals() as signals:
        ...                      # a signal here raises Stopped: the pool's workers end, nothing is written
        with signals.held():
            staged.publish()     # a signal here waits: the swap of --out is never cut in half
        if signals.pending: ...  # it came while held

``Stopped`` is a ``BaseException`` so no ``except Exception`` swallows it; the process pool
(``evaluation.executors.stop_pool``) and the staging folder (``evaluation.outputs``) clean up as it passes.
:class:`Watchdog` is the last resort of a command: a signal the main thread cannot act on within
``FORCE_AFTER_S`` ends the process anyway, its child processes with it (:func:`force_exit`).
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType
from typing import Any, NoReturn

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Stopped(BaseException):
    """A stop signal arrived: ``signum`` is the signal, ``name`` its name (``SIGTERM``)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum
        self.name = signal.Signals(signum).name


class StopSignals(contextlib.AbstractContextManager):
    """SIGINT and SIGTERM raise :class:`Stopped` inside the block, except while :meth:`held`
    (then the first one is kept in ``pending``); the previous handlers come back after the block."""

    def __init__(self) -> None:
        self.pending: int | None = None
        self._held = False
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> StopSignals:
        self._previous = {s: signal.signal(s, self._handle) for s in STOP_SIGNALS}
        return self

    def __exit__(self, *exc: object) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if not self._held:
            raise Stopped(signum)
        self.pending = self.pending or signum

    @property
    def holding(self) -> bool:
        """Whether a stop signal is held now (inside :meth:`held`)."""
        return self._held

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """Inside, a stop signal is recorded in ``pending`` instead of raised."""
        self._held = True
        try:
            yield
        finally:
            self._held = False


FORCE_AFTER_S = 1.5
"""Seconds a stop signal may wait for the main thread before :class:`Watchdog` ends the process."""


def descendants(pid: int | None = None) -> list[int]:
    """Every process descended from ``pid`` (default: this one), read from /proc (none without it)."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir() if Path("/proc").is_dir() else ():
        if entry.name.isdigit():
            try:
                parents[int(entry.name)] = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
    found, frontier = [], [os.getpid() if pid is None else pid]
    while frontier:
        parent = frontier.pop()
        children = [child for child, of in parents.items() if of == parent]
        found += children
        frontier += children
    return found


def kill_descendants(rounds: int = 50) -> None:
    """Kill every process descended from this one, none left orphaned: each one found is first
    stopped (SIGSTOP, so it can start no more) and the tree read again until it shows no new one
    (a process starting children meanwhile, as Ray's raylet does in its start-up, would otherwise
    leave them to outlive it); then all are killed."""
    stopped: set[int] = set()
    for _ in range(rounds):
        found = set(descendants()) - stopped
        if not found:
            break
        for pid in found:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGSTOP)
        stopped |= found
    for pid in stopped:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    reap(stopped)


def reap(pids: set[int], timeout: float = 1.0) -> None:
    """Collect the exit status of those of ``pids`` that are this process's children, so that none is
    left listed as ``<defunct>`` (killed children stay so until their parent waits for them)."""
    deadline = time.monotonic() + timeout
    waiting = set(pids)
    while waiting and time.monotonic() < deadline:
        for pid in list(waiting):
            try:
                done, _ = os.waitpid(pid, os.WNOHANG)
            except ChildProcessError:  # not our child (its parent reaps it), or already reaped
                waiting.discard(pid)
                continue
            if done:
                waiting.discard(pid)
        if waiting:
            time.sleep(0.01)


def force_exit(line: str, signum: int) -> NoReturn:
    """End the process now: every descendant process killed (none orphaned), ``line`` on stderr,
    exit status 128 + ``signum``; for a stop the main thread cannot act on in time."""
    kill_descendants()
    with contextlib.suppress(OSError, ValueError):
        sys.stdout.flush()
        sys.stderr.write(line + "\n")
        sys.stderr.flush()
    os._exit(128 + signum)


class Watchdog:
    """A stop signal acts within about 2 s even when the main thread cannot run its handler (a long
    C call, or a third-party start-up such as ``ray.init`` that replaced or delays it): the signal
    also wakes a thread (``signal.set_wakeup_fd``) that, if the process still runs ``grace`` seconds
    later and ``held()`` is false, calls :func:`force_exit` with ``line(signal name)``, unless
    ``disarmed`` (the command finished on its own). Create it in the main thread."""

    def __init__(self, line: Callable[[str], str], held: Callable[[], bool] = lambda: False,
                 grace: float = FORCE_AFTER_S) -> None:
        self.line, self.held, self.grace = line, held, grace
        self.disarmed = False
        read, write = os.pipe()
        os.set_blocking(write, False)
        signal.set_wakeup_fd(write, warn_on_full_buffer=False)
        threading.Thread(target=self._watch, args=(read,), name="stop-watchdog", daemon=True).start()

    def _watch(self, read: int) -> None:
        """Wait for SIGINT or SIGTERM, then for ``grace`` seconds (longer while held), then end the process."""
        signum = 0
        while signum not in STOP_SIGNALS:
            signum = os.read(read, 1)[0]
        deadline = time.monotonic() + self.grace
        while time.monotonic() < deadline or self.held():
            time.sleep(0.05)
        if not self.disarmed:
            force_exit(self.line(signal.Signals(signum).name), signum)

    def disarm(self) -> None:
        """From now on a stop signal is left to the handlers alone."""
        self.disarmed = True
