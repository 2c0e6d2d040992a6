"""CBM over time's tracking parameters in a real browser: the Method tab's advanced folder shows only
when *CBM over time* is chosen, each control with its unit and its docstring as hint, and an edit
recomputes the frame under the new tracking."""
from __future__ import annotations

import pytest

from app.panels.method import TRACKING_FOLDER
from app.scene.text import EVENT_WORDS
from app.scene.words import TRACKING, WORDS
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

CHAIN = WORDS[(TRACKING, "chain")][0]


@pytest.fixture(scope="module")
def server(explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def text_box(page, label: str):
    """The text box in the row of ``label`` (viser's text input carries no id for its label)."""
    return ui.label(page, label).locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]").locator(
        "input")


def test_choosing_cbm_over_time_offers_its_tracking_and_an_edit_recomputes(browser, server) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    page.get_by_role("tab", name="Method").click()
    folder = page.get_by_text(TRACKING_FOLDER, exact=True)
    assert folder.count() == 0 or not folder.first.is_visible(), "per-frame CBM does not track"
    ui.pick_option(page, "method", "CBM over time")
    ui.wait_until(lambda: tab.last.settings.method == "cbm-time", 60)
    ui.go_to_frame(page, tab, 1)
    ui.wait_until(lambda: EVENT_WORDS["per frame"] in ui.metrics(page), 60)
    page.get_by_role("tab", name="Method").click()
    folder.first.wait_for(timeout=30_000)
    folder.first.click()
    box = text_box(page, CHAIN)
    box.wait_for(timeout=30_000)
    assert box.input_value() == "5"
    control = tab.controls.method.params[(TRACKING, "chain")]
    assert control.hint == WORDS[(TRACKING, "chain")][1] and control.hint.startswith("Measurements in a row")
    box.fill("2")
    box.press("Enter")
    ui.wait_until(lambda: tab.last.settings.tracking.chain == 2, 60)
    ui.wait_until(lambda: EVENT_WORDS["started"] in ui.metrics(page), 60)
    assert tab.last.frame_index == 1 and tab.last.result.track.event == "started"
    page.close()
