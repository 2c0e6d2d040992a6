"""The GUI of one browser tab: the frame controls and the status line at the top (``frame``,
``metrics``), the tab row, and under it the frame's metrics with the timeline (``metrics``) and the
CAVs folder (``frame``). The tabs of the row register themselves (``registry``): each module defining
``PANEL`` is one. Each panel holds its handles in a small dataclass (or a class, for a tab that keeps
state), built once; its callbacks change the tab's settings through ``TabActions.apply`` and never
touch another panel; ``show`` moves its controls to given settings (the app's own updates do not
re-fire callbacks, ``actions.on_user``)."""
from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any

import viser

from ..scene.drawing import Drawing
from ..session.explorer import Outcome
from ..session.settings import Settings
from . import frame, metrics, numbers
from .actions import TabActions
from .registry import found

FIRST = -1.0
"""The order of a panel that is a folder of another's tab (``Panel.inside``): first in the tab."""


@dataclass
class Controls:
    """The frame controls, the metrics and every registered tab's part."""

    metrics: metrics.MetricsControls
    frame: frame.FrameControls
    tabs: viser.GuiTabGroupHandle
    parts: dict[str, Any]
    """Each tab's part by its module's name (``registry.found``)."""

    def __getattr__(self, name: str) -> Any:
        """A tab's part by its module's name: ``controls.explore``."""
        try:
            return self.__dict__["parts"][name]
        except KeyError:
            raise AttributeError(name) from None

    def call(self, hook: str, *args: Any) -> None:
        """``part.hook(*args)`` for every part that has the hook (``registry``)."""
        for part in self.parts.values():
            method = getattr(part, hook, None)
            if method is not None:
                method(*args)

    def show(self, settings: Settings) -> None:
        """Move every control to ``settings`` (without re-firing callbacks)."""
        self.frame.show(settings)
        self.call("show", settings)
        self.reflect(settings)

    def reflect(self, settings: Settings) -> None:
        """Show the controls that apply to ``settings``; hide or disable the others."""
        self.call("reflect", settings)

    def refresh(self, outcome: Outcome, picture: Drawing) -> None:
        """Follow a result shown: the CAVs it offers, and every part that follows results."""
        self.frame.offer_cavs(outcome)
        self.call("refresh", outcome, picture)

    def close(self) -> None:
        self.metrics.close()
        self.call("close")


def build(gui: viser.GuiApi, tab: TabActions) -> Controls:
    """The panels of a new tab, in screen order, bound to ``tab``: the frame slider and play first,
    the status line, the tab row, so that it shows in the first screen of a 1280x720 window; then the
    metrics, the timeline and the CAVs."""
    navigation = frame.build_navigation(gui, tab.settings, len(tab.explorer))
    status = metrics.build_status(gui)
    tabs = gui.add_tab_group()
    parts, opened = {}, {}
    for name, panel in found().items():
        if panel.inside is None:
            opened[panel.title] = tabs.add_tab(panel.title)
        with opened[panel.inside or panel.title], (contextlib.nullcontext() if panel.inside is None else
                                                   gui.add_folder(panel.title, order=FIRST, expand_by_default=False)):
            parts[name] = panel.build(gui, tab)
        if panel.bind is not None:
            panel.bind(parts[name], tab)
    shown = metrics.build(gui, navigation.frame, status)
    frames = frame.build(gui, tab.settings, navigation)
    frame.bind(frames, tab)
    metrics.bind(shown, tab)
    controls = Controls(shown, frames, tabs, parts)
    controls.reflect(tab.settings)
    numbers.teach(tab.client)
    return controls


__all__ = ["Controls", "TabActions", "build"]
