"""The outputs above the controls: the frame's metrics and the plot over the frames seen so far."""
from __future__ import annotations

from dataclasses import dataclass

import viser

from .plot import add_frame_plot


@dataclass
class MetricsControls:
    text: viser.GuiMarkdownHandle
    plot: viser.GuiUplotHandle


def build(gui: viser.GuiApi) -> MetricsControls:
    return MetricsControls(gui.add_markdown("Computing the first frame…"),
                           add_frame_plot(gui, "over frames", with_rre=False))
