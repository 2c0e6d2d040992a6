"""What presentation mode writes into the scene: the labels' text size, and the line of key numbers
and where it goes (``drawing`` and ``view`` read it; ``presentation`` does the rest of the mode)."""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..session.settings import ViewOptions
from .text import number

if TYPE_CHECKING:
    from ..session.explorer import Outcome

LABEL_PX = 14.0
"""Height of the labels' text in CSS pixels (viser's own default is 12)."""
PRESENTATION_LABEL_PX = 20.0
"""In presentation mode: readable from the back of a room."""

def label_px(view: ViewOptions) -> float:
    """Height of the labels' text for ``view``."""
    return PRESENTATION_LABEL_PX if view.presentation else LABEL_PX


def key_numbers(outcome: Outcome) -> str:
    """The one line of numbers presentation mode shows in the 3D view."""
    m = outcome.metrics
    return (f"precision {number(m.precision)} · recall {number(m.recall)} · "
            f"RTE {number(m.rte, ' m')} · RRE {number(m.rre, '°', 1)}")


def numbers_position(agents: Sequence[tuple[float, float]]) -> tuple[float, float, float]:
    """Where the key numbers go: just below the agents on screen (x points up), starting at their
    left (the label's top-left corner is its anchor; y points left)."""
    points = np.asarray(agents, float).reshape(-1, 2)
    return float(points[:, 0].min() - 5.0), float(points[:, 1].max() + 4.0), 2.5
