"""The metric registry: every metric is one object with a name, unit, direction and formula, and the
evaluation's outputs (trials.csv, summary.md, metrics.json, summary.tex) are read from it, so that a
metric registered once appears in all of them."""
import json
import math
from collections.abc import Sequence

import polars as pl
import pytest

from evaluation.aggregates import method_metrics
from evaluation.cli import main
from evaluation.latex import summary_latex
from evaluation.metric_registry import (
    RUN_METRICS,
    TRIAL_METRICS,
    Metric,
    RunMetric,
    TrialMetric,
    Unit,
    aggregate,
    register,
    run_metrics,
)
from evaluation.metrics import TrialMetrics
from evaluation.report import definitions, table_one
from evaluation.sweep import Sweep, metric_columns

TINY = ["--dataset", "synthetic:30", "--frames", "0:3", "--methods", "cbm,icp", "--no-timing", "--workers", "1"]
EVERY = [*TRIAL_METRICS.values(), *RUN_METRICS.values()]


def record(rte: float, rre: float, estimated: bool = True, abstained: bool = False, **counts) -> TrialMetrics:
    """A trial's record with 4 of 4 true pairs matched unless ``counts`` say otherwise."""
    n = {"n_ego": 5, "n_cav": 5, "n_true": 4, "n_matched": 4, "n_correct": 4, **counts}
    return TrialMetrics(**n, precision=n["n_correct"] / n["n_matched"] if n["n_matched"] else math.nan,
                        recall=n["n_correct"] / n["n_true"], ad=0.0, rre=rre if estimated else math.nan,
                        rte=rte if estimated else math.nan, runtime_s=0.01, margin=3.0, estimated=estimated,
                        abstained=abstained)


def row(m: TrialMetrics) -> dict:
    """The per-trial row ``evaluation.sweep`` writes for ``m``, the pose before calibration 4 m and 5 deg off."""
    return {**m.__dict__, "init_rre": 5.0, "init_rte": 4.0, "localization": "gaussian"}


def cells(markdown: str) -> dict[str, list[str]]:
    """A Markdown table's rows below its header, by their first cell."""
    rows = [[cell.strip() for cell in line.strip().strip("|").split("|")] for line in markdown.splitlines()[2:]]
    return {first: rest for first, *rest in rows}


@pytest.mark.parametrize("metric", EVERY, ids=lambda m: f"{type(m).__name__}:{m.key}")
def test_every_metric_has_a_name_a_unit_a_direction_and_a_formula(metric: Metric) -> None:
    assert metric.key and metric.label and isinstance(metric.unit, Unit)
    assert metric.better in ("higher", "lower")
    assert " = " in metric.formula and len(metric.formula) > 40, metric.formula
    assert metric.heading.startswith(metric.label)
    if metric.unit.text:
        assert metric.heading.endswith(f"({metric.unit.text})")


def test_keys_are_unique_and_a_taken_key_is_refused() -> None:
    saved = [metric.saved_as for metric in RUN_METRICS.values()]
    assert len(set(saved)) == len(saved)
    with pytest.raises(ValueError, match="'rte' is already registered: RTE"):
        register(TRIAL_METRICS["rte"])


def test_aggregate_holds_the_counts_then_every_run_metric() -> None:
    found = aggregate([record(0.2, 0.1), record(0.0, 0.0, estimated=False)])
    assert list(found) == ["n_trials", "n_estimated", *RUN_METRICS]
    assert (found["n_trials"], found["n_estimated"]) == (2, 1)


def test_the_summary_metrics_json_and_latex_are_the_registry() -> None:
    rows = [row(record(0.4, 0.2)), row(record(3.0, 0.3)), row(record(0.1, 0.1, abstained=True))]
    metrics = method_metrics(rows, ["cbm"] * 3, timing=False)["cbm"]
    shown = run_metrics(timing=False)
    assert [key for key in metrics if key in {m.saved_as for m in RUN_METRICS.values()}] == [m.saved_as for m in shown]
    assert "median_runtime_s" not in metrics and "median_runtime_s" in method_metrics(rows, ["cbm"] * 3)["cbm"]
    assert list(cells(table_one(rows, ["cbm"] * 3, timing=False))) == [m.heading for m in shown]
    assert definitions(shown) == [f"- {f}" for f in dict.fromkeys(m.formula for m in shown)]
    header = summary_latex({"cbm": metrics}).splitlines()[3]
    assert header.count("&") == sum(m.headline for m in RUN_METRICS.values())


def test_the_trial_columns_are_the_record_then_the_registry() -> None:
    columns = Sweep(methods=("icp",)).columns()
    assert all(key in columns for key in TRIAL_METRICS)
    assert columns.index("n_ego") < columns.index("rte") < columns.index("success") < columns.index("init_rte")
    assert set(metric_columns()) <= set(columns)


def test_the_pose_before_calibration_is_scored_by_the_registry_as_none_would_be() -> None:
    table = cells(table_one([row(record(0.4, 0.2)), row(record(0.3, 0.1))], ["cbm", "cbm"], timing=False))
    assert table["median RTE (m)"] == ["0.35", "4.00"] and table["median RRE (deg)"] == ["0.15", "5.00"]
    assert table["success @ 1 m, 1 deg (%)"] == ["100.0", "0.0"] and table["precision (%)"] == ["100.0", "-"]
    assert table["recall (%)"] == ["100.0", "0.0"]


class F1(TrialMetric):
    """F1 = 2 precision recall / (precision + recall): the harmonic mean of one trial's precision and
    recall; NaN when either is undefined."""

    key, label, unit, better = "f1", "F1", Unit("", ""), "higher"

    def of(self, m: TrialMetrics) -> float:
        total = m.precision + m.recall
        return 2 * m.precision * m.recall / total if total > 0 else math.nan


class WorstRTE(RunMetric):
    """worst RTE = max RTE over the trials with an estimate (m): how far the worst answer is off."""

    key, label, unit, better = "rte_max", "worst RTE", Unit("m", " m"), "lower"

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        values = [m.rte for m in trials if m.estimated]
        return max(values) if values else math.nan


@pytest.fixture
def two_new_metrics():
    """F1 per trial and the worst RTE per run, registered for one test."""
    register(F1())
    register(WorstRTE())
    yield
    del TRIAL_METRICS["f1"], RUN_METRICS["rte_max"]


def test_a_metric_registered_once_appears_in_every_output_of_a_run(two_new_metrics, tmp_path) -> None:
    assert main([*TINY, "--latex", "--out", str(tmp_path)]) == 0
    trials = pl.read_csv(tmp_path / "trials.csv")
    p, r = trials["precision"].to_numpy(), trials["recall"].to_numpy()
    assert trials["f1"].to_list() == pytest.approx((2 * p * r / (p + r)).tolist(), nan_ok=True)
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    for name in ("cbm", "icp"):
        estimated = trials.filter((pl.col("method") == name) & pl.col("estimated"))
        assert metrics[name]["rte_max"] == pytest.approx(estimated["rte"].max())
    summary = (tmp_path / "summary.md").read_text()
    assert f"| worst RTE (m) | {metrics['cbm']['rte_max']:.2f} | {metrics['icp']['rte_max']:.2f} |" in summary
    assert f"- {WorstRTE().formula}" in summary


def test_mean_errors_over_the_successes_at_each_level_as_v2x_reg_plus_plus_reports_them() -> None:
    trials = [record(0.4, 0.2), record(1.5, 0.5), record(0.3, 2.6), record(0.0, 0.0, estimated=False),
              record(4.5, 1.0), record(0.9, 0.99, abstained=True), record(2.0, 0.1)]
    found = aggregate(trials)
    expected = {  # t: (successes, mRRE, mRTE); a threshold is strict, an abstention still counts
        1: (2, (0.2 + 0.99) / 2, (0.4 + 0.9) / 2),
        2: (3, (0.2 + 0.5 + 0.99) / 3, (0.4 + 1.5 + 0.9) / 3),
        3: (5, (0.2 + 0.5 + 2.6 + 0.99 + 0.1) / 5, (0.4 + 1.5 + 0.3 + 0.9 + 2.0) / 5),
        4: (5, (0.2 + 0.5 + 2.6 + 0.99 + 0.1) / 5, (0.4 + 1.5 + 0.3 + 0.9 + 2.0) / 5),
        5: (6, (0.2 + 0.5 + 2.6 + 1.0 + 0.99 + 0.1) / 6, (0.4 + 1.5 + 0.3 + 4.5 + 0.9 + 2.0) / 6),
    }
    for t, (successes, mrre, mrte) in expected.items():
        rate = found["success_rate" if t == 1 else f"success_rate_{t}"]
        assert (rate, found[f"mrre@{t}"], found[f"mrte@{t}"]) == pytest.approx((successes / 7, mrre, mrte))
    nothing = aggregate([record(9.0, 9.0), record(0.0, 0.0, estimated=False)])
    assert all(math.isnan(nothing[f"m{error}@{t}"]) for error in ("rre", "rte") for t in expected)


def test_success_and_the_mean_errors_of_successes_at_1_to_5_are_in_metrics_json_and_the_summary() -> None:
    rows = [row(record(0.4, 0.2)), row(record(1.5, 0.5)), row(record(0.0, 0.0, estimated=False))]
    metrics = method_metrics(rows, ["cbm"] * 3, timing=False)["cbm"]
    table = cells(table_one(rows, ["cbm"] * 3, timing=False))
    for t, (rate, mrre, mrte) in {1: (1 / 3, 0.2, 0.4), 2: (2 / 3, 0.35, 0.95), 5: (2 / 3, 0.35, 0.95)}.items():
        success = "success_rate" if t == 1 else f"success_rate_{t}"
        assert (metrics[success], metrics[f"mrre@{t}"], metrics[f"mrte@{t}"]) == pytest.approx((rate, mrre, mrte))
        assert table[f"success @ {t} m, {t} deg (%)"][0] == f"{100 * rate:.1f}"
        assert table[f"mRRE of successes @ {t} m, {t} deg (deg)"][0] == f"{mrre:.2f}"
        assert table[f"mRTE of successes @ {t} m, {t} deg (m)"][0] == f"{mrte:.2f}"
