"""The one trial builder: from a dataset frame, a protocol and a CAV choice to the inputs of every
trial made from that frame (``evaluation.scenario.FrameInputs``), and from (frame, scenario, seed) to the
trial itself. The app, ``evaluate.py``, sequence runs and the parameter search all build their
trials here, so what a user tunes in the app is what the evaluation measures.

    from evaluation.trials import build_trial
    trial = build_trial(sequence[12], ScenarioParams(protocol="range", sigma_p=0.3), seed=0)

Agents (``evaluation.agents``): the dataset's ego, and the CAV asked for or else the sequence's steady
CAV (else the vehicle nearest the target distance). Under the SIND protocol the two agents are
abstract (the protocol deals the objects out); the chosen ones set the frame of reference and do
not detect themselves, and a frame without two vehicles uses the objects' centroid. The range and
OPV2V protocols need an ego and a CAV; a dataset that does not say what each agent sees gets the
objects within the sensor range under OPV2V (and a note saying so). When the dataset carries a
detector's boxes (``loaders.open(path, detections=...)``), those of the ego and the CAV replace
their simulated detections (``FrameInputs.detections``; ``evaluation.detected`` for the true pairs).

More than two agents (``frame_cav_inputs``, ``evaluate.py --agents N``): the CAV above, then the
other candidates nearest the target distance, one trial each, CAV ``r`` drawing from
``trial_rng(seed, frame, r)`` (so CAV 0's trial is the two-agent trial, draw for draw).
"""
from __future__ import annotations

import dataclasses
import weakref
from collections import Counter
from collections.abc import Iterable

import numpy as np

from cbm import se2
from evaluation.delay import History, history_of
from evaluation.scenario import FrameInputs, Protocol, ScenarioParams, Trial
from evaluation.visibility import in_range
from loaders import Frame, Sequence
from loaders.detections import DetectedBoxes

from .agents import (
    TARGET_DISTANCE,
    _cav_candidates,
    agent_ids,
    agent_pose,
    choose_cav,
    choose_ego,
    frame_trial_inputs,
    in_trials,
    steady_cav,
)

AUTO_CAV = "auto"
"""The CAV choice that lets the builder pick (the steady CAV, else the nearest the target distance)."""

_STEADY: weakref.WeakKeyDictionary[Sequence, dict[float, str | None]] = weakref.WeakKeyDictionary()
"""Steady CAV of each loaded sequence by target distance (forgotten with the sequence)."""


class NoTrial(ValueError):
    """A frame that cannot make a trial under the protocol; the message says why."""


def sequence_cav(sequence: Sequence, target_distance: float = TARGET_DISTANCE) -> str | None:
    """The sequence's steady CAV (``evaluation.agents.steady_cav``), computed once per sequence."""
    known = _STEADY.setdefault(sequence, {})
    if target_distance not in known:
        known[target_distance] = steady_cav(sequence, target_distance)
    return known[target_distance]


def agents_of(frame: Frame, cav: str = AUTO_CAV,
              target_distance: float = TARGET_DISTANCE) -> tuple[str, str, str] | None:
    """(ego, CAV, note) of ``frame``: ``cav`` when it is in the frame, else the automatic choice
    (the note says which); None when the frame has no ego or no other vehicle."""
    ego = choose_ego(frame)
    if ego is None:
        return None
    present = set(frame.track_ids.tolist()) | set(agent_ids(frame).tolist())
    if cav != AUTO_CAV and cav != ego and cav in present:
        return ego, cav, "chosen"
    steady = sequence_cav(frame.sequence, target_distance)
    note = "auto" if cav == AUTO_CAV else f"auto ({cav[:8]} is not in this frame)"
    if steady not in (None, ego) and steady in present:
        return ego, steady, note
    nearest = choose_cav(frame, ego, target_distance)
    return None if nearest is None else (ego, nearest, note)


def frame_inputs(frame: Frame, protocol: Protocol, cav: str = AUTO_CAV, target_distance: float = TARGET_DISTANCE,
                 sensor_range: float = ScenarioParams.sensor_range, window_s: float = 0.0) -> FrameInputs:
    """The inputs of every trial of ``frame`` under ``protocol``; ``NoTrial`` when it has none.
    ``window_s``: seconds of the frames before it that a late message may come from (``FrameInputs.history``)."""
    agents = agents_of(frame, cav, target_distance)
    if agents is None:
        return _abstract_inputs(frame, protocol)
    ego, chosen, note = agents
    return _pair_inputs(frame, protocol, ego, chosen, note, sensor_range, window_s=window_s)


def frame_cav_inputs(frame: Frame, protocol: Protocol, agents: int = 2, cav: str = AUTO_CAV,
                     target_distance: float = TARGET_DISTANCE, sensor_range: float = ScenarioParams.sensor_range,
                     window_s: float = 0.0) -> list[FrameInputs]:
    """The inputs of the trials of ``frame`` with ``agents`` agents: one per CAV, at most
    ``agents - 1`` (fewer when the frame has fewer candidates); ``NoTrial`` when it has none.

    CAV 0 is ``frame_inputs``'s (its trial is today's two-agent trial, draw for draw); the others
    are the remaining candidates nearest ``target_distance`` from the ego (ties to the smallest id),
    CAV ``r`` drawing from ``trial_rng(seed, frame, r)``. Under the sind protocol each CAV trial deals
    the objects out anew (independent visibility draws); a frame without two vehicles gives
    ``agents - 1`` abstract CAVs, at most one per object of the frame (so a huge ``agents`` stays
    bounded by the frame). Each input carries the others as its ``peers``."""
    if agents < 2:
        raise ValueError(f"agents must be at least 2 (the ego and one CAV), got {agents}")
    first = agents_of(frame, cav, target_distance)
    if first is None:
        abstract = _abstract_inputs(frame, protocol)
        count = min(agents - 1, max(1, len(frame.track_ids)))
        return _with_peers([dataclasses.replace(abstract, stream=rank) for rank in range(count)])
    ego, chosen, note = first
    cavs = [chosen, *other_cavs(frame, ego, chosen, target_distance)][:agents - 1]
    return _with_peers([_pair_inputs(frame, protocol, ego, track, note if rank == 0 else "auto", sensor_range, rank,
                                     window_s) for rank, track in enumerate(cavs)])


def other_cavs(frame: Frame, ego: str, chosen: str, target_distance: float = TARGET_DISTANCE) -> list[str]:
    """The CAV candidates of ``frame`` other than ``chosen``, nearest ``target_distance`` from the
    ego first (ties to the smallest id): the CAVs beyond the first when there are more than two agents."""
    ids, xy = _cav_candidates(frame, ego)
    gap = np.abs(np.linalg.norm(xy - se2.translation_of(agent_pose(frame, ego)), axis=1) - target_distance)
    return [str(ids[k]) for k in np.lexsort((ids, gap)) if str(ids[k]) != chosen]


def sequence_inputs(sequence: Sequence, frames: Iterable[int], protocol: Protocol, cav: str = AUTO_CAV,
                    target_distance: float = TARGET_DISTANCE, sensor_range: float = ScenarioParams.sensor_range,
                    agents: int = 2, window_s: float = 0.0) -> tuple[list[FrameInputs], list[int]]:
    """``frame_cav_inputs`` of each of ``frames`` (one input per frame with two agents), and the
    frames that make no trial (skipped)."""
    inputs, skipped = [], []
    for k in frames:
        try:
            inputs.extend(frame_cav_inputs(sequence[k], protocol, agents, cav, target_distance, sensor_range,
                                           window_s))
        except NoTrial:
            skipped.append(k)
    return inputs, skipped


def short_frames(inputs: Iterable[FrameInputs], agents: int) -> list[int]:
    """The frames of ``inputs`` with fewer than ``agents - 1`` CAVs (too few vehicles)."""
    counts = Counter(item.index for item in inputs)
    return sorted(index for index, count in counts.items() if count < agents - 1)


def build_trial(frame: Frame, scenario: ScenarioParams, seed: int, cav: str = AUTO_CAV,
                target_distance: float = TARGET_DISTANCE) -> Trial:
    """The trial of ``frame`` under ``scenario`` and ``seed``: ``frame_inputs`` then
    ``FrameInputs.build`` (draws from ``trial_rng(seed, frame.index)``)."""
    inputs = frame_inputs(frame, scenario.protocol, cav, target_distance, scenario.sensor_range, scenario.window_s)
    return inputs.build(scenario, seed)


def _abstract_inputs(frame: Frame, protocol: Protocol) -> FrameInputs:
    """The sind trial of a frame without two vehicles (abstract agents); ``NoTrial`` otherwise."""
    if protocol != "sind":
        raise NoTrial(f"frame {frame.index} has no ego and CAV for the {protocol} protocol")
    inputs = {"boxes": frame.boxes(), "ids": frame.track_ids}
    return FrameInputs(frame.index, inputs, labels=frame.categories, note="no two vehicles: abstract agents",
                       times=frame.sequence.timestamps)


def _pair_inputs(frame: Frame, protocol: Protocol, ego: str, chosen: str, note: str, sensor_range: float,
                 stream: int = 0, window_s: float = 0.0) -> FrameInputs:
    """The inputs of the trial of ``ego`` and the CAV ``chosen``, drawing from stream ``stream``."""
    inputs = frame_trial_inputs(frame, ego, chosen)
    gap = capture_gap(frame, ego, chosen)
    if window_s and not frame.sequence.tracked:
        note += "; the dataset's frames are samples whose objects are not tracked: no late message is made"
    inputs["cav_reported_pose"] = frame.predicted_pose(chosen)
    said = inputs["visibility"] or {}
    if protocol == "opv2v" and len(said) < 2:
        inputs["visibility"] = {**_visibility_by_range(inputs, sensor_range), **said}
        unsaid = " and ".join(role for role in ("ego", "cav") if role not in said)
        note += f"; the dataset does not say what the {unsaid} sees: sensor range used"
    detected = _detections(frame, ego, chosen)
    if detected:
        note += f"; real detections of {' and '.join(detected)}"
    window = window_s + gap
    history = _history(frame, chosen, inputs["ids"], window) if window > 0.0 else None
    return FrameInputs(frame.index, inputs, labels=frame.categories[in_trials(frame)], note=note,
                       detections=detected or None, stream=stream, times=frame.sequence.timestamps, cav=str(chosen),
                       history=history, gap_s=gap)


def capture_gap(frame: Frame, ego: str, cav: str) -> float:
    """Seconds by which the CAV's capture precedes the ego's in the dataset's own timestamps (0 where
    the dataset has one time per frame; never negative: a later CAV capture counts as none)."""
    times = frame.agent_times()
    if not times or ego not in times or cav not in times:
        return 0.0
    return max(times[ego] - times[cav], 0.0)


def _history(frame: Frame, cav: str, ids: np.ndarray, window_s: float) -> History:
    """The frames from ``window_s`` seconds (and one frame more) before ``frame`` up to it, as the CAV
    saw them: the boxes of ``frame``'s objects ``ids`` in each, and the CAV's pose (``evaluation.delay``).
    Never beyond the start of ``frame``'s scenario, nor beyond ``frame`` itself where the sequence's
    track ids do not follow objects from frame to frame (``Sequence.tracked``)."""
    sequence, index = frame.sequence, frame.index
    times, boxes, poses = [], [], []
    for j in range(index, -1, -1):
        earlier = sequence[j]
        if earlier.scenario != frame.scenario or (j < index and not sequence.tracked):
            break
        try:
            pose = agent_pose(earlier, cav)
        except KeyError:
            break
        times.append(earlier.timestamp)
        boxes.append(_aligned(earlier, ids))
        poses.append(pose)
        if frame.timestamp - earlier.timestamp >= window_s:
            break
    return history_of(times[::-1], boxes[::-1], poses[::-1])


def _aligned(frame: Frame, ids: np.ndarray) -> np.ndarray:
    """(len(ids), 7) the boxes of ``frame``'s objects ``ids`` in that order, NaN where one is absent."""
    kept = in_trials(frame)
    have, boxes = frame.track_ids[kept], frame.boxes()[kept]
    out = np.full((len(ids), 7), np.nan)
    order = np.argsort(have)
    at = np.searchsorted(have, ids, sorter=order)
    found = (at < len(have)) & (have[order[np.minimum(at, len(have) - 1)]] == ids) if len(have) else at < 0
    out[found] = boxes[order[at[found]]]
    return out


def _with_peers(inputs: list[FrameInputs]) -> list[FrameInputs]:
    """Each of ``inputs`` with all of them as its ``cohort``, one shared tuple (none with one CAV):
    its ``peers`` are the others."""
    if len(inputs) < 2:
        return inputs
    cohort = tuple(inputs)
    return [dataclasses.replace(item, cohort=cohort) for item in inputs]


def _detections(frame: Frame, ego: str, cav: str) -> dict[str, DetectedBoxes]:
    """The detector's boxes (``loaders.detections``) of the ego and the CAV, by role, where the
    frame has them: they replace the simulated detections of those agents."""
    found = frame.detections or {}
    return {role: found[agent] for role, agent in (("ego", ego), ("cav", cav)) if agent in found}


def _visibility_by_range(inputs: dict, sensor_range: float) -> dict[str, np.ndarray]:
    """What each agent sees when the dataset does not say: the objects within sensor range."""
    boxes, ids = inputs["boxes"], np.asarray(inputs["ids"])
    return {"ego": ids[in_range(boxes, inputs["ego_pose"], sensor_range)],
            "cav": ids[in_range(boxes, inputs["cav_pose"], sensor_range)]}
