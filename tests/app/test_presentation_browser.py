"""Real-browser test of presentation mode and the dark theme: tick them in the View tab and check
the palette, the labels, the caption of key numbers (with the frame number, in the page's corner
rather than in the scene, and whole when the control panel opens), the camera, the minimised panel and the page's colour
scheme (in this tab only).

With ``CBM_UPDATE_DOCS_IMG=1`` the test also saves the presentation as docs/img/presentation.png
(1280x720, dark theme)."""
from __future__ import annotations

import dataclasses
import io
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from app.scene import colours
from app.scene.view import VISER_LABEL_PX
from app.server import ExplorerServer
from app.session.explorer import Explorer
from evaluation.metrics import is_success
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]
DOCS_IMAGE = Path(__file__).resolve().parents[2] / "docs" / "img" / "presentation.png"
FRAME = 120
"""A frame where CBM, with the thresholds below, finds right and wrong pairs and misses a few."""


@pytest.fixture(scope="module")
def server(explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets"), sigma_p=0.5, sigma_theta=5.0) as running:
        yield running


def _page(browser, server: ExplorerServer):
    page = browser.new_page(viewport={"width": 1280, "height": 720})
    page.goto(ui.address(server))
    page.get_by_text("precision / recall").first.wait_for(timeout=60_000)
    return page


def _scheme(page) -> str:
    return page.evaluate("document.documentElement.getAttribute('data-mantine-color-scheme')")


def _colour(handle) -> tuple[int, ...]:
    return tuple(int(c) for c in np.asarray(handle.colors)[0, 0])


def test_presentation_mode_and_dark_theme(browser, server: ExplorerServer) -> None:
    other = _page(browser, server)
    other_tab = ui.session(server, 1)
    page = _page(browser, server)
    tab = ui.session(server, 2)
    tab.apply(lambda s: dataclasses.replace(s, frame=FRAME).with_params("cbm", sigma1=2.0, sigma2=0.5, sigma3=0.5),
              move_controls=True)
    ui.wait_until(lambda: tab.last.frame_index == FRAME and tab.last.settings.cbm.sigma2 == 0.5, timeout=60)
    m = tab.last.metrics
    assert 0 < m.n_correct < m.n_matched < m.n_true + 2, "the frame shows right and wrong pairs"
    before = tuple(tab.client.camera.position)
    page.get_by_role("tab", name="View").click()
    assert _colour(tab.stage.view.lines["right"]) == colours.RIGHT
    assert tab.stage.view.labels["ego_after"].font_screen_scale * VISER_LABEL_PX == 14

    ui.label(page, "dark theme").click()
    ui.wait_until(lambda: _scheme(page) == "dark", timeout=30)
    assert tab.last.settings.view.dark and _scheme(other) == "light"

    ui.label(page, "presentation mode").click()
    ui.wait_until(lambda: tab.last.settings.view.presentation, timeout=60)
    okabe = colours.OKABE_ITO
    assert _colour(tab.stage.view.lines["right"]) == okabe.right.color
    wrong = tab.stage.view.lines["wrong"]
    assert _colour(wrong) == okabe.wrong.color and wrong.thickness == 6.0
    assert _colour(tab.stage.view.lines["missed"]) == okabe.missed.color
    caption = page.locator("#cbm-caption")
    caption.wait_for(timeout=20_000)
    margin = tab.last.result.evidence_margin
    assert caption.inner_text().splitlines() == [f"Frame {FRAME} · {'success' if is_success(m) else 'failed'}",
                                                 f"precision {m.precision:.2f} · recall {m.recall:.2f}",
                                                 f"RTE {m.rte:.2f} m · RRE {m.rre:.2f}°",
                                                 f"CBM is sure · evidence margin {margin:.1f}, sure from 8"]
    assert ui.in_first_screen(caption)
    page.locator("#cbm-key-numbers").wait_for(state="hidden", timeout=20_000)
    labels = tab.stage.view.labels.values()
    assert all(label.font_screen_scale * VISER_LABEL_PX >= 18 for label in labels if label.visible)
    agents = np.array(tab.last_drawing.agents)
    middle = (agents.min(axis=0) + agents.max(axis=0)) / 2
    ui.wait_until(lambda: tuple(tab.client.camera.position) != before)
    assert np.allclose(tab.client.camera.look_at[:2], middle, atol=0.5)
    expand = page.get_by_role("button", name="Expand column")
    expand.wait_for(timeout=20_000)
    ui.label(page, "presentation mode").wait_for(state="hidden", timeout=20_000)
    assert _scheme(other) == "light" and other.locator("#cbm-caption").count() == 0
    assert _colour(other_tab.stage.view.lines["right"]) == colours.RIGHT

    ui.close_notifications(page)
    shot = ui.settled_screenshot(page)
    pixels = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB"), dtype=int)
    assert np.median(pixels) < 60, "the dark theme's scene"
    if os.environ.get("CBM_UPDATE_DOCS_IMG"):
        DOCS_IMAGE.write_bytes(shot)

    expand.click()
    page.get_by_text("Okabe-Ito").first.wait_for(timeout=20_000)
    panel = ui.label(page, "presentation mode").locator("xpath=ancestor::*[contains(@class, 'mantine-Paper-root')][1]")
    ui.wait_until(lambda: panel.bounding_box() is not None and panel.bounding_box()["height"] > 300)
    assert ui.in_first_screen(caption) and not overlaps(caption.bounding_box(), panel.bounding_box())
    assert caption.inner_text().startswith(f"Frame {FRAME}")
    tab.client.camera.look_at = (50.0, 50.0, 0.0)
    page.get_by_role("button", name="reset camera").click()
    ui.wait_until(lambda: np.allclose(tab.client.camera.look_at[:2], middle, atol=0.5))
    ui.label(page, "presentation mode").click()
    ui.wait_until(lambda: not tab.last.settings.view.presentation, timeout=60)
    page.get_by_text("green right pair").first.wait_for(timeout=20_000)
    assert _colour(tab.stage.view.lines["right"]) == colours.RIGHT
    caption.wait_for(state="hidden", timeout=20_000)
    page.locator("#cbm-key-numbers").wait_for(timeout=20_000)
    page.close()
    other.close()


def overlaps(a: dict, b: dict) -> bool:
    return a["x"] < b["x"] + b["width"] and b["x"] < a["x"] + a["width"] and a["y"] < b["y"] + b["height"] \
        and b["y"] < a["y"] + a["height"]

