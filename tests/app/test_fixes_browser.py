"""Real-browser tests of issue 13's fixes at 1280x720: key numbers that never scroll away, a camera
that frames the layouts on the canvas left of the docked control panel (also at two pixels per CSS
pixel), an inspector beside the scene that is never blank,
inactive controls disabled with the reason, and a screenshot that can include the panel."""
from __future__ import annotations

import io
import math

import numpy as np
import pytest
from PIL import Image

import loaders
from app.scene.layouts import PANEL_PX
from app.server import ExplorerServer
from app.session.explorer import Explorer
from app.session.export import PANEL_WIDTH
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]
WIDTH, HEIGHT = 1280, 720


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def open_small_page(browser, server: ExplorerServer, pixel_ratio: int = 1):
    page = browser.new_page(viewport={"width": WIDTH, "height": HEIGHT}, device_scale_factor=pixel_ratio)
    page.goto(ui.address(server, pixel_ratio))
    page.get_by_text("precision / recall").first.wait_for(timeout=60_000)
    return page


def inside_viewport(box: dict | None) -> bool:
    return box is not None and box["y"] >= 0 and box["y"] + box["height"] <= HEIGHT and box["x"] >= 0


def across(camera, point: tuple[float, float, float]) -> float:
    """Where ``point`` shows across the scene's canvas through a viser camera (+z up): 0 at its left
    edge, 1 at its right."""
    position, look_at = np.asarray(camera.position), np.asarray(camera.look_at)
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    offset = np.asarray(point) - position
    ndc = (offset @ right) / ((offset @ forward) * math.tan(camera.fov / 2) * camera.aspect)
    return (ndc + 1.0) / 2.0


def test_key_numbers_stay_in_view_while_a_deep_method_control_is_edited(browser, server: ExplorerServer) -> None:
    page = open_small_page(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Method").click()
    gate = ui.label(page, "refine gate (σ)")
    gate.scroll_into_view_if_needed()
    row = gate.locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    box = row.locator("input.mantine-NumberInput-input")
    box.fill("5")
    box.blur()
    ui.wait_until(lambda: tab.last.settings.cbm.refine_gate == 5.0, timeout=30)
    assert not inside_viewport(page.locator("td", has_text="precision / recall").first.bounding_box()), \
        "the panel's own metrics scrolled away (else this test proves nothing)"
    pinned = page.locator("#cbm-key-numbers")
    assert inside_viewport(pinned.bounding_box())
    assert "precision / recall" in pinned.inner_text() and f"Frame {tab.last.frame_index}" in pinned.inner_text()
    assert beside_the_panel(page, pinned)
    assert pinned.bounding_box()["y"] < 100, "the key numbers sit at the top, beside the panel's top"
    seam = ui.scene_canvas(page)["width"]
    page.mouse.move(seam + 2, HEIGHT / 2)
    page.mouse.down()
    page.mouse.move(seam - 180, HEIGHT / 2, steps=10)
    page.mouse.up()
    ui.wait_until(lambda: ui.scene_canvas(page)["width"] < seam - 100)
    ui.wait_until(lambda: beside_the_panel(page, pinned))
    page.close()


def beside_the_panel(page, pinned) -> bool:
    """Whether the key numbers lie whole on the canvas, within 40 px of its right edge (the control
    panel's left)."""
    box, canvas = pinned.bounding_box(), ui.scene_canvas(page)
    right = canvas["x"] + canvas["width"]
    return box is not None and canvas["x"] < box["x"] and right - 40 < box["x"] + box["width"] < right


@pytest.mark.parametrize("pixel_ratio", [1, 2])
def test_side_by_side_keeps_both_copies_left_of_the_panel(browser, server: ExplorerServer, pixel_ratio: int) -> None:
    """Also on a screen of two pixels per CSS pixel (most laptops'), whose camera reports twice the
    page's pixels: the canvas stops at the docked panel, and both copies show on it."""
    page = open_small_page(browser, server, pixel_ratio)
    tab = ui.session(server, 1)
    ui.wait_until(lambda: tab.client.camera.update_timestamp > 0)
    page.get_by_role("tab", name="View").click()
    ui.pick_option(page, "CAV boxes", "side by side")
    ui.wait_until(lambda: tab.last.settings.view.layout == "side by side")
    canvas, panel_left = ui.scene_canvas(page), ui.label(page, "CAV boxes").bounding_box()["x"]
    assert canvas["x"] == 0 and canvas["x"] + canvas["width"] <= panel_left
    camera = tab.client.camera
    ui.wait_until(lambda: camera.image_width == round(pixel_ratio * canvas["width"]))
    after = across(camera, tab.stage.view.labels["after"].position)
    before = across(camera, tab.stage.view.labels["before"].position)
    assert 0.05 < before < 0.5 < after < 0.95, (before, after)
    page.get_by_role("button", name="reset camera").click()
    assert 0.05 < across(tab.client.camera, tab.stage.view.labels["after"].position) < 0.95
    page.close()


def purple_pixels(page) -> int:
    """Purple pixels (the inspector's sigma2 diamonds; the scene has none) of the page left of the
    control panel."""
    shot = np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB")).astype(int)
    r, g, b = np.moveaxis(shot[:, : WIDTH - PANEL_PX], -1, 0)
    return int(((r - g > 40) & (b - g > 40)).sum())


def test_the_inspector_sits_beside_the_scene_and_is_never_blank(browser, server: ExplorerServer) -> None:
    page = open_small_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="inspect the winning anchor").click()
    ui.wait_until(lambda: tab.controls.explore.shown is not None)
    shown = tab.controls.explore.shown
    ui.wait_until(lambda: purple_pixels(page) > 500, timeout=30)
    ui.wait_until(lambda: abs(tab.client.camera.look_at[1] - shown.centre[1]) < shown.span, timeout=30)
    scene_left = max(float(boxes[:, 1].max()) for boxes, _ in tab.last_drawing.objects.values() if len(boxes))
    assert shown.centre[1] > scene_left, "the panels are drawn left of the scene, away from the control panel"
    for attempt in range(4):
        tab.reset_camera()
        ui.wait_until(lambda: purple_pixels(page) < 100, timeout=30)
        page.get_by_role("button", name="look at the context panels").click()
        ui.wait_until(lambda: abs(tab.client.camera.look_at[1] - shown.centre[1]) < shown.span, timeout=30)
        ui.wait_until(lambda: purple_pixels(page) > 500, timeout=30)
        assert 0.25 < across(tab.client.camera, (*shown.centre, 0.0)) < 0.75, attempt
    ego_id = str(tab.last.trial.ego_ids[int(tab.last.result.anchor[0])])[:8]
    labels = tab.controls.explore.inspector_view.labels
    assert labels["inspector_ego"].text == f"EGO {ego_id}: context in its own frame"
    assert labels["inspector_legend"].visible and labels["inspector_legend"].text.startswith("legend: blue = ")
    assert any(name.startswith("inspector_ego_tip") and label.visible for name, label in labels.items())
    page.screenshot(path=str(ui.ARTIFACTS / "inspector-1280x720.png"))
    page.close()


def test_reset_camera_moves_the_browser_even_when_the_servers_copy_of_the_camera_lags(
        browser, server: ExplorerServer) -> None:
    """The browser reports its camera a little after each move, so the server's copy can still say
    the camera is where reset puts it while the browser shows the inspector's panels (a report sent
    just before the look-at move arrived). Reset camera must move the browser all the same."""
    page = open_small_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    ui.wait_until(lambda: purple_pixels(page) < 100, timeout=30)
    camera = tab.client.camera
    where_reset_puts_it = (camera.position.copy(), camera.look_at.copy())
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="inspect the winning anchor").click()
    ui.wait_until(lambda: purple_pixels(page) > 500, timeout=30)
    camera._state.position, camera._state.look_at = where_reset_puts_it
    page.get_by_role("tab", name="View").click()
    page.get_by_role("button", name="reset camera").click()
    ui.wait_until(lambda: purple_pixels(page) < 100, timeout=30)
    page.close()


def disabled(page, label: str) -> bool:
    return ui.slider(page, label).get_attribute("data-disabled") == "true" or \
        ui.slider(page, label).get_attribute("aria-disabled") == "true"


def test_controls_that_do_nothing_are_disabled_with_the_reason(browser, server: ExplorerServer) -> None:
    page = open_small_page(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Scenario").click()
    ui.wait_until(lambda: disabled(page, "co-visibility eta"))
    page.get_by_text("no effect under the range protocol").first.wait_for(timeout=10_000)
    ui.pick_option(page, "protocol", "sind")
    ui.wait_until(lambda: not disabled(page, "co-visibility eta") and disabled(page, "sensor range (m)"))

    page.get_by_role("tab", name="Method").click()
    assert not disabled(page, "σ3 voting (m)")
    ui.label(page, "consensus").click()
    ui.wait_until(lambda: not tab.settings.cbm.consensus and disabled(page, "σ3 voting (m)"))
    page.get_by_text("consensus is off").first.wait_for(timeout=10_000)
    ui.pick_option(page, "method", "ICP")
    ui.wait_until(lambda: disabled(page, "σ1 angle (°)"))
    page.get_by_text("ICP selected: CBM's parameters do not apply").first.wait_for(timeout=10_000)
    page.close()


def test_the_screenshot_can_include_the_control_panel(browser, server: ExplorerServer) -> None:
    page = open_small_page(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Explore").click()
    ui.label(page, "include the control panel").click()
    ui.wait_until(lambda: tab.controls.explore.with_panel.value)
    with page.expect_download(timeout=30_000) as download:
        page.get_by_role("button", name="screenshot of the view (PNG)").click()
    image = np.asarray(Image.open(download.value.path()).convert("RGB"))
    camera = tab.client.camera
    assert image.shape[1] == camera.image_width + PANEL_WIDTH
    panel = image[:, camera.image_width + 4:]
    assert (panel.sum(axis=-1) < 200).sum() > 500, "the panel's text is drawn"
    scene = image[:, : camera.image_width].astype(int)
    assert np.median(scene) > 200, "the light theme's scene is light, not black (the render's transparent background)"
    assert (np.abs(scene - (52, 120, 246)).sum(axis=-1) < 90).sum() > 50, "the ego's blue boxes are in it"
    page.close()


def pedestrians_only(folder) -> Explorer:
    """A table of 3 frames of 6 pedestrians and nothing else."""
    rows = ["frame,track_id,category,x,y,length,width,yaw"]
    rows += [f"{frame},p{k},pedestrian,{3.0 * k + frame},{2.0 * (k % 3)},0.6,0.6,0.0"
             for frame in range(3) for k in range(6)]
    path = folder / "pedestrians.csv"
    path.write_text("\n".join(rows) + "\n")
    return Explorer(loaders.open(path))


def test_a_dataset_without_vehicles_says_what_is_missing(browser, tmp_path) -> None:
    with ui.scenario_server(pedestrians_only(tmp_path), tmp_path / "presets") as running:
        page = browser.new_page(viewport={"width": WIDTH, "height": HEIGHT})
        page.goto(ui.address(running))
        page.get_by_text("CBM cannot run on this frame.").first.wait_for(timeout=60_000)
        text = page.get_by_text("What is missing").first.inner_text()
        assert "0 vehicle(s) among its 6 objects (pedestrian)" in text
        assert "sind" in page.get_by_text("What to try").first.inner_text()
        assert page.get_by_text("Computing the first frame…").count() == 0
        assert "CBM cannot run" in page.locator("#cbm-key-numbers").inner_text()
        page.close()
