"""The per-frame plots (uPlot): precision and recall on the left axis (0 to 1), RTE (and RRE) on
the right."""
from __future__ import annotations

import numpy as np
import viser
from viser import uplot

SERIES = (uplot.Series(label="frame"),
          uplot.Series(label="precision", stroke="#1e9c3c", width=2, scale="y"),
          uplot.Series(label="recall", stroke="#3478f6", width=2, scale="y"),
          uplot.Series(label="RTE (m)", stroke="#e1261e", width=2, scale="m"),
          uplot.Series(label="RRE (°)", stroke="#9b59b6", width=2, scale="m"))


def add_frame_plot(gui: viser.GuiApi, title: str, with_rre: bool) -> viser.GuiUplotHandle:
    """A plot over frames, with RRE as a fifth series when ``with_rre``.

    viser 1.1.1's uPlot never draws data sent to a chart that was created empty: it starts with
    two frames of gaps instead."""
    series = SERIES if with_rre else SERIES[:4]
    placeholder = (np.array([0.0, 1.0]), *(np.full(2, np.nan) for _ in series[1:]))
    return gui.add_uplot(placeholder, series, title=title, aspect=2.0,
                         scales={"x": uplot.Scale(time=False, auto=True),
                                 "y": uplot.Scale(auto=False, range=(0.0, 1.0)), "m": uplot.Scale(auto=True)},
                         axes=(uplot.Axis(), uplot.Axis(scale="y"), uplot.Axis(scale="m", side=1)))
