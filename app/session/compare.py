"""Every method on the whole sequence, side by side: the tab's settings run with each method ticked,
one after the other, over every frame.

Each method's run is a sequence run (``app.session.sequence.run_sequence``: the evaluation's sweep,
the rows known taken, a method over time continuing the frames the tab computed), so every number is
the one the tab shows on that frame and the one ``evaluate.py`` reports. The runs share one task:
its progress goes from the first method's first frame to the last method's last, and a stop ends
the method running (its frames done are kept) and runs no other. What the table shows per method
are run metrics of ``evaluation.metric_registry`` (``COLUMNS``).
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from cbm import Cancelled
from evaluation.metric_registry import RUN_METRICS, RunMetric

from .background import Task
from .explorer import Explorer
from .offers import Offers
from .sequence import SequenceRun, run_sequence
from .settings import Settings

COMPARABLE = ("cbm", "cbm-time", "cbm-smooth", "icp", "ricp", "vips", "v2xregpp", "freealign", "oracle")
"""The methods a comparison offers, in the table's order: CBM, CBM over time (and over the whole
recording, which a comparison's run over every frame allows), the baselines, the oracle."""
TICKED = ("cbm", "cbm-time", "icp", "v2xregpp", "oracle")
"""Ticked at first: CBM alone and over time, one classic and one recent baseline, and the oracle's reference."""
COLUMNS = ("success_rate", "success_rate_2", "success_rate_3", "rte_median", "rre_median", "abstain_rate",
           "runtime_median_s")
"""The run metrics of the table (keys of ``evaluation.metric_registry.RUN_METRICS``)."""


def columns() -> list[RunMetric]:
    """The table's run metrics, in order."""
    return [RUN_METRICS[key] for key in COLUMNS]


@dataclass(frozen=True)
class Comparison:
    """The runs of one comparison, by method in the order run, and what was asked."""

    settings: Settings
    """The tab's settings it ran under (each run replaces the method)."""
    asked: tuple[str, ...]
    runs: Mapping[str, SequenceRun]

    @property
    def stopped(self) -> bool:
        """Stopped before every method ran over every frame."""
        return len(self.runs) < len(self.asked) or any(run.cancelled for run in self.runs.values())

    def summaries(self) -> dict[str, dict[str, float]]:
        """Each method's run metrics (``evaluation.metric_registry.aggregate``), empty for a run without rows."""
        return {method: run.summary() for method, run in self.runs.items()}

    def per_frame(self, key: str = "rte") -> dict[str, dict[int, float]]:
        """Each method's per-frame ``key`` (a sweep column: ``rte``, ``rre``, ``success``), by frame."""
        return {method: {int(row["frame"]): _number(row.get(key)) for row in run.rows}
                for method, run in self.runs.items()}

    def beaten(self, method: str) -> list[tuple[int, tuple[str, ...]]]:
        """The frames on which ``method`` fails (the evaluation's success test) and other methods
        succeed: (frame, the methods that succeed), by frame; none when ``method`` did not run."""
        success = self.per_frame("success")
        if method not in success:
            return []
        found = []
        for frame, ok in sorted(success[method].items()):
            others = tuple(m for m, by_frame in success.items() if m != method and by_frame.get(frame) == 1.0)
            if ok != 1.0 and others:
                found.append((frame, others))
        return found


class _Share:
    """A part of a task: the share ``[start, start + size]`` of its progress, cancelled with it."""

    def __init__(self, task: Task | None, start: float, size: float) -> None:
        self._task, self._start, self._size = task, start, size

    @property
    def cancelled(self) -> bool:
        return self._task is not None and self._task.cancelled

    def report(self, fraction: float) -> None:
        if self._task is not None:
            self._task.report(self._start + self._size * min(max(fraction, 0.0), 1.0))

    def check(self) -> None:
        if self.cancelled:
            raise Cancelled


def refusals(offers: Offers, settings: Settings, methods: Sequence[str]) -> dict[str, str]:
    """The methods of ``methods`` the dataset cannot run under ``settings``, and why."""
    found = {m: offers.refusal(dataclasses.replace(settings, method=m)) for m in methods}
    return {m: why for m, why in found.items() if why}


def run_comparison(explorer: Explorer, settings: Settings, methods: Sequence[str],
                   task: Task | None = None) -> Comparison:
    """``settings`` with each of ``methods`` over every frame, in order, until ``task`` is cancelled."""
    asked = tuple(methods)
    runs: dict[str, SequenceRun] = {}
    for k, method in enumerate(asked):
        if task is not None and task.cancelled:
            break
        share = _Share(task, k / len(asked), 1 / len(asked))
        try:
            runs[method] = run_sequence(explorer, dataclasses.replace(settings, method=method), share)
        except Cancelled:
            break
        if runs[method].cancelled:
            break
    return Comparison(settings, asked, runs)


def _number(value: object) -> float:
    return math.nan if value is None else float(value)
