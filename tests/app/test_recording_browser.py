"""Real-browser test of the shareable recording: the Explore tab's export button downloads a page
that chromium opens from disk with every network request refused, draws the frames shown and
moves through them with its slider and buttons."""
from __future__ import annotations

import pytest

from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

FRAMES = 3


@pytest.fixture(scope="module")
def small_server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind", eta=0.4,
                            sigma_p=0.5, sigma_theta=6.0, seed=2) as running:
        yield running


def painted_pixels(page) -> int:
    return page.evaluate("""() => {
        const c = document.getElementById('view'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let n = 0; for (let k = 3; k < d.length; k += 4) if (d[k] > 0) n++; return n; }""")


def metrics_text(page) -> str:
    return page.locator("#metrics").inner_text()


def test_the_exported_recording_replays_offline(browser, small_server: ExplorerServer, tmp_path) -> None:
    app_page = ui.open_page(browser, small_server)
    tab = ui.session(small_server, 1)
    for frame in range(1, FRAMES):
        app_page.get_by_role("button", name="next ▶").first.click()
        ui.wait_until(lambda shown=frame: tab.last.frame_index == shown and len(tab.recording) == shown + 1,
                      timeout=30)
    records = tab.recording.frames()
    app_page.get_by_role("tab", name="Explore").click()
    with app_page.expect_download(timeout=30_000) as download:
        app_page.get_by_role("button", name="recording of the frames computed (HTML)").click()
    assert download.value.suggested_filename == f"cbm-explorer-synthetic-60-seed-0-{FRAMES}frames.html"
    path = tmp_path / download.value.suggested_filename
    download.value.save_as(path)
    app_page.close()

    context = browser.new_context(offline=True, viewport={"width": 1400, "height": 900})
    requested, errors = [], []
    context.route("**/*", lambda route: route.continue_() if route.request.url.startswith("file:")
                  else (requested.append(route.request.url), route.abort()))
    page = context.new_page()
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(path.as_uri())
    page.locator("#frame-label").get_by_text(f"(1 / {FRAMES})").wait_for(timeout=10_000)
    assert page.locator("#title").inner_text().startswith("CBM Explorer ")
    assert "synthetic:60" in page.locator("#title").inner_text()
    assert "Method: CBM" in page.locator("#settings").inner_text()
    assert page.locator("#frame-title").inner_text() == f"Frame {records[0].frame}"
    assert f"{records[0].metrics['n_ego']} / {records[0].metrics['n_cav']}" in metrics_text(page)
    assert painted_pixels(page) > 2_000

    page.locator("#next").click()
    ui.wait_until(lambda: page.locator("#frame-title").inner_text() == f"Frame {records[1].frame}")
    assert f"(2 / {FRAMES})" in page.locator("#frame-label").inner_text()
    assert f"{records[1].metrics['n_ego']} / {records[1].metrics['n_cav']}" in metrics_text(page)

    page.locator("#frame-slider").press("End")
    ui.wait_until(lambda: page.locator("#frame-title").inner_text() == f"Frame {records[-1].frame}")
    assert f"({FRAMES} / {FRAMES})" in page.locator("#frame-label").inner_text()
    assert painted_pixels(page) > 2_000
    assert requested == [] and errors == []
    context.close()
