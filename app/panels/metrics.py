"""The outputs above the controls: a status line (what the tab is waiting for), the frame's
metrics and the plot over the frames seen so far."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import viser

from .plot import add_frame_plot


@dataclass
class MetricsControls:
    status: viser.GuiMarkdownHandle
    text: viser.GuiMarkdownHandle
    plot: viser.GuiUplotHandle

    def say(self, status: str) -> None:
        """Show ``status`` above the metrics; an empty one hides the line."""
        self.status.content = status
        self.status.visible = bool(status)

    def show(self, metrics_markdown: str, plot_data: tuple[np.ndarray, ...], status: str = "") -> None:
        """One result: its metrics, the plot over frames, and what to say above them."""
        self.say(status)
        self.text.content = metrics_markdown
        self.plot.data = plot_data


def build(gui: viser.GuiApi) -> MetricsControls:
    return MetricsControls(gui.add_markdown("", visible=False), gui.add_markdown("Computing the first frame…"),
                           add_frame_plot(gui, "over frames", with_rre=False))
