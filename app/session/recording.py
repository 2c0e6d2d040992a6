"""A compact record of every frame a tab has shown, for the shareable recording (``scene.recording_html``).

A ``FrameRecord`` is plain data: the frame's boxes seen from above in the ego frame, the CAV's
where the wrong pose put them (``init``) and where the estimate puts them, the match pairs told
apart as right, wrong or missed against the true pairs, and the metrics. ``Recording`` keeps the
last ``LIMIT`` frames of the current settings; like the timeline's rows (``history``) it starts
afresh when a setting other than the frame, the CAV or the view changes.
"""
from __future__ import annotations

import math
import threading
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np

from cbm import se2
from evaluation.metrics import is_success

from .explorer import Outcome, classified_pairs
from .history import settings_key
from .names import agent_name
from .settings import Settings

LIMIT = 500
"""Frames a recording keeps (the oldest computed go first); a frame is about 2 kB."""


@dataclass(frozen=True)
class FrameRecord:
    """One frame shown: top-down boxes (M, 5) as x, y, length, width, yaw in the ego frame (metres,
    radians), pairs (K, 2) as (ego index, CAV index), and the frame's metrics."""

    frame: int
    agents: str
    ego: np.ndarray
    cav_before: np.ndarray
    """The CAV's boxes placed by ``init`` (the wrong pose)."""
    cav_after: np.ndarray
    """The CAV's boxes placed by the method's estimate (by ``init`` when it made none)."""
    cav_pose_before: tuple[float, float, float]
    cav_pose_after: tuple[float, float, float]
    """(x, y, yaw) of the CAV in the ego frame."""
    right: np.ndarray
    wrong: np.ndarray
    missed: np.ndarray
    metrics: dict[str, Any]
    """Numbers by name (NaN as None), ``success`` as the evaluation counts it."""


def top_down(boxes: np.ndarray) -> np.ndarray:
    """(N, 7) boxes (x, y, z, l, w, h, yaw) as (N, 5) x, y, l, w, yaw."""
    return np.asarray(boxes, dtype=float).reshape(-1, 7)[:, [0, 1, 3, 4, 6]]


def _pose(transform: np.ndarray) -> tuple[float, float, float]:
    x, y = se2.translation_of(transform)
    return float(x), float(y), float(se2.yaw_of(transform))


def _plain(value: Any) -> Any:
    """A JSON-ready number: NaN as None, numpy scalars as Python's."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    value = float(value)
    return None if math.isnan(value) else value


def metrics_of(outcome: Outcome) -> dict[str, Any]:
    """The frame's metrics, and the pose error of ``init`` (before calibration) beside the estimate's."""
    m, trial = outcome.metrics, outcome.trial
    init_rre = abs(math.degrees(se2.wrap_angle(se2.yaw_of(trial.init) - se2.yaw_of(trial.T_true))))
    init_rte = float(np.linalg.norm(se2.translation_of(trial.init) - se2.translation_of(trial.T_true)))
    numbers = {"n_ego": m.n_ego, "n_cav": m.n_cav, "n_true": m.n_true, "n_matched": m.n_matched,
               "n_correct": m.n_correct, "precision": m.precision, "recall": m.recall, "ad": m.ad,
               "rte": m.rte, "rre": m.rre, "rte_before": init_rte, "rre_before": init_rre,
               "margin": m.margin, "runtime_s": m.runtime_s, "estimated": m.estimated,
               "success": is_success(m)}
    plain = {name: _plain(value) for name, value in numbers.items()}
    result = outcome.result
    anchored = outcome.voted
    return {**plain, "consensus_count": int(result.consensus_count) if anchored else None,
            "runner_up_count": int(result.runner_up_count) if anchored else None}


def record_of(outcome: Outcome) -> FrameRecord:
    """The record of one outcome."""
    trial, result = outcome.trial, outcome.result
    after = result.transform if result.estimated else trial.init
    right, wrong, missed = classified_pairs(outcome.shown_pairs, trial.gt_pairs)
    return FrameRecord(
        frame=outcome.frame_index, agents=f"{agent_name('ego', outcome.ego_id)} · {agent_name('CAV', outcome.cav_id)}",
        ego=top_down(trial.ego_boxes), cav_before=top_down(se2.apply_boxes(trial.init, trial.cav_boxes)),
        cav_after=top_down(se2.apply_boxes(after, trial.cav_boxes)),
        cav_pose_before=_pose(trial.init), cav_pose_after=_pose(after),
        right=right, wrong=wrong, missed=missed, metrics=metrics_of(outcome))


class Recording:
    """The records of the frames shown under the current settings (``settings_key``), at most
    ``limit``, by frame; ``settings`` is the last outcome's (what the recording's header names)."""

    def __init__(self, limit: int = LIMIT) -> None:
        self.limit = limit
        self.key: Settings | None = None
        self.settings: Settings | None = None
        self._records: OrderedDict[int, FrameRecord] = OrderedDict()
        self._lock = threading.Lock()

    def add(self, outcome: Outcome) -> None:
        """Record a frame shown; other settings than the records' so far start afresh."""
        record = record_of(outcome)
        with self._lock:
            key = settings_key(outcome.settings)
            if key != self.key:
                self.key, self._records = key, OrderedDict()
            self.settings = outcome.settings
            self._records.pop(record.frame, None)
            self._records[record.frame] = record
            while len(self._records) > self.limit:
                self._records.popitem(last=False)

    def frames(self) -> list[FrameRecord]:
        """The records by frame index."""
        return self.snapshot()[1]

    def snapshot(self) -> tuple[Settings | None, list[FrameRecord]]:
        """The last settings and the records by frame index, read together."""
        with self._lock:
            return self.settings, [self._records[f] for f in sorted(self._records)]

    def __len__(self) -> int:
        return len(self._records)
