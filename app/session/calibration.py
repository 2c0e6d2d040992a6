"""The dataset-calibration check of a tab's sequence (``evaluation.calibration_check``), run in a
thread of its own, one at a time per tab; the Explore tab lists its flagged frames with *go to frame*.
No viser here: the panel reads ``text`` and ``options`` and asks for ``row_of(option)``.
"""
from __future__ import annotations

import threading
from collections.abc import Callable

from evaluation.calibration_check import DEFAULT_THRESHOLDS, FrameCheck, Thresholds, check_sequence, flagged_markdown
from loaders import Sequence

from .names import agent_name

INTRO = ("Compares the dataset's own transform between the agents with the one its labels give "
         "(the objects both agents label; CBM on the labels), frame by frame, and lists the frames off by more "
         "than 1 m or 1°: there the two label sets do not line up under the shipped transform.")
UNUSABLE = ("This dataset keeps no per-agent labels: there is no transform of its own to check "
            "(DAIR-V2X-C and the OPV2V family have them).")
NONE_FLAGGED = "(no frame flagged)"


class CalibrationCheck:
    """The last check's rows and what the panel shows of them."""

    def __init__(self, sequence: Sequence, thresholds: Thresholds = DEFAULT_THRESHOLDS) -> None:
        self.sequence, self.thresholds = sequence, thresholds
        self.rows: list[FrameCheck] = []
        self.text = INTRO if self.usable else UNUSABLE
        self._thread: threading.Thread | None = None

    @property
    def usable(self) -> bool:
        return bool(self.sequence.agent_views)

    def start(self, done: Callable[[], None]) -> bool:
        """Check every frame in a thread, then call ``done()``; False while a check is running."""
        if self._thread is not None and self._thread.is_alive():
            return False
        self.text = "*checking every frame…*"
        self._thread = threading.Thread(target=self._run, args=(done,), name="calibration-check", daemon=True)
        self._thread.start()
        return True

    def _run(self, done: Callable[[], None]) -> None:
        try:
            self.rows = check_sequence(self.sequence, list(range(len(self.sequence))), self.thresholds)
            self.text = flagged_markdown(self.rows, self.thresholds)
        except ValueError as error:
            self.text = f"**Cannot check:** {error}"
        done()

    def options(self) -> tuple[str, ...]:
        """The flagged frames as the list names them."""
        return tuple(option(row) for row in self.rows if row.flagged) or (NONE_FLAGGED,)

    def row_of(self, chosen: str) -> FrameCheck | None:
        return next((row for row in self.rows if row.flagged and option(row) == chosen), None)


def option(row: FrameCheck) -> str:
    """A flagged frame, with the disagreement it was judged on."""
    metres, degrees = (row.oracle_m, row.oracle_deg) if row.judged_by == "oracle" else (row.cbm_m, row.cbm_deg)
    return f"frame {row.frame} ({row.frame_id}): {agent_name('CAV', row.cav)}, {metres:.2f} m / {degrees:.2f}°"
