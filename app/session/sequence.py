"""Sequence runs: a tab's settings over every frame of the sequence, through the evaluation's sweep.

The frames' inputs come from the trial builder (``evaluation.trials.sequence_inputs``) with the tab's
protocol and CAV -- as ``Explorer.compute`` builds them -- and every trial is built by
``FrameInputs.build`` inside ``evaluation.sweep``, so each row is the number the tab shows on that frame.
Frames run in chunks; a cancel stops at the next chunk and keeps the rows done so far.

A frame whose row is known (``Explorer.rows``: an earlier run's, a comparison's) is not run again.
A method over time continues the frames the tab computed (``Explorer.over_time``: stepping through
them, or a jump ahead) and its rows are made from them by the sweep's own ``trial_row``: a frame
answered over time depends on every frame before it, so its rows come from one chain of frames.
"""
from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cbm import Cancelled
from cbm.methods import METHODS
from evaluation.ap import pooled_ap
from evaluation.fusion import decoded
from evaluation.scenario import FrameInputs
from evaluation.sweep import Sweep, run, summarise, trial_row
from evaluation.trials import sequence_inputs

from .background import Task
from .explorer import Explorer
from .over_time import Stopped
from .settings import Settings

CHUNK = 8
"""Frames per chunk: a cancel takes effect within one chunk."""


def sweep_for(settings: Settings) -> Sweep:
    """A one-point sweep that runs exactly the tab's method, parameters, scenario and seed, with
    late fusion (``evaluation.fusion``) for the run's AP."""
    params = settings.params
    grid = {name: [getattr(params, name)] for name in METHODS[settings.method].tunable}
    return Sweep(methods=(settings.method,), grid=grid, seed=settings.scenario.seed, scenario=settings.scenario,
                 tracking=settings.tracking, fusion="nms")


def frame_inputs(explorer: Explorer, settings: Settings, frames: Iterable[int]) -> tuple[list[FrameInputs], list[int]]:
    """The sweep inputs of ``frames`` as the tab builds them, and the frames that have no ego or
    no CAV (skipped)."""
    scenario = settings.scenario
    return sequence_inputs(explorer.sequence, frames, scenario.protocol, settings.cav,
                           sensor_range=scenario.sensor_range, window_s=scenario.window_s)


@dataclass(frozen=True)
class SequenceRun:
    """The rows of one sequence run (one per frame, ``evaluation.sweep`` columns) and what it ran."""

    settings: Settings
    rows: tuple[dict[str, Any], ...]
    n_frames: int
    """Frames asked for."""
    skipped: tuple[int, ...]
    """Frames without an ego or a CAV."""
    cancelled: bool

    def row(self, frame: int) -> dict[str, Any]:
        """The row of ``frame`` (``KeyError`` when it was not run)."""
        for row in self.rows:
            if row["frame"] == frame:
                return row
        raise KeyError(f"frame {frame} was not run")

    def summary(self) -> dict[str, float]:
        """The run metrics over the rows (``evaluation.metric_registry.aggregate``); empty without rows."""
        return summarise(self.rows, by=("method",))[0][1] if self.rows else {}

    def fused_ap(self) -> dict[float, float]:
        """Late-fusion AP over the rows at each BEV IoU threshold (``evaluation.ap.pooled_ap``: every
        frame's fused detections sorted by score together); empty without rows."""
        return pooled_ap(decoded(row) for row in self.rows) if self.rows else {}

    def plot_data(self) -> tuple[np.ndarray, ...]:
        """(frames, precision, recall, RTE, RRE) arrays for the per-frame plot (NaN where undefined)."""
        columns = ("frame", "precision", "recall", "rte", "rre")
        return tuple(np.array([_float(row[c]) for row in self.rows], dtype=float) for c in columns)


def run_sequence(explorer: Explorer, settings: Settings, task: Task | None = None,
                 frames: Sequence[int] | None = None, chunk: int = CHUNK) -> SequenceRun:
    """``settings`` over ``frames`` (default: all), the rows known taken (``Explorer.rows``) and the
    others run in chunks, reporting progress to ``task`` and stopping early (``cancelled=True``, the
    rows done) when it is cancelled: between chunks, or within one when the engine raises
    ``Cancelled`` (``background.Runner`` runs it under ``stoppable``). A method over time runs every
    frame up to the last of ``frames`` in order (``over_time_rows``); a whole recording's method
    (``cbm-smooth``) runs them all as one chunk, since its answers need every frame."""
    frames = list(range(len(explorer)) if frames is None else frames)
    known = explorer.rows.of(settings)
    if METHODS[settings.method].offline and not set(frames) <= set(known):
        rows, skipped = _frames_run(explorer, settings, frames, task, max(len(frames), 1))
    elif METHODS[settings.method].over_time and not set(frames) <= set(known):
        rows, skipped = over_time_rows(explorer, settings, frames, task)
    else:
        rows, skipped = _frames_run(explorer, settings, [f for f in frames if f not in known], task, chunk)
        rows = sorted([*rows, *(known[f] for f in frames if f in known)], key=lambda row: row["frame"])
    explorer.rows.add(settings, rows)
    done = len(rows) + len(skipped)
    return SequenceRun(settings, tuple(rows), len(frames), tuple(skipped), cancelled=done < len(frames))


def known_frames(explorer: Explorer, settings: Settings) -> int:
    """How many frames of ``settings`` a run would take rather than compute: the rows known, or the
    frames a method over time computed."""
    if METHODS[settings.method].over_time and not METHODS[settings.method].offline:
        return max(len(explorer.rows.of(settings)), len(explorer.over_time.done(settings)))
    return len(explorer.rows.of(settings))


def _frames_run(explorer: Explorer, settings: Settings, frames: list[int], task: Task | None,
                chunk: int) -> tuple[list[dict[str, Any]], list[int]]:
    """The sweep's rows of ``frames`` run in chunks, and the frames without a trial, until cancelled."""
    sweep = sweep_for(settings)
    rows: list[dict[str, Any]] = []
    skipped: list[int] = []
    for start in range(0, len(frames), chunk):
        if task is not None and task.cancelled:
            break
        inputs, missing = frame_inputs(explorer, settings, frames[start:start + chunk])
        try:
            rows.extend(run(sweep, inputs))
        except Cancelled:
            break
        skipped.extend(missing)
        if task is not None:
            task.report((start + chunk) / len(frames))
    return rows, skipped


def over_time_rows(explorer: Explorer, settings: Settings, frames: list[int],
                   task: Task | None) -> tuple[list[dict[str, Any]], list[int]]:
    """The rows of ``frames`` under a method over time, from the tab's frames over time (computing
    those up to the last of ``frames`` not yet computed, in order), and the frames without a trial;
    a cancel keeps the frames done."""
    last = max(frames, default=-1)
    report = (lambda done, of: None) if task is None else (lambda done, of: task.report((done + 1) / (of + 1)))
    try:
        done = explorer.over_time_frames(settings, last, report, lambda: task is not None and task.cancelled)
    except (Stopped, Cancelled):
        done = explorer.over_time.done(settings)
    sweep, scenario = sweep_for(settings), settings.scenario
    point = sweep.points(settings.method)[0]
    computed = max(done, default=-1) if task is not None and task.cancelled else last
    rows = []
    for j in (f for f in frames if f in done):
        inputs = explorer.trial_inputs(settings, j)
        rows.append(trial_row(sweep, inputs, scenario, settings.method, point, inputs.build(scenario, scenario.seed),
                              done[j].result))
    return rows, [f for f in frames if f not in done and f <= computed]


def _float(value: Any) -> float:
    return math.nan if value is None else float(value)
