"""A detector's score threshold in a real browser: on an OPV2V scenario with a CoAlign
stage1_boxes.json that carries scores, moving the Scenario tab's score slider drops the low-scored
boxes and the frame's object counts follow; without scores the slider is disabled and says why."""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

import loaders
from app.server import ExplorerServer
from app.session.explorer import Explorer
from app.session.offers import offers_of
from support import browser as ui

FIXTURES = Path(__file__).resolve().parents[1] / "loaders" / "fixtures"
SCORE = "detector score at least"
"""The slider's label in the Scenario tab."""


@pytest.fixture(scope="module")
def scored(tmp_path_factory: pytest.TempPathFactory) -> Explorer:
    """The OPV2V scenario fixture with its stage1 boxes, each agent's second box scored 0.03 / 0.02."""
    samples = json.loads((FIXTURES / "stage1" / "stage1_boxes.json").read_text())
    samples["13"]["pred_score_np_list"] = [[0.9, 0.03], [0.6, 0.02]]
    path = tmp_path_factory.mktemp("stage1") / "stage1_boxes.json"
    path.write_text(json.dumps(samples))
    return Explorer(loaders.open(FIXTURES / "opv2v" / "scenario", detections=path))


def test_without_scores_the_threshold_is_not_offered() -> None:
    plain = loaders.open(FIXTURES / "opv2v" / "scenario", detections=FIXTURES / "stage1" / "stage1_boxes.json")
    assert "--detections" in offers_of(plain).scores
    assert offers_of(loaders.open("synthetic:10")).scores is not None


@pytest.fixture(scope="module")
def server(scored: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(scored, tmp_path_factory.mktemp("presets"), protocol="opv2v") as running:
        yield running


@pytest.mark.browser
@ui.requires_chromium
def test_moving_the_score_slider_drops_the_low_scored_boxes(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.wait_until(lambda: tab.last is not None and tab.last.frame_index == 0, 60)
    before = len(tab.last.trial.ego_boxes)
    counts = (tab.last.metrics.n_ego, tab.last.metrics.n_cav)
    ui.wait_until(lambda: shown_counts(page) == counts, 60)
    page.get_by_role("tab", name="Scenario").click()
    slider = ui.slider(page, SCORE)
    assert slider.get_attribute("aria-valuenow") == "0" and slider.get_attribute("aria-disabled") != "true"
    slider.focus()
    page.keyboard.press("ArrowRight")
    ui.wait_until(lambda: tab.last.settings.scenario.min_score == pytest.approx(0.05), 120)
    assert len(tab.last.trial.ego_boxes) == before - 1          # the ego's 0.03 box is dropped
    m = tab.last.metrics
    ui.wait_until(lambda: shown_counts(page) == (m.n_ego, m.n_cav), 60)
    assert m.n_ego == counts[0] - 1
    page.close()


def shown_counts(page) -> tuple[int, int] | None:
    """The metrics table's ``objects (ego / CAV)`` row, as the page shows it."""
    found = re.search(r"objects \(ego / CAV\)\s+(\d+) / (\d+)", ui.metrics(page))
    return None if found is None else (int(found[1]), int(found[2]))
