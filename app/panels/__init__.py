"""The GUI of one browser tab, one module per tab of the control panel (``frame``, ``scenario``,
``method``, ``view``, ``presets``, ``explore``) and the outputs above them (``metrics``). Each
holds its handles in a small dataclass, built once; its callbacks write one field of the tab's
settings through ``TabActions.apply`` and never touch another panel; ``show`` moves its controls to
given settings (the app's own updates do not re-fire callbacks, ``actions.on_user``)."""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import viser

from ..session.offers import Offers
from ..session.settings import Settings
from . import frame, method, metrics, presets, scenario, view
from .actions import TabActions


@dataclass
class Controls:
    """Every panel of the tab but the Explore tab (``explore.ExplorePanel``, which keeps state)."""

    metrics: metrics.MetricsControls
    frame: frame.FrameControls
    tabs: viser.GuiTabGroupHandle
    scenario: scenario.ScenarioControls
    method: method.MethodControls
    view: view.ViewControls
    presets: presets.PresetControls

    def show(self, settings: Settings) -> None:
        """Move every control to ``settings`` (without re-firing callbacks)."""
        for part in (self.frame, self.scenario, self.method, self.view):
            part.show(settings)
        self.reflect(settings)

    def reflect(self, settings: Settings) -> None:
        """Show the controls that apply to ``settings``; hide or disable the others."""
        self.scenario.reflect(settings)
        self.method.reflect(settings)
        self.view.reflect(settings)


def build(gui: viser.GuiApi, settings: Settings, n_frames: int, descriptions: Mapping[str, str],
          offers: Offers) -> Controls:
    """The panels of a new tab, in screen order: the frame slider and play first, the status line,
    the tabs (Explore and Steps are added to ``Controls.tabs`` after), so that the tab row shows in
    the first screen of a 1280x720 window; then the metrics, the timeline and the CAVs.
    ``descriptions``: the presets by name; ``offers``: what the dataset cannot offer, and why."""
    navigation = frame.build_navigation(gui, settings, n_frames)
    status = metrics.build_status(gui)
    tabs = gui.add_tab_group()
    with tabs.add_tab("Scenario"):
        scenario_controls = scenario.build(gui, settings, offers)
    with tabs.add_tab("Method"):
        method_controls = method.build(gui, settings, offers)
    with tabs.add_tab("View"):
        view_controls = view.build(gui, settings, offers)
    with tabs.add_tab("Presets"):
        preset_controls = presets.build(gui, descriptions)
    shown = metrics.build(gui, navigation.frame, status)
    frames = frame.build(gui, settings, navigation)
    controls = Controls(shown, frames, tabs, scenario_controls, method_controls, view_controls, preset_controls)
    controls.reflect(settings)
    return controls


def bind(controls: Controls, tab: TabActions) -> None:
    """Connect every control to the tab."""
    frame.bind(controls.frame, tab)
    scenario.bind(controls.scenario, tab)
    method.bind(controls.method, tab)
    view.bind(controls.view, tab)
    presets.bind(controls.presets, tab)


__all__ = ["Controls", "TabActions", "bind", "build"]
