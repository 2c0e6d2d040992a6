"""Several CAVs in the app: the Frame panel's CAVs number adds CAVs, each drawn in its own colour
with a metrics row of its own; one CAV is the app as it was."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from app.scene.colours import CAV_COLOURS
from app.scene.drawing import draw
from app.server import ExplorerServer
from app.session.explorer import Explorer
from app.session.settings import Settings
from support import browser as ui


def test_one_cav_draws_no_other_cav_and_no_per_cav_table(explorer: Explorer) -> None:
    outcome = explorer.compute(Settings(frame=10))
    drawing = draw(outcome, explorer.map_segments)
    assert outcome.others == () and "Per CAV" not in drawing.metrics_markdown
    assert all(len(drawing.meshes[f"cav_boxes_{k}"].faces) == 0 for k in (2, 3, 4))


def test_three_cavs_are_drawn_in_their_colours_with_a_row_each(explorer: Explorer) -> None:
    outcome = explorer.compute(dataclasses.replace(Settings(frame=10), cavs=3))
    drawing = draw(outcome, explorer.map_segments)
    ids = [outcome.cav_id, *(other.cav_id for other in outcome.others)]
    assert len(outcome.others) == 2 and len(set(ids)) == 3
    for k, colour in ((2, CAV_COLOURS[0]), (3, CAV_COLOURS[1])):
        mesh = drawing.meshes[f"cav_boxes_{k}"]
        assert len(mesh.faces) == 2 * len(outcome.others[k - 2].trial.cav_boxes) and mesh.color == colour
    assert len(drawing.meshes["cav_boxes_4"].faces) == 0
    for k, cav in enumerate(ids, 1):
        assert f"| CAV {k} `{cav[:8]}`" in drawing.metrics_markdown


def test_cbm_graph_uses_the_other_cavs(explorer: Explorer) -> None:
    settings = dataclasses.replace(Settings(frame=10), cavs=3)
    plain = explorer.compute(settings)
    joint = explorer.compute(dataclasses.replace(settings, method="cbm-graph"))
    assert np.array_equal(joint.result.pairs, plain.result.pairs)
    assert not np.array_equal(joint.result.transform, plain.result.transform)


@pytest.fixture(scope="module")
def server(explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


@pytest.mark.browser
@ui.requires_chromium
def test_setting_two_cavs_shows_two_cav_colours_and_metrics_rows(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    box = page.locator(f'[id="{ui.label(page, "CAVs").get_attribute("for")}"]')
    box.fill("2")
    box.blur()
    ui.wait_until(lambda: tab.last.settings.cavs == 2 and len(tab.last.others) == 1, timeout=60)
    page.get_by_text("Per CAV").first.wait_for(timeout=30_000)
    rows = page.get_by_text("Per CAV").first.locator("xpath=following::table[1]").inner_text()
    assert "CAV 1" in rows and "CAV 2" in rows and "CAV 3" not in rows
    ui.wait_until(lambda: tab.stage.view.meshes["cav_boxes_2"].visible, timeout=30)
    assert tuple(tab.stage.view.meshes["cav_boxes_2"].color) == CAV_COLOURS[0]
    assert tuple(tab.stage.view.meshes["cav_boxes"].color) != CAV_COLOURS[0]
    assert not tab.stage.view.meshes["cav_boxes_3"].visible
    page.close()
