"""Worst frames: ranking, labels, diagnoses, and a jump that reproduces the measured row."""
from __future__ import annotations

import dataclasses
import math

from app.panels.reports import worst_markdown
from app.session import worst
from app.session.explorer import Explorer
from app.session.sequence import run_sequence
from app.session.settings import Settings
from evaluation.metric_registry import TRIAL_METRICS


def _row(frame: int, **values) -> dict:
    base = {"precision": 1.0, "recall": 1.0, "ad": 0.0, "rte": 0.1, "rre": 0.1, "margin": 10.0}
    return {"frame": frame, **base, **values}


def test_ranking_puts_undefined_values_first_and_breaks_ties_by_frame() -> None:
    rows = [_row(0, rte=0.5), _row(1, rte=math.nan), _row(2, rte=3.0), _row(3, rte=3.0), _row(4)]
    assert [r["frame"] for r in worst.rank(rows, "RTE")] == [1, 2, 3, 0, 4]
    rows = [_row(0, precision=0.5), _row(1, precision=math.nan), _row(2, margin=1.0)]
    assert [r["frame"] for r in worst.rank(rows, "precision", count=2)] == [1, 0]
    assert worst.rank(rows, "consensus margin")[0]["frame"] == 2


def test_labels_name_their_frame() -> None:
    entry = worst.label(_row(37, rte=4.213), "RTE")
    assert entry == "frame 37 · RTE 4.21 m" and worst.frame_of(entry) == 37
    assert worst.frame_of(worst.label(_row(5, precision=math.nan), "precision")) == 5


def test_the_rankings_and_the_table_are_the_registrys_trial_metrics() -> None:
    assert list(worst.RANKINGS) == [metric.label for metric in TRIAL_METRICS.values()]
    rows = worst.rank([_row(0, ad=0.5), _row(1, ad=2.0, recall=math.nan)], "AD")
    assert [row["frame"] for row in rows] == [1, 0]
    text = worst_markdown(rows, "AD", {})
    assert "| frame | RTE | RRE | precision | recall | AD | consensus margin | latency error | why it failed |" in text
    assert "| 1 | 0.10 m | 0.10° | 1.00 | — | 2.00 m | 10.0 pairs | — | — |" in text


def test_jumping_to_a_worst_frame_reproduces_its_row(small_explorer: Explorer) -> None:
    settings = Settings().with_params("cbm", sigma1=3.0, sigma2=1.0)
    settings = dataclasses.replace(settings, scenario=dataclasses.replace(
        settings.scenario, protocol="sind", eta=0.3, sigma_p=0.6, sigma_theta=8.0, seed=5))
    run = run_sequence(small_explorer, settings, frames=range(8))
    for metric in worst.RANKINGS:
        row = worst.rank(run.rows, metric, count=1)[0]
        shown = small_explorer.compute(dataclasses.replace(run.settings, frame=row["frame"]))
        m = shown.metrics
        assert (m.n_matched, m.n_correct, m.n_true) == (row["n_matched"], row["n_correct"], row["n_true"])
        for name in ("rte", "rre", "margin"):
            value = getattr(m, name)
            assert (math.isnan(value) and math.isnan(row[name])) or value == row[name], (metric, name)


def test_worst_list_shows_each_frames_diagnosis(small_explorer: Explorer) -> None:
    settings = Settings().with_params("cbm", sigma2=0.25, sigma3=0.25, sigma1=1.0)
    settings = dataclasses.replace(settings, scenario=dataclasses.replace(
        settings.scenario, protocol="sind", sigma_p=0.8, sigma_theta=10.0))
    run = run_sequence(small_explorer, settings, frames=range(4))
    frames = worst.candidate_frames(run, count=2)
    findings = worst.diagnoses(small_explorer, run, frames)
    assert set(findings) == set(frames) and any(findings.values())
    rows = worst.rank(run.rows, "recall", count=2)
    text = worst_markdown(rows, "recall", findings)
    assert "Worst frames by recall" in text
    for row in rows:
        for finding in findings[row["frame"]]:
            assert finding.message in text
