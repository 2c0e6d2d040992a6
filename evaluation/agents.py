"""Which agents make a trial in a frame: the ego, the CAV, their poses and what each sees.

One deterministic rule, used by the trial builder (``evaluation.trials``) for the app and the
evaluation alike:

- **ego**: the dataset's own ego (``Sequence.ego``) when it is present in the frame; otherwise (e.g.
  synthetic scenes, drone recordings) the vehicle nearest the centroid of the frame's objects.
- **CAV candidates**: the frame's agents other than the ego when there are any (OPV2V, DAIR-V2X:
  they carry the per-agent visibility); otherwise the frame's vehicles (``is_vehicle``) other than
  the ego.
- **steady CAV** of a sequence: the candidate that is ``STEADY_BAND`` times the target distance
  from the ego (15 to 40 m for 25 m) in the most frames, so that stepping through the frames keeps
  one CAV; **CAV** of a frame: the steady CAV where it is present, else the candidate whose distance
  from the ego is closest to the target distance.

Ties go to the smallest id (string order), so the choice never depends on row order. An agent that
is not in the frame's agent table is an object of the frame, and its pose is its box (centre, yaw).
"""
from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from cbm import se2
from loaders import Frame, is_vehicle

TARGET_DISTANCE = 25.0
"""Metres. Default distance from the ego of the CAV ``choose_cav`` prefers."""
STEADY_BAND = (0.6, 1.6)
"""The steady CAV is counted in a frame when it lies between these multiples of the target distance."""


def choose_ego(frame: Frame) -> str | None:
    """The ego of ``frame``: the dataset's ego if present, else the vehicle nearest the objects'
    centroid; None when there is neither."""
    ego = frame.ego
    if ego is not None and ego in agent_ids(frame):
        return ego
    vehicles = is_vehicle(frame.categories)
    if not vehicles.any():
        return None
    centroid = frame.boxes()[:, :2].mean(axis=0)
    distance = np.linalg.norm(frame.boxes()[vehicles, :2] - centroid, axis=1)
    return _nearest(frame.track_ids[vehicles], distance)


def choose_cav(frame: Frame, ego_id: str, target_distance: float = TARGET_DISTANCE) -> str | None:
    """The CAV of ``frame`` for ``ego_id``: the other agent, or failing agents the other vehicle,
    whose distance from the ego is closest to ``target_distance`` metres; None when there is none."""
    ids, xy = _cav_candidates(frame, ego_id)
    if not len(ids):
        return None
    gap = np.abs(np.linalg.norm(xy - se2.translation_of(agent_pose(frame, ego_id)), axis=1) - target_distance)
    return _nearest(ids, gap)


def steady_cav(frames: Iterable[Frame], target_distance: float = TARGET_DISTANCE) -> str | None:
    """The CAV candidate that lies within ``STEADY_BAND`` times ``target_distance`` of the ego in
    the most of ``frames`` (ties to the smallest id); None when none ever does."""
    near, far = (factor * target_distance for factor in STEADY_BAND)
    counts: dict[str, int] = {}
    for frame in frames:
        ego = choose_ego(frame)
        if ego is None:
            continue
        ids, xy = _cav_candidates(frame, ego)
        distance = np.linalg.norm(xy - se2.translation_of(agent_pose(frame, ego)), axis=1)
        for track in ids[(distance >= near) & (distance <= far)]:
            counts[str(track)] = counts.get(str(track), 0) + 1
    return min(counts, key=lambda track: (-counts[track], track)) if counts else None


def agent_pose(frame: Frame, agent_id: str) -> np.ndarray:
    """``(3, 3)`` agent->world pose: from the agent table, else from the object's box (centre, yaw)."""
    if agent_id in agent_ids(frame):
        return frame.agent_pose(agent_id)
    rows = np.flatnonzero(frame.track_ids == agent_id)
    if not len(rows):
        raise KeyError(f"{frame.sequence.name} frame {frame.index}: no agent or object {agent_id!r}")
    x, y, yaw = frame.boxes()[rows[0], [0, 1, 6]]
    return se2.make(x, y, yaw)


def frame_trial_inputs(frame: Frame, ego_id: str, cav_id: str) -> dict[str, Any]:
    """The keyword arguments of ``evaluation.scenario.make_trial`` for this frame and agent pair (all but
    ``params`` and ``rng``): ``boxes, ids, ego_pose, cav_pose, cav_id, ego_id, visibility``; objects
    of the sequence's ``left_out_of_trials`` categories are not among them.

    ``visibility`` maps ``"ego"`` and / or ``"cav"`` to the ids that agent sees, for the agents the
    dataset says it of (the opv2v protocol needs both; line of sight uses what there is), else None.
    """
    seen = frame.visibility or {}
    said = {role: seen[agent] for role, agent in (("ego", ego_id), ("cav", cav_id)) if agent in seen}
    kept = in_trials(frame)
    return {
        "boxes": frame.boxes()[kept],
        "ids": frame.track_ids[kept],
        "ego_pose": agent_pose(frame, ego_id),
        "cav_pose": agent_pose(frame, cav_id),
        "cav_id": cav_id,
        "ego_id": ego_id,
        "visibility": said or None,
    }


def in_trials(frame: Frame) -> np.ndarray:
    """Which of the frame's objects take part in trials (not of a ``left_out_of_trials`` category)."""
    return ~np.isin(frame.categories, list(frame.sequence.left_out_of_trials))


def agent_ids(frame: Frame) -> np.ndarray:
    """Ids of the frame's agents (empty when the dataset has no agent table)."""
    agents = frame.agents
    return np.empty(0, dtype=str) if agents is None else agents["agent_id"].to_numpy().astype(str)


def _cav_candidates(frame: Frame, ego_id: str) -> tuple[np.ndarray, np.ndarray]:
    """Ids and world centres of the agents other than the ego, or else of the other vehicles."""
    agents = frame.agents
    if agents is not None:
        others = agents["agent_id"].to_numpy().astype(str) != ego_id
        if others.any():
            return agents["agent_id"].to_numpy().astype(str)[others], agents.select("x", "y").to_numpy()[others]
    vehicles = is_vehicle(frame.categories) & (frame.track_ids != ego_id)
    return frame.track_ids[vehicles], frame.boxes()[vehicles, :2]


def _nearest(ids: np.ndarray, key: np.ndarray) -> str:
    """The id of the smallest ``key``, ties to the smallest id."""
    return str(ids[np.lexsort((ids, key))[0]])
