"""The charts draw what their legends list, read back from the page's own uPlot charts: the
timeline's RTE on a labelled right axis, no line across frames never computed, the top tick inside
the chart, pinned series only while a baseline is pinned; the Explore tab's run gives metres and
degrees an axis each."""
from __future__ import annotations

import math

import pytest

from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

CHARTS = """() => Object.values(window.__viserTestpoints?.uplots ?? {}).map(({chart}) => ({
  title: chart.root.querySelector('.u-title')?.textContent ?? '',
  series: chart.series.map(s => ({label: s.label, scale: s.scale})),
  axes: chart.axes.map(a => ({scale: a.scale, side: a.side, label: a.label ?? null})),
  scales: Object.fromEntries(Object.entries(chart.scales).map(([k, v]) => [k, [v.min, v.max]])),
  data: chart.data.map(a => Array.from(a)),
  top: chart.bbox.top / devicePixelRatio,
  legend: [...chart.root.querySelectorAll('.u-legend .u-label')].map(e => e.textContent)}))"""


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind") as running:
        yield running


def chart(page, title: str) -> dict | None:
    """The page's chart titled ``title`` as uPlot holds it (None before it is drawn)."""
    return next((c for c in page.evaluate(CHARTS) if c["title"] == title), None)


def column(found: dict, label: str) -> list:
    return found["data"][[s["label"] for s in found["series"]].index(label)]


def has_values(found: dict | None, label: str, frames: set[int]) -> bool:
    """Whether ``found`` draws ``label`` at every one of ``frames``."""
    if found is None or label not in [s["label"] for s in found["series"]]:
        return False
    drawn = {int(x) for x, v in zip(found["data"][0], column(found, label)) if v is not None and not math.isnan(v)}
    return frames <= drawn


def axis_of(found: dict, label: str) -> dict:
    scale = next(s["scale"] for s in found["series"] if s["label"] == label)
    return next(a for a in found["axes"] if a["scale"] == scale)


def test_the_timeline_draws_rte_on_its_own_axis_with_gaps_and_no_pinned_entries(browser,
                                                                                   server: ExplorerServer) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    for frame in (1, 2):
        page.get_by_role("button", name="next ▶").click()
        ui.wait_until(lambda f=frame: tab.last.frame_index == f, 60)
    ui.go_to_frame(page, tab, 10)
    page.get_by_role("button", name="next ▶").click()
    ui.wait_until(lambda: has_values(chart(page, "timeline"), "RTE (m)", {0, 1, 2, 10, 11}), 60)
    timeline = chart(page, "timeline")
    rte_axis = axis_of(timeline, "RTE (m)")
    assert rte_axis["side"] == 1 and rte_axis["label"] == "RTE (m)"
    low, high = timeline["scales"][rte_axis["scale"]]
    assert math.isfinite(low) and math.isfinite(high) and high > low
    assert axis_of(timeline, "precision")["label"] and axis_of(timeline, "precision")["scale"] != rte_axis["scale"]
    between = [v for x, v in zip(timeline["data"][0], column(timeline, "precision")) if 2 < x < 10]
    assert between and all(v is None for v in between)
    assert timeline["top"] >= 6
    assert not any("pinned" in entry for entry in timeline["legend"])
    page.get_by_role("button", name="pin baseline").click()
    ui.wait_until(lambda: any("pinned" in e for e in (chart(page, "timeline") or {"legend": []})["legend"]), 60)
    page.get_by_role("button", name="unpin").click()
    ui.wait_until(lambda: not any("pinned" in e for e in (chart(page, "timeline") or {"legend": []})["legend"]), 60)
    page.close()


def test_the_run_charts_give_metres_and_degrees_an_axis_each(browser, server: ExplorerServer) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="run all frames").click()
    ui.wait_until(lambda: tab.controls.explore.run is not None, 180)
    every = set(range(len(tab.explorer)))
    ui.wait_until(lambda: has_values(chart(page, "pose error per frame"), "RRE (°)", every), 60)
    errors = chart(page, "pose error per frame")
    rte, rre = axis_of(errors, "RTE (m)"), axis_of(errors, "RRE (°)")
    assert rte["scale"] != rre["scale"] and rte["side"] != rre["side"]
    assert (rte["label"], rre["label"]) == ("RTE (m)", "RRE (°)")
    assert has_values(chart(page, "precision and recall per frame"), "recall", every)
    page.close()
