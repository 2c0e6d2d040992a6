"""evaluate.py --fusion nms: AP rows in the summary, ap@0.5 / ap@0.7 in metrics.json, the per-trial
detections in the table; no AP without the flag."""
from __future__ import annotations

import json

import polars as pl
import pytest

from evaluation.cli import main

TINY = ["--dataset", "synthetic:40", "--frames", "0:20:10", "--protocol", "sind", "--methods", "none,cbm,oracle",
        "--grid", "eta=0.6", "sigma_p=0.1", "--seed", "1", "--workers", "1", "--no-timing"]


def test_fusion_adds_ap_to_the_summary_the_metrics_and_the_table(tmp_path, capsys: pytest.CaptureFixture) -> None:
    assert main([*TINY, "--fusion", "nms", "--out", str(tmp_path)]) == 0
    summary = (tmp_path / "summary.md").read_text()
    assert "| AP@0.5 (%) |" in summary and "| AP@0.7 (%) |" in summary and "VOC 2010 all-point" in summary
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    for name in ("none", "cbm", "oracle"):
        assert 0.0 <= metrics[name]["ap@0.5"] <= 1.0 and metrics[name]["ap@0.7"] <= metrics[name]["ap@0.5"]
    assert metrics["none"]["ap@0.5"] < metrics["oracle"]["ap@0.5"]
    table = pl.read_csv(tmp_path / "trials.csv")
    assert {"n_gt", "fused"} <= set(table.columns)
    assert all(len(d) == 3 for row in table["fused"] for d in json.loads(row))
    assert "AP@0.7" in capsys.readouterr().out


def test_without_fusion_there_is_no_ap(tmp_path) -> None:
    assert main([*TINY, "--out", str(tmp_path)]) == 0
    assert "AP@" not in (tmp_path / "summary.md").read_text()
    assert "ap@0.5" not in json.loads((tmp_path / "metrics.json").read_text())["cbm"]
    assert "fused" not in pl.read_csv(tmp_path / "trials.csv").columns


def test_an_unknown_fusion_is_a_one_line_error(tmp_path, capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as stop:
        main([*TINY, "--fusion", "mean", "--out", str(tmp_path)])
    assert stop.value.code == 2 and "--fusion" in capsys.readouterr().err
