"""The clutter condition in a real browser: the shipped ``clutter`` preset sets the Scenario tab's
missed-detection share and false-box rate, and the frame's metrics and key numbers follow; moving
the false-box slider recomputes the frame with the new rate; with the ghosts on, each false box is
crossed out."""
from __future__ import annotations

import pytest

from app.scene.text import number
from app.server import ExplorerServer
from app.session.explorer import Explorer
from evaluation.clutter import is_false
from evaluation.conditions import condition
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

MISSED, FALSE = "missed detections (share)", "false boxes (per detection)"
"""The two sliders' labels in the Scenario tab."""


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def key_numbers(page) -> str:
    return page.locator("#cbm-key-numbers").inner_text()


def test_the_clutter_preset_sets_both_rates_and_the_frame_follows(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    assert "false boxes" not in ui.metrics(page)
    ui.load_preset(page, "clutter")
    ui.wait_until(lambda: tab.last.settings.scenario == condition("clutter"), 120)
    outcome = tab.last
    ego_false, cav_false = int(is_false(outcome.trial.ego_ids).sum()), int(is_false(outcome.trial.cav_ids).sum())
    assert ego_false + cav_false > 0
    m = outcome.metrics
    ui.wait_until(lambda: f"{ego_false} / {cav_false} (they match no object)" in ui.metrics(page), 60)
    table = ui.metrics(page)
    assert f"{m.n_ego} / {m.n_cav}" in table and "20% of each agent's" in table
    ui.wait_until(lambda: f"precision / recall {number(m.precision)} / {number(m.recall)}" in key_numbers(page), 60)
    assert f"RRE / RTE {number(m.rre, '°')} / {number(m.rte, ' m')}" in key_numbers(page)

    page.get_by_role("tab", name="Scenario").click()
    assert ui.slider(page, MISSED).get_attribute("aria-valuenow") == "0.2"
    assert ui.slider(page, FALSE).get_attribute("aria-valuenow") == "0.3"
    ui.slider(page, FALSE).focus()
    page.keyboard.press("ArrowRight")
    ui.wait_until(lambda: tab.last.settings.scenario.false_rate == pytest.approx(0.35), 120)
    moved = tab.last
    counts = f"{int(is_false(moved.trial.ego_ids).sum())} / {int(is_false(moved.trial.cav_ids).sum())}"
    ui.wait_until(lambda: f"{counts} (they match no object)" in ui.metrics(page), 60)

    page.get_by_role("tab", name="View").click()
    ui.label(page, "ground-truth ghosts").click()
    ui.wait_until(lambda: tab.last.settings.view.ghosts and crosses(tab) > 0, 60)
    trial = tab.last.trial
    assert crosses(tab) == int(is_false(trial.ego_ids).sum() + is_false(trial.cav_ids).sum())
    page.close()


def crosses(tab) -> int:
    """How many false boxes the scene crosses out (2 segments each; 0 when hidden)."""
    handle = tab.stage.view.lines.get("false_marks")
    return 0 if handle is None or not handle.visible else len(handle.points) // 2
