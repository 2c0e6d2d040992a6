"""The View tab's "LiDAR points" toggle and its subsampling slider (greyed out, with the reason, while
the points are off), in a real browser, on an OPV2V fixture that ships one ASCII and one binary .pcd
sweep (40 points each)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import loaders
from app.session.explorer import Explorer
from support import browser as ui

FIXTURE = Path(__file__).resolve().parents[1] / "loaders" / "fixtures" / "opv2v_points" / "scenario"

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory):
    explorer = Explorer(loaders.open(FIXTURE))
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def _cloud(session, name: str):
    return session.stage.view.clouds.get(name)


def _shown(session, name: str) -> int:
    """How many points the node ``name`` shows (0 when hidden or absent)."""
    handle = _cloud(session, name)
    return 0 if handle is None or not handle.visible else len(handle.points)


def _type_into(page, text: str, value: str) -> None:
    row = ui.label(page, text).locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    box = row.locator("input.mantine-NumberInput-input")
    box.fill(value)
    box.blur()


def every_nth_disabled(page) -> bool:
    """Whether "points: every Nth" shows greyed out."""
    return ui.slider(page, "points: every Nth").get_attribute("data-disabled") == "true"


def test_points_toggle_and_subsampling(browser, server) -> None:
    page = ui.open_page(browser, server)
    session = ui.session(server, 1)
    assert _shown(session, "ego_points") == 0 and _shown(session, "cav_points") == 0

    page.get_by_role("tab", name="View").click()
    ui.wait_until(lambda: every_nth_disabled(page))
    note = page.get_by_text("Disabled (LiDAR points are off: tick LiDAR points to draw them): points: every Nth.")
    note.first.wait_for(timeout=20_000)
    ui.label(page, "LiDAR points").click()
    ui.wait_until(lambda: _shown(session, "ego_points") == 4 and _shown(session, "cav_points") == 4, timeout=60)
    ui.wait_until(lambda: not every_nth_disabled(page))
    note.first.wait_for(state="hidden", timeout=20_000)
    assert {"/scene/ego_points", "/scene/cav_points"} <= session.stage.view.node_names
    ego = np.asarray(_cloud(session, "ego_points").points, dtype=float)
    # the ego's first point: (6, 0, -1.5) in its left-handed LiDAR frame, lifted by the 1.9 m sensor height
    np.testing.assert_allclose(ego[0], [6.0, 0.0, 0.4], atol=1e-3)

    _type_into(page, "points: every Nth", "1")
    ui.wait_until(lambda: _shown(session, "ego_points") == 40 and _shown(session, "cav_points") == 40, timeout=60)

    ui.label(page, "LiDAR points").click()
    ui.wait_until(lambda: not session.last.settings.view.points and _shown(session, "ego_points") == 0
                  and _shown(session, "cav_points") == 0, timeout=60)
