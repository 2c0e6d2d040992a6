"""The View tab: layout, ghosts, match lines (and, for CBM, its own pairs or all), labels, camera."""
from __future__ import annotations

from dataclasses import dataclass

import viser

from cbm.methods import METHODS

from ..session.settings import LAYOUTS, LINE_PAIRS, Settings
from .actions import TabActions, on_user

LEGEND = ("Boxes: **ego** blue, **CAV** orange (faint: before calibration). Lines: green right pair, red wrong "
          "pair, grey dashed a true pair missed.")
LINE_PAIR_KEYS = {label: key for key, label in LINE_PAIRS.items()}


@dataclass
class ViewControls:
    layout: viser.GuiDropdownHandle
    ghosts: viser.GuiCheckboxHandle
    lines: viser.GuiCheckboxHandle
    line_pairs: viser.GuiDropdownHandle
    labels: viser.GuiCheckboxHandle
    reset_camera: viser.GuiButtonHandle

    def show(self, settings: Settings) -> None:
        view = settings.view
        self.layout.value, self.ghosts.value, self.lines.value = view.layout, view.ghosts, view.lines
        self.line_pairs.value, self.labels.value = LINE_PAIRS[view.line_pairs], view.labels

    def reflect(self, settings: Settings) -> None:
        self.line_pairs.visible = METHODS[settings.method].explains


def build(gui: viser.GuiApi, settings: Settings) -> ViewControls:
    view = settings.view
    controls = ViewControls(
        layout=gui.add_dropdown("CAV boxes", LAYOUTS, initial_value=view.layout),
        ghosts=gui.add_checkbox("ground-truth ghosts", view.ghosts),
        lines=gui.add_checkbox("match lines", view.lines),
        line_pairs=gui.add_dropdown("CBM's lines", tuple(LINE_PAIRS.values()),
                                    initial_value=LINE_PAIRS[view.line_pairs],
                                    hint="CBM's own pairs (eq. 13), or all pairs after the guided re-association"),
        labels=gui.add_checkbox("label clicked objects", view.labels),
        reset_camera=gui.add_button("reset camera"))
    gui.add_markdown(LEGEND)
    return controls


def bind(c: ViewControls, tab: TabActions) -> None:
    for name, control in (("layout", c.layout), ("ghosts", c.ghosts), ("lines", c.lines), ("labels", c.labels)):
        on_user(control, lambda n=name, h=control: tab.apply(lambda s: s.with_view(**{n: h.value})))
    on_user(c.line_pairs, lambda: tab.apply(lambda s: s.with_view(line_pairs=LINE_PAIR_KEYS[c.line_pairs.value])))
    c.reset_camera.on_click(lambda e: tab.reset_camera())
