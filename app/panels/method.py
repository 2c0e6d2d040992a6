"""The Method tab: the method list and a folder per parameter set, showing the set of the selected
method and CBM's (CBM's thresholds are the ones the app is about), and for a method over time an
advanced folder of its tracking parameters (``cbm.TrackingParams``); a control that has no effect under
the current settings is disabled, and its folder's note says why (``cbm.methods``: what a method
tunes, what it forces, what needs what); a method that cannot run here (the joint pose graph with
one CAV) is not offered, and a note under the list says why. A method over a whole recording
(``cbm-smooth``) answers only once every frame is in: it is not among the live frame's methods."""
from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass, field
from typing import Any

import viser

from cbm import MOST
from cbm.methods import METHODS

from ..scene.words import TRACKING, WORDS, label_of
from ..session.coalesce import Later
from ..session.markup import plain
from ..session.offers import Offers
from ..session.settings import Settings
from .actions import TabActions, assign, on_user
from .registry import Panel

SLIDERS = {
    # (parameter set, field): (min, max, step); the max is the parameter's own (``cbm.params.MOST``)
    ("cbm", "sigma1"): (1.0, MOST["sigma1"], 0.5),
    ("cbm", "sigma2"): (0.25, MOST["sigma2"], 0.25),
    ("cbm", "sigma3"): (0.25, MOST["sigma3"], 0.25),
    ("cbm", "distance_limit"): (1.0, MOST["distance_limit"], 1.0),
    ("cbm", "refine_gate"): (1.0, MOST["refine_gate"], 0.25),
}
LABELS = {m.label: m.name for m in METHODS.values() if not m.offline}
TYPING_PAUSE = 0.8
"""Seconds without a keystroke after which a typed number applies."""
ABOUT = {"cbm": "*σ1 and σ2: how alike two objects' neighbourhoods must be to match (angle, distance). σ3: how "
                "closely matched pairs must agree to back each other in the consensus vote. Hover a control for "
                "more.*",
         TRACKING: "*How CBM over time follows the CAV's pose error from frame to frame: when a frame's own answer "
                   "joins the track, when a track starts, is lost or jumps. Hover a control for more.*"}
"""A folder's words above its controls, in plain language."""
TRACKING_FOLDER = "CBM over time: tracking (advanced)"


@dataclass
class MethodControls:
    method: viser.GuiDropdownHandle
    folders: dict[str, viser.GuiFolderHandle]
    """A folder per parameter set (``Method.params_key``)."""
    params: dict[tuple[str, str], Any]
    """(parameter set, field) -> its control; ``TRACKING``'s set is ``Settings.tracking``."""
    notes: dict[str, viser.GuiMarkdownHandle]
    """A folder's note: which of its controls are disabled, and why."""
    hints: dict[tuple[str, str], str]
    """Each control's own hint (a disabled one's hint starts with why it is disabled)."""
    unoffered: viser.GuiMarkdownHandle
    """Under the method list: the methods not offered here, and why."""
    offers: Offers = field(default_factory=Offers)
    typed: dict[str, viser.GuiMarkdownHandle] = field(default_factory=dict)
    """A folder's note on a number typed that is not one: the value in use stays."""
    pause: Later = field(default_factory=lambda: Later(TYPING_PAUSE))
    """A typed number applies once typing pauses: a text box reports every keystroke, and "1e5"
    passes through "1" and "1e" on the way."""

    def show(self, settings: Settings) -> None:
        self.method.value = METHODS[settings.method].label
        for (key, name), control in self.params.items():
            value = getattr(values_of(settings, key), name)
            control.value = f"{value:g}" if isinstance(control.value, str) and not isinstance(value, str) else value

    def reflect(self, settings: Settings) -> None:
        """Offer the methods that can run; show the chosen method's folder and CBM's; disable, with a
        note, what does not act."""
        self._offer(settings)
        chosen = METHODS[settings.method]
        for key, folder in self.folders.items():
            assign(folder, visible=chosen.over_time if key == TRACKING else key in (chosen.params_key, "cbm"))
        inactive: dict[str, dict[str, list[str]]] = {key: {} for key in self.folders}
        for (key, name), control in self.params.items():
            why = inactive_reason(settings, key, name)
            assign(control, disabled=why is not None,
                   hint=self.hints[(key, name)] if why is None else f"Disabled: {why}. {self.hints[(key, name)]}")
            if why is not None:
                inactive[key].setdefault(why, []).append(control.label)
        for key, note in self.notes.items():
            assign(note, content="  \n".join(f"*Disabled ({why}): {', '.join(names)}.*"
                                              for why, names in inactive[key].items()), visible=bool(inactive[key]))

    def _offer(self, settings: Settings) -> None:
        why = self.offers.pose_graph(settings.cavs)
        offered = tuple(label for label, name in LABELS.items() if why is None or not METHODS[name].takes_peers)
        if tuple(self.method.options) != offered:
            self.method.options = offered
        graphs = [m.label for m in METHODS.values() if m.takes_peers]
        assign(self.unoffered, content=f"*Not offered: {', '.join(graphs)} ({why}).*" if why and graphs else "",
               visible=bool(why and graphs))


def values_of(settings: Settings, key: str) -> Any:
    """The parameter set ``key`` of ``settings``: a method's (``Method.params_key``), or ``TRACKING``."""
    return settings.tracking if key == TRACKING else settings.method_params[key]


def with_values(settings: Settings, key: str, **changes: Any) -> Settings:
    """``settings`` with some parameters of the set ``key`` changed."""
    return settings.with_tracking(**changes) if key == TRACKING else settings.with_params(key, **changes)


def inactive_reason(settings: Settings, key: str, name: str) -> str | None:
    """Why parameter ``name`` of set ``key`` has no effect under ``settings``; None when it acts (the
    tracking parameters act whenever they show: under a method over time)."""
    chosen = METHODS[settings.method]
    if key == TRACKING:
        return None
    if key != chosen.params_key:
        return f"{chosen.label} selected: {METHODS[key].label}'s parameters do not apply"
    if name in chosen.forced:
        return f"{chosen.label} forces {label_of(key, name)} {_worded(chosen.forced[name])}"
    needed = chosen.requires.get(name)
    if needed is not None and name not in chosen.controls(settings.params):
        return f"{label_of(key, needed[0])} is off"
    return None


def _worded(value: Any) -> str:
    return {True: "on", False: "off"}.get(value, f"= {value}") if isinstance(value, bool) else f"= {value}"


def build(gui: viser.GuiApi, settings: Settings, offers: Offers) -> MethodControls:
    method = gui.add_dropdown("method", tuple(LABELS), initial_value=METHODS[settings.method].label)
    unoffered = gui.add_markdown("", visible=False)
    c = MethodControls(method, {}, {}, {}, {}, unoffered, offers)
    for key, values in settings.method_params.items():
        if dataclasses.fields(values):
            _folder(gui, c, key, f"{METHODS[key].label} parameters", values)
    _folder(gui, c, TRACKING, TRACKING_FOLDER, settings.tracking, expand=False)
    c.hints = {k: control.hint or "" for k, control in c.params.items()}
    return c


def _folder(gui: viser.GuiApi, c: MethodControls, key: str, title: str, values: Any, expand: bool = True) -> None:
    """The folder of the parameter set ``key``: its words, its note, a control per field of ``values``."""
    with gui.add_folder(title, expand_by_default=expand) as folder:
        c.folders[key] = folder
        if key in ABOUT:
            gui.add_markdown(ABOUT[key])
        c.notes[key] = gui.add_markdown("", visible=False)
        for f in dataclasses.fields(values):
            c.params[(key, f.name)] = _control(gui, key, f.name, getattr(values, f.name))
        c.typed[key] = gui.add_markdown("", visible=False)


def _control(gui: viser.GuiApi, key: str, name: str, value: Any) -> Any:
    """A slider for the listed thresholds, a checkbox for a switch, a list for a choice, else a number
    typed as text (``typed_number``): viser's number box drops an ``e``, so "1e5" became 15 and
    "1e-07" became -107, silently."""
    label, hint = WORDS[(key, name)]
    if (key, name) in SLIDERS:
        low, high, step = SLIDERS[(key, name)]
        return gui.add_slider(label, low, high, step, value, hint=hint)
    if isinstance(value, bool):
        return gui.add_checkbox(label, value, hint=hint)
    if isinstance(value, str):
        options = typing.get_args(typing.get_type_hints(METHODS[key].params)[name])
        return gui.add_dropdown(label, options, initial_value=value, hint=hint)
    return gui.add_text(label, f"{value:g}", hint=hint)


def bind(c: MethodControls, tab: TabActions) -> None:
    on_user(c.method, lambda: tab.apply(lambda s: dataclasses.replace(s, method=LABELS[c.method.value])))
    for (key, name), control in c.params.items():
        on_user(control, lambda k=key, n=name, h=control: _edited(c, tab, k, n, h.value))


def _edited(c: MethodControls, tab: TabActions, key: str, name: str, value: Any) -> None:
    """Apply a control's new value; a typed number once typing pauses (``MethodControls.pause``)."""
    if isinstance(value, str) and not isinstance(getattr(values_of(tab.settings, key), name), str):
        c.pause.call(lambda: _typed(c, tab, key, name, value))
    else:
        tab.apply(lambda s: with_values(s, key, **{name: value}))


def _typed(c: MethodControls, tab: TabActions, key: str, name: str, value: str) -> None:
    """Apply a typed number; text that is not a number is said under the folder, the value in use stays."""
    current = getattr(values_of(tab.settings, key), name)
    try:
        number = typed_number(value, current, key, name)
    except ValueError as error:
        assign(c.typed[key], content=f"*{plain(error)}; the value in use is {current:g}.*", visible=True)
        return
    assign(c.typed[key], visible=False)
    tab.apply(lambda s: with_values(s, key, **{name: number}))


def typed_number(value: str, current: float, key: str, name: str) -> float:
    """The number typed in a text box, as the parameter's type (``1e5``, ``2.5e-1`` accepted), or a
    ``ValueError`` naming the control and what was typed."""
    try:
        number = float(value.strip())
    except ValueError:
        raise ValueError(f"{label_of(key, name)}: {value!r} is not a number") from None
    if isinstance(current, int) and not isinstance(current, bool):
        if not number.is_integer():
            raise ValueError(f"{label_of(key, name)}: {value!r} is not a whole number")
        return int(number)
    return number


PANEL = Panel("Method", 20, "the calibration method and its parameters",
              lambda gui, tab: build(gui, tab.settings, tab.offers), bind)
