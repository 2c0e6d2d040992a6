"""The Method tab: the method list and a folder per parameter set, showing the set of the selected
method only, and within it the parameters that act (``cbm.methods``: what it tunes, what it forces,
what needs what)."""
from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass
from typing import Any

import viser

from cbm.methods import METHODS

from ..session.settings import Settings
from .actions import TabActions, on_user

SLIDERS = {
    # (parameter set, field): (label, min, max, step, hint)
    ("cbm", "sigma1"): ("σ1 angle (°)", 1.0, 45.0, 0.5, "largest angle between matching context vectors (eq. 7)"),
    ("cbm", "sigma2"): ("σ2 L1 (m)", 0.25, 10.0, 0.25, "largest L1 distance between matching context vectors (eq. 7)"),
    ("cbm", "sigma3"): ("σ3 voting (m)", 0.25, 10.0, 0.25, "L1 tolerance of the voting sets of the consensus"),
    ("cbm", "distance_limit"): ("distance limit (m)", 1.0, 60.0, 1.0,
                                "reject anchors whose pairs are farther apart on average"),
    ("cbm", "refine_gate"): ("refine gate (σ)", 1.0, 8.0, 0.25, "re-association gate, in std-devs of the pairs' noise"),
}
LABELS = {m.label: m.name for m in METHODS.values()}


@dataclass
class MethodControls:
    method: viser.GuiDropdownHandle
    folders: dict[str, viser.GuiFolderHandle]
    """A folder per parameter set (``Method.params_key``)."""
    params: dict[tuple[str, str], Any]
    """(parameter set, field) -> its control."""

    def show(self, settings: Settings) -> None:
        self.method.value = METHODS[settings.method].label
        for (key, name), control in self.params.items():
            control.value = getattr(settings.method_params[key], name)

    def reflect(self, settings: Settings) -> None:
        chosen = METHODS[settings.method]
        acting = chosen.controls(settings.params)
        for key, folder in self.folders.items():
            folder.visible = key == chosen.params_key
        for (key, name), control in self.params.items():
            control.visible = key != chosen.params_key or name in acting


def build(gui: viser.GuiApi, settings: Settings) -> MethodControls:
    method = gui.add_dropdown("method", tuple(LABELS), initial_value=METHODS[settings.method].label)
    folders, params = {}, {}
    for key, values in settings.method_params.items():
        if not dataclasses.fields(values):
            continue
        with gui.add_folder(f"{METHODS[key].label} parameters") as folder:
            folders[key] = folder
            for f in dataclasses.fields(values):
                params[(key, f.name)] = _control(gui, key, f.name, getattr(values, f.name))
    return MethodControls(method, folders, params)


def _control(gui: viser.GuiApi, key: str, name: str, value: Any) -> Any:
    """A slider for the listed thresholds, a checkbox for a switch, a list for a choice, else a number."""
    if (key, name) in SLIDERS:
        label, low, high, step, hint = SLIDERS[(key, name)]
        return gui.add_slider(label, low, high, step, value, hint=hint)
    if isinstance(value, bool):
        return gui.add_checkbox(name, value)
    options = typing.get_args(typing.get_type_hints(METHODS[key].params)[name])
    if isinstance(value, str) and options:
        return gui.add_dropdown(name, options, initial_value=value)
    return gui.add_number(name, value, step=1 if isinstance(value, int) else 0.01)


def bind(c: MethodControls, tab: TabActions) -> None:
    on_user(c.method, lambda: tab.apply(lambda s: dataclasses.replace(s, method=LABELS[c.method.value])))
    for (key, name), control in c.params.items():
        on_user(control, lambda k=key, n=name, h=control: tab.apply(lambda s: s.with_params(k, **{n: h.value})))
