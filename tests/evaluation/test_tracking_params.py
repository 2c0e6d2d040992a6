"""CBM over time's tracking parameters (``cbm.TrackingParams``) where users tune them: a preset's
``[tracking]`` table (saved by the app, read by the app and ``evaluate.py --preset``), ``--grid
tracking.<field>``, each reaching the calibrator that steps through the frames."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import polars as pl
import pytest

import loaders
from app.session.presets import discover, save_preset
from app.session.settings import Settings
from cbm import CBMParams, SequenceCalibrator, TrackingParams
from evaluation.cli import main
from evaluation.conditions import CONDITIONS
from evaluation.presets import PresetError, read_preset_file
from evaluation.sweep import Sweep, run
from evaluation.trials import sequence_inputs

TUNED = TrackingParams(gate=4.5, drift_m=0.25, chain=2, lost_after=9, sure_margin=12.0, max_gap_s=3.0)
QUICK = ["--dataset", "synthetic:40", "--frames", "0:30:3", "--workers", "1", "--no-timing"]


def test_a_saved_preset_keeps_the_tracking_and_loading_it_applies_it(tmp_path: Path) -> None:
    settings = dataclasses.replace(Settings(), method="cbm-time", tracking=TUNED)
    path = save_preset("tuned tracking", settings, users=tmp_path)
    assert "[tracking]" in path.read_text() and "gate = 4.5" in path.read_text()
    presets, problems = discover(users=tmp_path)
    assert not problems
    loaded = presets[path.stem].apply(Settings())
    assert loaded.tracking == TUNED and loaded.method == "cbm-time"
    assert read_preset_file(path).tracking == TUNED, "evaluate.py --preset reads the same table"
    assert presets["default"].apply(loaded).tracking == TrackingParams(), "the default preset resets it"


def test_a_wrong_tracking_key_or_value_names_the_table_the_key_and_the_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[tracking]\ngat = 4.0\n")
    with pytest.raises(PresetError, match=r"bad.toml: \[tracking\] unknown key 'gat'"):
        read_preset_file(bad)
    bad.write_text("[tracking]\nchain = 1\n")
    with pytest.raises(PresetError,
                       match=r"bad.toml: \[tracking\] TrackingParams.chain must be an integer from 2 to 1000, got 1"):
        read_preset_file(bad)


def test_each_tracking_grid_point_runs_a_calibrator_of_its_own() -> None:
    inputs, _ = sequence_inputs(loaders.open("argoverse2"), range(8), "range")
    sweep = Sweep(methods=("cbm", "cbm-time"), grid={"tracking.chain": (2, 5)}, seed=0,
                  scenario=dataclasses.replace(CONDITIONS["drift-heavy"], seed=0))
    rows = run(sweep, inputs)
    assert all(row["tracking.chain"] is None for row in rows if row["method"] == "cbm")
    answers = {}
    for chain in (2, 5):
        calibrator = SequenceCalibrator(CBMParams(), TrackingParams(chain=chain))
        mine = [row for row in rows if row["method"] == "cbm-time" and row["tracking.chain"] == chain]
        assert len(mine) == len(inputs) and all(row["tracking.gate"] == 3.5 for row in mine)
        for frame, row in zip(inputs, mine):
            trial = frame.build(sweep.scenario_points()[0], sweep.seed)
            result = calibrator.step(trial.ego_boxes, trial.cav_boxes, trial.init, float(frame.times[frame.index]),
                                     agent=frame.trial["cav_id"])
            assert row["n_matched"] == len(result.pairs)
        answers[chain] = [row["rte"] for row in mine]
    assert not np.allclose(answers[2], answers[5], equal_nan=True), \
        "a track started after two agreeing frames answers otherwise than after five"


def test_evaluate_sweeps_a_tracking_parameter_over_a_presets_tracking(tmp_path: Path) -> None:
    preset = tmp_path / "tracking.toml"
    preset.write_text('method = "cbm-time"\n\n[tracking]\nlost_after = 9\n')
    out = tmp_path / "out"
    assert main([*QUICK, "--methods", "cbm,cbm-time", "--preset", str(preset), "--grid", "tracking.gate=2,5",
                 "--out", str(out)]) == 0
    table = pl.read_csv(out / "trials.csv")
    over_time = table.filter(pl.col("method") == "cbm-time")
    assert sorted(over_time["tracking.gate"].unique().to_list()) == [2.0, 5.0]
    assert over_time["tracking.lost_after"].unique().to_list() == [9]
    assert table.filter(pl.col("method") == "cbm")["tracking.gate"].null_count() == len(over_time) // 2
    assert "cbm-time tracking.gate=2" in (out / "summary.md").read_text()


@pytest.mark.parametrize("args, words", [
    (["--methods", "cbm", "--grid", "tracking.gate=2,5"], "'tracking.gate' is a tracking parameter of a method "
                                                          "over time (cbm-time, cbm-smooth); select one"),
    (["--methods", "cbm-time", "--grid", "tracking.nope=1"], "unknown parameter 'tracking.nope'"),
    (["--methods", "cbm-time", "--grid", "tracking.chain=2.5"], "tracking.chain takes int values, got '2.5'"),
])
def test_a_wrong_tracking_grid_is_one_line_and_exit_2(args, words, tmp_path: Path, capsys) -> None:
    with pytest.raises(SystemExit) as stop:
        main([*QUICK, *args, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and words in err and len(err.strip().splitlines()) == 1
