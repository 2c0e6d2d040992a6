"""What each agent saw, as the session computes it for the views (``app.session.seen``): the sight
drawn agrees with the trial (an object the CAV does not see lies in its shadow or out of range, one
it sees is reached by its sight), an agent the dataset speaks for gets the range alone, and a late
message's objects are where the CAV saw them, with how far they moved said and labelled."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import loaders
from app.scene.captions import caption_lines
from app.scene.drawing import draw
from app.scene.seen import sight_node
from app.session.explorer import Explorer, Outcome
from app.session.settings import Settings
from cbm import se2
from evaluation.conditions import condition
from evaluation.sight import OUTLINE_RAYS, contains, footprints
from support import releases, releases_v2i

TOUCH_M = 0.02
"""Metres: an outline point this close to a footprint's edge ends on it."""


@pytest.fixture(scope="module")
def synthetic() -> Explorer:
    return Explorer(loaders.open("synthetic:60"))


def occluded(frame: int, **scenario) -> Settings:
    settings = dataclasses.replace(Settings(), scenario=condition("occluded"), frame=frame, method="none")
    return settings.with_scenario(**scenario).with_view(sight=True)


def touched_share(outline: np.ndarray, box: np.ndarray) -> float:
    """Share of the outline's rays across ``box``'s footprint (sensor at the origin) that end on it:
    how much of it the drawn sight reaches."""
    grown = box.copy()
    grown[3:5] += 2 * TOUCH_M
    corners = footprints(grown[None])
    angles = np.arctan2(outline[:, 1], outline[:, 0])
    rim = footprints(box[None])[0]
    spread = se2.wrap_angle(np.arctan2(rim[:, 1], rim[:, 0]) - np.arctan2(box[1], box[0]))
    across = np.abs(se2.wrap_angle(angles - np.arctan2(box[1], box[0]) - (spread.max() + spread.min()) / 2)) \
        <= (spread.max() - spread.min()) / 2
    ends = [contains(corners, point)[0] for point in outline[across]]
    return float(np.mean(ends)) if ends else 0.0


@pytest.mark.parametrize("frame", [5, 25, 45])
def test_what_the_cav_does_not_see_lies_in_its_shadow_or_out_of_range(synthetic: Explorer, frame: int) -> None:
    outcome = synthetic.compute(occluded(frame))
    sight = outcome.sights()["cav"]
    assert sight.shadows and not sight.said and len(sight.outline) == OUTLINE_RAYS
    params, trial = outcome.settings.scenario, outcome.trial
    in_cav = se2.apply_boxes(se2.inverse(trial.T_true), outcome.world_boxes)
    seen = np.isin(outcome.world_ids, trial.cav_ids)
    hidden = 0
    for box, object_id, is_seen in zip(in_cav, outcome.world_ids, seen):
        if object_id == outcome.cav_id:
            continue
        share = touched_share(sight.outline, box)
        if is_seen:
            assert share > 0.0, f"{object_id} is seen, yet the drawn sight does not reach it"
        elif np.hypot(*box[:2]) <= params.sensor_range:
            assert share < params.sight_share + 0.1, f"{object_id} is not seen, yet {share:.0%} of it is in sight"
            hidden += 1
    assert hidden > 0, "the frame hides something from the CAV: the test has a shadow to check"


def test_the_sight_is_drawn_in_each_agents_colour_and_only_when_asked(synthetic: Explorer) -> None:
    outcome = synthetic.compute(occluded(25))
    drawing = draw(outcome, synthetic.map_segments)
    for role in ("ego", "cav"):
        fill = drawing.meshes[sight_node(role)]
        assert len(fill.faces) == OUTLINE_RAYS and 0 < fill.opacity < 0.5
        assert len(drawing.lines[sight_node(role, "sight_edge")].segments) == OUTLINE_RAYS
    cav_at = se2.translation_of(outcome.placements["after"])
    assert np.allclose(drawing.meshes["cav_sight"].vertices[0, :2], cav_at, atol=1e-4), "the fan starts at the CAV"
    plain = draw(synthetic.compute(dataclasses.replace(outcome.settings, view=Settings().view)), synthetic.map_segments)
    assert len(plain.meshes["cav_sight"].faces) == 0 and len(plain.lines["ego_sight_edge"].segments) == 0


def test_without_line_of_sight_the_sight_is_the_range_and_under_sind_there_is_none(synthetic: Explorer) -> None:
    outcome = synthetic.compute(occluded(25, sight=False))
    for sight in outcome.sights().values():
        assert not sight.shadows
        assert np.allclose(np.linalg.norm(sight.outline, axis=1), outcome.settings.scenario.sensor_range)
    assert synthetic.compute(occluded(25, protocol="sind")).sights() is None


def test_an_agent_the_dataset_speaks_for_sees_its_range_within_which_the_dataset_decides(explorer: Explorer) -> None:
    outcome = explorer.compute(occluded(12))
    sights = outcome.sights()
    assert sights["ego"].said and not sights["ego"].shadows and sights["cav"].shadows
    assert np.allclose(np.linalg.norm(sights["ego"].outline, axis=1), 50.0)
    assert "ego: what the dataset says it saw, within range · CAV: the boxes' shadows" in \
        draw(outcome, explorer.map_segments).metrics_markdown


def test_a_late_message_draws_the_objects_where_the_cav_saw_them_and_says_how_far_they_moved(
        synthetic: Explorer) -> None:
    outcome = synthetic.compute(occluded(30, delay_ms=300.0, sigma_p=0.0, sigma_theta=0.0, flip_prob=0.0))
    late, trial = outcome.late(), outcome.trial
    assert late.age_s == pytest.approx(0.3) == trial.message_age_s
    cav_seen = se2.apply_points(trial.T_true, trial.cav_boxes[:, :2])
    assert np.allclose(late.captured, cav_seen), "captured where the CAV's detections lie, at the truth"
    now = outcome.world_boxes[np.isin(outcome.world_ids, late.ids), :2]
    assert np.allclose(late.now, now)
    assert late.moving.any() and late.moved.max() > 1.0, "cars drive: 300 ms moves them metres"

    drawing = draw(outcome, synthetic.map_segments)
    text = f"moved {late.moved.max():.1f} m while the message travelled"
    assert drawing.labels["moved_after"][0] == text
    assert len(drawing.lines["moved"].segments) == int(late.moving.sum())
    assert "| message age | 300 ms |" in drawing.metrics_markdown
    assert f"up to {late.moved.max():.1f} m ({late.moving.sum()} of the {len(late.ids)} objects" \
        in drawing.metrics_markdown
    assert caption_lines(outcome)[-1] == f"message 300 ms old · moved up to {late.moved.max():.1f} m"


def test_without_a_delay_nothing_is_late(synthetic: Explorer) -> None:
    outcome = synthetic.compute(occluded(30))
    drawing = draw(outcome, synthetic.map_segments)
    assert outcome.late() is None and len(drawing.lines["moved"].segments) == 0
    assert "message age" not in drawing.metrics_markdown and "moved_after" not in drawing.labels


def test_the_datasets_own_capture_gap_is_said_and_starts_the_message(synthetic: Explorer) -> None:
    first = synthetic.compute(occluded(30))
    sequence = loaders.open("synthetic:60")
    sequence.agent_times = {k: {first.ego_id: float(t), first.cav_id: float(t) - 0.04}
                            for k, t in enumerate(sequence.timestamps)}
    outcome: Outcome = Explorer(sequence).compute(occluded(30))
    assert outcome.capture_gap_s == pytest.approx(0.04) and outcome.trial.message_age_s == pytest.approx(0.04)
    assert caption_lines(outcome)[-1].startswith("CAV captured 40 ms before the ego · message 40 ms old")
    assert "| capture times | CAV captured 40 ms before the ego (the dataset's timestamps) |" in \
        draw(outcome, synthetic.map_segments).metrics_markdown


@pytest.mark.parametrize("release, words", [
    (lambda root: releases.dair_release(root / "cooperative-vehicle-infrastructure"),
     "roadside unit captured 40 ms before the ego (the dataset's timestamps)"),
    (lambda root: releases_v2i.spd_release(root / "V2X-Seq-SPD"),
     "roadside unit captured 63 ms after the ego (the dataset's timestamps; counted as no delay)")])
def test_a_pairs_capture_times_are_said(tmp_path, release, words: str) -> None:
    explorer = Explorer(loaders.open(release(tmp_path)))
    outcome = explorer.compute(occluded(0, sensor_range=200.0))
    assert f"| capture times | {words} |" in draw(outcome, explorer.map_segments).metrics_markdown
    assert caption_lines(outcome)[-1] == words.split(" (")[0]


def test_a_delay_older_than_the_sequence_is_said_to_be_cut_short(synthetic: Explorer) -> None:
    outcome = synthetic.compute(occluded(1, delay_ms=300.0))
    assert outcome.trial.message_age_s == pytest.approx(0.1), "frame 1 has one frame before it"
    assert "| message age | 100 ms (as old as the frames before this one allow) |" in \
        draw(outcome, synthetic.map_segments).metrics_markdown
