"""The session computes, the scene draws: late fusion and CBM's sets are part of a frame's outcome,
computed once when a view first asks for them; drawing only turns them into nodes."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import app.session.explorer as explorer_module
from app.scene import geometry
from app.scene.drawing import draw
from app.scene.planes import FUSED
from app.session.explorer import Explorer, Outcome
from app.session.settings import Settings
from evaluation.fusion import fused_against_truth


@pytest.fixture()
def fusions(monkeypatch: pytest.MonkeyPatch) -> list[np.ndarray]:
    """The CAV placements the session fused, one per fusion computed."""
    calls: list[np.ndarray] = []

    def counting(trial, transform, *args):
        calls.append(transform)
        return fused_against_truth(trial, transform, *args)

    monkeypatch.setattr(explorer_module, "fused_against_truth", counting)
    return calls


def _fused_outcome(explorer: Explorer, layout: str) -> Outcome:
    settings = Settings(frame=3)
    settings = dataclasses.replace(settings, view=dataclasses.replace(settings.view, fused=True, layout=layout))
    return explorer.compute(settings)


def test_a_redraw_fuses_nothing_again(small_explorer: Explorer, fusions: list[np.ndarray]) -> None:
    outcome = _fused_outcome(small_explorer, "side by side")
    assert not fusions
    first = draw(outcome, small_explorer.map_segments)
    again = draw(outcome, small_explorer.map_segments)
    assert len(fusions) == 2
    assert np.array_equal(fusions[0], outcome.result.init) and np.array_equal(fusions[1], outcome.result.transform)
    assert np.array_equal(first.lines["fused_tp"].segments, again.lines["fused_tp"].segments)


def test_the_drawn_fused_boxes_are_the_outcomes(small_explorer: Explorer) -> None:
    outcome = _fused_outcome(small_explorer, "after")
    fused = outcome.fused("after")
    truth, hits = fused_against_truth(outcome.trial, outcome.result.transform, outcome.world_boxes,
                                      outcome.world_ids, outcome.settings.scenario.seed, outcome.frame_index)
    assert np.array_equal(fused.boxes, truth.boxes) and np.array_equal(fused.hits, hits)
    picture = draw(outcome, small_explorer.map_segments)
    assert np.allclose(picture.lines["fused_tp"].segments, geometry.outline_segments(fused.boxes[fused.hits], FUSED))
    assert np.allclose(picture.lines["fused_fp"].segments, geometry.outline_segments(fused.boxes[~fused.hits], FUSED))


def test_cbm_sets_are_the_ones_the_method_built(small_explorer: Explorer) -> None:
    outcome = small_explorer.compute(Settings(frame=3))
    assert outcome.cbm() is outcome.result, "the method is CBM: its own run explains it, nothing runs twice"
    assert outcome.result.explanation is not None
    baseline = small_explorer.compute(Settings(frame=3, method="icp"))
    assert baseline.cbm() is baseline.cbm() and baseline.cbm().explanation is not None
