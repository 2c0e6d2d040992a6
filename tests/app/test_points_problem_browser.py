"""A sweep that cannot be read (here the CAV's .pcd is a Git LFS pointer) never costs the frame: with
"LiDAR points" on, the boxes and CBM's result stay, the ego's points draw, and the metrics panel
names the unreadable file."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import loaders
from app.session.explorer import Explorer
from support import browser as ui

FIXTURE = Path(__file__).resolve().parents[1] / "loaders" / "fixtures" / "opv2v_points" / "scenario"
POINTER = b"version https://git-lfs.github.com/spec/v1\noid sha256:" + b"1" * 64 + b"\nsize 2048\n"

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory):
    scenario = tmp_path_factory.mktemp("lfs") / "scenario"
    shutil.copytree(FIXTURE, scenario)
    (scenario / "650" / "000068.pcd").write_bytes(POINTER)
    explorer = Explorer(loaders.open(scenario))
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def _shown(session, name: str) -> int:
    handle = session.stage.view.clouds.get(name)
    return 0 if handle is None or not handle.visible else len(handle.points)


def test_an_unreadable_sweep_is_named_and_the_frame_still_computes(browser, server) -> None:
    page = ui.open_page(browser, server)
    session = ui.session(server, 1)
    before = session.last.result.transform.copy()

    page.get_by_role("tab", name="View").click()
    ui.label(page, "LiDAR points").click()
    ui.wait_until(lambda: session.last.settings.view.points and _shown(session, "ego_points") == 4, timeout=60)
    assert _shown(session, "cav_points") == 0
    page.get_by_text("LiDAR points not shown").first.wait_for(timeout=30_000)
    page.get_by_text("000068.pcd is a Git LFS pointer, not the data").first.wait_for(timeout=30_000)
    assert "precision / recall" in ui.metrics(page)
    assert page.get_by_text("CBM cannot run on this frame").count() == 0
    assert (session.last.result.transform == before).all()
