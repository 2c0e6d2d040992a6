"""Trials on a real detector's boxes: the simulated detections of an agent (sec. IV-A noise) are
replaced by what the detector found, while the ground truth still defines the true pairs.

Each detected box is matched to a ground-truth object of the frame (other than the agent itself)
by centre distance in the agent's frame: an optimal one-to-one assignment, pairs at most
:data:`MATCH_RADIUS` metres apart. A matched detection takes its object's id (so the same object
detected by both agents is a true pair) and its true centre; an unmatched one (a false positive)
gets the id ``det:<role>:<k>`` and pairs with nothing.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import TypeVar

import numpy as np
from scipy.optimize import linear_sum_assignment

from cbm import se2

Trial = TypeVar("Trial")
"""A ``evaluation.scenario.Trial`` (not imported: ``evaluation.scenario`` builds its trials with this module)."""

MATCH_RADIUS = 2.0
"""Metres: the farthest a detection may lie from the ground-truth centre it is matched to."""
FALSE_POSITIVE_CLASS = "car"
"""The class of a detection that matches no object (for methods that read classes, such as VIPS):
CoAlign's and HEAL's first stages detect vehicles only."""


def match_to_truth(detected_xy: np.ndarray, true_xy: np.ndarray, radius: float = MATCH_RADIUS) -> np.ndarray:
    """For each detection, the index of its ground-truth object, or -1: the one-to-one assignment
    of least total centre distance, pairs farther than ``radius`` dropped."""
    matched = np.full(len(detected_xy), -1, dtype=np.int64)
    if not len(detected_xy) or not len(true_xy):
        return matched
    cost = np.linalg.norm(detected_xy[:, None, :2] - true_xy[None, :, :2], axis=2)
    rows, cols = linear_sum_assignment(np.where(cost <= radius, cost, 1e6))
    keep = cost[rows, cols] <= radius
    matched[rows[keep]] = cols[keep]
    return matched


def with_detections(trial: Trial, detections: Mapping[str, np.ndarray], boxes: np.ndarray, ids: np.ndarray,
                    agent_ids: Mapping[str, object]) -> Trial:
    """``trial`` with the detections of ``"ego"`` and / or ``"cav"`` (``(N, 7)`` boxes in that
    agent's frame) in place of its simulated ones; ``boxes``, ``ids``: the frame's world-frame
    ground truth; ``agent_ids``: the id of each agent (never matched to its own detections)."""
    ids = np.asarray(ids)
    changes: dict[str, np.ndarray] = {}
    for role, pose in (("ego", trial.ego_pose), ("cav", trial.cav_pose)):
        if role not in detections:
            continue
        detected = np.asarray(detections[role], dtype=float).reshape(-1, 7)
        others = ids != agent_ids.get(role)
        truth = se2.apply_boxes(se2.inverse(pose), np.asarray(boxes, dtype=float)[others])
        matched = match_to_truth(detected[:, :2], truth[:, :2])
        hit = matched >= 0
        truth_ids = ids[others]
        role_ids = np.array([str(truth_ids[m]) if m >= 0 else f"det:{role}:{k}" for k, m in enumerate(matched)],
                            dtype=str)
        true_xy = detected[:, :2].copy()
        true_xy[hit] = truth[matched[hit], :2]
        changes.update({f"{role}_boxes": detected, f"{role}_ids": role_ids,
                        f"{role}_true_xy": true_xy if role == "ego" else se2.apply_points(trial.T_true, true_xy)})
    trial = dataclasses.replace(trial, **changes)
    return dataclasses.replace(trial, gt_pairs=_pairs_by_id(trial.ego_ids, trial.cav_ids))


def _pairs_by_id(ego_ids: np.ndarray, cav_ids: np.ndarray) -> np.ndarray:
    """(K, 2) (ego index, CAV index) of the ids both lists hold, by ego index."""
    common = np.intersect1d(np.asarray(ego_ids).astype(str), np.asarray(cav_ids).astype(str))
    ego_sees = np.isin(np.asarray(ego_ids).astype(str), common)
    cav_index = {str(i): k for k, i in enumerate(cav_ids)}
    pairs = [(int(k), cav_index[str(ego_ids[k])]) for k in np.flatnonzero(ego_sees)]
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)
