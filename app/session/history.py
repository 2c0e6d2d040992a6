"""The metrics of the frames a tab has shown under its current settings, for the plot over frames."""
from __future__ import annotations

import dataclasses

import numpy as np

from .explorer import Outcome
from .settings import AUTO_CAV, Settings, ViewOptions


class FrameHistory:
    """Per-frame metrics of the current settings, for the plot over frames; forgotten when any
    setting other than the frame, the CAV or the view changes."""

    def __init__(self) -> None:
        self.key: Settings | None = None
        self.rows: dict[int, tuple[float, float, float]] = {}

    @staticmethod
    def _key(settings: Settings) -> Settings:
        return dataclasses.replace(settings, frame=0, cav=AUTO_CAV, view=ViewOptions())

    def add(self, outcome: Outcome) -> None:
        key = self._key(outcome.settings)
        if key != self.key:
            self.key, self.rows = key, {}
        m = outcome.metrics
        self.rows[outcome.frame_index] = (m.precision, m.recall, m.rte)

    def arrays(self) -> tuple[np.ndarray, ...]:
        frames = np.array(sorted(self.rows), dtype=float)
        values = np.array([self.rows[int(f)] for f in frames], dtype=float).reshape(-1, 3)
        return (frames, *(np.where(np.isfinite(values[:, k]), values[:, k], np.nan) for k in range(3)))
