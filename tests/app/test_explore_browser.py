"""Real-browser tests of the Explore tab: a sequence run with its progress bar and results, a jump
to a worst frame, and a download."""
from __future__ import annotations

import time

import polars as pl
import pytest

import app.session.sequence
from app.server import ExplorerServer
from app.session.explorer import Explorer
from evaluation.metric_registry import RUN_METRICS
from support import browser as ui

pytestmark = [pytest.mark.browser,
              ui.requires_chromium]


@pytest.fixture(scope="module")
def small_server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind", eta=0.4,
                            sigma_p=0.5, sigma_theta=6.0, seed=2) as running:
        yield running


def test_sequence_run_jump_to_a_worst_frame_and_download(browser, small_server: ExplorerServer,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    sweep_run = app.session.sequence.run

    def slowed(*args, **kwargs):
        time.sleep(0.15)
        return sweep_run(*args, **kwargs)

    monkeypatch.setattr(app.session.sequence, "run", slowed)
    page = ui.open_page(browser, small_server)
    tab = ui.session(small_server, 1)
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="run all frames").click()
    page.locator('[role="progressbar"]').first.wait_for(state="visible", timeout=10_000)
    page.get_by_text(RUN_METRICS["success_rate"].label).wait_for(timeout=30_000)
    run = tab.controls.explore.run
    assert run is not None and len(run.rows) == len(small_server.explorer) and not run.cancelled
    ui.wait_until(lambda: not page.locator('[role="progressbar"]').first.is_visible())
    page.get_by_text("Worst frames by RTE").wait_for(timeout=10_000)

    target = next(option for option in tab.controls.explore.worst.options if not option.startswith("frame 0 "))
    frame = int(target.split(" · ")[0].removeprefix("frame "))
    ui.pick_option(page, "worst", target)
    page.get_by_role("button", name="jump there").click()
    ui.wait_until(lambda: tab.last.frame_index == frame and ui.header(page).startswith(f"Frame {frame}"))
    assert ui.slider(page, "frame").get_attribute("aria-valuenow") == str(frame)
    assert tab.last.metrics.rte == run.row(frame)["rte"] and tab.last.metrics.n_correct == run.row(frame)["n_correct"]

    with page.expect_download(timeout=15_000) as download:
        page.get_by_role("button", name="per-frame metrics (CSV)").click()
    assert download.value.suggested_filename.endswith(".csv")
    table = pl.read_csv(download.value.path())
    assert table["frame"].to_list() == [row["frame"] for row in run.rows]
    page.close()
