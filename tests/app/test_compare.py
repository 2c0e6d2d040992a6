"""Every method on the whole sequence (issue 47, item 4): one comparison runs each method ticked over
every frame as the evaluation does, reports its progress and stops when asked; its table reads the
registry's run metrics; its chart has a line per method; two methods' pairs show on one frame, the
second beside the first or over it."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from app.panels.compare import beaten_options, chart_data, chart_series, stale, table_markdown
from app.scene.beside import LINES, MESHES, with_pinned_beside
from app.scene.drawing import draw
from app.scene.pinned import with_baseline
from app.session.background import Task
from app.session.compare import COLUMNS, COMPARABLE, Comparison, run_comparison
from app.session.explorer import Explorer, classified_pairs
from app.session.sequence import SequenceRun, run_sequence
from app.session.settings import Settings
from evaluation.metric_registry import RUN_METRICS
from evaluation.sweep import Sweep, run

METHODS = ("cbm", "icp", "oracle")


def sind(**changes) -> Settings:
    """A prior far enough off that ICP, which starts from it, fails on some frames (CBM on none)."""
    settings = Settings()
    return settings.with_scenario(protocol="sind", sigma_p=0.3, sigma_theta=3.0, loc_x=8.0, loc_yaw=15.0, **changes)


@pytest.fixture(scope="module")
def compared(small_explorer: Explorer) -> tuple[Comparison, list[float]]:
    small_explorer.rows.clear()
    reports: list[float] = []
    return run_comparison(small_explorer, sind(seed=8), METHODS, Task(reports.append)), reports


def test_each_method_runs_every_frame_as_a_sequence_run_gives_it(small_explorer: Explorer, compared) -> None:
    comparison, reports = compared
    assert tuple(comparison.runs) == METHODS and not comparison.stopped
    small_explorer.rows.clear()
    for method in METHODS:
        alone = run_sequence(small_explorer, dataclasses.replace(sind(seed=8), method=method))
        ours = comparison.runs[method]
        assert len(ours.rows) == len(small_explorer) and [r["rte"] for r in ours.rows] == [r["rte"] for r in alone.rows]
    assert reports == sorted(reports) and reports[-1] == pytest.approx(1.0)


def test_the_table_has_a_row_per_method_and_the_registrys_run_metrics(compared) -> None:
    comparison, _ = compared
    text = table_markdown(comparison, [])
    for key in COLUMNS:
        assert RUN_METRICS[key].heading in text
    summary = comparison.summaries()["icp"]
    rate = RUN_METRICS["success_rate"].unit.shown(summary["success_rate"], "—")
    median = RUN_METRICS["rte_median"].unit.shown(summary["rte_median"], "—")
    assert any(line.startswith(f"| ICP | {rate} |") for line in text.splitlines())
    assert any(line.startswith(f"| ICP | {median} |") and line.endswith(" 50 of 50 |") for line in text.splitlines())
    assert "**3 of 3 methods**, every frame" in text and "oracle" in text


def test_the_chart_draws_each_methods_rte_per_frame_and_the_success_line(small_explorer: Explorer, compared) -> None:
    comparison, _ = compared
    data, series = chart_data(comparison, len(small_explorer)), chart_series(comparison)
    assert len(data) == len(series) == 1 + len(METHODS) + 1
    x = data[0]
    for k, method in enumerate(METHODS, start=1):
        rte = {row["frame"]: row["rte"] for row in comparison.runs[method].rows}
        drawn = np.isfinite(data[k])
        assert {int(f): v for f, v in zip(x[drawn], data[k][drawn])} == {f: v for f, v in rte.items() if v == v}
    assert np.nanmax(data[-1]) == np.nanmin(data[-1]) == 1.0


def test_the_frames_a_method_fails_and_another_succeeds_are_listed(compared) -> None:
    comparison, _ = compared
    success = comparison.per_frame("success")
    expected = [f for f, ok in success["icp"].items() if not ok and (success["cbm"][f] or success["oracle"][f])]
    assert expected and comparison.beaten("cbm") == []
    assert [frame for frame, _ in comparison.beaten("icp")] == sorted(expected)
    options = beaten_options(comparison, "icp")
    assert len(options) == len(expected) and options[0].startswith(f"frame {expected[0]}: ✓ ")
    assert beaten_options(comparison, "vips") == ("(VIPS was not run)",)


def test_a_stop_ends_the_method_running_and_runs_no_other(small_explorer: Explorer) -> None:
    small_explorer.rows.clear()
    task = Task(lambda fraction: task.cancel() if fraction > 0.2 else None)
    comparison = run_comparison(small_explorer, sind(seed=9), METHODS, task)
    assert comparison.stopped and list(comparison.runs) == ["cbm"] and comparison.runs["cbm"].cancelled
    assert 0 < len(comparison.runs["cbm"].rows) < len(small_explorer)
    assert "**1 of 3 methods**, stopped" in table_markdown(comparison, [])


def test_a_comparison_says_when_the_settings_moved_since(compared) -> None:
    comparison, _ = compared
    assert stale(comparison, dataclasses.replace(sind(seed=8), method="vips", frame=7)) == []
    found = stale(comparison, sind(seed=3).with_params("icp", max_iterations=7))
    assert {d.label for d in found} >= {"seed"} and len(found) == 2
    assert "Computed under other settings" in table_markdown(comparison, found)


def _run(frames_ok: dict[int, bool], method: str) -> SequenceRun:
    rows = tuple({"frame": f, "success": ok, "rte": 0.1 if ok else 9.0} for f, ok in frames_ok.items())
    return SequenceRun(dataclasses.replace(Settings(), method=method), rows, len(rows), (), False)


def test_beaten_frames_from_rows_alone() -> None:
    runs = {"cbm": _run({0: True, 1: False, 2: False}, "cbm"), "icp": _run({0: False, 1: True, 2: False}, "icp")}
    comparison = Comparison(Settings(), ("cbm", "icp"), runs)
    assert comparison.beaten("cbm") == [(1, ("icp",))] and comparison.beaten("icp") == [(0, ("cbm",))]


def test_two_methods_side_by_side_each_in_a_copy_of_its_own(explorer: Explorer) -> None:
    settings = dataclasses.replace(Settings(), frame=45)
    current = explorer.compute(settings)
    pinned = explorer.compute(dataclasses.replace(settings, method="icp"))
    plain = draw(current, explorer.map_segments)
    picture = with_pinned_beside(plain, current, pinned)
    assert set(MESHES) <= set(picture.meshes) and set(LINES) <= set(picture.lines)
    right, wrong, missed = classified_pairs(pinned.result.pairs, pinned.trial.gt_pairs)
    assert len(picture.lines["pinned_right"].segments) == len(right)
    assert len(picture.lines["pinned_wrong"].segments) == len(wrong)
    left_of_current = max(float(boxes[:, 1].max()) for boxes, _ in plain.objects.values())
    copy = picture.meshes["pinned_cav_boxes"].vertices
    assert copy[:, 1].min() > left_of_current and len(picture.agents) == len(plain.agents) + 2
    assert picture.labels["title_pinned"][0] == "ICP (pinned)" and picture.labels["title_current"][0] == "CBM (current)"
    overlaid = with_baseline(plain, current, pinned)
    assert all(len(overlaid.meshes[name].faces) == 0 for name in MESHES) and len(overlaid.lines["pinned"].segments)
    beside = with_baseline(plain, current, pinned, beside=True)
    assert len(beside.lines["pinned"].segments) == 0 and len(beside.meshes["pinned_cav_boxes"].faces)
    assert "drawn beside, on the left" in beside.metrics_markdown


def test_the_whole_recordings_method_is_offered_and_smooths_over_every_frame(small_explorer: Explorer) -> None:
    """CBM over a whole recording answers once every frame is in: a comparison runs it over them all,
    its rows those of the evaluation's sweep (``cbm.sequence.Smoother`` over the frames)."""
    assert "cbm-smooth" in COMPARABLE
    settings = dataclasses.replace(Settings(), method="cbm-smooth")
    frames = list(range(6))
    smoothed = run_sequence(small_explorer, settings, frames=frames)
    inputs = [small_explorer.trial_inputs(settings, f) for f in frames]
    swept = run(Sweep(methods=("cbm-smooth",), seed=settings.scenario.seed, scenario=settings.scenario,
                      params={"cbm": settings.cbm}), inputs)
    assert [row["rte"] for row in smoothed.rows] == pytest.approx([row["rte"] for row in swept], nan_ok=True)
