"""Evaluation conventions: the success curve, metrics.json, ``compare`` of two runs and the LaTeX summary."""
import json
import math
import subprocess
import sys
from pathlib import Path

import polars as pl
import pytest

from evaluation.aggregates import THRESHOLDS, curve_csv, method_metrics, metrics_json, success_curve
from evaluation.cli import main
from evaluation.compare import compare, differences
from evaluation.latex import escape, summary_latex

REPO = Path(__file__).resolve().parents[2]
TINY = ["--dataset", "synthetic:30", "--frames", "0:3", "--methods", "cbm,icp,oracle", "--no-timing", "--workers", "1"]


def trial(rte: float, rre: float, estimated: bool = True, **counts) -> dict:
    """A per-trial row as in trials.csv (the metrics ``evaluation.sweep.summarise`` reads)."""
    n = {"n_ego": 5, "n_cav": 5, "n_true": 4, "n_matched": 4, "n_correct": 4, **counts}
    return {**n, "precision": n["n_correct"] / n["n_matched"] if n["n_matched"] else math.nan,
            "recall": n["n_correct"] / n["n_true"], "ad": 0.0, "rre": rre if estimated else math.nan,
            "rte": rte if estimated else math.nan, "runtime_s": 0.01, "margin": math.nan, "estimated": estimated}


def test_the_success_curve_counts_trials_under_both_thresholds_and_failures_as_misses():
    rows = [trial(0.4, 0.2), trial(1.2, 0.3), trial(0.3, 2.6), trial(0.1, 0.1, estimated=False), trial(9.0, 9.0)]
    curve = dict(success_curve(rows, ["a"] * 4 + ["b"]))
    assert list(curve) == list(THRESHOLDS) == [0.5 * k for k in range(1, 11)]
    assert [curve[t]["a"] for t in (0.5, 1.5, 2.5, 3.0, 5.0)] == [0.25, 0.5, 0.5, 0.75, 0.75]
    assert all(rates["b"] == 0.0 for rates in curve.values())
    table = pl.read_csv(curve_csv(success_curve(rows, ["a"] * 4 + ["b"])).encode())
    assert table.columns == ["rte_max_m", "rre_max_deg", "a", "b"] and table.height == 10
    assert table["rte_max_m"].to_list() == table["rre_max_deg"].to_list() == list(THRESHOLDS)


def test_metrics_json_holds_each_methods_aggregates_with_nan_as_null():
    rows = [trial(0.4, 0.2), trial(3.0, 0.3), trial(0, 0, estimated=False, n_matched=0, n_correct=0)]
    metrics = method_metrics(rows, ["cbm", "cbm", "none"], timing=False)
    loaded = json.loads(metrics_json(metrics))
    cbm, none = loaded["cbm"], loaded["none"]
    assert cbm["precision"] == 1.0 and cbm["recall"] == 1.0 and cbm["success_rate"] == 0.5
    assert cbm["median_rte"] == pytest.approx(1.7) and cbm["median_rre"] == pytest.approx(0.25)
    assert cbm["n_trials"] == 2 and cbm["success_rte_max_m"] == 1.0 and cbm["success_rre_max_deg"] == 1.0
    assert none["precision"] is None and none["median_rte"] is None and none["success_rate"] == 0.0
    assert "median_runtime_s" not in cbm
    assert method_metrics(rows, ["cbm", "cbm", "none"], timing=True)["cbm"]["median_runtime_s"] == 0.01
    assert "NaN" not in metrics_json(metrics)


def write_run(folder: Path, metrics: dict) -> Path:
    folder.mkdir(parents=True)
    (folder / "metrics.json").write_text(json.dumps(metrics))
    return folder


def test_compare_prints_b_minus_a_lists_lone_methods_and_plots_into_b(tmp_path, capsys):
    a = write_run(tmp_path / "before", {"cbm": {"precision": 0.8, "median_rte": 1.0, "success_rte_max_m": 1.0},
                                         "icp": {"precision": 0.5}})
    b = write_run(tmp_path / "after", {"cbm": {"precision": 0.9, "median_rte": None, "success_rte_max_m": 1.0},
                                        "vips": {"precision": 0.7}})
    assert main(["compare", str(a), str(b)]) == 0
    printed = capsys.readouterr().out
    assert "| method | precision | median_rte |" in printed and "| cbm | +0.1 | - |" in printed
    assert f"Only in {a}: icp" in printed and f"Only in {b}: vips" in printed
    out = b / "compare_vs_before"
    assert (out / "compare.md").read_text() == printed and (out / "compare.png").stat().st_size > 0
    assert differences({"m": {"recall": 0.5}}, {"m": {"recall": 0.25}}) == {"m": {"recall": -0.25}}
    compare(a, b, tmp_path / "elsewhere")
    assert (tmp_path / "elsewhere" / "compare.png").is_file()


@pytest.mark.parametrize("case, message", [
    ("missing", "no such folder"),
    ("file", "not a folder"),
    ("empty", "has no metrics.json"),
    ("garbled", "not readable as JSON"),
    ("list", "not a metrics file"),
])
def test_compare_errors_are_one_line_with_exit_status_2(case, message, tmp_path, capsys):
    good = write_run(tmp_path / "good", {"cbm": {"precision": 1.0}})
    bad = tmp_path / "bad"
    if case == "file":
        bad.write_text("x")
    elif case != "missing":
        bad.mkdir()
    if case == "garbled":
        (bad / "metrics.json").write_text("{not json")
    if case == "list":
        (bad / "metrics.json").write_text("[1, 2]")
    with pytest.raises(SystemExit) as stop:
        main(["compare", str(good), str(bad)])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("evaluate.py compare: error:") and message in err
    assert not (good / "compare_vs_bad").exists()


def test_the_latex_summary_bolds_the_best_of_each_column_among_the_compared_methods():
    metrics = {"cbm": {"precision": 0.95, "recall": 0.9, "success_rate": 0.8, "median_rte": 0.2, "median_rre": 0.3},
               "icp": {"precision": 0.9, "recall": 0.9, "success_rate": None, "median_rte": 0.5, "median_rre": 0.1},
               "oracle": {"precision": 1.0, "recall": 1.0, "success_rate": 1.0, "median_rte": 0.0, "median_rre": 0.0},
               "cbm top_k=3": {"precision": 0.1, "recall": 0.1, "success_rate": 0.0, "median_rte": 9.0,
                               "median_rre": 9.0}}
    tex = summary_latex(metrics)
    lines = tex.splitlines()
    assert lines[1] == "\\begin{tabular}{lrrrrr}" and lines[-1] == "\\end{tabular}"
    assert {"\\toprule", "\\midrule", "\\bottomrule"} <= set(lines)
    assert lines[3] == ("Method & precision (\\%) & recall (\\%) & median RRE (deg) & median RTE (m) & "
                        "success @ 1 m, 1 deg (\\%) \\\\")
    assert "cbm & \\textbf{95.0} & \\textbf{90.0} & 0.30 & \\textbf{0.20} & \\textbf{80.0} \\\\" in lines
    assert "icp & 90.0 & \\textbf{90.0} & \\textbf{0.10} & 0.50 & -- \\\\" in lines
    assert "oracle & 100.0 & 100.0 & 0.00 & 0.00 & 100.0 \\\\" in lines
    assert "cbm top\\_k=3 & 10.0" in tex and escape("a&b%c_d") == "a\\&b\\%c\\_d"


@pytest.fixture(scope="module")
def two_tiny_runs(tmp_path_factory):
    """The tiny run with seeds 0 and 1, the first with --latex."""
    a, b = tmp_path_factory.mktemp("seed0"), tmp_path_factory.mktemp("seed1")
    assert main([*TINY, "--seed", "0", "--latex", "--out", str(a)]) == 0
    assert main([*TINY, "--seed", "1", "--out", str(b)]) == 0
    return a, b


def test_a_run_writes_metrics_the_curve_and_latex_that_agree_with_its_trials(two_tiny_runs):
    a, b = two_tiny_runs
    metrics = json.loads((a / "metrics.json").read_text())
    trials = pl.read_csv(a / "trials.csv")
    curve = pl.read_csv(a / "success_curve.csv")
    assert list(metrics) == ["cbm", "icp", "oracle"] == curve.columns[2:]
    for name, values in metrics.items():
        mine = trials.filter(pl.col("method") == name)
        assert values["success_rate"] == pytest.approx(mine["success"].mean())
        assert values["median_rte"] == pytest.approx(mine["rte"].median())
        assert curve.filter(pl.col("rte_max_m") == 1.0)[name].item() == pytest.approx(values["success_rate"])
    assert (a / "success_curve.png").stat().st_size > 0 and "## Success rate (%)" in (a / "summary.md").read_text()
    assert "\\begin{tabular}" in (a / "summary.tex").read_text() and not (b / "summary.tex").exists()


def test_evaluate_compare_end_to_end(two_tiny_runs):
    a, b = two_tiny_runs
    done = subprocess.run([sys.executable, "evaluate.py", "compare", str(a), str(b)], cwd=REPO,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    header = "| method | precision | recall | ad | median_rre | median_rte | mean_rre | mean_rte | success_rate |"
    assert header in done.stdout
    assert "| oracle | 0 | 0 |" in done.stdout and "## Success rate (percentage points" in done.stdout
    assert (b / f"compare_vs_{a.name}" / "compare.png").is_file()
