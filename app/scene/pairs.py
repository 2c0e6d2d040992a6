"""What the scene draws for one CAV's pairs: match lines from the centre of the ego footprint drawn
to the centre of the CAV footprint drawn (the very boxes the tiles show, so lines and boxes agree),
and the boxes of wrong and missed pairs marked themselves: outlined in the pair's colour and
labelled with both ids, so that a wrong pair whose boxes overlap (its line has no length) shows."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evaluation.diagnosis import short_id

from ..session.explorer import classified_pairs
from . import colours, geometry, planes

Labels = dict[str, tuple[str, tuple[float, float, float]]]
"""Text and (x, y, z) of each label, by name."""
Room = dict[str, tuple[float, float]]
"""Half the width and half the height, in metres along a top-down screen (ground y and x), of the
thing each label names (``labelling.lay_out`` puts the label beside it)."""


@dataclass(frozen=True)
class Drawn:
    """Boxes as the scene draws them (their footprints, in the scene's frame) and their object ids."""

    boxes: np.ndarray
    """(N, 7)."""
    ids: np.ndarray
    """(N,)."""


@dataclass(frozen=True)
class PairShapes:
    """Segments of one CAV's pairs in one copy of the scene, and the labels of its wrong and missed ones."""

    right: np.ndarray
    wrong: np.ndarray
    missed: np.ndarray
    wrong_marks: np.ndarray
    """Outlines of the two boxes of every wrong pair."""
    missed_marks: np.ndarray
    """Outlines of the two boxes of every true pair the method missed."""
    labels: Labels
    room: Room


def half_extents(box: np.ndarray) -> tuple[float, float]:
    """Half the width (along ground y) and half the height (along ground x) of a box's footprint:
    what its label steps aside of on a top-down screen."""
    c, s = abs(float(np.cos(box[6]))), abs(float(np.sin(box[6])))
    half_l, half_w = float(box[3]) / 2, float(box[4]) / 2
    return half_l * s + half_w * c, half_l * c + half_w * s


def pair_shapes(pairs: np.ndarray, truth: np.ndarray, ego: Drawn, cav: Drawn, palette: colours.Palette,
                cav_name: str, key: str) -> PairShapes:
    """The lines and marks of ``pairs`` (ego index, CAV index) against the true ``truth``, between
    the drawn boxes ``ego`` and ``cav``; labels named ``key`` and the pair, the CAV called ``cav_name``."""
    right, wrong, missed = classified_pairs(pairs, truth)
    lines = [_segments(ego, cav, p, stroke.dash) for p, stroke in
             ((right, palette.right), (wrong, palette.wrong), (missed, palette.missed))]
    labels, room = _labels(wrong, ego, cav, f"{key}_wrong", "✗", cav_name, on_cav=True)
    missed_labels, missed_room = _labels(unexplained(missed, wrong), ego, cav, f"{key}_missed", "missed", cav_name,
                                         on_cav=False)
    return PairShapes(*lines, _marks(wrong, ego, cav), _marks(missed, ego, cav), {**labels, **missed_labels},
                      {**room, **missed_room})


def unexplained(missed: np.ndarray, wrong: np.ndarray) -> np.ndarray:
    """The missed pairs whose boxes are not both in wrong pairs (a swap's missed pairs are named by
    its wrong pairs' labels already, and their outlines stay)."""
    both = np.isin(missed[:, 0], wrong[:, 0]) & np.isin(missed[:, 1], wrong[:, 1])
    return missed[~both]


def _segments(ego: Drawn, cav: Drawn, pairs: np.ndarray, dash: float | None) -> np.ndarray:
    """Lines from each pair's drawn ego centre to its drawn CAV centre, solid or in dashes ``dash`` long."""
    a, b = ego.boxes[pairs[:, 0], :2], cav.boxes[pairs[:, 1], :2]
    return geometry.segments(a, b, planes.LINES) if dash is None else geometry.dashed(a, b, planes.LINES, dash)


def _marks(pairs: np.ndarray, ego: Drawn, cav: Drawn) -> np.ndarray:
    """Outlines of both boxes of each pair, as drawn."""
    return geometry.outline_segments(np.concatenate([ego.boxes[pairs[:, 0]], cav.boxes[pairs[:, 1]]]), planes.MARKS)


def _labels(pairs: np.ndarray, ego: Drawn, cav: Drawn, key: str, kind: str, cav_name: str,
            on_cav: bool) -> tuple[Labels, Room]:
    """A label per pair, beside its CAV box (``on_cav``) or its ego box: what went wrong and both ids
    (one id when both detections are of the same object, as a missed pair's are), and the box's room."""
    labels, room = {}, {}
    for i, j in pairs.tolist():
        ego_id, cav_id = short_id(ego.ids[i]), short_id(cav.ids[j])
        ids = ego_id if ego_id == cav_id else f"ego {ego_id} ↔ {cav_name} {cav_id}"
        box = cav.boxes[j] if on_cav else ego.boxes[i]
        labels[f"{key}_{i}_{j}"] = (f"{kind} {ids}", (float(box[0]), float(box[1]), planes.LABELS))
        room[f"{key}_{i}_{j}"] = half_extents(box)
    return labels, room
