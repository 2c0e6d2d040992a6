"""The CAVs beyond the first (``Settings.cavs`` > 1): their boxes, each CAV in its own colour
(``colours.CAV_COLOURS``), and a metrics row per CAV."""
from __future__ import annotations

import numpy as np

from cbm import se2
from evaluation.metrics import TrialMetrics, is_success

from ..session.explorer import Outcome
from ..session.settings import MAX_CAVS
from . import geometry, planes
from .colours import CAV_COLOURS
from .layouts import Panel

COLOUR_NAMES = ("orange", "reddish purple", "sky blue", "yellow")
"""How the metrics table names each CAV's colour: the first CAV's orange, then ``CAV_COLOURS``."""


def mesh_name(rank: int) -> str:
    """The scene node of the boxes of CAV ``rank`` (2 for the second CAV)."""
    return f"cav_boxes_{rank}"


def other_cav_boxes(outcome: Outcome, panels: list[Panel]) -> dict[str, tuple[np.ndarray, np.ndarray, tuple]]:
    """``(vertices, faces, colour)`` of the boxes of CAVs 2 to ``MAX_CAVS``, where each panel puts
    them (before: at its ``init``; after: at its estimate); empty for a CAV the outcome lacks, so
    that the node is hidden."""
    meshes = {}
    for rank in range(2, MAX_CAVS + 1):
        boxes = np.zeros((0, 7))
        if rank - 2 < len(outcome.others):
            other = outcome.others[rank - 2]
            where = {"before": other.result.init, "after": other.result.transform}
            boxes = np.concatenate([se2.apply_boxes(se2.make(*panel.offset, 0.0) @ where[panel.placement],
                                                    _slimmer(other.trial.cav_boxes)) for panel in panels])
        meshes[mesh_name(rank)] = (*geometry.footprint_mesh(boxes, planes.cav(rank)), CAV_COLOURS[rank - 2])
    return meshes


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


def _slimmer(boxes: np.ndarray) -> np.ndarray:
    """The other CAVs' boxes drawn narrower than the first CAV's, so boxes on one object all show."""
    out = boxes.copy()
    out[:, 3:5] *= 0.5
    return out
