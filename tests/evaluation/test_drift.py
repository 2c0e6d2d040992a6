"""A localization error that drifts like GNSS (``localization="drifting"``): a Gauss-Markov bias
per axis with the asked standard deviation and time constant, the same for a frame whatever was
computed before it."""
import numpy as np
import pytest

import loaders
from evaluation.drift import drift_error
from evaluation.scenario import ScenarioParams
from evaluation.trials import frame_inputs


def test_the_bias_has_the_asked_spread_and_correlation_time():
    times = np.arange(20000) * 0.5
    sigma = np.array([3.0, 2.0, 0.1])
    series = np.array([drift_error(sigma, 30.0, 0.0, 7, "cav", times, k) for k in range(0, len(times), 5)])
    np.testing.assert_allclose(series.std(axis=0), sigma, rtol=0.1)
    step = 30.0 / 2.5  # samples one time constant apart (every 5th frame, 0.5 s each)
    lagged = np.corrcoef(series[:-int(step), 0], series[int(step):, 0])[0, 1]
    assert lagged == pytest.approx(np.exp(-1.0), abs=0.08)


def test_a_frames_error_is_the_same_whatever_order_frames_are_computed_in():
    sequence = loaders.open("argoverse2")
    params = ScenarioParams(protocol="range", localization="drifting", loc_x=3.0, loc_y=3.0, loc_yaw=5.0)
    frames = [40, 3, 40, 120, 3]
    inits = [frame_inputs(sequence[k], "range").build(params, 5).init for k in frames]
    np.testing.assert_array_equal(inits[0], inits[2])
    np.testing.assert_array_equal(inits[1], inits[4])
    consecutive = [frame_inputs(sequence[k], "range").build(params, 5).init for k in (40, 41)]
    assert np.abs(consecutive[0] - consecutive[1]).max() < 0.5
    assert np.abs(inits[0] - frame_inputs(sequence[40], "range").build(params, 6).init).max() > 0.0


def test_drifting_needs_the_frames_times_and_a_positive_time_constant():
    with pytest.raises(ValueError, match=r"ScenarioParams.loc_tau must be a number in \[1, 3600\]"):
        ScenarioParams(localization="drifting", loc_tau=0.0)
    from evaluation.scenario import FrameInputs
    boxes = np.zeros((3, 7))
    boxes[:, 0] = [0.0, 10.0, 20.0]
    inputs = FrameInputs(0, {"boxes": boxes, "ids": np.arange(3)})
    with pytest.raises(ValueError, match="needs the frames' timestamps"):
        inputs.build(ScenarioParams(localization="drifting"), 0)
