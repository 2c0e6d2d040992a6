"""Every CAV of an outcome (``Settings.cavs``), each drawn as a CAV: its boxes in its own colour
(the first CAV's orange, then ``colours.CAV_COLOURS``), its vehicle, its label, its match lines,
a legend entry and a metrics row."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cbm import MatchResult, se2
from evaluation.metrics import TrialMetrics, is_success
from evaluation.scenario import Trial

from ..session.explorer import Outcome
from ..session.names import role_of
from . import colours
from .colours import CAV_COLOURS
from .pairs import Drawn

COLOUR_NAMES = ("orange", "teal", "sky blue", "yellow")
"""How the metrics table names each CAV's colour: the first CAV's orange, then ``CAV_COLOURS``."""
SLIM = (0.7, 0.5, 0.35, 0.25)
"""Width and length of each CAV's drawn footprints, per rank, as a fraction of the box's: nested on
the same centre inside the ego's, so that the boxes of all agents on one object show."""


@dataclass(frozen=True)
class ShownCav:
    """One CAV as the scene draws it."""

    rank: int
    """1 for the first CAV."""
    cav_id: str | None
    trial: Trial
    result: MatchResult
    metrics: TrialMetrics
    pairs: np.ndarray
    """The pairs its match lines show."""

    @property
    def placements(self) -> dict[str, np.ndarray]:
        """CAV->ego transforms: before (``init``) and after (the estimate)."""
        return {"before": self.result.init, "after": self.result.transform}


def every_cav(outcome: Outcome) -> list[ShownCav]:
    """The outcome's CAVs, the first (``outcome.trial``) and the others (``outcome.others``)."""
    first = ShownCav(1, outcome.cav_id, outcome.trial, outcome.result, outcome.metrics, outcome.shown_pairs)
    return [first, *(ShownCav(rank, other.cav_id, other.trial, other.result, other.metrics, other.result.pairs)
                     for rank, other in enumerate(outcome.others, 2))]


def drawn_cav(cav: ShownCav, placement: str, offset: np.ndarray) -> Drawn:
    """The CAV's boxes as drawn: placed as ``placement`` says, shifted by the copy's ``offset``,
    narrowed for its rank (``SLIM``)."""
    boxes = se2.apply_boxes(se2.make(offset[0], offset[1], 0.0) @ cav.placements[placement], cav.trial.cav_boxes)
    boxes[:, 3:5] *= SLIM[cav.rank - 1]
    return Drawn(boxes, cav.trial.cav_ids)


def drawn_partners(cav: ShownCav, ego: Drawn, offset: np.ndarray) -> Drawn:
    """The ego boxes the CAV's pairs end at: the drawn ego box of the same object (``ego``, the
    first CAV's trial's), else the CAV trial's own ego detection (its noise draw) shifted by ``offset``."""
    boxes = cav.trial.ego_boxes.copy()
    boxes[:, :2] += offset
    where = {object_id: k for k, object_id in enumerate(ego.ids.tolist())}
    for k, object_id in enumerate(cav.trial.ego_ids.tolist()):
        if object_id in where:
            boxes[k] = ego.boxes[where[object_id]]
    return Drawn(boxes, cav.trial.ego_ids)


def box_colour(rank: int, palette: colours.Palette) -> tuple[int, int, int]:
    """The colour of CAV ``rank``'s boxes."""
    return palette.cav_boxes if rank == 1 else CAV_COLOURS[rank - 2]


def vehicle_colour(rank: int, palette: colours.Palette) -> tuple[int, int, int]:
    """The colour of CAV ``rank``'s vehicle (the others' vehicles in their boxes' colour)."""
    return palette.cav_vehicle if rank == 1 else CAV_COLOURS[rank - 2]


def node(kind: str, rank: int) -> str:
    """The scene node of CAV ``rank``'s ``kind`` (``cav_boxes``, ``cav_vehicle``): ``cav_boxes`` for
    the first CAV, ``cav_boxes_2`` for the second."""
    return kind if rank == 1 else f"{kind}_{rank}"


def name(rank: int, count: int, cav_id: object = None) -> str:
    """What labels call CAV ``rank`` of ``count``: ``CAV`` when it is the only one, else ``CAV 2``;
    ``roadside unit`` (``roadside unit 2``) when the agent ``cav_id`` is infrastructure."""
    role = role_of("CAV", cav_id)
    return role if count == 1 else f"{role} {rank}"


def legend(count: int) -> str:
    """The legend's line for ``count`` CAVs (none for one)."""
    if count < 2:
        return ""
    return " CAVs: " + ", ".join(f"**CAV {rank}** {COLOUR_NAMES[rank - 1]}" for rank in range(1, count + 1)) + \
        " (boxes nested on one centre, vehicle and label in the same colour)."


def per_cav_rows(outcome: Outcome) -> list[str]:
    """A table of every CAV's id, matches, RRE / RTE and success (none with one CAV)."""
    if not outcome.others:
        return []
    cavs = [(outcome.cav_id, outcome.metrics), *((other.cav_id, other.metrics) for other in outcome.others)]
    return ["", "**Per CAV**", "", "| CAV | matches | RRE / RTE | success |", "|---|---|---|---|",
            *(_row(rank, str(cav)[:8], COLOUR_NAMES[rank - 1], metrics) for rank, (cav, metrics) in enumerate(cavs, 1))]


def _row(rank: int, cav: str, colour: str, m: TrialMetrics) -> str:
    pose = f"{m.rre:.2f}° / {m.rte:.2f} m" if m.estimated else "—"
    return f"| CAV {rank} `{cav}` ({colour}) | {m.n_matched} ({m.n_correct} right) | {pose} | " \
           f"{'yes' if is_success(m) else 'no'} |"
