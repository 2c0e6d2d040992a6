"""Fixtures of the method's tests: the engine's tuning set for one test."""
from __future__ import annotations

import pytest

from cbm.engine import tuning

NEVER = float("inf")


@pytest.fixture
def tuned(monkeypatch):
    """``tuned(threads=None, every=None, **named)``: for this test, the engine runs on ``threads``
    threads, every hand-over threshold of ``cbm.engine.tuning`` is ``every`` (0: every hand-over taken;
    ``NEVER``: none), and the named settings take their values."""

    def tune(threads: int | None = None, every: float | None = None, **named) -> None:
        if threads is not None:
            monkeypatch.setattr(tuning, "THREADS", threads)
        if every is not None:
            for name in tuning.THRESHOLDS:
                monkeypatch.setattr(tuning, name, every)
        for name, value in named.items():
            assert hasattr(tuning, name), name
            monkeypatch.setattr(tuning, name, value)

    return tune
