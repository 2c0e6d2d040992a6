"""A method over time (``cbm-time``) in a tab: the frames computed in time order, kept per settings.

A calibrator over time answers frame k from the frames before it, so frame k is computed only after
0..k-1. ``Runs`` keeps, per settings that change the answers (everything but the frame and the
view), the frames computed so far and the calibrator where it stopped: stepping forward costs one
frame, going back costs nothing, and a jump ahead computes the frames in between, reporting its
progress and stopping when asked (``Stopped``: the frames done are kept).

Each frame is compared with per-frame CBM on the same trial (the timeline, the metrics). That
comparison is not on the way to the frame asked for: a catch-up steps the calibrator only, and
per-frame CBM comes for the frame shown at once and for the frames before afterwards
(``fill_alone``, stopped by a newer edit). A frame the calibrator answered without its track (the
error not seen to persist yet: ``TrackNote.predicted`` is None) ran per-frame CBM itself, so its
answer is taken as is.
"""
from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

from cbm import MatchResult, SequenceCalibrator, match
from evaluation.metrics import TrialMetrics, evaluate
from evaluation.scenario import FrameInputs, Trial
from evaluation.sweep import calibrator_for
from evaluation.trials import NoTrial

from .settings import Settings, ViewOptions

RUNS_KEPT = 4
"""Settings whose frames over time are kept (the current ones, and a few the user came from)."""

TrialOf = Callable[[int], tuple[FrameInputs, Trial, float]]
"""Frame j's inputs, trial and time in seconds; ``NoTrial`` for a frame without a trial."""


class Stopped(Exception):
    """A catch-up over the frames before the one asked for was stopped; ``frame``: the last computed."""

    def __init__(self, frame: int) -> None:
        super().__init__(f"stopped at frame {frame}")
        self.frame = frame


@dataclass(frozen=True)
class FrameOverTime:
    """One frame's answer over time, the first frame whose evidence the answer pools (None when it
    pools none: per-frame CBM's answer), and per-frame CBM's answer on the same trial (None until
    computed, ``Runs.fill_alone``)."""

    result: MatchResult
    since: int | None
    metrics: TrialMetrics
    alone: MatchResult | None = None
    alone_metrics: TrialMetrics | None = None


@dataclass
class Run:
    """The frames of one setting computed so far, in time order, and the calibrator after them."""

    calibrator: SequenceCalibrator
    done: dict[int, FrameOverTime] = field(default_factory=dict)
    order: list[int] = field(default_factory=list)
    """The frames done, in time order (as ``times``)."""
    times: list[float] = field(default_factory=list)
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

    def frame(self, settings: Settings, index: int, trial_of: TrialOf, progress: Callable[[int, int], None],
              stop: Callable[[], bool]) -> FrameOverTime:
        """Frame ``index`` over time with per-frame CBM beside, computing the frames before it first
        (``trial_of(j)``; a frame without a trial is passed over); ``progress(j, index)`` after each,
        ``Stopped`` when ``stop()`` says so between two frames."""
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
            found = run.done[index]
        return found if found.alone is not None else self._with_alone(run, index, trial_of)

    def to_compute(self, settings: Settings, index: int) -> int:
        """How many frames a request for frame ``index`` under ``settings`` computes (it and those
        before it not yet computed)."""
        found = self._found(settings)
        return max(0, index + 1 - (0 if found is None else found.next_frame))

    def fill_alone(self, settings: Settings, trial_of: TrialOf, stop: Callable[[], bool]) -> int:
        """Per-frame CBM on every frame done under ``settings`` that lacks it, the latest first,
        until ``stop()`` says so; the frames filled."""
        run = self._found(settings)
        if run is None:
            return 0
        with run.lock:
            missing = [j for j in reversed(run.order) if run.done[j].alone is None]
        filled = 0
        for j in missing:
            if stop():
                break
            self._with_alone(run, j, trial_of)
            filled += 1
        return filled

    def done(self, settings: Settings) -> dict[int, FrameOverTime]:
        """The frames computed so far under ``settings`` (a copy; empty for settings never run)."""
        found = self._found(settings)
        if found is None:
            return {}
        with found.lock:
            return dict(found.done)

    def _found(self, settings: Settings) -> Run | None:
        key = run_key(settings)
        with self._lock:
            return next((run for known, run in self._runs if known == key), None)

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
    def _step(run: Run, settings: Settings, j: int, trial_of: TrialOf) -> None:
        """Frame j through the calibrator (per-frame CBM's answer kept where it is the calibrator's own)."""
        try:
            inputs, trial, time_s = trial_of(j)
        except NoTrial:
            return
        result = run.calibrator.step(trial.ego_boxes, trial.cav_boxes, trial.init, time_s,
                                     agent=inputs.trial.get("cav_id"))
        note = result.track
        pooled = note is not None and note.pooled > 0 and note.event not in ("per frame", "lost")
        since = next((k for k, t in zip(run.order, run.times) if t >= note.since_s), j) if pooled else None
        metrics = evaluate(result, trial)
        done = FrameOverTime(result, since, metrics)
        if note is not None and note.predicted is None:
            done = dataclasses.replace(done, alone=dataclasses.replace(result, track=None), alone_metrics=metrics)
        run.order.append(j)
        run.times.append(time_s)
        run.done[j] = done

    @staticmethod
    def _with_alone(run: Run, j: int, trial_of: TrialOf) -> FrameOverTime:
        """Frame j with per-frame CBM's answer on its trial (computed outside the run's lock)."""
        _, trial, _ = trial_of(j)
        alone = match(trial.ego_boxes, trial.cav_boxes, trial.init, run.calibrator.params)
        with run.lock:
            done = dataclasses.replace(run.done[j], alone=alone, alone_metrics=evaluate(alone, trial))
            run.done[j] = done
        return done
