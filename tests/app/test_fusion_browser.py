"""Real-browser test of late fusion in the app: the View tab's "fused boxes" option draws the fused
boxes green (true positive) or red (false positive), and the Explore tab's sequence run reports AP."""
from __future__ import annotations

import numpy as np
import pytest

from app.scene.colours import palette
from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind", eta=0.6,
                            sigma_p=0.0, sigma_theta=0.0, seed=1) as running:
        yield running


def outlines(tab, name: str) -> int:
    """How many box outlines node ``name`` shows (4 segments each; 0 when hidden)."""
    handle = tab.stage.view.lines.get(name)
    return 0 if handle is None or not handle.visible else len(handle.points) // 4


def test_fused_view_colours_true_and_false_positives_and_the_sequence_run_reports_ap(
        browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    page.get_by_role("tab", name="View").click()
    ui.label(page, "fused boxes (late fusion)").click()
    ui.wait_until(lambda: tab.last.settings.view.fused and outlines(tab, "fused_tp") > 0, 60)
    assert outlines(tab, "fused_fp") == 0
    wrong = palette(tab.last.settings.view).wrong.color
    assert tuple(tab.stage.view.lines["fused_tp"].colors[0, 0]) == palette(tab.last.settings.view).right.color

    ui.pick_option(page, "CAV boxes", "before")
    ui.wait_until(lambda: tab.last.settings.view.layout == "before" and outlines(tab, "fused_fp") > 0, 60)
    assert tuple(tab.stage.view.lines["fused_fp"].colors[0, 0]) == wrong
    assert np.all(tab.stage.view.lines["fused_fp"].colors == np.array(wrong, np.uint8))

    ui.label(page, "fused boxes (late fusion)").click()
    ui.wait_until(lambda: not tab.last.settings.view.fused and outlines(tab, "fused_fp") == 0, 60)
    assert outlines(tab, "fused_tp") == 0

    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="run all frames").click()
    page.get_by_text("late-fusion AP@0.7 (BEV IoU)").wait_for(timeout=90_000)
    run = tab.controls.explore.run
    assert run is not None and 0.0 < run.fused_ap()[0.7] <= 1.0
    assert f"{100 * run.fused_ap()[0.7]:.1f} %" in tab.controls.explore.summary.content
    page.close()
