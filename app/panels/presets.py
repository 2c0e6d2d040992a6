"""The Presets tab: which preset the settings are (the list starts on it), pick a shipped or saved
preset and read what it sets before loading it, load it, save the current settings under a name;
below, the preset files that were skipped and why."""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import viser

from ..session.markup import plain
from .actions import TabActions, assign, on_user

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
    descriptions: dict[str, str] = field(default_factory=dict)
    last: str | None = None
    """The preset last in use (what the settings were changed from)."""

    def offer(self, descriptions: Mapping[str, str]) -> None:
        """List the presets (name -> description), keeping the one picked when it is still there."""
        self.descriptions = dict(descriptions)
        picked = self.preset.value
        self.preset.options = tuple(self.descriptions) or (NONE,)
        self.preset.value = picked if picked in self.descriptions else self.preset.options[0]
        self.describe()

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
        text = self.descriptions.get(self.preset.value, "")
        assign(self.about, content=f"*{plain(text)}*" if text else "")


def build(gui: viser.GuiApi, descriptions: Mapping[str, str]) -> PresetControls:
    controls = PresetControls(using=gui.add_markdown(""),
                              preset=gui.add_dropdown("preset", tuple(descriptions) or (NONE,)),
                              about=gui.add_markdown(""), load=gui.add_button("load"),
                              name=gui.add_text("save as", "my-preset"), save=gui.add_button("save current settings"),
                              skipped=gui.add_markdown(""))
    controls.offer(descriptions)
    return controls


def bind(c: PresetControls, tab: TabActions) -> None:
    on_user(c.preset, c.describe)
    c.load.on_click(lambda e: tab.load_preset(c.preset.value))
    c.save.on_click(lambda e: tab.save_preset(c.name.value))
