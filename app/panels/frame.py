"""The frame controls: at the top of the panel, the one frame slider (the timeline marks every
failed frame known on it, ``metrics.MetricsControls.show_timeline``) and ◀ prev / ▶ play / next ▶;
lower down, the "CAVs and playback" folder: play speed, which vehicle is the CAV, how many CAVs, and
(for a dataset of several scenarios, e.g. an OPV2V release root) a jump to a scenario's first frame."""
from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field

import viser

from ..session.explorer import CavChoice, Outcome
from ..session.history import FAILED_MEANING
from ..session.settings import AUTO_CAV, MAX_CAVS, Settings
from .actions import TabActions, on_user

PREV, PLAY, PAUSE, NEXT = "◀ prev", "▶ play", "❚❚ pause", "next ▶"
FRAME_HINT = f"the frame shown; a dot under the track marks each failed frame known ({FAILED_MEANING})"


@dataclass
class Navigation:
    """The controls at the top of the panel."""

    frame: viser.GuiSliderHandle
    step: viser.GuiButtonGroupHandle
    """◀ prev, ▶ play (❚❚ pause while playing), next ▶."""


@dataclass
class FrameControls:
    frame: viser.GuiSliderHandle
    step: viser.GuiButtonGroupHandle
    speed: viser.GuiSliderHandle
    cav: viser.GuiDropdownHandle
    cavs: viser.GuiNumberHandle
    scenario: viser.GuiDropdownHandle
    starts: dict[str, int] = field(default_factory=dict)
    """Scenario name -> its first frame (``Sequence.scenarios``); empty hides the scenario list."""
    cav_choices: Callable[[int], list[CavChoice]] = lambda frame: []
    """The vehicles of a frame that may act as the CAV (``Explorer.cav_choices``)."""
    choices: list[CavChoice] = field(default_factory=list)
    """Those of the frame shown, as the CAV list offers them."""
    choices_frame: int = -1

    def show(self, settings: Settings) -> None:
        self.frame.value = settings.frame
        self.cavs.value = settings.cavs
        if self.starts:
            self.scenario.value = scenario_of(self.starts, settings.frame)

    def offer_cavs(self, outcome: Outcome) -> None:
        """List the vehicles that may act as the CAV in the outcome's frame (once per frame)."""
        if outcome.frame_index == self.choices_frame:
            return
        self.choices_frame = outcome.frame_index
        self.choices = self.cav_choices(outcome.frame_index)
        self.cav.options = (AUTO_CAV, *[c.label for c in self.choices])
        self.cav.value = next((c.label for c in self.choices if c.id == outcome.settings.cav), AUTO_CAV)

    def cav_id(self, label: str) -> str:
        """The vehicle id behind an entry of the CAV list."""
        return next((c.id for c in self.choices if c.label == label), AUTO_CAV)

    def show_playing(self, playing: bool) -> None:
        """The middle button offers to pause while playing, to play otherwise."""
        self.step.options = (PREV, PAUSE if playing else PLAY, NEXT)


def scenario_of(starts: dict[str, int], frame: int) -> str:
    """The scenario whose frames include ``frame`` (the last one starting at or before it)."""
    begun = [name for name, first in starts.items() if first <= frame]
    return begun[-1] if begun else next(iter(starts))


def build_navigation(gui: viser.GuiApi, settings: Settings, n_frames: int) -> Navigation:
    """The frame slider and the step / play buttons, where the panel starts."""
    last = max(n_frames - 1, 0)
    return Navigation(frame=gui.add_slider("frame", 0, last, 1, settings.frame, hint=FRAME_HINT),
                      step=gui.add_button_group("step", (PREV, PLAY, NEXT)))


def build(gui: viser.GuiApi, settings: Settings, navigation: Navigation) -> FrameControls:
    """The "CAVs and playback" folder, completing the frame controls of ``navigation``."""
    with gui.add_folder("CAVs and playback", expand_by_default=True):
        return FrameControls(
            frame=navigation.frame, step=navigation.step,
            speed=gui.add_slider("play speed (frames/s)", 1, 10, 1, 4, hint="frames shown per second by ▶ play"),
            cav=gui.add_dropdown("CAV", (AUTO_CAV,), initial_value=AUTO_CAV, hint="vehicle acting as the CAV"),
            cavs=gui.add_number("CAVs", settings.cavs, min=1, max=MAX_CAVS, step=1,
                                hint="how many CAVs, each calibrated to the ego and drawn in its own colour "
                                     "(the first is the CAV above, the others the next nearest 25 m)"),
            scenario=gui.add_dropdown("scenario", ("-",), visible=False,
                                      hint="jump to the first frame of a scenario of this dataset"))


def bind(c: FrameControls, tab: TabActions) -> None:
    c.cav_choices = tab.explorer.cav_choices
    on_user(c.frame, lambda: _slid(c, tab))
    c.step.on_click(lambda e: _stepped(c, tab, e.target.value))
    on_user(c.cav, lambda: tab.apply(lambda s: dataclasses.replace(s, cav=c.cav_id(c.cav.value))))
    on_user(c.cavs, lambda: tab.apply(lambda s: dataclasses.replace(s, cavs=_cav_count(c.cavs.value))))
    scenarios = tab.explorer.sequence.scenarios or {}
    if len(scenarios) > 1:
        c.starts = dict(scenarios)
        c.scenario.options = tuple(scenarios)
        c.scenario.value = scenario_of(c.starts, tab.settings.frame)
        c.scenario.visible = True
        on_user(c.scenario, lambda: tab.apply(
            lambda s: dataclasses.replace(s, frame=c.starts[c.scenario.value]), move_controls=True, frame_camera=True))


def _stepped(c: FrameControls, tab: TabActions, button: str) -> None:
    """◀ prev and next ▶ step one frame; ▶ play and ❚❚ pause start and stop the play loop."""
    if button in (PREV, NEXT):
        tab.step(-1 if button == PREV else 1)
        return
    playing = button == PLAY
    tab.set_playing(playing)
    c.show_playing(playing)


def _slid(c: FrameControls, tab: TabActions) -> None:
    """The frame slider moved: show that frame (and, with scenarios, name its scenario)."""
    frame = int(c.frame.value)
    tab.apply(lambda s: dataclasses.replace(s, frame=frame))
    if c.starts:
        c.scenario.value = scenario_of(c.starts, frame)


def _cav_count(value: float) -> int:
    """The CAVs number as a count from 1 to ``MAX_CAVS`` (typed values may fall outside or be fractional)."""
    return min(max(int(round(value)), 1), MAX_CAVS)
