"""A pinned baseline: settings a person keeps to compare against, and their per-frame results.

Pinning copies the timeline's rows of the current settings; from then on, each frame the tab shows
is also computed under the pinned settings (same frame and CAV, the pinned method, parameters and
scenario), so the comparison and the pinned series keep filling as the person moves on.
"""
from __future__ import annotations

import dataclasses
import threading
from collections.abc import Mapping

from .explorer import Explorer, Outcome
from .history import FrameHistory, Row, row_of, settings_key
from .settings import Settings


class Baseline:
    """The pinned settings (None: nothing pinned), their rows by frame and outcomes by (frame, CAV)."""

    def __init__(self) -> None:
        self.settings: Settings | None = None
        self.rows: dict[int, Row] = {}
        self.beside = False
        """Drawn as a copy of the scene of its own beside the current one (else its lines over it)."""
        self._outcomes: dict[tuple[int, str], Outcome] = {}
        self._lock = threading.Lock()

    @property
    def pinned(self) -> bool:
        return self.settings is not None

    def pin(self, settings: Settings, history: FrameHistory, shown: Outcome | None,
            rows: Mapping[int, Row] | None = None, beside: bool = False) -> None:
        """Keep ``settings``, their ``rows`` (by default the history's, when they are theirs) and the
        outcome on screen; ``beside``: drawn beside the current run rather than over it."""
        with self._lock:
            self.settings, self.beside = settings_key(settings), beside
            self.rows = dict(rows) if rows is not None else dict(history.rows) if history.matches(settings) else {}
            self._outcomes = {}
            if shown is not None and settings_key(shown.settings) == self.settings:
                self._outcomes[(shown.frame_index, shown.settings.cav)] = shown

    def unpin(self) -> None:
        with self._lock:
            self.settings, self.rows, self._outcomes, self.beside = None, {}, {}, False

    def outcome(self, explorer: Explorer, current: Settings) -> Outcome | None:
        """The pinned settings' outcome on ``current``'s frame and CAV (computed once, then kept);
        None when nothing is pinned."""
        with self._lock:
            pinned = self.settings
            if pinned is None:
                return None
            key = (current.frame, current.cav)
            cached = self._outcomes.get(key)
        if cached is not None:
            return cached
        outcome = explorer.compute(dataclasses.replace(pinned, frame=current.frame, cav=current.cav,
                                                       view=current.view))
        with self._lock:
            if self.settings == pinned:
                self._outcomes[key] = outcome
                self.rows[outcome.frame_index] = row_of(outcome.metrics)
        return outcome
