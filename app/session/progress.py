"""Saying how long a tab has been waiting, while it waits.

A recompute of a large scene, or the first one while CBM's kernels compile, takes long enough to
look like a freeze; ``announced`` runs a block and, once it has taken a moment, reports the seconds
elapsed at a steady pace until it ends. Nothing is reported for a block that ends quickly.
"""
from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator


@contextlib.contextmanager
def announced(report: Callable[[float], None], after: float = 0.5, every: float = 0.5,
              since: float | None = None) -> Iterator[None]:
    """Run the block; from ``after`` seconds into it, call ``report(seconds)`` every ``every``
    seconds until it ends (seconds since ``since``, a ``time.monotonic()`` value, or since the
    block began). No call comes after the block has ended."""
    began = time.monotonic()
    start = began if since is None else since
    done = threading.Event()

    def tick() -> None:
        delay = after
        while not done.wait(delay):
            report(time.monotonic() - start)
            delay = every

    ticker = threading.Thread(target=tick, name="announced", daemon=True)
    ticker.start()
    try:
        yield
    finally:
        done.set()
        ticker.join()
