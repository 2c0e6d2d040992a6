"""Named test conditions and clutter: missed detections, false boxes, success at 1 / 2 / 3 and abstentions."""
import dataclasses
import importlib.util
import json
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from evaluation.clutter import false_box_count
from evaluation.conditions import CONDITIONS, SPARSE_RANGE, condition
from evaluation.metric_registry import aggregate
from evaluation.metrics import evaluate
from evaluation.scenario import ScenarioParams, make_trial

REPO = Path(__file__).resolve().parents[2]


def scene(n: int = 60) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(4)
    boxes = np.zeros((n, 7))
    boxes[:, :2] = rng.uniform(-40, 40, (n, 2))
    boxes[:, 3:6] = rng.uniform([3.5, 1.6, 1.4], [5.5, 2.1, 1.9], (n, 3))
    boxes[:, 6] = rng.uniform(-np.pi, np.pi, n)
    return boxes, np.arange(n)


def test_misses_remove_detections_and_their_true_pairs_and_leave_every_earlier_draw_alone():
    boxes, ids = scene()
    base = ScenarioParams(eta=1.0, sigma_p=0.3, seed=2)
    full, thinned = make_trial(boxes, ids, base), make_trial(boxes, ids, ScenarioParams(eta=1.0, sigma_p=0.3,
                                                                                       miss_rate=0.3, seed=2))
    assert len(full.gt_pairs) == 60 and 25 < len(thinned.gt_pairs) < 45
    assert set(thinned.ego_ids) < set(full.ego_ids) and set(thinned.cav_ids) < set(full.cav_ids)
    kept = np.isin(full.ego_ids, thinned.ego_ids)
    np.testing.assert_array_equal(full.ego_boxes[kept], thinned.ego_boxes)
    np.testing.assert_array_equal(full.init, thinned.init)
    assert all(thinned.ego_ids[i] == thinned.cav_ids[j] for i, j in thinned.gt_pairs)


def test_false_boxes_pair_with_nothing_lie_in_the_sensor_disc_and_copy_real_sizes():
    boxes, ids = scene()
    poses = {"ego_pose": np.eye(3), "cav_pose": np.array([[1, 0, 10.0], [0, 1, 0], [0, 0, 1]])}
    params = ScenarioParams(protocol="range", sensor_range=30.0, false_rate=0.5, seed=1)
    clean = make_trial(boxes, ids, ScenarioParams(protocol="range", sensor_range=30.0, seed=1), **poses)
    trial = make_trial(boxes, ids, params, **poses)
    n_real = len(clean.ego_boxes)
    added = trial.ego_boxes[n_real:]
    assert len(added) == false_box_count(n_real, 0.5) > 5
    assert np.all(np.hypot(*added[:, :2].T) <= 30.0)
    assert all(tuple(size) in {tuple(s) for s in clean.ego_boxes[:, 3:6]} for size in added[:, 3:6])
    np.testing.assert_array_equal(trial.gt_pairs, clean.gt_pairs)
    assert all(str(i).startswith("false:ego:") for i in trial.ego_ids[n_real:])
    assert not set(trial.ego_ids[n_real:]) & set(trial.cav_ids)
    np.testing.assert_array_equal(make_trial(boxes, ids, params, **poses).ego_boxes, trial.ego_boxes)


@pytest.mark.parametrize("field, value", [("miss_rate", 1.5), ("miss_rate", -0.1), ("false_rate", -1.0),
                                          ("false_rate", math.inf)])
def test_bad_clutter_rates_name_the_field(field, value):
    with pytest.raises(ValueError, match=f"ScenarioParams.{field} must be"):
        ScenarioParams(**{field: value})


def test_the_named_conditions_are_the_issue_settings():
    assert list(CONDITIONS) == ["mild", "hard", "range-50", "heavy-noise", "prior-error", "clutter", "drift-heavy",
                                "drift-clutter", "drift-bigloc", "drift-sparse", "no-prior", "occluded", "latency"]
    occluded, late = CONDITIONS["occluded"], CONDITIONS["latency"]
    assert (occluded.sight, occluded.sensor_range, occluded.sigma_p) == (True, 50.0, CONDITIONS["range-50"].sigma_p)
    assert (late.delay_ms - late.jitter_ms, late.delay_ms + late.jitter_ms, late.localization) == (100.0, 300.0,
                                                                                                   "drifting")
    drift, bigloc = CONDITIONS["drift-heavy"], CONDITIONS["drift-bigloc"]
    assert (drift.localization, drift.sigma_p, drift.sigma_theta, drift.miss_rate) == ("drifting", 0.8, 15.0, 0.2)
    assert (bigloc.loc_x, bigloc.loc_yaw, bigloc.loc_tau) == (6.0, 15.0, 60.0)
    sparse = dataclasses.replace(CONDITIONS["drift-sparse"], sensor_range=CONDITIONS["drift-clutter"].sensor_range)
    assert sparse == CONDITIONS["drift-clutter"] and CONDITIONS["drift-sparse"].sensor_range == SPARSE_RANGE == 25.0
    heavy, clutter, prior = CONDITIONS["heavy-noise"], CONDITIONS["clutter"], CONDITIONS["prior-error"]
    assert (heavy.eta, heavy.sigma_p, heavy.sigma_theta, heavy.flip_prob) == (0.2, 0.8, 15.0, 0.5)
    assert (clutter.sensor_range, clutter.miss_rate, clutter.false_rate, clutter.sigma_p) == (50.0, 0.2, 0.3, 0.4)
    assert (prior.sensor_range, prior.loc_x, prior.loc_yaw, prior.localization) == (80.0, 6.0, 15.0, "gaussian")
    assert (CONDITIONS["no-prior"].localization, CONDITIONS["no-prior"].loc_x) == ("none", 0.0)
    with pytest.raises(ValueError, match="unknown condition 'foggy'; choose from mild"):
        condition("foggy")


def test_success_at_two_and_three_and_abstentions_are_counted_apart():
    trial = make_trial(*scene(20), ScenarioParams(eta=1.0, flip_prob=0.0, loc_x=0.0, loc_y=0.0, loc_yaw=0.0))
    off = trial.T_true.copy()
    off[0, 2] += 1.5
    results = [SimpleNamespace(pairs=trial.gt_pairs, transform=trial.T_true, estimated=True),
               SimpleNamespace(pairs=trial.gt_pairs, transform=off, estimated=True),
               SimpleNamespace(pairs=trial.gt_pairs, transform=off, estimated=True, abstained=True)]
    agg = aggregate([evaluate(r, trial) for r in results])
    assert agg["success_rate"] == pytest.approx(1 / 3) and agg["success_rate_2"] == pytest.approx(1.0)
    assert agg["success_rate_3"] == pytest.approx(1.0)
    assert agg["abstain_rate"] == pytest.approx(1 / 3) and agg["returned_success"] == pytest.approx(1 / 2)


def load_evaluate():
    spec = importlib.util.spec_from_file_location("evaluate_conditions", REPO / "evaluate.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_evaluate_runs_a_named_condition_and_reports_success_at_two_and_three(tmp_path):
    out = tmp_path / "clutter"
    args = ["--dataset", "synthetic:60", "--frames", "0:2", "--condition", "clutter", "--methods", "cbm,oracle",
            "--no-timing", "--workers", "1", "--out", str(out)]
    assert load_evaluate().main(args) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert {"success_rate_2", "success_rate_3", "abstain_rate", "returned_success"} <= set(metrics["cbm"])
    assert metrics["oracle"]["precision"] == 1.0
    summary = (out / "summary.md").read_text()
    assert "protocol `range`" in summary and "success @ 2 m, 2 deg (%)" in summary and "abstained (%)" in summary


def test_an_unknown_condition_is_one_line_and_exit_status_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        load_evaluate().main(["--condition", "foggy", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1 and "--condition" in err


def ranged_trial(params: ScenarioParams, seed: int = 0):
    boxes, ids = scene()
    cav_pose = np.array([[np.cos(2.0), -np.sin(2.0), 25.0], [np.sin(2.0), np.cos(2.0), -10.0], [0.0, 0.0, 1.0]])
    return make_trial(boxes, ids, params, ego_pose=np.eye(3), cav_pose=cav_pose, rng=np.random.default_rng(seed))


def test_no_prior_takes_the_cav_frame_for_the_ego_frame_and_leaves_the_detections_alone():
    trial = ranged_trial(CONDITIONS["no-prior"])
    np.testing.assert_array_equal(trial.init, np.eye(3))
    gaussian = ranged_trial(ScenarioParams(**{**CONDITIONS["no-prior"].__dict__, "localization": "gaussian"}))
    np.testing.assert_array_equal(trial.cav_boxes, gaussian.cav_boxes)
    np.testing.assert_array_equal(trial.T_true, gaussian.T_true)


def test_no_prior_with_a_radius_guesses_within_it_with_any_heading():
    params = ScenarioParams(protocol="range", localization="none", loc_x=10.0)
    errors = []
    for seed in range(200):
        trial = ranged_trial(params, seed)
        error = np.linalg.inv(trial.T_true) @ trial.init
        cav_error = trial.cav_pose[:2, :2] @ error[:2, 2]
        errors.append((np.hypot(*cav_error), np.arctan2(error[1, 0], error[0, 0])))
    distance, yaw = np.array(errors).T
    assert distance.max() <= 10.0 and np.median(distance) > 5.0
    assert np.histogram(yaw, bins=4, range=(-np.pi, np.pi))[0].min() > 30
