"""Tabs are found, not listed (``app.panels.registry``): a module that registers a ``Panel`` gets its
tab in the row, its controls wired to the session (an edit applies, a result reaches it) and its line
in ``cbm-explorer --help``, with no edit anywhere else."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

import app.panels
from app.cli import parse
from app.panels import registry
from app.session.explorer import Explorer
from support import browser as ui

THROWAWAY = '''
import dataclasses

from app.panels.registry import Panel


class Notes:
    """A throwaway tab: a button that jumps to frame 3, and the frame of the last result shown."""

    def __init__(self, gui, tab):
        self.shown = gui.add_markdown("no result yet")
        self.jump = gui.add_button("jump to frame 3")
        self.jump.on_click(lambda e: tab.apply(lambda s: dataclasses.replace(s, frame=3), move_controls=True))

    def refresh(self, outcome, picture):
        self.shown.content = f"notes on frame {outcome.frame_index}"


PANEL = Panel("Notes", 70, "a throwaway tab that jumps to frame 3", Notes)
'''


@pytest.fixture
def notes_tab(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A panel module written to a folder the ``app.panels`` package is searched in too; gone after."""
    (tmp_path / "throwaway_notes.py").write_text(THROWAWAY)
    monkeypatch.setattr(app.panels, "__path__", [*app.panels.__path__, str(tmp_path)])
    yield
    sys.modules.pop("app.panels.throwaway_notes", None)


def test_a_registered_panel_is_listed_last_and_in_the_help(notes_tab, capsys: pytest.CaptureFixture) -> None:
    assert list(registry.found()) == ["scenario", "method", "view", "presets", "explore", "compare", "walkthrough",
                                      "throwaway_notes"]
    with pytest.raises(SystemExit):
        parse(["--help"])
    assert "  Notes: a throwaway tab that jumps to frame 3" in capsys.readouterr().out


@pytest.mark.browser
@ui.requires_chromium
def test_a_new_panel_module_gets_its_tab_its_wiring_and_its_results(notes_tab, browser, small_explorer: Explorer,
                                                                     tmp_path: Path) -> None:
    with ui.scenario_server(small_explorer, tmp_path / "presets") as server:
        page = ui.open_page(browser, server)
        tab = ui.session(server, 1)
        names = [item.inner_text() for item in ui.panel_tabs(page)]
        assert names == ["Scenario", "Method", "View", "Presets", "Explore", "Steps", "Notes"]
        page.get_by_role("tab", name="Notes").click()
        page.get_by_text("notes on frame 0").first.wait_for(timeout=60_000)
        page.get_by_role("button", name="jump to frame 3").click()
        ui.wait_until(lambda: tab.last.frame_index == 3, 60)
        page.get_by_text("notes on frame 3").first.wait_for(timeout=60_000)
        assert tab.controls.throwaway_notes.shown.content == "notes on frame 3"
        page.close()
