"""Parameter search from the app: the grid and the current thresholds, scored alike."""
from __future__ import annotations

import dataclasses
import math

from app.panels.reports import search_markdown, ties_words
from app.session.explorer import Explorer
from app.session.search import SearchResult, run_search
from app.session.settings import Settings
from evaluation.search import Candidate, rank_key


def test_search_scores_the_grid_and_the_current_setting(small_explorer: Explorer) -> None:
    settings = Settings()
    settings = dataclasses.replace(settings, scenario=dataclasses.replace(settings.scenario, protocol="sind"))
    result = run_search(small_explorer, settings, "f1", stride=10)
    assert result.frames == (0, 10, 20, 30, 40) and len(result.candidates) == 36
    assert [c.score for c in result.candidates] == sorted((c.score for c in result.candidates), reverse=True)
    assert result.current.params == {"sigma1": 10.0, "sigma2": 3.0, "sigma3": 1.0, "distance_limit": 20.0}
    match = [c for c in result.candidates if c.params == {"sigma1": 10.0, "sigma2": 3.0, "sigma3": 1.0}]
    assert match and match[0].score == result.current.score
    assert "| current | 10 | 3 | 1 | 20 |" in search_markdown(result) and result.option(0).startswith("#1 sigma1 ")


def _candidate(sigma1: float, score: float, rte: float, margin: float) -> Candidate:
    summary = {"rte_mean": rte, "margin_median": margin, "success_rate": score, "precision": 1.0, "recall": 1.0}
    return Candidate({"sigma1": sigma1, "sigma2": 3.0, "sigma3": 1.0}, score, summary)


def test_ties_on_the_score_are_broken_by_rte_then_margin_and_said() -> None:
    tied = [_candidate(5.0, 1.0, 0.3, 9.0), _candidate(10.0, 1.0, 0.1, 2.0), _candidate(15.0, 1.0, 0.1, 7.0),
            _candidate(20.0, 1.0, math.nan, 50.0)]
    ranked = sorted(tied, key=rank_key)
    assert [c.params["sigma1"] for c in ranked] == [15.0, 10.0, 5.0, 20.0]
    current = _candidate(10.0, 1.0, 0.1, 2.0)
    current.params["distance_limit"] = 20.0
    result = SearchResult(Settings(), "success", (0, 10), tuple(ranked), current)
    shown = search_markdown(result)
    assert "*All 4 tie on success (1.000): ranked by mean RTE (lower first)" in shown
    assert "| #1 | 15 | 3 | 1 | 20 | 1.000 | 0.10 m | 7.0 |" in shown
    top_tie = (ranked[0], ranked[1], _candidate(1.0, 0.5, 0.1, 1.0))
    assert ties_words(SearchResult(Settings(), "success", (0,), top_tie, current)).startswith("*2 tie on success at")
    assert "tie on" not in ties_words(SearchResult(Settings(), "f1", (0,), (ranked[0], top_tie[2]), current))
