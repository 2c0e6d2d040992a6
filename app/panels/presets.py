"""The Presets tab: which preset the settings are (the list starts on it), pick a shipped or saved
preset and read what it sets before loading it, load it, save the current settings under a name;
below, the preset files that were skipped and why."""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import viser

from ..session.markup import plain
from ..session.presets import Preset, PresetError, discover, in_use, save_preset, skipped_markdown
from ..session.settings import Settings
from .actions import TabActions, assign, on_user
from .registry import Panel

NONE = "(none)"


@dataclass
class PresetControls:
    using: viser.GuiMarkdownHandle
    """Which preset the settings are, or the one they were changed from."""
    preset: viser.GuiDropdownHandle
    about: viser.GuiMarkdownHandle
    """The picked preset's description, shown before it is loaded."""
    load: viser.GuiButtonHandle
    name: viser.GuiTextHandle
    save: viser.GuiButtonHandle
    skipped: viser.GuiMarkdownHandle
    """Which preset files were skipped and why (empty when none was)."""
    presets: dict[str, Preset] = field(default_factory=dict)
    """The presets found (shipped and the user's), by name."""
    problems: list[str] = field(default_factory=list)
    """The preset files skipped, and why."""
    last: str | None = None
    """The preset last in use (what the settings were changed from)."""

    def offer(self, presets: Mapping[str, Preset], problems: list[str]) -> None:
        """List the presets, keeping the one picked when it is still there, and the files skipped."""
        self.presets, self.problems = dict(presets), problems
        picked = self.preset.value
        self.preset.options = tuple(self.presets) or (NONE,)
        self.preset.value = picked if picked in self.presets else self.preset.options[0]
        self.skipped.content = skipped_markdown(problems)
        self.describe()

    def reflect(self, settings: Settings) -> None:
        self.in_use(in_use(self.presets, settings))

    def in_use(self, name: str | None) -> None:
        """Say that the settings are the preset ``name`` (None: none) and, when another preset than
        before is in use, move the list to it (a preset picked to read stays picked otherwise); when
        they are none, name the preset they were changed from."""
        if name is not None and name != self.last:
            self.last = name
            assign(self.preset, value=name)
            self.describe()
        if name is not None:
            words = f"*In use: **{plain(name)}**.*"
        elif self.last is not None:
            words = f"*In use: your own settings, changed from **{plain(self.last)}**.*"
        else:
            words = "*In use: your own settings (no preset).*"
        assign(self.using, content=words)

    def describe(self) -> None:
        """Show what the picked preset is for."""
        preset = self.presets.get(self.preset.value)
        assign(self.about, content=f"*{plain(preset.description)}*" if preset and preset.description else "")


def build(gui: viser.GuiApi, presets: Mapping[str, Preset], problems: list[str]) -> PresetControls:
    controls = PresetControls(using=gui.add_markdown(""),
                              preset=gui.add_dropdown("preset", tuple(presets) or (NONE,)),
                              about=gui.add_markdown(""), load=gui.add_button("load"),
                              name=gui.add_text("save as", "my-preset"), save=gui.add_button("save current settings"),
                              skipped=gui.add_markdown(""))
    controls.offer(presets, problems)
    return controls


def bind(c: PresetControls, tab: TabActions) -> None:
    on_user(c.preset, c.describe)
    c.load.on_click(lambda e: load(c, tab, c.preset.value))
    c.save.on_click(lambda e: save(c, tab, c.name.value))
    if c.problems:
        tab.notify("Preset files skipped", f"{len(c.problems)} file(s): see the Presets tab", "yellow")


def load(c: PresetControls, tab: TabActions, name: str) -> None:
    """Load the preset ``name`` over the app's defaults (the frame and the CAVs stay), or say why not."""
    preset = c.presets.get(name)
    if preset is None:
        tab.notify("No such preset", f"{name!r} is not among the presets", "red")
        return
    current = tab.settings
    try:
        loaded = preset.apply(current)
        refused = tab.offers.refusal(dataclasses.replace(loaded, cavs=current.cavs))
        if refused:
            raise ValueError(refused)
    except (KeyError, TypeError, ValueError) as error:
        tab.notify("Preset not loaded", f"{name}: {error}", "red")
        return
    tab.apply(lambda s: dataclasses.replace(loaded, frame=s.frame, cav=s.cav, cavs=s.cavs), move_controls=True)
    tab.notify("Preset loaded", preset.description or name, "green")


def save(c: PresetControls, tab: TabActions, name: str) -> None:
    """Save the current settings as the user's preset ``name``, and list it."""
    try:
        path = save_preset(name.strip(), tab.settings)
    except (PresetError, OSError) as error:
        tab.notify("Preset not saved", str(error), "red")
        return
    c.offer(*discover())
    c.reflect(tab.settings)
    tab.notify("Preset saved", f"{name} -> {path.name} in your presets folder", "green")


PANEL = Panel("Presets", 40, "named settings: load a shipped or saved preset, save the current settings as one",
              lambda gui, tab: build(gui, *discover()), bind)
