"""CBM over time in the app: frames computed in time order and kept per settings, a catch-up that
reports its progress and stops when asked, and the metrics, timeline and walkthrough that say how
each answer was reached."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import loaders
from app.panels.plot import OVER_TIME, timeline_data, timeline_series
from app.panels.scenario import unread_reason
from app.scene.text import metrics_markdown
from app.session.explorer import Explorer
from app.session.history import FrameHistory
from app.session.over_time import Stopped
from app.session.presets import discover
from app.session.settings import Settings
from app.walkthrough.steps import walkthrough
from cbm import match
from cbm.methods import METHODS


@pytest.fixture(scope="module")
def explorer() -> Explorer:
    return Explorer(loaders.open("argoverse2"))


@pytest.fixture(scope="module")
def drifting() -> Settings:
    presets, _ = discover()
    return presets["drift-heavy"].apply(Settings())


def at(settings: Settings, frame: int) -> Settings:
    return dataclasses.replace(settings, frame=frame)


def test_jumping_ahead_computes_the_frames_before_in_order_and_keeps_them(explorer, drifting):
    assert drifting.method == "cbm-time" and drifting.scenario.localization == "drifting"
    seen = []
    outcome = explorer.compute(at(drifting, 12), lambda done, of: seen.append((done, of)))
    assert seen == [(k, 12) for k in range(13)]
    assert outcome.result.track is not None and outcome.alone is not None
    seen.clear()
    back = explorer.compute(at(drifting, 5), lambda done, of: seen.append(done))
    forward = explorer.compute(at(drifting, 13), lambda done, of: seen.append(done))
    assert seen == [13]
    assert back.result is explorer.compute(at(drifting, 5)).result
    assert forward.result.track.pooled > 0


def test_other_settings_are_a_run_of_their_own_and_a_catch_up_stops_when_asked(explorer, drifting):
    other = drifting.with_scenario(seed=4)
    asked = []
    with pytest.raises(Stopped) as stopped:
        explorer.compute(at(other, 30), lambda done, of: asked.append(done), stop=lambda: len(asked) >= 6)
    assert stopped.value.frame == 5
    resumed = []
    explorer.compute(at(other, 8), lambda done, of: resumed.append(done))
    assert resumed == [6, 7, 8]


def test_the_tabs_tracking_parameters_reach_its_calibrator(explorer, drifting):
    """Two agreeing frames start a track when ``chain`` is 2: on the shipped log under drift-heavy,
    frame 1 rather than frame 4 (five in a row, the default)."""
    events = {}
    for chain in (2, 5):
        settings = drifting.with_tracking(chain=chain)
        explorer.compute(at(settings, 4))
        done = explorer.over_time.done(settings)
        events[chain] = [done[k].result.track.event for k in range(5)]
    assert events[2][:2] == ["per frame", "started"] and events[5][3:] == ["per frame", "started"]


def test_the_metrics_say_how_the_answer_was_reached_and_from_which_frames(explorer, drifting):
    outcome = explorer.compute(at(drifting, 20))
    text = metrics_markdown(outcome)
    assert "| over time |" in text and "per-frame CBM (this frame)" in text
    assert outcome.pooled_from is not None and f"| answer from | frames {outcome.pooled_from}–20" in text


def test_the_timeline_draws_per_frame_cbms_rte_and_the_marked_frames_beside(explorer, drifting):
    history = FrameHistory()
    for frame in range(0, 20):
        history.add(explorer.compute(at(drifting, frame)))
    assert history.over_time()
    data = timeline_data(dict(history.rows), {}, 19, len(explorer), over_time=True)
    assert len(data) == len(timeline_series(False, over_time=True)) and timeline_series(False, True)[-2:] == OVER_TIME
    drawn = np.isfinite(data[-2])
    assert set(data[0][drawn].astype(int).tolist()) == set(range(20)) and (data[-2][drawn] >= 0).all()


def test_the_walkthrough_ends_with_the_prediction_the_measurement_and_the_answer(explorer, drifting):
    steps = walkthrough(explorer.compute(at(drifting, 15)))
    last = steps[-1]
    assert len(steps) == 10 and last.title == "Step 10/10 · Over time (step 8, beyond the paper)"
    assert {"truth", "predicted", "measured"} <= set(last.lines) and "the answer" in last.text


def test_the_drift_sliders_act_only_on_a_drifting_error():
    settings = Settings()
    assert unread_reason(settings, "loc_tau") == "the localization error does not drift"
    assert unread_reason(settings.with_scenario(localization="drifting"), "loc_tau") is None


def _params(settings: Settings):
    return METHODS[settings.method].resolved(settings.params)


def _same_answer(a, b) -> bool:
    return np.array_equal(a.pairs, b.pairs) and np.allclose(a.transform, b.transform) and a.abstained == b.abstained


def test_a_jump_ahead_computes_per_frame_cbm_for_the_frame_shown_and_the_rest_after(explorer, drifting):
    """Issue 47 item 7: the frames before the one asked for step the calibrator only; per-frame CBM
    on them comes afterwards (``fill_over_time``) and is the answer ``cbm.match`` gives on their trials."""
    settings = at(drifting.with_scenario(seed=11), 30)
    outcome = explorer.compute(settings)
    done = explorer.over_time.done(settings)
    assert outcome.alone is not None and done[30].alone is outcome.alone
    waiting = [j for j, d in done.items() if d.alone is None]
    assert waiting and 30 not in waiting
    assert explorer.fill_over_time(settings, stop=lambda: False) == len(waiting)
    done = explorer.over_time.done(settings)
    assert all(d.alone is not None and d.alone_metrics is not None for d in done.values())
    for j in (waiting[0], waiting[-1]):
        _, trial, _ = explorer.trial(settings, j)
        assert _same_answer(done[j].alone, match(trial.ego_boxes, trial.cav_boxes, trial.init, _params(settings)))


def test_a_frame_answered_by_per_frame_cbm_takes_its_answer_as_per_frame_cbms(explorer, drifting):
    """Before the error is seen to persist the calibrator runs per-frame CBM itself: that answer is
    per-frame CBM's beside it, without a second run."""
    settings = at(drifting.with_scenario(seed=12), 6)
    explorer.compute(settings)
    done = explorer.over_time.done(settings)
    watched = [j for j, d in done.items() if d.result.track.predicted is None]
    assert watched and all(done[j].alone is not None for j in watched)
    for j in watched:
        _, trial, _ = explorer.trial(settings, j)
        assert _same_answer(done[j].alone, match(trial.ego_boxes, trial.cav_boxes, trial.init, _params(settings)))


def test_filling_per_frame_cbm_stops_when_asked(explorer, drifting):
    settings = at(drifting.with_scenario(seed=13), 25)
    explorer.compute(settings)
    calls = []
    filled = explorer.fill_over_time(settings, stop=lambda: calls.append(1) or len(calls) > 3)
    assert filled == 3
    assert sum(d.alone is None for d in explorer.over_time.done(settings).values()) > 0


def test_a_noise_edit_reuses_every_frames_trial_inputs(explorer, drifting):
    settings = at(drifting, 3)
    before = [explorer.trial_inputs(settings, j) for j in range(4)]
    edited = settings.with_scenario(sigma_p=settings.scenario.sigma_p + 0.1)
    assert all(explorer.trial_inputs(edited, j) is inputs for j, inputs in enumerate(before))
    assert explorer.trial_inputs(edited.with_scenario(sensor_range=30.0), 0) is not before[0]
