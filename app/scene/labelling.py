"""Labels that never print over each other: each label, in turn, moves down the screen a line at a
time until it overprints none placed before it. The agents' labels are placed first (they stay on
their vehicles), the click label last (it moves, not what it would cover)."""
from __future__ import annotations

from .framing import CHAR_EM, LINE_EM
from .pairs import Labels

SLACK = 1.15
"""Room kept between two labels, as a share of a line: a camera framed a little higher than the one
they were spread for still shows them apart."""
AGENTS = ("ego", "cav")
LAST = ("picked",)


def rank(name: str) -> int:
    """Which labels are placed first: the agents' (0), then the others (1), the click label last (2)."""
    if name in LAST:
        return 2
    return 0 if name.startswith(AGENTS) else 1


def spread(labels: Labels, metres_per_px: float, label_px: float) -> Labels:
    """The labels moved down the screen (-x, the top-down camera's down), one line at a time, until
    none overprints one placed before it, seen through a camera showing ``metres_per_px`` metres of
    ground per CSS pixel, the text ``label_px`` high (it runs from its point to the screen's right, -y)."""
    line = SLACK * LINE_EM * label_px * metres_per_px
    char = CHAR_EM * label_px * metres_per_px
    placed: list[tuple[float, float, float]] = []
    out = {}
    for name, (text, (x, y, z)) in sorted(labels.items(), key=lambda item: (rank(item[0]), -item[1][1][0])):
        width = char * len(text) + line / 5
        while any(abs(x - px) < line and y - width < py and py - pw < y for px, py, pw in placed):
            x -= line
        placed.append((x, y, width))
        out[name] = (text, (x, y, z))
    return out
