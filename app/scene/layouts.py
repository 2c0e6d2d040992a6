"""The layouts of the scene, one record each: which copies of the scene are drawn (the CAV's boxes
where ``init`` puts them, or where the estimate does), where, and with which titles. The names are
``ViewOptions.layout``'s (``app.session.settings.LAYOUTS``)."""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..session.explorer import Outcome

SIDE_GAP = 20.0
"""Metres between the two copies of the side-by-side layout."""
TITLE_AT = (-12.0, 3.0)
"""(x, height) of a copy's title."""


@dataclass(frozen=True)
class Panel:
    """One copy of the scene."""

    placement: str
    """``before``: the CAV's boxes where ``init`` puts them; ``after``: where the estimate does."""
    offset: np.ndarray
    """(2,) metres added to every position of this copy."""
    title: str | None = None


@dataclass(frozen=True)
class Layout:
    name: str
    panels: Callable[[Outcome], list[Panel]]
    before_ghosts: bool = False
    """Also draw the CAV's boxes faintly where ``init`` put them."""


def single(placement: str) -> Callable[[Outcome], list[Panel]]:
    """One copy with the CAV's boxes at ``placement``."""
    return lambda outcome: [Panel(placement, np.zeros(2))]


def side_by_side(outcome: Outcome) -> list[Panel]:
    """Before on the left, after on the right, far enough apart not to overlap."""
    boxes = np.concatenate([outcome.trial.ego_boxes[:, :2], outcome.world_boxes[:, :2], np.zeros((1, 2))])
    width = float(boxes[:, 1].max() - boxes[:, 1].min()) + SIDE_GAP
    return [Panel("before", np.array([0.0, width]), "BEFORE calibration (CAV at init)"),
            Panel("after", np.zeros(2), "AFTER calibration (CAV at estimate)")]


LAYOUTS: dict[str, Layout] = {layout.name: layout for layout in (
    Layout("overlay", single("after"), before_ghosts=True),
    Layout("after", single("after")),
    Layout("before", single("before")),
    Layout("side by side", side_by_side),
)}
