"""The Explore tab's "Dataset calibration" folder: the dataset-calibration check
(``evaluation.calibration_check``) over the tab's sequence, its flagged frames listed with *go to
frame*.

The check runs in a thread of its own (one at a time per tab); the folder says what it found, and a
flagged frame is shown with its CAV under the tab's current scenario and view.
"""
from __future__ import annotations

import dataclasses
import threading

import viser

from evaluation.calibration_check import (
    DEFAULT_THRESHOLDS,
    FrameCheck,
    Thresholds,
    check_sequence,
    flagged_markdown,
)

from .actions import TabActions

NOTHING = "(check first)"
NONE_FLAGGED = "(no frame flagged)"
INTRO = ("Compares the dataset's own transform between the agents with the one its labels give "
         "(the objects both agents label; CBM on the labels), frame by frame; lists the frames off by more "
         "than 1 m or 1°. A flagged frame: the two label sets do not line up under the shipped transform there.")


class CalibrationFolder:
    """The folder's controls, the last check's rows, and the thread that computes them."""

    def __init__(self, gui: viser.GuiApi, tab: TabActions, thresholds: Thresholds = DEFAULT_THRESHOLDS) -> None:
        self.tab, self.thresholds = tab, thresholds
        self.rows: list[FrameCheck] = []
        self._thread: threading.Thread | None = None
        usable = bool(tab.explorer.sequence.agent_views)
        with gui.add_folder("Dataset calibration", expand_by_default=False):
            self.check = gui.add_button("check the dataset's calibration", disabled=not usable,
                                        hint="the shipped transform against the dataset's own labels")
            self.text = gui.add_markdown(INTRO if usable else
                                         "This dataset keeps no per-agent labels: there is no transform of its "
                                         "own to check (DAIR-V2X-C and the OPV2V family have them).")
            self.flagged = gui.add_dropdown("flagged frame", (NOTHING,))
            self.go = gui.add_button("go to frame", hint="that frame and CAV, under the current settings")
        self.check.on_click(lambda event: self.start())
        self.go.on_click(lambda event: self.go_to(self.flagged.value))

    def start(self) -> bool:
        """Check every frame in a thread; False while a check is already running."""
        if self._thread is not None and self._thread.is_alive():
            return False
        self.text.content = "*checking every frame…*"
        self._thread = threading.Thread(target=self._run, name="calibration-check", daemon=True)
        self._thread.start()
        return True

    def _run(self) -> None:
        sequence = self.tab.explorer.sequence
        try:
            rows = check_sequence(sequence, list(range(len(sequence))), self.thresholds)
        except ValueError as error:
            self.text.content = f"**Cannot check:** {error}"
            return
        self.show(rows)

    def show(self, rows: list[FrameCheck]) -> None:
        """List the check's flagged frames (as ``frame k: CAV c, x.xx m / y.yy°``)."""
        self.rows = rows
        self.text.content = flagged_markdown(rows, self.thresholds)
        options = tuple(option(row) for row in rows if row.flagged)
        self.flagged.options = options or (NONE_FLAGGED,)
        self.flagged.value = self.flagged.options[0]

    def go_to(self, chosen: str) -> None:
        """Show the flagged frame ``chosen`` (an entry of the list) with its CAV."""
        row = next((row for row in self.rows if row.flagged and option(row) == chosen), None)
        if row is None:
            return
        self.tab.apply(lambda s: dataclasses.replace(s, frame=row.frame, cav=row.cav), move_controls=True)


def option(row: FrameCheck) -> str:
    """A flagged frame as the list names it, with the disagreement it was judged on."""
    metres, degrees = (row.oracle_m, row.oracle_deg) if row.judged_by == "oracle" else (row.cbm_m, row.cbm_deg)
    return f"frame {row.frame} ({row.frame_id}): CAV {row.cav}, {metres:.2f} m / {degrees:.2f}°"
