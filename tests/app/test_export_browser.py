"""What leaves the app looks like the app (issue 24, item 10), in a real browser at 1280x720: the
recording's controls and metrics in the first screen and its consensus vote as the app prints it
(the screenshot with the control panel: ``test_fixes_browser``)."""
from __future__ import annotations

import re

import pytest

from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def test_the_recording_fits_the_first_screen_and_words_the_margin_as_the_app(browser, server, tmp_path) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("button", name="next ▶").click()
    ui.wait_until(lambda: len(tab.recording) == 2 and tab.last.frame_index == 1 and tab.last_drawing is not None
                  and tab.last_drawing.metrics_markdown.startswith("**Frame 1**"), 60)
    app_margin = re.search(r"\| consensus vote \| ([^|]+) \|", tab.last_drawing.metrics_markdown).group(1).strip()
    page.get_by_role("tab", name="Explore").click()
    with page.expect_download(timeout=60_000) as download:
        page.get_by_role("button", name="recording of the frames computed (HTML)").click()
    path = tmp_path / "recording.html"
    download.value.save_as(path)
    page.close()

    shown = browser.new_page(viewport=ui.FIRST_SCREEN)
    shown.goto(path.as_uri())
    shown.locator("#frame-title").get_by_text("Frame 0").wait_for(timeout=10_000)
    for element in ("#prev", "#play", "#next", "#frame-slider", "#metrics", "#frame-title"):
        assert ui.in_first_screen(shown.locator(element)), element
    assert ui.in_first_screen(shown.locator("#metrics tr").last)
    shown.keyboard.press("ArrowRight")
    shown.locator("#frame-title").get_by_text(f"Frame {tab.last.frame_index}").wait_for(timeout=10_000)
    assert shown.evaluate("window.scrollY") == 0
    row = shown.locator("#metrics tr").filter(has_text="consensus vote").inner_text()
    assert row.split("\t")[-1].strip() == app_margin, (row, app_margin)
    canvas = shown.locator("#view").bounding_box()
    assert canvas["width"] > 600 and canvas["y"] + canvas["height"] <= ui.FIRST_SCREEN["height"]
    shown.close()

