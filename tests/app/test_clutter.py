"""Clutter in the app (issue 25, follow-up): the Scenario tab's missed-detection share and false-box
rate make the very trial ``evaluate.py`` makes for the same settings and seed, the metrics count the
false boxes as the evaluation does, and a false box in the scene says it matches no object."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import polars as pl
import pytest

from app.scene.drawing import draw
from app.scene.picking import describe
from app.scene.text import metrics_markdown
from app.session.explorer import Explorer
from app.session.settings import Settings
from evaluation.cli import main
from evaluation.clutter import is_false
from evaluation.conditions import condition
from evaluation.run import frame_inputs

FRAME, SEED = 5, 3


def _clutter_settings(**changes: float) -> Settings:
    """The clutter condition at ``SEED`` on frame ``FRAME``, with some scenario fields changed."""
    return Settings(frame=FRAME, scenario=dataclasses.replace(condition("clutter"), seed=SEED, **changes))


@pytest.mark.parametrize("miss_rate, false_rate", [(0.2, 0.3), (0.5, 1.0)])
def test_the_two_rates_give_the_trial_evaluate_builds(explorer: Explorer, miss_rate: float, false_rate: float) -> None:
    settings = _clutter_settings(miss_rate=miss_rate, false_rate=false_rate)
    inputs, skipped = frame_inputs(explorer.sequence, [FRAME], settings.scenario.protocol)
    assert skipped == []
    expected = inputs[0].build(settings.scenario, SEED)
    trial = explorer.compute(settings).trial
    for name in ("ego_boxes", "cav_boxes", "ego_ids", "cav_ids", "gt_pairs", "init", "T_true"):
        assert np.array_equal(getattr(trial, name), getattr(expected, name)), name
    assert is_false(trial.ego_ids).sum() > 0 and is_false(trial.cav_ids).sum() > 0
    plain = explorer.compute(_clutter_settings(miss_rate=0.0, false_rate=0.0)).trial
    assert len(trial.gt_pairs) < len(plain.gt_pairs)


def test_the_app_counts_a_cluttered_frame_as_evaluate_py_does(explorer: Explorer, tmp_path: Path) -> None:
    out = tmp_path / "clutter"
    assert main(["--dataset", "argoverse2", "--frames", str(FRAME), "--methods", "cbm", "--condition", "clutter",
                 "--seed", str(SEED), "--workers", "1", "--no-timing", "--out", str(out)]) == 0
    row = pl.read_csv(out / "trials.csv").row(0, named=True)
    metrics = explorer.compute(_clutter_settings()).metrics
    for name in ("n_ego", "n_cav", "n_true", "n_matched", "n_correct"):
        assert getattr(metrics, name) == row[name], name
    assert metrics.rte == pytest.approx(row["rte"], abs=1e-9)


def test_false_boxes_match_no_object_and_say_so(explorer: Explorer) -> None:
    outcome = explorer.compute(_clutter_settings().with_view(ghosts=True))
    trial, picture = outcome.trial, draw(outcome, explorer.map_segments, explorer.sequence[FRAME])
    false_ego, false_cav = is_false(trial.ego_ids), is_false(trial.cav_ids)
    assert not false_ego[trial.gt_pairs[:, 0]].any() and not false_cav[trial.gt_pairs[:, 1]].any()
    assert not np.isin(outcome.world_ids.astype(str), trial.ego_ids[false_ego]).any()
    text = metrics_markdown(outcome)
    assert f"| of them false boxes | {false_ego.sum()} / {false_cav.sum()} (they match no object) |" in text
    assert "| missed detections | 20% of each agent's |" in text
    rows = picture.objects["ego"][1]
    row = int(np.flatnonzero(is_false(trial.ego_ids[rows]))[0])
    assert describe(outcome, picture, "ego", row).startswith("EGO false box ")
    assert "false box" not in describe(outcome, picture, "ego", int(np.flatnonzero(~false_ego[rows])[0]))


def test_with_the_ghosts_each_false_box_is_crossed_out(explorer: Explorer) -> None:
    settings = _clutter_settings()
    outcome = explorer.compute(settings.with_view(ghosts=True))
    picture = draw(outcome, explorer.map_segments, explorer.sequence[FRAME])
    crosses = picture.lines["false_marks"].segments
    (ego, ego_rows), (cav, cav_rows) = picture.objects["ego"], picture.objects["cav"]
    trial = outcome.trial
    false = np.concatenate([ego[is_false(trial.ego_ids[ego_rows])], cav[is_false(trial.cav_ids[cav_rows])]])
    assert len(crosses) == 2 * len(false) > 0
    centres = crosses[:, :, :2].mean(axis=1)
    assert np.allclose(np.sort(centres[:, 0]), np.sort(np.repeat(false[:, 0], 2)), atol=1e-3)
    hidden = draw(explorer.compute(settings), explorer.map_segments, explorer.sequence[FRAME])
    assert len(hidden.lines["false_marks"].segments) == 0


def test_without_clutter_the_metrics_have_no_clutter_rows(explorer: Explorer) -> None:
    text = metrics_markdown(explorer.compute(_clutter_settings(miss_rate=0.0, false_rate=0.0)))
    assert "false boxes" not in text and "missed detections" not in text
