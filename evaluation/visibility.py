"""Who sees what in a trial (``evaluation.scenario``): the SIND protocol's deal (sec. IV-A), each
agent's sensor range, the line of sight among the boxes (``evaluation.sight``), and what a dataset
says each agent saw, which wins over a model wherever the dataset says it."""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from cbm import se2

from .sight import line_of_sight


def agents_see(boxes: np.ndarray, cav_boxes: np.ndarray, ids: np.ndarray, params: Any, order: np.ndarray,
               ego_pose: np.ndarray, cav_pose: np.ndarray,
               visibility: Mapping[str, np.ndarray] | None) -> tuple[np.ndarray, np.ndarray]:
    """Masks of the objects (rows of ``boxes``) the ego and the CAV see. ``cav_boxes`` are the same
    objects where the CAV saw them (a late message: ``evaluation.delay``; NaN rows: not there).

    sind: ``sind_split``. range: within ``sensor_range`` of the agent and, with ``params.sight``, in
    its line of sight, or what the dataset says it saw where it says (``visibility[role]``: ids).
    opv2v: what the dataset says, for both agents."""
    there = ~np.isnan(cav_boxes[:, 0])
    if params.protocol == "sind":
        ego, cav = sind_split(order, params.eta)
        return ego, cav & there
    if params.protocol == "opv2v":
        if visibility is None or "ego" not in visibility or "cav" not in visibility:
            raise ValueError('the opv2v protocol needs visibility={"ego": ids, "cav": ids} (ids each agent sees)')
        return np.isin(ids, np.asarray(visibility["ego"])), np.isin(ids, np.asarray(visibility["cav"])) & there
    known = visibility or {}
    return (_sees(boxes, ids, ego_pose, params, known.get("ego")),
            _sees(cav_boxes, ids, cav_pose, params, known.get("cav"), there))


def _sees(boxes: np.ndarray, ids: np.ndarray, pose: np.ndarray, params: Any, said: np.ndarray | None,
          there: np.ndarray | None = None) -> np.ndarray:
    """One agent's mask under the range protocol (``agents_see``)."""
    there = np.ones(len(boxes), bool) if there is None else there
    seen = there.copy()
    seen[there] = in_range(boxes[there], pose, params.sensor_range)
    if params.sight and said is not None:
        return seen & np.isin(ids, np.asarray(said))
    if params.sight:
        seen[there] &= line_of_sight(boxes[there], pose, params.sensor_range, params.sight_share)
    return seen


def sind_split(order: np.ndarray, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """SIND protocol (sec. IV-A): masks of what the ego and the CAV see.

    The first ``round(eta * N)`` objects of the random ``order`` form the co-visible set M; the rest
    are dealt alternately, ego first, so I_X u I_Y = I and I_X n I_Y = M. An odd remainder's extra
    object goes to the ego.
    """
    n = len(order)
    k = int(round(eta * n))
    ego_sees = np.zeros(n, dtype=bool)
    cav_sees = np.zeros(n, dtype=bool)
    ego_sees[order[:k]] = True
    cav_sees[order[:k]] = True
    ego_sees[order[k::2]] = True
    cav_sees[order[k + 1 :: 2]] = True
    return ego_sees, cav_sees


def in_range(boxes: np.ndarray, pose: np.ndarray, sensor_range: float) -> np.ndarray:
    """Range protocol: mask of the objects whose centre is within ``sensor_range`` of the agent."""
    return np.linalg.norm(boxes[:, :2] - se2.translation_of(pose), axis=1) <= sensor_range
