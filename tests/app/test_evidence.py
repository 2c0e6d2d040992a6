"""CBM's confidence in the app (issue 47, item 3): one quantity with its scale and threshold (the
evidence margin, "sure from 8") in the key numbers, the metrics table and the caption, and words that
never call a failed frame right: "CBM was sure, and wrong" with the diagnosis's reason."""
import dataclasses
import math
import re
from types import SimpleNamespace

import numpy as np

from app.panels.keynumbers import WARNING_ID, WRONG_ID, key_numbers_html
from app.scene.captions import caption_lines
from app.scene.confidence import sure_words, verdict
from app.scene.glossary import GLOSSARY
from app.scene.text import confidence_rows, metrics_markdown
from app.session.explorer import Explorer
from app.session.presets import discover
from app.session.settings import Settings
from evaluation.diagnosis import Finding
from evaluation.metrics import TrialMetrics, is_success


def _metrics(rte: float) -> TrialMetrics:
    return TrialMetrics(n_ego=5, n_cav=5, n_true=2, n_matched=2, n_correct=2, precision=1.0, recall=1.0, ad=0.0,
                        rre=0.1, rte=rte, runtime_s=0.01, margin=1.0, estimated=True, abstained=False)


def _outcome(result, rte: float, findings=()) -> SimpleNamespace:
    return SimpleNamespace(metrics=_metrics(rte), frame_index=4, others=(), result=result, findings=list(findings))


FOUR = np.array([[0, 0], [1, 1], [2, 2], [3, 3]])
"""The pairs of a pose CBM can stand by (at least three)."""

WRONG = [Finding("wrong_anchor", "the winning anchor ego a ↔ CAV b was wrong", "its winning anchor was a wrong pair"),
         Finding("few_right_pairs", "the pose rests on 4 right pairs …", "its 4 right pairs are too few for the noise")]


def test_a_sure_pose_on_a_failed_frame_is_called_wrong_with_its_reason():
    sure = SimpleNamespace(abstained=False, reason="", evidence_margin=12.24, hypotheses=3, pairs=FOUR)
    page = key_numbers_html(_outcome(sure, rte=3.7, findings=WRONG))
    assert "CBM was sure, and wrong</b>: evidence margin 12.2, sure from 8; its 4 right pairs are too few" in page
    assert WRONG_ID in page and WARNING_ID not in page
    assert confidence_rows(sure, False, WRONG) == [
        "| confidence | CBM was sure, and wrong: evidence margin 12.2, sure from 8; its 4 right pairs are too few "
        "for the noise |"]
    assert verdict(sure, True) == "CBM is sure: evidence margin 12.2, sure from 8"


def test_an_abstention_says_not_sure_rightly_or_though_the_pose_is_right():
    few = SimpleNamespace(abstained=True, reason="fewer than 3 objects could be paired", evidence_margin=math.nan,
                          hypotheses=1, pairs=FOUR[:1])
    page = key_numbers_html(_outcome(few, rte=4.0))
    assert WARNING_ID in page and "CBM was not sure, rightly" in page and "fewer than 3 objects" in page
    assert "no evidence margin, sure from 8" in page
    close = SimpleNamespace(abstained=True, reason="a different pose explains the scene almost as well",
                            evidence_margin=6.2, hypotheses=4, pairs=FOUR)
    assert verdict(close, True) == "CBM was not sure, though the pose is right: evidence margin 6.2, sure from 8"
    assert confidence_rows(close, True, [])[0].startswith("| confidence | ⚠ CBM was not sure")


def test_no_rival_pose_is_an_infinite_margin_and_other_methods_show_none():
    alone = SimpleNamespace(abstained=False, reason="", evidence_margin=math.inf, hypotheses=1, pairs=FOUR)
    assert verdict(alone, True) == "CBM is sure: evidence margin ∞, sure from 8"
    icp = SimpleNamespace(pairs=None)
    assert confidence_rows(icp, False, WRONG) == [] and "CBM" not in key_numbers_html(_outcome(icp, rte=3.0))


def test_the_heavy_noise_frames_that_contradicted_themselves_no_longer_do(explorer: Explorer):
    """Frame 75 said "confidence 30.1 (far better than the runner-up)" and frame 22 "12.2" on failed
    frames; frame 45's panel showed a consensus margin and an evidence margin side by side."""
    settings = discover()[0]["heavy-noise"].apply(Settings())
    for frame in (75, 22):
        outcome = explorer.compute(dataclasses.replace(settings, frame=frame))
        page, table = key_numbers_html(outcome), outcome.findings
        assert "CBM was sure, and wrong" in page and "sure from 8" in page and table
        assert "far better" not in page and "confidence:" not in page
        assert caption_lines(outcome)[-1].startswith("CBM was sure, and wrong · evidence margin")
    outcome = explorer.compute(dataclasses.replace(settings, frame=45))
    text = metrics_markdown(outcome)
    assert "consensus margin" not in text and "| consensus vote | 7 pairs vs 5 for the runner-up |" in text
    assert "| confidence | ⚠ CBM was not sure, rightly: evidence margin 6.7, sure from 8; " in text


def test_the_shipped_scene_shows_cbms_confidence(explorer: Explorer):
    outcome = explorer.compute(dataclasses.replace(Settings(), frame=0))
    assert not outcome.result.abstained and outcome.result.hypotheses >= 1
    page = key_numbers_html(outcome)
    assert "<b>CBM is sure</b>: evidence margin" in page and "sure from 8" in page and WARNING_ID not in page


def test_a_tracks_answer_is_the_tracks_not_a_sure_cbm_below_its_threshold():
    """CBM over time's frame 8 under drift-heavy read "CBM was sure, and wrong: evidence margin 4.5,
    sure from 8": the track stood by an answer whose frame alone CBM was not sure of."""
    note = SimpleNamespace(event="accepted", pooled=9, measured=np.eye(3))
    tracked = SimpleNamespace(abstained=False, reason="", evidence_margin=4.46, hypotheses=3, track=note, pairs=FOUR)
    assert verdict(tracked, False, WRONG) == ("The track stood by it, and was wrong: 9 frames pooled; this "
                                              "frame's own evidence margin 4.5, sure from 8; its 4 right pairs are "
                                              "too few for the noise")
    assert verdict(tracked, True).startswith("The track stands by it: 9 frames pooled")
    unmeasured = SimpleNamespace(abstained=False, evidence_margin=math.nan, hypotheses=0, pairs=FOUR,
                                 track=SimpleNamespace(event="no measurement", pooled=30, measured=None))
    assert verdict(unmeasured, True) == ("The track stands by it: 30 frames pooled; this frame has no "
                                         "evidence margin of its own")
    page = key_numbers_html(_outcome(tracked, rte=3.7, findings=WRONG))
    assert "<b>The track stood by it, and was wrong</b>: 9 frames pooled" in page and WRONG_ID in page
    per_frame = SimpleNamespace(abstained=False, reason="", evidence_margin=12.24, hypotheses=3, pairs=FOUR,
                                track=SimpleNamespace(event="per frame", pooled=0, measured=np.eye(3)))
    assert verdict(per_frame, True) == "CBM is sure: evidence margin 12.2, sure from 8"
    assert "never abstains" in GLOSSARY["track"], "the Words tab says what a track's answer is"


def test_cbm_over_time_never_calls_itself_sure_below_the_threshold(explorer: Explorer):
    """Drift-heavy frames 0-40 over time: a line that says CBM is (or was) sure shows a margin of at
    least 8; frame 14, which per-frame CBM gets right alone, says so."""
    settings = dataclasses.replace(discover()[0]["drift-heavy"].apply(Settings()), method="cbm-time")
    tracked = 0
    for frame in range(41):
        outcome = explorer.compute(dataclasses.replace(settings, frame=frame))
        words = confidence_rows(outcome.result, is_success(outcome.metrics), outcome.findings)[0]
        margin = outcome.result.evidence_margin
        if "CBM is sure" in words or "CBM was sure" in words:
            assert margin >= 8, (frame, words)
        tracked += words.startswith("| confidence | The track")
        if frame == 14:
            assert not is_success(outcome.metrics)
            assert words.endswith("; per-frame CBM alone gets this frame right (0.73° / 0.16 m) |"), words
    assert tracked > 20


def test_a_margin_of_fewer_than_three_pairs_is_never_shown():
    """Two pairs fit any pose exactly, so no rival pose reads as a margin of ∞: drift-sparse's frame
    112 said "CBM was not sure, rightly: evidence margin ∞, sure from 8", and over time frame 124 "this
    frame's own evidence margin ∞" where the frame gave the track no measurement."""
    two = SimpleNamespace(abstained=True, reason="fewer than 3 objects could be paired", evidence_margin=math.inf,
                          hypotheses=1, pairs=FOUR[:2])
    assert verdict(two, False) == ("CBM was not sure, rightly: fewer than 3 objects could be paired; no evidence "
                                   "margin, sure from 8")
    assert sure_words(two) == "CBM not sure"
    note = SimpleNamespace(event="no measurement", pooled=92, measured=None)
    unmeasured = SimpleNamespace(abstained=False, reason="", evidence_margin=math.inf, hypotheses=1, pairs=FOUR,
                                 track=note)
    assert verdict(unmeasured, True).endswith("92 frames pooled; this frame has no evidence margin of its own")
    assert sure_words(unmeasured) == "the track's answer"


def test_a_weak_measurement_set_aside_by_the_track_says_so_not_its_margin():
    note = SimpleNamespace(event="weak measurement", pooled=40, measured=np.eye(3))
    weak = SimpleNamespace(abstained=False, reason="", evidence_margin=math.inf, hypotheses=1, pairs=FOUR, track=note)
    assert verdict(weak, True) == ("The track stands by it: 40 frames pooled; this frame's own pairs explain it "
                                   "hardly better than a coincidence")
    assert sure_words(weak) == "the track's answer"


def test_an_abstention_beside_a_margin_of_infinity_says_its_reason():
    weak = SimpleNamespace(abstained=True, evidence_margin=math.inf, hypotheses=1, pairs=FOUR[:3],
                           reason="its pairs explain the scene hardly better than a coincidence (evidence 4.3 < 8)")
    assert verdict(weak, False) == ("CBM was not sure, rightly: its pairs explain the scene hardly better than a "
                                    "coincidence (evidence 4.3 < 8)")
    assert sure_words(weak) == "CBM not sure"


def test_on_a_quiet_street_a_line_says_sure_exactly_beside_a_sure_margin(explorer: Explorer):
    """drift-sparse, frames 100-130, per frame and over time: a line that shows a margin of 8 or more
    (∞ included) never says CBM was not sure, and one that says CBM is or was sure shows such a margin
    (frame 116 over time, the frame's own sure answer beside its single pair under that pose, read
    "CBM was sure, and wrong: no evidence margin" once the margin went by the answer's pairs)."""
    settings = discover()[0]["drift-sparse"].apply(Settings())
    abstained = sure = 0
    for method in ("cbm", "cbm-time"):
        for frame in range(100, 131):
            outcome = explorer.compute(dataclasses.replace(settings, frame=frame, method=method))
            words = verdict(outcome.result, is_success(outcome.metrics), outcome.findings) or ""
            shown = re.search(r"evidence margin (∞|[\d.]+)", words)
            sure_margin = bool(shown) and (shown[1] == "∞" or float(shown[1]) >= 8)
            abstained += outcome.result.abstained
            if words.startswith(("CBM is sure", "CBM was sure")):
                sure += 1
                assert sure_margin, (method, frame, words)
            elif sure_margin:
                assert "not sure" not in words, (method, frame, words)
    assert abstained > 5 and sure > 3
