"""Which drawn box a click hits, and what its label says: the ego's boxes and every CAV's (each
CAV's footprints nested inside the ego's on the same centre, a layer above: the box seen on top wins)."""
from __future__ import annotations

import numpy as np

from evaluation.clutter import is_false
from evaluation.diagnosis import short_id

from ..session.explorer import Outcome
from ..session.settings import MAX_CAVS
from . import cavs
from .drawing import Drawing

NODES = ("ego_boxes", *(cavs.node("cav_boxes", rank) for rank in range(1, MAX_CAVS + 1)))
"""The scene nodes of the boxes a click picks from: the ego's and every CAV's footprints."""
REACH = 2.0
"""Metres from a box's centre within which a click outside every box still picks it."""


def pick(picture: Drawing, point: np.ndarray) -> tuple[str, int] | None:
    """(group, row) of the drawn box whose footprint holds ``point`` (of several, the one drawn on
    top: the last group's), else of the nearest centre within ``REACH``; None when there is none."""
    best: tuple[float, str, int] | None = None
    for group, (boxes, _) in picture.objects.items():
        if len(boxes) == 0:
            continue
        local = point[None, :2] - boxes[:, :2]
        c, s = np.cos(boxes[:, 6]), np.sin(boxes[:, 6])
        along, across = c * local[:, 0] + s * local[:, 1], -s * local[:, 0] + c * local[:, 1]
        inside = (np.abs(along) <= boxes[:, 3] / 2) & (np.abs(across) <= boxes[:, 4] / 2)
        distance = np.where(inside, 0.0, np.hypot(local[:, 0], local[:, 1]))
        k = int(np.argmin(distance))
        if distance[k] <= REACH and (best is None or distance[k] < best[0] or distance[k] == 0.0):
            best = (float(distance[k]), group, k)
    return None if best is None else (best[1], best[2])


def rank_of(group: str) -> int:
    """The CAV rank of a picked group: 1 for ``cav``, 3 for ``cav_3`` (``cavs.node``'s names)."""
    return 1 if group == "cav" else int(group.rsplit("_", 1)[1])


def describe(outcome: Outcome, picture: Drawing, group: str, row: int) -> str:
    """Label text of one drawn box: whose detection (the ego's or which CAV's), its id (or that it
    is a false box), and what it was matched to (the ego's boxes: by the first CAV)."""
    shown = cavs.every_cav(outcome)
    cav = shown[0] if group == "ego" else shown[rank_of(group) - 1]
    trial, pairs = cav.trial, cav.result.pairs
    index = int(picture.objects[group][1][row])
    ids = trial.ego_ids if group == "ego" else trial.cav_ids
    column = 0 if group == "ego" else 1
    partner = pairs[pairs[:, column] == index]
    truth = trial.gt_pairs[trial.gt_pairs[:, column] == index]
    false = bool(is_false(ids[index:index + 1])[0])
    name = f"false box {str(ids[index]).rsplit(':', 1)[-1]}" if false else short_id(ids[index])
    whose = "EGO" if group == "ego" else cavs.name(cav.rank, len(shown), cav.cav_id)
    text = f"{whose} {name}"
    if len(partner):
        other = int(partner[0, 1 - column])
        right = len(truth) and int(truth[0, 1 - column]) == other
        other_ids = trial.cav_ids if group == "ego" else trial.ego_ids
        text += f" -> {short_id(other_ids[other])} ({'right' if right else 'wrong'})"
    elif false:
        text += " (matches no object)"
    elif len(truth):
        text += " (co-visible, missed)"
    else:
        text += " (seen by one agent)"
    return text
