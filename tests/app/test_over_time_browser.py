"""CBM over time in a browser: the preset picks it, a jump ahead computes the frames before in order,
and the metrics and the timeline show how the answer was reached beside per-frame CBM."""
from __future__ import annotations

import pytest

from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def test_choosing_cbm_over_time_and_jumping_ahead_shows_the_frames_pooled(browser, server) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    ui.load_preset(page, "drift-heavy")
    ui.wait_until(lambda: tab.last.settings.method == "cbm-time", 60)
    ui.go_to_frame(page, tab, 25)
    ui.wait_until(lambda: "answer from" in ui.metrics(page) or "this frame alone" in ui.metrics(page), 60)
    assert "over time" in ui.metrics(page) and "per-frame CBM (this frame)" in ui.metrics(page)
    ui.wait_until(lambda: set(range(26)) <= set(tab.history.rows), 60)
    ui.wait_until(lambda: page.locator(".uplot").filter(has_text="per-frame CBM RTE").count() == 1, 30)
    page.close()
