"""The walkthrough's steps as plain data: titles, the frame's numbers in the text, what each step
draws, and that it reuses CBM's own sets and fit."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

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
    assert shown[6].title == "Step 7/9 · Robust estimate (eq. 14-15)"
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
        assert set(step.meshes) == {"ego_boxes", "cav_boxes"} and 2 <= len(step.text.split(". ")) <= 8


def test_local_matching_draws_one_wedge_and_diamond(outcome: Outcome) -> None:
    step = steps.build(gather(outcome), 2)
    assert step.lines["diamond"].segments.shape == (4, 2, 3)
    assert len(step.lines["wedge"].segments) > 2 and "region" in step.labels
    facts = gather(outcome)
    origin = facts.ego_xy[facts.pair[0]]
    assert np.allclose(step.lines["ego_vectors"].segments[:, 0, :2], origin, atol=1e-4)
    members, _ = facts.inspection.context("ego", facts.pair[0])
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
    assert f"{len(added)} pairs were added" in step.text
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
