"""The Frame panel's scenario list: an OPV2V release root of three scenarios opens as one
sequence, and picking a scenario jumps to its first frame; a DAIR-V2X release with missing files
loads what it can and the page says what was skipped."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

import loaders
from app.server import ExplorerServer
from app.session.explorer import Explorer
from app.session.settings import Settings
from support import browser as ui

SCENARIO = Path(__file__).resolve().parents[1] / "loaders" / "fixtures" / "opv2v" / "scenario"

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory):
    root = tmp_path_factory.mktemp("opv2v")
    for name in ("train/2021_a", "train/2021_b", "test/2021_c"):
        shutil.copytree(SCENARIO, root / name)
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("CBM_EXPLORER_PRESETS", str(tmp_path_factory.mktemp("presets")))
        running = ExplorerServer(Explorer(loaders.open(root)), Settings(), port=0)
        yield running
        running.stop()


def test_picking_a_scenario_jumps_to_its_first_frame(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    session = ui.session(server, 1)
    assert ui.label(page, "scenario").is_visible()
    ui.pick_option(page, "scenario", "test/2021_c")
    ui.wait_until(lambda: session.last.frame_index == 4, timeout=30)
    page.get_by_text("Frame 4").first.wait_for(timeout=30_000)
    assert session.settings.frame == 4
    page.get_by_text("◀ prev", exact=True).first.click()
    ui.wait_until(lambda: session.controls.frame.scenario.value == "train/2021_b", timeout=30)
    page.get_by_text("Frame 3").first.wait_for(timeout=30_000)


def test_a_release_with_missing_files_says_what_was_skipped(browser, tmp_path: Path) -> None:
    root = tmp_path / "cooperative-vehicle-infrastructure"
    shutil.copytree(SCENARIO.parents[1] / "dair_v2x" / root.name, root)
    info = root / "cooperative" / "data_info.json"
    pairs = json.loads(info.read_text())
    info.write_text(json.dumps(pairs + [{**pairs[0], "vehicle_pointcloud_path": "vehicle-side/velodyne/000099.pcd"}]))
    with pytest.warns(UserWarning, match="skipped 1 of 2"):
        sequence = loaders.open(root)
    running = ExplorerServer(Explorer(sequence), Settings(), port=0)
    try:
        page = ui.open_page(browser, running)
        page.get_by_text("Dataset loaded with gaps").first.wait_for(timeout=30_000)
        assert "skipped 1 of 2 pair(s)" in page.get_by_text("skipped 1 of 2").first.inner_text()
    finally:
        running.stop()
