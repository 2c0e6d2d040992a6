"""One trial builder: the app's session and the evaluation build the same trial from the same
frame, scenario and seed, and the automatic CAV stays one vehicle through the sequence."""
from pathlib import Path

import numpy as np
import pytest

import loaders
from app.session.explorer import Explorer
from app.session.settings import Settings
from evaluation.run import frame_inputs as evaluation_inputs
from evaluation.scenario import ScenarioParams
from evaluation.trials import AUTO_CAV, NoTrial, build_trial, frame_inputs, sequence_cav

REPO = Path(__file__).resolve().parents[2]
FIELDS = ("ego_boxes", "cav_boxes", "ego_ids", "cav_ids", "T_true", "init", "gt_pairs", "ego_true_xy",
          "cav_true_xy", "ego_pose", "cav_pose")


@pytest.fixture(scope="module")
def scene() -> Explorer:
    return Explorer(loaders.open("argoverse2"))


@pytest.mark.parametrize("protocol", ["sind", "range"])
def test_app_and_evaluation_build_identical_trials_on_every_frame(scene: Explorer, protocol: str) -> None:
    frames = range(len(scene))
    inputs, skipped = evaluation_inputs(scene.sequence, frames, protocol, 25.0)
    assert not skipped and [f.index for f in inputs] == list(frames)
    for seed in (0, 1, 7):
        scenario = ScenarioParams(protocol=protocol, eta=0.4, sigma_p=0.3, sigma_theta=5.0, seed=seed)
        for k in frames:
            app = scene.compute(Settings(frame=k, scenario=scenario)).trial
            evaluated = inputs[k].build(scenario, seed)
            for name in FIELDS:
                np.testing.assert_array_equal(getattr(app, name), getattr(evaluated, name), err_msg=f"{name} frame {k}")


def test_the_automatic_cav_is_one_vehicle_through_the_shipped_scene(scene: Explorer) -> None:
    steady = sequence_cav(scene.sequence)
    cavs = [frame_inputs(scene.sequence[k], "range").trial["cav_id"] for k in range(len(scene))]
    assert steady is not None and cavs.count(steady) > len(cavs) // 2
    assert all(cav == steady for cav, k in zip(cavs, range(len(scene))) if steady in scene.sequence[k].track_ids)


def test_a_chosen_cav_is_used_where_present_and_noted_where_not(scene: Explorer) -> None:
    frame = scene.sequence[0]
    other = next(str(t) for t in frame.track_ids if str(t) not in ("ego", sequence_cav(scene.sequence))
                 and loaders.is_vehicle(frame.categories[frame.track_ids == t])[0])
    chosen = frame_inputs(frame, "range", cav=other)
    assert chosen.trial["cav_id"] == other and chosen.note == "chosen"
    missing = frame_inputs(frame, "range", cav="no-such-vehicle")
    assert missing.trial["cav_id"] == sequence_cav(scene.sequence) and "not in this frame" in missing.note


def test_build_trial_is_frame_inputs_then_build(scene: Explorer) -> None:
    scenario = ScenarioParams(protocol="range", sigma_p=0.2, seed=3)
    direct = build_trial(scene.sequence[9], scenario, seed=3)
    via = frame_inputs(scene.sequence[9], "range", AUTO_CAV).build(scenario, 3)
    np.testing.assert_array_equal(direct.cav_boxes, via.cav_boxes)


def test_frames_without_vehicles_make_sind_trials_only() -> None:
    walkers = loaders.open(str(REPO / "tests/loaders/fixtures/sind/Xian_412_m1"))
    frame = next(walkers[k] for k in range(len(walkers)) if len(walkers[k].track_ids) >= 2)
    sind = frame_inputs(frame, "sind")
    assert "abstract agents" in sind.note and "ego_id" not in sind.trial
    assert len(build_trial(frame, ScenarioParams(protocol="sind", eta=1.0), seed=0).gt_pairs) == len(frame.track_ids)
    with pytest.raises(NoTrial, match="no ego and CAV for the range protocol"):
        frame_inputs(frame, "range")
