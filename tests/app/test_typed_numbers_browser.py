"""A method's number typed as text (issue 40, item 6): viser's number box drops an ``e``, so "1e5"
became 15 and "1e-07" became -107 silently. Scientific notation is read; what is not a number, or
lies beyond the parameter's range, is refused on the page, and the value in use stays (and says so)."""
from __future__ import annotations

import pytest

from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

PAIRING = "pairing distance (m)"


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind") as running:
        yield running


def text_box(page):
    """The text box in the row of the label (viser's text input carries no id for its label)."""
    return ui.label(page, PAIRING).locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]").locator(
        "input")


def typed(page, text: str) -> None:
    """Typed key by key, as a person does: the box reports every keystroke ("1", "1e", "1e5"), and the
    number applies once typing pauses."""
    box = text_box(page)
    box.fill("")
    box.press_sequentially(text, delay=50)
    box.press("Enter")


def test_scientific_notation_is_read_and_a_bad_number_is_refused_visibly(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Method").click()
    ui.pick_option(page, "method", "ICP")
    ui.wait_until(lambda: tab.last.settings.method == "icp", 60)
    box = text_box(page)

    typed(page, "2e1")
    ui.wait_until(lambda: tab.last.settings.method_params["icp"].max_correspondence_distance == 20.0, 60)
    typed(page, "1e5")
    page.get_by_text(f"{PAIRING} must be at most 100").first.wait_for(timeout=30_000)
    assert page.get_by_text("ICPParams").count() == 0
    in_use = tab.settings.method_params["icp"]
    ui.wait_until(lambda: box.input_value() == f"{in_use.max_correspondence_distance:g}", 30)
    assert in_use.max_correspondence_distance != 1e5
    typed(page, "2e1")
    ui.wait_until(lambda: tab.last.settings.method_params["icp"].max_correspondence_distance == 20.0, 60)
    typed(page, "abc")
    page.get_by_text(f"{PAIRING}: 'abc' is not a number; the value in use is 20.").first.wait_for(timeout=30_000)
    assert tab.settings.method_params["icp"].max_correspondence_distance == 20.0
    page.close()
