"""Heights of what the scene compares: every box is drawn as its bird's-eye footprint (what CBM
and the metrics compare), flat near the ground, never at its roof. Each group lies a few
centimetres above the one it is to cover, so the depth buffer shows it on top while no camera,
however tilted, can shift one against another by more than a pixel or so."""
from __future__ import annotations

STEP = 0.03
"""Metres between two layers of the plane."""
MAP = 0.0
"""The map's lines, on the ground under everything."""
SIGHT = STEP / 3
"""The agents' sight, translucent fills just above the map: the ego's at this height, the CAV's at twice it."""
EGO = STEP
"""The ego's filled footprints."""
OUTLINES = 9 * STEP
"""Outlines of the ground truth (ghosts) and of the CAV's boxes where ``init`` put them."""
MARKS = 10 * STEP
"""Outlines marking the boxes of wrong and missed pairs."""
PINNED = 11 * STEP
"""The pinned baseline's match lines (under the current run's)."""
LINES = 12 * STEP
"""Match lines, from a drawn box's centre to its partner's."""
FUSED = 13 * STEP
"""Outlines of the fused boxes (late fusion)."""
HIGHLIGHT = 14 * STEP
"""Lines drawn over the match lines: the walkthrough's followed pair and the context vectors that matched."""
LABELS = 15 * STEP
"""Every label, just over what it names (screen-space text, drawn over everything): at one height near
the footprints', so that a top-down camera shows each beside its thing as laid out, at any zoom."""


def cav(rank: int) -> float:
    """The filled footprints of CAV ``rank`` (1 for the first), above the ego's and the CAVs' before it."""
    return EGO + rank * STEP
