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


def test_a_track_holds_through_frames_without_measurements_until_its_prediction_is_too_uncertain():
    """Frames where CBM alone cannot answer cost the track nothing: its prediction, surer than a
    per-frame guess, is the answer; once the prediction grows too uncertain the track is lost and
    the frame abstains with per-frame CBM's answer."""
    trials = frames(30, drifting(8))
    calibrator = SequenceCalibrator(CBMParams(), TrackingParams(lost_after=2, lost_m=1.5, lost_deg=1.5))
    run(trials, calibrator)
    empty = np.zeros((0, 7))
    results = [calibrator.step(empty, empty, trials[0].init, 0.7 + 1.0 * k, agent="cav") for k in range(1, 8)]
    events = [r.track.event for r in results]
    held = events.index("lost")
    assert held >= 2 and set(events[:held]) == {"no measurement"}
    assert all(r.estimated and not r.abstained for r in results[:held]), "the prediction answers"
    lost = results[held]
    assert lost.abstained and lost.reason.startswith("lost: ") and not lost.estimated
    np.testing.assert_array_equal(lost.transform, trials[0].init)


def test_bad_time_and_tracking_settings_are_named():
    with pytest.raises(ValueError, match="time_s must be a finite number"):
        SequenceCalibrator().step(np.zeros((0, 7)), np.zeros((0, 7)), None, float("nan"))
    with pytest.raises(ValueError, match="TrackingParams.chain must be an integer from 2 to 1000, got 1"):
        TrackingParams(chain=1)


# --- issue 50, item 6 -----------------------------------------------------------------------------------------------

EMPTY = np.zeros((0, 7))


TIME = "time_s must be a finite number of seconds, got "


@pytest.mark.parametrize("call, words", [
    (lambda: SequenceCalibrator().step(EMPTY, EMPTY, None, None), TIME + "None"),
    (lambda: SequenceCalibrator().step(EMPTY, EMPTY, None, "0.5"), TIME + "'0.5'"),
    (lambda: SequenceCalibrator("fast"), "SequenceCalibrator's params must be a CBMParams, got 'fast'"),
    (lambda: SequenceCalibrator(tracking={"chain": 3}), "SequenceCalibrator's tracking must be a TrackingParams"),
    (lambda: SequenceCalibrator().step(EMPTY, EMPTY, None, 0.0, agent=np.array([1, 2])), "agent must be None, a"),
    (lambda: SequenceCalibrator().step(EMPTY, EMPTY, None, 0.0, agent=float("nan")), "agent must be None, a string"),
    (lambda: SequenceCalibrator().step(np.ones((3, 7)) * 1j, EMPTY, None, 0.0),
     "ego_boxes must be an array of real numbers, got dtype complex128"),
    (lambda: SequenceCalibrator().step(EMPTY, [["a"] * 7], None, 0.0), "cav_boxes must be an array of real numbers"),
])
def test_a_bad_argument_of_a_step_is_named(call, words):
    with pytest.raises(ValueError, match=words.replace("(", r"\(").replace(")", r"\)")):
        call()


@pytest.mark.parametrize("name", ["gate", "drift_m", "drift_deg", "drift_share", "lost_m", "lost_deg", "sure_margin",
                                  "max_gap_s", "chain", "window", "lost_after", "reacquire_after"])
def test_every_tracking_setting_has_an_upper_bound_named_in_its_message(name):
    with pytest.raises(ValueError, match=f"TrackingParams.{name} must be (at most|an integer from 2 to) "):
        TrackingParams(**{name: 10**300 if name in ("chain", "window", "lost_after", "reacquire_after") else 1e300})


def test_numpy_numbers_are_numbers_and_are_kept_as_python_ones():
    tracking = TrackingParams(chain=np.int64(5), gate=np.float32(3.5))
    assert tracking == TrackingParams(chain=5, gate=3.5) and type(tracking.chain) is int
    assert CBMParams(sigma2=np.float32(3)) == CBMParams(sigma2=3.0)
    with pytest.raises(ValueError, match="CBMParams.sigma2 must be at most 10, got 300.0"):
        CBMParams(sigma2=np.float32(300))
    with pytest.raises(ValueError, match="TrackingParams.chain must be at most window"):
        TrackingParams(chain=11, window=10)


def test_the_persistence_keeps_at_most_window_measurements_over_any_sequence():
    from cbm.track import Measurement, Persistence

    persistence, rate = Persistence(10), np.array([0.25, 0.25, 3e-4])
    chains = [persistence.add(Measurement(np.array([1.0, 2.0, 0.1]), np.eye(3) * 0.01, 0.1 * k, None), rate, 0.1, 3.5)
              for k in range(1500)]
    assert max(len(chain) for chain in chains) == 10 and len(chains[-1]) == 10
    held = {id(m) for _, chain in persistence.kept for m in chain}
    assert len(held) <= 19


def test_a_stopped_step_run_again_answers_as_one_never_stopped():
    from cbm.engine.threads import Cancelled, stoppable

    trials = frames(30, drifting(12))
    times = np.arange(12) * 0.1
    times[8:] += 30.0
    never = run(trials, SequenceCalibrator(CBMParams()), times)
    calibrator = SequenceCalibrator(CBMParams())
    run(trials[:8], calibrator, times[:8])
    with pytest.raises(Cancelled), stoppable(lambda: True):
        calibrator.step(trials[8].ego_boxes, trials[8].cav_boxes, trials[8].init, float(times[8]), agent="cav")
    again = run(trials[8:], calibrator, times[8:])
    assert never[8].track.event.startswith("reset: a gap")
    assert [r.track.event for r in again] == [r.track.event for r in never[8:]]
    for a, b in zip(again, never[8:]):
        np.testing.assert_array_equal(a.transform, b.transform)


def test_the_smoother_starts_on_the_first_frame_where_the_causal_track_still_watches():
    """The first frames of a drifting error: CBM over time answers them per frame (the error has not
    been seen to persist yet); over the whole recording the frames after them vouch for them, so
    their answers are the track's, with its covariance, and no farther from the truth on average."""
    from cbm.sequence import Smoother

    trials = frames(30, drifting(16), noise=0.6)
    smoother = Smoother(CBMParams())
    causal = [smoother.step(t.ego_boxes, t.cav_boxes, t.init, 0.1 * k, agent="cav") for k, t in enumerate(trials)]
    smoothed = smoother.smoothed()
    assert len(smoothed) == len(trials)
    assert causal[0].track.event == "per frame" and not causal[0].track.persists

    def error(result, trial):
        return float(np.hypot(*se2.translation_of(se2.inverse(trial.T_true) @ result.transform)))

    early = range(4)
    assert np.mean([error(s, t) for s, t in zip(smoothed[:4], trials)]) <= \
        np.mean([error(c, t) for c, t in zip(causal[:4], trials)]) + 1e-9
    assert any(not np.array_equal(smoothed[k].transform, causal[k].transform) for k in early)
    assert [r.pairs.tolist() for r in smoothed] == [r.pairs.tolist() for r in causal]


def test_the_smoothers_backward_pass_matches_anew_only_frames_no_forward_prediction_guided(monkeypatch):
    """The backward pass takes the forward pass's measurement of a frame a prediction guided (a
    second match of it would pair alike at a match's cost), and matches anew, under its own
    prediction, the first frames that the forward pass matched alone."""
    import cbm.sequence
    from cbm.sequence import Smoother

    trials = frames(30, drifting(16), noise=0.6)
    smoother = Smoother(CBMParams())
    for k, t in enumerate(trials):
        smoother.step(t.ego_boxes, t.cav_boxes, t.init, 0.1 * k, agent="cav")
    matched = []
    real = cbm.sequence.match
    monkeypatch.setattr(cbm.sequence, "match", lambda ego, *rest: matched.append(ego) or real(ego, *rest))
    smoother.smoothed()
    anew = [next(k for k, t in enumerate(trials) if np.array_equal(t.ego_boxes, ego)) for ego in matched]
    guided_forward = [k for k, (_, guided) in enumerate(smoother.measured) if guided]
    assert guided_forward and anew
    assert not set(anew) & set(guided_forward)
    assert set(anew) == set(range(len(trials))) - set(guided_forward) == set(range(5))


def test_measurements_pulled_away_frame_by_frame_leave_a_prediction_that_holds_for_seconds():
    """A wrong pair kept over a few frames moves the measurements alike, as a fast drift would. The
    track learns no more than ``DRIFT_MOST`` times the set drift rate from them, so that its
    prediction still answers three seconds of frames without a measurement (before, it grew past
    ``lost_deg`` within one)."""
    from cbm.track import DRIFT_MOST, Measurement, Track

    tracking = TrackingParams()
    rate = np.array([tracking.drift_m ** 2, tracking.drift_m ** 2, np.radians(tracking.drift_deg) ** 2])
    R = np.diag([0.05 ** 2, 0.05 ** 2, np.radians(0.2) ** 2])

    def measured(k: int, pulled: float) -> Measurement:
        return Measurement(np.array([2.0 + pulled, -1.0 - pulled, np.radians(3.0 + 6.0 * pulled)]), R, 0.1 * k, None)

    track = Track.started([measured(k, 0.0) for k in range(5)], rate)
    for k, pulled in enumerate([0.0, 0.3, 0.6, 0.9, 1.2], start=5):
        track.update(measured(k, pulled), rate)
    assert np.all(track.q <= DRIFT_MOST * rate + 1e-12)
    _, P = track.predicted(0.9 + 3.0)
    assert np.sqrt(P[0, 0] + P[1, 1]) <= tracking.lost_m and np.degrees(np.sqrt(P[2, 2])) <= tracking.lost_deg
