"""CBM over time tells how old the CAV's messages are on the shipped log's own frames and on moving
traffic read from drone recordings (SinD's and INTERACTION's layouts): within 50 ms (median) of each
frame's true, jittering age under the latency condition, and near 0 where nothing is late."""
from pathlib import Path

import numpy as np
import pytest

import loaders
from cbm import SequenceCalibrator
from evaluation.conditions import condition
from evaluation.trials import frame_inputs
from support.recordings import moving_traffic


def told_ages(name: str, seed: int = 0, log: loaders.Sequence | None = None) -> tuple[np.ndarray, np.ndarray]:
    log, scenario = log or loaders.open("argoverse2"), condition(name)
    calibrator, told, true = SequenceCalibrator(), [], []
    for k in range(len(log)):
        inputs = frame_inputs(log[k], "range", window_s=scenario.window_s)
        trial = inputs.build(scenario, seed)
        result = calibrator.step(trial.ego_boxes, trial.cav_boxes, trial.init, float(log.timestamps[k]),
                                 agent=inputs.cav)
        if result.latency_s is not None:
            told.append(result.latency_s)
            true.append(trial.message_age_s)
    return np.array(told), np.array(true)


def test_the_age_of_late_messages_is_told_within_50_ms():
    told, true = told_ages("latency")
    assert len(told) > 100, "the age is told on most frames once moving objects pin it"
    assert np.median(np.abs(told - true)) < 0.050
    assert np.all((true >= 0.1 - 1e-9) & (true <= 0.3 + 1e-9))


@pytest.mark.parametrize("name", ["drift-heavy", "range-50"])
def test_where_nothing_is_late_the_age_told_is_near_zero(name):
    told, true = told_ages(name)
    assert np.all(true == 0.0)
    assert len(told) == 0 or np.median(told) < 0.050


@pytest.mark.parametrize("layout", ["sind", "interaction"])
def test_the_age_is_told_within_50_ms_on_moving_traffic_of_drone_recordings(layout, tmp_path: Path):
    log = loaders.open(str(moving_traffic(tmp_path / layout, layout)))
    told, true = told_ages("latency", log=log)
    assert len(told) > len(log) // 2
    assert np.median(np.abs(told - true)) < 0.050
    told, true = told_ages("drift-heavy", log=log)
    assert len(told) == 0 or np.median(told) < 0.050
