"""The words the app uses for its numbers, in a few lines each: the *Words* tab beside the key numbers,
one click from anywhere (``app.panels.keynumbers``)."""
from __future__ import annotations

import html

from evaluation.diagnosis import SURE_FROM

GLOSSARY = {
    "RTE": "relative translation error: how far (m) the estimated CAV position lies from the true one. A "
           "frame succeeds with RTE under 1 m and RRE under 1°.",
    "RRE": "relative rotation error: how far (°) the estimated CAV heading turns from the true one.",
    "AD": "average distance: the true distance (m) between the two objects of each pair matched, 0 for a "
          "right pair (paper sec. V-B).",
    "co-visible": "seen by both the ego and the CAV: the objects that can be paired, the true pairs.",
    "anchor": "a pair (ego object i, CAV object j) taken to be one object; CBM compares every other pair's "
              "neighbourhood against it (eq. 9) and keeps the anchor whose set of agreeing pairs is largest "
              "(eq. 13).",
    "L_ij": "the candidate set of anchor (i, j): the pairs whose vectors to their neighbours agree within σ1 "
            "(angle) and σ2 (distance between their tips) seen from i and from j (eq. 9).",
    "margin": f"evidence margin: how much better CBM's pose explains the scene than the best different pose, "
              f"as a natural-log likelihood ratio; CBM is sure from {SURE_FROM:g} (e^{SURE_FROM:g}, about 3000 "
              f"times likelier). The consensus vote counts pairs instead: the winning anchor's against the "
              f"runner-up's.",
    "abstain": f"CBM says it is not sure: fewer than 3 objects could be paired, the evidence margin is under "
               f"{SURE_FROM:g}, or its pairs explain the scene less than {SURE_FROM:g} better than a coincidence "
               f"would (a handful of boxes forms no rival pose: a margin of ∞ then says nothing). Its pose is "
               f"still shown and scored.",
    "track": "CBM over time's estimate of the CAV's pose error, pooled from the frames whose own answer "
             "agreed with it. While it holds, it answers every frame, even one CBM alone is not sure of (the "
             "frame's own margin is then shown beside), and never abstains.",
    "oracle": "least squares on the true pairs: the pose a method would reach knowing which pairs are right, "
              "so its errors are the noise's share. A reference, not a bound (a robust fit can beat it).",
    "precision / recall": "the share of the pairs matched that are right / the share of the co-visible objects "
                          "matched rightly.",
}
"""Each term the panels print, in plain words (the paper's equations named where they come from)."""


def glossary_html(style: str) -> str:
    """The glossary as HTML, one term a line, in ``style``."""
    lines = [f"<b>{html.escape(term)}</b>: {html.escape(words)}" for term, words in GLOSSARY.items()]
    return f'<div id="cbm-glossary" style="{style}">' + "<br>".join(lines) + "</div>"
