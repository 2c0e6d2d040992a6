"""A sequence run never goes stale silently: once the controls move to other settings, its summary
and worst frames say so and name the settings, *jump there* asks before it sets the run's settings,
and the per-frame export gives what the current settings give."""
from __future__ import annotations

import io

import polars as pl
import pytest

from app.server import ExplorerServer
from app.session import worst
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

STALE = "Computed under other settings"
RUN_SIGMA_P, STRESS_SIGMA_P = 0.2, 0.9
"""The position noise of the tab's settings and of the shipped ``stress`` preset."""


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind",
                            sigma_p=RUN_SIGMA_P) as running:
        yield running


def load_stress(page, tab) -> None:
    ui.load_preset(page, "stress")
    ui.wait_until(lambda: tab.last.settings.scenario.sigma_p == STRESS_SIGMA_P, 60)
    page.get_by_role("tab", name="Explore").click()


def stale_marks(page) -> int:
    return page.get_by_text(STALE).count()


def jump_and_answer(page, answer: str) -> None:
    """Click *jump there* and answer the question it asks (which must list σp's change back)."""
    page.get_by_role("button", name="jump there").click()
    dialog = page.get_by_role("dialog")
    dialog.get_by_text(f"position noise σp (m): {STRESS_SIGMA_P:g} → {RUN_SIGMA_P:g}").wait_for(timeout=30_000)
    dialog.get_by_role("button", name=answer).click()
    dialog.wait_for(state="hidden", timeout=30_000)


def test_a_run_under_other_settings_is_marked_asks_before_a_jump_and_exports_the_current(
        browser, server: ExplorerServer) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="run all frames").click()
    ui.wait_until(lambda: tab.controls.explore.run is not None, 180)
    assert stale_marks(page) == 0
    load_stress(page, tab)
    ui.wait_until(lambda: stale_marks(page) >= 2, 30)
    assert f"position noise σp (m) {RUN_SIGMA_P:g} (now {STRESS_SIGMA_P:g})" in \
        page.get_by_text(STALE).first.locator("xpath=..").inner_text()
    page.get_by_text("pose error per frame (other settings)").wait_for(timeout=30_000)
    worst_frame = worst.frame_of(tab.controls.explore.worst.value)
    if tab.settings.frame == worst_frame:
        page.get_by_role("button", name="next ▶").click()
        ui.wait_until(lambda: tab.last.frame_index == worst_frame + 1, 60)

    jump_and_answer(page, "cancel")
    assert tab.settings.scenario.sigma_p == STRESS_SIGMA_P and tab.settings.frame != worst_frame
    jump_and_answer(page, "jump, keep my settings")
    ui.wait_until(lambda: tab.last.frame_index == worst_frame, 60)
    assert tab.last.settings.scenario.sigma_p == STRESS_SIGMA_P
    jump_and_answer(page, "set the run's settings and jump")
    ui.wait_until(lambda: tab.last.settings.scenario.sigma_p == RUN_SIGMA_P and tab.last.frame_index == worst_frame, 60)
    ui.wait_until(lambda: stale_marks(page) == 0, 30)

    load_stress(page, tab)
    ui.wait_until(lambda: stale_marks(page) >= 2, 30)
    with page.expect_download(timeout=240_000) as download:
        page.get_by_role("button", name="per-frame metrics (CSV)").click()
    rows = pl.read_csv(io.BytesIO(download.value.path().read_bytes()))
    assert len(rows) == len(tab.explorer) and rows["sigma_p"].unique().to_list() == [STRESS_SIGMA_P]
    ui.wait_until(lambda: stale_marks(page) == 0, 30)
    page.close()
