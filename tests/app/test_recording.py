"""The shareable recording: the per-frame records a tab keeps, and the self-contained page made of them."""
from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest

from app.scene import colours
from app.scene.cavs import SLIM
from app.scene.drawing import draw
from app.scene.recording_html import DATA_ID, recording_html
from app.session.explorer import Explorer, Outcome, classified_pairs
from app.session.recording import Recording, record_of, top_down
from app.session.settings import Settings, ViewOptions
from cbm import se2


@pytest.fixture(scope="module")
def outcomes(small_explorer: Explorer) -> list[Outcome]:
    return [small_explorer.compute(Settings(frame=f)) for f in range(3)]


def page_data(page: bytes) -> dict:
    text = page.decode("utf-8")
    found = re.search(f'<script type="application/json" id="{DATA_ID}">(.*?)</script>', text, re.S)
    return json.loads(found.group(1).replace("<\\/", "</"))


def test_pairs_are_told_apart_against_the_truth() -> None:
    right, wrong, missed = classified_pairs(np.array([[0, 0], [1, 2], [3, 3]]), np.array([[0, 0], [1, 1], [3, 3]]))
    assert right.tolist() == [[0, 0], [3, 3]] and wrong.tolist() == [[1, 2]] and missed.tolist() == [[1, 1]]
    assert all(a.shape == (0, 2) for a in classified_pairs(np.zeros((0, 2)), np.zeros((0, 2))))


def test_top_down_keeps_centre_size_and_yaw() -> None:
    boxes = np.array([[1.0, 2.0, 0.5, 4.0, 1.8, 1.5, 0.3]])
    assert top_down(boxes).tolist() == [[1.0, 2.0, 4.0, 1.8, 0.3]]


def test_a_record_holds_the_frame_geometry_and_metrics(outcomes: list[Outcome]) -> None:
    outcome = outcomes[1]
    record, trial = record_of(outcome), outcome.trial
    assert record.frame == 1 and record.ego.shape == (len(trial.ego_boxes), 5)
    assert np.allclose(record.cav_before, top_down(se2.apply_boxes(trial.init, trial.cav_boxes)))
    assert np.allclose(record.cav_after, top_down(se2.apply_boxes(outcome.result.transform, trial.cav_boxes)))
    assert len(record.right) == outcome.metrics.n_correct
    assert len(record.right) + len(record.wrong) == outcome.metrics.n_matched
    assert len(record.right) + len(record.missed) == outcome.metrics.n_true
    assert record.metrics["rte"] == pytest.approx(outcome.metrics.rte) and record.metrics["rte_before"] > 1.0


def test_the_recording_is_bounded_and_follows_the_settings(outcomes: list[Outcome], small_explorer: Explorer) -> None:
    recording = Recording(limit=2)
    for outcome in outcomes:
        recording.add(outcome)
    assert [r.frame for r in recording.frames()] == [1, 2]
    recording.add(dataclasses.replace(outcomes[1], settings=outcomes[1].settings.with_view(layout="after")))
    assert [r.frame for r in recording.frames()] == [1, 2] and recording.settings.view.layout == "after"
    other = small_explorer.compute(Settings(frame=0).with_params("cbm", sigma1=20.0))
    recording.add(other)
    assert [r.frame for r in recording.frames()] == [0] and recording.settings.cbm.sigma1 == 20.0


def test_the_page_holds_the_frames_as_json_and_nothing_from_the_network(outcomes: list[Outcome]) -> None:
    recording = Recording()
    for outcome in outcomes:
        recording.add(outcome)
    page = recording_html(recording, "synthetic </script> <b>", presentation=False)
    text = page.decode("utf-8")
    assert not re.search(r"""(src|href)\s*=\s*["']?\s*https?://""", text, re.I)
    assert "<link" not in text and not re.search(r"<script[^>]*\ssrc=", text) and "@import" not in text
    data = page_data(page)
    assert [f["frame"] for f in data["frames"]] == [0, 1, 2] and data["dataset"] == "synthetic </script> <b>"
    assert data["app"] == "CBM Explorer" and data["version"]
    assert data["settings"][0] == "Method: CBM" and "σ1 angle (°) 10.0" in data["settings"][1]
    first = data["frames"][0]
    assert len(first["ego"]) == outcomes[0].metrics.n_ego and len(first["right"]) == outcomes[0].metrics.n_correct
    assert ["co-visible", str(outcomes[0].metrics.n_true)] in first["table"]
    assert data["palette"]["right"]["color"] == list(colours.STANDARD.right.color)
    assert "outlined red" in data["legend"] and "labelled" not in data["legend"], "the page draws no pair labels"


def test_presentation_mode_uses_the_colour_blind_safe_palette(outcomes: list[Outcome]) -> None:
    recording = Recording()
    recording.add(dataclasses.replace(outcomes[0], settings=outcomes[0].settings.with_view(dark=True)))
    data = page_data(recording_html(recording, "synthetic", presentation=True))
    assert data["palette"]["wrong"]["color"] == list(colours.OKABE_ITO.wrong.color)
    assert data["palette"]["wrong"]["dash"] == colours.OKABE_ITO.wrong.dash
    assert data["palette"]["before"] == list(colours.palette(ViewOptions(presentation=True)).cav_before)


def test_an_empty_recording_makes_no_page() -> None:
    with pytest.raises(ValueError):
        recording_html(Recording(), "synthetic")


def test_the_page_draws_the_apps_footprints_and_a_right_pair_at_rte_0_on_one_centre(small_explorer: Explorer) -> None:
    """Without noise the oracle's estimate is the true pose (RTE 0): the page's data puts the CAV's
    footprint of each right pair on its ego footprint's centre, narrowed as the app narrows it, and
    every footprint at the corners of the tile the app draws."""
    settings = Settings()
    settings = dataclasses.replace(settings, method="oracle", scenario=dataclasses.replace(
        settings.scenario, sigma_p=0.0, sigma_theta=0.0, flip_prob=0.0))
    outcome = small_explorer.compute(settings)
    recording = Recording()
    recording.add(outcome)
    frame = page_data(recording_html(recording, "synthetic"))["frames"][0]
    ego, after, right = np.array(frame["ego"]), np.array(frame["after"]), np.array(frame["right"])
    assert outcome.metrics.rte < 1e-9 and len(right) == outcome.metrics.n_true > 0
    centre = ego[right[:, 0]].mean(axis=1, keepdims=True)
    assert np.allclose(after[right[:, 1]], centre + SLIM[0] * (ego[right[:, 0]] - centre), atol=2e-3)
    scene = draw(outcome, {})
    assert np.allclose(ego, scene.meshes["ego_boxes"].vertices[:, :2].reshape(-1, 4, 2), atol=1e-3)
    assert np.allclose(after, scene.meshes["cav_boxes"].vertices[:, :2].reshape(-1, 4, 2), atol=1e-3)
