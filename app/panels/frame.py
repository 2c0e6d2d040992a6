"""The Frame folder: frame slider, step buttons, play loop and speed, and which vehicle is the CAV."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import viser

from ..session.settings import AUTO_CAV, Settings
from .actions import TabActions, on_user


@dataclass
class FrameControls:
    frame: viser.GuiSliderHandle
    step: viser.GuiButtonGroupHandle
    play: viser.GuiCheckboxHandle
    speed: viser.GuiSliderHandle
    cav: viser.GuiDropdownHandle

    def show(self, settings: Settings) -> None:
        self.frame.value = settings.frame


def build(gui: viser.GuiApi, settings: Settings, n_frames: int) -> FrameControls:
    with gui.add_folder("Frame", expand_by_default=True):
        return FrameControls(
            frame=gui.add_slider("frame", 0, max(n_frames - 1, 0), 1, settings.frame),
            step=gui.add_button_group("step", ("◀ prev", "next ▶")),
            play=gui.add_checkbox("play", False),
            speed=gui.add_slider("speed (frames/s)", 1, 10, 1, 4),
            cav=gui.add_dropdown("CAV", (AUTO_CAV,), initial_value=AUTO_CAV, hint="vehicle acting as the CAV"))


def bind(c: FrameControls, tab: TabActions) -> None:
    on_user(c.frame, lambda: tab.apply(lambda s: dataclasses.replace(s, frame=int(c.frame.value))))
    c.step.on_click(lambda e: tab.step(-1 if e.target.value.startswith("◀") else 1))
    on_user(c.play, lambda: tab.set_playing(c.play.value))
    on_user(c.cav, lambda: tab.apply(lambda s: dataclasses.replace(s, cav=tab.cav_id(c.cav.value))))
