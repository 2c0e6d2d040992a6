"""CoAlign / HEAL stage1_boxes.json as a detections source, and trials built on it.

The fixture follows CoAlign's pose_graph_pre_calc.py output for the OPV2V scenario fixture: sample
"13" is its frame 0 (ego 641 at lidar_pose_clean (10, 20) yaw 90 deg in CARLA's left-handed world),
sample "12" belongs to another scenario (ego 500 m away) and "0" is null. Corners were made with
OpenCOOD's boxes_to_corners_3d in each agent's left-handed LiDAR frame.
"""
import json
import math

import numpy as np
import pytest

import loaders
from evaluation.detected import match_to_truth
from evaluation.scenario import ScenarioParams
from evaluation.trials import build_trial
from loaders.detections import fit_boxes

SCENARIO = "opv2v/scenario"
STAGE1 = "stage1/stage1_boxes.json"


@pytest.fixture
def detected(fixtures):
    return loaders.open(fixtures / SCENARIO, detections=fixtures / STAGE1)


def test_samples_matched_to_frames_by_ego_pose(detected):
    assert list(detected.detections) == [0]
    assert detected[1].detections is None
    assert sorted(detected[0].detections) == ["641", "650"]


def test_corners_fitted_into_right_handed_agent_frames(detected):
    ego = detected[0].detections["641"]
    # (1.3, -5.5), yaw -60 deg, 4.4 x 1.9 x 1.5 in the left-handed LiDAR frame -> y and yaw mirrored
    np.testing.assert_allclose(ego.boxes[0], [1.3, 5.5, -1.1, 4.4, 1.9, 1.5, math.radians(60)], atol=1e-5)
    np.testing.assert_allclose(ego.uncertainty, [[0.2, 0.3], [1.5, 1.4]])
    cav = detected[0].detections["650"]
    np.testing.assert_allclose(cav.boxes[:, [0, 1, 6]], [[14.5, 1.2, math.radians(150)], [20.4, 0.0, math.pi / 2]],
                               atol=1e-5)


def test_trial_uses_detections_and_truth_for_pairs(detected):
    trial = build_trial(detected[0], ScenarioParams(protocol="opv2v", sigma_p=1.0), seed=3, cav="650")
    # the detector's boxes, not noisy ground truth: the same whatever sigma_p and seed
    np.testing.assert_allclose(trial.ego_boxes, detected[0].detections["641"].boxes)
    np.testing.assert_allclose(trial.cav_boxes, detected[0].detections["650"].boxes)
    # vehicle 700 is at (1, 5.5) in the ego frame: the detection 0.3 m off matches it; (30, -30) matches nothing
    assert list(trial.ego_ids) == ["700", "det:ego:1"]
    assert list(trial.cav_ids) == ["700", "641"]            # the CAV detects the ego car
    np.testing.assert_array_equal(trial.gt_pairs, [[0, 0]])
    np.testing.assert_allclose(trial.ego_true_xy, [[1.0, 5.5], [30.0, -30.0]], atol=1e-9)
    np.testing.assert_allclose(trial.cav_true_xy, [[1.0, 5.5], [0.0, 0.0]], atol=1e-9)


def test_frame_without_detections_keeps_simulated_boxes(detected):
    trial = build_trial(detected[1], ScenarioParams(protocol="opv2v"), seed=0)
    assert not any(str(i).startswith("det:") for i in trial.ego_ids)


def test_fit_boxes_inverts_opencood_corners():
    template = np.array([[1, 1, -1], [1, -1, -1], [-1, -1, -1], [-1, 1, -1],
                         [1, 1, 1], [1, -1, 1], [-1, -1, 1], [-1, 1, 1]]) / 2
    yaw = 2.5
    rotation = np.array([[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0], [0, 0, 1]])
    corners = (template * [4.0, 2.0, 1.5]) @ rotation.T + [3.0, -2.0, 0.5]
    np.testing.assert_allclose(fit_boxes(corners[None])[0], [3.0, -2.0, 0.5, 4.0, 2.0, 1.5, yaw], atol=1e-12)


def test_matching_is_one_to_one_within_two_metres():
    truth = np.array([[0.0, 0.0], [1.0, 0.0], [10.0, 0.0]])
    detected = np.array([[0.9, 0.0], [0.2, 0.0], [13.0, 0.0]])
    np.testing.assert_array_equal(match_to_truth(detected, truth), [1, 0, -1])


def _rewritten(tmp_path, fixtures, change) -> str:
    data = json.loads((fixtures / STAGE1).read_text())
    change(data)
    path = tmp_path / "stage1_boxes.json"
    path.write_text(json.dumps(data))
    return path


def test_bad_corners_name_the_sample_and_field(tmp_path, fixtures):
    for corners in ([[[1, 2]] * 8], [[[1, 2, 3]] * 8, [[1, 2]] * 8]):
        path = _rewritten(tmp_path, fixtures, lambda d, c=corners: d["13"]["pred_corner3d_np_list"].__setitem__(1, c))
        with pytest.raises(loaders.LoaderError, match=r"13.pred_corner3d_np_list\[1\]: expected N boxes of 8 corners"):
            loaders.open(fixtures / SCENARIO, detections=path)


def test_missing_key_and_no_matching_sample(tmp_path, fixtures):
    path = _rewritten(tmp_path, fixtures, lambda d: d["13"].pop("cav_id_list"))
    with pytest.raises(loaders.LoaderError, match="missing key 13.cav_id_list"):
        loaders.open(fixtures / SCENARIO, detections=path)
    path = _rewritten(tmp_path, fixtures, lambda d: d.pop("13"))
    with pytest.raises(loaders.LoaderError, match="no sample matches a frame of opv2v/scenario"):
        loaders.open(fixtures / SCENARIO, detections=path)
    with pytest.raises(loaders.LoaderError, match="detections file .* does not exist"):
        loaders.open(fixtures / SCENARIO, detections=tmp_path / "absent.json")


@pytest.mark.parametrize("value", [1e300, -1e7])
def test_finite_but_huge_corners_are_refused_at_load_naming_the_file_and_field(tmp_path, fixtures, value) -> None:
    def huge(samples):
        samples["13"]["pred_corner3d_np_list"][0][0][3][1] = value
    path = _rewritten(tmp_path, fixtures, huge)
    with pytest.raises(loaders.LoaderError) as raised:
        loaders.open(fixtures / SCENARIO, detections=path)
    assert str(raised.value) == (f"{path}: 13.pred_corner3d_np_list[0]: a corner coordinate is {abs(value):.3g} m from "
                                 "the agent; expected box corners within 1e+05 m of its LiDAR")


def test_a_second_sample_for_the_same_frame_is_left_out_with_a_warning(tmp_path, fixtures):
    def repeat(samples):
        samples["14"] = json.loads(json.dumps(samples["13"]))
        samples["14"]["pred_corner3d_np_list"][0] = samples["14"]["pred_corner3d_np_list"][0][:1]
    path = _rewritten(tmp_path, fixtures, repeat)
    with pytest.warns(UserWarning, match=r"1 sample\(s\) match a frame an earlier sample matched"):
        sequence = loaders.open(fixtures / SCENARIO, detections=path)
    first = loaders.open(fixtures / SCENARIO, detections=fixtures / STAGE1)
    assert np.array_equal(sequence.detections[0]["641"].boxes, first.detections[0]["641"].boxes)
    assert sequence.warnings == [f"{path}: 1 sample(s) match a frame an earlier sample matched (the same ego pose), "
                                 "and were left out: 14 (frame 0, kept 13)"]


def test_a_sample_whose_cav_is_not_in_its_frame_is_refused(tmp_path, fixtures):
    path = _rewritten(tmp_path, fixtures, lambda samples: samples["13"]["cav_id_list"].__setitem__(1, "777"))
    with pytest.raises(loaders.LoaderError) as raised:
        loaders.open(fixtures / SCENARIO, detections=path)
    assert str(raised.value) == (f"{path}: 13.cav_id_list: agent '777' is not in frame 0 of opv2v/scenario (its "
                                 "agents: -1, 641, 650); the sample belongs to another dataset or split")


def test_the_file_is_read_one_sample_at_a_time_and_must_be_one_whole_object(tmp_path, fixtures, monkeypatch):
    monkeypatch.setattr("loaders.structured.STREAM_CHUNK", 64)
    streamed = loaders.open(fixtures / SCENARIO, detections=fixtures / STAGE1)
    assert list(streamed.detections) == [0] and len(streamed.detections[0]["641"].boxes)
    for text, reason in (('{"13": null', "expected ',' or '}' after a value"),
                         ('{"13": null} {}', "extra data after the object"), ("[1]", None)):
        path = tmp_path / "bad.json"
        path.write_text(text)
        with pytest.raises(loaders.LoaderError, match="expected a JSON object of sample index" if reason is None
                           else f"not valid JSON \\({reason}"):
            loaders.open(fixtures / SCENARIO, detections=path)


def test_a_file_with_a_byte_order_mark_is_read_as_json_loads_reads_it(tmp_path, fixtures):
    path = tmp_path / "stage1_boxes.json"
    path.write_bytes(b"\xef\xbb\xbf" + (fixtures / STAGE1).read_bytes())
    assert list(loaders.open(fixtures / SCENARIO, detections=path).detections) == [0]


SCORES = [[0.9, 0.3], [0.6, 0.2]]
"""pred_score_np_list for sample 13 (agents 641 and 650, two boxes each), as CoAlign saves it."""


def _with_scores(samples):
    samples["13"]["pred_score_np_list"] = SCORES


def test_scores_are_read_and_the_threshold_drops_boxes_below_it(tmp_path, fixtures):
    sequence = loaders.open(fixtures / SCENARIO, detections=_rewritten(tmp_path, fixtures, _with_scores))
    ego = sequence[0].detections["641"]
    np.testing.assert_allclose(ego.scores, SCORES[0])
    assert len(ego.above(0.5).boxes) == 1 and ego.above(0.0) is ego
    np.testing.assert_allclose(ego.above(0.5).boxes, ego.boxes[:1])
    counts = []
    for threshold in (0.0, 0.5, 0.95):
        trial = build_trial(sequence[0], ScenarioParams(protocol="opv2v", min_score=threshold), seed=0,
                            cav="650")
        counts.append((len(trial.ego_boxes), len(trial.cav_boxes)))
    assert counts == [(2, 2), (1, 1), (0, 0)]


def test_without_scores_the_threshold_keeps_every_box(detected):
    assert detected[0].detections["641"].scores is None
    trial = build_trial(detected[0], ScenarioParams(protocol="opv2v", min_score=0.9), seed=0, cav="650")
    assert (len(trial.ego_boxes), len(trial.cav_boxes)) == (2, 2)


def test_a_file_written_without_uncertainty_loads(tmp_path, fixtures):
    def drop(samples):
        for sample in samples.values():
            if sample:
                sample.pop("uncertainty_np_list")
    path = _rewritten(tmp_path, fixtures, drop)
    assert "uncertainty_np_list" not in path.read_text()
    ego = loaders.open(fixtures / SCENARIO, detections=path)[0].detections["641"]
    assert ego.boxes.shape == (2, 7) and ego.uncertainty.shape == (2, 0)


@pytest.mark.parametrize("scores, message", [([[0.9], [0.6, 0.2]], r"expected 2 scores \(one per box\), got 1"),
                                             ([[0.9, "high"], [0.6, 0.2]], r"expected nested lists of numbers"),
                                             ([[0.9, 0.3]], r"expected one entry per agent of cav_id_list")])
def test_bad_scores_name_the_sample_and_field(tmp_path, fixtures, scores, message):
    path = _rewritten(tmp_path, fixtures, lambda d: d["13"].__setitem__("pred_score_np_list", scores))
    with pytest.raises(loaders.LoaderError, match=r"13.pred_score_np_list(\[\d\])?: " + message):
        loaders.open(fixtures / SCENARIO, detections=path)


@pytest.mark.parametrize("threshold", [-0.1, 1.5, float("nan")])
def test_min_score_outside_0_1_is_refused(threshold):
    with pytest.raises(ValueError, match="min_score"):
        ScenarioParams(min_score=threshold)


def test_an_integer_of_5001_digits_names_the_file(tmp_path, fixtures):
    """Python converts at most 4300 digits to an integer; the message named neither the file nor
    where (issue 40, item 5)."""
    path = tmp_path / "stage1_boxes.json"
    path.write_text((fixtures / STAGE1).read_text().replace("[", "[" + "7" * 5001 + ", ", 1))
    with pytest.raises(loaders.LoaderError, match=r"stage1_boxes.json: not valid JSON \(Exceeds the limit \(4300 "
                                                  r"digits\) for integer string conversion near character \d+\)"):
        loaders.open(fixtures / SCENARIO, detections=path)
