"""Pinning a baseline: the metrics compare current and pinned and name the settings that differ, the
timeline shows both, the pinned run's matches can be shown in the scene (violet, apart from the grey
missed pairs), and unpinning takes it all away.

With ``CBM_UPDATE_DOCS_IMG=1`` the test also saves the pinned timeline as docs/img/timeline.png."""
from __future__ import annotations

import contextlib
import os
from pathlib import Path

import numpy as np
import pytest

from app.panels.plot import TIMELINE
from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

SCREENSHOT = Path(__file__).resolve().parents[2] / "docs" / "img" / "timeline.png"


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind") as running:
        yield running


def dismiss_notifications(page) -> None:
    """Close the notifications on screen (one may close itself meanwhile)."""
    for button in page.locator(".mantine-Notification-root button").all():
        with contextlib.suppress(Exception):
            button.click(timeout=2_000)


def run_all_frames(page, tab) -> None:
    """Run the current settings over every frame (Explore tab) and wait until the timeline has them."""
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="run all frames").click()
    ui.wait_until(lambda: len(tab.history.rows) == len(tab.explorer) and tab.history.matches(tab.settings), 180)
    ui.wait_until(lambda: page.get_by_role("button", name="run all frames").is_enabled(), 60)


def pinned_frames(tab) -> set[int]:
    """Frames where the timeline draws the pinned precision (no pinned series: none)."""
    data = tab.controls.metrics.plot.data
    if len(data) == len(TIMELINE):
        return set()
    x, pinned_precision = data[0], data[len(TIMELINE)]
    return set(x[np.isfinite(pinned_precision)].astype(int))


def test_a_pinned_baseline_is_compared_plotted_and_ghosted_until_unpinned(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    run_all_frames(page, tab)
    page.get_by_role("button", name="pin baseline").click()
    page.get_by_text("current − pinned").first.wait_for(timeout=60_000)
    page.get_by_text("Pinned under the same settings").first.wait_for(timeout=30_000)
    ui.load_preset(page, "stress")
    ui.wait_until(lambda: tab.last.settings.scenario.sigma_p == 0.9, 60)
    page.get_by_text("current − pinned").first.wait_for(timeout=30_000)
    settings = page.get_by_text("Pinned under other settings").first.inner_text()
    assert "position noise σp (m) 0.2 (now 0.9)" in settings and "seed" not in settings
    drawn = tab.last_drawing.lines
    assert len(drawn["pinned"].segments) and drawn["pinned"].color != drawn["missed"].color
    for frame in (1, 2, 3):
        page.get_by_role("button", name="next ▶").click()
        ui.wait_until(lambda f=frame: tab.last.frame_index == f, 60)
    ui.wait_until(lambda: {0, 1, 2, 3} <= pinned_frames(tab), 30)
    assert tab.stage.view.lines["pinned"].visible
    run_all_frames(page, tab)
    ui.wait_until(lambda: pinned_frames(tab) == set(range(len(tab.explorer))), 30)
    page.set_viewport_size({"width": 1280, "height": 720})
    dismiss_notifications(page)
    page.get_by_text("Pinned baseline").first.evaluate("e => e.scrollIntoView({block: 'start'})")
    if os.environ.get("CBM_UPDATE_DOCS_IMG") == "1":
        page.screenshot(path=str(SCREENSHOT))
    page.get_by_role("tab", name="View").click()
    ui.label(page, "show pinned matches").click()
    ui.wait_until(lambda: not tab.last.settings.view.pinned_lines and not tab.stage.view.lines["pinned"].visible, 60)
    page.get_by_role("button", name="unpin").click()
    ui.wait_until(lambda: not pinned_frames(tab) and "current − pinned" not in ui.metrics(page), 60)
    page.get_by_role("button", name="pin baseline").wait_for(timeout=30_000)
    page.close()
