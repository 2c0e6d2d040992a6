"""The README's first picture, as a newcomer gets it: the shipped scene at 1280x720, a frame chosen
with the frame slider at the top of the panel, the CAV's boxes side by side before (left) and after
(right) calibration, both halves in view left of the panel.

With ``CBM_UPDATE_DOCS_IMG=1`` the test also saves the page as docs/screenshot.png."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]
DOCS_IMAGE = Path(__file__).resolve().parents[2] / "docs" / "screenshot.png"
FRAME = 15


@pytest.fixture(scope="module")
def server(explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def test_the_readme_picture_shows_both_halves_of_side_by_side(browser, server: ExplorerServer) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    row = ui.label(page, "frame").locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    box = row.locator("input.mantine-NumberInput-input")
    box.fill(str(FRAME))
    box.blur()
    ui.wait_until(lambda: tab.last.frame_index == FRAME, 60)
    page.get_by_role("tab", name="View").click()
    ui.pick_option(page, "CAV boxes", "side by side")
    ui.wait_until(lambda: tab.last.settings.view.layout == "side by side", 60)
    ui.wait_until(lambda: ui.header(page).startswith(f"Frame {FRAME}"))
    assert tab.stage.view.labels["before"].visible and tab.stage.view.labels["after"].visible
    assert tab.last.metrics.precision == 1.0
    page.get_by_role("tab", name="Scenario").click()
    page.locator(".mantine-ScrollArea-viewport").first.evaluate("element => element.scrollTo(0, 0)")
    ui.close_notifications(page)
    shot = ui.settled_screenshot(page)
    if os.environ.get("CBM_UPDATE_DOCS_IMG") == "1":
        DOCS_IMAGE.write_bytes(shot)
    page.close()
