"""Line of sight and late messages in a real browser: the Scenario tab's "line of sight" checkbox and
the View tab's "agents' sight" draw each agent's sight (a translucent fan in its colour, the shadows
its holes) from the outcome's own outlines; a message delay typed into the Scenario tab shows how far
the objects moved while the message travelled, in the metrics and as a label in the scene."""
from __future__ import annotations

import numpy as np
import pytest

from app.scene.colours import palette
from app.server import ExplorerServer
from app.session.explorer import Explorer
from cbm import se2
from evaluation.sight import OUTLINE_RAYS
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

SIGHT, DRAW_SIGHT, DELAY = "line of sight", "agents' sight", "message delay (ms)"
"""The controls' labels: the Scenario tab's checkbox and slider, the View tab's checkbox."""


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="range", sensor_range=50.0,
                            sigma_p=0.0, sigma_theta=0.0, seed=0) as running:
        yield running


def fan(tab, role: str) -> np.ndarray | None:
    """The vertices of the sight fan node of ``role`` as the browser was sent them (None: hidden)."""
    handle = tab.stage.view.meshes.get(f"{role}_sight")
    return None if handle is None or not handle.visible else np.asarray(handle.vertices)


def type_value(page, text: str, value: float) -> None:
    """Type ``value`` into the number box of the slider labelled ``text``."""
    row = ui.label(page, text).locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    box = row.locator("input.mantine-NumberInput-input")
    box.fill(f"{value:g}")
    box.press("Enter")


def test_line_of_sight_and_its_drawing_then_a_delay_shows_how_far_objects_moved(browser,
                                                                                  server: ExplorerServer) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    page.get_by_role("tab", name="Scenario").click()
    ui.label(page, SIGHT).click()
    ui.wait_until(lambda: tab.last.settings.scenario.sight and tab.last.trial is not None, 120)
    assert fan(tab, "cav") is None, "the sight is drawn only when the View tab asks"

    page.get_by_role("tab", name="View").click()
    ui.label(page, DRAW_SIGHT).click()
    ui.wait_until(lambda: tab.last.settings.view.sight and fan(tab, "cav") is not None, 120)
    outcome = tab.last
    sights = outcome.sights()
    colours = palette(outcome.settings.view)
    for role, colour in (("ego", colours.ego_boxes), ("cav", colours.cav_boxes)):
        handle = tab.stage.view.meshes[f"{role}_sight"]
        assert len(handle.faces) == OUTLINE_RAYS and tuple(handle.color) == colour and handle.opacity < 0.5
        assert tab.stage.view.lines[f"{role}_sight_edge"].visible
    placed = se2.apply_points(outcome.placements["after"], sights["cav"].outline)
    assert np.allclose(fan(tab, "cav")[1:, :2], placed, atol=1e-3), "the CAV's sight, placed as its boxes are"
    assert sights["cav"].shadows, "line of sight on: the boxes cast shadows"
    assert np.ptp(np.linalg.norm(sights["cav"].outline, axis=1)) > 1.0, "some rays stop at a box"
    ui.ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ui.ARTIFACTS / "sight-1280x720.png"))

    ui.go_to_frame(page, tab, 10)
    page.get_by_role("tab", name="Scenario").click()
    type_value(page, DELAY, 300)
    ui.wait_until(lambda: tab.last.settings.scenario.delay_ms == 300.0, 120)
    late = tab.last.late()
    assert late is not None and late.moving.any()
    words = f"moved {late.moved.max():.1f} m while the message travelled"
    ui.wait_until(lambda: "message age\t300 ms" in ui.metrics(page), 60)
    assert "moved while the message travelled" in ui.metrics(page)
    ui.wait_until(lambda: tab.stage.view.labels.get("moved_after") is not None
                  and tab.stage.view.labels["moved_after"].visible, 60)
    assert tab.stage.view.labels["moved_after"].text == words
    page.close()
