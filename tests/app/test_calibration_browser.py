"""The Explore tab's "Dataset calibration" folder in a real browser: on a DAIR-V2X-C release whose
last pair ships an infrastructure transform 1.5 m off, the check lists that frame and *go to frame*
shows it."""
from __future__ import annotations

import pytest

import loaders
from app.session.explorer import Explorer
from support import browser as ui
from support import releases

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory):
    root = releases.dair_release(tmp_path_factory.mktemp("dair") / "cooperative-vehicle-infrastructure",
                                 pairs=3, infra_error=(1.5, 0.0))
    with ui.scenario_server(Explorer(loaders.open(root)), tmp_path_factory.mktemp("presets"),
                            protocol="opv2v") as running:
        yield running


def test_flagged_frames_are_listed_and_go_to_frame_shows_one(browser, server) -> None:
    page = ui.open_page(browser, server)
    session = ui.session(server, 1)
    assert session.last.frame_index == 0
    page.get_by_role("tab", name="Explore").click()
    page.get_by_text("Dataset calibration").click()
    page.get_by_role("button", name="check the dataset's calibration").click()
    page.get_by_text("1 of 3 frames checked disagrees").wait_for(timeout=60_000)
    assert session.controls.explore.flagged.options == ("frame 2 (000012): roadside unit, 1.50 m / 0.00°",)
    page.get_by_role("button", name="go to frame").click()
    ui.wait_until(lambda: session.last.frame_index == 2 and ui.header(page).startswith("Frame 2"), timeout=60)
    assert session.last.cav_id == "infrastructure"


def test_a_dataset_without_per_agent_labels_says_so(browser, tmp_path_factory) -> None:
    with ui.scenario_server(Explorer(loaders.open("synthetic:30")), tmp_path_factory.mktemp("p2")) as running:
        page = ui.open_page(browser, running)
        session = ui.session(running, 1)
        page.get_by_role("tab", name="Explore").click()
        page.get_by_text("Dataset calibration").click()
        page.get_by_text("keeps no per-agent labels").wait_for(timeout=30_000)
        assert session.controls.explore.check.disabled
