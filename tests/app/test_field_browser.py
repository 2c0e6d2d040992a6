"""The field side by side in the browser, without GNSS: V2X-Reg++ and FreeAlign are in the method
list with their parameters in words; a run of V2X-Reg++ over every frame ranks its worst frames and
jumps to one; pinned, it is compared with CBM without a prior on the same frames."""
from __future__ import annotations

import numpy as np
import pytest

from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="range", sensor_range=50.0,
                            localization="none", loc_x=0.0, sigma_p=0.3, sigma_theta=5.0) as running:
        yield running


def run_all_frames(page, tab) -> None:
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="run all frames").click()
    explore = tab.controls.explore
    ui.wait_until(lambda: explore.run is not None and len(explore.run.rows) == len(tab.explorer)
                  and tab.history.matches(tab.settings), 180)
    ui.wait_until(lambda: page.get_by_role("button", name="run all frames").is_enabled(), 60)


def test_v2xregpp_is_run_ranked_pinned_and_compared_with_cbm_without_a_prior(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Method").click()
    ui.pick_option(page, "method", "FreeAlign")
    ui.wait_until(lambda: tab.last.settings.method == "freealign", 60)
    assert ui.label(page, "anchor tolerance (m)").is_visible()
    ui.pick_option(page, "method", "V2X-Reg++")
    ui.wait_until(lambda: tab.last.settings.method == "v2xregpp", 60)
    ui.wait_until(lambda: ui.label(page, "boxes kept per agent").is_visible()
                  and not ui.label(page, "anchor tolerance (m)").is_visible())

    run_all_frames(page, tab)
    page.get_by_text("Worst frames by RTE").wait_for(timeout=30_000)
    run = tab.controls.explore.run
    target = next(option for option in tab.controls.explore.worst.options if not option.startswith("frame 0 "))
    frame = int(target.split(" · ")[0].removeprefix("frame "))
    ui.pick_option(page, "worst", target)
    page.get_by_role("button", name="jump there").click()
    ui.wait_until(lambda: tab.last.frame_index == frame and tab.last.settings.method == "v2xregpp", 60)
    shown = tab.last.metrics
    np.testing.assert_equal((shown.rte, shown.n_matched, shown.n_correct),
                            (run.row(frame)["rte"], run.row(frame)["n_matched"], run.row(frame)["n_correct"]))

    page.get_by_role("button", name="pin baseline").click()
    page.get_by_role("tab", name="Method").click()
    ui.pick_option(page, "method", "CBM without a prior")
    ui.wait_until(lambda: tab.last.settings.method == "cbm-no-prior", 60)
    page.get_by_text("current − pinned").first.wait_for(timeout=60_000)
    assert "V2X-Reg++" in page.get_by_text("Pinned under other settings").first.inner_text()
    assert tab.last.frame_index == frame
    page.close()
