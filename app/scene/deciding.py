"""The pairs that explain a frame's result, in the order the camera shows them: on a failed frame of
CBM, first its winning anchor (eq. 13), the pairs its pose rests on and the best right anchor that
lost; then, on any frame, every other wrong and missed pair, nearest the ego first. The
camera frames them while a car stays a readable box (``focus``); the panel lists the others and the
canvas's edge marks where they lie."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evaluation.diagnosis import short_id
from evaluation.metrics import is_success

from ..session.explorer import classified_pairs
from .cavs import ShownCav
from .pairs import Drawn, Labels, unexplained

KINDS = {"right": "✓", "wrong": "✗", "missed": "missed"}
"""How the panel's list names a pair of each kind (the scene's labels say the same)."""


@dataclass(frozen=True)
class Ranked:
    """One pair of one CAV, in the order the camera takes it."""

    rank: int
    """The CAV's (1 for the first)."""
    kind: str
    """``right``, ``wrong`` or ``missed``."""
    pair: tuple[int, int]
    """(ego row, CAV row) in the CAV's trial."""
    deciding: bool
    """It decides the result: CBM's pose rests on it, or it is the best right anchor that lost."""


@dataclass(frozen=True)
class Mark:
    """A pair the camera is to show, in every copy of the scene that draws it."""

    key: str
    """``rank:kind:i:j``: the same pair in every copy."""
    words: str
    """What the panel's list calls it."""
    points: np.ndarray
    """(K, 2) metres: the corners of its two boxes as drawn, in every copy."""
    labels: tuple[str, ...]
    """The scene's labels naming it (one per copy; none for a right pair)."""
    deciding: bool
    distance: float
    """Metres from the ego to its nearer box (the first copy's)."""


def ranked_pairs(cav: ShownCav) -> list[Ranked]:
    """The CAV's pairs the camera frames, most telling first: on a failed frame with CBM's
    explanation, its own set and the best right anchor that lost (deciding); then the wrong and the
    missed pairs not yet taken, nearest the ego first."""
    truth = cav.trial.gt_pairs
    right, wrong, missed = classified_pairs(cav.pairs, truth)
    kind = {**{tuple(p): "right" for p in right.tolist()}, **{tuple(p): "wrong" for p in wrong.tolist()},
            **{tuple(p): "missed" for p in missed.tolist()}}
    out: dict[tuple[int, int], Ranked] = {}
    for pair in _deciding(cav) if not is_success(cav.metrics) else []:
        if pair in kind:
            out.setdefault(pair, Ranked(cav.rank, kind[pair], pair, True))
    ego_xy = cav.trial.ego_boxes[:, :2]
    rest = [tuple(p) for p in (*wrong.tolist(), *unexplained(missed, wrong).tolist())]
    for pair in sorted(rest, key=lambda p: float(np.hypot(*ego_xy[p[0]]))):
        out.setdefault(pair, Ranked(cav.rank, kind[pair], pair, False))
    return list(out.values())


def _deciding(cav: ShownCav) -> list[tuple[int, int]]:
    """The winning anchor (eq. 13), the pairs the pose rests on (those the lines show: the answer, or
    CBM's own set) and the best right anchor when it lost; none for a method without CBM's explanation."""
    result = cav.result
    if result.explanation is None or result.anchor is None:
        return []
    pairs = [tuple(map(int, result.anchor)), *(tuple(p) for p in np.asarray(cav.pairs).reshape(-1, 2).tolist())]
    best = result.explanation.best_anchor_among(cav.trial.gt_pairs)
    if best is not None and tuple(best.anchor) != tuple(result.anchor):
        pairs.append(tuple(map(int, best.anchor)))
    return pairs


def words_of(ranked: Ranked, cav: ShownCav, cav_name: str) -> str:
    """The pair in the panel's list, short: ``✗ 6df1adc2 ↔ 842a35d7`` (ego id, CAV id), ``missed
    27c0efd0`` (one id when both are one object); ``CAV 2: ...`` for a CAV beyond the first."""
    i, j = ranked.pair
    ego_id, cav_id = short_id(cav.trial.ego_ids[i]), short_id(cav.trial.cav_ids[j])
    ids = ego_id if ego_id == cav_id else f"{ego_id} ↔ {cav_id}"
    return f"{cav_name}: " * (ranked.rank > 1) + f"{KINDS[ranked.kind]} {ids}"


def corners(boxes: np.ndarray) -> np.ndarray:
    """(N * 4, 2) the corners of (N, 7) boxes' footprints."""
    c, s = np.cos(boxes[:, 6]), np.sin(boxes[:, 6])
    half_l, half_w = boxes[:, 3] / 2, boxes[:, 4] / 2
    out = [np.c_[boxes[:, 0] + a * half_l * c - b * half_w * s, boxes[:, 1] + a * half_l * s + b * half_w * c]
           for a, b in ((1, 1), (1, -1), (-1, -1), (-1, 1))]
    return np.stack(out, axis=1).reshape(-1, 2)


def marks_of(ranked: list[Ranked], cav: ShownCav, cav_name: str, ego: Drawn, drawn: Drawn, labels: Labels,
             key: str) -> list[Mark]:
    """The ``ranked`` pairs as one copy of the scene draws them: between the ego boxes ``ego`` and
    the CAV's ``drawn``, named by the labels ``key``_kind_i_j among ``labels`` where there is one."""
    marks = []
    for r in ranked:
        i, j = r.pair
        label = f"{key}_{r.kind}_{i}_{j}"
        boxes = np.stack([ego.boxes[i], drawn.boxes[j]])
        distance = float(np.hypot(*cav.trial.ego_boxes[i, :2]))
        marks.append(Mark(f"{r.rank}:{r.kind}:{i}:{j}", words_of(r, cav, cav_name), corners(boxes),
                          (label,) if label in labels else (), r.deciding, distance))
    return marks


def merged(marks: list[Mark]) -> tuple[Mark, ...]:
    """The marks of every copy joined by pair (points and labels of all copies), in their first order."""
    joined: dict[str, Mark] = {}
    for mark in marks:
        if mark.key in joined:
            first = joined[mark.key]
            mark = Mark(first.key, first.words, np.concatenate([first.points, mark.points]),
                        first.labels + mark.labels, first.deciding, first.distance)
        joined[mark.key] = mark
    return tuple(joined.values())
