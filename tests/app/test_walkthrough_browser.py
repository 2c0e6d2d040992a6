"""Real-browser test of the Walkthrough tab: start, next through the nine steps, prev, the
animation, a frame change while it is open, and leaving it.

With ``CBM_UPDATE_DOCS_IMG=1`` the test also saves the local matching step as docs/img/walkthrough.png
(1280x720)."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from app.scene.layouts import screen_of
from app.server import ExplorerServer
from app.session.explorer import Explorer
from app.walkthrough import steps
from app.walkthrough.nodes import CAV_NODE, ROOT
from app.walkthrough.panel import IDLE_TITLE, camera_over
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]
DOCS_IMAGE = Path(__file__).resolve().parents[2] / "docs" / "img" / "walkthrough.png"
AGENTS = {f"{ROOT}/ego_vehicle", f"{ROOT}/cav_vehicle", f"{ROOT}/labels/ego_agent", f"{ROOT}/labels/cav_agent"}
"""The ego and the CAV, drawn and labelled in every step (issue 39)."""


@pytest.fixture(scope="module")
def small_server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind", eta=0.4,
                            sigma_p=0.5, sigma_theta=6.0, seed=2) as running:
        yield running


def _title(page, k: int) -> None:
    page.get_by_text(steps.title(k), exact=True).wait_for(timeout=20_000)


def test_walk_through_every_step_animate_follow_a_frame_and_leave(browser, small_server: ExplorerServer) -> None:
    page = ui.open_page(browser, small_server)
    tab = ui.session(small_server, 1)
    walk = tab.controls.walkthrough
    page.get_by_role("tab", name="Steps").click()
    ui.wait_until(lambda: tab.client.camera.update_timestamp > 0)
    before = tuple(tab.client.camera.look_at)
    page.get_by_role("button", name="start walkthrough").click()
    _title(page, 0)
    ui.wait_until(lambda: f"{ROOT}/ego_boxes" in walk.nodes.visible_names)
    ui.wait_until(lambda: AGENTS <= walk.nodes.visible_names)
    assert all(not frame.visible for frame in walk.nodes._normal)
    page.get_by_text("Play the animation").first.wait_for(timeout=10_000)

    for k in range(1, 9):
        page.get_by_role("button", name="next step ▶").click()
        _title(page, k)
        ui.wait_until(lambda k=k: walk.step is not None and walk.step.key == steps.NAMES[k][0])
        ui.wait_until(lambda: AGENTS <= walk.nodes.visible_names)
        if k == 2:
            ui.wait_until(lambda: looks_at_the_object(tab), 20)
    ui.wait_until(lambda: f"{ROOT}/truth" in walk.nodes.visible_names)
    assert page.get_by_text("pairs matched").first.is_visible()

    for k in (7, 6):
        page.get_by_role("button", name="◀ prev step").click()
        _title(page, k)
    ui.wait_until(lambda: f"{ROOT}/weights_1" in walk.nodes.visible_names)

    cav = walk.nodes.meshes[CAV_NODE]
    page.get_by_role("button", name="play animation").click()
    end = walk.step.motion[1]
    ui.wait_until(lambda: np.allclose(cav.position[:2], end[:2, 2], atol=1e-4), timeout=20)
    label = walk.nodes.view.labels["cav_agent"]
    assert np.allclose(walk.nodes.meshes["cav_vehicle"].position, cav.position, atol=1e-4)
    assert np.allclose(label.position[:2], end[:2, 2], atol=1e-4), "the CAV's label moves with it"

    for k in (5, 4, 3, 2):
        page.get_by_role("button", name="◀ prev step").click()
        _title(page, k)
    ui.wait_until(lambda: f"{ROOT}/diamond" in walk.nodes.visible_names)
    frame = tab.last.frame_index
    tab.step(1)
    ui.wait_until(lambda: tab.last.frame_index != frame and walk._facts is not None
                  and walk._facts.outcome is tab.last and walk.step.key == "local")
    _title(page, 2)
    page.get_by_role("button", name="look at the object").click()
    ui.wait_until(lambda: looks_at_the_object(tab), 20)
    if os.environ.get("CBM_UPDATE_DOCS_IMG") == "1":
        _save_screenshot(page)

    page.get_by_role("button", name="leave walkthrough").click()
    page.get_by_role("button", name="start walkthrough").wait_for(timeout=10_000)
    ui.wait_until(lambda: not walk.active and not walk.nodes.visible_names)
    assert all(frame.visible for frame in walk.nodes._normal)
    ui.wait_until(lambda: np.allclose(tab.client.camera.look_at, before, atol=0.5), 20)
    assert walk.title.content == IDLE_TITLE
    page.close()


def looks_at_the_object(tab) -> bool:
    """Whether the camera looks down on the walkthrough's followed object as "look at the object" puts it."""
    step, camera = tab.controls.walkthrough.step, tab.client.camera
    _, look_at = camera_over(step.focus, step.span, screen_of(camera))
    return np.allclose(camera.look_at[:2], look_at[:2], atol=0.5)


def _save_screenshot(page) -> None:
    """The local matching step at 1280x720, the step's text in view, notifications closed."""
    page.set_viewport_size({"width": 1280, "height": 720})
    ui.close_notifications(page)
    page.get_by_role("button", name="leave walkthrough").scroll_into_view_if_needed()
    DOCS_IMAGE.write_bytes(ui.settled_screenshot(page))
