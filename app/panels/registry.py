"""The tabs of the control panel are found, not listed: every module of this package that defines
``PANEL = Panel(...)`` is one. The tab row, the tab's wiring (built, bound, told of every change)
and ``cbm-explorer --help``'s list of tabs follow from the registration, so a new tab is one module
and nothing else changes.

A part (what ``Panel.build`` returns) is called by the browser tab where it has the method:
``show(settings)`` moves its controls to settings the controls did not set (a preset, a jump),
``reflect(settings)`` shows what applies after every change, ``refresh(outcome, drawing)`` follows
a result shown, ``picked(outcome, drawing, group, index)`` a box clicked in the scene, ``close()``
the browser tab closing."""
from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import viser

from .actions import TabActions


@dataclass(frozen=True)
class Panel:
    """One tab of the control panel, as its module registers it."""

    title: str
    """Its name in the tab row."""
    order: int
    """Its place in the tab row: tabs are shown by increasing order, left to right."""
    help: str
    """What it is for, in one line (``cbm-explorer --help`` lists the tabs with it)."""
    build: Callable[[viser.GuiApi, TabActions], Any]
    """Its controls, built inside its tab: the part the browser tab calls (see the module)."""
    bind: Callable[[Any, TabActions], None] | None = None
    """Connects the built part's controls to the browser tab (None: ``build`` did)."""
    inside: str | None = None
    """The title of the tab it is a folder of, first in it and folded (None: a tab of its own). Its
    ``order`` comes after that tab's."""


def found() -> dict[str, Panel]:
    """Every registered panel by its module's name, in tab-row order."""
    package = importlib.import_module(__package__)
    declared = {info.name: getattr(importlib.import_module(f"{__package__}.{info.name}"), "PANEL", None)
                for info in pkgutil.iter_modules(package.__path__)}
    panels = [(name, panel) for name, panel in declared.items() if isinstance(panel, Panel)]
    return dict(sorted(panels, key=lambda item: item[1].order))


def tabs_help() -> str:
    """The tabs of the control panel and what each is for, one line each (a folder of a tab after it)."""
    return "\n".join(f"  {panel.title}: {panel.help}" if panel.inside is None else
                     f"    {panel.title} (in {panel.inside}): {panel.help}" for panel in found().values())
