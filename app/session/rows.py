"""The per-frame rows (``evaluation.sweep``'s) computed so far, by the settings they depend on: what a
sequence run, a comparison of methods and an export take instead of computing a frame again.

A row is the number a run gives on its frame under its settings (every trial is reproducible from
them), so rows are kept per dataset and any tab takes them. Rows come from sequence runs (each
method of a comparison is one) and from the frames a method over time computed while a person
stepped through them (``app.session.sequence``). ``RowStore`` keeps the settings used last, at most
``ROWS_KEPT`` rows in all.
"""
from __future__ import annotations

import threading
from collections.abc import Iterable, Mapping
from typing import Any

from .over_time import run_key
from .settings import Settings

ROWS_KEPT = 20_000
"""Rows kept in all (a row with its fused boxes is a few kB): the settings used least recently go first."""


class RowStore:
    """Rows by ``run_key`` (the settings without the frame and the view), then by frame; the settings
    used last at the end (settings hold a mapping: they compare, they do not hash)."""

    def __init__(self, most: int = ROWS_KEPT) -> None:
        self.most = most
        self._rows: list[tuple[Settings, dict[int, Mapping[str, Any]]]] = []
        self._lock = threading.Lock()

    def of(self, settings: Settings) -> dict[int, Mapping[str, Any]]:
        """The rows known under ``settings``, by frame (a copy)."""
        with self._lock:
            return dict(self._used(run_key(settings)))

    def add(self, settings: Settings, rows: Iterable[Mapping[str, Any]]) -> None:
        """Keep ``rows`` (computed under ``settings``), the least recently used settings' going past ``most``."""
        with self._lock:
            self._used(run_key(settings)).update({int(row["frame"]): row for row in rows})
            while sum(len(found) for _, found in self._rows) > self.most and len(self._rows) > 1:
                del self._rows[0]

    def clear(self) -> None:
        with self._lock:
            self._rows.clear()

    def _used(self, key: Settings) -> dict[int, Mapping[str, Any]]:
        """The rows of ``key`` (new and empty if none), moved to the end as the settings used last."""
        found = next((rows for known, rows in self._rows if known == key), {})
        self._rows = [(known, rows) for known, rows in self._rows if rows is not found] + [(key, found)]
        return found
