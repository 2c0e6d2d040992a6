"""The walkthrough's steps as plain data: titles, the frame's numbers in the text, what each step
draws, and that it reuses CBM's own sets and fit."""
from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from app.scene import planes
from app.scene.colours import CAV_BOXES, EGO_BOXES, GHOST, MISSED, RIGHT, WRONG
from app.scene.drawing import draw
from app.scene.inspector import BAND, REGION
from app.scene.linecolours import as_shown
from app.scene.words import plural
from app.session.explorer import Explorer, Outcome
from app.session.settings import Settings
from app.walkthrough import shapes, steps
from app.walkthrough.facts import gather
from app.walkthrough.nodes import glide
from cbm import se2


def _outcome(explorer: Explorer, **cbm) -> Outcome:
    settings = Settings()
    settings = dataclasses.replace(settings, scenario=dataclasses.replace(settings.scenario, protocol="sind",
                                                                          sigma_p=0.5, sigma_theta=6.0, eta=0.4))
    return explorer.compute(settings.with_params("cbm", **cbm) if cbm else settings)


@pytest.fixture(scope="module")
def outcome(small_explorer: Explorer) -> Outcome:
    return _outcome(small_explorer)


def test_nine_titled_steps_with_the_frames_numbers(outcome: Outcome) -> None:
    shown = steps.walkthrough(outcome)
    assert [s.title for s in shown] == [steps.title(k) for k in range(9)]
    assert shown[0].title == "Step 1/9 · The wrong pose (eq. 4)"
    assert shown[7].title == "Step 8/9 · Guided re-association (step 7b, beyond the paper)"
    assert shown[6].title == "Step 7/9 · Robust estimate (eq. 15-16)"
    facts = gather(outcome)
    i, j = facts.pair
    assert facts.pair == tuple(outcome.result.anchor)
    assert facts.ego_name(i) in shown[1].text and facts.cav_name(j) in shown[1].text
    assert f"|L_ij| = {len(facts.detail.candidates)}" in shown[2].text
    assert f"σ1 = {outcome.settings.cbm.sigma1:g}°" in shown[2].text
    assert f"{outcome.metrics.n_matched} pairs matched, {outcome.metrics.n_correct} right" in shown[8].text
    assert ("the same object" if facts.pair in facts.truth() else "two different objects") in shown[1].text
    assert shown[2].focus == tuple(facts.ego_xy[i]) and shown[0].focus is None and shown[8].focus is None
    for step in shown:
        assert set(step.meshes) == {"ego_boxes", "cav_boxes", "ego_vehicle", "cav_vehicle"}
        assert 2 <= len(step.text.split(". ")) <= 8 and step.labels["ego_agent"][0] == "ego"


def test_local_matching_draws_one_wedge_and_diamond(outcome: Outcome) -> None:
    step = steps.build(gather(outcome), 2)
    assert step.lines["diamond"].segments.shape == (4, 2, 3)
    assert len(step.lines["wedge"].segments) > 2 and "region" in step.labels
    facts = gather(outcome)
    origin = facts.ego_xy[facts.pair[0]]
    assert np.allclose(step.lines["ego_vectors"].segments[:, 0, :2], origin, atol=1e-4)
    members, _ = facts.explanation.context("ego", facts.pair[0])
    assert np.allclose(step.lines["ego_vectors"].segments[:, 1, :2], facts.ego_xy[members], atol=1e-3)


def test_candidates_and_consensus_are_the_inspections(outcome: Outcome) -> None:
    facts = gather(outcome)
    detail = facts.detail
    candidates, consensus = steps.build(facts, 3), steps.build(facts, 4)
    assert len(candidates.lines["true"].segments) + len(candidates.lines["wrong"].segments) == len(detail.candidates)
    assert len(consensus.lines["kept"].segments) == int(detail.kept_by_consensus.sum())
    assert len(consensus.lines["removed"].segments) == int((~detail.kept_by_consensus).sum())


def test_the_robust_fit_is_cbms_own_and_its_weights_set_the_widths(small_explorer: Explorer) -> None:
    outcome = _outcome(small_explorer, refine=False)
    facts = gather(outcome)
    assert np.allclose(facts.fit_pose, outcome.result.transform)
    step = steps.build(facts, 6)
    widths = {name: lines.thickness for name, lines in step.lines.items() if name.startswith("weights_")}
    assert list(widths.values()) == sorted(widths.values(), reverse=True) and len(widths) == 4
    assert sum(len(step.lines[name].segments) for name in widths) == len(outcome.result.pairs)
    heavy = step.lines["weights_1"].segments
    assert len(heavy) == int((facts.fit.weights >= shapes.WEIGHT_CLASSES[0][0]).sum())
    assert step.motion is not None and np.allclose(step.motion[1], outcome.result.transform)
    assert "switched off" in steps.build(facts, 7).text


def test_reassociation_shows_the_pairs_it_added(outcome: Outcome) -> None:
    facts = gather(outcome)
    own = {tuple(p) for p in facts.own_pairs.tolist()}
    added = [p for p in outcome.result.pairs.tolist() if tuple(p) not in own]
    step = steps.build(facts, 7)
    assert len(step.lines["added"].segments) == len(added)
    assert (f"It added {plural(len(added), 'pair')} (purple)" if added else "It added no pair") in step.text
    assert np.allclose(step.cav_pose, facts.fit_pose)


def test_another_method_is_walked_through_with_cbm(small_explorer: Explorer) -> None:
    outcome = small_explorer.compute(dataclasses.replace(Settings(), method="oracle"))
    facts = gather(outcome)
    assert facts.result.context_pairs is not None and facts.result is not outcome.result
    assert len(steps.walkthrough(outcome)) == 9


def test_glide_runs_from_start_to_end_the_short_way() -> None:
    start, end = se2.make(0.0, 0.0, np.radians(170.0)), se2.make(4.0, -2.0, np.radians(-170.0))
    poses = glide(start, end, 20)
    assert len(poses) == 21 and np.allclose(poses[0], start) and np.allclose(poses[-1], end)
    yaws = np.degrees([abs(se2.wrap_angle(se2.yaw_of(p) - np.radians(180.0))) for p in poses])
    assert yaws.max() <= 10.0 + 1e-9


COLOUR_WORDS = {"orange": {CAV_BOXES}, "blue": {EGO_BOXES}, "green": {RIGHT}, "red": {WRONG},
                "purple": {REGION, steps.ADDED}, "grey": {BAND, MISSED, GHOST}}


def test_every_colour_the_words_name_is_drawn_and_every_object_named_is_labelled(outcome: Outcome) -> None:
    """A step's text names only colours it draws and objects it labels in the scene."""
    facts = gather(outcome)
    for step in steps.walkthrough(outcome):
        drawn = {line.color for line in step.lines.values() if len(line.segments)}
        drawn |= {mesh.color for mesh in step.meshes.values()}
        for word, colours in COLOUR_WORDS.items():
            if re.search(rf"\b{word}\b", step.text):
                assert drawn & colours, (step.key, word)
        labelled = " ".join(text for text, _ in step.labels.values())
        for name in re.findall(r"(?:EGO|CAV) [0-9a-f]{8}", step.text):
            assert name in labelled, (step.key, name)
    assert facts.pair is not None


def test_the_lines_show_the_colours_the_words_name(small_explorer: Explorer) -> None:
    """viser brightens per-vertex line colours: the nodes send the colour that shows as the named one."""
    assert as_shown((255, 255, 255)) == (255, 255, 255) and as_shown((0, 0, 0)) == (0, 0, 0)
    orange = as_shown(CAV_BOXES)
    assert orange[0] == 255 and orange[1] < CAV_BOXES[1] / 2


def test_the_robust_estimate_says_why_the_cav_moves_less_than_the_correction(explorer: Explorer) -> None:
    facts = gather(explorer.compute(Settings()))
    text = steps.build(facts, 6).text
    moved = np.linalg.norm(se2.translation_of(facts.fit_pose) - se2.translation_of(facts.result.init))
    assert "about the ego's origin" in text and f"the CAV itself moves by {moved:.2f} m" in text
    assert "back across the 4.24 m its pose was off" in text


def test_one_is_singular() -> None:
    assert plural(1, "pair") == "1 pair" and plural(2, "pair") == "2 pairs" and plural(0, "vector") == "0 vectors"


def test_a_step_about_the_pair_says_how_far_to_look(outcome: Outcome) -> None:
    shown = steps.walkthrough(outcome)
    facts = gather(outcome)
    local = shown[2]
    tip = local.labels["region"][1]
    assert np.hypot(tip[0] - local.focus[0], tip[1] - local.focus[1]) < local.span / 2
    assert all(steps.SPAN[0] <= s.span <= steps.SPAN[1] for s in shown if s.focus is not None)
    assert facts.pair is not None


def _centres(vertices: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """(N, 2) centres of footprint tiles (4 vertices each) placed by the SE(2) ``pose``."""
    return se2.apply_points(pose, vertices.reshape(-1, 4, 3).mean(axis=1)[:, :2])


def test_every_step_draws_flat_in_the_main_scenes_planes_where_it_drew_the_boxes(explorer: Explorer) -> None:
    """Stepping into the walkthrough from the default view leaves every box where the main scene
    drew it: the same footprints on the same layers, the CAV's at ``init`` where the faint outlines
    were and at the estimate where its tiles were; every line flat between the outlines' layer and
    the highlighted lines', none at a box's height."""
    outcome = explorer.compute(Settings())
    scene, shown = draw(outcome, {}), steps.walkthrough(outcome)
    before = scene.lines["cav_before"].segments[:, 0, :2].reshape(-1, 4, 2).mean(axis=1)
    for step in shown:
        assert np.allclose(step.meshes["ego_boxes"].vertices, scene.meshes["ego_boxes"].vertices), step.key
        assert np.allclose(step.meshes["cav_boxes"].vertices[:, 2], planes.cav(1)), step.key
        for name, line in step.lines.items():
            heights = line.segments[..., 2]
            assert np.all((heights >= planes.OUTLINES) & (heights <= planes.HIGHLIGHT)), (step.key, name)
    first, last = shown[0], shown[-1]
    assert np.allclose(_centres(first.meshes["cav_boxes"].vertices, first.cav_pose), before, atol=1e-3)
    assert np.allclose(se2.apply_points(last.cav_pose, last.meshes["cav_boxes"].vertices[:, :2]),
                       scene.meshes["cav_boxes"].vertices[:, :2], atol=1e-3)
