"""Parameter search from the app: the grid and the current thresholds, scored alike."""
from __future__ import annotations

import dataclasses

from app.panels.reports import search_markdown
from app.session.explorer import Explorer
from app.session.search import run_search
from app.session.settings import Settings


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
