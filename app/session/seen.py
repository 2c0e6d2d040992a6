"""What each agent saw of a frame, computed for the views: its sight (the area its sensor sees, the
shadows behind the boxes, ``evaluation.sight``) and, for a late message (``evaluation.delay``),
where the CAV saw the objects and how far they moved while the message travelled.

Both come from the very inputs the trial was made from (``FrameInputs.late``), so what is drawn is
what the trial decided: under line of sight an object the trial says an agent does not see lies
outside its sight (in a shadow or out of range), unless it was a missed detection or the dataset
says what the agent saw (then the sight is the range alone, and the dataset decides within it)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cbm import se2
from evaluation.clutter import is_false
from evaluation.scenario import FrameInputs, ScenarioParams, Trial
from evaluation.sight import sight_outline

ROLES = ("ego", "cav")
MOVED_M = 0.2
"""Metres: an object that moved less than this while the message travelled counts as standing still
(a detector's noise is about as large)."""


@dataclass(frozen=True)
class Sight:
    """What one agent's sensor sees, in the agent's own frame (the CAV's: at its capture)."""

    outline: np.ndarray
    """(R, 2) the visible area's outline (``evaluation.sight.sight_outline``): the first box met or the
    range along each ray; the range's circle where boxes hide nothing in this trial."""
    shadows: bool
    """Whether boxes cast shadows: line of sight decides what the agent sees (``ScenarioParams.sight``)
    and the dataset does not say it."""
    said: bool
    """Whether the dataset says what this agent saw (its visibility decides within the range)."""


@dataclass(frozen=True)
class Late:
    """A late message: the CAV's objects where it saw them, ``age_s`` before the ego's frame."""

    age_s: float
    """Seconds between the CAV's capture and the ego's frame (``Trial.message_age_s``)."""
    gap_s: float | None
    """Seconds by which the CAV captured before the ego in the dataset's own timestamps (negative:
    after); None where the dataset has one time per frame."""
    ids: np.ndarray
    """(K,) the objects the CAV detected (its false boxes left out)."""
    captured: np.ndarray
    """(K, 2) their centres where the CAV saw them, in the ego frame."""
    now: np.ndarray
    """(K, 2) their centres at the ego's frame, in the ego frame."""

    @property
    def moved(self) -> np.ndarray:
        """(K,) metres each object moved while the message travelled."""
        return np.linalg.norm(self.now - self.captured, axis=1)

    @property
    def moving(self) -> np.ndarray:
        """(K,) which objects moved at least ``MOVED_M``."""
        return self.moved >= MOVED_M


def sights(inputs: FrameInputs, trial: Trial, params: ScenarioParams, seed: int) -> dict[str, Sight] | None:
    """The ego's and the CAV's sight under the range protocol (each in its own frame), None under the
    others (the sind protocol deals the objects out; opv2v takes what the dataset says)."""
    if params.protocol != "range":
        return None
    said = inputs.trial.get("visibility") or {}
    late = inputs.late(params, seed)
    world = {"ego": np.asarray(inputs.trial["boxes"], float), "cav": _present(late.get("cav_world", world_of(inputs)))}
    poses = {"ego": trial.ego_pose, "cav": trial.cav_pose}
    found = {}
    for role in ROLES:
        shadows = params.sight and role not in said
        boxes = se2.apply_boxes(se2.inverse(poses[role]), world[role]) if shadows else np.zeros((0, 7))
        found[role] = Sight(sight_outline(within(boxes, params.sensor_range), np.zeros(2), params.sensor_range),
                            shadows, role in said)
    return found


def within(boxes: np.ndarray, sensor_range: float) -> np.ndarray:
    """The boxes (in the agent's frame) some part of whose footprint may lie within ``sensor_range``:
    the others cannot cut a ray the range already ends."""
    return boxes[np.linalg.norm(boxes[:, :2], axis=1) <= sensor_range + np.hypot(boxes[:, 3], boxes[:, 4]) / 2]


def late(inputs: FrameInputs, trial: Trial, params: ScenarioParams, seed: int, gap_s: float | None) -> Late | None:
    """Where the CAV saw the objects it detected and where they are now (ego frame), when its message is
    late (by the scenario's delay or the dataset's own gap); None when it is not."""
    if trial.message_age_s == 0.0 and not gap_s and not params.delayed:
        return None
    ids = np.asarray(inputs.trial["ids"])
    real = trial.cav_ids[~is_false(trial.cav_ids)]
    picked = np.flatnonzero(np.isin(ids, real))
    to_ego = se2.inverse(trial.ego_pose)
    captured = inputs.late(params, seed).get("cav_world", world_of(inputs))
    return Late(trial.message_age_s, gap_s, ids[picked],
                se2.apply_points(to_ego, np.asarray(captured, float)[picked, :2]),
                se2.apply_points(to_ego, world_of(inputs)[picked, :2]))


def world_of(inputs: FrameInputs) -> np.ndarray:
    """(N, 7) the frame's objects in the world, at the ego's frame."""
    return np.asarray(inputs.trial["boxes"], float)


def _present(boxes: np.ndarray) -> np.ndarray:
    """The rows of ``boxes`` that are there (a late message's objects absent at capture are NaN)."""
    boxes = np.asarray(boxes, float)
    return boxes[~np.isnan(boxes[:, 0])]
