"""Sequence runs: every row is the tab's own number on that frame; a cancel stops early."""
from __future__ import annotations

import dataclasses
import math

import pytest

from app.panels.reports import sequence_markdown
from app.session import sequence
from app.session.background import Task
from app.session.explorer import Explorer
from app.session.sequence import CHUNK, run_sequence, sweep_for
from app.session.settings import Settings
from evaluation.metric_registry import run_metrics

COMPARED = ("n_ego", "n_cav", "n_true", "n_matched", "n_correct", "precision", "recall", "ad", "rre", "rte",
            "margin", "estimated")


def sind(**changes) -> Settings:
    settings = Settings()
    return dataclasses.replace(settings, scenario=dataclasses.replace(settings.scenario, protocol="sind",
                                                                      sigma_p=0.3, sigma_theta=3.0, **changes))


@pytest.fixture(autouse=True)
def no_rows_known(small_explorer: Explorer) -> None:
    """Each test runs its frames afresh (a run takes the rows an earlier one computed)."""
    small_explorer.rows.clear()


def _same(a, b) -> bool:
    return (math.isnan(a) and math.isnan(b)) if isinstance(a, float) and math.isnan(a) else a == b


@pytest.mark.parametrize("settings", [sind(seed=3), sind(seed=1).with_params("cbm", sigma2=1.5, heading="fold"),
                                      dataclasses.replace(sind(eta=0.3), method="icp")],
                         ids=["cbm", "cbm-tuned", "icp"])
def test_rows_equal_the_tabs_own_computation(small_explorer: Explorer, settings: Settings) -> None:
    run = run_sequence(small_explorer, settings, frames=range(6))
    assert [row["frame"] for row in run.rows] == list(range(6)) and not run.cancelled
    for frame in range(6):
        shown = small_explorer.compute(dataclasses.replace(settings, frame=frame))
        row = run.row(frame)
        assert row["method"] == settings.method and row["seed"] == settings.scenario.seed
        assert row["cav_id"] == shown.cav_id and row["ego_id"] == shown.ego_id
        for name in COMPARED:
            assert _same(row[name], getattr(shown.metrics, name)), (frame, name)


def test_the_sweep_runs_the_tabs_parameters() -> None:
    settings = sind().with_params("cbm", sigma1=7.5, distance_limit=30.0)
    sweep = sweep_for(settings)
    assert sweep.method_points("cbm") == [settings.cbm]
    assert sweep.scenario_points() == [settings.scenario]


def test_cancel_stops_at_the_next_chunk(small_explorer: Explorer) -> None:
    reports: list[float] = []
    task = Task(reports.append)
    original = task.report

    def report_then_cancel(fraction: float) -> None:
        original(fraction)
        task.cancel()

    task.report = report_then_cancel
    run = run_sequence(small_explorer, sind(), task, frames=range(3 * CHUNK))
    assert run.cancelled and len(run.rows) == CHUNK and len(reports) == 1
    assert "cancelled after 8 of 24 frames" in sequence_markdown(run)


def test_summary_table_and_plot(small_explorer: Explorer) -> None:
    run = run_sequence(small_explorer, sind(), frames=range(4))
    text, summary = sequence_markdown(run), run.summary()
    assert "over 4 of 4 frames" in text
    for metric in run_metrics():
        assert f"| {metric.label} | {metric.unit.shown(summary[metric.key], '—', suffix=True)} |" in text
    frames, *values = run.plot_data()
    assert frames.tolist() == [0, 1, 2, 3] and [len(v) for v in values] == [4, 4, 4, 4]
    with pytest.raises(KeyError):
        run.row(40)


def test_a_cancel_inside_a_chunk_stops_in_the_engine_and_keeps_the_chunks_done(small_explorer: Explorer,
                                                                              monkeypatch) -> None:
    """A long job runs under ``stoppable`` (``background.Runner``): cancelled while a chunk computes,
    CBM's engine stops at its next check instead of finishing the chunk, and the chunks done are kept."""
    import threading

    from app.session.background import Runner, Slots

    chunks, original, ended, results = [], sequence.run, threading.Event(), []

    def cancelled_in_the_second_chunk(sweep, inputs):
        chunks.append(len(inputs))
        if len(chunks) == 2:
            runner.cancel()
        return original(sweep, inputs)

    monkeypatch.setattr(sequence, "run", cancelled_in_the_second_chunk)
    runner = Runner(lambda fraction: None, lambda title, error: results.append(error), ended.set, slots=Slots(1))
    runner.start("Sequence run", lambda task: run_sequence(small_explorer, sind(), task, frames=range(3 * CHUNK)),
                 lambda run, cancelled: results.append((run, cancelled)))
    assert ended.wait(300)
    (run, cancelled), = results
    assert cancelled and run.cancelled and len(run.rows) == CHUNK and len(chunks) == 2


def test_a_run_takes_the_rows_known_and_runs_only_the_frames_missing(small_explorer: Explorer, monkeypatch) -> None:
    """Issue 47 item 7: an export or a comparison after a run computes no frame again."""
    ran, original = [], sequence.run
    monkeypatch.setattr(sequence, "run", lambda sweep, inputs: ran.extend(i.index for i in inputs) or
                        original(sweep, inputs))
    first = run_sequence(small_explorer, sind(seed=5), frames=range(6))
    again = run_sequence(small_explorer, dataclasses.replace(sind(seed=5), frame=3).with_view(ghosts=True),
                         frames=range(10))
    assert ran == [*range(6), *range(6, 10)]
    assert again.rows[:6] == first.rows and [row["frame"] for row in again.rows] == list(range(10))
    run_sequence(small_explorer, sind(seed=6), frames=range(2))
    assert ran[-2:] == [0, 1]


def test_a_method_over_time_continues_the_frames_the_tab_computed_and_gives_the_sweeps_rows(
        small_explorer: Explorer) -> None:
    """The rows of CBM over time come from the tab's own frames over time (a jump to frame 20
    computed 0-20: the run computes the rest only), and are the evaluation's rows of the same chain."""
    from evaluation.sweep import run

    settings = dataclasses.replace(sind(seed=2), method="cbm-time").with_scenario(localization="drifting")
    small_explorer.compute(dataclasses.replace(settings, frame=20))
    stepped = []
    ours = run_sequence(small_explorer, settings, Task(lambda fraction: stepped.append(fraction)), frames=range(30))
    assert 0 < len(stepped) <= 9 and not ours.cancelled
    inputs, _ = sequence.frame_inputs(small_explorer, settings, range(30))
    theirs = run(sweep_for(settings), inputs)
    assert [row["frame"] for row in ours.rows] == [row["frame"] for row in theirs]
    for mine, sweep_row in zip(ours.rows, theirs):
        assert mine.keys() == sweep_row.keys()
        assert all(_same(mine[k], sweep_row[k]) for k in mine if k != "runtime_s"), mine["frame"]
