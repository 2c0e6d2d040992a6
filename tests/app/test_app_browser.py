"""Real-browser end-to-end tests: Playwright drives Debian's chromium against a live server."""
from __future__ import annotations

import io
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from app.server import ExplorerServer
from app.session.explorer import Explorer
from app.session.presets import discover
from app.session.settings import Settings
from support import browser as ui

REPO = Path(__file__).resolve().parents[2]

pytestmark = [pytest.mark.browser,
              ui.requires_chromium]


@pytest.fixture(scope="module")
def server(explorer: Explorer, tmp_path_factory: pytest.TempPathFactory, monkeypatch_module) -> ExplorerServer:
    monkeypatch_module.setenv("CBM_EXPLORER_PRESETS", str(tmp_path_factory.mktemp("presets")))
    presets, _ = discover()
    running = ExplorerServer(explorer, presets["default"].apply(Settings()), port=0)
    yield running
    running.stop()


@pytest.fixture(scope="module")
def monkeypatch_module():
    with pytest.MonkeyPatch.context() as patch:
        yield patch


def _type_into(page, label: str, value: str) -> None:
    """Type ``value`` into the number box beside a slider, as a user does (arrow keys would also
    turn viser's camera, which listens to the keyboard)."""
    row = ui.label(page, label).locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    box = row.locator("input.mantine-NumberInput-input")
    box.fill(value)
    box.blur()


def test_scene_controls_and_sessions(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    session = ui.session(server, 1)
    nodes = {"/scene/ego_vehicle", "/scene/cav_vehicle", "/scene/ego_boxes", "/scene/cav_boxes"}
    assert nodes <= session.stage.view.node_names

    first = ui.metrics(page)
    page.get_by_role("tab", name="Method").click()
    sigma2 = ui.slider(page, "σ2 distance (m)")
    _type_into(page, "σ2 distance (m)", "0.25")
    ui.wait_until(lambda: ui.metrics(page) != first)
    assert session.settings.cbm.sigma2 == 0.25
    assert session.last.settings.cbm.sigma2 == 0.25

    for k in range(1, 6):
        _type_into(page, "frame", str(k))
        ui.wait_until(lambda k=k: session.last.frame_index == k)
    ui.wait_until(lambda: ui.header(page).startswith("Frame 5"))

    page.get_by_role("tab", name="View").click()
    ui.pick_option(page, "CAV boxes", "before")
    ui.wait_until(lambda: session.last.settings.view.layout == "before")
    ui.pick_option(page, "CAV boxes", "side by side")
    ui.wait_until(lambda: session.last.settings.view.layout == "side by side")
    assert session.stage.view.labels["before"].visible and session.stage.view.labels["after"].visible

    second = ui.open_page(browser, server)
    other = ui.session(server, 2)
    assert other is not session
    assert other.settings.cbm.sigma2 == 3.0 and other.settings.frame == 0
    second.get_by_role("tab", name="Method").click()
    assert ui.slider(second, "σ2 distance (m)").get_attribute("aria-valuenow") == "3"
    assert ui.header(second).startswith("Frame 0")
    _type_into(second, "σ2 distance (m)", "10")
    ui.wait_until(lambda: other.last.settings.cbm.sigma2 == 10.0)
    assert session.settings.cbm.sigma2 == 0.25 and session.settings.frame == 5
    page.get_by_role("tab", name="Method").click()
    assert sigma2.get_attribute("aria-valuenow") == "0.25"
    second.close()

    page.get_by_role("tab", name="Method").click()
    _type_into(page, "σ2 distance (m)", "3")
    ui.wait_until(lambda: session.last.settings.cbm.sigma2 == 3.0)
    for k in range(6, 16):
        _type_into(page, "frame", str(k))
        ui.wait_until(lambda k=k: session.last.frame_index == k)
    assert len(session.history.rows) >= 10
    ui.close_notifications(page)
    time.sleep(1.0)
    ui.ARTIFACTS.mkdir(exist_ok=True)
    shot = ui.ARTIFACTS / "explorer.png"
    page.screenshot(path=str(shot))
    from PIL import Image

    pixels = np.asarray(Image.open(io.BytesIO(shot.read_bytes())).convert("RGB"), dtype=int)
    scene = pixels[:, : pixels.shape[1] * 2 // 3]
    orange = (scene[..., 0] > 200) & (scene[..., 1] > 100) & (scene[..., 1] < 190) & (scene[..., 2] < 80)
    blue = (scene[..., 2] > 180) & (scene[..., 0] < 140)
    assert orange.sum() > 200 and blue.sum() > 200, "the scene shows ego (blue) and CAV (orange) boxes"
    assert scene.std() > 10, "the screenshot is not blank"
    page.close()


def test_a_failing_recompute_is_notified_and_the_server_lives_on(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    session = ui.session(server, 1)
    frames = len(server.explorer)
    session.explorer = _Broken(server.explorer)
    session.apply(lambda s: s.with_params("cbm", sigma1=12.0))
    page.get_by_text("CBM cannot run on this frame").first.wait_for(timeout=15_000)
    session.explorer = server.explorer
    other = ui.open_page(browser, server)
    assert ui.header(other).startswith("Frame 0") and len(server.explorer) == frames
    other.close()
    page.close()


class _Broken:
    """An explorer whose recompute fails, as a dataset with a bad frame would."""

    def __init__(self, explorer: Explorer) -> None:
        self.inner = explorer

    def compute(self, settings: Settings):
        raise ValueError("this frame cannot be computed")

    def __getattr__(self, name: str):
        return getattr(self.inner, name)


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_serve_prints_the_url_and_serves_the_page(tmp_path: Path) -> None:
    import urllib.request

    port = _free_port()
    process = subprocess.Popen([sys.executable, "serve.py", "--port", str(port), "--dataset", "synthetic"],
                               cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={"CBM_EXPLORER_PRESETS": str(tmp_path), "PATH": "/usr/bin:/bin"})
    watchdog = threading.Timer(60, process.kill)
    watchdog.start()
    try:
        announced = next((line for line in process.stdout if line.startswith("CBM Explorer on")), "")
        assert f"http://127.0.0.1:{port}" in announced
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=10) as response:
            assert response.status == 200
    finally:
        watchdog.cancel()
        process.terminate()
        process.wait(timeout=10)
