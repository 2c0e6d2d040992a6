"""The picture is evidence (issue 24, items 1 to 3) without a browser: every footprint lies in the
plane of comparison, match lines join the centres of the boxes drawn, wrong and missed pairs are
marked on their boxes, every CAV is drawn as a CAV and the key numbers say which CAV they describe."""
from __future__ import annotations

import dataclasses

import numpy as np

from app.panels.keynumbers import key_numbers_html
from app.scene import cavs, picking, planes
from app.scene.drawing import draw
from app.scene.pairs import unexplained
from app.session.explorer import Explorer, classified_pairs
from app.session.presets import SHIPPED_DIR, read
from app.session.settings import Settings
from evaluation.diagnosis import short_id
from evaluation.metrics import is_success


def test_every_footprint_is_flat_at_its_layer_whatever_the_box_heights(explorer: Explorer) -> None:
    drawing = draw(explorer.compute(dataclasses.replace(Settings(frame=10), cavs=3)), explorer.map_segments)
    layers = {"ego_boxes": planes.EGO, "cav_boxes": planes.cav(1), "cav_boxes_2": planes.cav(2),
              "cav_boxes_3": planes.cav(3)}
    for name, z in layers.items():
        assert np.allclose(drawing.meshes[name].vertices[:, 2], z), name
    assert max(layers.values()) < planes.OUTLINES < planes.LINES < 0.5
    assert np.allclose(drawing.lines["right"].segments[..., 2], planes.LINES)


def test_match_lines_join_the_centres_of_the_boxes_drawn_for_every_cav(explorer: Explorer) -> None:
    outcome = explorer.compute(dataclasses.replace(Settings(frame=10), cavs=3))
    drawing = draw(outcome, explorer.map_segments)
    ends = drawing.lines["right"].segments[:, :, :2].reshape(-1, 2)
    centres = np.concatenate([drawing.meshes[name].vertices.reshape(-1, 4, 3).mean(axis=1)[:, :2]
                              for name in ("ego_boxes", "cav_boxes", "cav_boxes_2", "cav_boxes_3")])
    nearest = np.min(np.linalg.norm(ends[:, None] - centres[None], axis=2), axis=1)
    assert len(ends) == 2 * sum(len(c.result.pairs) for c in (outcome, *outcome.others)) and nearest.max() < 1e-3


def test_wrong_and_missed_pairs_are_outlined_and_labelled_with_both_ids(explorer: Explorer) -> None:
    outcome = explorer.compute(read(SHIPPED_DIR / "stress.toml", True).apply(Settings(frame=18)))
    drawing = draw(outcome, explorer.map_segments)
    _, wrong, missed = classified_pairs(outcome.result.pairs, outcome.trial.gt_pairs)
    assert len(wrong) and len(missed)
    assert len(drawing.lines["wrong_marks"].segments) == 8 * len(wrong)
    assert len(drawing.lines["missed_marks"].segments) == 8 * len(missed)
    for i, j in wrong.tolist():
        text = drawing.labels[f"pairs_after_wrong_{i}_{j}"][0]
        assert str(outcome.trial.ego_ids[i])[:8] in text and str(outcome.trial.cav_ids[j])[:8] in text
    assert sum(name.startswith("pairs_after_missed_") for name in drawing.labels) == len(unexplained(missed, wrong))
    assert len(unexplained(np.array([[1, 2], [2, 1], [3, 3]]), np.array([[1, 1], [2, 2]]))) == 1


def test_a_right_frame_marks_nothing(explorer: Explorer) -> None:
    drawing = draw(explorer.compute(Settings(frame=10)), explorer.map_segments)
    assert len(drawing.lines["wrong_marks"].segments) == len(drawing.lines["missed_marks"].segments) == 0
    assert not any(name.startswith("pairs_") for name in drawing.labels)


def test_every_cav_has_a_vehicle_a_label_and_a_key_numbers_line(explorer: Explorer) -> None:
    outcome = explorer.compute(dataclasses.replace(Settings(frame=10), cavs=3))
    drawing = draw(outcome, explorer.map_segments)
    shown = cavs.every_cav(outcome)
    key_numbers = key_numbers_html(outcome)
    for cav in shown:
        assert len(drawing.meshes[cavs.node("cav_vehicle", cav.rank)].faces) > 0
        assert drawing.labels[f"{cavs.node('cav', cav.rank)}_after"][0] == f"CAV {cav.rank}"
        assert f"CAV {cav.rank} · {'success' if is_success(cav.metrics) else 'failed'}" in key_numbers
    assert len(drawing.meshes["cav_vehicle_4"].faces) == 0 and "3 of 3 CAVs succeed" in key_numbers
    assert "CAV 3" in cavs.legend(3) and cavs.legend(1) == ""


def test_a_click_picks_the_box_seen_on_top_and_names_its_cav(explorer: Explorer) -> None:
    """Every CAV's boxes can be clicked (issue 24): a click on a CAV's footprint, nested inside the
    ego's and the CAVs' before it, picks that CAV's box and names the CAV; on the ego's rim, the ego's."""
    outcome = explorer.compute(dataclasses.replace(Settings(frame=10), cavs=3))
    picture = draw(outcome, explorer.map_segments)
    shown = cavs.every_cav(outcome)
    assert list(picture.objects) == ["ego", "cav", "cav_2", "cav_3"] and set(picking.NODES) <= set(picture.meshes)
    for cav in shown:
        group, later = cavs.node("cav", cav.rank), [other.trial.cav_ids for other in shown[cav.rank:]]
        boxes, rows = picture.objects[group]
        alone = [r for r in range(len(rows)) if not any(np.isin(cav.trial.cav_ids[rows[r]], ids) for ids in later)]
        under = [r for r in alone if np.isin(cav.trial.cav_ids[rows[r]], outcome.trial.ego_ids)]
        row = under[0]
        assert picking.pick(picture, boxes[row, :2]) == (group, row)
        name = short_id(cav.trial.cav_ids[rows[row]])
        assert picking.describe(outcome, picture, group, row).startswith(f"CAV {cav.rank} {name}")
    ego, _ = picture.objects["ego"]
    i = int(outcome.result.pairs[0, 0])
    rim = ego[i, :2] + 0.45 * ego[i, 3] * np.array([np.cos(ego[i, 6]), np.sin(ego[i, 6])])
    assert picking.pick(picture, rim) == ("ego", i)
    assert picking.describe(outcome, picture, "ego", i).startswith(f"EGO {short_id(outcome.trial.ego_ids[i])}")
