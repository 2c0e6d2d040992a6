"""Parameter search: every grid point scored, ranked by the objective, reproducible."""
import numpy as np
import pytest

from cbm import CBMParams, match
from evaluation.metric_registry import aggregate
from evaluation.metrics import evaluate
from evaluation.scenario import FrameInputs, ScenarioParams, make_trial, trial_rng
from evaluation.search import f1, grid_size, search
from support.scenes import street_scene

SCENARIO = ScenarioParams(eta=0.5, sigma_p=0.4, sigma_theta=4.0)
SPACE = {"sigma2": (0.5, 3.0), "sigma3": (0.5, 1.0)}


def frames(n=3):
    out = []
    for k in range(n):
        world = street_scene(30, np.random.default_rng(k))
        out.append(FrameInputs(k, {"boxes": world, "ids": np.arange(30)}))
    return out


def test_every_point_is_scored_and_ranked_best_first():
    ranked = search(frames(), SCENARIO, space=SPACE, objective="f1", seed=3)
    assert len(ranked) == grid_size(SPACE) == 4
    assert {tuple(c.params.values()) for c in ranked} == {(a, b) for a in SPACE["sigma2"] for b in SPACE["sigma3"]}
    scores = [c.score for c in ranked]
    assert scores == sorted(scores, reverse=True)
    assert ranked[0].params["sigma2"] == 3.0 and ranked[-1].params["sigma2"] == 0.5


def test_a_score_is_what_the_app_would_measure_with_those_settings():
    inputs = frames()
    best = search(inputs, SCENARIO, space=SPACE, objective="f1", seed=3)[0]
    metrics = []
    for frame in inputs:
        trial = make_trial(**frame.trial, params=SCENARIO, rng=trial_rng(3, frame.index))
        metrics.append(evaluate(match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(**best.params)), trial))
    assert best.score == pytest.approx(f1(aggregate(metrics)))


def test_fixed_parameters_are_kept_and_results_repeat():
    first = search(frames(2), SCENARIO, space={"sigma1": (5.0, 20.0)}, base={"heading": "fold"}, seed=1)
    again = search(frames(2), SCENARIO, space={"sigma1": (5.0, 20.0)}, base={"heading": "fold"}, seed=1)
    assert [(c.params, c.score) for c in first] == [(c.params, c.score) for c in again]


@pytest.mark.parametrize("kwargs,message", [(dict(space={"eta": (0.1,)}), "space must name"),
                                            (dict(objective="speed"), "objective must be one of")])
def test_bad_requests_say_what_was_expected(kwargs, message):
    with pytest.raises(ValueError, match=message):
        search(frames(1), SCENARIO, **kwargs)
