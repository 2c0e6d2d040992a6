"""Line colours as they show: viser hands a line set's per-vertex colours to three.js as linear
values, which the screen then brightens (orange shows yellow, blue light blue). ``as_shown`` gives
the colour to send so that a line shows the named sRGB colour, as a box of that colour does."""
from __future__ import annotations

RGB = tuple[int, int, int]


def linear(channel: int) -> float:
    """One 0-255 sRGB channel as a linear value in [0, 1] (the sRGB transfer function)."""
    c = channel / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def as_shown(rgb: RGB) -> RGB:
    """The per-vertex colour that shows as ``rgb`` on screen."""
    r, g, b = (round(255.0 * linear(c)) for c in rgb)
    return r, g, b
