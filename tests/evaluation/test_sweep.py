"""evaluation.sweep: trials over frames and a grid, every method, rows reproducible from (frame, params, seed)."""
import dataclasses

import numpy as np
import pytest

from cbm import CBMParams, match
from evaluation.metric_registry import aggregate
from evaluation.metrics import TrialMetrics, evaluate
from evaluation.scenario import FrameInputs, ScenarioParams, make_trial, trial_rng
from evaluation.sweep import TIMING_COLUMNS, Sweep, run, run_task, summarise
from support.scenes import street_scene

METHODS = ("cbm", "cbm-no-consensus", "icp", "ricp", "vips")


def frames(n=2, objects=25):
    rng = np.random.default_rng(5)
    return [FrameInputs(k, {"boxes": street_scene(objects, rng), "ids": np.arange(objects)},
                        np.array(["car"] * objects)) for k in range(3, 3 + n)]


def without_timing(rows):
    return repr([{k: v for k, v in row.items() if k not in TIMING_COLUMNS} for row in rows])


SWEEP = Sweep(methods=METHODS, grid={"eta": [0.3, 0.7], "sigma_p": [0.0, 0.3], "sigma2": [2.0, 3.0]}, seed=11)


def test_same_seed_gives_the_same_rows_in_the_same_order_whatever_the_workers():
    inputs = frames()
    serial = run(SWEEP, inputs)
    assert without_timing(serial) == without_timing(run(SWEEP, inputs))
    assert without_timing(serial) == without_timing(run(SWEEP, inputs, workers=2))
    other_seed = dataclasses.replace(SWEEP, seed=12)
    assert without_timing(serial) != without_timing(run(other_seed, inputs))


def test_rows_cover_the_grid_and_method_parameters_vary_only_their_methods():
    rows = run(SWEEP, frames())
    assert len(rows) == SWEEP.trial_count(2) == 2 * 4 * (2 + 2 + 1 + 1 + 1)
    assert all(list(row) == SWEEP.columns() for row in rows)
    icp = [r for r in rows if r["method"] == "icp"]
    assert len(icp) == 8 and all(r["sigma2"] is None and r["max_iterations"] == 100 for r in icp)
    assert {r["sigma2"] for r in rows if r["method"] == "cbm"} == {2.0, 3.0}
    assert all(r["consensus"] is False for r in rows if r["method"] == "cbm-no-consensus")
    assert all(r["seed"] == 11 and r["protocol"] == "sind" for r in rows)


def test_a_row_is_what_the_app_gets_from_its_frame_parameters_and_seed():
    frame = frames(1)[0]
    scenario = ScenarioParams(eta=0.7, sigma_p=0.3, seed=11)
    row = next(r for _, r in run_task(SWEEP, (0,), (frame,), (0, scenario), False)
               if r["method"] == "cbm" and r["sigma2"] == 2.0)
    trial = make_trial(frame.trial["boxes"], frame.trial["ids"], scenario, rng=trial_rng(11, frame.index))
    expected = evaluate(match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(sigma2=2.0)), trial)
    names = ("n_ego", "n_cav", "n_true", "n_matched", "n_correct", "precision", "recall", "ad", "rre", "rte")
    assert repr([row[n] for n in names]) == repr([getattr(expected, n) for n in names])


def test_summarise_gives_the_micro_averages_of_cbm_metrics_per_group():
    rows = run(Sweep(methods=("cbm", "icp"), grid={"eta": [0.3, 0.7]}, seed=1), frames())
    groups = dict(summarise(rows, ["method"]))
    assert list(groups) == [("cbm",), ("icp",)]
    icp = [TrialMetrics(**{f.name: r[f.name] for f in dataclasses.fields(TrialMetrics)})
           for r in rows if r["method"] == "icp"]
    assert groups[("icp",)]["precision"] == aggregate(icp)["precision"]


def test_the_range_protocol_records_its_agents():
    frame = frames(1, 30)[0]
    boxes = frame.trial["boxes"]
    trial = {**frame.trial, "ego_pose": np.eye(3), "cav_pose": np.eye(3), "ego_id": 0, "cav_id": 1}
    trial["cav_pose"][:2, 2] = boxes[1, :2]
    sweep = Sweep(methods=("icp",), seed=0, scenario=ScenarioParams(protocol="range", localization="gaussian"))
    (row,) = run(sweep, [FrameInputs(0, trial)])
    assert (row["ego_id"], row["cav_id"], row["localization"]) == ("0", "1", "gaussian")
    assert row["init_rte"] > 0 and row["n_true"] > 0


@pytest.mark.parametrize("grid, message", [
    ({"sigma2": [2.0]}, "sigma2.*cbm, cbm-no-consensus, cbm-graph, cbm-time, cbm-smooth, cbm-no-prior, none of which "
                        "is selected"),
    ({"wobble": [1]}, "'wobble' is not a parameter"),
    ({"seed": [1]}, "seed is the sweep's own argument"),
    ({"eta": []}, "'eta' has no values"),
    ({"eta": [1.5]}, "ScenarioParams.eta"),
    ({"max_iterations": [0]}, "ICPParams.max_iterations"),
])
def test_a_bad_grid_is_refused_before_anything_runs(grid, message):
    with pytest.raises(ValueError, match=message):
        Sweep(methods=("icp",), grid=grid)


def test_unknown_or_repeated_methods_are_refused():
    with pytest.raises(ValueError, match="methods must be"):
        Sweep(methods=("cbm", "sift"))
    with pytest.raises(ValueError, match="must not repeat"):
        Sweep(methods=("icp", "icp"))
