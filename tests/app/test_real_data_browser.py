"""Real data at first contact (issue 39, item 6), in a real browser: a DAIR-V2X subset names and
draws its infrastructure as a roadside unit, and its calibration fallback is a note, not a warning
of gaps."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import loaders
from app.scene.geometry import ROADSIDE_SIZE
from app.session.explorer import Explorer
from support import browser as ui
from support import releases

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def dair_server(tmp_path_factory: pytest.TempPathFactory):
    root = releases.dair_release(tmp_path_factory.mktemp("dair") / "cooperative-vehicle-infrastructure",
                                 world_calib=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sequence = loaders.open(root)
    with ui.scenario_server(Explorer(sequence), tmp_path_factory.mktemp("presets")) as running:
        yield running


def test_dair_infrastructure_is_a_roadside_unit_and_the_fallback_a_note(browser, dair_server) -> None:
    page = ui.open_page(browser, dair_server)
    tab = ui.session(dair_server, 1)
    page.get_by_text("How this dataset is read").first.wait_for(timeout=30_000)
    assert page.get_by_text("Dataset loaded with gaps").count() == 0
    drawing = tab.last_drawing
    assert drawing.metrics_markdown.splitlines()[0] == "**Frame 0** · ego · roadside unit (auto)"
    page.get_by_text("· ego · roadside unit (auto)").first.wait_for(timeout=10_000)
    assert drawing.labels["cav_after"][0] == "roadside unit"
    mast = drawing.meshes["cav_vehicle"].vertices
    assert np.ptp(mast[:, 0]) < ROADSIDE_SIZE[0] + 0.5 and np.ptp(mast[:, 2]) == pytest.approx(ROADSIDE_SIZE[2], abs=0.1)
    page.close()
