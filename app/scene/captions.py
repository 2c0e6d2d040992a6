"""What presentation mode writes for the room: the labels' text size (``drawing`` and ``view`` read
it) and the caption of the frame's key numbers (``presentation.Caption`` shows it in a small panel
of its own at the page's bottom left, where it covers no box and stays whole when the control panel
opens; ``presentation`` does the rest of the mode)."""
from __future__ import annotations

from typing import TYPE_CHECKING

from evaluation.metrics import is_success

from ..session.settings import ViewOptions
from .confidence import margin_words, tracked, verdict
from .seen import caption_line
from .text import number

if TYPE_CHECKING:
    from ..session.explorer import Outcome

LABEL_PX = 14.0
"""Height of the labels' text in CSS pixels (viser's own default is 12)."""
PRESENTATION_LABEL_PX = 20.0
"""In presentation mode: readable from the back of a room."""
CAPTION_PX = 24
"""Height of the caption's text in CSS pixels."""


def label_px(view: ViewOptions) -> float:
    """Height of the labels' text for ``view``."""
    return PRESENTATION_LABEL_PX if view.presentation else LABEL_PX


def caption_lines(outcome: Outcome) -> list[str]:
    """The frame and its verdict, precision and recall, the pose errors (to the key numbers'
    precision: an RRE of 0.04° is not "0.0°") and CBM's confidence against the truth (its words and
    evidence margin, without the reason): one line each (with several CAVs, the first CAV's, and the
    caption says so)."""
    m = outcome.metrics
    which = f"CAV 1 of {len(outcome.others) + 1} · " if outcome.others else ""
    words = verdict(outcome.result, is_success(m))
    own = "this frame's " if tracked(outcome.result) else ""
    sure = [f"{words.partition(':')[0]} · {own}{margin_words(outcome.result) or 'no evidence margin'}"] if words else []
    return [f"Frame {outcome.frame_index} · {which}{'success' if is_success(m) else 'failed'}",
            f"precision {number(m.precision)} · recall {number(m.recall)}",
            f"RTE {number(m.rte, ' m')} · RRE {number(m.rre, '°')}", *sure, *caption_line(outcome)]


def caption_html(outcome: Outcome) -> str:
    """The caption as HTML, in the theme's text colour."""
    style = f"font:600 {CAPTION_PX}px/1.35 system-ui,sans-serif;padding:2px 12px 10px;color:inherit"
    return f'<div id="cbm-caption" style="{style}">' + "<br>".join(caption_lines(outcome)) + "</div>"
