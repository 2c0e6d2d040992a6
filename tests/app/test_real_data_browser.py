"""Real data at first contact (issue 39, item 6), in a real browser: a DAIR-V2X subset names and
draws its infrastructure as a roadside unit, and its calibration fallback is a note, not a warning
of gaps; INTERACTION starts on the first frame CBM can run on."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import loaders
from app.scene.geometry import ROADSIDE_SIZE
from app.session.explorer import Explorer
from app.session.settings import Settings
from app.session.start import first_usable, runs_on
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
    assert np.ptp(mast[:, 0]) < ROADSIDE_SIZE[0] + 0.5
    assert np.ptp(mast[:, 2]) == pytest.approx(ROADSIDE_SIZE[2], abs=0.1)
    page.close()


def test_interaction_with_two_cars_says_no_frame_has_enough_shared_objects(browser, tmp_path_factory) -> None:
    """INTERACTION's test recording holds two cars: from frame 30 on they are an ego and a CAV, but
    neither sees an object the other sees, so CBM can stand by a pose on no frame (issue 47: it
    opened on frame 30 as if it could, and failed). The tab starts on frame 30 and says why."""
    explorer = Explorer(loaders.open(releases.FIXTURES / "interaction" / "vehicle_tracks_000.csv"))
    settings = Settings()
    assert first_usable(explorer, settings, range(len(explorer))) is None and not runs_on(explorer, settings, 30)
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        page = ui.open_page(browser, running)
        tab = ui.session(running, 1)
        assert tab.last.frame_index == 30 and ui.header(page) == "Frame 30"
        page.get_by_text("Too few objects seen by both agents").first.wait_for(timeout=30_000)
        page.get_by_text("has 3 objects seen by both an ego and a CAV under the range protocol (at most 0)").first\
            .wait_for(timeout=30_000)
        page.close()


def test_a_sind_clone_without_git_lfs_is_told_to_fetch_the_data(browser, tmp_path_factory) -> None:
    """Only the pedestrians load from a SinD clone whose vehicle tracks are a Git LFS pointer: the page
    says to fetch them (not to change the protocol, which cannot help)."""
    root = releases.sind_without_lfs(tmp_path_factory.mktemp("sind") / "Xian_412_m1")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        explorer = Explorer(loaders.open(root))
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        page = browser.new_page()
        page.goto(ui.address(running))
        page.get_by_text("CBM cannot run on this frame.").first.wait_for(timeout=60_000)
        advice = page.get_by_text("What to try").first.inner_text()
        assert "git lfs pull" in advice and "Veh_smoothed_tracks.csv" in advice and "protocol" not in advice
        page.close()
