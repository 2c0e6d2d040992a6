"""CBM over time (``cbm.SequenceCalibrator``): per-frame CBM's answer unchanged while the error does
not persist, a track that pools frames when it does, and what starts it over."""
from __future__ import annotations

import numpy as np
import pytest

from cbm import CBMParams, SequenceCalibrator, TrackingParams, match, se2
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene


def frames(n: int, errors: list[np.ndarray], seed: int = 0, noise: float = 0.3):
    """``len(errors)`` trials of one street scene, the CAV's world pose off by ``errors[k]`` (dx, dy,
    dyaw) in frame k, fresh detection noise each frame."""
    world = street_scene(n, np.random.default_rng(seed), extent=45.0)
    ids = np.arange(n)
    ego_pose, cav_pose = se2.make(0.0, 0.0, 0.0), se2.make(12.0, -4.0, 0.4)
    out = []
    for k, error in enumerate(errors):
        reported = se2.make(12.0 + error[0], -4.0 + error[1], 0.4 + error[2])
        params = ScenarioParams(protocol="range", sensor_range=80.0, sigma_p=noise, sigma_theta=3.0, seed=k)
        trial = make_trial(world, ids, params, ego_pose=ego_pose, cav_pose=cav_pose,
                           rng=np.random.default_rng([seed, k]))
        trial = type(trial)(**{**trial.__dict__, "init": se2.inverse(ego_pose) @ reported})
        out.append(trial)
    return out


def drifting(count: int, seed: int = 0) -> list[np.ndarray]:
    """A slowly drifting bias (3 m, 3 m, 5 deg) with a little white noise."""
    rng = np.random.default_rng(seed)
    bias = np.array([2.5, -2.0, np.radians(4.0)])
    out = []
    for _ in range(count):
        bias = bias + rng.normal(0.0, [0.03, 0.03, np.radians(0.05)])
        out.append(bias + rng.normal(0.0, [0.05, 0.05, np.radians(0.05)]))
    return out


def independent(count: int, seed: int = 0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.normal(0.0, [3.0, 3.0, np.radians(5.0)]) for _ in range(count)]


def run(trials, calibrator: SequenceCalibrator, times=None, agents=None):
    times = np.arange(len(trials)) * 0.1 if times is None else times
    agents = ["cav"] * len(trials) if agents is None else agents
    return [calibrator.step(t.ego_boxes, t.cav_boxes, t.init, float(s), agent=a)
            for t, s, a in zip(trials, times, agents)]


def test_an_error_drawn_anew_every_frame_gets_per_frame_cbms_answers_unchanged():
    trials = frames(30, independent(25))
    over_time = run(trials, SequenceCalibrator(CBMParams()))
    for trial, result in zip(trials, over_time):
        alone = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams())
        np.testing.assert_array_equal(result.transform, alone.transform)
        assert result.track.event == "per frame" and not result.track.persists


def test_a_drifting_error_starts_a_track_that_pools_the_frames():
    trials = frames(30, drifting(30))
    results = run(trials, SequenceCalibrator(CBMParams()))
    events = [r.track.event for r in results]
    assert events[:4] == ["per frame"] * 4 and "started" in events[4:8]
    assert events[-1] == "accepted" and results[-1].track.pooled >= 20
    errors = [np.hypot(*se2.translation_of(se2.inverse(t.T_true) @ r.transform)) for t, r in zip(trials, results)]
    assert max(errors[10:]) < 0.5


def test_a_real_jump_is_re_acquired_and_a_frame_against_the_track_is_rejected():
    errors = drifting(40)
    for k in range(20, 40):
        errors[k] = errors[k] + np.array([4.0, 3.0, np.radians(6.0)])
    trials = frames(30, errors)
    results = run(trials, SequenceCalibrator(CBMParams()))
    after = [r.track.event for r in results[20:26]]
    assert "re-acquired" in after
    truth_error = se2.inverse(trials[-1].T_true) @ results[-1].transform
    assert np.hypot(*se2.translation_of(truth_error)) < 0.5


@pytest.mark.parametrize("change", ["backwards", "gap", "agent"])
def test_time_going_backwards_a_long_gap_or_another_cav_start_over(change):
    trials = frames(30, drifting(12))
    times = np.arange(12) * 0.1
    agents = ["cav"] * 12
    if change == "backwards":
        times[8:] -= 1.0
    elif change == "gap":
        times[8:] += 30.0
    else:
        agents[8:] = ["other"] * 4
    results = run(trials, SequenceCalibrator(CBMParams()), times, agents)
    assert results[7].track.pooled > 0
    assert results[8].track.event.startswith("reset: ") and results[8].track.pooled == 0


def test_a_track_nothing_confirms_is_lost_and_abstains_with_per_frame_cbms_answer():
    trials = frames(30, drifting(8))
    calibrator = SequenceCalibrator(CBMParams(), TrackingParams(lost_after=2))
    run(trials, calibrator)
    empty = np.zeros((0, 7))
    results = [calibrator.step(empty, empty, trials[0].init, 0.8 + 0.1 * k, agent="cav") for k in range(3)]
    assert [r.track.event for r in results] == ["no measurement", "no measurement", "lost"]
    lost = results[-1]
    assert lost.abstained and lost.reason.startswith("lost: ") and not lost.estimated
    np.testing.assert_array_equal(lost.transform, trials[0].init)
    assert calibrator.track is None


def test_bad_time_and_tracking_settings_are_named():
    with pytest.raises(ValueError, match="time_s must be a finite number"):
        SequenceCalibrator().step(np.zeros((0, 7)), np.zeros((0, 7)), None, float("nan"))
    with pytest.raises(ValueError, match="TrackingParams.chain must be an integer >= 2"):
        TrackingParams(chain=1)
