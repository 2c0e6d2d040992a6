"""Every method on the whole sequence in a browser (issue 47, item 4): tick methods, run them on
every frame with progress and a stop button, read one table and one chart with a line per method,
click a frame under the chart to show it, and put two methods' pairs on one frame side by side or
over each other."""
from __future__ import annotations

import threading

import pytest

from app.server import ExplorerServer
from app.session import compare
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]
FOLDER = "Every method, whole sequence"


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind", sigma_p=0.3,
                            sigma_theta=3.0, loc_x=8.0, loc_yaw=15.0, seed=21) as running:
        yield running


def open_folder(page) -> None:
    page.get_by_role("tab", name="Explore").click()
    page.get_by_text(FOLDER, exact=True).click()
    page.get_by_role("button", name="run every method ticked").wait_for(timeout=30_000)


def tick(page, name: str, ticked: bool) -> None:
    box = page.locator(f'[id="{ui.label(page, name).get_attribute("for")}"]')
    if box.is_checked() != ticked:
        box.click()


def test_ticked_methods_run_on_every_frame_into_one_table_and_one_chart(browser, server: ExplorerServer) -> None:
    server.explorer.rows.clear()
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    open_folder(page)
    tick(page, "CBM over time", False)
    tick(page, "V2X-Reg++", False)
    part = tab.controls.compare
    ui.wait_until(lambda: not part.ticks["cbm-time"].value and not part.ticks["v2xregpp"].value)
    page.get_by_role("button", name="run every method ticked").click()
    ui.wait_until(lambda: part.comparison is not None, 300)
    assert tuple(part.comparison.runs) == ("cbm", "icp", "oracle") and not part.comparison.stopped
    page.get_by_text("median RTE (m)").first.wait_for(timeout=30_000)
    table = page.get_by_text("median RTE (m)").first.locator("xpath=ancestor::table").inner_text()
    assert "ICP" in table and "oracle" in table and f"{len(tab.explorer)} of {len(tab.explorer)}" in table
    chart = page.locator(".uplot").filter(has_text="RTE per frame, a line per method")
    for name in ("CBM", "ICP", "oracle", "1 m (success)"):
        assert chart.get_by_text(name, exact=True).count() == 1
    ui.pick_option(page, "method A", "ICP")
    failed = part.comparison.beaten("icp")
    assert failed
    frame, _ = failed[-1]
    ui.wait_until(lambda: any(option.startswith(f"frame {frame}:") for option in part.beaten.options))
    ui.pick_option(page, "A fails, others not", next(o for o in part.beaten.options if o.startswith(f"frame {frame}:")))
    ui.wait_until(lambda: tab.last.frame_index == frame, 60)
    slider = ui.slider(page, "show frame").locator("xpath=..")
    box = slider.bounding_box()
    slider.click(position={"x": box["width"] * 0.1, "y": box["height"] / 2})
    ui.wait_until(lambda: tab.last.frame_index == int(part.frame.value) and tab.last.frame_index < frame, 60)
    page.close()


def test_a_comparison_stops_when_asked_and_keeps_what_it_ran(browser, server: ExplorerServer, monkeypatch) -> None:
    """The first method's run is held until the stop button was clicked, so the click always lands
    while the comparison runs, however busy the machine."""
    server.explorer.rows.clear()
    clicked, started, original = threading.Event(), threading.Event(), compare.run_sequence

    def held(explorer, settings, task):
        started.set()
        clicked.wait(60)
        return original(explorer, settings, task)

    monkeypatch.setattr(compare, "run_sequence", held)
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    open_folder(page)
    page.get_by_role("button", name="run every method ticked").click()
    stop = page.get_by_role("button", name="stop", exact=True)
    stop.wait_for(timeout=30_000)
    assert started.wait(60) and page.locator(".mantine-Progress-root").first.is_visible()
    stop.click()
    clicked.set()
    part = tab.controls.compare
    ui.wait_until(lambda: part.comparison is not None, 120)
    assert part.comparison.stopped and len(part.comparison.runs) <= 1
    page.get_by_text(f"of {len(compare.TICKED)} methods, stopped").first.wait_for(timeout=30_000)
    stop.wait_for(state="hidden", timeout=30_000)
    page.close()


def test_two_methods_pairs_on_one_frame_side_by_side_then_overlaid(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    ui.go_to_frame(page, tab, 7)
    open_folder(page)
    ui.pick_option(page, "method A", "ICP")
    ui.pick_option(page, "method B", "CBM")
    page.get_by_role("button", name="side by side").click()
    ui.wait_until(lambda: tab.last.settings.method == "icp" and "title_pinned" in tab.last_drawing.labels, 60)
    assert tab.last_drawing.labels["title_pinned"][0] == "CBM (pinned)" and tab.last.frame_index == 7
    assert len(tab.last_drawing.meshes["pinned_cav_boxes"].faces) and tab.baseline.beside
    assert {"/scene/pinned_cav_boxes", "/scene/pinned_ego_boxes"} <= tab.stage.view.visible_names
    page.get_by_text("drawn beside, on the left").first.wait_for(timeout=30_000)
    page.get_by_role("button", name="overlaid").click()
    ui.wait_until(lambda: "title_pinned" not in tab.last_drawing.labels and not tab.baseline.beside, 60)
    assert len(tab.last_drawing.lines["pinned"].segments) and "/scene/pinned_cav_boxes" not in \
        tab.stage.view.visible_names
    page.get_by_text("thin violet lines").first.wait_for(timeout=30_000)
    page.close()
