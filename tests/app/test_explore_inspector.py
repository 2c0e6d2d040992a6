"""Context inspector: what it draws for an anchor pair and what it says."""
from __future__ import annotations

import dataclasses

import numpy as np

from app.scene import drawing, inspector
from app.session.explorer import Explorer
from app.session.settings import Settings


def _outcome(explorer: Explorer):
    settings = Settings()
    settings = dataclasses.replace(settings, scenario=dataclasses.replace(settings.scenario, protocol="sind",
                                                                          sigma_p=0.3, sigma_theta=3.0))
    outcome = explorer.compute(settings)
    return outcome, drawing.draw(outcome, {})


def test_band_and_region_outlines() -> None:
    vectors = np.array([[10.0, 0.0], [0.0, -5.0]])
    origin = np.array([1.0, 2.0])
    bands = inspector.band_segments(origin, vectors, 10.0, 3.0)
    regions = inspector.region_segments(origin, vectors, 3.0)
    assert bands.shape == (2 * (2 + inspector.ARC_SEGMENTS), 2, 3) and regions.shape == (8, 2, 3)
    ray_ends = bands[:2, 1, :2] - origin
    assert np.allclose(np.linalg.norm(ray_ends, axis=1), 13.0)
    assert np.allclose(np.degrees(np.arctan2(ray_ends[:, 1], ray_ends[:, 0])), [-10.0, 10.0])
    corners = regions[:4, 0, :2] - (origin + vectors[0])
    assert np.allclose(np.abs(corners).sum(axis=1), 3.0)
    assert inspector.band_segments(origin, np.zeros((0, 2)), 10.0, 3.0).shape == (0, 2, 3)


def test_the_winning_anchor_is_drawn_and_explained(small_explorer: Explorer) -> None:
    outcome, picture = _outcome(small_explorer)
    i, j = map(int, outcome.result.anchor)
    shown = inspector.inspect(outcome, picture, i, j)
    n_ego, n_cav = len(outcome.trial.ego_boxes) - 1, len(outcome.trial.cav_boxes) - 1
    lines = {name: len(drawn.segments) for name, drawn in shown.lines.items()}
    assert lines["inspector_ego_vectors"] == n_ego and lines["inspector_cav_vectors"] == n_cav
    assert lines["inspector_ego_bands"] == n_ego * (2 + inspector.ARC_SEGMENTS)
    assert lines["inspector_ego_regions"] == 4 * n_ego and lines["inspector_cav_regions"] == 4 * n_cav
    detail = outcome.cbm().explanation.anchor(i, j)
    assert lines["inspector_ego_kept"] > 0
    assert f"L_ij holds {len(detail.candidates)} pairs" in shown.markdown
    rows = zip(detail.candidates.tolist()[:5], detail.votes.tolist(), detail.kept_by_consensus.tolist())
    ego_ids, cav_ids = outcome.trial.ego_ids, outcome.trial.cav_ids
    for (a, b), votes, kept in rows:
        row = f"| {str(ego_ids[a])[:8]} | {str(cav_ids[b])[:8]} | {votes} | {'kept' if kept else 'removed'} |"
        assert row in shown.markdown
    drawn = np.concatenate([part.segments for part in shown.lines.values() if len(part.segments)])
    scene_left = max(boxes[:, 1].max() for boxes, _ in picture.objects.values())
    assert drawn[..., 1].min() > scene_left, "the panels sit left of the scene, away from the control panel"
    assert drawn[..., 1].min() >= shown.centre[1] - shown.span / 2 - 1e-6
    assert drawn[..., 1].max() <= shown.centre[1] + shown.span / 2 + 1e-6


def test_a_click_finds_the_counterpart(small_explorer: Explorer) -> None:
    outcome, picture = _outcome(small_explorer)
    i, j = map(int, outcome.result.pairs[0])
    assert inspector.counterpart(outcome, "ego", i) == (i, j)
    assert inspector.counterpart(outcome, "cav", j) == (i, j)
    alone = sorted(set(range(len(outcome.trial.ego_boxes))) - set(outcome.trial.gt_pairs[:, 0].tolist())
                   - set(outcome.result.pairs[:, 0].tolist()))
    assert inspector.counterpart(outcome, "ego", alone[0]) == (alone[0], None)
    shown = inspector.inspect(outcome, picture, alone[0], None)
    assert len(shown.lines["inspector_ego_vectors"].segments) > 0
    assert len(shown.lines["inspector_ego_bands"].segments) == 0
    assert len(shown.lines["inspector_cav_vectors"].segments) == 0
    assert "seen by one agent only" in shown.markdown
    assert set(inspector.empty().lines) == set(shown.lines)
