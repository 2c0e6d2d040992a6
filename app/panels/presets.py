"""The Presets tab: load a shipped or saved preset, save the current settings under a name; below,
the preset files that were skipped and why."""
from __future__ import annotations

from dataclasses import dataclass

import viser

from .actions import TabActions


@dataclass
class PresetControls:
    preset: viser.GuiDropdownHandle
    load: viser.GuiButtonHandle
    name: viser.GuiTextHandle
    save: viser.GuiButtonHandle
    skipped: viser.GuiMarkdownHandle
    """Which preset files were skipped and why (empty when none was)."""


def build(gui: viser.GuiApi, preset_names: list[str]) -> PresetControls:
    return PresetControls(preset=gui.add_dropdown("preset", tuple(preset_names) or ("(none)",)),
                          load=gui.add_button("load"), name=gui.add_text("save as", "my-preset"),
                          save=gui.add_button("save current settings"), skipped=gui.add_markdown(""))


def bind(c: PresetControls, tab: TabActions) -> None:
    c.load.on_click(lambda e: tab.load_preset(c.preset.value))
    c.save.on_click(lambda e: tab.save_preset(c.name.value))
