"""The app's metric tables read the metric registry: a metric registered once shows in the frame's
panel, the pinned comparison, the sequence table and the worst-frames table."""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import pytest

from app.panels.reports import sequence_markdown, worst_markdown
from app.scene.pinned import comparison_markdown
from app.scene.text import metrics_markdown
from app.session.explorer import Explorer
from app.session.sequence import run_sequence
from app.session.settings import Settings
from evaluation.metric_registry import METRES, RATIO, RUN_METRICS, TRIAL_METRICS, RunMetric, TrialMetric, register
from evaluation.metrics import TrialMetrics


class MissedPairs(TrialMetric):
    """missed pairs = |M| - |M_hat n M|: the true pairs one trial's output left out."""

    key, label, unit, better = "missed", "missed pairs", RATIO, "lower"

    def of(self, m: TrialMetrics) -> float:
        return float(m.n_true - m.n_correct)


class WorstRTE(RunMetric):
    """worst RTE = max RTE over the trials with an estimate (m): how far the worst answer is off."""

    key, label, unit, better = "rte_max", "worst RTE", METRES, "lower"

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        return max((m.rte for m in trials if m.estimated), default=math.nan)


@pytest.fixture
def registered():
    register(MissedPairs())
    register(WorstRTE())
    yield
    del TRIAL_METRICS["missed"], RUN_METRICS["rte_max"]


def test_a_registered_trial_metric_shows_in_the_frame_panel_and_the_pinned_comparison(
        registered, small_explorer: Explorer) -> None:
    settings = Settings(scenario=dataclasses.replace(Settings().scenario, protocol="sind", eta=0.5))
    outcome = small_explorer.compute(settings)
    pinned = small_explorer.compute(settings.with_scenario(sigma_p=0.8))
    missed = outcome.metrics.n_true - outcome.metrics.n_correct
    assert f"| missed pairs | {missed:.2f} |" in metrics_markdown(outcome)
    comparison = comparison_markdown(outcome, pinned)
    for metric in TRIAL_METRICS.values():
        assert f"| {metric.label} | {metric.unit.shown(metric.of(outcome.metrics), '—', suffix=True)} |" in comparison


def test_a_registered_metric_shows_in_the_sequence_and_worst_frames_tables(registered,
                                                                           small_explorer: Explorer) -> None:
    settings = Settings(scenario=dataclasses.replace(Settings().scenario, protocol="sind", sigma_p=0.5))
    run = run_sequence(small_explorer, settings, frames=range(3))
    worst = max(row["rte"] for row in run.rows if row["estimated"])
    assert f"| worst RTE | {worst:.2f} m |" in sequence_markdown(run)
    lines = [[cell.strip() for cell in line.strip("|").split("|")]
             for line in worst_markdown(list(run.rows), "missed pairs", {}).splitlines()[2:]]
    column = lines[0].index("missed pairs")
    shown = {int(cells[0]): cells[column] for cells in lines[2:]}
    assert shown == {row["frame"]: f"{row['n_true'] - row['n_correct']:.2f}" for row in run.rows}
