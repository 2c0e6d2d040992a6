"""A method over time (``cbm-time``) in a tab: the frames computed in time order, kept per settings.

A calibrator over time answers frame k from the frames before it, so frame k is computed only after
0..k-1. ``Runs`` keeps, per settings that change the answers (everything but the frame and the
view), the frames computed so far and the calibrator where it stopped: stepping forward costs one
frame, going back costs nothing, and a jump ahead computes the frames in between, reporting its
progress and stopping when asked (``Stopped``: the frames done are kept). Each frame also keeps
per-frame CBM's answer on the same trial, for the timeline and the metrics to compare.
"""
from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

from cbm import MatchResult, SequenceCalibrator, match
from evaluation.metrics import TrialMetrics, evaluate
from evaluation.sweep import calibrator_for
from evaluation.trials import NoTrial

from .settings import Settings, ViewOptions

RUNS_KEPT = 4
"""Settings whose frames over time are kept (the current ones, and a few the user came from)."""


class Stopped(Exception):
    """A catch-up over the frames before the one asked for was stopped; ``frame``: the last computed."""

    def __init__(self, frame: int) -> None:
        super().__init__(f"stopped at frame {frame}")
        self.frame = frame


@dataclass(frozen=True)
class FrameOverTime:
    """One frame's answer over time, per-frame CBM's on the same trial, and the first frame whose
    evidence the answer pools (None when it pools none: per-frame CBM's answer)."""

    result: MatchResult
    alone: MatchResult
    since: int | None
    metrics: TrialMetrics
    alone_metrics: TrialMetrics


@dataclass
class Run:
    """The frames of one setting computed so far, in time order, and the calibrator after them."""

    calibrator: SequenceCalibrator
    done: dict[int, FrameOverTime] = field(default_factory=dict)
    times: dict[int, float] = field(default_factory=dict)
    next_frame: int = 0
    lock: threading.Lock = field(default_factory=threading.Lock)


def run_key(settings: Settings) -> Settings:
    """What a frame's answer over time depends on: the settings without the frame and the view."""
    return dataclasses.replace(settings, frame=0, view=ViewOptions())


class Runs:
    """The ``RUNS_KEPT`` runs used last, by ``run_key`` (most recent last)."""

    def __init__(self) -> None:
        self._runs: list[tuple[Settings, Run]] = []
        self._lock = threading.Lock()

    def clear(self) -> None:
        """Forget every run (no tab shows one any more)."""
        with self._lock:
            self._runs.clear()

    def frame(self, settings: Settings, index: int, trial_of: Callable, progress: Callable[[int, int], None],
              stop: Callable[[], bool]) -> FrameOverTime:
        """Frame ``index`` over time, computing the frames before it first (``trial_of(j)``: frame j's
        inputs and trial, ``NoTrial`` for a frame without one, which is passed over); ``progress(j,
        index)`` after each, ``Stopped`` when ``stop()`` says so between two frames."""
        run = self._run(settings)
        with run.lock:
            if index not in run.done and index < run.next_frame:
                raise NoTrial(f"frame {index} makes no trial under these settings")
            while run.next_frame <= index:
                if run.next_frame > 0 and stop():
                    raise Stopped(max(run.done, default=0))
                self._step(run, settings, run.next_frame, trial_of)
                progress(run.next_frame, index)
                run.next_frame += 1
            if index not in run.done:
                raise NoTrial(f"frame {index} makes no trial under these settings")
            return run.done[index]

    def done(self, settings: Settings) -> dict[int, FrameOverTime]:
        """The frames computed so far under ``settings`` (a copy; empty for settings never run)."""
        key = run_key(settings)
        with self._lock:
            found = next((run for known, run in self._runs if known == key), None)
        return {} if found is None else dict(found.done)

    def _run(self, settings: Settings) -> Run:
        key = run_key(settings)
        with self._lock:
            found = next((run for known, run in self._runs if known == key), None)
            if found is None:
                found = Run(calibrator_for(settings.method, settings.params, settings.tracking))
            self._runs = [(known, run) for known, run in self._runs if run is not found][-(RUNS_KEPT - 1):]
            self._runs.append((key, found))
            return found

    @staticmethod
    def _step(run: Run, settings: Settings, j: int, trial_of: Callable) -> None:
        """Frame j through the calibrator, and per-frame CBM on its trial."""
        try:
            inputs, trial, time_s = trial_of(j)
        except NoTrial:
            return
        result = run.calibrator.step(trial.ego_boxes, trial.cav_boxes, trial.init, time_s,
                                     agent=inputs.trial.get("cav_id"))
        alone = match(trial.ego_boxes, trial.cav_boxes, trial.init, run.calibrator.params)
        note = result.track
        pooled = note is not None and note.pooled > 0 and note.event not in ("per frame", "lost")
        since = next((k for k in sorted(run.done) if run.times[k] >= note.since_s), j) if pooled else None
        run.times[j] = time_s
        run.done[j] = FrameOverTime(result, alone, since, evaluate(result, trial), evaluate(alone, trial))
