"""The key numbers of the frame on screen, pinned beside the top of the control panel: the panel is
one scroll area, so the metrics at its top scroll away while a slider deep in a tab is moved; this
box never does, and sits where the eye is while editing (notifications open top-left). It is a
small panel of its own floating at the canvas's top right (viser's ``add_panel``), so it follows the
docked control panel's edge when that is dragged wider. It also carries the lasting message of a
frame CBM cannot run on (``unusable_markdown``), and, in a tab of its own, the glossary of the words
the panels use (``app.scene.glossary``)."""
from __future__ import annotations

import html

import numpy as np
import viser

from cbm.methods import METHODS
from evaluation.metrics import TrialMetrics, is_success
from loaders import is_vehicle

from ..scene import cavs
from ..scene.colours import Palette, palette
from ..scene.confidence import SURE_WORDS, sure_words, verdict
from ..scene.glossary import glossary_html
from ..scene.text import number
from ..scene.words import error_words
from ..session.explorer import Explorer, Outcome
from ..session.markup import plain
from ..session.settings import Settings

ELEMENT_ID = "cbm-key-numbers"
WARNING_ID = "cbm-not-enough-evidence"
WARNING_COLOUR = "#c77700"
"""The warning light of a pose CBM has not enough evidence for (amber: shown, but not to be trusted)."""
WRONG_ID = "cbm-sure-and-wrong"
WRONG_COLOUR = "#d01c1c"
"""The light of a pose CBM was sure of on a failed frame (red: its confidence was wrong)."""
TAB, WORDS_TAB = "Key numbers", "Words"
"""The floating panel's tabs: the frame's key numbers, and the glossary of the words they use."""
GAP, WIDTH = 16.0, 360.0
"""CSS pixels from the canvas's top right corner to the panel, and its width."""
STYLE = "font:13px/1.4 system-ui,sans-serif;padding:2px 12px 8px;color:inherit"


def key_numbers_html(outcome: Outcome) -> str:
    """One line per fact: the frame and its verdict, precision / recall, the pose errors, and CBM's
    confidence against the truth (``confidence_lines``); with several CAVs, how many succeed and a
    line per CAV (``per_cav_line``)."""
    m = outcome.metrics
    if not outcome.others:
        return _box([f"<b>Frame {outcome.frame_index}</b> · {_verdict(m)}",
                     f"precision / recall {number(m.precision)} / {number(m.recall)}",
                     f"RRE / RTE {number(m.rre, '°')} / {number(m.rte, ' m')}",
                     *confidence_lines(outcome)])
    shown = cavs.every_cav(outcome)
    wins = sum(is_success(cav.metrics) for cav in shown)
    sure = f" · {SURE_WORDS}" if any(sure_words(cav.result) for cav in shown) else ""
    return _box([f"<b>Frame {outcome.frame_index}</b> · {wins} of {len(shown)} CAVs succeed{sure}",
                 *(per_cav_line(cav, palette(outcome.settings.view)) for cav in shown)])


def confidence_lines(outcome: Outcome) -> list[str]:
    """CBM's confidence against the truth (``confidence.verdict``), after a light: amber when CBM was
    not sure, red when it was sure and wrong (nothing for methods that do not verify)."""
    success = is_success(outcome.metrics)
    words = verdict(outcome.result, success, getattr(outcome, "findings", ()))
    if words is None:
        return []
    head, _, rest = words.partition(":")
    if getattr(outcome.result, "abstained", False):
        light = f'<span id="{WARNING_ID}" style="color:{WARNING_COLOUR}">&#9679;</span> '
    else:
        light = "" if success else f'<span id="{WRONG_ID}" style="color:{WRONG_COLOUR}">&#9679;</span> '
    return [f"{light}<b>{html.escape(head)}</b>:{html.escape(rest)}"]


def per_cav_line(cav: cavs.ShownCav, colours: Palette) -> str:
    """One CAV's verdict, precision / recall, pose errors and CBM's confidence, after a square of its colour."""
    m, (r, g, b) = cav.metrics, cavs.box_colour(cav.rank, colours)
    sure = sure_words(cav.result)
    return (f'<span style="color:rgb({r},{g},{b})">■</span> CAV {cav.rank} · {_verdict(m)} · '
            f"P / R {number(m.precision)} / {number(m.recall)} · "
            f"RRE / RTE {number(m.rre, '°')} / {number(m.rte, ' m')}" + (f" · {html.escape(sure)}" if sure else ""))


def _verdict(m: TrialMetrics) -> str:
    return "success" if is_success(m) else "failed"


def problem_html(title: str) -> str:
    return _box([f"<b>{html.escape(title)}</b>"])


def _box(lines: list[str]) -> str:
    return f'<div id="{ELEMENT_ID}" style="{STYLE}">' + "<br>".join(lines) + "</div>"


def unusable_markdown(explorer: Explorer, settings: Settings, error: BaseException) -> str:
    """What is missing for CBM to run on the tab's frame, and what to try."""
    sequence = explorer.sequence
    index = min(max(settings.frame, 0), len(sequence) - 1)
    frame = sequence[index]
    n_objects = len(frame.track_ids)
    n_vehicles = int(np.count_nonzero(is_vehicle(frame.categories)))
    kinds = ", ".join(plain(c) for c in sorted({str(c) for c in frame.categories})) or "none"
    protocol = settings.scenario.protocol
    if n_objects < 2:
        missing = (f"frame {index} has {n_objects} object(s): CBM matches objects between two agents' views and "
                   f"needs at least 2 (3 to tell contexts apart).")
        fix = "pick another frame (the frame slider) or load a dataset with more objects."
    elif protocol != "sind" and n_vehicles < 2:
        missing = (f"frame {index} has {n_vehicles} vehicle(s) among its {n_objects} objects ({kinds}): the "
                   f"{protocol} protocol needs two vehicles (or agents in the table's `agent` column) to act as "
                   f"the ego and the CAV.")
        fix = ("set the Scenario tab's protocol to `sind` (abstract agents: no vehicles needed), or load a "
               "dataset with vehicles.")
    else:
        missing = f"{error_words(error)}."
        fix = "pick another frame, protocol or dataset."
    pointers = [warning for warning in sequence.warnings if "Git LFS pointer" in warning]
    if pointers:
        fix = f"fetch the data Git LFS left behind, then start the app again: {pointers[0]}."
    method = METHODS[settings.method].label
    return f"**{method} cannot run on this frame.**\n\nWhat is missing: {missing}\n\nWhat to try: {fix}"


class KeyNumbers:
    """The pinned key numbers of one tab, hidden in presentation mode (its caption shows them)."""

    def __init__(self, gui: viser.GuiApi) -> None:
        self.panel = gui.add_panel()
        with self.panel.add_tab(TAB):
            self.handle = gui.add_html(problem_html("Computing the first frame…"))
        with self.panel.add_tab(WORDS_TAB):
            gui.add_html(glossary_html(STYLE))
        self.panel.float(x=-GAP, y=GAP, width=WIDTH)

    def show(self, outcome: Outcome) -> None:
        self.handle.content = key_numbers_html(outcome)
        self.panel.visible = not outcome.settings.view.presentation

    def problem(self, title: str) -> None:
        self.handle.content = problem_html(title)
