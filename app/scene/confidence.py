"""CBM's confidence in its pose as the app says it: one quantity with its scale and threshold, the
evidence margin (how much better its pose explains the scene than the best different pose, as a
natural-log likelihood ratio: 8 is 3000 times likelier; ``cbm.hypotheses``), sure from
``SURE_FROM``; and words that never call a failed frame right ("CBM was sure, and wrong: ...",
with the diagnosis's reason). Methods that do not verify their pose have no confidence to show."""
from __future__ import annotations

import math
from collections.abc import Sequence

from cbm import MIN_SHARED
from evaluation.diagnosis import SURE_FROM, Finding

REASONS = ("track", "over_time", "noise", "wrong_pairs", "few_right_pairs", "wrong_anchor", "distance_limit",
           "heading_fold", "not_the_fit", "no_anchor", "single_pair", "no_estimate", "few_covisible", "nothing_paired",
           "unexplained")
"""The findings that say best why a frame failed, the most telling first (the key numbers give one)."""


def own_margin(result: object) -> float:
    """The evidence margin of the frame's own CBM; NaN where it was not verified or paired fewer than
    ``MIN_SHARED`` objects (any pose fits two pairs exactly: no rival pose then reads as a margin of
    ∞ that says nothing). An answer of CBM over time may carry other pairs than the frame's own:
    whether the frame gave a measurement tells (``TrackNote.measured``), and one set aside as weak
    (its pairs hardly better than a coincidence) has none that speaks either."""
    note = getattr(result, "track", None)
    if note is None:
        measured = len(getattr(result, "pairs", ())) >= MIN_SHARED
    else:
        measured = note.measured is not None and note.event != "weak measurement"
    return getattr(result, "evidence_margin", math.nan) if measured else math.nan


def margin_words(result: object) -> str | None:
    """``evidence margin 12.2, sure from 8`` (``∞``: no different pose explains the scene at all);
    None for a result with no margin that speaks (``own_margin``)."""
    margin = own_margin(result)
    if margin != margin:
        return None
    shown = "∞" if math.isinf(margin) else f"{margin:.1f}"
    return f"evidence margin {shown}, sure from {SURE_FROM:g}"


def reason(findings: Sequence[Finding]) -> str:
    """The diagnosis's most telling finding, in a few words ("" without one)."""
    ranked = sorted(findings, key=lambda f: REASONS.index(f.code) if f.code in REASONS else len(REASONS))
    return ranked[0].brief if ranked else ""


TRACKED = ("accepted", "rejected", "no measurement", "weak measurement", "re-acquired")
"""The events of CBM over time (``cbm.result.TrackNote``) whose answer is the track's: it stands by
it whatever this frame's own evidence margin, which then speaks of the frame's measurement only."""


def tracked(result: object) -> bool:
    """Whether the answer is a track's (CBM over time), not one frame's."""
    note = getattr(result, "track", None)
    return note is not None and note.event in TRACKED


def has_confidence(result: object) -> bool:
    """Whether the result has a confidence to show: CBM verified its pose or abstained, or a track answered."""
    return bool(getattr(result, "hypotheses", 0) or getattr(result, "abstained", False) or tracked(result))


def verdict(result: object, success: bool, findings: Sequence[Finding] = ()) -> str | None:
    """CBM's confidence against the truth, in words: sure or not (from the evidence margin, or its
    reason for not being sure), and whether that was right; for a track's answer (CBM over time, and
    the smoother's), that the track stands by it and this frame's own margin; None for a method that
    does not verify."""
    if not has_confidence(result):
        return None
    margin = margin_words(result)
    numbers = margin or f"no evidence margin, sure from {SURE_FROM:g}"
    why = reason(findings)
    because = f"; {why}" if why and not success else ""
    if tracked(result):
        head = "The track stands by it" if success else "The track stood by it, and was wrong"
        weak = result.track.event == "weak measurement"
        own = (f"this frame's own {margin}" if margin else "this frame's own pairs explain it hardly better than a "
               "coincidence" if weak else "this frame has no evidence margin of its own")
        return f"{head}: {result.track.pooled} frames pooled; {own}{because}"
    if getattr(result, "abstained", False):
        head = "CBM was not sure, rightly" if not success else "CBM was not sure, though the pose is right"
        return f"{head}: {doubt(result, numbers)}{because}"
    if success:
        return f"CBM is sure: {numbers}"
    return f"CBM was sure, and wrong: {numbers}{because}"


def doubt(result: object, numbers: str) -> str:
    """Why CBM abstained: its margin where that is why (under ``SURE_FROM``), else its reason (too
    few pairs, or pairs hardly more likely than a coincidence), with "no evidence margin" where it
    has none."""
    margin, why = own_margin(result), getattr(result, "reason", "")
    if margin != margin:
        return f"{why}; {numbers}"
    return numbers if margin < SURE_FROM else why


def sure_words(result: object) -> str | None:
    """A CAV's confidence in a few words, its threshold said once elsewhere (``SURE_WORDS``): ``CBM
    sure, margin 25.3`` (a track's answer: ``the track's answer, this frame's margin 4.5``); None for a
    method that does not verify."""
    if not has_confidence(result):
        return None
    margin = own_margin(result)
    shown = "" if margin != margin else "∞" if math.isinf(margin) else f"{margin:.1f}"
    if tracked(result):
        return f"the track's answer, this frame's margin {shown}" if shown else "the track's answer"
    if getattr(result, "abstained", False):
        return f"CBM not sure, margin {shown}" if margin < SURE_FROM else "CBM not sure"
    return f"CBM sure, margin {shown}" if shown else "CBM sure"


SURE_WORDS = f"CBM sure from evidence margin {SURE_FROM:g}"
"""The threshold, said once above several CAVs' ``sure_words``."""
