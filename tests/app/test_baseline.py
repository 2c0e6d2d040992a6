"""The timeline's rows and data, and the pinned baseline, without a browser."""
from __future__ import annotations

import dataclasses

import numpy as np

from app.panels.plot import TIMELINE, timeline_data, timeline_series
from app.scene.drawing import draw
from app.scene.pinned import with_baseline
from app.session.baseline import Baseline
from app.session.explorer import Explorer
from app.session.history import FrameHistory, Row, step_to_failure
from app.session.settings import Settings


def row(failed: bool) -> Row:
    return Row(1.0, 0.5, 0.2, 0.1, 3, failed)


def test_the_timeline_spans_the_sequence_and_marks_failures_and_the_current_frame() -> None:
    data = timeline_data({3: row(False), 5: row(True)}, {3: row(False)}, 5, 50, with_pinned=True)
    x, precision, rte, failed, now, pinned_precision = data[0], data[1], data[3], data[4], data[5], data[6]
    assert len(data) == len(timeline_series(True)) and all(len(a) == len(x) for a in data)
    assert x[0] == 0 and x[-1] == 49 and list(x).count(5) == 2
    assert set(x[np.isfinite(precision)]) == {3, 5} and set(x[np.isfinite(rte)]) == {3, 5}
    assert set(x[np.isfinite(pinned_precision)]) == {3}
    assert set(x[np.isfinite(failed)]) == {5}
    assert list(now[np.isfinite(now)]) == [0.0, 1.0] and set(x[np.isfinite(now)]) == {5}
    assert len(timeline_data({3: row(False)}, {3: row(False)}, 3, 50)) == len(TIMELINE)


def test_no_timeline_line_bridges_frames_never_computed() -> None:
    x, precision = timeline_data({2: row(False), 3: row(False), 9: row(False)}, {}, 9, 20)[:2]
    between = (x > 3) & (x < 9)
    assert between.any() and np.isnan(precision[between]).all()
    assert not ((x > 2) & (x < 3)).any()


def test_failures_are_stepped_through_in_either_direction() -> None:
    rows = {f: row(f in (4, 9)) for f in range(12)}
    assert step_to_failure(rows, 0, 1) == 4 and step_to_failure(rows, 4, 1) == 9
    assert step_to_failure(rows, 9, 1) is None and step_to_failure(rows, 9, -1) == 4
    assert step_to_failure(rows, 4, -1) is None


def test_the_history_keeps_its_rows_across_frame_and_view_changes(small_explorer: Explorer) -> None:
    history = FrameHistory()
    settings = Settings(scenario=dataclasses.replace(Settings().scenario, protocol="sind"))
    history.add(small_explorer.compute(settings))
    history.add(small_explorer.compute(dataclasses.replace(settings, frame=1).with_view(ghosts=True)))
    assert set(history.rows) == {0, 1}
    history.add(small_explorer.compute(settings.with_scenario(sigma_p=0.5)))
    assert set(history.rows) == {0}


def test_a_pinned_baseline_keeps_its_rows_and_computes_each_frame_once(small_explorer: Explorer) -> None:
    settings = Settings(scenario=dataclasses.replace(Settings().scenario, protocol="sind"))
    shown = small_explorer.compute(settings)
    history = FrameHistory()
    history.add(shown)
    baseline = Baseline()
    baseline.pin(settings, history, shown)
    current = dataclasses.replace(settings.with_scenario(sigma_p=0.9), frame=2)
    assert baseline.outcome(small_explorer, settings) is shown
    pinned = baseline.outcome(small_explorer, current)
    assert pinned.settings.scenario.sigma_p == settings.scenario.sigma_p and pinned.frame_index == 2
    assert baseline.outcome(small_explorer, current) is pinned and set(baseline.rows) == {0, 2}
    outcome = small_explorer.compute(current)
    picture = with_baseline(draw(outcome, {}), outcome, pinned)
    assert len(picture.lines["pinned"].segments) == len(pinned.result.pairs)
    assert "current − pinned" in picture.metrics_markdown
    unlined = dataclasses.replace(outcome, settings=current.with_view(pinned_lines=False))
    hidden = with_baseline(draw(unlined, {}), unlined, pinned)
    assert len(hidden.lines["pinned"].segments) == 0
    baseline.unpin()
    assert baseline.outcome(small_explorer, current) is None and not baseline.rows


def test_a_timeline_sent_again_unchanged_is_not_resent() -> None:
    """``send`` queues the chart's data only when it differs from what it last sent (NaN = NaN),
    and never skips the first data after the placeholder."""
    import viser

    from app.panels.plot import add_timeline, send

    server = viser.ViserServer(port=0, verbose=False)
    try:
        plot = add_timeline(server.gui)
        sent: list[object] = []
        queue = plot._queue_update
        object.__setattr__(plot, "_queue_update", lambda name, value: (sent.append(value), queue(name, value)))
        data = timeline_data({0: row(False), 3: row(True)}, {}, 3, 10)
        send(plot, data)
        send(plot, tuple(a.copy() for a in data))
        assert len(sent) == 1
        send(plot, timeline_data({0: row(False), 3: row(True)}, {}, 0, 10))
        assert len(sent) == 2
    finally:
        server.stop()
