"""A tab's computation, free of any GUI: settings -> trial -> method result -> metrics -> drawing.

``Explorer`` holds what all tabs share (the loaded sequence, its map); ``compute`` makes one
outcome from one ``Settings`` value, reproducibly: the trial comes from the one trial builder
(``evaluation.trials``), as the evaluation's do.
"""
from __future__ import annotations

import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from cbm import MatchResult, Reuse, match, se2
from cbm.methods import METHODS
from evaluation.agents import agent_pose, choose_ego
from evaluation.diagnosis import Finding, diagnose_failure
from evaluation.fusion import fused_against_truth
from evaluation.metrics import TrialMetrics, evaluate
from evaluation.scenario import FrameInputs, Trial
from evaluation.sweep import run_method
from evaluation.trials import NoTrial, frame_cav_inputs, frame_inputs
from loaders import Frame, Sequence, is_roadside, is_vehicle

from .names import agent_name
from .over_time import FrameOverTime, Runs
from .rows import RowStore
from .seen import Late, Sight, late, sights
from .settings import MAX_CAVS, Settings

TRIALS_KEPT = 8
"""Trials an ``Explorer`` keeps (with their oracle limit): a threshold or method edit, or the
pinned baseline, recomputes on a trial already made."""
INPUTS_KEPT = 1024
"""Frames' trial inputs an ``Explorer`` keeps (a few kB each): a scenario edit other than the
protocol, the range or the delay rebuilds only the trials (a method over time rebuilds every frame's)."""


@dataclass(frozen=True)
class CavChoice:
    """A vehicle that may act as the CAV, and its distance from the ego."""

    id: str
    distance: float

    @property
    def label(self) -> str:
        shown = agent_name("roadside unit", self.id) if is_roadside(self.id) else self.id[:8]
        return f"{shown} · {self.distance:.0f} m"


@dataclass(frozen=True)
class CavOutcome:
    """One more CAV of a several-CAV outcome (``Settings.cavs``), calibrated to the ego on its own trial."""

    cav_id: str | None
    trial: Trial
    result: MatchResult
    metrics: TrialMetrics


@dataclass(frozen=True)
class Fused:
    """Late fusion of one placement of the CAV's boxes with the ego's (``evaluation.fusion``)."""

    boxes: np.ndarray
    """(N, 7) fused boxes in the ego frame."""
    hits: np.ndarray
    """(N,) bool: a true positive at BEV IoU 0.7 against the objects either agent sees."""


@dataclass(frozen=True)
class Outcome:
    """Everything one recompute produced."""

    settings: Settings
    frame_index: int
    ego_id: str | None
    cav_id: str | None
    """The agents (None under the SIND protocol in a frame without two vehicles: abstract agents)."""
    cav_note: str
    """Why the CAV is the one it is (auto choice, or the chosen one missing from this frame)."""
    trial: Trial
    world_boxes: np.ndarray
    """(N, 7) true boxes of every object of the frame, in the ego frame."""
    world_ids: np.ndarray
    result: MatchResult
    metrics: TrialMetrics
    limit: TrialMetrics
    """What least squares on the true pairs reaches on this trial (the oracle): a reference, not a bound."""
    findings: list[Finding]
    seconds: float
    """Server time of the whole recompute (trial, method, metrics, diagnosis)."""
    others: tuple[CavOutcome, ...] = ()
    """The CAVs beyond the first (``Settings.cavs`` > 1), each in its own colour."""
    alone: MatchResult | None = None
    """A method over time: per-frame CBM's answer on the same trial, to compare (None otherwise)."""
    pooled_from: int | None = None
    """A method over time: the first frame whose evidence the answer pools (None: this frame alone)."""
    inputs: FrameInputs | None = None
    """The inputs the trial was made from (``evaluation.scenario.FrameInputs``), for what each agent saw."""
    capture_gap_s: float | None = None
    """Seconds by which the CAV captured before the ego in the dataset's own timestamps (negative:
    after; ``loaders.Sequence.agent_times``); None where the dataset has one time per frame."""
    _kept: dict[str, object] = field(default_factory=dict, repr=False, compare=False)
    """What the views computed from this outcome on their first ask (fusion, CBM's sets), kept."""

    @property
    def placements(self) -> dict[str, np.ndarray]:
        """CAV->ego transforms: before (``init``), after (the estimate), truth."""
        return {"before": self.result.init, "after": self.result.transform, "truth": self.trial.T_true}

    @property
    def voted(self) -> bool:
        """Whether the result has a consensus margin: an anchor won CBM's consensus vote (CBM without
        consensus and the other methods hold no vote)."""
        method = METHODS[self.settings.method]
        return self.result.anchor is not None and (
            method.params_key != "cbm" or bool(method.resolved(self.settings.cbm).consensus))

    def fused(self, placement: str) -> Fused:
        """Late fusion with the CAV's boxes placed as ``placement`` says (a key of ``placements``),
        the scores from the scenario's seed; computed the first time a view asks, then kept."""
        key = f"fused_{placement}"
        if key not in self._kept:
            boxes, hits = fused_against_truth(self.trial, self.placements[placement], self.world_boxes, self.world_ids,
                                              self.settings.scenario.seed, self.frame_index)
            self._kept[key] = Fused(boxes.boxes, hits)
        return self._kept[key]

    def sights(self) -> dict[str, Sight] | None:
        """The ego's and the CAV's sight (``app.session.seen.sights``), computed on the first ask, then kept."""
        if "sights" not in self._kept:
            scenario = self.settings.scenario
            self._kept["sights"] = None if self.inputs is None else sights(self.inputs, self.trial, scenario,
                                                                            scenario.seed)
        return self._kept["sights"]

    def late(self) -> Late | None:
        """Where the CAV saw its objects when its message is late (``app.session.seen.late``), kept."""
        if "late" not in self._kept:
            scenario = self.settings.scenario
            self._kept["late"] = None if self.inputs is None else late(self.inputs, self.trial, scenario,
                                                                        scenario.seed, self.capture_gap_s)
        return self._kept["late"]

    def cbm(self) -> MatchResult:
        """CBM's result on this trial, with its explanation (``cbm.Explanation``), under the thresholds
        the tab's CBM runs with: the method's own result when it is CBM, else CBM run on the first ask
        (the inspector, the walkthrough)."""
        if "cbm" not in self._kept:
            method, trial = METHODS[self.settings.method], self.trial
            params = method.resolved(self.settings.cbm) if method.explains else self.settings.cbm
            self._kept["cbm"] = match(trial.ego_boxes, trial.cav_boxes, trial.init, params, explain=True)
        return self._kept["cbm"]

    @property
    def shown_pairs(self) -> np.ndarray:
        """The pairs the match lines show: CBM's own (before the re-association) when the view asks
        for them and the method has them, else the method's final pairs."""
        if self.settings.view.line_pairs == "own" and self.result.context_pairs is not None:
            return self.result.context_pairs
        return self.result.pairs


def classified_pairs(pairs: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pairs found and true: (right, wrong, missed), each (K, 2) int sorted."""
    true = {tuple(p) for p in np.asarray(truth, int).reshape(-1, 2).tolist()}
    found = {tuple(p) for p in np.asarray(pairs, int).reshape(-1, 2).tolist()}

    def array(chosen: set) -> np.ndarray:
        return np.array(sorted(chosen), dtype=int).reshape(-1, 2)

    return array(found & true), array(found - true), array(true - found)


class Explorer:
    """One loaded dataset, shared read-only by every tab."""

    def __init__(self, sequence: Sequence) -> None:
        self.sequence = sequence
        self.map_segments = _map_segments(sequence)
        self.reuse = Reuse()
        """What CBM built for the last few inputs that a threshold edit does not change (``cbm.engine.EditCache``)."""
        self._trials: OrderedDict[tuple, tuple[FrameInputs, Trial, TrialMetrics]] = OrderedDict()
        self._inputs: OrderedDict[tuple, FrameInputs] = OrderedDict()
        self._trials_lock = threading.Lock()
        self.over_time = Runs()
        """The frames a method over time computed so far, per settings (``app.session.over_time``)."""
        self.rows = RowStore()
        """The sweep rows computed so far, per settings (``app.session.rows``)."""

    def forget(self) -> None:
        """Forget what was kept for the tabs (the edit cache, the recent trials, the runs over time)
        and hand the memory back to the system: called when the last tab closes."""
        with self._trials_lock:
            self._trials.clear()
            self._inputs.clear()
        self.over_time.clear()
        self.rows.clear()
        self.reuse.clear()

    def __len__(self) -> int:
        return len(self.sequence)

    def cav_choices(self, frame_index: int, limit: int = 40) -> list[CavChoice]:
        """Vehicles of a frame that may act as the CAV, nearest first (at most ``limit``)."""
        frame = self.sequence[frame_index]
        ego = choose_ego(frame)
        if ego is None:
            return []
        ego_xy = se2.translation_of(agent_pose(frame, ego))
        vehicles = is_vehicle(frame.categories) & (frame.track_ids != ego)
        ids, xy = frame.track_ids[vehicles], frame.boxes()[vehicles, :2]
        distance = np.linalg.norm(xy - ego_xy, axis=1)
        order = np.lexsort((ids, distance))[:limit]
        return [CavChoice(str(ids[k]), float(distance[k])) for k in order]

    def trial_inputs(self, settings: Settings, index: int) -> FrameInputs:
        """Frame ``index``'s trial inputs under ``settings`` (``evaluation.trials.frame_inputs``), as
        ``compute`` and the sequence runs use them, kept for the ``INPUTS_KEPT`` used last; ``ValueError``
        when the frame makes no trial."""
        scenario = settings.scenario
        key = (index, settings.cav, scenario.protocol, scenario.sensor_range, scenario.window_s)
        with self._trials_lock:
            found = self._inputs.get(key)
            if found is not None:
                self._inputs.move_to_end(key)
                return found
        made = frame_inputs(self.sequence[index], scenario.protocol, settings.cav, sensor_range=scenario.sensor_range,
                            window_s=scenario.window_s)
        with self._trials_lock:
            self._inputs[key] = made
            while len(self._inputs) > INPUTS_KEPT:
                self._inputs.popitem(last=False)
        return made

    def trial(self, settings: Settings, index: int) -> tuple[FrameInputs, Trial, TrialMetrics]:
        """Frame ``index``'s trial inputs and trial under ``settings`` (its scenario and CAV choice, all
        the trial depends on), and what the oracle reaches on it (``Outcome.limit``): made once and
        kept for the ``TRIALS_KEPT`` used last; ``ValueError`` when the frame makes no trial."""
        key = (index, settings.cav, settings.scenario)
        with self._trials_lock:
            found = self._trials.get(key)
            if found is not None:
                self._trials.move_to_end(key)
                return found
        inputs = self.trial_inputs(settings, index)
        trial = inputs.build(settings.scenario, settings.scenario.seed)
        made = inputs, trial, evaluate(METHODS["oracle"](trial.ego_boxes, trial.cav_boxes, trial.init,
                                                         true_pairs=trial.gt_pairs), trial)
        with self._trials_lock:
            self._trials[key] = made
            while len(self._trials) > TRIALS_KEPT:
                self._trials.popitem(last=False)
        return made

    def compute(self, settings: Settings, progress: Callable[[int, int], None] = lambda done, of: None,
                stop: Callable[[], bool] = lambda: False) -> Outcome:
        """Trial, method result, metrics and diagnosis for ``settings``. A method over time first
        computes the frames before this one that it has not yet (``progress(frame, of)`` after
        each, ``app.session.over_time.Stopped`` when ``stop()`` says so)."""
        started = time.perf_counter()
        index = min(max(settings.frame, 0), len(self.sequence) - 1)
        inputs, trial, limit = self.trial(settings, index)
        others = self.other_cavs(settings, index) if settings.cavs > 1 else ()
        alone = pooled_from = None
        if METHODS[settings.method].over_time:
            done = self.over_time.frame(settings, index, lambda j: self._timed_trial(settings, j), progress, stop)
            result, alone, pooled_from = done.result, done.alone, done.since
        else:
            result = _run(settings, trial, inputs, [other.trial for other in others], self.reuse)
        metrics = evaluate(result, trial)
        findings = diagnose_failure(result, trial, metrics, limit, result.explanation, alone)
        world_to_ego = se2.inverse(trial.ego_pose)
        objects = inputs.trial
        return Outcome(settings=settings, frame_index=index, ego_id=objects.get("ego_id"), cav_id=objects.get("cav_id"),
                       cav_note=inputs.note, trial=trial, world_boxes=se2.apply_boxes(world_to_ego, objects["boxes"]),
                       world_ids=np.asarray(objects["ids"]), result=result, metrics=metrics, limit=limit,
                       findings=findings, seconds=time.perf_counter() - started, others=others, alone=alone,
                       pooled_from=pooled_from, inputs=inputs,
                       capture_gap_s=signed_gap(self.sequence[index], objects.get("ego_id"), objects.get("cav_id")),
                       _kept={} if result.explanation is None else {"cbm": result})

    def _timed_trial(self, settings: Settings, index: int) -> tuple[FrameInputs, Trial, float]:
        """Frame ``index``'s inputs and trial and its time in seconds, for a method over time: the
        trial built as ``trial`` builds it, without the oracle's limit (a frame on the way to the one
        shown needs none)."""
        inputs = self.trial_inputs(settings, index)
        return inputs, inputs.build(settings.scenario, settings.scenario.seed), float(self.sequence.timestamps[index])

    def over_time_frames(self, settings: Settings, last: int, progress: Callable[[int, int], None],
                         stop: Callable[[], bool]) -> dict[int, FrameOverTime]:
        """Every frame up to ``last`` that a method over time answers under ``settings``, by frame,
        computing the frames not yet computed (``Stopped`` as in ``compute``)."""
        try:
            self.over_time.frame(settings, last, lambda j: self._timed_trial(settings, j), progress, stop)
        except NoTrial:
            pass
        return {j: done for j, done in self.over_time.done(settings).items() if j <= last}

    def fill_over_time(self, settings: Settings, stop: Callable[[], bool]) -> int:
        """Per-frame CBM on the frames a method over time computed under ``settings`` without it
        (``Runs.fill_alone``), until ``stop()``; the frames filled."""
        return self.over_time.fill_alone(settings, lambda j: self._timed_trial(settings, j), stop)

    def other_cavs(self, settings: Settings, index: int) -> tuple[CavOutcome, ...]:
        """The CAVs of frame ``index`` beyond the first (``evaluation.trials.frame_cav_inputs``), at
        most ``settings.cavs - 1`` of them, each run through the selected method (``cbm-graph``
        with the others as its peers)."""
        scenario, agents = settings.scenario, min(settings.cavs, MAX_CAVS) + 1
        every = frame_cav_inputs(self.sequence[index], scenario.protocol, agents, settings.cav,
                                 sensor_range=scenario.sensor_range, window_s=scenario.window_s)
        trials = [inputs.build(scenario, scenario.seed) for inputs in every]
        outcomes = []
        for k, (inputs, trial) in enumerate(zip(every[1:], trials[1:]), start=1):
            peers = trials[:k] + trials[k + 1:]
            result = run_method(settings.method, trial, settings.params, inputs, peers)
            outcomes.append(CavOutcome(inputs.trial.get("cav_id"), trial, result, evaluate(result, trial)))
        return tuple(outcomes)


def _run(settings: Settings, trial: Trial, frame: FrameInputs, peers: list[Trial],
         reuse: Reuse | None = None) -> MatchResult:
    """The selected method's result; for the methods that build CBM's sets, CBM explains the run
    that answered (``explain=True``), for the diagnosis and the views. ``peers``: the other CAVs'
    trials; ``reuse``: what earlier runs on the same input built that the thresholds do not change."""
    method = METHODS[settings.method]
    if not method.explains:
        return run_method(settings.method, trial, settings.params, frame, peers)
    return match(trial.ego_boxes, trial.cav_boxes, trial.init, method.resolved(settings.params), reuse=reuse,
                 explain=True)


def signed_gap(frame: Frame, ego: str | None, cav: str | None) -> float | None:
    """Seconds by which ``cav`` captured ``frame`` before ``ego`` in the dataset's own timestamps
    (negative: after); None where the dataset keeps no time of either."""
    times = frame.agent_times()
    return times[ego] - times[cav] if ego in times and cav in times else None


def _map_segments(sequence: Sequence) -> dict[str, np.ndarray]:
    """World-frame (N, 2, 2) segments of the map by kind (empty without a map)."""
    segments: dict[str, list[np.ndarray]] = {}
    for kind, points in sequence.map or []:
        if len(points) > 1:
            segments.setdefault(kind, []).append(np.stack([points[:-1, :2], points[1:, :2]], axis=1))
    return {kind: np.concatenate(parts) for kind, parts in segments.items()}
