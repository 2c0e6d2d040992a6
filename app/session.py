"""A tab's computation, free of any GUI: settings -> trial -> method result -> metrics -> drawing.

``Explorer`` holds what all tabs share (the loaded sequence, its map); ``compute`` makes one
outcome from one ``Settings`` value, reproducibly: the trial draws from
``trial_rng(seed, frame)``, as the evaluation command does.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from cbm import se2
from cbm.baselines import match_oracle
from cbm.diagnosis import Finding, diagnose
from cbm.inspect import Inspection
from cbm.methods import METHODS
from cbm.metrics import TrialMetrics, evaluate
from cbm.result import MatchResult
from cbm.scenario import Trial, in_range, make_trial, trial_rng
from cbm.sweep import FrameInputs, run_method
from loaders import Sequence, is_vehicle
from loaders.agents import agent_pose, choose_cav, choose_ego, frame_trial_inputs

from .settings import AUTO_CAV, Settings


@dataclass(frozen=True)
class CavChoice:
    """A vehicle that may act as the CAV, and its distance from the ego."""

    id: str
    distance: float

    @property
    def label(self) -> str:
        return f"{self.id[:8]} · {self.distance:.0f} m"


@dataclass(frozen=True)
class TrialInputs:
    """One frame's inputs as a tab makes its trial: the sweep's ``FrameInputs`` and the agents."""

    frame: FrameInputs
    ego_id: str
    cav_id: str
    cav_note: str


@dataclass(frozen=True)
class Outcome:
    """Everything one recompute produced."""

    settings: Settings
    frame_index: int
    ego_id: str
    cav_id: str
    cav_note: str
    """Why the CAV is the one it is (auto choice, or the chosen one missing from this frame)."""
    trial: Trial
    world_boxes: np.ndarray
    """(N, 7) true boxes of every object of the frame, in the ego frame."""
    world_ids: np.ndarray
    result: MatchResult
    metrics: TrialMetrics
    limit: TrialMetrics
    """What least squares on the true pairs reaches on this trial (the oracle): the limit."""
    findings: list[Finding]
    seconds: float
    """Server time of the whole recompute (trial, method, metrics, diagnosis)."""


class Explorer:
    """One loaded dataset, shared read-only by every tab."""

    def __init__(self, sequence: Sequence) -> None:
        self.sequence = sequence
        self.map_segments = _map_segments(sequence)
        self.steady_cav = steady_cav(sequence)
        """The automatic CAV where present: the vehicle most often 15-40 m from the ego."""

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

    def trial_inputs(self, settings: Settings, index: int) -> TrialInputs:
        """Frame ``index``'s trial inputs under ``settings`` (ego, CAV, visibility), as ``compute``
        and the sequence runs use them; ``ValueError`` when the frame has no ego or no CAV."""
        frame = self.sequence[index]
        ego = choose_ego(frame)
        if ego is None:
            raise ValueError(f"frame {index} has no vehicle that could be the ego")
        cav, note = self._cav(frame, ego, settings.cav)
        inputs = frame_trial_inputs(frame, ego, cav)
        if settings.scenario.protocol == "opv2v" and inputs["visibility"] is None:
            inputs["visibility"] = _visibility_by_range(inputs, settings.scenario.sensor_range)
            note += "; no per-agent visibility in this dataset: sensor range used"
        return TrialInputs(FrameInputs(index, inputs, labels=frame.categories), ego, cav, note)

    def compute(self, settings: Settings) -> Outcome:
        """Trial, method result, metrics and diagnosis for ``settings``."""
        started = time.perf_counter()
        index = min(max(settings.frame, 0), len(self.sequence) - 1)
        prepared = self.trial_inputs(settings, index)
        inputs, ego, cav, note = prepared.frame.trial, prepared.ego_id, prepared.cav_id, prepared.cav_note
        trial = make_trial(**inputs, params=settings.scenario, rng=trial_rng(settings.scenario.seed, index))
        result, findings = _run(settings, trial, prepared.frame)
        metrics = evaluate(result, trial)
        limit = evaluate(match_oracle(trial.ego_boxes, trial.cav_boxes, trial.init, true_pairs=trial.gt_pairs), trial)
        world_to_ego = se2.inverse(trial.ego_pose)
        return Outcome(settings=settings, frame_index=index, ego_id=ego, cav_id=cav, cav_note=note, trial=trial,
                       world_boxes=se2.apply_boxes(world_to_ego, inputs["boxes"]), world_ids=np.asarray(inputs["ids"]),
                       result=result, metrics=metrics, limit=limit, findings=findings,
                       seconds=time.perf_counter() - started)

    def _cav(self, frame, ego: str, wanted: str) -> tuple[str, str]:
        present = set(frame.track_ids.tolist())
        if wanted != AUTO_CAV and wanted != ego and wanted in present:
            return wanted, "chosen"
        if wanted == AUTO_CAV and self.steady_cav not in (None, ego) and self.steady_cav in present:
            return self.steady_cav, "auto"
        cav = choose_cav(frame, ego)
        if cav is None:
            raise ValueError(f"frame {frame.index} has no other vehicle to act as the CAV")
        return cav, "auto" if wanted == AUTO_CAV else f"auto ({wanted[:8]} is not in this frame)"

def steady_cav(sequence: Sequence, near: float = 15.0, far: float = 40.0) -> str | None:
    """The vehicle that is ``near``-``far`` metres from the ego in the most frames (ties to the
    smallest id); None when no vehicle ever is."""
    counts: dict[str, int] = {}
    for frame in sequence:
        ego = choose_ego(frame)
        if ego is None:
            continue
        vehicles = is_vehicle(frame.categories) & (frame.track_ids != ego)
        distance = np.linalg.norm(frame.boxes()[vehicles, :2] - se2.translation_of(agent_pose(frame, ego)), axis=1)
        for track in frame.track_ids[vehicles][(distance >= near) & (distance <= far)]:
            counts[str(track)] = counts.get(str(track), 0) + 1
    return min(counts, key=lambda track: (-counts[track], track)) if counts else None


def _visibility_by_range(inputs: dict[str, Any], sensor_range: float) -> dict[str, np.ndarray]:
    """What each agent sees when the dataset does not say: the objects within sensor range."""
    boxes, ids = inputs["boxes"], np.asarray(inputs["ids"])
    return {"ego": ids[in_range(boxes, inputs["ego_pose"], sensor_range)],
            "cav": ids[in_range(boxes, inputs["cav_pose"], sensor_range)]}


def _run(settings: Settings, trial: Trial, frame: FrameInputs) -> tuple[MatchResult, list[Finding]]:
    """The selected method's result and, for the methods that build CBM's sets, why it failed: the
    sets are built once and serve both the match and the diagnosis."""
    method = METHODS[settings.method]
    if not method.explains:
        return run_method(settings.method, trial, settings.params, frame), []
    inspection = Inspection(trial.ego_boxes, trial.cav_boxes, trial.init, method.resolved(settings.params))
    result = inspection.match()
    return result, diagnose(result, trial, inspection)


def _map_segments(sequence: Sequence) -> dict[str, np.ndarray]:
    """World-frame (N, 2, 2) segments of the map by kind (empty without a map)."""
    segments: dict[str, list[np.ndarray]] = {}
    for kind, points in sequence.map or []:
        if len(points) > 1:
            segments.setdefault(kind, []).append(np.stack([points[:-1, :2], points[1:, :2]], axis=1))
    return {kind: np.concatenate(parts) for kind, parts in segments.items()}
