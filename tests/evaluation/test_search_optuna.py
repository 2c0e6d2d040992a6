"""The Optuna searcher: seeded draws inside the grid's box, reproducible, scored like the grid."""
import numpy as np
import pytest

from evaluation.scenario import FrameInputs, ScenarioParams
from evaluation.search import search
from support.scenes import street_scene

pytest.importorskip("optuna")

SCENARIO = ScenarioParams(eta=0.5, sigma_p=0.4, sigma_theta=4.0)
SPACE = {"sigma2": (0.5, 3.0), "sigma3": (0.5, 1.0)}


def frames(n=2):
    return [FrameInputs(k, {"boxes": street_scene(30, np.random.default_rng(k)), "ids": np.arange(30)})
            for k in range(n)]


def test_the_same_seed_draws_and_scores_the_same_settings():
    first = search(frames(), SCENARIO, space=SPACE, objective="f1", seed=4, searcher="optuna", n_trials=6)
    again = search(frames(), SCENARIO, space=SPACE, objective="f1", seed=4, searcher="optuna", n_trials=6)
    other = search(frames(), SCENARIO, space=SPACE, objective="f1", seed=5, searcher="optuna", n_trials=6)
    assert [(c.params, c.score) for c in first] == [(c.params, c.score) for c in again]
    assert {tuple(c.params.values()) for c in first} != {tuple(c.params.values()) for c in other}
    assert len(first) == 6 and [c.score for c in first] == sorted((c.score for c in first), reverse=True)
    assert all(0.5 <= c.params["sigma2"] <= 3.0 and 0.5 <= c.params["sigma3"] <= 1.0 for c in first)


def test_an_optuna_setting_scores_what_the_grid_gives_it():
    best = search(frames(), SCENARIO, space=SPACE, objective="f1", seed=4, searcher="optuna", n_trials=3)[0]
    on_grid = search(frames(), SCENARIO, space={n: (v,) for n, v in best.params.items()}, objective="f1", seed=4)
    assert on_grid[0].score == best.score


def test_an_unknown_searcher_is_refused():
    with pytest.raises(ValueError, match="searcher must be one of grid, optuna"):
        search(frames(1), SCENARIO, space=SPACE, searcher="random")
