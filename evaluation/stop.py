"""Stopping a run cleanly: SIGINT (Ctrl-C) and SIGTERM become :class:`Stopped` in the main process.

    with StopSignals() as signals:
        ...                      # a signal here raises Stopped: the pool's workers end, nothing is written
        with signals.held():
            staged.publish()     # a signal here waits: the swap of --out is never cut in half
        if signals.pending: ...  # it came while held

``Stopped`` is a ``BaseException`` so no ``except Exception`` swallows it; the process pool
(``evaluation.executors.stop_pool``) and the staging folder (``evaluation.outputs``) clean up as it passes.
"""
from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator
from types import FrameType
from typing import Any

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

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """Inside, a stop signal is recorded in ``pending`` instead of raised."""
        self._held = True
        try:
            yield
        finally:
            self._held = False
