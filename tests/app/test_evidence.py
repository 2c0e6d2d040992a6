"""CBM's verdict on its own pose in the app: a warning light when it has not enough evidence, the
evidence margin over the runner-up pose otherwise (key numbers and the metrics table)."""
import dataclasses
import math
from types import SimpleNamespace

import loaders
from app.panels.keynumbers import WARNING_ID, key_numbers_html
from app.scene.text import evidence_rows
from app.session.explorer import Explorer
from app.session.settings import Settings
from evaluation.metrics import TrialMetrics


def _metrics(abstained: bool) -> TrialMetrics:
    return TrialMetrics(n_ego=5, n_cav=5, n_true=2, n_matched=2, n_correct=2, precision=1.0, recall=1.0, ad=0.0,
                        rre=0.1, rte=0.2, runtime_s=0.01, margin=1.0, estimated=True, abstained=abstained)


def test_an_abstention_lights_the_warning_with_its_reason():
    result = SimpleNamespace(abstained=True, reason="fewer than 3 objects could be paired",
                             evidence_margin=math.nan, hypotheses=1)
    page = key_numbers_html(SimpleNamespace(metrics=_metrics(True), frame_index=4, others=(), result=result))
    assert WARNING_ID in page and "not enough evidence" in page and "fewer than 3 objects" in page
    assert evidence_rows(result) == ["| evidence | ⚠ not enough evidence: fewer than 3 objects could be paired |"]


def test_a_verified_pose_shows_its_margin_and_other_methods_show_nothing():
    result = SimpleNamespace(abstained=False, reason="", evidence_margin=12.34, hypotheses=3)
    page = key_numbers_html(SimpleNamespace(metrics=_metrics(False), frame_index=4, others=(), result=result))
    assert WARNING_ID not in page and "confidence: 12.3" in page
    assert evidence_rows(result) == ["| evidence | margin 12.3 over the runner-up pose (of 3 hypotheses) |"]
    alone = SimpleNamespace(abstained=False, reason="", evidence_margin=math.inf, hypotheses=1)
    assert evidence_rows(alone) == ["| evidence | 1 hypothesis, no rival anchor set to test |"]
    icp = SimpleNamespace(pairs=None)
    assert evidence_rows(icp) == [] and "confidence" not in key_numbers_html(
        SimpleNamespace(metrics=_metrics(False), frame_index=4, others=(), result=icp))


def test_the_shipped_scene_shows_cbms_confidence():
    outcome = Explorer(loaders.open("argoverse2")).compute(dataclasses.replace(Settings(), frame=0))
    assert not outcome.result.abstained and outcome.result.hypotheses >= 1
    assert "confidence:" in key_numbers_html(outcome) and WARNING_ID not in key_numbers_html(outcome)
