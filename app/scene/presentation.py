"""Presentation mode and the dark theme, as far as they go beyond the drawing: the camera over the
two agents, the control panel, the caption of key numbers and the page's colour scheme, all for one
browser tab."""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import viser

from ..session.settings import ViewOptions
from .captions import caption_html

if TYPE_CHECKING:
    from ..session.explorer import Outcome

THEME = {"show_share_button": False, "control_width": "large", "show_logo": False}
"""The theme of every tab (``app.server``); a tab's own ``configure_theme`` replaces the whole theme,
so it passes these with its colour scheme."""
MARGIN = 14.0
"""Metres of scene kept around the agents by the presentation camera."""
CAPTION_TAB = "Key numbers"
CAPTION_GAP, CAPTION_WIDTH = 16.0, 400.0
"""CSS pixels from the page's bottom left corner to the caption, and its width."""
LOWEST = 30.0
"""The presentation camera's lowest height (m): agents close together still show their surroundings."""
TILT = 0.05
"""How far the presentation camera stands behind the point it looks at, per metre of height (a
camera looking straight down has no 'up' to keep x pointing up the screen)."""


def camera_over(agents: Sequence[tuple[float, float]], fov: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Camera position and look-at point above the middle of ``agents`` ((x, y) of each vehicle
    drawn), high enough that the vertical field of view ``fov`` (radians) holds all of them and
    ``MARGIN`` around them."""
    points = np.asarray(agents, float).reshape(-1, 2)
    low, high = points.min(axis=0), points.max(axis=0)
    centre = (low + high) / 2
    half = float(np.max(high - low)) / 2 + MARGIN
    height = max(LOWEST, half / math.tan(fov / 2))
    return (float(centre[0] - TILT * height), float(centre[1]), height), (float(centre[0]), float(centre[1]), 0.0)


def restage(client: viser.ClientHandle, before: ViewOptions | None, after: ViewOptions) -> bool:
    """Switch the tab's colour scheme and control panel from ``before``'s (None: the defaults) to
    ``after``'s; whether presentation mode changed (then the camera is to be framed again).

    The panel is minimised (``main_panel.minimize``: the same as its on-screen minimise control,
    which expands it again) when presentation mode starts, and expanded when it ends."""
    before = before or ViewOptions()
    if after.dark != before.dark:
        client.gui.configure_theme(dark_mode=after.dark, **THEME)
    if after.presentation == before.presentation:
        return False
    panel = client.gui.main_panel
    (panel.minimize if after.presentation else panel.expand)()
    return True


class Caption:
    """Presentation mode's caption of one tab: the frame's number, verdict, precision, recall and pose
    errors in large type, in a panel of its own floating at the page's bottom left (viser's
    ``add_panel``), outside the minimised control panel and over no part of the scene that matters."""

    def __init__(self, client: viser.ClientHandle) -> None:
        self.client = client
        self.panel: viser.PanelHandle | None = None
        self.html: viser.GuiHtmlHandle | None = None

    def show(self, outcome: Outcome) -> None:
        """The caption of ``outcome`` in presentation mode; hidden otherwise."""
        shown = outcome.settings.view.presentation
        if self.panel is None and not shown:
            return
        if self.panel is None:
            self.panel = self.client.gui.add_panel()
            with self.panel.add_tab(CAPTION_TAB):
                self.html = self.client.gui.add_html(caption_html(outcome))
            self.panel.float(x=CAPTION_GAP, y=-CAPTION_GAP, width=CAPTION_WIDTH)
        elif shown:
            self.html.content = caption_html(outcome)
        self.panel.visible = shown
